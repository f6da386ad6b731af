// What identify.h checks before a fit: its options and the record (sampling
// found and said), and the names of the intersample behaviour and the
// initial condition.

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {
std::string CheckedNumber(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
}  // namespace

bool ParseIntersample(const std::string& s, Intersample* v) {
  if (s == "zoh")
    *v = Intersample::kZoh;
  else if (s == "foh")
    *v = Intersample::kFoh;
  else
    return false;
  return true;
}

bool ParseInitialCondition(const std::string& s, InitialCondition* v) {
  if (s == "zero")
    *v = InitialCondition::kZero;
  else if (s == "steady-state")
    *v = InitialCondition::kSteadyState;
  else if (s == "estimate")
    *v = InitialCondition::kEstimate;
  else
    return false;
  return true;
}

std::string ToString(Intersample v) { return v == Intersample::kFoh ? "foh" : "zoh"; }

std::string ToString(InitialCondition v) {
  switch (v) {
    case InitialCondition::kSteadyState:
      return "steady-state";
    case InitialCondition::kEstimate:
      return "estimate";
    case InitialCondition::kZero:
      break;
  }
  return "zero";
}

bool IdentifyOptions::IsValid(std::string* error) const {
  std::string e;
  if (starts < 1)
    e = "starts = " + std::to_string(starts) + " must be at least 1";
  else if (!(max_delay_fraction > 0.0 && max_delay_fraction < 1.0))
    e = "max_delay_fraction = " + CheckedNumber(max_delay_fraction) + " must be in (0, 1)";
  else if (max_iterations < 1)
    e = "max_iterations = " + std::to_string(max_iterations) + " must be at least 1";
  else if (std::isinf(u0) || std::isinf(y0))
    e = "u0 and y0 must be finite, or NaN for the first sample";
  if (error) *error = e;
  return e.empty();
}

Status CheckData(const IdentifyData& data, Sampling* sampling) {
  const std::size_t n = data.t.size();
  if (data.u.size() != n || data.y.size() != n)
    return Status::InvalidInput("t, u and y have different lengths (" + std::to_string(n) + ", " +
                                std::to_string(data.u.size()) + ", " + std::to_string(data.y.size()) + ")");
  if (n < kMinSamples)
    return Status::InvalidInput("too short: " + std::to_string(n) + " samples, at least " +
                                std::to_string(kMinSamples) + " needed");
  for (std::size_t k = 0; k < n; ++k) {
    const char* name = !std::isfinite(data.t[k])   ? "t"
                       : !std::isfinite(data.u[k]) ? "u"
                       : !std::isfinite(data.y[k]) ? "y"
                                                   : nullptr;
    if (name)
      return Status::InvalidInput(std::string("not finite: ") + name + " at sample " + std::to_string(k) +
                                  " is " +
                                  CheckedNumber(std::string(name) == "t"   ? data.t[k]
                                                : std::string(name) == "u" ? data.u[k]
                                                                           : data.y[k]));
  }
  for (std::size_t k = 1; k < n; ++k)
    if (!(data.t[k] > data.t[k - 1]))
      return Status::InvalidInput("t is not strictly increasing: t = " + CheckedNumber(data.t[k]) +
                                  " at sample " + std::to_string(k) + " after " +
                                  CheckedNumber(data.t[k - 1]));
  Sampling found;
  found.mean_interval_s = (data.t[n - 1] - data.t[0]) / static_cast<double>(n - 1);
  found.min_interval_s = found.max_interval_s = data.t[1] - data.t[0];
  for (std::size_t k = 1; k < n; ++k) {
    const double h = data.t[k] - data.t[k - 1];
    found.min_interval_s = std::min(found.min_interval_s, h);
    found.max_interval_s = std::max(found.max_interval_s, h);
    if (std::abs(h - found.mean_interval_s) > kUniformSamplingTolerance * found.mean_interval_s)
      found.uniform = false;
  }
  if (std::all_of(data.u.begin(), data.u.end(), [&](double v) { return v == data.u[0]; }))
    return Status::InvalidInput("constant input: u is " + CheckedNumber(data.u[0]) +
                                " throughout, so nothing can be identified");
  *sampling = found;
  return Status::Ok();
}

}  // namespace pidlab::identify
