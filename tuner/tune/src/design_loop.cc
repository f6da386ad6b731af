// The design engine's loop: responses on a uniform grid and peaks on a
// frequency grid (design_loop.h).

#include "design_loop.h"

#include <algorithm>
#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::tune::design {

using cd = std::complex<double>;

namespace {

cd PolyAt(const std::vector<double>& p, cd s) {
  cd r = 0.0;
  for (double c : p) r = r * s + c;
  return r;
}

// The loop's linear system for gains g and inputs in, with the dead time
// moved to the measurement (the same loop: u(t) = -C[G(u + d)](t - L)):
// states z = [x; the integral of e; the derivative filter's state], the
// delayed output m(t) = y(t - L) as input and a constant drive q (the unit
// steps):
//   z' = M z + nm m + nq,   u = kz z + km m + kq,   y = cy z + dym m + dyq,
// y the plant's output before the dead time. The controller's fast
// transients (its derivative kick) stay inside the exact discretisation;
// only y, smoothed by the plant, is interpolated.
struct LoopMatrices {
  Eigen::MatrixXd m;
  Eigen::VectorXd nm, nq;
  Eigen::RowVectorXd kz, cy;
  double km = 0.0, kq = 0.0, dym = 0.0, dyq = 0.0;
};

LoopMatrices Matrices(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, const Eigen::RowVectorXd& c,
                      double d, const PidGains& g, const Inputs& in) {
  const int n = static_cast<int>(a.rows());
  const bool filter = g.kd > 0.0;
  const int nz = n + 1 + (filter ? 1 : 0);
  const double kdf = filter ? g.kd / g.tf : 0.0;
  const double kinf = g.kp + kdf;
  LoopMatrices lm;
  lm.kz = Eigen::RowVectorXd::Zero(nz);
  lm.kz(n) = g.ki;
  if (filter) lm.kz(n + 1) = -kdf;
  lm.km = -kinf;
  lm.kq = g.kp * in.r_p + kdf * in.r_d;
  lm.m = Eigen::MatrixXd::Zero(nz, nz);
  lm.m.topLeftCorner(n, n) = a;
  lm.m.topRows(n) += b * lm.kz;
  lm.nm = Eigen::VectorXd::Zero(nz);
  lm.nq = Eigen::VectorXd::Zero(nz);
  lm.nm.head(n) = b * lm.km;
  lm.nm(n) = -1.0;
  lm.nq.head(n) = b * (lm.kq + in.load);
  lm.nq(n) = in.r_i;
  if (filter) {
    lm.m(n + 1, n + 1) = -1.0 / g.tf;
    lm.nm(n + 1) = -1.0 / g.tf;
    lm.nq(n + 1) = in.r_d / g.tf;
  }
  lm.cy = d * lm.kz;
  lm.cy.head(n) += c;
  lm.dym = d * lm.km;
  lm.dyq = d * (lm.kq + in.load);
  return lm;
}

}  // namespace

LoopSimulator::LoopSimulator(const Plant& plant, double h_s) {
  const StateSpace ss = Realize(plant.tf);
  a_ = ss.a;
  b_ = ss.b;
  c_ = ss.c;
  d_ = ss.d;
  if (plant.delay_s > 0.0) {
    delay_steps_ = std::max(1, static_cast<int>(std::ceil(plant.delay_s / h_s - 1e-9)));
    h_ = plant.delay_s / delay_steps_;
  } else {
    h_ = h_s;
  }
}

Response LoopSimulator::Run(const PidGains& g, const Inputs& in, int max_steps, int min_steps) const {
  const LoopMatrices lm = Matrices(a_, b_, c_, d_, g, in);
  const int nz = static_cast<int>(lm.m.rows());
  Eigen::MatrixXd phi, gm, gs;
  Eigen::VectorXd gq;
  const int n_delay = delay_steps_;
  if (n_delay == 0) {
    // No delay: m = y closes the loop algebraically.
    const double den = 1.0 - lm.dym;
    Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(nz + 1, nz + 1);
    aug.topLeftCorner(nz, nz) = lm.m + lm.nm * lm.cy / den;
    aug.block(0, nz, nz, 1) = lm.nq + lm.nm * (lm.dyq / den);
    const Eigen::MatrixXd e = (aug * h_).exp();
    phi = e.topLeftCorner(nz, nz);
    gq = e.block(0, nz, nz, 1);
  } else {
    // m linear between samples: [z; m; m'; q] with m' and q constant.
    Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(nz + 3, nz + 3);
    aug.topLeftCorner(nz, nz) = lm.m;
    aug.block(0, nz, nz, 1) = lm.nm;
    aug(nz, nz + 1) = 1.0;
    aug.block(0, nz + 2, nz, 1) = lm.nq;
    const Eigen::MatrixXd e = (aug * h_).exp();
    phi = e.topLeftCorner(nz, nz);
    gm = e.block(0, nz, nz, 1);
    gs = e.block(0, nz + 1, nz, 1) / h_;
    gq = e.block(0, nz + 2, nz, 1);
  }
  Response r;
  r.y.reserve(static_cast<std::size_t>(std::min(max_steps, 20000)) + 1);
  r.u.reserve(r.y.capacity());
  Eigen::VectorXd z = Eigen::VectorXd::Zero(nz), next(nz);
  double peak_y = 0.0, peak_u = 0.0;
  int still = 0;
  const auto m_at = [&r, n_delay](int k) { return k >= n_delay && n_delay > 0 ? r.y[k - n_delay] : 0.0; };
  for (int k = 0;; ++k) {
    double m = 0.0, y = 0.0;
    if (n_delay == 0) {
      y = (lm.cy.dot(z) + lm.dyq) / (1.0 - lm.dym);
      m = y;
    } else {
      m = m_at(k);
      y = lm.cy.dot(z) + lm.dym * m + lm.dyq;
    }
    const double u = lm.kz.dot(z) + lm.km * m + lm.kq;
    if (!std::isfinite(y) || !std::isfinite(u) || std::abs(y) > 1e12 || std::abs(u) > 1e15) return r;
    if (k > 0) {
      const bool y_still = std::abs(y - r.y.back()) <= 1e-9 * std::max(peak_y, 1e-300);
      const bool u_still = std::abs(u - r.u.back()) <= 1e-9 * std::max(peak_u, 1e-300);
      still = y_still && u_still ? still + 1 : 0;
    }
    r.y.push_back(y);
    r.u.push_back(u);
    peak_y = std::max(peak_y, std::abs(y));
    peak_u = std::max(peak_u, std::abs(u));
    if (k >= min_steps && still > n_delay + 50) {
      r.settled = true;
      return r;
    }
    if (k >= max_steps) return r;
    if (n_delay == 0) {
      next.noalias() = phi * z + gq;
    } else {
      // m(k+1) = y(k+1-N) is known: N >= 1.
      const double m_next = m_at(k + 1);
      next.noalias() = phi * z + gm * m + gs * (m_next - m) + gq;
    }
    z.swap(next);
  }
}

double IntegralAbs(const std::vector<double>& y, double target, double h) {
  double sum = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) {
    const double a = y[k - 1] - target, b = y[k] - target;
    if ((a >= 0.0) == (b >= 0.0)) {
      sum += 0.5 * h * std::abs(a + b);
    } else {
      const double m = std::abs(a) + std::abs(b);
      sum += 0.5 * h * (a * a + b * b) / m;
    }
  }
  return sum;
}

FrequencyGrid MakeFrequencyGrid(const Plant& plant, double w_lo, double w_hi, double points_per_decade) {
  FrequencyGrid grid;
  const double lo = std::log10(w_lo), hi = std::log10(w_hi);
  const int n = std::max(2, std::min(6000, static_cast<int>(std::ceil((hi - lo) * points_per_decade)) + 1));
  for (int i = 0; i < n; ++i) {
    const double w = std::pow(10.0, lo + (hi - lo) * i / (n - 1));
    const cd s(0.0, w);
    grid.w.push_back(w);
    grid.g.push_back(PolyAt(plant.tf.num, s) / PolyAt(plant.tf.den, s) *
                     std::exp(cd(0.0, -w * plant.delay_s)));
  }
  for (int i = 0; i < n; ++i) {
    const double dw = i + 1 < n ? grid.w[i + 1] - grid.w[i] : grid.w[i] - grid.w[i - 1];
    grid.coarse.push_back(plant.delay_s * dw > 0.6 ? 1 : 0);
  }
  std::vector<double> num = plant.tf.num, den = plant.tf.den;
  while (num.size() > 1 && num.front() == 0.0) num.erase(num.begin());
  while (den.size() > 1 && den.front() == 0.0) den.erase(den.begin());
  grid.g_inf = num.size() == den.size() ? num.front() / den.front() : 0.0;
  return grid;
}

cd ControllerAt(const PidGains& g, double w) {
  const cd s(0.0, w);
  return g.kp + g.ki / s + (g.kd > 0.0 ? g.kd * s / (1.0 + g.tf * s) : cd(0.0));
}

Peaks PeaksOf(const FrequencyGrid& grid, const PidGains& g) {
  Peaks p;
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < grid.w.size(); ++i) {
    const cd c = ControllerAt(g, grid.w[i]);
    const cd l = c * grid.g[i];
    const double ml = std::abs(l);
    double s = 0.0, t = 0.0, cs = 0.0;
    if (grid.coarse[i]) {
      // The delay turns L faster than the grid: the worst phase.
      if (ml >= 1.0) return Peaks{inf, inf, inf, grid.w[i]};
      s = 1.0 / (1.0 - ml);
      t = ml * s;
      cs = std::abs(c) * s;
    } else {
      const double d = std::abs(1.0 + l);
      s = 1.0 / d;
      t = ml / d;
      cs = std::abs(c) / d;
    }
    p.ms = std::max(p.ms, s);
    p.mt = std::max(p.mt, t);
    p.noise_gain = std::max(p.noise_gain, cs);
    if (ml >= 1.0) p.crossover = grid.w[i];
  }
  const double c_inf = g.kp + (g.kd > 0.0 ? g.kd / g.tf : 0.0);
  const double l_inf = c_inf * grid.g_inf;
  const double s_inf = 1.0 / std::abs(1.0 + l_inf);
  p.ms = std::max(p.ms, s_inf);
  p.mt = std::max(p.mt, std::abs(l_inf) * s_inf);
  p.noise_gain = std::max(p.noise_gain, c_inf * s_inf);
  return p;
}

}  // namespace pidlab::tune::design
