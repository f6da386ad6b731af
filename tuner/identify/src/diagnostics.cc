// The residuals' whiteness test and the choice among the kinds by AIC
// (identify.h; docs/identify.md, "Choosing the model" and "The output").

#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "pidlab/identify/identify.h"

namespace pidlab::identify {

Whiteness ResidualWhiteness(const std::vector<double>& residuals) {
  Whiteness w;
  const std::size_t n = residuals.size();
  if (n < 2) return w;
  w.lags = static_cast<int>(std::max<std::size_t>(1, std::min<std::size_t>(25, n / 4)));
  double mean = 0.0;
  for (double e : residuals) mean += e / static_cast<double>(n);
  double r0 = 0.0;
  for (double e : residuals) r0 += (e - mean) * (e - mean);
  const double nn = static_cast<double>(n);
  w.band = 1.96 / std::sqrt(nn);
  for (int k = 1; k <= w.lags; ++k) {
    double rk = 0.0;
    for (std::size_t i = 0; i + static_cast<std::size_t>(k) < n; ++i)
      rk += (residuals[i] - mean) * (residuals[i + static_cast<std::size_t>(k)] - mean);
    rk = r0 > 0.0 ? rk / r0 : 0.0;
    w.autocorrelation.push_back(rk);
    w.outside_band += std::abs(rk) > w.band ? 1 : 0;
    w.ljung_box_q += rk * rk / (nn - k);
  }
  w.ljung_box_q *= nn * (nn + 2.0);
  w.p_value = r0 > 0.0 ? boost::math::gamma_q(0.5 * w.lags, 0.5 * w.ljung_box_q) : 1.0;
  w.white = w.p_value >= 0.05;
  return w;
}

Status IdentifyAuto(const IdentifyData& data, const IdentifyOptions& options, AutoResult* result) {
  *result = AutoResult{};
  for (ProcessModelKind kind :
       {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU, ProcessModelKind::kP1DI}) {
    AutoCandidate c;
    c.kind = kind;
    c.status = Identify(data, kind, options, &c.result);
    // Bad data or options are the same for every kind: say it once.
    if (c.status.code() == StatusCode::kInvalidInput) return c.status;
    result->candidates.push_back(std::move(c));
  }
  // The lowest AIC; then, among the kinds within 2 of it (which the data
  // hardly tell apart, Burnham & Anderson), the one of fewest parameters.
  int lowest = -1;
  const auto aic = [&](int i) { return result->candidates[static_cast<std::size_t>(i)].result.aic; };
  const auto usable = [&](int i) {
    const AutoCandidate& c = result->candidates[static_cast<std::size_t>(i)];
    return c.status.ok() && std::isfinite(c.result.aic);
  };
  const int count = static_cast<int>(result->candidates.size());
  for (int i = 0; i < count; ++i)
    if (usable(i) && (lowest < 0 || aic(i) < aic(lowest))) lowest = i;
  if (lowest < 0) return Status::RunnerFailed("no model kind could be fitted");
  const auto parameters = [&](int i) {
    return result->candidates[static_cast<std::size_t>(i)].result.names.size();
  };
  result->chosen = lowest;
  for (int i = 0; i < count; ++i)
    if (usable(i) && aic(i) < aic(lowest) + 2.0 &&
        (parameters(i) < parameters(result->chosen) ||
         (parameters(i) == parameters(result->chosen) && aic(i) < aic(result->chosen))))
      result->chosen = i;
  const AutoCandidate& best = result->candidates[static_cast<std::size_t>(result->chosen)];
  std::ostringstream os;
  os << std::setprecision(6);
  if (result->chosen == lowest) {
    // The runner-up: the next lowest AIC.
    int next = -1;
    for (int i = 0; i < count; ++i)
      if (i != lowest && usable(i) && (next < 0 || aic(i) < aic(next))) next = i;
    os << ToString(best.kind) << " has the lowest AIC (" << best.result.aic << ", fit "
       << best.result.fit_percent << " %)";
    if (next >= 0) {
      const double delta = aic(next) - aic(lowest);
      os << "; the next, " << ToString(result->candidates[static_cast<std::size_t>(next)].kind) << ", is "
         << delta << " higher";
      if (delta < 2.0)
        os << " (less than 2, but it has more parameters)";
      else if (delta > 10.0)
        os << " (more than 10: the data rule it out)";
    }
  } else {
    os << ToString(best.kind) << " (AIC " << best.result.aic << ", fit " << best.result.fit_percent
       << " %) is within 2 of the lowest AIC, "
       << ToString(result->candidates[static_cast<std::size_t>(lowest)].kind) << "'s " << aic(lowest)
       << ", with fewer parameters (" << best.result.names.size() << " against " << parameters(lowest)
       << "): the data hardly tell them apart, so the simpler is kept";
  }
  result->reason = os.str();
  return Status::Ok();
}

}  // namespace pidlab::identify
