// Evaluate (evaluation.h): check the loop, then the continuous loop exactly,
// or the sampled loop as simulate (RunSampled: in process, the trio, or a
// log's record) then score (a pure function of the record).

#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "evaluation_internal.h"
#include "pidlab/evaluation/delayed_loop.h"
#include "pidlab/evaluation/evaluation.h"

namespace pidlab::evaluation {
namespace {

using internal::kInf;

// Lost steps: over the last tenth of the horizon the rotor is half a step
// angle or more away from the reference (another detent, or still moving),
// or not finite.
void JudgeMotor(const NonlinearStepperPlant& motor, const std::vector<double>& y_all, double reference,
                Evaluation* ev) {
  ev->has_motor = true;
  ev->motor = motor.peaks();
  ev->final_error = reference - y_all.back();
  const double lambda = motor.options().motor.tooth_pitch_rad;
  // A rotor still swinging half a step away there has not settled, even if
  // it happens to pass the reference at the end.
  const std::size_t n = y_all.size();
  double worst = 0.0;
  for (std::size_t i = n - std::max<std::size_t>(1, n / 10); i < n; ++i) {
    const double e = std::abs(reference - y_all[i]);
    worst = std::isfinite(e) ? std::max(worst, e) : HUGE_VAL;
  }
  ev->lost_steps = !(worst < lambda / 2.0);
  std::ostringstream os;
  if (ev->lost_steps)
    os << "LOST STEPS: over the last 10 % of the horizon the rotor is up to " << worst
       << " rad from the reference and ends " << ev->final_error << " rad from it (half a step is "
       << lambda / 2.0 << " rad): it settled at another detent or never settled";
  ev->motor_note = os.str();
}

// The motor's verdict from a run: the in-process motor, or the model
// re-driven by the run's u_k + n_k, which must give the run's y bit for bit
// (the plant process integrates the same model with the same inputs).
void ScoreMotor(const Plant& plant, const LoopOptions& options, const SampledRun& run, Evaluation* ev) {
  if (run.motor) {
    JudgeMotor(*run.motor, run.y, options.reference, ev);
    return;
  }
  NonlinearStepperPlant motor(*plant.nonlinear, options.dt_s);
  std::size_t differ = 0;
  for (const SampledStep& st : run.trajectory) {
    motor.Step(st.u + st.n);
    const auto next = static_cast<std::size_t>(st.k) + 1;
    const double measured =
        options.measurement_noise.Measured(motor.Output(), static_cast<std::int64_t>(next));
    if (next < run.y.size() && !(measured == run.y[next])) ++differ;
  }
  JudgeMotor(motor, run.y, options.reference, ev);
  if (differ > 0) {
    std::ostringstream os;
    os << (ev->motor_note.empty() ? "" : "; ") << "the motor model re-driven by the run's u + n differs "
       << "from the run's y at " << differ << " steps (peaks are the model's)";
    ev->motor_note += os.str();
  }
}

// y at the sample times t_m = m ts from y at every step.
std::vector<double> AtSamples(const std::vector<double>& y_all, const LoopOptions& options) {
  std::vector<double> out;
  const int per = options.StepsPerSample();
  for (int m = 0; m < options.NumSamples(); ++m) out.push_back(y_all[static_cast<std::size_t>(m) * per]);
  return out;
}

// The checks every evaluation makes; *gains are the loop's (LoopGains).
Status CheckLoop(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                 PidGains* gains) {
  std::string error;
  if (!GainsAreValid(typed_gains, &error) || !options.IsValid(&error)) return Status::InvalidInput(error);
  *gains = LoopGains(typed_gains, options);
  if (!std::isfinite(gains->tf))
    return Status::InvalidInput("a derivative filter ratio needs kp > 0 when kd > 0 (tf = kd / (N kp))");
  if (!GainsAreValid(*gains, &error) || !plant.tf.IsValid(&error)) return Status::InvalidInput(error);
  if (plant.tf.RelativeDegree() < 1)
    return Status::InvalidInput("plant " + plant.tf.ToString() + " must be strictly proper");
  if (const Status st = DelayIsValid(plant, options, "delay"); !st.ok()) return st;
  if (options.loop == LoopKind::kContinuous && plant.delay_s > 0.0) {
    if (const Status st = DelayedLoopIsRetarded(plant.tf, *gains); !st.ok()) return st;
  }
  if (plant.nonlinear && options.loop != LoopKind::kSampled)
    return Status::InvalidInput("plant " + plant.name +
                                " is nonlinear: the exact continuous loop applies to linear plants only, use "
                                "--loop sampled (with --dt 1e-4 or less)");
  return Status::Ok();
}

// A fresh evaluation: what was evaluated, the sample times and n there.
void StartEvaluation(const Plant& plant, const PidGains& gains, const LoopOptions& options, Evaluation* ev) {
  *ev = Evaluation();
  ev->plant = plant;
  ev->gains = gains;
  ev->options = options;
  const Disturbance disturbance(options.disturbance);
  for (int m = 0; m < options.NumSamples(); ++m) {
    ev->t.push_back(m * options.sample_time_s);
    ev->n.push_back(disturbance.Value(m * options.sample_time_s));
  }
}

// The exact continuous loop: y at the samples, the undisturbed IAE, the
// integral of |e| and stepinfo.
Status EvaluateContinuous(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                          const EvaluateOptions& what, Evaluation* ev) {
  if (plant.delay_s > 0.0) return internal::EvaluateDelayedContinuous(plant, gains, options, what, ev);
  const Disturbance disturbance(options.disturbance), none(DisturbanceOptions{});
  const StateSpace ss = Realize(plant.tf);
  const double a = options.reference, ts = options.sample_time_s;
  ContinuousClosedLoop<double> loop;
  const SetpointWeights weights = SetpointWeightsOf(options.pid);
  if (const Status built = BuildContinuousClosedLoop<double>(ss, gains, disturbance, &loop, a, weights);
      !built.ok())
    return built;
  ev->stability = ContinuousStability(loop, options.stability_margin);
  if (!ev->stability.stable) return Status::Ok();
  SampleContinuousLoop<double>(loop, disturbance, ts, options.NumSamples(), &ev->y);
  if (options.disturbance.kind != DisturbanceKind::kNone) {
    ContinuousClosedLoop<double> clean;
    // The loop above without n: it builds whenever that one did.
    (void)BuildContinuousClosedLoop<double>(ss, gains, none, &clean, a, weights);
    std::vector<double> y1;
    SampleContinuousLoop<double>(clean, none, ts, options.NumSamples(), &y1);
    ev->iae_undisturbed = ObjectiveFromSamples(ObjectiveKind::kIae, y1, ts, a);
  }
  if (what.compute_iae_continuous)
    ev->iae_continuous = ContinuousIntegralAbsError(loop, disturbance, ev->stability, options.horizon_s);
  if (what.compute_step_info) ev->step = ContinuousStepInfo(loop, ev->stability);
  return Status::Ok();
}

// The sampled loop's scores from its run: y at the samples, the trapezoidal
// integral of |e| at dt, the undisturbed IAE and stepinfo, the motor.
void ScoreSampled(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                  const EvaluateOptions& what, const SampledRun& run, Evaluation* ev) {
  const double a = options.reference;
  if (plant.nonlinear) ScoreMotor(plant, options, run, ev);
  ev->y = AtSamples(run.y, options);
  double integral = 0.0;
  for (std::size_t k = 1; k < run.y.size(); ++k)
    integral += 0.5 * options.dt_s * (std::abs(a - run.y[k]) + std::abs(a - run.y[k - 1]));
  ev->iae_continuous = integral;
  const std::vector<double>& y1 = run.y_undisturbed.empty() ? run.y : run.y_undisturbed;
  if (!run.y_undisturbed.empty())
    ev->iae_undisturbed =
        ObjectiveFromSamples(ObjectiveKind::kIae, AtSamples(y1, options), options.sample_time_s, a);
  if (what.compute_step_info) {
    std::vector<double> t_all(y1.size());
    for (std::size_t k = 0; k < t_all.size(); ++k) t_all[k] = static_cast<double>(k) * options.dt_s;
    // The final value of the continuous loop's step response, as the
    // continuous loop with this disturbance is built.
    ContinuousClosedLoop<double> loop;
    const bool built =
        BuildContinuousClosedLoop<double>(Realize(plant.tf), gains, Disturbance(options.disturbance), &loop,
                                          a, SetpointWeightsOf(options.pid))
            .ok();
    const bool continuous_stable = built && ContinuousStability(loop, options.stability_margin).stable;
    // With a dead time the sampled loop is stable here and its final value is
    // the undelayed loop's steady state (e^(-sL) = 1 at s = 0), whatever the
    // undelayed loop's stability.
    const double delayed_final = built && plant.delay_s > 0.0 ? ContinuousFinalValue(loop) : a;
    ev->step = SampledStepInfo(
        t_all, y1,
        continuous_stable ? ContinuousFinalValue(loop) : (std::isfinite(delayed_final) ? delayed_final : a));
  }
  if (what.record_trajectory) ev->trajectory = run.trajectory;
}

// The sums of a stable loop from its samples, and its load response; +inf
// for an unstable one.
void FinishScores(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                  const EvaluateOptions& what, Evaluation* ev) {
  if (!ev->stability.stable) {
    ev->iae = ev->ise = ev->itae = ev->iae_continuous = ev->iae_undisturbed = ev->iae_per_unit =
        ev->load_iae = ev->load_iae_continuous = kInf;
    ev->step.note = "unstable loop: no step metrics";
    return;
  }
  const double a = options.reference, ts = options.sample_time_s;
  ev->iae = ObjectiveFromSamples(ObjectiveKind::kIae, ev->y, ts, a);
  ev->ise = ObjectiveFromSamples(ObjectiveKind::kIse, ev->y, ts, a);
  ev->itae = ObjectiveFromSamples(ObjectiveKind::kItae, ev->y, ts, a);
  ev->iae_per_unit = ev->iae / std::abs(a);
  if (options.disturbance.kind == DisturbanceKind::kNone) ev->iae_undisturbed = ev->iae;
  if (!what.compute_load_iae) {
    ev->load_iae = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  const std::unique_ptr<DiscretePlant> discrete =
      options.loop == LoopKind::kSampled ? std::make_unique<DiscretePlant>(SampledPlant(plant, options.dt_s))
                                         : nullptr;
  // The load response of a linear plant; a nonlinear plant's is not computed (NaN).
  if (options.loop == LoopKind::kContinuous && plant.delay_s > 0.0) {
    if (what.compute_iae_continuous)
      ev->load_iae = internal::DelayedLoadIae(plant, gains, options, &ev->load_iae_continuous);
    else
      ev->load_iae = internal::DelayedLoadIae(plant, gains, options);
    return;
  }
  ev->load_iae = plant.nonlinear ? std::numeric_limits<double>::quiet_NaN()
                                 : internal::LoadIaeOfStableLoop(Realize(plant.tf), discrete.get(), gains,
                                                                 options, Disturbance(UnitLoadStep()));
  // The continuous loop's \int|y_L|dt by its exact walker, r = 0.
  ContinuousClosedLoop<double> load;
  if (options.loop == LoopKind::kContinuous && what.compute_iae_continuous && !plant.nonlinear &&
      BuildContinuousClosedLoop<double>(Realize(plant.tf), gains, Disturbance(UnitLoadStep()), &load, 0.0)
          .ok())
    ev->load_iae_continuous =
        ContinuousIntegralAbsError(load, Disturbance(UnitLoadStep()), ev->stability, options.horizon_s);
}

// Checked, started, stability of the sampled loop: the common head of
// Evaluate and EvaluateSampledRun. *gains are the loop's.
Status StartSampled(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                    PidGains* gains, Evaluation* ev) {
  const Status checked = CheckLoop(plant, typed_gains, options, gains);
  if (!checked.ok()) return checked;
  StartEvaluation(plant, *gains, options, ev);
  const DiscretePlant discrete = SampledPlant(plant, options.dt_s);
  ev->stability = SampledStability(discrete, *gains, options.Pid(), options.stability_margin);
  return Status::Ok();
}

}  // namespace

Status RunSampledLoopInProcess(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                               const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                               std::vector<SampledStep>* trajectory) {
  const PidOptions pid = options.Pid();
  if (plant.nonlinear) {
    NonlinearStepperPlant motor(*plant.nonlinear, options.dt_s);
    RunNonlinearSampledLoop(&motor, gains, pid, Disturbance(disturbance), options.TotalSteps(), 1, y_all,
                            trajectory, options.reference, options.measurement_noise);
    return Status::Ok();
  }
  const DiscretePlant discrete = SampledPlant(plant, options.dt_s);
  // A diverged loop (PidStatus::kInvalidInput) is not an error here: its
  // non-finite samples make every objective +inf, as for an unstable loop.
  RunSampledLoop<double>(discrete, gains, pid, Disturbance(disturbance), options.TotalSteps(), 1, y_all,
                         trajectory, options.reference, options.measurement_noise);
  return Status::Ok();
}

Status RunSampled(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                  bool record_trajectory, const SampledRunner& runner, SampledRun* run) {
  *run = SampledRun();
  std::string error;
  const bool has_disturbance = options.disturbance.kind != DisturbanceKind::kNone;
  if (plant.nonlinear && !runner) {
    // In process: the motor's peaks and whether it lost steps come with the run.
    auto motor = std::make_shared<NonlinearStepperPlant>(*plant.nonlinear, options.dt_s);
    RunNonlinearSampledLoop(motor.get(), gains, options.Pid(), Disturbance(options.disturbance),
                            options.TotalSteps(), 1, &run->y, record_trajectory ? &run->trajectory : nullptr,
                            options.reference, options.measurement_noise);
    run->motor = std::move(motor);
  } else {
    const SampledRunner& backend = runner ? runner : SampledRunner(RunSampledLoopInProcess);
    // A backend's nonlinear run always keeps its steps: the motor is re-driven by them.
    const bool steps = record_trajectory || plant.nonlinear;
    const Status ran =
        backend(plant, gains, options, options.disturbance, &run->y, steps ? &run->trajectory : nullptr);
    if (!ran.ok()) return Status::RunnerFailed(ran.message());
  }
  if (has_disturbance) {
    const SampledRunner& backend = runner ? runner : SampledRunner(RunSampledLoopInProcess);
    const Status ran = backend(plant, gains, options, DisturbanceOptions{}, &run->y_undisturbed, nullptr);
    if (!ran.ok()) return Status::RunnerFailed(ran.message());
  }
  return Status::Ok();
}

Status EvaluateSampledRun(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                          const EvaluateOptions& what, const SampledRun& run, Evaluation* ev) {
  if (options.loop != LoopKind::kSampled) return Status::InvalidInput("a run record is of the sampled loop");
  PidGains gains;
  const Status started = StartSampled(plant, typed_gains, options, &gains, ev);
  if (!started.ok()) return started;
  const auto steps = static_cast<std::size_t>(options.TotalSteps()) + 1;
  const bool undisturbed_ok =
      options.disturbance.kind == DisturbanceKind::kNone || run.y_undisturbed.size() == steps;
  if (ev->stability.stable && (run.y.size() != steps || !undisturbed_ok))
    return Status::InvalidInput("the run record has " + std::to_string(run.y.size()) + " outputs, not the " +
                                std::to_string(steps) +
                                " of the loop (and one undisturbed run with a disturbance)");
  if (ev->stability.stable) ScoreSampled(plant, gains, options, what, run, ev);
  FinishScores(plant, gains, options, what, ev);
  return Status::Ok();
}

Status Evaluate(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                const EvaluateOptions& what, Evaluation* ev, const SampledRunner& runner) {
  PidGains gains;
  if (options.loop == LoopKind::kContinuous) {
    const Status checked = CheckLoop(plant, typed_gains, options, &gains);
    if (!checked.ok()) return checked;
    StartEvaluation(plant, gains, options, ev);
    const Status evaluated = EvaluateContinuous(plant, gains, options, what, ev);
    if (!evaluated.ok()) return evaluated;
    FinishScores(plant, gains, options, what, ev);
    return Status::Ok();
  }
  const Status started = StartSampled(plant, typed_gains, options, &gains, ev);
  if (!started.ok()) return started;
  if (ev->stability.stable) {
    SampledRun run;
    const Status ran = RunSampled(plant, gains, options, what.record_trajectory, runner, &run);
    if (!ran.ok()) return ran;
    ScoreSampled(plant, gains, options, what, run, ev);
  }
  FinishScores(plant, gains, options, what, ev);
  return Status::Ok();
}

}  // namespace pidlab::evaluation
