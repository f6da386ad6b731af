// The continuous loop with dead time in Evaluate and the tuner's objective
// (evaluation_internal.h): stability by the crossing frequencies
// (delay_crossings.h; the Nyquist count where they leave it undecided), the
// responses by the method of steps (delayed_loop.h). The reference path,
// the Nyquist count always and the method of steps node by node, is the
// same loop computed as before both: the equivalence tests and
// bench/delay_bench.cc measure the fast path against it.

#include <cmath>
#include <limits>

#include "evaluation_internal.h"
#include "pidlab/evaluation/delay_crossings.h"
#include "pidlab/evaluation/delayed_loop.h"
#include "pidlab/evaluation/loop_frequency.h"

namespace pidlab::evaluation::internal {
namespace {

using internal::kInf;
// The Nyquist count's grid, as the analysis's default.
constexpr double kPointsPerDecade = 100.0;

// y at the samples of the delayed loop with `disturbance` and reference a;
// false (with *error) when the run is refused.
bool Sample(const Plant& plant, const PidGains& gains, const LoopOptions& options, const Disturbance& d,
            double a, DelayedPath path, std::vector<double>* y, DelayedTrace* trace, std::string* error) {
  DelayedClosedLoop loop;
  if (const Status st = BuildDelayedClosedLoop(plant.tf, Realize(plant.tf), gains, d, plant.delay_s, a, &loop,
                                               SetpointWeightsOf(options.pid));
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  DelayedTrace untraced;
  if (!trace) trace = &untraced;
  trace->node_by_node = path == DelayedPath::kReference;
  const Status st = SampleDelayedLoop(loop, d, options.sample_time_s, options.NumSamples(), y, trace);
  if (!st.ok() && error) *error = st.message();
  return st.ok();
}

// The integral of |e| over the nodes (trapezoids, a sign change split as
// the continuous loop's walker does).
double NodeIntegralAbsError(const DelayedTrace& trace, double a) {
  double sum = 0.0;
  for (std::size_t i = 1; i < trace.t.size(); ++i) {
    const double h = trace.t[i] - trace.t[i - 1];
    const double e0 = a - trace.y[i - 1], e1 = a - trace.y[i];
    if ((e0 > 0) == (e1 > 0) || e0 == 0.0 || e1 == 0.0) {
      sum += 0.5 * h * (std::abs(e0) + std::abs(e1));
    } else {
      const double f = std::abs(e0) / (std::abs(e0) + std::abs(e1));
      sum += 0.5 * h * (f * std::abs(e0) + (1.0 - f) * std::abs(e1));
    }
  }
  return std::isfinite(sum) ? sum : kInf;
}

}  // namespace

Status DelayedStability(const Plant& plant, const PidGains& gains, Stability* s, DelayedPath path) {
  *s = Stability();
  if (path == DelayedPath::kFast) {
    std::vector<double> num, den;
    ContinuousPidPolynomials(gains, &num, &den);
    const CrossingCount crossings =
        CountRootsByCrossings(frequency::Mul(num, frequency::Trim(plant.tf.num)),
                              frequency::Mul(den, frequency::Trim(plant.tf.den)), plant.delay_s);
    if (crossings.verdict != CrossingVerdict::kUndecided) {
      s->stable = crossings.verdict == CrossingVerdict::kStable;
      return Status::Ok();
    }
  }
  NyquistCount count;
  if (const Status st = CountContinuousNyquist(plant.tf, gains, plant.delay_s, kPointsPerDecade, &count);
      !st.ok())
    return st;
  s->stable = count.stable;
  return Status::Ok();
}

Status EvaluateDelayedContinuous(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                                 const EvaluateOptions& what, Evaluation* ev) {
  const Status st = DelayedStability(plant, gains, &ev->stability);
  if (!st.ok() || !ev->stability.stable) return st;
  const Disturbance disturbance(options.disturbance), none(DisturbanceOptions{});
  const double a = options.reference;
  const DelayedPath fast = DelayedPath::kFast;
  const bool disturbed = options.disturbance.kind != DisturbanceKind::kNone;
  std::string error;
  DelayedTrace trace, clean;
  // Without a disturbance one run records the nodes for both (a stiff
  // loop's Hermite nodes are millions).
  trace.record = what.compute_iae_continuous || (!disturbed && what.compute_step_info);
  clean.record = what.compute_step_info;
  if (!Sample(plant, gains, options, disturbance, a, fast, &ev->y, &trace, &error))
    return Status::InvalidInput(error);
  if (disturbed) {
    std::vector<double> y1;
    if (!Sample(plant, gains, options, none, a, fast, &y1, &clean, &error))
      return Status::InvalidInput(error);
    ev->iae_undisturbed = ObjectiveFromSamples(ObjectiveKind::kIae, y1, options.sample_time_s, a);
  } else if (clean.record) {
    clean = std::move(trace);
    ev->iae_undisturbed = ObjectiveFromSamples(ObjectiveKind::kIae, ev->y, options.sample_time_s, a);
  }
  if (what.compute_iae_continuous)
    ev->iae_continuous = NodeIntegralAbsError(!disturbed && clean.record ? clean : trace, a);
  if (what.compute_step_info) {
    // e^(-sL) = 1 at s = 0: the undelayed loop's steady state.
    ContinuousClosedLoop<double> undelayed;
    const bool built = BuildContinuousClosedLoop<double>(Realize(plant.tf), gains, none, &undelayed, a,
                                                         SetpointWeightsOf(options.pid))
                           .ok();
    const double yf = built ? ContinuousFinalValue(undelayed) : a;
    ev->step = SampledStepInfo(clean.t, clean.y, std::isfinite(yf) ? yf : a);
  }
  return Status::Ok();
}

double DelayedLoadIae(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                      DelayedPath path) {
  thread_local std::vector<double> y;
  if (!Sample(plant, gains, options, Disturbance(UnitLoadStep()), 0.0, path, &y, nullptr, nullptr))
    return kInf;
  double sum = 0.0;
  for (double v : y) sum += std::abs(v);
  return std::isfinite(sum) ? sum : kInf;
}

double DelayedLoadIae(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                      double* integral) {
  std::vector<double> y;
  DelayedTrace trace;
  trace.record = true;
  *integral = kInf;
  if (!Sample(plant, gains, options, Disturbance(UnitLoadStep()), 0.0, DelayedPath::kFast, &y, &trace,
              nullptr))
    return kInf;
  *integral = NodeIntegralAbsError(trace, 0.0);
  double sum = 0.0;
  for (double v : y) sum += std::abs(v);
  return std::isfinite(sum) ? sum : kInf;
}

double DelayedContinuousObjective(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                  double load_weight, const PidGains& gains, DelayedPath path) {
  if (!DelayedLoopIsRetarded(plant.tf, gains).ok()) return kInf;
  Stability s;
  if (!DelayedStability(plant, gains, &s, path).ok() || !s.stable) return kInf;
  if (kind == ObjectiveKind::kLoadIae) return DelayedLoadIae(plant, gains, options, path);
  thread_local std::vector<double> y;
  DelayedTrace trace;
  trace.record = kind == ObjectiveKind::kIaeContinuous;
  const double a = options.reference;
  if (!Sample(plant, gains, options, Disturbance(options.disturbance), a, path, &y, &trace, nullptr))
    return kInf;
  if (kind == ObjectiveKind::kIaeContinuous) return NodeIntegralAbsError(trace, a);
  if (kind != ObjectiveKind::kSetpointLoad) return ObjectiveFromSamples(kind, y, options.sample_time_s, a);
  const double setpoint = ObjectiveFromSamples(ObjectiveKind::kIae, y, options.sample_time_s, a);
  const double sum =
      load_weight == 0.0 ? setpoint : setpoint + load_weight * DelayedLoadIae(plant, gains, options, path);
  return std::isfinite(sum) ? sum : kInf;
}

}  // namespace pidlab::evaluation::internal

namespace pidlab::evaluation {

double ReferenceDelayedObjective(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                 const PidGains& typed_gains, double load_weight) {
  const PidGains gains = LoopGains(typed_gains, options);
  if (!GainsAreValid(gains, nullptr)) return internal::kInf;
  return internal::DelayedContinuousObjective(plant, options, kind, load_weight, gains,
                                              internal::DelayedPath::kReference);
}

}  // namespace pidlab::evaluation
