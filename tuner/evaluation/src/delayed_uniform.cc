// The method of steps on the uniform grid (delayed_uniform.h).

#include "delayed_uniform.h"

#include <Eigen/StdVector>
#include <algorithm>
#include <cmath>

#include "pidlab/plant_sim/matrix_exp.h"

namespace pidlab::evaluation::internal {
namespace {

// Four generator states carry a cubic input: (P, P', P'', P''').
constexpr int kGen = 4;
// A ring this large (pieces) is given back after the run: a thread keeps
// the ring of ordinary loops, not that of the stiffest candidate it met.
constexpr std::size_t kKeptRing = 1 << 16;

// The generator (P, P', P'', P''') at offset 0 of the cubic Hermite
// interpolant on [0, h] of the data d = (q(0), q'(0), q(h), q'(h)).
Eigen::Matrix4d HermiteToGenerator(double h) {
  const double h2 = h * h, h3 = h2 * h;
  Eigen::Matrix4d t;
  t << 1.0, 0.0, 0.0, 0.0,                        //
      0.0, 1.0, 0.0, 0.0,                         //
      -6.0 / h2, -4.0 / h, 6.0 / h2, -2.0 / h,    // 2 a2
      12.0 / h3, 6.0 / h2, -12.0 / h3, 6.0 / h2;  // 6 a3
  return t;
}

// [[m, e 1'], [0, J]]: the loop with its input carried by the generator.
Eigen::MatrixXd Augmented(const DelayedClosedLoop& loop) {
  const int n = static_cast<int>(loop.m.rows());
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + kGen, n + kGen);
  aug.topLeftCorner(n, n) = loop.m;
  aug.block(0, n, n, 1) = loop.e;
  for (int k = 0; k + 1 < kGen; ++k) aug(n + k, n + k + 1) = 1.0;
  return aug;
}

// The stored piece j's data in a ring of m, thread-local: the tuner runs one
// loop after another on each thread.
std::vector<Eigen::Vector4d, Eigen::aligned_allocator<Eigen::Vector4d>>& Ring(std::size_t m) {
  thread_local std::vector<Eigen::Vector4d, Eigen::aligned_allocator<Eigen::Vector4d>> ring;
  ring.resize(m);
  return ring;
}

// y at offset tau into a piece from its start state w and input data d:
// y = rw w + rd d, for every distinct offset the samples fall at (reused
// within 1e-12 relative, as the node-by-node integrator's exponentials).
template <int N>
class SampleRows {
 public:
  using Row = Eigen::Matrix<double, 1, N>;
  SampleRows(const DelayedClosedLoop& loop, const Eigen::MatrixXd& aug, const Eigen::Matrix4d& to_generator)
      : loop_(loop), aug_(aug), to_generator_(to_generator) {}

  template <typename Vec>
  double Output(double tau, const Vec& w, const Eigen::Vector4d& d) {
    const Entry& e = Get(tau);
    return e.rw.dot(w) + e.rd.dot(d);
  }

 private:
  struct Entry {
    double tau;
    Row rw;
    Eigen::RowVector4d rd;
  };
  const Entry& Get(double tau) {
    auto it = std::lower_bound(entries_.begin(), entries_.end(), tau * (1.0 - 1e-12),
                               [](const Entry& e, double x) { return e.tau < x; });
    if (it != entries_.end() && it->tau <= tau * (1.0 + 1e-12)) return *it;
    const int n = static_cast<int>(loop_.m.rows()), p = loop_.plant_order;
    const Eigen::MatrixXd e = MatrixExp<double>(Eigen::MatrixXd(aug_ * tau));
    Entry entry{tau, Row(loop_.c * e.topLeftCorner(p, n)),
                Eigen::RowVector4d(loop_.c * e.block(0, n, p, kGen) * to_generator_)};
    return *entries_.insert(it, entry);
  }

  const DelayedClosedLoop& loop_;
  const Eigen::MatrixXd& aug_;
  const Eigen::Matrix4d& to_generator_;
  std::vector<Entry, Eigen::aligned_allocator<Entry>> entries_;
};

// The run on the state of size N (Eigen::Dynamic for the larger loops).
template <int N>
class UniformRun {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;

  UniformRun(const DelayedClosedLoop& loop, double h)
      : loop_(loop),
        h_(h),
        tol_(1e-9 * h),
        m_(std::max<long>(1, std::lround(loop.delay_s / h))),
        aug_(Augmented(loop)),
        to_generator_(HermiteToGenerator(h)),
        rows_(loop, aug_, to_generator_) {
    const int n = static_cast<int>(loop.m.rows());
    const Eigen::MatrixXd e = MatrixExp<double>(Eigen::MatrixXd(aug_ * h));
    phi_ = e.topLeftCorner(n, n);
    gamma_d_ = e.topRightCorner(n, kGen) * to_generator_;
    k_.resize(2, n);
    k_.row(0) = loop.kq;
    k_.row(1) = loop.kq * loop.m;
    kqe_ = loop.kq.dot(loop.e);
    c_ = Eigen::Matrix<double, 1, N>::Zero(1, n);
    c_.head(loop.plant_order) = loop.c;
  }

  void Run(double ts, int num_samples, std::vector<double>* y, DelayedTrace* trace) {
    const double t_end = (num_samples - 1) * ts;
    const bool record = trace && trace->record;
    y->assign(static_cast<std::size_t>(num_samples), 0.0);
    auto& ring = Ring(static_cast<std::size_t>(m_));
    Vec w = loop_.w0;
    (*y)[0] = c_.dot(w);
    if (record) {
      // Every node, reserved once: a stiff loop's are millions.
      const std::size_t nodes = static_cast<std::size_t>(std::ceil(t_end / h_ - 1e-9)) + 2;
      trace->t.clear(), trace->y.clear();
      trace->t.reserve(nodes), trace->y.reserve(nodes);
      trace->t.push_back(0.0), trace->y.push_back((*y)[0]);
    }
    Eigen::Vector2d kw = k_ * w;  // (q, kq m w) at the current node
    int k = 1;
    long j = 0, pieces = 0;
    std::size_t slot = 0;  // j mod m: the piece j - m's data, then the piece j's
    const Eigen::Vector4d zero = Eigen::Vector4d::Zero();
    while (k < num_samples) {
      const double t = static_cast<double>(j) * h_;
      const double tb = std::min(t_end, static_cast<double>(j + 1) * h_);
      const Eigen::Vector4d d = j >= m_ ? ring[slot] : zero;
      ++pieces;
      for (; k < num_samples && k * ts < tb - tol_; ++k) (*y)[k] = rows_.Output(k * ts - t, w, d);
      if (tb < static_cast<double>(j + 1) * h_) {  // the last, shorter piece ends at t_end
        if (k < num_samples) (*y)[k++] = rows_.Output(tb - t, w, d);
        if (record) trace->t.push_back(tb), trace->y.push_back((*y)[k - 1]);
        break;
      }
      Vec next = phi_ * w + gamma_d_ * d;
      const Eigen::Vector2d kn = k_ * next;
      ring[slot] = {kw(0), kw(1) + kqe_ * d(0), kn(0), kn(1) + kqe_ * d(2)};
      if (++slot == static_cast<std::size_t>(m_)) slot = 0;
      ++j;
      w = next;
      kw = kn;
      if (k < num_samples && std::abs(k * ts - tb) <= tol_) (*y)[k++] = c_.dot(w);
      if (j == m_ && loop_.impulse.any()) {  // the ideal derivative's kick reaches the plant
        w += loop_.impulse;
        kw = k_ * w;
      }
      if (record) trace->t.push_back(tb), trace->y.push_back(c_.dot(w));
    }
    if (ring.capacity() > kKeptRing) ring = {};
    if (trace) trace->pieces = pieces, trace->step_s = h_;
  }

 private:
  const DelayedClosedLoop& loop_;
  double h_, tol_;
  long m_;
  Eigen::MatrixXd aug_;
  Eigen::Matrix4d to_generator_;
  SampleRows<N> rows_;
  Mat phi_;
  Eigen::Matrix<double, N, kGen> gamma_d_;
  Eigen::Matrix<double, 2, N> k_;
  Eigen::Matrix<double, 1, N> c_;
  double kqe_ = 0.0;
};

template <int N>
void RunOfSize(const DelayedClosedLoop& loop, double h, double ts, int num_samples, std::vector<double>* y,
               DelayedTrace* trace) {
  UniformRun<N> run(loop, h);
  run.Run(ts, num_samples, y, trace);
}

}  // namespace

bool UniformGridApplies(const DelayedClosedLoop& loop, const Disturbance& disturbance, double h,
                        double t_end_s) {
  if (!(h > 0.0) || !(loop.delay_s > 0.0)) return false;
  const double m = std::round(loop.delay_s / h);
  if (!(m >= 1.0) || std::abs(m * h - loop.delay_s) > 1e-9 * h) return false;
  const bool piecewise = loop.exo_size == 1 && disturbance.IsPiecewiseConstant();
  return !piecewise || !(disturbance.NextBreakpoint(0.0) <= t_end_s + 1e-9 * h);
}

void SampleUniformDelayedLoop(const DelayedClosedLoop& loop, double h, double ts, int num_samples,
                              std::vector<double>* y, DelayedTrace* trace) {
  switch (loop.m.rows()) {
    case 3:
      return RunOfSize<3>(loop, h, ts, num_samples, y, trace);
    case 4:
      return RunOfSize<4>(loop, h, ts, num_samples, y, trace);
    case 5:
      return RunOfSize<5>(loop, h, ts, num_samples, y, trace);
    case 6:
      return RunOfSize<6>(loop, h, ts, num_samples, y, trace);
    case 7:
      return RunOfSize<7>(loop, h, ts, num_samples, y, trace);
    case 8:
      return RunOfSize<8>(loop, h, ts, num_samples, y, trace);
    default:
      return RunOfSize<Eigen::Dynamic>(loop, h, ts, num_samples, y, trace);
  }
}

}  // namespace pidlab::evaluation::internal
