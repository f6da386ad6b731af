#include "did_you_mean.h"

#include <algorithm>

namespace pidlab::cli {

std::size_t EditDistance(const std::string& a, const std::string& b) {
  // d[i][j]: the distance of a's first i characters to b's first j.
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::string ClosestName(const std::string& typed, const std::vector<std::string>& names) {
  // Beyond this many characters a typo is not a name (and the table would be
  // large): a pasted value, suggested nothing.
  constexpr std::size_t kLongest = 64;
  if (typed.size() > kLongest) return "";
  const std::string bare = typed.substr(std::min(typed.find_first_not_of('-'), typed.size()));
  const std::size_t most = std::min(1 + bare.size() / 4, bare.size() == 0 ? 0 : bare.size() - 1);
  std::string best;
  std::size_t best_distance = most + 1;
  for (const std::string& name : names) {
    const std::size_t distance = EditDistance(typed, name);
    if (distance < best_distance) {
      best = name;
      best_distance = distance;
    }
  }
  return best;
}

}  // namespace pidlab::cli
