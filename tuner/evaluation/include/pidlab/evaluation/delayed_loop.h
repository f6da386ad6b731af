#pragma once
// The continuous closed loop with a plant dead time L > 0 (docs/deadtime.md,
// "The continuous loop"): a delay-differential loop
//
//   x' = A x + B p(t),  p(t) = q(t - L),  q(t) = u(t) + n(t)  (0 for t < 0),
//   u = the ideal or filtered PID of the loop's state w = [x; z; v; r; exo],
//
// the disturbance entering the plant input before the delay, as in the
// sampled loop. Integrated node to node by the method of steps: every piece
// of q is stored as a cubic Hermite polynomial (one-sided values and
// derivatives at both ends, q' = Kq w' from the state equation), every
// integration piece is split so that its delayed interval lies in one stored
// piece, and the step over a piece is exact for that cubic input by an
// augmented matrix exponential (four polynomial-generator states). The only
// error is the Hermite interpolation of q, h^4 / 384 max |q''''| per piece
// with the step h chosen from the loop's fastest rate (DelayedStepSize).

#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/plant_sim/disturbance.h"
#include "pidlab/plant_sim/transfer_function.h"
#include "pidlab/spec/status.h"

namespace pidlab::evaluation {

/// Step h = L / m: h |rho| <= kDelayedStepFraction for the loop's fastest
/// rate rho (DelayedStepSize).
inline constexpr double kDelayedStepFraction = 0.02;
/// At most this many integration pieces per run (each a few small
/// matrix-vector products and 48 bytes of stored input).
inline constexpr long kMaxDelayedPieces = 20000000;

/// The delayed loop as an open system w' = m w + e p(t), q = kq w; the plant
/// input p is the delayed q. `impulse` is added to w at t = L: the ideal
/// derivative's kick kd A B delta(t) of the reference step, reaching the
/// plant through the delay (zero for the filtered PID).
struct DelayedClosedLoop {
  Eigen::MatrixXd m;
  Eigen::VectorXd e, w0, impulse;
  Eigen::RowVectorXd kq, c;
  int plant_order = 0;
  int exo_size = 0;
  int exo_index = 0;
  int reference_index = 0;  // r's state (r_f's, where a setpoint filter runs, follows it)
  double delay_s = 0.0;
  double Output(const Eigen::VectorXd& w) const { return c.dot(w.head(plant_order)); }
};

/// A failed Status (kInvalidInput) (one line naming the derivative and saying a filter is
/// needed) for an ideal derivative (tf = 0 < kd) on a plant of relative degree
/// 1: that loop is of neutral type.
Status DelayedLoopIsRetarded(const TransferFunction& tf, const PidGains& loop_gains);

/// Builds the delayed loop of `plant` (Realize(tf)) with the loop's gains
/// (LoopGains), the disturbance, reference A and the 2-DOF setpoint weights
/// (closed_loop.h). A failed Status (kInvalidInput) as DelayedLoopIsRetarded.
Status BuildDelayedClosedLoop(const TransferFunction& tf, const StateSpace& plant, const PidGains& loop_gains,
                              const Disturbance& disturbance, double delay_s, double reference,
                              DelayedClosedLoop* out, const SetpointWeights& weights = {});

/// The step h = L / m, m = ceil(L / h_max), h_max = kDelayedStepFraction /
/// rho, rho the largest modulus among the eigenvalues of the open system m
/// and of the undelayed closed loop m + e kq (and the sine's frequency).
double DelayedStepSize(const DelayedClosedLoop& loop);

/// What one run records besides y at the samples.
struct DelayedTrace {
  bool record = false;        // fill t and y at every node
  double force_step_s = 0.0;  // > 0: this h instead of DelayedStepSize (tests)
  // true: node by node even where the uniform grid applies (h divides L, no
  // disturbance breakpoint inside the horizon), the reference of the
  // equivalence test and the bench; the two agree to rounding.
  bool node_by_node = false;
  std::vector<double> t, y;  // the nodes (t = 0 first) and y there
  long pieces = 0;           // integration pieces taken
  double step_s = 0.0;       // h
};

/// y at t = 0, ts, ..., (num_samples - 1) ts of the delayed loop, on the
/// uniform grid t_j = j h where it applies (one map per piece, a ring of the
/// m = L / h stored pieces), else node by node. A failed Status (kInvalidInput) when the
/// run needs more than kMaxDelayedPieces pieces.
Status SampleDelayedLoop(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts,
                         int num_samples, std::vector<double>* y, DelayedTrace* trace);

}  // namespace pidlab::evaluation
