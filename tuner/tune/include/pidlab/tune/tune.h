#pragma once
// PID tuning: a search method on the paper's objective (or ISE/ITAE/
// continuous IAE), over the gain box, followed by a Ceres least-squares
// cross-check of the result. The default search is a multi-start from a
// space-filling design (multi_start.h), whose result does not depend on the
// seed's luck.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/optim/multi_start.h"
#include "pidlab/optim/optimizer.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/design.h"
#include "pidlab/tune/migo.h"
#include "pidlab/tune/tuning_rules.h"
#include "pidlab/tune/two_dof.h"
#include "pidlab/tune/ziegler_nichols.h"

namespace pidlab::tune {

/// The most loop steps one tuning may cost: its evaluation budget times
/// LoopOptions::StepsPerEvaluation() (README.md, "Exit status and limits";
/// a few minutes here). The default sampled loop, 5000 evaluations of 25,000
/// steps, is 40 times below it. The Ceres cross-check comes on top.
inline constexpr double kMaxTuneSteps = 5e9;

enum class TuneMethod {
  kMultiStart,
  kNelderMead,
  kPaperNelderMead,
  kZieglerNichols,
  kGeneticAlgorithm,
  kPsoGsa,
  kSimc,     // Skogestad's SIMC rule on a reduced model (tuning_rules.h)
  kAmigo,    // Astrom and Hagglund's AMIGO rule on a reduced model (tuning_rules.h)
  kMigo,     // the largest ki under an Ms bound, on the frequency response (migo.h)
  kOptimal,  // the design engine: the least load IAE under Ms, Mt and noise bounds (design.h)
};
/// multi-start | nelder-mead | paper-nm | ziegler-nichols | ga | pso-gsa | simc | amigo | migo | optimal
bool ParseTuneMethod(const std::string& s, TuneMethod* method);
std::string ToString(TuneMethod method);
/// True for the methods that compute their gains by a rule and evaluate them
/// once (ziegler-nichols, simc, amigo, migo, optimal): no search over the
/// box, no Ceres cross-check.
bool IsTuningRule(TuneMethod method);

/// The multi-start's defaults (docs/optimisers.md, "MultiStart"): the design
/// of 1024 scrambled Sobol' points warped by ln(10^4), 16 polished starts at
/// least 0.2 apart in the warped cube, 20000 evaluations in all, Ceres from the
/// best 2 distinct polished minima. Chosen so that seeds 1-20 all reach the
/// best objective any method finds on the three plants (tune_test).
inline constexpr int kMultiStartDesignPoints = 1024;
inline constexpr int kMultiStartStarts = 16;
inline constexpr int kMultiStartEvaluations = 20000;
inline constexpr double kMultiStartSeparation = 0.2;
/// ln(10^4): as many design points in the first 10^-4 of each gain's range
/// as in its upper half, because good gains span decades (the stepper's
/// optimum has kp = 0.05 and kd = 0.05 in a box of width 30).
inline constexpr double kGainWarp = 9.210340371976184;

struct TuneOptions {
  TuneMethod method = TuneMethod::kMultiStart;
  evaluation::ObjectiveKind objective = evaluation::ObjectiveKind::kIae;
  /// W of setpoint-load (iae + W load_iae); finite, >= 0.
  double load_weight = 1.0;
  /// The loop the objective is evaluated on (default: the paper's continuous
  /// loop, ts = 0.05 s, n = 25 s, no disturbance). Its stability_margin is the
  /// acceptance margin of candidates; DefaultTuneLoop() raises it to 0.01, because
  /// with a margin near zero the search parks poles a hair left of the
  /// imaginary axis where the sampled objective cannot see them.
  evaluation::LoopOptions loop = DefaultTuneLoop();
  static evaluation::LoopOptions DefaultTuneLoop() {
    evaluation::LoopOptions o;
    o.stability_margin = 0.01;
    return o;
  }
  /// Search box, the same for kp, ki and kd (paper: 0 to 30); upper <= kMaxGain.
  double lower = 0.0;
  double upper = 30.0;
  /// Iteration budget; 0 = the method's default (100 for paper-nm, as the paper).
  int max_iterations = 0;
  /// Evaluation budget over all starts; 0 = the method's default.
  int max_evaluations = 0;
  /// Independent seeded starts (nelder-mead, paper-nm: 0 = 4), or polished
  /// starts (multi-start: 0 = kMultiStartStarts); >= 0.
  int starts = 0;
  /// multi-start: points of the space-filling design; with max_evaluations
  /// set, at most half of it.
  int design_points = kMultiStartDesignPoints;
  /// multi-start: Ceres runs from this many distinct polished minima, best
  /// first (>= 1); the best exact result is kept.
  int refine_starts = 2;
  /// nelder-mead: the base point of the first start (kp, ki, kd), e.g. a
  /// tuning rule's gains to improve on; empty: drawn from the seed. Inside
  /// the box. Other methods ignore it.
  std::vector<double> start;
  /// nelder-mead: Gao & Han's dimension-dependent coefficients instead of
  /// (1, 2, 1/2, 1/2).
  bool adaptive = false;
  std::uint64_t seed = 1;
  /// `tune --two-dof` (docs/two_dof.md): after the feedback gains, the
  /// setpoint weights b, c for the setpoint step with the gains fixed
  /// (TuneSetpointWeights); TuneSummary::two_dof.
  bool two_dof = false;
  /// Constraints on the undisturbed step response (+inf = none): a candidate
  /// violating them is rejected like an unstable loop.
  double max_overshoot_pct = std::numeric_limits<double>::infinity();
  double max_settling_time_s = std::numeric_limits<double>::infinity();
  /// Robustness bounds (Ms, Mt, noise gain, margins, time constant): a
  /// candidate breaking one is rejected like an unstable loop, by the cheap
  /// check ContinuousLoopMeetsBounds (continuous loop) or AnalyzeLoop
  /// (sampled loop, 20 points a decade); the Ceres point only if it meets them.
  analysis::LoopBounds bounds;
  /// The robust set (`--robust-samples N`, docs/robustness.md): when N > 0
  /// the search minimises the `robust_quantile` quantile (nearest rank; 1 =
  /// the worst case) of the objective over the nominal plant and N plants
  /// drawn around it as `evaluate --monte-carlo` draws them (DrawPlants with
  /// `robust_spread` and `seed`; an identified model with a covariance:
  /// from that covariance, `robust_spread` unused). A draw whose loop is not strictly stable
  /// counts as +inf, so the worst case accepts only gains that stabilise
  /// every draw. The bounds and step constraints apply to the nominal loop.
  int robust_samples = 0;
  double robust_spread = 0.1;
  double robust_quantile = 1.0;
  /// Table I of the stepper motor, for the draws when the plant is
  /// "stepper_motor" (its --stepper overrides); unused otherwise.
  StepperMotorParameters stepper;
  /// Run the Ceres cross-check after the search (not with a robust set,
  /// whose quantile has no least-squares form).
  bool refine = true;
  /// RefineVerdict::kAgree when |f_ceres - f_search| <= agree_tolerance * f_search.
  double agree_tolerance = 1e-3;
  /// Ziegler-Nichols rule (ziegler-nichols only).
  ZieglerNicholsRule zn_rule = ZieglerNicholsRule::kClassic;
  /// PI or PID (simc, amigo and migo only).
  RuleForm rule = RuleForm::kPid;
  /// migo: the bound on Ms and Mt, the response time (0: as fast as the
  /// bound allows) and the setpoint overshoot its weight b allows.
  double robustness_ms = kMigoDefaultMs;
  /// migo: 0, or a phase margin (deg, in [kMigoMinPhaseMarginDeg,
  /// kMigoMaxPhaseMarginDeg]) the design keeps instead of robustness_ms
  /// (MigoMsForPhaseMargin: the largest Ms bound whose design keeps it).
  double robustness_phase_margin_deg = 0.0;
  double response_time_s = 0.0;
  double migo_max_overshoot_pct = 20.0;
  /// optimal: robustness_ms was given (a response time then moves along
  /// the front below it), not the plant's default (the front up to
  /// kFrontMaxMs).
  bool robustness_given = false;
  /// simc: the closed-loop time constant tau_c (s); 0: tau_c = theta.
  double tau_c_s = 0.0;
  /// Runs independent evaluations at the same time (e.g. one thread per LCM
  /// trio): the starts of multi-start Nelder-Mead, each generation of GA and
  /// PSO-GSA. Empty: one after the other. The result is the same bits either
  /// way.
  optim::ParallelFor parallel_for;

  /// Valid bounds, budgets, constraints and loop, and at most kMaxTuneSteps
  /// loop steps over EvaluationBudget().
  bool IsValid(std::string* error) const;
  /// The search's evaluation budget: max_evaluations, else the method's
  /// default (5000; multi-start 20000); 1 for ziegler-nichols, simc and
  /// amigo, which evaluate their rule once.
  int EvaluationBudget() const;
  /// starts, or the method's default when 0.
  int StartCount() const;
};

/// The `--robust` preset (docs/robustness.md, "The robust preset"): gains an
/// engineer would deploy rather than the paper's optimum.
struct RobustPreset {
  /// ||S||inf <= 1.6 (about 45 deg of phase margin and a gain margin >= 2.7).
  static constexpr double kMaxMs = 1.6;
  /// Derivative filter Tf = kd / (N kp) with N = 10: a finite noise gain
  /// ||C S||inf, at most about kp (1 + N) at high frequency.
  static constexpr double kFilterRatio = 10.0;
  /// Objective setpoint-load with W = 1: the IAE of the reference step plus
  /// the IAE of a unit step at the plant input.
  static constexpr double kLoadWeight = 1.0;
  /// No closed-loop time constant beyond a tenth of the horizon (2.5 s of
  /// the paper's 25 s): no slow pole left behind by a near cancellation.
  static constexpr double kTimeConstantFraction = 0.1;
};
/// What ApplyRobustPreset leaves as the caller set it (the CLI: the flags
/// given explicitly next to --robust).
struct RobustPresetKeep {
  bool objective = false;
  bool load_weight = false;
  bool derivative_filter = false;
  bool max_ms = false;
  bool max_time_constant = false;
};
/// Sets *o to the robust preset: objective setpoint-load (W = 1), derivative
/// filter ratio N = 10, Ms <= 1.6 and slowest time constant <= 0.1 x the
/// loop's horizon, except the fields `keep` names.
void ApplyRobustPreset(TuneOptions* o, const RobustPresetKeep& keep = RobustPresetKeep{});

/// How Ceres's solver ended (its ceres::TerminationType), or kNotRun.
enum class RefineTermination {
  kNotRun,         // "": the cross-check did not run
  kConvergence,    // "CONVERGENCE": a function, gradient or parameter tolerance was met
  kNoConvergence,  // "NO_CONVERGENCE": the iteration budget ran out first
  kFailure,        // "FAILURE": the solver stopped on an error; the start point is kept
  kUserSuccess,    // "USER_SUCCESS": stopped by an iteration callback (pidlab sets none)
  kUserFailure,    // "USER_FAILURE": stopped by an iteration callback (pidlab sets none)
};
/// The text in the quotes above (Ceres's own names; "" for kNotRun).
std::string ToString(RefineTermination termination);

/// What the cross-check concluded, after re-evaluating Ceres's point with the
/// exact objective f (f_search: the search result's objective).
enum class RefineVerdict {
  /// "not run": --refine none, ziegler-nichols, simc, amigo (never refined), the
  /// iae-continuous, load-iae and setpoint-load objectives (no least-squares
  /// form in pidlab), or no stable
  /// loop to start from; RefineSummary::message says which of the last two.
  kNotRun,
  /// "agree": |f - f_search| <= agree_tolerance * f_search; Ceres's gains are
  /// returned only if f < f_search.
  kAgree,
  /// "<method> stopped short" (e.g. "nelder-mead stopped short"):
  /// f < (1 - agree_tolerance) f_search; Ceres's gains are returned.
  kSearchStoppedShort,
  /// "search better": f > (1 + agree_tolerance) f_search, or f is not finite
  /// (Ceres's smooth optimum is worse on the exact objective); the search
  /// result stands.
  kSearchBetter,
};
/// The text of `verdict` for a search by `method`, as in the quotes above
/// (the JSON "verdict" key, `pidlab tune` and the report print it).
std::string ToString(RefineVerdict verdict, TuneMethod method);

/// The Ceres cross-check: starting from the search result, a bound-constrained
/// least-squares problem whose minimum is the same objective, with derivatives
/// by automatic differentiation through the templated loop.
struct RefineSummary {
  bool ran = false;
  /// The better of the start and Ceres's point by the verdict: Ceres's for
  /// kSearchStoppedShort (and kAgree when lower), else the start. The
  /// objective is the exact one, not the smoothed least-squares cost.
  PidGains gains;
  double objective = std::numeric_limits<double>::infinity();
  RefineTermination termination = RefineTermination::kNotRun;
  int iterations = 0;
  RefineVerdict verdict = RefineVerdict::kNotRun;
  /// (f_search - f_ceres) / f_search, f_ceres the exact objective of Ceres's
  /// point (0 when not run).
  double relative_improvement = 0.0;
  /// One line on the verdict, or why the cross-check did not run ("" when it
  /// was not asked for).
  std::string message;
  /// The start the returned run began from (several starts: 0 = the search
  /// result, k = the k-th other polished minimum).
  int start_index = 0;
  /// Ceres runs made (several starts).
  int runs = 0;
};

struct TuneSummary {
  TuneMethod method = TuneMethod::kNelderMead;
  /// Best gains found (the Ceres gains if it found better), and their objective.
  PidGains gains;
  double objective = std::numeric_limits<double>::infinity();
  /// The search method's own result before the cross-check.
  PidGains search_gains;
  double search_objective = std::numeric_limits<double>::infinity();
  /// A strictly stable loop was found (false: every candidate was rejected,
  /// the gains stay 0 and message says why).
  bool stable = false;
  int evaluations = 0;
  int iterations = 0;
  double wall_time_s = 0.0;
  /// The search's summary; for ziegler-nichols the rule's gains as one
  /// converged evaluation.
  optim::OptimizerSummary optimizer;
  /// multi-start: the polished starts, best first.
  std::vector<optim::LocalMinimum> local_minima;
  ZieglerNicholsResult ziegler_nichols;  // ziegler-nichols only
  TuningRuleResult tuning_rule;          // simc and amigo only: the model and the rule's controller
  MigoDesign migo;                       // migo only: the design's peaks and crossover
  DesignSummary design;                  // optimal only: the engine's design and its bounds
  RefineSummary refine;
  /// With a robust set (TuneOptions::robust_samples > 0): its size (nominal
  /// plus the valid draws), the draws whose parameters gave no valid plant
  /// (left out), and the nominal plant's objective at the gains found
  /// (`objective` is then the quantile).
  int robust_set_size = 0;
  int robust_invalid_draws = 0;
  /// A model's draws redrawn because they were not a model's, and what the
  /// draws perturb (analysis::PerturbedText; with a robust set only).
  int robust_redrawn = 0;
  std::string robust_perturbed;
  double nominal_objective = std::numeric_limits<double>::infinity();
  /// The bounds of the box the gains found lie on (GainsAtBounds: "kp_lo",
  /// "kp_hi", "ki_lo", ..., within 1e-6 of the box's width): an optimum on
  /// an edge the box may have cut short. Empty for a rule (no box) and when
  /// no stable loop was found.
  std::vector<std::string> at_bounds;
  /// TuneOptions::two_dof: the setpoint weights found and both responses.
  TwoDofSummary two_dof;
  /// The search's one-line summary, or why no strictly stable loop was found.
  std::string message;
  /// One line: method, gains, objective, evaluations and the refine verdict.
  std::string BriefReport() const;
};

/// Tunes the PID for `plant`. kInvalidInput naming the cause for invalid
/// input or when the method does not apply (e.g. Ziegler-Nichols on 1/s^2,
/// SIMC on 1/(s^2+1), or simc and amigo on a plant with a dead time, which the
/// loops do not simulate yet: ApplyTuningRule gives its gains); Ok otherwise,
/// with summary->stable false if no strictly stable loop was found.
/// `runner` evaluates the sampled loop (episodes over the LCM trio); null: in process.
Status Tune(const Plant& plant, const TuneOptions& options, TuneSummary* summary,
            const optim::ProgressCallback& progress = nullptr,
            const evaluation::SampledRunner& runner = nullptr);

/// The Ceres cross-check alone, from `start` (used by Tune).
RefineSummary RefineWithCeres(const Plant& plant, const TuneOptions& options, const PidGains& start,
                              double start_objective);

/// The cross-check from several starts (multi-start: the search result first,
/// then other polished minima): Ceres from each, the best exact objective
/// judged against starts[0]'s objective as RefineWithCeres would. Its
/// start_index says which start it came from.
RefineSummary RefineWithCeres(const Plant& plant, const TuneOptions& options,
                              const std::vector<PidGains>& starts,
                              const std::vector<double>& start_objectives);

}  // namespace pidlab::tune
