// The continuous loop with dead time (delayed_loop.h, docs/deadtime.md):
// the method of steps with a cubic Hermite store of the plant's input and an
// exact step per piece by an augmented matrix exponential.

#include "pidlab/evaluation/delayed_loop.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "delayed_exact.h"
#include "delayed_uniform.h"
#include "evaluation_internal.h"
#include "pidlab/plant_sim/matrix_exp.h"

namespace pidlab::evaluation {
namespace {

using internal::kInf;
// Four generator states carry a cubic input: (P, P', P'', P''').
constexpr int kGen = 4;

// The largest eigenvalue modulus of m (0 for an empty matrix).
double SpectralRadius(const Eigen::MatrixXd& m) {
  if (m.rows() == 0) return 0.0;
  Eigen::MatrixXd b = m;
  BalanceInPlace(&b);
  Eigen::EigenSolver<Eigen::MatrixXd> es(b, false);
  if (es.info() != Eigen::Success) return kInf;
  double r = 0.0;
  for (int i = 0; i < b.rows(); ++i) r = std::max(r, std::abs(es.eigenvalues()(i)));
  return r;
}

// One stored piece of q: q(sa + s) = a0 + a1 s + a2 s^2 + a3 s^3 on [sa, sb].
struct StoredPiece {
  double sa = 0.0, sb = 0.0;
  double a[4] = {0.0, 0.0, 0.0, 0.0};
};

// The cubic Hermite interpolant of one-sided values and derivatives.
StoredPiece Hermite(double sa, double sb, double qa, double dqa, double qb, double dqb) {
  StoredPiece s;
  s.sa = sa;
  s.sb = sb;
  const double h = sb - sa;
  s.a[0] = qa;
  s.a[1] = dqa;
  if (h > 0.0) {
    const double slope = (qb - qa) / h;
    s.a[2] = (3.0 * slope - 2.0 * dqa - dqb) / h;
    s.a[3] = (dqa + dqb - 2.0 * slope) / (h * h);
  }
  return s;
}

// The generator state (P, P', P'', P''') of a stored cubic at offset o.
Eigen::Vector4d TaylorAt(const StoredPiece& s, double o) {
  const double* a = s.a;
  return {a[0] + o * (a[1] + o * (a[2] + o * a[3])), a[1] + o * (2.0 * a[2] + 3.0 * o * a[3]),
          2.0 * a[2] + 6.0 * o * a[3], 6.0 * a[3]};
}

double PolyAt(const Eigen::Vector4d& g, double tau) {
  return g(0) + tau * (g(1) + tau * (g(2) / 2.0 + tau * g(3) / 6.0));
}

// exp([[m, e 1'], [0, J]] h) by piece length h, reused within 1e-12 relative:
// the regular step, its splits and the sample offsets repeat.
class ExpCache {
 public:
  explicit ExpCache(const DelayedClosedLoop& loop) : n_(static_cast<int>(loop.m.rows())) {
    aug_ = Eigen::MatrixXd::Zero(n_ + kGen, n_ + kGen);
    aug_.topLeftCorner(n_, n_) = loop.m;
    aug_.block(0, n_, n_, 1) = loop.e;
    for (int k = 0; k + 1 < kGen; ++k) aug_(n_ + k, n_ + k + 1) = 1.0;
  }
  // The state after h from w with the input generator g.
  Eigen::VectorXd Step(double h, const Eigen::VectorXd& w, const Eigen::Vector4d& g) {
    const Eigen::MatrixXd& e = Get(h);
    return e.topLeftCorner(n_, n_) * w + e.topRightCorner(n_, kGen) * g;
  }

 private:
  const Eigen::MatrixXd& Get(double h) {
    auto it = cache_.lower_bound(h * (1.0 - 1e-12));
    if (it != cache_.end() && it->first <= h * (1.0 + 1e-12)) return it->second;
    if (cache_.size() > 4096) cache_.clear();
    return cache_.emplace(h, MatrixExp<double>(Eigen::MatrixXd(aug_ * h))).first->second;
  }
  int n_;
  Eigen::MatrixXd aug_;
  std::map<double, Eigen::MatrixXd> cache_;
};

// The stored pieces of one run, reused per thread (cleared by each run).
std::vector<StoredPiece>& StoredBuffer() {
  thread_local std::vector<StoredPiece> buffer;
  buffer.clear();
  return buffer;
}

// The method of steps, node to node. Nodes: the regular grid k h, the
// disturbance's breakpoints, and every stored node + L (so that each piece's
// delayed interval lies in one stored piece).
class DelayedIntegrator {
 public:
  DelayedIntegrator(const DelayedClosedLoop& loop, const Disturbance& disturbance, double h)
      : loop_(loop), disturbance_(disturbance), cache_(loop), h_(h), tol_(1e-9 * h) {
    piecewise_ = loop.exo_size == 1 && disturbance.IsPiecewiseConstant();
  }

  bool Run(double ts, int num_samples, std::vector<double>* y, DelayedTrace* trace, std::string* error) {
    const double t_end = (num_samples - 1) * ts;
    y->assign(static_cast<std::size_t>(num_samples), 0.0);
    Eigen::VectorXd w = loop_.w0;
    double t = 0.0;
    (*y)[0] = loop_.Output(w);
    if (trace && trace->record) trace->t.assign(1, 0.0), trace->y.assign(1, (*y)[0]);
    int k = 1;
    long pieces = 0;
    while (k < num_samples) {
      if (++pieces > kMaxDelayedPieces) {
        std::ostringstream os;
        os << "dead time " << loop_.delay_s << " s: the continuous loop needs more than " << kMaxDelayedPieces
           << " pieces of " << h_ << " s over the horizon " << t_end << " s";
        if (error) *error = os.str();
        return false;
      }
      const double tb = NextNode(t, t_end);
      const Eigen::Vector4d g = DelayedInput(t);
      for (; k < num_samples && k * ts < tb - tol_; ++k)
        (*y)[k] = loop_.Output(cache_.Step(k * ts - t, w, g));
      Eigen::VectorXd next = cache_.Step(tb - t, w, g);
      Store(t, tb, w, next, g);
      t = tb;
      w.swap(next);
      if (k < num_samples && std::abs(k * ts - t) <= tol_) (*y)[k++] = loop_.Output(w);
      Events(t, &w);
      if (trace && trace->record) trace->t.push_back(t), trace->y.push_back(loop_.Output(w));
    }
    if (trace) trace->pieces = pieces, trace->step_s = h_;
    return true;
  }

 private:
  double NextNode(double t, double t_end) {
    double tb = std::min(t_end, (std::floor((t + tol_) / h_) + 1.0) * h_);
    if (piecewise_) {
      // A breakpoint within rounding of the regular node replaces it: the
      // node after it would ask for the breakpoint after that one.
      next_break_ = disturbance_.NextBreakpoint(t);
      if (next_break_ < tb + tol_) tb = next_break_;
    }
    const double s = t - loop_.delay_s;
    const double cap = s < -tol_ ? loop_.delay_s : stored_[Source(s)].sb + loop_.delay_s;
    if (cap < tb - tol_) tb = cap;
    return tb;
  }

  // The stored piece holding s (s >= 0), by a pointer that only moves
  // forward. The pieces behind it are never read again (s only grows): they
  // are dropped once they are half the store, so memory follows the dead
  // time's window, not the horizon (a tuner's fast candidates need millions
  // of pieces).
  std::size_t Source(double s) {
    while (source_ + 1 < stored_.size() && stored_[source_].sb <= s + tol_) ++source_;
    if (source_ >= kPruneAt && 2 * source_ >= stored_.size()) {
      stored_.erase(stored_.begin(), stored_.begin() + static_cast<std::ptrdiff_t>(source_));
      source_ = 0;
    }
    return source_;
  }
  static constexpr std::size_t kPruneAt = 4096;

  Eigen::Vector4d DelayedInput(double t) {
    const double s = t - loop_.delay_s;
    if (s < -tol_) return Eigen::Vector4d::Zero();
    const StoredPiece& p = stored_[Source(s)];
    return TaylorAt(p, std::max(0.0, s - p.sa));
  }

  // q on [ta, tb]: its one-sided values and derivatives from the states.
  void Store(double ta, double tb, const Eigen::VectorXd& wa, const Eigen::VectorXd& wb,
             const Eigen::Vector4d& g) {
    const double qa = loop_.kq.dot(wa), qb = loop_.kq.dot(wb);
    const double dqa = loop_.kq.dot(loop_.m * wa + loop_.e * g(0));
    const double dqb = loop_.kq.dot(loop_.m * wb + loop_.e * PolyAt(g, tb - ta));
    stored_.push_back(Hermite(ta, tb, qa, dqa, qb, dqb));
  }

  // At node t: a disturbance breakpoint resets its state; the ideal
  // derivative's kick reaches the plant at t = L.
  void Events(double t, Eigen::VectorXd* w) {
    if (piecewise_ && t == next_break_) (*w)(loop_.exo_index) = disturbance_.Value(t);
    if (!kicked_ && std::abs(t - loop_.delay_s) <= tol_) {
      *w += loop_.impulse;
      kicked_ = true;
    }
  }

  const DelayedClosedLoop& loop_;
  const Disturbance& disturbance_;
  ExpCache cache_;
  double h_, tol_;
  bool piecewise_ = false, kicked_ = false;
  double next_break_ = kInf;  // the disturbance's next breakpoint after the current node
  std::vector<StoredPiece>& stored_ = StoredBuffer();
  std::size_t source_ = 0;
};

}  // namespace

namespace {

// DelayedLoopIsRetarded() with the refusal's message in *error.
bool DelayedLoopIsRetardedOrExplain(const TransferFunction& tf, const PidGains& g, std::string* error) {
  if (g.kd == 0.0 || g.tf > 0.0 || tf.RelativeDegree() >= 2) return true;
  if (error) {
    std::ostringstream os;
    os << "kd " << g.kd << " with no derivative filter on a plant of relative degree 1 and a dead time makes "
       << "the continuous loop of neutral type: give a derivative filter (--derivative-filter or "
          "--derivative-filter-ratio)";
    *error = os.str();
  }
  return false;
}

}  // namespace

Status DelayedLoopIsRetarded(const TransferFunction& tf, const PidGains& g) {
  std::string why;
  if (!DelayedLoopIsRetardedOrExplain(tf, g, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

namespace {

// BuildDelayedClosedLoop() with the refusal's message in *error.
bool BuildDelayedClosedLoopOrExplain(const TransferFunction& tf, const StateSpace& plant, const PidGains& g,
                                     const Disturbance& disturbance, double delay_s, double reference,
                                     DelayedClosedLoop* out, std::string* error,
                                     const SetpointWeights& weights) {
  if (const Status st = DelayedLoopIsRetarded(tf, g); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  const int n = plant.order();
  const bool filtered = g.tf > 0.0;
  const DisturbanceKind kind = disturbance.options().kind;
  const int exo = kind == DisturbanceKind::kNone ? 0 : (kind == DisturbanceKind::kSine ? 2 : 1);
  const int rf = weights.filter_s > 0.0 ? 1 : 0;
  // is: the setpoint the PID reads, r or the setpoint filter's r_f.
  const int iz = n, iv = n + 1, ir = filtered ? n + 2 : n + 1, is = ir + rf, ie = is + 1;
  const int size = ie + exo;
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(size, size);
  Eigen::RowVectorXd u = Eigen::RowVectorXd::Zero(size);
  m.topLeftCorner(n, n) = plant.a;
  m.block(iz, 0, 1, n) = -plant.c;
  m(iz, is) = 1.0;
  if (rf) {  // r_f' = (r - r_f) / tr
    m(is, ir) = 1.0 / weights.filter_s;
    m(is, is) = -1.0 / weights.filter_s;
  }
  if (filtered) {
    // u = kp (b r - C x) + ki z + kf (c r - C x - v), v' = (c r - C x - v) / tf.
    const double kf = g.kd / g.tf;
    u.head(n) = -(g.kp + kf) * plant.c;
    u(iv) = -kf;
    u(is) = g.kp * weights.b + kf * weights.c;
    m.block(iv, 0, 1, n) = -plant.c / g.tf;
    m(iv, iv) = -1.0 / g.tf;
    m(iv, is) = weights.c / g.tf;
  } else {
    // u = kp (b r - C x) + ki z - kd C A x: e' = -C (A x + B p), C B = 0 here.
    u.head(n) = -g.kp * plant.c - g.kd * (plant.c * plant.a);
    u(is) = g.kp * weights.b;
    if (rf) {  // kd c r_f' = kd c (r - r_f) / tr
      u(ir) += g.kd * weights.c / weights.filter_s;
      u(is) -= g.kd * weights.c / weights.filter_s;
    }
  }
  u(iz) = g.ki;
  Eigen::VectorXd w0 = Eigen::VectorXd::Zero(size);
  w0(ir) = reference;
  SetExosystem<double>(disturbance, exo, ie, &m, &w0);
  out->kq = u;
  if (exo > 0) out->kq(ie) += 1.0;  // q = u + n
  out->m = std::move(m);
  out->e = Eigen::VectorXd::Zero(size);
  out->e.head(n) = plant.b;
  out->w0 = std::move(w0);
  out->impulse = Eigen::VectorXd::Zero(size);
  if (!filtered && !rf) out->impulse.head(n) = g.kd * weights.c * reference * plant.b;
  out->c = plant.c;
  out->plant_order = n;
  out->exo_size = exo;
  out->exo_index = ie;
  out->reference_index = ir;
  out->delay_s = delay_s;
  return true;
}

}  // namespace

Status BuildDelayedClosedLoop(const TransferFunction& tf, const StateSpace& plant, const PidGains& g,
                              const Disturbance& disturbance, double delay_s, double reference,
                              DelayedClosedLoop* out, const SetpointWeights& weights) {
  std::string why;
  if (!BuildDelayedClosedLoopOrExplain(tf, plant, g, disturbance, delay_s, reference, out, &why, weights))
    return Status::InvalidInput(why);
  return Status::Ok();
}

double DelayedStepSize(const DelayedClosedLoop& loop) {
  const Eigen::MatrixXd closed = loop.m + loop.e * loop.kq;
  const double rho = std::max({SpectralRadius(loop.m), SpectralRadius(closed), 1e-12 / loop.delay_s});
  const double h_max = kDelayedStepFraction / rho;
  const double m = std::ceil(loop.delay_s / h_max);
  return loop.delay_s / std::max(1.0, m);
}

namespace {

// The samples (and the trace) by the Hermite store of step h: on the
// uniform grid where it applies, else node by node.
bool SampleByHermiteStore(const DelayedClosedLoop& loop, const Disturbance& disturbance, double h, double ts,
                          int num_samples, std::vector<double>* y, DelayedTrace* trace, std::string* error) {
  const double t_end = (num_samples - 1) * ts;
  if (!(trace && trace->node_by_node) && internal::UniformGridApplies(loop, disturbance, h, t_end)) {
    internal::SampleUniformDelayedLoop(loop, h, ts, num_samples, y, trace);
    return true;
  }
  DelayedIntegrator integrator(loop, disturbance, h);
  return integrator.Run(ts, num_samples, y, trace, error);
}

}  // namespace

namespace {

// SampleDelayedLoop() with the refusal's message in *error.
bool SampleDelayedLoopOrExplain(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts,
                                int num_samples, std::vector<double>* y, DelayedTrace* trace,
                                std::string* error) {
  const double h = trace && trace->force_step_s > 0.0 ? trace->force_step_s : DelayedStepSize(loop);
  const double t_end = (num_samples - 1) * ts;
  if (!(h > 0.0) || t_end / h > static_cast<double>(kMaxDelayedPieces)) {
    std::ostringstream os;
    os << "dead time " << loop.delay_s << " s: the continuous loop's step " << h << " s (the loop's fastest "
       << "rate) needs more than " << kMaxDelayedPieces << " pieces over the horizon " << t_end << " s";
    if (error) *error = os.str();
    return false;
  }
  const bool hermite_only = trace && (trace->node_by_node || trace->force_step_s > 0.0);
  DelayedTrace exact;
  if (hermite_only || !internal::SampleExactDelayedLoop(loop, disturbance, ts, num_samples, y, &exact))
    return SampleByHermiteStore(loop, disturbance, h, ts, num_samples, y, trace, error);
  if (!trace) return true;
  if (!trace->record) {
    trace->pieces = exact.pieces;
    trace->step_s = exact.step_s;
    return true;
  }
  // The nodes of the trace are the Hermite store's (its integral over them,
  // its stepinfo); the samples stay the exact ones.
  thread_local std::vector<double> hermite;
  return SampleByHermiteStore(loop, disturbance, h, ts, num_samples, &hermite, trace, error);
}

}  // namespace

Status SampleDelayedLoop(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts,
                         int num_samples, std::vector<double>* y, DelayedTrace* trace) {
  std::string why;
  if (!SampleDelayedLoopOrExplain(loop, disturbance, ts, num_samples, y, trace, &why))
    return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::evaluation
