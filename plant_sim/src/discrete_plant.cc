#include "pidlab/plant_sim/discrete_plant.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "pidlab/plant_sim/matrix_exp.h"

namespace pidlab {

namespace {

// The value with all its digits, for the messages of the delay checks.
std::string Exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void CheckStep(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    throw std::invalid_argument("dt " + std::to_string(dt_s) + " s must be positive and finite");
}

}  // namespace

DelaySplit SplitDelay(double delay_s, double dt_s) {
  CheckStep(dt_s);
  if (!std::isfinite(delay_s) || !(delay_s >= 0.0))
    throw std::invalid_argument("delay " + Exact(delay_s) + " s must be finite and not negative");
  if (delay_s > kMaxDelaySeconds)
    throw std::invalid_argument("delay " + Exact(delay_s) + " s is above the limit of " + Exact(kMaxDelaySeconds) +
                                " s");
  const double ratio = delay_s / dt_s;  // +inf for a tiny dt
  const auto refuse_steps = [&]() {
    throw std::invalid_argument("delay " + Exact(delay_s) + " s at dt " + Exact(dt_s) + " s is " +
                                Exact(std::ceil(ratio)) + " steps, above the limit of " +
                                std::to_string(kMaxDelaySteps) + " stored inputs");
  };
  if (!(ratio <= static_cast<double>(kMaxDelaySteps) + 1.0)) refuse_steps();
  DelaySplit split;
  const double nearest = std::nearbyint(ratio);
  const double eps = std::numeric_limits<double>::epsilon();
  if (std::abs(ratio - nearest) <= 8.0 * eps * std::max(1.0, nearest)) {
    // A multiple of dt (0 included): a pure delay of `nearest` steps.
    split.steps = static_cast<long>(nearest);
    split.fraction_s = dt_s;
    split.split = false;
    if (split.steps > kMaxDelaySteps) refuse_steps();
    return split;
  }
  split.steps = static_cast<long>(std::ceil(ratio));
  if (split.steps > kMaxDelaySteps) refuse_steps();
  split.fraction_s = delay_s - static_cast<double>(split.steps - 1) * dt_s;
  // ratio is at least 8 eps away from an integer, so (d - 1) dt < L < d dt
  // up to rounding; keep L' strictly inside (0, dt) all the same.
  split.fraction_s = std::min(std::max(split.fraction_s, std::numeric_limits<double>::min()), dt_s);
  split.split = split.fraction_s < dt_s;
  if (!split.split) split.fraction_s = dt_s;
  return split;
}

DelayedZoh DelayedZeroOrderHold(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double dt_s, double delay_s) {
  DelayedZoh z;
  z.delay = SplitDelay(delay_s, dt_s);
  Eigen::MatrixXd gamma;
  // Phi and the undelayed Gamma exactly as the undelayed plant computes them.
  ZeroOrderHold<double>(a, Eigen::MatrixXd(b), dt_s, &z.phi, &gamma);
  z.gamma = gamma.col(0);
  if (!z.delay.split) {
    z.gamma1 = z.gamma;
    return z;
  }
  // The step split at L' from its start: u_{k-d} over [0, L'), u_{k-d+1}
  // over [L', dt). Each integral is one van Loan exponential,
  // exp([[A, B], [0, 0]] h) = [[e^{Ah}, int_0^h e^{As} ds B], [0, 1]].
  const double late = z.delay.fraction_s;  // L'
  const double early = dt_s - late;        // dt - L'
  Eigen::MatrixXd phi_early, gamma_early, phi_late, gamma_late;
  ZeroOrderHold<double>(a, Eigen::MatrixXd(b), early, &phi_early, &gamma_early);
  ZeroOrderHold<double>(a, Eigen::MatrixXd(b), late, &phi_late, &gamma_late);
  z.gamma0 = gamma_early.col(0);
  z.gamma1 = phi_early * gamma_late.col(0);
  return z;
}

DiscretePlant::DiscretePlant(const TransferFunction& tf, double dt_s) : DiscretePlant(tf, dt_s, 0.0) {}

DiscretePlant::DiscretePlant(const TransferFunction& tf, double dt_s, double delay_s)
    : dt_s_(dt_s), delay_s_(delay_s) {
  CheckStep(dt_s);
  if (tf.RelativeDegree() < 1)
    throw std::invalid_argument("plant " + tf.ToString() + " must be strictly proper for a sampled loop");
  const StateSpace ss = Realize(tf);
  const DelayedZoh delayed = DelayedZeroOrderHold(ss.a, ss.b, dt_s, delay_s);
  delay_ = delayed.delay;
  phi_ = delayed.phi;
  gamma_ = delayed.gamma;
  gamma1_ = delayed.gamma1;
  gamma0_ = delayed.gamma0;
  c_ = ss.c;
  state_.assign(static_cast<std::size_t>(ss.order()), 0.0);
  next_ = state_;
  line_ = InputDelayLine<double>(delay_.steps);
}

double DiscretePlant::Output() const { return OutputOf(c_, state_); }

void DiscretePlant::Step(double input) {
  DelayedPlantStep(*this, &line_, state_, input, &next_);
  state_.swap(next_);
}

void DiscretePlant::Reset() {
  std::fill(state_.begin(), state_.end(), 0.0);
  line_.Reset();
}

DiscreteTransferFunction ZTransferFunction(const DiscretePlant& plant) {
  // Faddeev-LeVerrier: det(zI - Phi) = sum_k c_k z^k with c_n = 1, and
  // adj(zI - Phi) = sum_{k=1..n} M_k z^{n-k}, M_1 = I,
  // M_{k+1} = Phi M_k + c_{n-k} I, c_{n-k} = -tr(Phi M_k) / k.
  const Eigen::MatrixXd& phi = plant.phi();
  const int n = plant.order();
  const Eigen::VectorXd gamma0 =
      plant.gamma0().size() == 0 ? Eigen::VectorXd(Eigen::VectorXd::Zero(n)) : plant.gamma0();
  const Eigen::VectorXd& gamma1 = plant.gamma1();
  DiscreteTransferFunction g;
  g.delay_steps = plant.delay_steps();
  g.den.assign(static_cast<std::size_t>(n) + 1, 0.0);  // descending: den[i] is the z^{n-i} coefficient
  g.num.assign(static_cast<std::size_t>(n) + 1, 0.0);
  g.den[0] = 1.0;
  Eigen::MatrixXd m = Eigen::MatrixXd::Identity(n, n);
  for (int k = 1; k <= n; ++k) {
    // M_k multiplies z^{n-k}: C M_k Gamma0 z^{n-k+1} + C M_k Gamma1 z^{n-k}.
    g.num[static_cast<std::size_t>(k - 1)] += plant.c() * m * gamma0;
    g.num[static_cast<std::size_t>(k)] += plant.c() * m * gamma1;
    const Eigen::MatrixXd pm = phi * m;
    const double coefficient = -pm.trace() / k;  // c_{n-k}
    g.den[static_cast<std::size_t>(k)] = coefficient;
    m = pm + coefficient * Eigen::MatrixXd::Identity(n, n);
  }
  return g;
}

}  // namespace pidlab
