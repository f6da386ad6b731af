#pragma once
// What the identify tests share: the sampling interval of their uniform
// records and the step-rich input every record is made from.

#include <cstddef>
#include <random>
#include <vector>

namespace pidlab::identify::test {

/// The uniform records' sampling interval, s.
inline constexpr double kDt = 0.1;

/// A step-rich input: at rest for five samples, then random levels in
/// [-1, 1] held for 3 to 15 samples each (seeded).
inline std::vector<double> StepRichInput(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(-1.0, 1.0);
  std::uniform_int_distribution<int> hold(3, 15);
  std::vector<double> u(n, 0.0);
  std::size_t k = 5;
  while (k < n) {
    const double v = level(rng);
    for (int i = hold(rng); i > 0 && k < n; --i) u[k++] = v;
  }
  return u;
}

}  // namespace pidlab::identify::test
