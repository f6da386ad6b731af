// The residuals' whiteness test and the choice among the kinds by AIC
// (identify.h; docs/identify.md, "Choosing the model" and "The output").

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <complex>
#include <iomanip>
#include <sstream>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/field.h"

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

namespace {

// The roots of den (descending powers), the upper one of a pair first;
// complex roots of a real polynomial come in conjugate pairs.
std::vector<std::complex<double>> Roots(const std::vector<double>& den) {
  std::vector<double> d = den;
  std::vector<std::complex<double>> roots;
  while (d.size() > 1 && d.back() == 0.0) {  // factors of s
    roots.emplace_back(0.0, 0.0);
    d.pop_back();
  }
  const int n = static_cast<int>(d.size()) - 1;
  if (n >= 1) {
    Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
    for (int j = 0; j < n; ++j) companion(0, j) = -d[static_cast<std::size_t>(j + 1)] / d[0];
    for (int i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
    const Eigen::VectorXcd eig = companion.eigenvalues();
    for (int i = 0; i < n; ++i) roots.push_back(eig[i]);
  }
  std::sort(roots.begin(), roots.end(), [](const std::complex<double>& a, const std::complex<double>& b) {
    return a.real() != b.real() ? a.real() > b.real() : a.imag() > b.imag();
  });
  return roots;
}

}  // namespace

std::vector<PoleEstimate> PoleEstimates(const IdentifyResult& result) {
  const std::vector<std::complex<double>> poles = Roots(result.model.ToTransferFunction().den);
  std::vector<PoleEstimate> out;
  for (const auto& p : poles) out.push_back({p.real(), p.imag()});
  const std::size_t n = result.values.size();
  if (!result.covariance_ok || result.covariance.size() != n * n) return out;
  // d(re, im)/d value_j by central differences, relative steps.
  std::vector<std::vector<double>> d_re(poles.size(), std::vector<double>(n)), d_im = d_re;
  for (std::size_t j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(std::abs(result.values[j]), 1e-6);
    std::vector<double> up = result.values, down = result.values;
    up[j] += h;
    down[j] -= h;
    const auto pu = Roots(ModelFromValues(result.model.kind, up, result.model.poles, result.model.zeros)
                              .ToTransferFunction()
                              .den);
    const auto pd = Roots(ModelFromValues(result.model.kind, down, result.model.poles, result.model.zeros)
                              .ToTransferFunction()
                              .den);
    if (pu.size() != poles.size() || pd.size() != poles.size()) return out;
    for (std::size_t i = 0; i < poles.size(); ++i) {
      d_re[i][j] = (pu[i].real() - pd[i].real()) / (2.0 * h);
      d_im[i][j] = (pu[i].imag() - pd[i].imag()) / (2.0 * h);
    }
  }
  for (std::size_t i = 0; i < poles.size(); ++i) {
    double v_re = 0.0, v_im = 0.0;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) {
        v_re += d_re[i][a] * result.covariance[a * n + b] * d_re[i][b];
        v_im += d_im[i][a] * result.covariance[a * n + b] * d_im[i][b];
      }
    out[i].re_se = std::sqrt(std::max(0.0, v_re));
    out[i].im_se = std::sqrt(std::max(0.0, v_im));
  }
  return out;
}

Status IdentifyAuto(const IdentifyData& data, const IdentifyOptions& options, AutoResult* result) {
  *result = AutoResult{};
  for (ProcessModelKind kind : {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU,
                                ProcessModelKind::kP1DI, ProcessModelKind::kP2DZ}) {
    AutoCandidate c;
    c.kind = kind;
    // The model it contains, fitted before it: P1D for P2D, P2D for P2DU and P2DZ.
    const IdentifyResult* contained = nullptr;
    const ProcessModelKind inner =
        kind == ProcessModelKind::kP2D ? ProcessModelKind::kP1D : ProcessModelKind::kP2D;
    for (const AutoCandidate& before : result->candidates)
      if (before.kind == inner && before.status.ok() && kind != ProcessModelKind::kP1D &&
          kind != ProcessModelKind::kP1DI)
        contained = &before.result;
    c.status = Identify(data, kind, options, contained, &c.result);
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
  if (lowest < 0) {
    std::string why;
    for (const AutoCandidate& c : result->candidates)
      if (!c.status.ok() && why.empty()) why = std::string(ToString(c.kind)) + ": " + c.status.message();
    return Status::RunnerFailed("no model kind could be fitted (p1d, p2d, p2du, p1di and p2dz tried" +
                                (why.empty() ? std::string(")") : "; " + spec::Truncate(why, 150) + ")"));
  }
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
