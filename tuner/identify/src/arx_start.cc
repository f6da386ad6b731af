#include "arx_start.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>

namespace pidlab::identify::internal {
namespace {

// Delays tried per sampling scale.
constexpr long kDelaysPerScale = 40;

int PoleCount(ProcessModelKind kind) { return kind == ProcessModelKind::kP1D ? 1 : 2; }

// The roots of z^n + a_1 z^(n-1) + ... + a_n: by formula for n = 1 or 2,
// else the eigenvalues of the companion matrix.
std::vector<std::complex<double>> Roots(const Eigen::VectorXd& a) {
  if (a.size() == 1) return {std::complex<double>(-a[0], 0.0)};
  if (a.size() == 2) {
    const std::complex<double> disc = std::sqrt(std::complex<double>(a[0] * a[0] - 4.0 * a[1], 0.0));
    return {(-a[0] + disc) / 2.0, (-a[0] - disc) / 2.0};
  }
  const auto n = a.size();
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  companion.row(0) = -a.transpose();
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  const Eigen::VectorXcd eig = companion.eigenvalues();
  return {eig.data(), eig.data() + n};
}

// The values of `kind` from its discrete poles; empty if they do not fit it.
std::optional<std::vector<double>> FromPoles(ProcessModelKind kind,
                                             const std::vector<std::complex<double>>& z, double dt_s,
                                             double td_s) {
  std::vector<std::complex<double>> s;
  for (const auto& zi : z) {
    if (std::abs(zi) <= 0.0) return std::nullopt;
    s.push_back(std::log(zi) / dt_s);
  }
  const auto lag = [](std::complex<double> p) -> std::optional<double> {
    if (!(p.real() < 0.0) || std::abs(p.imag()) > 1e-9 * std::abs(p)) return std::nullopt;
    return -1.0 / p.real();
  };
  switch (kind) {
    case ProcessModelKind::kP1D: {
      const auto t = lag(s[0]);
      if (!t) return std::nullopt;
      return std::vector<double>{1.0, *t, td_s};
    }
    case ProcessModelKind::kP2D: {
      if (std::abs(s[0].imag()) > 1e-9 * std::abs(s[0])) {
        // A complex pair: two equal lags of the same modulus.
        if (!(s[0].real() < 0.0)) return std::nullopt;
        const double t = 1.0 / std::abs(s[0]);
        return std::vector<double>{1.0, t, t, td_s};
      }
      const auto t1 = lag(s[0]), t2 = lag(s[1]);
      if (!t1 || !t2) return std::nullopt;
      return std::vector<double>{1.0, std::max(*t1, *t2), std::min(*t1, *t2), td_s};
    }
    case ProcessModelKind::kP2DU: {
      // wn^2 = s1 s2, 2 zeta wn = -(s1 + s2), for a pair or two real poles.
      const double product = (s[0] * s[1]).real(), sum = (s[0] + s[1]).real();
      if (!(product > 0.0) || !(sum < 0.0)) return std::nullopt;
      const double wn = std::sqrt(product);
      const double zeta = std::clamp(-sum / (2.0 * wn), 1e-3, 0.999);
      return std::vector<double>{1.0, 1.0 / wn, zeta, td_s};
    }
    case ProcessModelKind::kP2DZ: {
      // P2D's poles and no zero yet (Tz = 0): the fit finds the zero.
      auto p2d = FromPoles(ProcessModelKind::kP2D, z, dt_s, td_s);
      if (!p2d) return std::nullopt;
      return std::vector<double>{1.0, (*p2d)[1], (*p2d)[2], 0.0, td_s};
    }
    case ProcessModelKind::kTf:  // tf_start.h
      return std::nullopt;
    case ProcessModelKind::kP1DI: {
      // The pole nearest z = 1 is the integrator; the other the lag.
      const std::size_t integrator = std::abs(z[0] - 1.0) < std::abs(z[1] - 1.0) ? 0 : 1;
      const auto t = lag(s[1 - integrator]);
      if (!t) return std::nullopt;
      return std::vector<double>{1.0, *t, td_s};
    }
  }
  return std::nullopt;
}

}  // namespace

std::vector<ArxFit> ArxFits(int n, const std::vector<double>& du, const std::vector<double>& dy, double dt_s,
                            double max_delay_s) {
  std::vector<ArxFit> fits;
  const long samples = static_cast<long>(dy.size());
  for (long m = 1; samples / m >= 40L * n; m *= 2) {
    // Every m-th output, and the mean input over each coarse interval.
    const long coarse = samples / m;
    std::vector<double> yc(static_cast<std::size_t>(coarse)), uc(static_cast<std::size_t>(coarse));
    for (long j = 0; j < coarse; ++j) {
      yc[static_cast<std::size_t>(j)] = dy[static_cast<std::size_t>(j * m)];
      double sum = 0.0;
      for (long i = 0; i < m; ++i) sum += du[static_cast<std::size_t>(j * m + i)];
      uc[static_cast<std::size_t>(j)] = sum / static_cast<double>(m);
    }
    const double h = dt_s * static_cast<double>(m);
    const long max_d = std::min(static_cast<long>(std::floor(max_delay_s / h)), coarse / 2);
    const long step = std::max(1L, (max_d + kDelaysPerScale - 1) / kDelaysPerScale);
    for (long d = 0; d <= max_d; d += step) {
      const long first = n + d;
      const long rows = coarse - first;
      if (rows < 4 * n) break;
      Eigen::MatrixXd phi(rows, 2 * n);
      Eigen::VectorXd target(rows);
      for (long r = 0; r < rows; ++r) {
        const long k = first + r;
        for (int i = 1; i <= n; ++i) {
          phi(r, i - 1) = -yc[static_cast<std::size_t>(k - i)];
          phi(r, n + i - 1) = uc[static_cast<std::size_t>(k - i - d)];
        }
        target[r] = yc[static_cast<std::size_t>(k)];
      }
      const Eigen::VectorXd theta = phi.colPivHouseholderQr().solve(target);
      if (!theta.allFinite()) continue;
      fits.push_back({Roots(theta.head(n)), h, static_cast<double>(d) * h});
    }
  }
  return fits;
}

std::vector<std::vector<double>> ArxCandidates(ProcessModelKind kind, const std::vector<double>& du,
                                               const std::vector<double>& dy, double dt_s,
                                               double max_delay_s) {
  std::vector<std::vector<double>> candidates;
  for (const ArxFit& fit : ArxFits(PoleCount(kind), du, dy, dt_s, max_delay_s)) {
    auto values = FromPoles(kind, fit.z, fit.h_s, fit.td_s);
    if (values) candidates.push_back(*values);
  }
  return candidates;
}

}  // namespace pidlab::identify::internal
