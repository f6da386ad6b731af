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

bool ParseLoss(const std::string& s, Loss* v) {
  if (s == "l2")
    *v = Loss::kL2;
  else if (s == "huber")
    *v = Loss::kHuber;
  else if (s == "cauchy")
    *v = Loss::kCauchy;
  else
    return false;
  return true;
}

std::string ToString(Loss v) {
  switch (v) {
    case Loss::kHuber:
      return "huber";
    case Loss::kCauchy:
      return "cauchy";
    case Loss::kL2:
      break;
  }
  return "l2";
}

bool IdentifyOptions::IsValid(std::string* error) const {
  std::string e;
  if (starts < 1 || starts > kMaxStarts)
    e = "starts = " + std::to_string(starts) + " must be in [1, " + std::to_string(kMaxStarts) + "]";
  else if (!(max_delay_fraction > 0.0 && max_delay_fraction < 1.0))
    e = "max_delay_fraction = " + CheckedNumber(max_delay_fraction) + " must be in (0, 1)";
  else if (max_iterations < 1)
    e = "max_iterations = " + std::to_string(max_iterations) + " must be at least 1";
  else if (std::isinf(u0) || std::isinf(y0))
    e = "u0 and y0 must be finite, or NaN for the first sample";
  else if (!std::isnan(loss_scale) && !(loss_scale > 0.0 && loss_scale <= kMaxRecordMagnitude))
    e = "loss_scale = " + CheckedNumber(loss_scale) + " must be a number in (0, 1e12] (units of y)";
  else if (!std::isnan(loss_scale) && loss == Loss::kL2)
    e = "loss_scale = " + CheckedNumber(loss_scale) + " applies to the losses huber and cauchy, not l2";
  else if (max_samples < kMinMaxSamples || max_samples > kMaxMaxSamples)
    e = "max_samples = " + std::to_string(max_samples) + " must be in [" + std::to_string(kMinMaxSamples) +
        ", " + std::to_string(kMaxMaxSamples) + "]";
  else if (start_samples != 0 && (start_samples < kMinMaxSamples || start_samples > kMaxMaxSamples))
    e = "start_samples = " + std::to_string(start_samples) + " must be 0 or in [" +
        std::to_string(kMinMaxSamples) + ", " + std::to_string(kMaxMaxSamples) + "]";
  if (error) *error = e;
  return e.empty();
}

namespace {

// "sample 11 (row 13)": the index, and the line of a CSV file where known.
std::string Where(const std::vector<long>* rows, std::size_t k) {
  std::string where = "sample " + std::to_string(k);
  if (rows && k < rows->size()) where += " (row " + std::to_string((*rows)[k]) + ")";
  return where;
}

double Median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The rules of absurd but finite data (docs/identify.md, "What a record
// must be"): numbers no larger than any number pidlab takes, no sample
// beyond kMaxOutlierRatio times the column's typical deviation from its
// median.
Status CheckColumn(const std::vector<long>* rows, const std::vector<double>& x, const char* name) {
  for (std::size_t k = 0; k < x.size(); ++k)
    if (std::abs(x[k]) > kMaxRecordMagnitude)
      return Status::InvalidInput("column " + std::string(name) + ", " + Where(rows, k) + ": " +
                                  CheckedNumber(x[k]) +
                                  " is beyond 1e12 in magnitude, the limit of every "
                                  "number pidlab takes (rescale the column's units)");
  const double median = Median(x);
  std::vector<double> deviation(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) deviation[k] = std::abs(x[k] - median);
  const double typical = Median(deviation);
  if (typical > 0.0)
    for (std::size_t k = 0; k < x.size(); ++k)
      if (deviation[k] > kMaxOutlierRatio * typical)
        return Status::InvalidInput("column " + std::string(name) + ", " + Where(rows, k) + ": " +
                                    CheckedNumber(x[k]) +
                                    " lies more than 1e12 times the column's median "
                                    "deviation (" +
                                    CheckedNumber(typical) +
                                    ") from its median: an outlier "
                                    "to remove");
  return Status::Ok();
}

}  // namespace

Status CheckData(const IdentifyData& data, Sampling* sampling, const std::vector<long>* rows) {
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
      return Status::InvalidInput(std::string("not finite: ") + name + " at " + Where(rows, k) + " is " +
                                  CheckedNumber(std::string(name) == "t"   ? data.t[k]
                                                : std::string(name) == "u" ? data.u[k]
                                                                           : data.y[k]));
  }
  for (std::size_t k = 1; k < n; ++k)
    if (!(data.t[k] > data.t[k - 1]))
      return Status::InvalidInput("t is not strictly increasing: t = " + CheckedNumber(data.t[k]) + " at " +
                                  Where(rows, k) + " after " + CheckedNumber(data.t[k - 1]));
  for (std::size_t k = 0; k < n; ++k)
    if (std::abs(data.t[k]) > kMaxRecordMagnitude)
      return Status::InvalidInput("column t, " + Where(rows, k) + ": " + CheckedNumber(data.t[k]) +
                                  " s is beyond 1e12 in magnitude, the limit of every number pidlab takes "
                                  "(rescale t's units)");
  for (std::size_t k = 1; k < n; ++k)
    if (data.t[k] - data.t[k - 1] < kMinRecordInterval)
      return Status::InvalidInput("column t, " + Where(rows, k) + ": the interval " +
                                  CheckedNumber(data.t[k] - data.t[k - 1]) +
                                  " s is below 1e-12 s, the shortest time pidlab takes (rescale t's units)");
  const char* const names[] = {"t", "u", "y"};
  const std::vector<double>* const columns[] = {&data.t, &data.u, &data.y};
  for (int c = 1; c < 3; ++c)
    if (Status s = CheckColumn(rows, *columns[c], names[c]); !s.ok()) return s;
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
  // A constant u is a step when u0 is given (Identify decides): not refused here.
  *sampling = found;
  return Status::Ok();
}

Status CheckResponse(const IdentifyData& data) {
  // Constant to 12 digits: what is left is rounding, not a response.
  const auto [y_min, y_max] = std::minmax_element(data.y.begin(), data.y.end());
  const double y_scale = std::max(std::abs(*y_min), std::abs(*y_max));
  if (*y_max - *y_min <= 1e-12 * y_scale)
    return Status::InvalidInput("constant output: y is " + CheckedNumber(data.y[0]) +
                                (*y_max > *y_min ? " to 12 digits" : "") +
                                " throughout, so no response can be identified");
  return Status::Ok();
}

}  // namespace pidlab::identify
