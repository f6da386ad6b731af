// The continuous loop with dead time in Evaluate and the tuner's objective
// (evaluation_internal.h): stability by the Nyquist count, the responses by
// the method of steps (delayed_loop.h).

#include <cmath>
#include <limits>

#include "evaluation_internal.h"
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
            double a, std::vector<double>* y, DelayedTrace* trace, std::string* error) {
  DelayedClosedLoop loop;
  if (!BuildDelayedClosedLoop(plant.tf, Realize(plant.tf), gains, d, plant.delay_s, a, &loop, error,
                              SetpointWeightsOf(options.pid)))
    return false;
  return SampleDelayedLoop(loop, d, options.sample_time_s, options.NumSamples(), y, trace, error);
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

Status DelayedStability(const Plant& plant, const PidGains& gains, Stability* s) {
  *s = Stability();
  NyquistCount count;
  std::string error;
  if (!CountContinuousNyquist(plant.tf, gains, plant.delay_s, kPointsPerDecade, &count, &error))
    return Status::InvalidInput(error);
  s->stable = count.stable;
  return Status::Ok();
}

Status EvaluateDelayedContinuous(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                                 const EvaluateOptions& what, Evaluation* ev) {
  const Status st = DelayedStability(plant, gains, &ev->stability);
  if (!st.ok() || !ev->stability.stable) return st;
  const Disturbance disturbance(options.disturbance), none(DisturbanceOptions{});
  const double a = options.reference;
  std::string error;
  DelayedTrace trace, clean;
  trace.record = what.compute_iae_continuous;
  clean.record = what.compute_step_info;
  if (!Sample(plant, gains, options, disturbance, a, &ev->y, &trace, &error))
    return Status::InvalidInput(error);
  std::vector<double> y1;
  if (options.disturbance.kind != DisturbanceKind::kNone || clean.record) {
    if (!Sample(plant, gains, options, none, a, &y1, &clean, &error)) return Status::InvalidInput(error);
    ev->iae_undisturbed = ObjectiveFromSamples(ObjectiveKind::kIae, y1, options.sample_time_s, a);
  }
  if (what.compute_iae_continuous) ev->iae_continuous = NodeIntegralAbsError(trace, a);
  if (what.compute_step_info) {
    // e^(-sL) = 1 at s = 0: the undelayed loop's steady state.
    ContinuousClosedLoop<double> undelayed;
    const bool built = BuildContinuousClosedLoop<double>(Realize(plant.tf), gains, none, &undelayed, nullptr,
                                                         a, SetpointWeightsOf(options.pid));
    const double yf = built ? ContinuousFinalValue(undelayed) : a;
    ev->step = SampledStepInfo(clean.t, clean.y, std::isfinite(yf) ? yf : a);
  }
  return Status::Ok();
}

double DelayedLoadIae(const Plant& plant, const PidGains& gains, const LoopOptions& options) {
  thread_local std::vector<double> y;
  if (!Sample(plant, gains, options, Disturbance(UnitLoadStep()), 0.0, &y, nullptr, nullptr)) return kInf;
  double sum = 0.0;
  for (double v : y) sum += std::abs(v);
  return std::isfinite(sum) ? sum : kInf;
}

double DelayedContinuousObjective(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                  double load_weight, const PidGains& gains) {
  if (!DelayedLoopIsRetarded(plant.tf, gains, nullptr)) return kInf;
  Stability s;
  if (!DelayedStability(plant, gains, &s).ok() || !s.stable) return kInf;
  if (kind == ObjectiveKind::kLoadIae) return DelayedLoadIae(plant, gains, options);
  thread_local std::vector<double> y;
  DelayedTrace trace;
  trace.record = kind == ObjectiveKind::kIaeContinuous;
  const double a = options.reference;
  if (!Sample(plant, gains, options, Disturbance(options.disturbance), a, &y, &trace, nullptr)) return kInf;
  if (kind == ObjectiveKind::kIaeContinuous) return NodeIntegralAbsError(trace, a);
  if (kind != ObjectiveKind::kSetpointLoad) return ObjectiveFromSamples(kind, y, options.sample_time_s, a);
  const double setpoint = ObjectiveFromSamples(ObjectiveKind::kIae, y, options.sample_time_s, a);
  const double sum =
      load_weight == 0.0 ? setpoint : setpoint + load_weight * DelayedLoadIae(plant, gains, options);
  return std::isfinite(sum) ? sum : kInf;
}

}  // namespace pidlab::evaluation::internal
