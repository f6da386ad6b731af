#include "pidlab/spec/field.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace pidlab::spec {

std::string FlagName(const std::string& key) {
  std::string flag = "--" + key;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

std::string DisplayName(const std::string& key, NameStyle style) {
  return style == NameStyle::kFlag ? FlagName(key) : key;
}

}  // namespace pidlab::spec

namespace pidlab::spec {

std::string Truncate(const std::string& text, std::size_t max_chars) {
  const std::string marker = "...(" + std::to_string(text.size()) + " chars)";
  const std::size_t keep = max_chars > marker.size() ? max_chars - marker.size() : 0;
  std::string out;
  std::size_t head = 0;  // the longest prefix of whole pieces that leaves room for the marker
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
    if (out.size() <= keep) head = out.size();
    if (out.size() > max_chars) return out.substr(0, head) + marker;
  }
  return out;
}

std::string Quote(const std::string& text) { return "'" + Truncate(text) + "'"; }

std::string FormatNumber(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace pidlab::spec
