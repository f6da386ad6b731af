// The sampled loop's stability: the eigenvalues of its one-step map
// (SampledStability), and for a long delay line the same verdict from the
// argument principle (SampledLoopIsStable), without the O((n + d)^3) dense
// eigenvalue problem. docs/deadtime.md, "The sampled loop's stability gate".

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <optional>
#include <vector>

#include "pidlab/evaluation/closed_loop.h"

namespace pidlab::evaluation {
namespace {

using cd = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

// The PID's rows over a state whose controller part [I_{k-1}; D_{k-1};
// e_{k-1}; s_{k-1}] starts at column c0, with r = n = 0 so that e_k = s_k =
// -C x_k for both derivative modes (the plant's x at columns 0 .. n - 1).
struct ControllerRows {
  Eigen::RowVectorXd e, i, d, u;
};

ControllerRows MakeControllerRows(const DiscretePlant& plant, const PidGains& g, const PidOptions& o,
                                  int size, int c0) {
  const int n = plant.order();
  const int ii = c0, id = c0 + 1, iep = c0 + 2, isp = c0 + 3;
  const double dt = o.dt_s, tf = EffectiveDerivativeFilter(g, o);
  const double a = tf / (tf + dt), b = g.kd / (tf + dt);
  ControllerRows r;
  r.e = Eigen::RowVectorXd::Zero(size);
  r.e.head(n) = -plant.c();
  r.i = Eigen::RowVectorXd::Zero(size);
  r.i(ii) = 1.0;
  switch (o.integral) {
    case IntegralMethod::kBackwardEuler:
      r.i += g.ki * dt * r.e;
      break;
    case IntegralMethod::kForwardEuler:
      r.i(iep) += g.ki * dt;
      break;
    case IntegralMethod::kTrapezoidal:
      r.i += 0.5 * g.ki * dt * r.e;
      r.i(iep) += 0.5 * g.ki * dt;
      break;
  }
  r.d = b * r.e;
  r.d(id) += a;
  r.d(isp) -= b;
  r.u = g.kp * r.e + r.i + r.d;
  return r;
}

// The controller's rows of a loop matrix, from column c0 on. With ki = 0 the
// integral stays 0: its hidden eigenvalue at z = 1 is dropped (row zero).
void SetControllerRows(const ControllerRows& r, double ki, int c0, Eigen::MatrixXd* m) {
  m->row(c0) = r.i;
  m->row(c0 + 1) = r.d;
  m->row(c0 + 2) = r.e;
  m->row(c0 + 3) = r.e;
  if (ki == 0.0) m->row(c0).setZero();
}

// The plant's rows of the sampled loop matrix m over the state
// [x; u_{k-1} .. u_{k-d}; ...] (the delay line at columns n .. n + d - 1):
// x_{k+1} = Phi x + Gamma1 u_{k-d} + Gamma0 u_{k-d+1} (u_{k-d} = u_k when
// d = 0, u_{k-d+1} = u_k when d = 1), the line shifted by one with u_k in
// front. u_row is u_k over the state.
void SetPlantRows(const DiscretePlant& plant, const Eigen::RowVectorXd& u_row, Eigen::MatrixXd* m) {
  const int n = plant.order();
  const int d = static_cast<int>(plant.delay_steps());
  m->topLeftCorner(n, n) = plant.phi();
  const auto input = [&](int age) -> Eigen::RowVectorXd {  // u_{k-age} over the state
    if (age == 0) return u_row;
    Eigen::RowVectorXd e = Eigen::RowVectorXd::Zero(u_row.size());
    e(n + age - 1) = 1.0;
    return e;
  };
  m->topRows(n) += plant.gamma1() * input(d);
  if (plant.gamma0().size() > 0) m->topRows(n) += plant.gamma0() * input(d - 1);
  for (int j = 0; j < d; ++j) m->row(n + j) = input(j);
}

// The margin's boundary: the decay sigma_b(w) at which the criterion
// Re p < -m max(1, min(|p|, cap)) turns, for p = sigma + j w (w >= 0, m < 1).
// sigma + m max(1, min(|p|, cap)) grows strictly with sigma, so the set is
// sigma < sigma_b(w), and z = e^{p dt} lies inside iff |z| < e^{sigma_b dt}.
double MarginBoundary(double w, double m, double cap) {
  const double s = std::sqrt(1.0 - m * m);
  const double modulus = w / s;  // |p| on the middle branch sigma = -m |p|
  if (modulus <= 1.0 || cap <= 1.0) return -m;
  if (modulus >= cap) return -m * cap;
  return -m * modulus;
}

// h(z) = z^-d det(zI - M) = alpha(z) - z^-d beta(z) on the margin's contour,
// with alpha = det(zI - A) and beta = u adj(zI - A) (b1 + z b0) for the loop A
// without its delay line (a Schur complement of the line's shift). A is
// block lower triangular, [Phi 0; R C] with the PID's C upper triangular, so
// one elimination of [zI - Phi | b1 + z b0] and a triangular solve give
// both: h is exact for a matrix near A even where A's own eigenvalues (the
// plant's, the integrator's) lie on or near the contour, as alpha x_i keeps
// the product of the other pivots and a small pivot cancels. h has no poles
// but z = 0.
class LoopFunction {
 public:
  LoopFunction(const Eigen::MatrixXd& a, int n, const Eigen::VectorXd& b1, const Eigen::VectorXd& b0,
               const Eigen::RowVectorXd& u, int d, double dt, double m, double cap)
      : a_(a), n_(n), b1_(b1), b0_(b0), u_(u), d_(d), dt_(dt), m_(m), cap_(cap) {}
  // Whether A has the block form the evaluation relies on.
  bool Structured() const {
    const int k = static_cast<int>(a_.rows());
    if (k <= n_ || (b1_.tail(k - n_).array() != 0.0).any() || (b0_.tail(k - n_).array() != 0.0).any())
      return false;
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) {
        const bool top_right = i < n_ && j >= n_, below_c = i >= n_ && j >= n_ && j < i;
        if ((top_right || below_c) && a_(i, j) != 0.0) return false;
      }
    return true;
  }
  // h at the contour's point z = r(theta) e^{j theta}, theta in [0, pi];
  // *scale2 = |alpha|^2 + |z^-d beta|^2 (for a near-zero test). Complex
  // quotients as products with conj(p) / |p|^2, moduli compared squared.
  cd At(double theta, double* scale2) const {
    const double log_r = MarginBoundary(theta / dt_, m_, cap_) * dt_;
    const cd z = std::exp(log_r) * cd(std::cos(theta), std::sin(theta));
    const int k = static_cast<int>(a_.rows()), n = n_;
    thread_local std::vector<cd> w, x;  // [zI - Phi | b1 + z b0], row major; the solution
    w.resize(static_cast<std::size_t>(n * (n + 1)));
    x.resize(static_cast<std::size_t>(k));
    const auto at = [&](int i, int j) -> cd& { return w[static_cast<std::size_t>(i * (n + 1) + j)]; };
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) at(i, j) = -a_(i, j);
      at(i, i) += z;
      at(i, n) = b1_(i) + z * b0_(i);
    }
    cd det = 1.0;
    bool singular = false;
    for (int c = 0; c < n && !singular; ++c) {  // partial pivoting
      int p = c;
      for (int i = c + 1; i < n; ++i)
        if (std::norm(at(i, c)) > std::norm(at(p, c))) p = i;
      if (p != c) {
        for (int j = c; j <= n; ++j) std::swap(at(p, j), at(c, j));
        det = -det;
      }
      const cd pivot = at(c, c);
      det *= pivot;
      singular = std::norm(pivot) == 0.0;
      if (singular) break;
      const cd inverse = std::conj(pivot) * (1.0 / std::norm(pivot));
      for (int i = c + 1; i < n; ++i) {
        const cd f = at(i, c) * inverse;
        for (int j = c + 1; j <= n; ++j) at(i, j) -= f * at(c, j);
      }
    }
    for (int i = n; i < k && !singular; ++i) {
      det *= z - a_(i, i);
      singular = std::norm(z - a_(i, i)) == 0.0;
    }
    if (singular) {  // alpha = 0 on the contour: h = -z^-d beta, not resolved here
      *scale2 = 1.0;
      return 0.0;
    }
    cd ux = 0.0;
    for (int i = n - 1; i >= 0; --i) {  // U x_p = y
      cd sum = at(i, n);
      for (int j = i + 1; j < n; ++j) sum -= at(i, j) * x[static_cast<std::size_t>(j)];
      x[static_cast<std::size_t>(i)] = sum * std::conj(at(i, i)) * (1.0 / std::norm(at(i, i)));
      ux += u_(i) * x[static_cast<std::size_t>(i)];
    }
    for (int i = k - 1; i >= n; --i) {  // (zI - C) x_c = R x_p
      cd sum = 0.0;
      for (int j = 0; j < n; ++j) sum += a_(i, j) * x[static_cast<std::size_t>(j)];
      for (int j = i + 1; j < k; ++j) sum += a_(i, j) * x[static_cast<std::size_t>(j)];
      const cd pivot = z - a_(i, i);
      x[static_cast<std::size_t>(i)] = sum * std::conj(pivot) * (1.0 / std::norm(pivot));
      ux += u_(i) * x[static_cast<std::size_t>(i)];
    }
    const double turn = static_cast<double>(d_) * theta;  // z^-d = r^-d e^{-j d theta}
    const cd zbeta =
        std::exp(-static_cast<double>(d_) * log_r) * cd(std::cos(turn), -std::sin(turn)) * det * ux;
    *scale2 = std::norm(det) + std::norm(zbeta);
    return det - zbeta;
  }

 private:
  const Eigen::MatrixXd& a_;
  int n_;
  const Eigen::VectorXd &b1_, &b0_;
  const Eigen::RowVectorXd& u_;
  int d_;
  double dt_, m_, cap_;
};

// The continuous change of arg h from theta0 to theta1, bisecting where the
// wrapped change exceeds 0.4 pi; nullopt when h nears zero on the contour (a
// closed-loop pole on the margin's boundary) or the bisection runs deep.
std::optional<double> ArgChange(const LoopFunction& f, double t0, double t1, cd g0, cd g1, int depth) {
  const double step = std::arg(g1 * std::conj(g0));  // the wrapped change, in (-pi, pi]
  if (std::abs(step) < 0.4 * kPi) return step;
  if (depth >= 60 || !(t1 > t0)) return std::nullopt;
  const double tm = 0.5 * (t0 + t1);
  double scale = 0.0;
  const cd gm = f.At(tm, &scale);
  if (!(std::norm(gm) > 1e-24 * scale)) return std::nullopt;
  const auto lo = ArgChange(f, t0, tm, g0, gm, depth + 1);
  const auto hi = lo ? ArgChange(f, tm, t1, gm, g1, depth + 1) : std::nullopt;
  if (!hi) return std::nullopt;
  return *lo + *hi;
}

// The angles on [0, pi] at which h is sampled first: three points a turn of
// z^-d (whose d turns over the circle dominate far from z = 1), and a log
// grid of 100 points a decade from theta_lo = max(0.1 m dt, 1e-10) (as the
// continuous loop's Nyquist grid in w), which resolves the loop's own poles
// and zeros crowding towards z = 1 as dt shrinks.
const std::vector<double>& ContourGrid(int turns, double dt, double margin) {
  const int count = std::max(64, 3 * turns);
  const double step = kPi / count, lo = std::max(0.1 * margin * dt, 1e-10);
  thread_local std::vector<double> uniform, log, theta;
  uniform.clear();
  log.clear();
  for (int j = 0; j <= count; ++j) uniform.push_back(j == count ? kPi : step * j);
  // 10^0.01 apart, where that is finer than the uniform grid.
  for (double t = lo; t < kPi && t * 0.0232929922807541 < step; t *= 1.0232929922807541) log.push_back(t);
  theta.resize(uniform.size() + log.size());
  std::merge(uniform.begin(), uniform.end(), log.begin(), log.end(), theta.begin());
  return theta;
}

}  // namespace

std::optional<bool> CountedSampledStability(const DiscretePlant& plant, const PidGains& g,
                                            const PidOptions& o, double margin) {
  if (!(margin >= 0.0) || !(margin < 1.0)) return std::nullopt;
  const int n = plant.order();
  const int d = static_cast<int>(plant.delay_steps());
  const int k = n + 4;
  const ControllerRows rows = MakeControllerRows(plant, g, o, k, n);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(k, k);
  a.topLeftCorner(n, n) = plant.phi();
  SetControllerRows(rows, g.ki, n, &a);
  Eigen::VectorXd b1 = Eigen::VectorXd::Zero(k), b0 = Eigen::VectorXd::Zero(k);
  b1.head(n) = plant.gamma1();
  if (plant.gamma0().size() > 0) b0.head(n) = plant.gamma0();
  const LoopFunction f(a, n, b1, b0, rows.u, d, o.dt_s, margin, DelayedMarginModulus(plant.delay_s()));
  if (!f.Structured()) return std::nullopt;
  const std::vector<double>& theta = ContourGrid(d + k, o.dt_s, margin);
  double total = 0.0, scale = 0.0;
  cd prev = f.At(theta.front(), &scale);
  if (!(std::norm(prev) > 1e-24 * scale)) return std::nullopt;
  for (std::size_t j = 1; j < theta.size(); ++j) {
    const cd next = f.At(theta[j], &scale);
    if (!(std::norm(next) > 1e-24 * scale)) return std::nullopt;
    const auto change = ArgChange(f, theta[j - 1], theta[j], prev, next, 0);
    if (!change) return std::nullopt;
    total += *change;
    prev = next;
  }
  // h is real at theta = 0 and pi, and h(conj z) = conj h(z): the lower half
  // turns as the upper, so the winding is this half's change over pi. All
  // n + d + 4 zeros of det(zI - M) lie inside iff h (with its pole of order
  // d at 0) winds n + 4 times.
  const double turns = total / kPi;
  const double whole = std::round(turns);
  if (std::abs(turns - whole) > 0.05) return std::nullopt;
  return static_cast<int>(whole) == k;
}

Stability SampledStability(const DiscretePlant& plant, const PidGains& g, const PidOptions& o,
                           double margin) {
  // State z_k = [x_k; u_{k-1} .. u_{k-d}; I_{k-1}; D_{k-1}; e_{k-1}; s_{k-1}].
  const int n = plant.order();
  const int d = static_cast<int>(plant.delay_steps());
  const int size = n + d + 4;
  const ControllerRows rows = MakeControllerRows(plant, g, o, size, n + d);
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(size, size);
  SetPlantRows(plant, rows.u, &m);
  SetControllerRows(rows, g.ki, n + d, &m);
  // The verdict is a function of the map, dt, the margin and the dead time
  // alone. An evaluation and the analysis of the same loop (a Monte Carlo
  // draw runs both) ask for it twice in a row: the thread's last answer is
  // given again, bit for bit, when all four are the same, instead of solving
  // the (n + d + 4)-square eigenvalue problem a second time.
  struct Last {
    Eigen::MatrixXd m;
    double dt_s = 0.0, margin = 0.0, delay_s = 0.0;
    Stability s;
  };
  thread_local Last last;
  const auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  if (last.m.rows() == size && same(last.dt_s, o.dt_s) && same(last.margin, margin) &&
      same(last.delay_s, plant.delay_s()) &&
      std::memcmp(last.m.data(), m.data(), sizeof(double) * static_cast<std::size_t>(m.size())) == 0)
    return last.s;
  last.m = m;
  last.dt_s = o.dt_s;
  last.margin = margin;
  last.delay_s = plant.delay_s();
  BalanceInPlace(&m);
  Eigen::EigenSolver<Eigen::MatrixXd> es(m, false);
  Stability s;
  s.abscissa = 0.0;
  bool ok = es.info() == Eigen::Success;
  // The continuous criterion Re p < -margin max(1, |p|) applied to the
  // equivalent s-plane poles p = log(z) / dt, so that a margin means the same
  // in both loops whatever dt; z = 0 is the fastest possible decay. With a
  // dead time L, |p| counts up to pi / L only (DelayedMarginModulus).
  const double cap = DelayedMarginModulus(plant.delay_s());
  for (int i = 0; i < size && es.info() == Eigen::Success; ++i) {  // every pole, even past an unstable one
    const std::complex<double> z = es.eigenvalues()(i);
    s.poles.push_back(z);
    s.abscissa = std::max(s.abscissa, std::abs(z));
    if (!std::isfinite(std::abs(z)) || !(std::abs(z) < 1.0)) {
      ok = false;
    } else if (std::abs(z) > 0.0) {
      const std::complex<double> p = std::log(z) / o.dt_s;
      if (!(p.real() < -margin * std::max(1.0, std::min(std::abs(p), cap)))) ok = false;
    }
  }
  s.stable = ok && std::isfinite(s.abscissa) && s.abscissa < 1.0;
  std::sort(s.poles.begin(), s.poles.end(), [](const auto& p, const auto& q) {
    return std::abs(p) != std::abs(q) ? std::abs(p) > std::abs(q) : p.imag() < q.imag();
  });
  last.s = s;
  return s;
}

bool SampledLoopIsStable(const DiscretePlant& plant, const PidGains& gains, const PidOptions& options,
                         double margin) {
  if (plant.delay_steps() >= kCountedStabilityFromSteps) {
    if (const auto counted = CountedSampledStability(plant, gains, options, margin)) return *counted;
  }
  return SampledStability(plant, gains, options, margin).stable;
}

}  // namespace pidlab::evaluation
