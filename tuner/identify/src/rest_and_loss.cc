// What Identify and IdentifyAuto decide around their fits (identify.h;
// docs/identify.md, "Step tests, bounds and real records" and "Robust losses
// for dropouts"): the input a record rested at when u0 is not given, chosen
// by AIC between resting under u[0] and resting at u = 0, and the scale of
// a robust loss, derived from the residuals of the l2 fit.

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fit_problem.h"
#include "pidlab/identify/identify.h"
#include "pidlab/spec/field.h"

namespace pidlab::identify {
namespace internal {
namespace {

// Both rests are worth fitting: u0 neither given nor estimated, the state
// at rest at u0 (kZero: with the other initial conditions u0 only shifts
// y0), and a record whose u varies from a first sample other than 0 (a
// constant u is refused at its first sample: Identify's message says why).
bool TwoRests(const IdentifyData& data, const IdentifyOptions& options) {
  if (!std::isnan(options.u0) || options.estimate_u0 || options.initial_condition != InitialCondition::kZero)
    return false;
  if (data.u.empty() || data.u[0] == 0.0 || !std::isfinite(data.u[0])) return false;
  return std::any_of(data.u.begin(), data.u.end(), [&](double v) { return v != data.u[0]; });
}

std::string Aic(const Status& status, const IdentifyResult& r) {
  return status.ok() ? "AIC " + Number(r.aic) : "not fitted: " + spec::Truncate(status.message(), 120);
}

}  // namespace

// The fit at rest under u[0] and the one at rest at u = 0: the lower AIC
// (the same parameters, so the lower cost) kept, the other said beside it.
// Resting under u[0] is kept on a tie, and when the other failed.
Status ChooseRest(double u_first, const Status& first_status, IdentifyResult* first,
                  const Status& zero_status, IdentifyResult* zero, IdentifyResult* result) {
  const bool zero_wins = zero_status.ok() && (!first_status.ok() || zero->aic < first->aic);
  if (!zero_wins && !first_status.ok()) return first_status;
  std::vector<IdentifyResult::RestHypothesis> hypotheses = {
      {u_first, first_status.ok() ? first->aic : kNaN, first_status.ok() ? "" : first_status.message()},
      {0.0, zero_status.ok() ? zero->aic : kNaN, zero_status.ok() ? "" : zero_status.message()}};
  std::ostringstream os;
  if (zero_wins)
    os << "at rest at u = 0 before the record (AIC " << Number(zero->aic)
       << "; at rest under u[0] = " << Number(u_first) << ": " << Aic(first_status, *first) << ")";
  else
    os << "at rest under its first input u[0] = " << Number(u_first) << " (AIC " << Number(first->aic)
       << "; at rest at u = 0: " << Aic(zero_status, *zero) << ")";
  *result = std::move(zero_wins ? *zero : *first);
  result->rest_hypotheses = std::move(hypotheses);
  result->u0_source = os.str();
  return Status::Ok();
}

double DerivedLossScale(Loss loss, const std::vector<double>& residuals, const std::vector<double>& y,
                        std::string* source) {
  const auto median = [](std::vector<double> v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  const double centre = median(residuals);
  std::vector<double> deviations;
  for (double r : residuals) deviations.push_back(std::abs(r - centre));
  double sigma = 1.4826 * median(deviations);
  // An l2 fit that is exact at most samples has no spread to measure: a
  // scale of 1e-9 of the output's spread then still tells inliers from
  // outliers.
  double mean = 0.0, spread = 0.0;
  for (double v : y) mean += v / static_cast<double>(y.size());
  for (double v : y) spread += (v - mean) * (v - mean) / static_cast<double>(y.size());
  const double floor = 1e-9 * std::sqrt(spread);
  const bool floored = !(sigma > floor);
  if (floored) sigma = floor;
  const double sigmas = loss == Loss::kHuber ? kHuberScaleInSigmas : kCauchyScaleInSigmas;
  std::ostringstream os;
  os << Number(sigmas) << " x " << Number(sigma)
     << (floored ? ", 1e-9 of the output's standard deviation (the l2 fit's residuals have no spread)"
                 : ", the robust standard deviation (1.4826 MAD) of the l2 fit's residuals");
  *source = os.str();
  return sigmas * sigma;
}

// The fit at rest at u = 0 beside `first`, the fit at rest under u[0]
// (nullptr if it failed): a screen first (a quarter of the starts, the ARX
// start, no nesting; not from first's optimum, which would favour this
// rest with one more start), and the full fit, from the screen's optimum
// too, only if the screen's AIC is below first's. A record that rests under
// u[0] then costs a quarter of a fit more, not a whole one. A screen that
// is the full fit (one start, nothing nested) is not run twice.
Status FitAtZero(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& at_zero,
                 const IdentifyResult* first, IdentifyResult* result) {
  IdentifyOptions screen = at_zero;
  screen.starts = std::max(1, (at_zero.starts + 3) / 4);
  screen.nested_starts = false;
  IdentifyResult screened;
  const Status status = FitKind(data, kind, screen, Seeds{}, &screened);
  ProcessModelKind inner;
  const bool screen_is_full =
      screen.starts >= at_zero.starts && !(at_zero.nested_starts && ContainedKind(kind, &inner));
  if (!status.ok() || screen_is_full || (first && !(screened.aic < first->aic))) {
    *result = std::move(screened);
    return status;
  }
  return FitNested(data, kind, at_zero, &screened, result);
}

// One kind at the rest the record implies (ChooseRest when TwoRests), with
// its contained model as a start.
Status FitAtRest(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                 const IdentifyResult* same_kind, IdentifyResult* result) {
  if (!TwoRests(data, options)) return FitNested(data, kind, options, same_kind, result);
  IdentifyOptions at_first = options, at_zero = options;
  at_first.u0 = data.u[0];
  at_zero.u0 = 0.0;
  IdentifyResult first, zero;
  const Status first_status = FitNested(data, kind, at_first, same_kind, &first);
  if (first_status.code() == StatusCode::kInvalidInput) return first_status;
  const Status zero_status = FitAtZero(data, kind, at_zero, first_status.ok() ? &first : nullptr, &zero);
  return ChooseRest(data.u[0], first_status, &first, zero_status, &zero, result);
}

bool RestsToChoose(const IdentifyData& data, const IdentifyOptions& options) {
  return TwoRests(data, options);
}

}  // namespace internal

Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                IdentifyResult* result) {
  if (const Status shape = internal::CheckTfShape(kind, options.poles, options.zeros); !shape.ok())
    return shape;
  if (options.loss == Loss::kL2 || !std::isnan(options.loss_scale))
    return internal::FitAtRest(data, kind, options, nullptr, result);
  // A robust loss without its scale: the l2 fit first, whose residuals give
  // the scale and whose optimum is one more start.
  if (std::string error; !options.IsValid(&error)) return Status::InvalidInput(error);
  IdentifyOptions l2 = options;
  l2.loss = Loss::kL2;
  IdentifyResult least_squares;
  if (Status s = internal::FitAtRest(data, kind, l2, nullptr, &least_squares); !s.ok()) return s;
  IdentifyOptions robust = options;
  std::string source;
  robust.loss_scale = internal::DerivedLossScale(options.loss, least_squares.residuals, data.y, &source);
  const Status status = internal::FitAtRest(data, kind, robust, &least_squares, result);
  if (status.ok()) result->loss_scale_source = source;
  return status;
}

}  // namespace pidlab::identify
