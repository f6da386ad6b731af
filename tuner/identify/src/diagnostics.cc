// The residuals' whiteness test and the poles' standard errors (identify.h;
// docs/identify.md, "The output").

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <complex>

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

}  // namespace pidlab::identify
