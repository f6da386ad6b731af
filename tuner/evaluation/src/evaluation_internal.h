#pragma once
// What evaluate.cc and metrics.cc share inside the evaluation library.

#include <limits>

#include "pidlab/evaluation/evaluation.h"

namespace pidlab::evaluation::internal {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// sum_m |y_L(m ts)| of the load response of a strictly stable loop: the
/// continuous loop built with r = 0 (no reference state, no derivative kick)
/// and the step as its exosystem state, or the sampled loop run with r_k = 0.
/// `discrete` is the plant at dt (sampled loop only).
double LoadIaeOfStableLoop(const StateSpace& realization, const DiscretePlant* discrete,
                           const PidGains& gains, const LoopOptions& options, const Disturbance& step);

}  // namespace pidlab::evaluation::internal

namespace pidlab::evaluation::internal {

/// How the continuous loop with dead time is computed: kFast by the crossing
/// frequencies (the Nyquist count where they do not decide) and the uniform
/// grid where it applies; kReference by the Nyquist count and node by node,
/// as before both (ReferenceDelayedObjective).
enum class DelayedPath { kFast, kReference };

/// The continuous loop with dead time (evaluate_delayed.cc): its stability
/// (no poles, abscissa NaN; kInvalidInput when the Nyquist count is needed and
/// e^(-jwL) cannot be resolved),
Status DelayedStability(const Plant& plant, const PidGains& loop_gains, Stability* s,
                        DelayedPath path = DelayedPath::kFast);
/// y at the samples, the undisturbed IAE, the integral of |e| over the nodes
/// and stepinfo of the undisturbed response on the nodes, into *ev (a stable
/// loop; +inf scores are FinishScores' for an unstable one),
Status EvaluateDelayedContinuous(const Plant& plant, const PidGains& loop_gains, const LoopOptions& options,
                                 const EvaluateOptions& what, Evaluation* ev);
/// sum_m |y_L(m ts)| of its load response (r = 0, a unit step at the plant
/// input, delayed with the control),
double DelayedLoadIae(const Plant& plant, const PidGains& loop_gains, const LoopOptions& options,
                      DelayedPath path = DelayedPath::kFast);
/// The same run's \int_0^horizon |y_L| dt, by the trapezoids on its nodes
/// (NodeIntegralAbsError), into *integral; the samples' sum is returned.
double DelayedLoadIae(const Plant& plant, const PidGains& loop_gains, const LoopOptions& options,
                      double* integral);
/// and the tuner's objective: +inf for an unstable or neutral loop.
double DelayedContinuousObjective(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                  double load_weight, const PidGains& loop_gains,
                                  DelayedPath path = DelayedPath::kFast);

}  // namespace pidlab::evaluation::internal
