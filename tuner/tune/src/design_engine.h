#pragma once
// Internal to the design engine (design.h): the optimisation of the load
// response under the bounds, for one Ms bound.

#include <Eigen/Dense>
#include <complex>
#include <vector>

#include "design_loop.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/tune/design.h"

namespace pidlab::tune::design {

/// The problem's bounds, as the engine applies them.
struct Bounds {
  double ms = 1.4, mt = 1.4, noise_gain = 0.0, td_max_s = 0.0;
  /// The loop the exact analysis checks the bounds on (continuous, or the
  /// sampled loop at its dt).
  evaluation::LoopOptions loop;
  /// No gain crossover above this (rad/s): a plant that allows any speed
  /// (no dead time, relative degree 1) gets a loop ten times faster than its
  /// fastest time, as migo's.
  double crossover_cap = 0.0;
};

/// The best gains for one set of bounds.
struct Optimum {
  PidGains gains;
  double load_iae = std::numeric_limits<double>::infinity();
  /// The shape it was found at (log Ti, log Td, log N; PI: log Ti), to start
  /// the next design of a front from.
  Eigen::VectorXd shape;
  int evaluations = 0;
};

class Engine {
 public:
  /// `min_tf_s`: the derivative filter's least time constant (the sampled
  /// loop's dt; 0 continuous).
  /// `crossover_hint`: the crossover (rad/s) the grid step is chosen for;
  /// 0: estimated from the rules' shapes.
  /// `speed_cap`: the highest crossover allowed (rad/s); 0: migo's,
  /// kMigoSpeedCap over the plant's fastest time.
  Engine(const Plant& plant, bool pi, double min_tf_s = 0.0, double crossover_hint = 0.0,
         double speed_cap = 0.0);
  /// The optimum under `bounds`, from the rules' shapes and `warm` (if not
  /// empty; `warm_only`: one short search from it alone, not polished).
  /// False when no shape has a stable
  /// loop meeting the bounds.
  bool Optimize(const Bounds& bounds, const Eigen::VectorXd& warm, Optimum* best,
                bool warm_only = false) const;
  /// \int|y|dt of the unit load step (+inf when it does not settle).
  double LoadIae(const PidGains& g) const;
  /// The shape of gains (kp, ki > 0; a PID's kd, tf > 0), to start from.
  Eigen::VectorXd ShapeOf(const PidGains& g) const;
  const LoopSimulator& Simulator() const { return sim_; }
  int MaxSteps() const { return max_steps_; }
  /// The characteristic time the grid and the step came from (s).
  double Time() const { return time_s_; }
  /// The crossover the step was chosen for (rad/s).
  double Crossover() const { return 1.0 / time_s_; }
  double SpeedCap() const { return speed_cap_; }

 private:
  PidGains ShapeGains(const Eigen::VectorXd& shape, double kp) const;
  /// The largest kp whose loop meets the bounds on the grid, from `hint`.
  /// The largest kp whose loop meets the bounds on the grid (`hint`: the
  /// last shape's, 0: none).
  /// 0 when none, with *least_violation (may be null) the least of the
  /// peaks' ratios to their bounds seen.
  double MaxKp(const Eigen::VectorXd& shape, const Bounds& bounds, double hint,
               double* least_violation = nullptr) const;
  /// The shape's load IAE at kp = max kp * exp(min(alpha, 0)).
  double Cost(const Eigen::VectorXd& shape, double alpha, const Bounds& bounds, double* kp_hint,
              PidGains* gains) const;
  std::vector<Eigen::VectorXd> Starts(const Bounds& bounds) const;

  const Plant& plant_;
  bool pi_;
  double time_s_ = 1.0, speed_cap_ = 0.0, min_tf_s_ = 0.0;
  FrequencyGrid grid_;
  LoopSimulator sim_;
  int max_steps_ = 20000;
  // The plant's poles in the right half-plane, and at the origin with the
  // controller's integrator.
  int rhp_poles_ = 0, origin_poles_ = 1;
  mutable int evaluations_ = 0;
};

/// The setpoint overshoot target of a design at Ms bound `ms_bound` along a
/// knob (DesignOptions::monotone_front, design_front.cc): options'
/// max_overshoot_pct capped by the overshoot of the front's designs at the
/// knots Ms = kFrontMaxMs, kFrontMaxMs - 0.1, ... above ms_bound, each
/// designed under the cap of the knots above it. *from_ms: the knot that set
/// the cap (0: none did).
double FrontOvershootCap(const Plant& plant, const DesignOptions& options, double ms_bound, double* from_ms);

}  // namespace pidlab::tune::design
