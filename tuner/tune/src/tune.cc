#include "pidlab/tune/tune.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "pidlab/optim/genetic_algorithm.h"
#include "pidlab/optim/multi_start.h"
#include "pidlab/optim/nelder_mead.h"
#include "pidlab/optim/paper_nelder_mead.h"
#include "pidlab/optim/pso_gsa.h"
#include "pidlab/spec/field.h"
#include "pidlab/tune/search_box.h"
#include "rejections.h"

namespace pidlab::tune {

namespace {

// The seed and the budgets of TuneOptions (0 = the method's default) applied
// to one optimiser's options.
template <typename Options>
Options WithBudget(Options o, const TuneOptions& t, int Options::*iterations) {
  o.seed = t.seed;
  if (t.max_iterations > 0) o.*iterations = t.max_iterations;
  if (t.max_evaluations > 0) o.max_evaluations = t.max_evaluations;
  return o;
}

// The function the search minimises: the evaluator's objective, or +inf
// where the undisturbed step response breaks the overshoot or settling
// constraint of `options`.
// True if the loop of `g` meets options.bounds (cheap check, see TuneOptions).
bool MeetsBounds(const Plant& plant, const StateSpace& realization, const TuneOptions& options,
                 const PidGains& typed) {
  if (!options.bounds.Any()) return true;
  const PidGains g = evaluation::LoopGains(typed, options.loop);
  // With dead time the continuous loop's bounds come from the frequency-domain
  // analysis (e^(-jwL) exact, the Nyquist count), as the sampled loop's.
  if (options.loop.loop == evaluation::LoopKind::kContinuous && plant.delay_s == 0.0) {
    evaluation::ContinuousClosedLoop<double> loop;
    if (!evaluation::BuildContinuousClosedLoop<double>(realization, g, Disturbance(DisturbanceOptions{}),
                                                       &loop)
             .ok())
      return false;
    return analysis::ContinuousLoopMeetsBounds(
        plant.tf, g, evaluation::ContinuousStability(loop, options.loop.stability_margin), options.bounds);
  }
  analysis::LoopAnalysisOptions coarse;
  coarse.points_per_decade = 20.0;
  analysis::LoopBounds bounds = options.bounds;
  // (The delay-free continuous loop returned above.)
  const bool delayed_continuous = options.loop.loop == evaluation::LoopKind::kContinuous;
  // With dead time, the time constant's bound is one count on its line: no
  // closed-loop root right of Re s = -1/max_time_constant (not the bisection
  // of the spectral abscissa the full analysis runs).
  if (delayed_continuous) {
    coarse.delayed_time_constant = false;
    bounds.max_time_constant_s = std::numeric_limits<double>::infinity();
  }
  analysis::LoopAnalysis a;
  if (!analysis::AnalyzeLoop(plant, g, options.loop, coarse, &a).ok() ||
      !analysis::LoopBoundsViolation(a, bounds).empty())
    return false;
  if (!delayed_continuous || !std::isfinite(options.bounds.max_time_constant_s)) return true;
  evaluation::NyquistCount n;
  return evaluation::CountContinuousRootsRightOf(plant.tf, g, plant.delay_s,
                                                 -1.0 / options.bounds.max_time_constant_s,
                                                 coarse.points_per_decade, &n)
             .ok() &&
         n.decided && n.closed_loop_rhp_poles == 0;
}

optim::ObjectiveFunction ConstrainedObjective(const Plant& plant, const TuneOptions& options,
                                              const evaluation::ObjectiveEvaluator& evaluator) {
  const bool constrained =
      std::isfinite(options.max_overshoot_pct) || std::isfinite(options.max_settling_time_s);
  auto realization = std::make_shared<StateSpace>(Realize(plant.tf));
  // The continuous loop with dead time is simulated by the method of steps,
  // which costs far more than the bounds' frequency-domain check (a stiff
  // candidate: hundreds of ms): check the bounds first there. The value is the
  // same either way (+inf when either rejects).
  const bool bounds_first = options.loop.loop == evaluation::LoopKind::kContinuous && plant.delay_s > 0.0;
  return [&plant, &options, &evaluator, constrained, realization, bounds_first](const Eigen::VectorXd& x) {
    const PidGains g{x(0), x(1), x(2)};
    if (bounds_first && !MeetsBounds(plant, *realization, options, g)) return HUGE_VAL;
    const double value = evaluator(g);
    if (!std::isfinite(value)) return value;
    if (!bounds_first && !MeetsBounds(plant, *realization, options, g)) return HUGE_VAL;
    if (!constrained) return value;
    evaluation::LoopOptions undisturbed = options.loop;
    undisturbed.disturbance = DisturbanceOptions{};
    evaluation::Evaluation ev;
    evaluation::EvaluateOptions what;
    what.compute_iae_continuous = false;
    if (!evaluation::Evaluate(plant, g, undisturbed, what, &ev).ok() || !ev.step.valid) return HUGE_VAL;
    if (ev.step.overshoot_pct > options.max_overshoot_pct) return HUGE_VAL;
    if (ev.step.settling_time_s > options.max_settling_time_s) return HUGE_VAL;
    return value;
  };
}

// The plants of the robust set and their evaluators (one per valid draw).
struct RobustSet {
  std::vector<std::unique_ptr<const evaluation::ObjectiveEvaluator>> draws;
  int invalid = 0;
  int redrawn = 0;
};

RobustSet MakeRobustSet(const Plant& plant, const TuneOptions& options,
                        const evaluation::SampledRunner& runner) {
  RobustSet set;
  if (options.robust_samples == 0) return set;
  analysis::MonteCarloOptions mc;
  mc.samples = options.robust_samples;
  mc.spread = options.robust_spread;
  mc.seed = options.seed;
  for (const Plant& p : analysis::DrawPlants(
           plant, plant.name == "stepper_motor" ? &options.stepper : nullptr, mc, &set.redrawn)) {
    if (p.tf.num.empty() || p.tf.den.empty()) {
      ++set.invalid;
      continue;
    }
    set.draws.push_back(std::make_unique<const evaluation::ObjectiveEvaluator>(
        p, options.loop, options.objective, runner, options.load_weight));
  }
  return set;
}

// The nearest-rank `quantile` of the objective over the nominal plant (with
// the constraints of f) and the draws of `set`: +inf when the nominal loop is
// rejected, and a draw that is not strictly stable counts as +inf.
optim::ObjectiveFunction RobustSetObjective(const optim::ObjectiveFunction& nominal, const RobustSet& set,
                                            double quantile) {
  if (set.draws.empty()) return nominal;
  return [nominal, &set, quantile](const Eigen::VectorXd& x) {
    const double f0 = nominal(x);
    if (!std::isfinite(f0)) return f0;
    std::vector<double> values{f0};
    values.reserve(set.draws.size() + 1);
    const PidGains g{x(0), x(1), x(2)};
    for (const auto& e : set.draws) values.push_back((*e)(g));
    const std::size_t rank = static_cast<std::size_t>(
        std::max(1.0, std::ceil(quantile * static_cast<double>(values.size()) - 1e-9)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank - 1), values.end());
    return values[rank - 1];
  };
}

// A rule's gains as the search's result: one converged evaluation.
void RuleResult(const PidGains& g, const evaluation::ObjectiveEvaluator& evaluator,
                const std::string& message, optim::OptimizerSummary* opt) {
  opt->x = Eigen::Vector3d(g.kp, g.ki, g.kd);
  opt->f = evaluator(g);
  opt->evaluations = 1;
  opt->termination = optim::TerminationType::kConverged;
  opt->message = message;
}

// SIMC or AMIGO into summary->tuning_rule and summary->optimizer. False with
// *error where the rule does not apply. A plant's dead time is simulated in
// both loops (the sampled loop's stored inputs, the continuous loop's method
// of steps), so delay_simulated is true on either.
bool RuleSearch(const Plant& plant, const TuneOptions& options,
                const evaluation::ObjectiveEvaluator& evaluator, TuneSummary* summary, std::string* error) {
  const TuningRule rule = options.method == TuneMethod::kSimc ? TuningRule::kSimc : TuningRule::kAmigo;
  const Status status = ApplyTuningRule(plant, rule, options.rule, &summary->tuning_rule, options.tau_c_s);
  if (!status.ok()) {
    if (error) *error = status.message();
    return false;
  }
  RuleResult(summary->tuning_rule.gains, evaluator, summary->tuning_rule.message, &summary->optimizer);
  return true;
}

// The MIGO design (migo.h) into summary->migo, ->two_dof and ->optimizer.
bool MigoSearch(const Plant& plant, const TuneOptions& options,
                const evaluation::ObjectiveEvaluator& evaluator, TuneSummary* summary, std::string* error) {
  MigoOptions o{
      options.robustness_ms, options.rule == RuleForm::kPi, options.response_time_s,
      options.migo_max_overshoot_pct,
      options.loop.derivative_filter_ratio > 0.0 ? options.loop.derivative_filter_ratio : kMigoFilterRatio};
  Status status = options.robustness_phase_margin_deg > 0.0
                      ? MigoMsForPhaseMargin(plant, options.robustness_phase_margin_deg, &o)
                      : Status::Ok();
  if (status.ok()) status = DesignMigoForSetpoint(plant, options.loop, o, &summary->migo, &summary->two_dof);
  if (!status.ok() && error) *error = status.message();
  if (status.ok()) RuleResult(summary->migo.gains, evaluator, summary->migo.message, &summary->optimizer);
  return status.ok();
}

// The design engine (design.h) into summary->design, ->two_dof (its
// setpoint weights) and ->optimizer. --robustness is the Ms bound (or a
// phase margin: the largest Ms bound whose design keeps it), --max-mt and
// --max-noise-gain bound Mt and C S, --response-time T the crossover 2 / T
// on the front, --max-overshoot the setpoint stage's target (default 10 %).
bool OptimalSearch(const Plant& plant, const TuneOptions& options,
                   const evaluation::ObjectiveEvaluator& evaluator, TuneSummary* summary,
                   std::string* error) {
  DesignOptions o;
  o.loop = options.loop;
  o.max_ms = options.robustness_ms;
  if (std::isfinite(options.bounds.max_mt)) o.max_mt = options.bounds.max_mt;
  o.max_noise_gain = options.bounds.max_noise_gain;
  o.pi = options.rule == RuleForm::kPi;
  o.crossover_rad_s = options.response_time_s > 0.0 ? 2.0 / options.response_time_s : 0.0;
  if (o.crossover_rad_s > 0.0 && !options.robustness_given) o.max_ms = kFrontMaxMs;
  o.max_overshoot_pct =
      std::isfinite(options.max_overshoot_pct) ? options.max_overshoot_pct : kDesignDefaultOvershootPct;
  Status status = options.robustness_phase_margin_deg > 0.0
                      ? DesignMsForPhaseMargin(plant, options.robustness_phase_margin_deg, &o)
                      : Status::Ok();
  // Along a knob the setpoint stage keeps to the front's faster overshoot
  // (after the phase margin's bisection, which designs without it).
  o.monotone_front = options.robustness_given || o.crossover_rad_s > 0.0;
  if (status.ok()) status = DesignOptimal(plant, o, &summary->design);
  if (!status.ok()) {
    if (error) *error = status.message();
    return false;
  }
  const DesignSummary& d = summary->design;
  TwoDofSummary& two = summary->two_dof;
  two.ran = true;
  two.b = d.b;
  two.c = d.c;
  two.setpoint_filter_s = d.setpoint_filter_s;
  two.termination = optim::TerminationType::kConverged;
  two.message =
      d.setpoint_note.empty()
          ? "the setpoint overshoot " + spec::FormatNumber(d.overshoot_pct) +
                " % <= " + spec::FormatNumber(d.overshoot_target_pct) +
                " %, the least setpoint integral |e| dt" +
                (d.setpoint_filter_s > 0.0 ? " (with a setpoint filter: no weights b, c reach it alone)" : "")
          : d.setpoint_note;
  if (!d.overshoot_cap_note.empty()) two.message += "; " + d.overshoot_cap_note;
  RuleResult(d.gains, evaluator, d.message, &summary->optimizer);
  return true;
}

// Runs options.method on f over the gain box into summary->optimizer
// (Ziegler-Nichols, SIMC, AMIGO: the rule's gains, evaluated once). False
// with *error if the rule does not apply.
bool Search(const Plant& plant, const TuneOptions& options, const optim::ObjectiveFunction& f,
            const evaluation::ObjectiveEvaluator& evaluator, const optim::ProgressCallback& progress,
            TuneSummary* summary, std::string* error) {
  optim::Bounds bounds{Eigen::VectorXd::Constant(3, options.lower),
                       Eigen::VectorXd::Constant(3, options.upper)};
  optim::OptimizerSummary& opt = summary->optimizer;
  switch (options.method) {
    case TuneMethod::kMultiStart: {
      optim::MultiStartOptions o;
      o.seed = options.seed;
      o.max_evaluations = options.EvaluationBudget();
      o.design_points = options.max_evaluations > 0
                            ? std::max(1, std::min(options.design_points, o.max_evaluations / 2))
                            : options.design_points;
      o.starts = options.StartCount();
      o.warp = kGainWarp;
      o.min_separation = kMultiStartSeparation;
      if (options.max_iterations > 0) o.polish.max_iterations = options.max_iterations;
      o.polish.adaptive = options.adaptive;
      o.parallel_for = options.parallel_for;
      optim::MultiStart(f, bounds, o, &opt, progress, &summary->local_minima);
      break;
    }
    case TuneMethod::kNelderMead: {
      optim::NelderMeadOptions o =
          WithBudget(optim::NelderMeadOptions{}, options, &optim::NelderMeadOptions::max_iterations);
      o.starts = options.StartCount();
      if (options.start.size() == 3)
        o.x0 = Eigen::Vector3d(options.start[0], options.start[1], options.start[2]);
      o.adaptive = options.adaptive;
      o.parallel_for = options.parallel_for;
      optim::NelderMead(f, bounds, o, &opt, progress);
      break;
    }
    case TuneMethod::kPaperNelderMead: {
      optim::PaperNelderMeadOptions o = WithBudget(optim::PaperNelderMeadOptions{}, options,
                                                   &optim::PaperNelderMeadOptions::max_iterations);
      o.starts = options.StartCount();
      optim::PaperNelderMead(f, bounds, o, &opt, progress);
      break;
    }
    case TuneMethod::kGeneticAlgorithm: {
      optim::GeneticAlgorithmOptions o = WithBudget(optim::GeneticAlgorithmOptions{}, options,
                                                    &optim::GeneticAlgorithmOptions::max_generations);
      o.parallel_for = options.parallel_for;
      optim::GeneticAlgorithm(f, bounds, o, &opt, progress);
      break;
    }
    case TuneMethod::kPsoGsa: {
      optim::PsoGsaOptions o =
          WithBudget(optim::PsoGsaOptions{}, options, &optim::PsoGsaOptions::max_iterations);
      o.parallel_for = options.parallel_for;
      optim::PsoGsa(f, bounds, o, &opt, progress);
      break;
    }
    case TuneMethod::kZieglerNichols: {
      if (const Status st = ZieglerNicholsTune(plant.tf, options.zn_rule, &summary->ziegler_nichols);
          !st.ok()) {
        if (error) *error = st.message();
        return false;
      }
      RuleResult(summary->ziegler_nichols.gains, evaluator, summary->ziegler_nichols.message, &opt);
      break;
    }
    case TuneMethod::kSimc:
    case TuneMethod::kAmigo:
      return RuleSearch(plant, options, evaluator, summary, error);
    case TuneMethod::kMigo:
      return MigoSearch(plant, options, evaluator, summary, error);
    case TuneMethod::kOptimal:
      return OptimalSearch(plant, options, evaluator, summary, error);
  }
  return true;
}

// Adds the polished minima that differ from every start so far (by more than
// 1e-4 of the box width in some gain), best first, up to refine_starts starts.
void AddDistinctMinima(const TuneOptions& options, const std::vector<optim::LocalMinimum>& minima,
                       std::vector<PidGains>* starts, std::vector<double>* objectives) {
  const double tolerance = 1e-4 * (options.upper - options.lower);
  for (const optim::LocalMinimum& m : minima) {
    if (static_cast<int>(starts->size()) >= options.refine_starts) break;
    if (m.x.size() != 3 || !std::isfinite(m.f)) continue;
    const PidGains g{m.x(0), m.x(1), m.x(2)};
    const bool distinct = std::all_of(starts->begin(), starts->end(), [&](const PidGains& s) {
      return std::max({std::abs(s.kp - g.kp), std::abs(s.ki - g.ki), std::abs(s.kd - g.kd)}) > tolerance;
    });
    if (!distinct) continue;
    starts->push_back(g);
    objectives->push_back(m.f);
  }
}

// Ceres from the search's result into summary->refine, its gains and
// objective kept when better (and, for one start, feasible for f).
void RefineSearchResult(const Plant& plant, const TuneOptions& options, const optim::ObjectiveFunction& f,
                        TuneSummary* summary) {
  // Ceres differentiates the linear loops only; a nonlinear plant keeps the
  // search's result (refine "not run"), and so does a robust set.
  if (options.refine && options.robust_samples > 0) {
    summary->refine.message = "not run: the robust set's quantile has no least-squares form";
  } else if (options.refine && options.method == TuneMethod::kMultiStart && !plant.nonlinear) {
    std::vector<PidGains> starts{summary->search_gains};
    std::vector<double> objectives{summary->search_objective};
    AddDistinctMinima(options, summary->local_minima, &starts, &objectives);
    summary->refine = RefineWithCeres(plant, options, starts, objectives);
    if (summary->refine.objective < summary->objective) {
      summary->gains = summary->refine.gains;
      summary->objective = summary->refine.objective;
    }
  } else if (options.refine && !IsTuningRule(options.method) && !plant.nonlinear) {
    summary->refine = RefineWithCeres(plant, options, summary->search_gains, summary->search_objective);
    const PidGains& r = summary->refine.gains;
    // Ceres knows no constraint: its point is kept only if it meets them all.
    const bool better = summary->refine.objective < summary->objective;
    const bool feasible = better && std::isfinite(f(Eigen::Vector3d(r.kp, r.ki, r.kd)));
    if (better && !feasible)
      summary->refine.message += "; its gains break a constraint of the tuning, the search result stands";
    if (feasible) {
      summary->gains = summary->refine.gains;
      summary->objective = summary->refine.objective;
    }
  }
}

// A rule's PID with an ideal derivative on a plant of relative degree 1 with
// a dead time is a neutral continuous loop (delayed_loop.h): refused up front
// rather than scored +inf.
bool RuleLoopIsRetarded(const Plant& plant, const TuneOptions& options, std::string* error) {
  const bool rule = options.method == TuneMethod::kSimc || options.method == TuneMethod::kAmigo;
  if (!rule || options.rule != RuleForm::kPid || options.loop.loop != evaluation::LoopKind::kContinuous ||
      !(plant.delay_s > 0.0) || plant.tf.RelativeDegree() != 1 ||
      options.loop.derivative_filter_ratio > 0.0 || options.loop.pid.derivative_filter_s > 0.0)
    return true;
  if (error)
    *error =
        "--rule pid's ideal derivative on a plant of relative degree 1 with a dead time makes the "
        "continuous loop of neutral type: give a derivative filter (--derivative-filter or "
        "--derivative-filter-ratio)";
  return false;
}

// What Tune() refuses before any work, in this order: bad options, a dead
// time a method or a robust set does not take, a load objective off the
// process or on a nonlinear plant, a robust set of a nonlinear plant.
bool TuneApplies(const Plant& plant, const TuneOptions& options, bool custom_runner, std::string* error) {
  if (!options.IsValid(error)) return false;
  if (const Status st = evaluation::DelayIsValid(plant, options.loop, "delay"); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  if (plant.delay_s > 0.0 && options.method == TuneMethod::kZieglerNichols) {
    if (error)
      *error =
          "ziegler-nichols with a plant dead time is not supported yet (its rules read the "
          "undelayed plant): use another method";
    return false;
  }
  if (!RuleLoopIsRetarded(plant, options, error)) return false;
  // A model's draws carry their dead time (DrawPlants); others' are undelayed.
  if (plant.delay_s > 0.0 && options.robust_samples > 0 && !plant.model) {
    if (error) *error = "a robust set with a plant dead time is not supported yet (its draws are undelayed)";
    return false;
  }
  const bool load = options.objective == evaluation::ObjectiveKind::kLoadIae ||
                    options.objective == evaluation::ObjectiveKind::kSetpointLoad;
  if (load && custom_runner) {
    if (error) *error = ToString(options.objective) + " is evaluated in process: use --backend local";
    return false;
  }
  if (load && plant.nonlinear) {
    if (error)
      *error = ToString(options.objective) + " needs a linear plant (the load response of " + plant.name +
               " is not computed): tune the linearisation (--plant stepper) or use --objective iae";
    return false;
  }
  if (options.robust_samples > 0 && plant.nonlinear) {
    if (error) *error = "a robust set draws linear plants: it does not take plant " + plant.name;
    return false;
  }
  return true;
}

}  // namespace

namespace {

// Tune() with the refusal's message in *error.
bool TuneOrExplain(const Plant& plant, const TuneOptions& options, TuneSummary* summary, std::string* error,
                   const optim::ProgressCallback& progress, const evaluation::SampledRunner& runner) {
  const auto start_time = std::chrono::steady_clock::now();
  *summary = TuneSummary();
  summary->method = options.method;
  // No runner: the evaluator runs the sampled loop itself; another runner
  // (the LCM trio) is handed to it.
  const bool custom_runner = options.loop.loop == evaluation::LoopKind::kSampled && runner != nullptr;
  if (!TuneApplies(plant, options, custom_runner, error)) return false;
  const evaluation::ObjectiveEvaluator evaluator(plant, options.loop, options.objective,
                                                 custom_runner ? runner : evaluation::SampledRunner(nullptr),
                                                 options.load_weight);
  const RobustSet robust_set =
      MakeRobustSet(plant, options, custom_runner ? runner : evaluation::SampledRunner(nullptr));
  summary->robust_set_size = options.robust_samples > 0 ? static_cast<int>(robust_set.draws.size()) + 1 : 0;
  summary->robust_invalid_draws = robust_set.invalid;
  summary->robust_redrawn = robust_set.redrawn;
  if (options.robust_samples > 0) summary->robust_perturbed = analysis::PerturbedText(plant, nullptr);
  const optim::ObjectiveFunction f = RobustSetObjective(ConstrainedObjective(plant, options, evaluator),
                                                        robust_set, options.robust_quantile);
  if (!Search(plant, options, f, evaluator, progress, summary, error)) return false;
  const optim::OptimizerSummary& opt = summary->optimizer;
  summary->evaluations = opt.evaluations;
  summary->iterations = opt.iterations;
  if (opt.termination == optim::TerminationType::kInvalidOptions) {
    if (error) *error = opt.message;
    return false;
  }
  if (!opt.IsUsable()) {
    summary->message = "no strictly stable loop found in the box: " + opt.message +
                       ExplainRejections(plant, options, evaluator);
    summary->wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return true;
  }
  summary->search_gains = {opt.x(0), opt.x(1), opt.x(2)};
  // The engine designs its own derivative filter.
  if (options.method == TuneMethod::kOptimal) summary->search_gains.tf = summary->design.gains.tf;
  summary->search_objective = opt.f;
  summary->gains = summary->search_gains;
  summary->objective = summary->search_objective;
  summary->stable = true;
  summary->message = opt.message;
  RefineSearchResult(plant, options, f, summary);
  if (options.robust_samples > 0) summary->nominal_objective = evaluator(summary->gains);
  // The loop's derivative filter of the gains found (tf = 0 for the ideal PID).
  summary->gains = evaluation::LoopGains(summary->gains, options.loop);
  summary->search_gains = evaluation::LoopGains(summary->search_gains, options.loop);
  summary->refine.gains = evaluation::LoopGains(summary->refine.gains, options.loop);
  if (!IsTuningRule(options.method))
    summary->at_bounds = GainsAtBounds(summary->gains, options.lower, options.upper);
  if (options.two_dof) {
    if (const Status st = TuneSetpointWeights(plant, summary->gains, options.loop, &summary->two_dof);
        !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
  }
  summary->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return true;
}

}  // namespace

Status Tune(const Plant& plant, const TuneOptions& options, TuneSummary* summary,
            const optim::ProgressCallback& progress, const evaluation::SampledRunner& runner) {
  std::string error;
  try {
    if (!TuneOrExplain(plant, options, summary, &error, progress, runner)) return Status::InvalidInput(error);
  } catch (const evaluation::RunnerFailure& e) {
    // The trio failed under the search (the episode client already ran the
    // episode again as often as it may): a Status, not an exception.
    return Status::RunnerFailed(e.what());
  }
  return Status::Ok();
}

}  // namespace pidlab::tune
