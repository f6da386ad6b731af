#pragma once
// One run assembly: a spec (pidlab/spec/loop_spec.h) to the problem it
// describes, every build, check and resolve step in one function per job,
// then the problem run to the result every front end prints. The command
// line, Python, the workbench's handlers and the live server call these and
// no step of their own, so a refusal is written once, here, and a default
// that depends on the plant has one place to live.
//
//   EvaluationProblem problem;
//   Status s = BuildEvaluation(spec, {NameStyle::kFlag}, &problem);
//   EvaluationResult result;
//   if (s.ok()) s = RunEvaluation(problem, {}, &result);
//
// Every function returns Status: kInvalidInput with one line naming the field
// as the caller names it (a flag or a key), its value and the rule broken;
// kRunnerFailed when the caller's runner (the trio) failed. No exception
// leaves them, except one a caller's progress callback throws to stop a
// tuning.

#include <functional>
#include <set>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/optim/optimizer.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/migo.h"
#include "pidlab/tune/search_box.h"
#include "pidlab/tune/tune.h"

namespace pidlab::tune {

/// Where the sampled loop runs.
enum class Backend {
  /// In this process.
  kInProcess,
  /// On the caller's SampledRunner (the LCM trio: EpisodeClient, EpisodePool),
  /// which runs the sampled loop only, and no Monte Carlo draws.
  kRunner,
};

/// How a spec is read: not part of what runs.
struct BuildOptions {
  /// How a message names a field: a flag (--sample-time, the command line)
  /// or a key (sample_time, Python and JSON).
  spec::NameStyle style = spec::NameStyle::kKey;
  Backend backend = Backend::kInProcess;
  /// The keys the user gave (the flags, keywords or JSON keys; a spec file's
  /// keys count): the tuning's robust preset and search box fill only the
  /// others, and with a runner an evaluation refuses a `loop` given other
  /// than sampled (a `loop` not given becomes sampled).
  std::set<std::string> given;
};

// ---- Evaluate: one gain set on a plant (pidlab evaluate, pidlab.evaluate,
// the workbench's evaluate and run_on_trio).

/// An evaluation spec built, checked and resolved.
struct EvaluationProblem {
  /// The spec as it runs (plant normalised; with a runner, loop sampled):
  /// what the result echoes as "spec", which runs again to the same numbers.
  spec::EvaluateSpec spec;
  Plant plant;
  PidGains gains;
  evaluation::LoopOptions loop;
  analysis::LoopBounds bounds;
  /// The draws of monte_carlo (samples at least 1; run only when
  /// HasMonteCarlo()), seeded by the loop's seed.
  analysis::MonteCarloOptions monte_carlo;
  /// Table I with the spec's stepper overrides (the draws of stepper_motor).
  StepperMotorParameters stepper;
  /// The horizon and sample spacing used, and why: off the paper's plants,
  /// with neither given, from the closed loop of the gains (time_scale.h).
  TimeScale time_scale;

  /// The spec asks for Monte Carlo draws (monte_carlo > 0).
  bool HasMonteCarlo() const { return spec.monte_carlo > 0; }
};

/// Builds the plant, gains, loop, bounds and Monte Carlo options of `s` and
/// checks them together (the plant's dead time in its loop; the draws: in
/// process, of undelayed linear plants). kInvalidInput naming the first bad
/// field; *problem is written only on success.
Status BuildEvaluation(const spec::EvaluateSpec& s, const BuildOptions& options, EvaluationProblem* problem);

/// How an evaluation runs.
struct EvaluationRunOptions {
  /// What is computed and recorded (the trajectory of the sampled loop, ...).
  evaluation::EvaluateOptions what;
  /// The sampled loop's backend (BuildOptions::backend kRunner); null: in process.
  evaluation::SampledRunner runner;
  /// Run the Monte Carlo draws the spec asks for (in process, after the loop).
  bool monte_carlo = true;
  /// Called after each draw with (done, total); may be empty.
  std::function<void(int, int)> monte_carlo_progress;
};

/// What an evaluation gives, for every front end to print.
struct EvaluationResult {
  evaluation::Evaluation evaluation;
  /// Margins, peaks, noise gain and time constants of the loop evaluated.
  analysis::LoopAnalysis analysis;
  /// The draws' summary, when they ran (monte_carlo_ran).
  bool monte_carlo_ran = false;
  analysis::MonteCarloSummary monte_carlo;
};

/// Evaluates the problem's gains (on `options.runner` for the sampled loop),
/// analyses the loop and runs the draws. The loop's status (kInvalidInput,
/// kRunnerFailed); kInvalidInput when the analysis or the draws refuse it.
Status RunEvaluation(const EvaluationProblem& problem, const EvaluationRunOptions& options,
                     EvaluationResult* result);

/// A plant in its loop, for a front end that brings its own gains (pidlab
/// plot: several gain sets on one loop).
Status BuildPlantInLoop(const spec::PlantSpec& plant, const spec::LoopSpec& loop, spec::NameStyle style,
                        Plant* p, evaluation::LoopOptions* options);

/// The loop of a figure of several gain sets (pidlab plot): the plant in its
/// loop, framed for them. With neither horizon nor sample_time in `given`,
/// the closed loops' time scale (ResolveGainsTimeScale, kFigure); else the
/// loop as given. kInvalidInput naming the field as `style` spells it.
Status BuildFigureLoop(const spec::PlantSpec& plant, const spec::LoopSpec& loop,
                       const std::vector<PidGains>& gains, const std::set<std::string>& given,
                       spec::NameStyle style, Plant* p, evaluation::LoopOptions* options);

/// The PID an evaluation spec describes, without its plant (pidlab export,
/// the workbench's export): the gains and the loop options it runs with.
Status BuildController(const spec::EvaluateSpec& s, spec::NameStyle style, PidGains* gains,
                       evaluation::LoopOptions* loop);

/// What `pidlab export` (and the workbench's export) found of the loop it writes.
struct SampledControllerCheck {
  /// False when nothing could be checked (no plant given; a nonlinear plant,
  /// which has no closed-loop poles).
  bool checked = false;
  /// The sampled loop at dt is strictly stable (true when not checked).
  bool stable = true;
  /// One clause: what was found, e.g. "the sampled loop of plant stepper is
  /// stable, largest pole z = 0.99 (|z| = 0.99)"; when unstable, the refusal
  /// naming dt, the largest pole and the way out (a smaller dt, or `force`).
  std::string verdict;
};

/// The spec's plant under the discrete PID at the spec's dt: the sampled
/// loop's poles. kInvalidInput only for a spec that does not build (naming
/// the field); an unstable loop is check->stable false, for the front end to
/// refuse or, forced, to write with a warning.
Status CheckSampledController(const spec::EvaluateSpec& s, spec::NameStyle style,
                              SampledControllerCheck* check);

/// The nonlinear stepper a plant spec describes (pidlab linearize).
Status BuildNonlinearStepper(const spec::PlantSpec& s, spec::NameStyle style, NonlinearStepperOptions* out);

// ---- Tune: gains for a plant (pidlab tune, pidlab.tune, the workbench's tune).

/// True for the paper's three plants (and the nonlinear stepper), whose
/// time scale is the paper's: eq. (4)'s 25 s at 0.05 s.
bool IsPaperPlant(const spec::PlantSpec& p);

/// Resolves what a tuning spec leaves to the plant and the preset, in this
/// order (docs/tuning.md, "Any plant"):
/// - with no `method` given and nothing that asks for a search (an
///   objective, a box, budgets, a margin, a settling or time-constant bound,
///   `robust`, a robust set, the sampled loop on the caller's trio runner;
///   the sampled loop in process is the engine's too), the
///   design engine, method optimal (the nonlinear stepper: multi-start),
///   with max_ms as its robustness where that is not given; TimeScale's
///   method_reason says which and why;
/// - with no derivative filter given (nor `robust`), a PID of any method
///   but optimal (which designs its own) gets derivative_filter_ratio 10 (on
///   the paper's plants, migo's only);
/// - optimal and migo: with no robustness given, SIMC's Ms on the plant
///   (DefaultRobustness); optimal: with no max_noise_gain given, migo's
///   noise gain at that Ms (DefaultNoiseGain);
/// - with neither `horizon` nor `sample_time` given, on a plant other than
///   the paper's, the time scale of the migo design's closed loop
///   (LoopTimeScale; the plant's own times where migo does not apply); on a
///   sampled loop the spacing is a multiple of dt;
/// - with `robust`, every preset field not in `given` takes the preset's
///   value (objective setpoint-load, load weight 1, derivative filter ratio
///   10, Ms <= 1.6, slowest time constant <= horizon / 10);
/// - with no `bounds` given, the box from the plant's scale (search_box.h).
/// The spec then says what runs, so its echo runs again to the same tuning.
/// Nothing is validated (a plant that does not build keeps the defaults).
/// Returns the box and its source; *time_scale (may be null) the time scale
/// and its source.
SearchBox ResolveTuningSpec(spec::TuningSpec* s, const std::set<std::string>& given,
                            TimeScale* time_scale = nullptr, Backend backend = Backend::kInProcess);

/// A tuning spec resolved, built and checked.
struct TuningProblem {
  /// The spec as it runs (plant normalised, preset and box resolved): the echo.
  spec::TuningSpec spec;
  /// The gain box and where it came from.
  SearchBox box;
  /// The horizon and sample spacing and where they came from.
  TimeScale time_scale;
  Plant plant;
  TuneOptions options;
};

/// ResolveTuningSpec, then the plant and the tuning options of the resolved
/// spec, checked together (the dead time in the loop; a nonlinear plant on
/// the sampled loop; a runner on the sampled loop). kInvalidInput naming the
/// first bad field; *problem is written only on success.
Status BuildTuning(const spec::TuningSpec& s, const BuildOptions& options, TuningProblem* problem);

/// How a tuning runs.
struct TuningRunOptions {
  /// The sampled loop's backend (BuildOptions::backend kRunner); null: in process.
  evaluation::SampledRunner runner;
  /// Independent evaluations at the same time (TuneOptions::parallel_for:
  /// e.g. one trio each); empty: the problem's.
  optim::ParallelFor parallel_for;
  /// Called once per iteration of the search; may throw to stop it (the
  /// exception leaves RunTuning).
  optim::ProgressCallback progress;
};

/// What a tuning gives, for every front end to print.
struct TuningResult {
  TuneSummary summary;
  /// With a stable result: the loop with the setpoint weights found (two_dof),
  /// evaluated in process with the gains found, and analysed.
  evaluation::LoopOptions loop;
  evaluation::Evaluation evaluation;
  analysis::LoopAnalysis analysis;
  /// A search in process on a box not given, off the paper's plants (whose
  /// box is the paper's [0, 30]), that ended on an upper edge
  /// ran again on a box ten times wider (up to twice): the upper bounds it
  /// had before, in order ([] when it did not widen), and the upper bound the
  /// summary's gains were found in.
  std::vector<double> widened_from;
  double box_upper = 0.0;
  /// A search whose every loop was neutral (an ideal derivative on relative
  /// degree 1 with dead time: IdealDerivativeMakesLoopNeutral) ran again
  /// with a filtered derivative, tf = Td / kMigoFilterRatio: that, in one
  /// line ("" when it did not).
  std::string fallback;
  /// The options the summary's gains were tuned with: problem.options with
  /// the box widened and the fallback's filter.
  TuneOptions options;
};

/// Tunes (Tune()), then evaluates and analyses the gains found in process
/// when the result is stable. kInvalidInput when the method does not apply
/// or the loop of the gains found cannot be analysed. An unstable result is
/// not an error: summary.stable is false. *result holds the summary (what
/// the search reached) even when the method failed.
Status RunTuning(const TuningProblem& problem, const TuningRunOptions& options, TuningResult* result);

}  // namespace pidlab::tune
