#pragma once
// The report's one number format.

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace pidlab::report {

/// `v` with `digits` significant digits, plain or scientific as the value
/// needs; "n/a" for NaN, "inf" / "-inf".
inline std::string Num(double v, int digits) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream os;
  os << std::setprecision(digits) << v;
  return os.str();
}

}  // namespace pidlab::report
