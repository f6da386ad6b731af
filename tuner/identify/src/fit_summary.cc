// The summary of a fit (identify.h's IdentifyResult): the covariance of the
// parameters, which of them sit at a bound, the warnings, the figures of merit.

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

#include "fit_problem.h"
#include "piecewise_response.h"

namespace pidlab::identify::internal {
namespace {

// The covariance of the parameters at `theta` (of the values, not of theta;
// p x p, row-major) and their standard errors, scaled by the residual
// variance; false with the reason if Ceres cannot invert J'J.
bool Covariance(const Record& record, std::vector<double> theta, double cost, std::vector<double>* errors,
                std::vector<double>* matrix, double* offset_error, double* input_offset_error,
                std::string* message) {
  const int p = ParameterCount(record);
  const int q = BlockSize(record);
  *offset_error = *input_offset_error = kNaN;
  const int n = static_cast<int>(record.dy.size());
  errors->assign(static_cast<std::size_t>(p), kNaN);
  matrix->assign(static_cast<std::size_t>(p * p), kNaN);
  ceres::Problem problem;
  BuildProblem(record, theta.data(), &problem);
  ceres::Covariance::Options covariance_options;
  covariance_options.algorithm_type = ceres::DENSE_SVD;
  covariance_options.num_threads = 1;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> blocks = {{theta.data(), theta.data()}};
  // Ceres logs a rank-deficient J'J through glog as an error on stderr; the
  // result says it in its own words (covariance_message), so keep glog quiet.
  const int log_level = FLAGS_minloglevel;
  FLAGS_minloglevel = google::GLOG_FATAL;
  const bool computed = covariance.Compute(blocks, &problem);
  FLAGS_minloglevel = log_level;
  if (!computed) {
    *message = "Ceres could not compute the covariance (J'J singular or ill-conditioned)";
    return false;
  }
  std::vector<double> full(static_cast<std::size_t>(q * q));
  covariance.GetCovarianceBlock(theta.data(), theta.data(), full.data());
  // The model's block (the offset's row and column left out: the marginal
  // covariance of the model's parameters).
  std::vector<double> c(static_cast<std::size_t>(p * p));
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j)
      c[static_cast<std::size_t>(i * p + j)] = full[static_cast<std::size_t>(i * q + j)];
  const double variance =
      2.0 * cost / std::max(1, n - q - FittedStates(record, ModelOf(record, theta.data())));
  if (record.offset)
    *offset_error = std::sqrt(std::max(0.0, full[static_cast<std::size_t>(p * q + p)] * variance));
  if (record.input_offset) {
    const int i = InputOffsetIndex(record);
    *input_offset_error = std::sqrt(std::max(0.0, full[static_cast<std::size_t>(i * q + i)] * variance));
  }
  const ProcessModel model = ModelOf(record, theta.data());
  const std::vector<double> values = ParameterValues(model);
  // d value / d theta: the value for a logarithm, else 1.
  std::vector<double> d(static_cast<std::size_t>(p));
  for (int i = 0; i < p; ++i)
    d[static_cast<std::size_t>(i)] = IsLogParameter(record, i) ? values[static_cast<std::size_t>(i)] : 1.0;
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j) {
      const auto ij = static_cast<std::size_t>(i * p + j);
      (*matrix)[ij] = c[ij] * variance * d[static_cast<std::size_t>(i)] * d[static_cast<std::size_t>(j)];
    }
  for (int i = 0; i < p; ++i)
    (*errors)[static_cast<std::size_t>(i)] =
        std::sqrt(std::max(0.0, (*matrix)[static_cast<std::size_t>(i * p + i)]));
  return true;
}

// Which parameters sit at (within 1e-6, relative to the bound's scale, of)
// a bound of the fit: "lower", "upper" or "" for each. Td at 0, Zeta at 1 (or
// at its floor), a time constant at dt/1000 or 1000 times the record.
std::vector<std::string> AtBound(const Record& record, const std::vector<double>& values) {
  std::vector<std::string> at(values.size());
  const int p = static_cast<int>(values.size());
  if (p == 0) return at;
  const double td = values.back();
  if (td <= 1e-6 * record.dt_s)
    at.back() = "lower";
  else if (td >= record.max_delay_s * (1 - 1e-6))
    at.back() = "upper";
  for (int i = 1; i < p - 1 && record.kind != ProcessModelKind::kTf; ++i) {
    const double v = values[static_cast<std::size_t>(i)];
    std::string& a = at[static_cast<std::size_t>(i)];
    if (IsLogParameter(record, i)) {
      if (v <= record.dt_s / kTimeConstantRange * (1 + 1e-6))
        a = "lower";
      else if (v >= record.length_s * kTimeConstantRange * (1 - 1e-6))
        a = "upper";
    } else if (!IsZeroParameter(record.kind, i)) {  // Zeta
      if (v >= 1.0 - 1e-6)
        a = "upper";
      else if (v <= kMinZeta * (1 + 1e-6))
        a = "lower";
    }
  }
  return at;
}

// The plain warnings of IdentifyResult::warnings.
std::vector<std::string> Warnings(const Record& record, const IdentifyResult& r) {
  const double max_delay_s = record.max_delay_s;
  std::vector<std::string> w;
  if (!r.covariance_ok) w.push_back("no intervals: " + r.covariance_message);
  for (std::size_t i = 0; i < r.names.size() && r.covariance_ok; ++i) {
    const double half = 1.96 * r.standard_errors[i];
    if (!r.at_bound[i].empty()) continue;  // said below, with its one-sided interval
    if (half > std::abs(r.values[i]))
      w.push_back(r.names[i] + " = " + Number(r.values[i]) + " +- " + Number(half) +
                  " (95 %): the interval is wider than the value, so the data do not determine " +
                  r.names[i]);
  }
  const double td = r.model.td_s;
  if (r.at_bound.back() == "lower")
    w.push_back(
        "Td = " + Number(td) +
        " s is at its lower bound 0: the record shows no dead time the fit can resolve; its interval is "
        "one-sided and not reported");
  for (std::size_t i = 0; i < r.names.size(); ++i)
    if (r.names[i] == "Zeta" && !r.at_bound[i].empty())
      w.push_back("Zeta = " + Number(r.values[i]) + " is at its " + r.at_bound[i] + " bound (" +
                  (r.at_bound[i] == "upper" ? "1: the poles are real or nearly so, which p2d describes"
                                            : Number(kMinZeta) + ": an undamped oscillation") +
                  "); its interval is one-sided and not reported");
  if (r.starts >= 3 && r.starts_at_best < 3)
    w.push_back("only " + std::to_string(r.starts_at_best) + " of " + std::to_string(r.starts) +
                " starts reached the best cost" +
                (r.bounds_refit_improved ? " (the refit with the parameters at a bound held there found it)"
                 : r.delay_profile_improved ? " (the delay's profile found it)"
                                            : "") +
                ": the optimum may not be the global one; try more --starts or another --seed");
  if (td >= max_delay_s * (1 - 1e-6))
    w.push_back("Td = " + Number(td) + " s is at its bound (" + Number(max_delay_s) +
                " s, half the record): the delay may be longer than the record can show");
  // An exact fit (residual RMS below 1e-9 of the output's spread, as with
  // noise-free data) leaves rounding in its residuals: not worth a warning.
  const bool exact = r.fit_percent > 100.0 * (1.0 - 1e-9);
  if (r.whiteness.lags > 0 && !r.whiteness.white && !exact)
    w.push_back("the residuals are not white (Ljung-Box Q = " + Number(r.whiteness.ljung_box_q) + " over " +
                std::to_string(r.whiteness.lags) + " lags, p = " + Number(r.whiteness.p_value) +
                "): the model leaves dynamics unexplained, or the noise is coloured");
  return w;
}

// Each sample's weight rho'(r^2) and, under a robust loss, the samples it
// down-weighted and the fit of the residuals themselves (the cost is then
// not their sum of squares).
void SummariseLoss(const Record& record, double spread, IdentifyResult* result) {
  result->weights.assign(result->residuals.size(), 1.0);
  if (!record.loss) return;
  double squares = 0.0;
  for (std::size_t k = 0; k < result->residuals.size(); ++k) {
    const double r = result->residuals[k];
    squares += r * r;
    result->weights[k] = SampleWeight(record, r);
    if (result->weights[k] < kDownweightedBelow) result->downweighted.push_back(static_cast<int>(k));
  }
  result->fit_percent = 100.0 * (1.0 - std::sqrt(squares) / std::sqrt(spread));
}

}  // namespace

// Figures of merit of the fit at `theta` into *result.
void Summarise(const Record& record, const IdentifyData& data, const std::vector<double>& theta, double cost,
               IdentifyResult* result, const IdentifyResult* contained) {
  const double n = static_cast<double>(data.y.size());
  result->model = ModelOf(record, theta.data());
  result->names = ParameterNames(record.kind, record.poles, record.zeros);
  result->values = ParameterValues(result->model);
  result->cost = cost;
  double mean = 0.0;
  for (double v : data.y) mean += v / n;
  double spread = 0.0;
  for (double v : data.y) spread += (v - mean) * (v - mean);
  result->fit_percent = 100.0 * (1.0 - std::sqrt(2.0 * cost) / std::sqrt(spread));
  result->aic =
      n * std::log(2.0 * cost / n) + 2.0 * (BlockSize(record) + FittedStates(record, result->model));
  const double offset = OffsetOf(record, theta.data());
  result->y0 += offset;
  result->y0_estimated = record.offset;
  result->u0 += InputOffsetOf(record, theta.data());
  result->u0_estimated = record.input_offset;
  result->covariance_ok =
      Covariance(record, theta, cost, &result->standard_errors, &result->covariance,
                 &result->y0_standard_error, &result->u0_standard_error, &result->covariance_message);
  std::vector<double> yhat;
  result->initial_state.assign(static_cast<std::size_t>(internal::ModelOrder(result->model)), 0.0);
  if (TrySimulate(result->model, record, &yhat, offset, InputOffsetOf(record, theta.data()), true,
                  &result->initial_state)) {
    if (result->initial_state.empty())
      result->initial_state.assign(static_cast<std::size_t>(internal::ModelOrder(result->model)), 0.0);
    for (std::size_t k = 0; k < yhat.size(); ++k) {
      result->simulated.push_back(result->y0 + yhat[k]);
      result->residuals.push_back(record.dy[k] - offset - yhat[k]);
    }
    result->whiteness = ResidualWhiteness(result->residuals);
    // The cost of the parameters reported, from the residuals reported.
    double resimulated = 0.0;
    for (double r : result->residuals) resimulated += SampleCost(record, r);
    result->cost = resimulated;
  }
  SummariseLoss(record, spread, result);
  result->at_bound = AtBound(record, result->values);
  for (std::size_t i = 0; i < result->at_bound.size(); ++i)
    if (!result->at_bound[i].empty() && i < result->standard_errors.size()) result->standard_errors[i] = kNaN;
  result->warnings = Warnings(record, *result);
  result->not_identifiable = NotIdentifiable(record, *result);
  for (const IdentifyResult::NotIdentifiable& entry : result->not_identifiable)
    result->warnings.push_back(NotIdentifiableWarning(entry, *result, contained));
}

}  // namespace pidlab::identify::internal
