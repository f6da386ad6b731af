#pragma once
// Evaluation of a PID loop: the paper's objective (eq. 4-5), other error
// measures, stability and MATLAB-stepinfo step metrics.

#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/spec/status.h"

namespace pidlab::evaluation {

/// Objectives over the error samples e_m = A - y(m ts), m = 0..M, A the size
/// of the reference step (LoopOptions::reference, 1 in the paper):
///   iae  = sum |e_m|          (eq. 4, the paper's Error(K); not scaled by ts)
///   ise  = sum e_m^2
///   itae = sum t_m |e_m|
///   iae_continuous = \int_0^n |e(t)| dt (continuous time, on a grid fine
///                    enough for the fastest pole; trapezoidal at dt for the
///                    sampled loop)
/// and over the load response y_L: r = 0, a unit step n = 1 at the plant
/// input from t = 0, no other disturbance, so e = -y_L (LoadIntegralAbsError):
///   load_iae      = sum |y_L(m ts)|  (the same 501 samples as eq. 4)
///   setpoint_load = iae + W load_iae  (W = the load weight, default 1)
enum class ObjectiveKind { kIae, kIse, kItae, kIaeContinuous, kLoadIae, kSetpointLoad };
bool ParseObjectiveKind(const std::string& s, ObjectiveKind* kind);
std::string ToString(ObjectiveKind kind);

/// Step metrics as MATLAB's stepinfo defines them, for the undisturbed unit
/// step response y1 (eq. 17): rise time 10 % -> 90 % of the final value,
/// overshoot in % of the final value, settling time after which
/// |y - y_final| <= 2 % of |y_final| for good.
struct StepInfo {
  bool valid = false;
  std::string note;  // why not valid; empty when valid or not computed
  double final_value = 0, rise_time_s = 0, overshoot_pct = 0, settling_time_s = 0;
  double peak = 0, peak_time_s = 0;
};

struct Evaluation {
  Plant plant;
  PidGains gains;
  LoopOptions options;
  Stability stability;
  /// Sample times t_m, outputs y(t_m) with the disturbance, disturbance n(t_m).
  std::vector<double> t, y, n;
  /// Objectives of y (with the disturbance if one is set). +inf if unstable.
  double iae = 0, ise = 0, itae = 0, iae_continuous = 0;
  /// iae / |A| (A = options.reference): the IAE per unit of step, so that
  /// moves of different sizes compare. +inf if unstable.
  double iae_per_unit = 0;
  /// IAE of the undisturbed response y1 (equals iae without a disturbance).
  double iae_undisturbed = 0;
  /// IAE of the load response (LoadIntegralAbsError; unit input step, r = 0).
  /// +inf if unstable.
  double load_iae = 0;
  /// The continuous loop's \int_0^horizon |y_L| dt of that load response
  /// (the exact walker; with dead time the trapezoids on the delayed loop's
  /// nodes); NaN for the sampled loop, a nonlinear plant, or when
  /// compute_iae_continuous or compute_load_iae is off.
  double load_iae_continuous = std::numeric_limits<double>::quiet_NaN();
  StepInfo step;
  /// stepper_nonlinear only: what the motor did, and whether it lost steps
  /// (at the horizon the rotor is lambda/2 or more from A: it settled at
  /// another detent or never settled). A response that lost steps keeps its
  /// IAE, but says so (status, note).
  bool has_motor = false;
  StepperPeaks motor;
  bool lost_steps = false;
  double final_error = 0.0;  // A - y at the horizon, rad
  std::string motor_note;
  /// Every step of the sampled loop (sampled loop with record_trajectory).
  std::vector<SampledStep> trajectory;

  /// The objective `kind`; setpoint-load weighs load_iae by load_weight.
  double Objective(ObjectiveKind kind, double load_weight = 1.0) const;
};

struct EvaluateOptions {
  bool compute_step_info = true;
  bool compute_iae_continuous = true;
  bool record_trajectory = false;
  /// The load response (load_iae); off, load_iae is NaN. A search over the
  /// setpoint weights, which move no pole and no load response, skips it.
  bool compute_load_iae = true;
};

/// Runs the sampled loop of `options` with the disturbance `disturbance`
/// (which may differ from options.disturbance: the undisturbed response is
/// run too) and returns y at every step k = 0..TotalSteps() in *y_all;
/// records every step in *trajectory when it is not null. A backend other
/// than the process itself: the LCM trio (EpisodeClient::Run), with results
/// bit-identical to the in-process loop. kRunnerFailed naming the cause if the
/// run failed.
using SampledRunner = std::function<Status(const Plant& plant, const PidGains& gains,
                                           const LoopOptions& options, const DisturbanceOptions& disturbance,
                                           std::vector<double>* y_all, std::vector<SampledStep>* trajectory)>;

/// The sampled loop run in process (linear or nonlinear plant), as a SampledRunner.
Status RunSampledLoopInProcess(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                               const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                               std::vector<SampledStep>* trajectory);

/// What one run of the sampled loop leaves, whichever backend ran it (in
/// process, the trio, a log). Evaluation is: simulate (RunSampled, or read a
/// log), then score this record (EvaluateSampledRun), a pure function of it.
struct SampledRun {
  /// y_k at every step k = 0..TotalSteps(), with the loop's disturbance.
  std::vector<double> y;
  /// The same loop without the disturbance; empty when it has none.
  std::vector<double> y_undisturbed;
  /// Every step (k, t, r, y, u, n) of the disturbed run, when recorded; a
  /// nonlinear plant run by a backend always has it (the motor's peaks are
  /// the model re-driven by its u + n).
  std::vector<SampledStep> trajectory;
  /// The nonlinear motor as the run left it, when it ran in process.
  std::shared_ptr<const NonlinearStepperPlant> motor;
};

/// Runs the sampled loop (and, with a disturbance, the undisturbed one) with
/// `gains` (LoopGains already applied) on `runner`, or in process when
/// `runner` is null. kRunnerFailed with the runner's message if it failed.
Status RunSampled(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                  bool record_trajectory, const SampledRunner& runner, SampledRun* run);

/// Evaluates the sampled loop `options` describes from a run record (a
/// log's episode, a run made elsewhere): the same checks and the same
/// numbers as Evaluate with the backend that made the record.
Status EvaluateSampledRun(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                          const EvaluateOptions& what, const SampledRun& run, Evaluation* evaluation);

/// Evaluates `gains` on `plant`: the continuous loop exactly, or the sampled
/// loop run on `runner` (in process when null) and scored. kInvalidInput for
/// invalid input, kRunnerFailed when the runner failed. An unstable loop is
/// not an error: evaluation->stability.stable is false and the objectives
/// are +inf.
Status Evaluate(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                const EvaluateOptions& what, Evaluation* evaluation, const SampledRunner& runner = nullptr);

/// The continuous-loop objective of `gains` by the general path:
/// BuildContinuousClosedLoop, ContinuousStability (eigenvalues), then
/// SampleContinuousLoop and ObjectiveFromSamples, or
/// ContinuousIntegralAbsError. +inf when the loop is ill-posed or not strictly
/// stable. ObjectiveEvaluator falls back to it for what
/// FastContinuousObjective does not cover.
double GeneralContinuousObjective(const StateSpace& realization, const Disturbance& disturbance,
                                  const LoopOptions& options, ObjectiveKind kind, const PidGains& gains);

class FastContinuousObjective;

/// The unit step at the plant input from t = 0 of the load response.
DisturbanceOptions UnitLoadStep();

/// What ObjectiveEvaluator::operator() throws when its runner (the trio)
/// fails: the search stops, and Tune returns it as a kRunnerFailed Status, so
/// it never leaves the tuner.
struct RunnerFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The tuner's inner loop: the objective of one gain vector, +inf for any loop
/// that is not strictly stable. Realisation and discretisation are done once.
class ObjectiveEvaluator {
 public:
  /// Throws std::invalid_argument if the options are invalid. A sampled loop
  /// is run in-process unless another `runner` (e.g. the LCM trio) is given;
  /// the load objectives run in-process only (invalid with a runner).
  /// `load_weight` (finite, >= 0): W of setpoint-load.
  ObjectiveEvaluator(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                     SampledRunner runner = nullptr, double load_weight = 1.0);
  /// Throws RunnerFailure if the runner fails.
  double operator()(const PidGains& gains) const;
  /// Evaluations so far. operator() may be called from several threads at
  /// once (parallel starts over several trios).
  long evaluations() const { return evaluations_.load(); }
  const LoopOptions& options() const { return options_; }
  const Plant& plant() const { return plant_; }
  ObjectiveKind kind() const { return kind_; }
  /// True when operator() runs FastContinuousObjective (the continuous loop
  /// in the cases it covers), false on the general path.
  bool fast_path() const { return fast_ != nullptr; }

 private:
  // The objective of a strictly stable loop (checked by operator()).
  double LoadIae(const PidGains& gains) const;

  Plant plant_;
  LoopOptions options_;
  ObjectiveKind kind_;
  double load_weight_ = 1.0;
  Disturbance load_step_{UnitLoadStep()};
  StateSpace realization_;
  Disturbance disturbance_;
  std::unique_ptr<DiscretePlant> discrete_;
  std::shared_ptr<const FastContinuousObjective> fast_;  // null where it does not cover the case
  SampledRunner runner_;
  mutable std::atomic<long> evaluations_{0};
};

/// ObjectiveEvaluator's objective on the continuous loop with dead time
/// (plant.delay_s > 0) by the reference path: the Nyquist count on the
/// analysis grid for every candidate and the method of steps node by node,
/// the loop computed as before the crossing test (delay_crossings.h) and the
/// uniform grid (delayed_loop.h). The same objective to rounding, many times
/// slower: only for the equivalence tests and bench/delay_bench.cc.
double ReferenceDelayedObjective(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                 const PidGains& typed_gains, double load_weight = 1.0);

/// Objective from output samples y_m at t_m = m ts (iae, ise, itae only;
/// throws std::logic_error for the others), with e_m = reference - y_m.
double ObjectiveFromSamples(ObjectiveKind kind, const std::vector<double>& y, double ts,
                            double reference = 1.0);

/// The load response's IAE: the loop of `options` (continuous or sampled,
/// with its stability margin) with r = 0 and, instead of options.disturbance,
/// a unit step n = 1 at the plant input from t = 0; e = -y, summed over the
/// samples t_m = m ts of eq. (4): sum_m |y(t_m)|. Exact on the continuous loop
/// (the step is a state of the exosystem; no derivative kick since r does not
/// move). +inf if the loop is not strictly stable.
double LoadIntegralAbsError(const Plant& plant, const PidGains& gains, const LoopOptions& options);

/// MATLAB stepinfo on the exact continuous step response (no disturbance),
/// on a grid whose step follows the fastest pole still alive, with crossings
/// and the peak refined by exact propagation.
StepInfo ContinuousStepInfo(const ContinuousClosedLoop<double>& loop, const Stability& stability);

/// \int_0^horizon |A - y(t)| dt of the continuous loop (with its disturbance), A = loop.reference.
double ContinuousIntegralAbsError(const ContinuousClosedLoop<double>& loop, const Disturbance& disturbance,
                                  const Stability& stability, double horizon_s);

/// stepinfo on a sampled response (linear interpolation at crossings).
StepInfo SampledStepInfo(const std::vector<double>& t, const std::vector<double>& y, double final_value);

/// Final value of the step response (step of size loop.reference) of a stable continuous loop.
double ContinuousFinalValue(const ContinuousClosedLoop<double>& loop);

}  // namespace pidlab::evaluation
