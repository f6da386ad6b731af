#pragma once
// The second stage of `tune --two-dof` (docs/two_dof.md): with the feedback
// gains fixed, the setpoint weights b, c of the 2-DOF PID in [0, 1]^2 that
// minimise the IAE of the setpoint step (the loop without its disturbance).
// The weights cannot move the loop's poles, its load response, Ms, Mt or the
// margins: the summary reports the responses before and after, to show it.

#include <string>

#include "pidlab/controller/pid.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/optim/optimizer.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

/// The responses of one loop: the setpoint step (without the loop's
/// disturbance) and the load step (a unit step at the plant input, r = 0),
/// and Ms.
struct TwoDofResponse {
  double b = 1.0, c = 1.0;
  double setpoint_iae = 0.0;  // eq. (4) on the setpoint step
  double overshoot_pct = 0.0, rise_time_s = 0.0, settling_time_s = 0.0;
  double load_iae = 0.0;  // LoadIntegralAbsError
  double ms = 0.0;
};

struct TwoDofSummary {
  bool ran = false;
  /// The weights found (the grid's best polished by Nelder-Mead in the box).
  double b = 1.0, c = 1.0;
  /// The first-order setpoint filter's time constant (s; 0 = none): the
  /// design engine's, where b and c alone miss the overshoot target.
  double setpoint_filter_s = 0.0;
  /// With the weights the feedback stage ran with (the loop's, 1, 1 by
  /// default), and with the weights found.
  TwoDofResponse before, after;
  int evaluations = 0;
  optim::TerminationType termination = optim::TerminationType::kInvalidOptions;
  std::string message;
};

/// Points per side of the starting grid on [0, 1]^2, and the Nelder-Mead
/// budget after it.
inline constexpr int kTwoDofGridPoints = 11;
inline constexpr int kTwoDofMaxEvaluations = 200;

/// Tunes b, c for `gains` (LoopGains applied) on `loop`, run in process.
/// kInvalidInput when the loop cannot be evaluated; the responses of an
/// unstable loop are not searched (ran false, message says why).
Status TuneSetpointWeights(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& loop,
                           TwoDofSummary* summary);

/// The setpoint weight b in [0, 1] with c fixed: 1 if the setpoint step's
/// overshoot is at most `max_overshoot_pct` there, else the largest b (by
/// bisection, 12 steps) whose overshoot is within it (tune --method migo's
/// second stage). Fills *summary as TuneSetpointWeights does.
Status SetpointWeightForOvershoot(const Plant& plant, const PidGains& gains,
                                  const evaluation::LoopOptions& loop, double c, double max_overshoot_pct,
                                  TwoDofSummary* summary);

/// `loop` with the weights (and the setpoint filter) of `summary` when it ran.
evaluation::LoopOptions WithSetpointWeights(evaluation::LoopOptions loop, const TwoDofSummary& summary);

}  // namespace pidlab::tune
