// pidlab tune: a multi-start from a space-filling design (or Nelder-Mead, the
// paper's variant, a baseline) on the paper's objective, with a Ceres
// least-squares cross-check.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/tuner/episode_client.h"
#include "pidlab/tuner/tune.h"

namespace pidlab::cli {
namespace {

struct TuneCommand {
  PlantFlags plant;
  LoopFlags loop;
  std::string method = "multi-start", objective = "iae", backend = "local", bounds = "0,30";
  std::string refine = "ceres", trace, zn_rule = "classic";
  int max_iterations = 0, max_evaluations = 0, starts = 0, design_points = kMultiStartDesignPoints,
      refine_starts = 2;
  double max_overshoot_pct = HUGE_VAL, max_settling_time_s = HUGE_VAL, agree_tolerance = 1e-3,
         load_weight = 1.0;
  bool json = false, adaptive = false, robust = false;
  int robust_samples = 0;
  double robust_quantile = 1.0;
  std::string robust_spread = "10%";
  BoundsFlags loop_bounds;
  LcmFlags lcm;
  std::unique_ptr<EpisodePool> pool;
  CLI::App* app_ = nullptr;

  // The tuner's acceptance margin: with the evaluation's 1e-9 the search games
  // the sampled objective by parking poles a hair left of the imaginary axis
  // (e.g. -1e-9 +/- 1j on 1/(s^2+1), nearly cancelled by the PID zeros). 0.01
  // asks every pole for Re p <= -0.01 max(1, |p|): damping ratio >= 0.01, or a
  // decay rate >= 0.01 1/s for poles slower than 1 rad/s. See docs/tuning.md.
  TuneCommand() { loop.stability_margin = 0.01; }

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Tune PID gains on the paper's objective (IAE of the unit-step response, eq. 4) by a multi-start "
        "from a space-filling design (default), Nelder-Mead or a baseline, rejecting every loop that is not "
        "strictly stable, then cross-check with Ceres.");
    plant.Register(app);
    loop.Register(app);
    app->add_option("--method", method,
                    "multi-start (Sobol' design + Nelder-Mead polish) | nelder-mead | paper-nm | "
                    "ziegler-nichols | ga | pso-gsa")
        ->capture_default_str();
    app->add_option("--objective", objective,
                    "iae | ise | itae | iae-continuous | load-iae (IAE of a unit step at the plant input, "
                    "r = 0) | setpoint-load (iae + W load-iae)")
        ->capture_default_str();
    app->add_option("--load-weight", load_weight, "W of --objective setpoint-load (>= 0)")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--backend", backend, "local (in-process) or lcm (episodes over a running trio)")
        ->capture_default_str();
    app->add_option("--bounds", bounds, "gain box LO,HI for each of kp, ki, kd")->capture_default_str();
    app->add_option("--max-iter", max_iterations, "iteration budget (0 = method default; paper-nm: 100)")
        ->capture_default_str();
    app->add_option("--max-evals", max_evaluations, "evaluation budget over all starts (0 = method default)")
        ->capture_default_str();
    app->add_option("--starts", starts,
                    "seeded starts (nelder-mead, paper-nm; 0 = 4) or polished starts (multi-start; 0 = 16)")
        ->capture_default_str();
    app->add_option("--design-points", design_points,
                    "multi-start: Sobol' points of the design (at most half of --max-evals when given)")
        ->capture_default_str();
    app->add_option("--refine-starts", refine_starts,
                    "multi-start: Ceres from this many distinct polished minima, best first")
        ->capture_default_str();
    app->add_flag("--adaptive", adaptive, "nelder-mead, multi-start: Gao & Han's adaptive coefficients");
    app->add_option("--refine", refine, "ceres | none: the least-squares cross-check")->capture_default_str();
    app->add_option("--agree-tolerance", agree_tolerance,
                    "relative objective difference for the 'agree' verdict")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--max-overshoot", max_overshoot_pct, "reject candidates overshooting more (%)")
        ->check(NumberOrInfinity());
    app->add_option("--max-settling", max_settling_time_s, "reject candidates settling later (s)")
        ->check(NumberOrInfinity());
    loop_bounds.Register(app, "reject candidates");
    app->add_flag("--robust", robust,
                  "the robust preset (docs/robustness.md): --objective setpoint-load --load-weight 1 "
                  "--derivative-filter-ratio 10 --max-ms 1.6 --max-time-constant <horizon/10>; a flag given "
                  "explicitly overrides its part");
    app->add_option("--robust-samples", robust_samples,
                    "optimise over the nominal plant and N plants drawn as evaluate --monte-carlo draws them "
                    "(seeded by --seed): the --robust-quantile of the objective over the set")
        ->check(WholeNumber())
        ->capture_default_str();
    app->add_option("--robust-quantile", robust_quantile,
                    "quantile of the robust set's objective to minimise, (0, 1]; 1 = the worst case")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--robust-spread", robust_spread,
                    "relative spread of the robust set's draws, 10% or 0.1, in [0, 1)")
        ->capture_default_str();
    app->add_option("--zn-rule", zn_rule, "classic | pessen | some-overshoot | no-overshoot")
        ->capture_default_str();
    app->add_option("--trace", trace, "write the best-so-far trajectory of the search to this CSV file");
    app->add_flag("--json", json, "print one JSON object");
    lcm.Register(app);
    app_ = app;
    return [this] { return Run(); };
  }

  int Run() {
    const Plant p = plant.Build();
    TuneOptions o = BuildOptions();
    if (p.nonlinear && o.loop.loop != LoopKind::kSampled)
      throw BadInput("--plant " + p.name +
                     " is nonlinear: tune it on the sampled loop (--loop sampled --dt 1e-4)");
    CheckOutputFile(trace, "--trace");  // before the search, not after it
    const SampledRunner runner = MakeRunner(o);
    if (pool) o.parallel_for = pool->AsParallelFor();  // the starts on idle trios
    const bool tty = isatty(STDERR_FILENO) != 0;
    TuneSummary s;
    std::string error;
    if (!Tune(p, o, &s, &error, MakeProgress(tty), runner)) throw BadInput(error);
    if (tty) std::fprintf(stderr, "\r%70s\r", "");
    if (!trace.empty()) WriteTrace(s);
    Evaluation ev;
    LoopAnalysis analysis;
    if (s.stable) {
      EvaluateOptions what;
      Evaluate(p, s.gains, o.loop, what, &ev, &error);
      analysis = AnalyzeOrThrow(p, s.gains, o.loop);
    }
    if (json) {
      nlohmann::json j = json::TuneJson(p, o, s, ev, backend);
      j["robustness"] = s.stable ? RobustnessJson(analysis, o.bounds) : nlohmann::json(nullptr);
      std::cout << j.dump() << "\n";
    } else {
      PrintText(o, s, ev);
      if (s.stable) std::cout << FormatRobustness(analysis, o.bounds);
    }
    return s.stable ? 0 : 1;
  }

  // The tuning options of the flags; throws BadInput.
  TuneOptions BuildOptions() const {
    TuneOptions o;
    o.loop = loop.Build();
    if (!ParseTuneMethod(method, &o.method))
      throw BadInput("--method " + Quote(method) +
                     " must be multi-start, nelder-mead, paper-nm, ziegler-nichols, ga or pso-gsa");
    if (!ParseObjectiveKind(objective, &o.objective))
      throw BadInput("--objective " + Quote(objective) +
                     " must be iae, ise, itae, iae-continuous, load-iae or setpoint-load");
    if (!(load_weight >= 0.0))
      throw BadInput("--load-weight " + std::to_string(load_weight) + " must be >= 0");
    o.load_weight = load_weight;
    if (!ParseZieglerNicholsRule(zn_rule, &o.zn_rule))
      throw BadInput("--zn-rule " + Quote(zn_rule) +
                     " must be classic, pessen, some-overshoot or no-overshoot");
    const auto b = ParseList(bounds, "--bounds");
    if (b.size() != 2) throw BadInput("--bounds " + Quote(bounds) + " must be LO,HI");
    o.lower = b[0];
    o.upper = b[1];
    if (refine != "ceres" && refine != "none")
      throw BadInput("--refine " + Quote(refine) + " must be ceres or none");
    o.refine = refine == "ceres";
    o.max_iterations = max_iterations;
    o.max_evaluations = max_evaluations;
    o.starts = starts;
    o.design_points = design_points;
    o.refine_starts = refine_starts;
    o.adaptive = adaptive;
    o.seed = loop.seed;
    o.max_overshoot_pct = max_overshoot_pct;
    o.max_settling_time_s = max_settling_time_s;
    o.bounds = loop_bounds.Build();
    o.agree_tolerance = agree_tolerance;
    if (robust) {
      RobustPresetKeep keep;
      keep.objective = app_->count("--objective") > 0;
      keep.load_weight = app_->count("--load-weight") > 0;
      keep.derivative_filter =
          app_->count("--derivative-filter") > 0 || app_->count("--derivative-filter-ratio") > 0;
      keep.max_ms = app_->count("--max-ms") > 0;
      keep.max_time_constant = app_->count("--max-time-constant") > 0;
      ApplyRobustPreset(&o, keep);
    }
    if (robust_samples < 0 || robust_samples > 10000)
      throw BadInput("--robust-samples " + std::to_string(robust_samples) + " must be in [0, 10000]");
    o.robust_samples = robust_samples;
    o.robust_spread = ParseSpread(robust_spread, "--robust-spread");
    if (!(robust_quantile > 0.0) || !(robust_quantile <= 1.0))
      throw BadInput("--robust-quantile " + std::to_string(robust_quantile) + " must be in (0, 1]");
    o.robust_quantile = robust_quantile;
    o.stepper = plant.StepperParameters();
    std::string error;
    if (!o.IsValid(&error)) throw BadInput(error);
    return o;
  }

  // The sampled-loop runner of --backend; throws BadInput.
  SampledRunner MakeRunner(const TuneOptions& o) {
    if (backend == "local") return RunSampledLoopInProcess;
    if (backend != "lcm") throw BadInput("--backend " + Quote(backend) + " must be local or lcm");
    if (o.loop.loop != LoopKind::kSampled)
      throw BadInput("--backend lcm runs the sampled loop: add --loop sampled");
    pool = lcm.MakePool();
    return pool->AsRunner();
  }

  // Progress on a terminal, at most ten lines a second; silent otherwise.
  static ProgressCallback MakeProgress(bool tty) {
    auto last = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now() -
                                                                        std::chrono::seconds(1));
    return [tty, last](const TracePoint& tp) {
      if (!tty) return;
      const auto now = std::chrono::steady_clock::now();
      if (now - *last < std::chrono::milliseconds(100)) return;
      *last = now;
      std::fprintf(stderr, "\r  iteration %5d  evaluations %6d  best %.6g   ", tp.iteration, tp.evaluations,
                   tp.best_f);
      std::fflush(stderr);
    };
  }

  // The human-readable result; `ev` as for ToJson.
  static void PrintText(const TuneOptions& o, const TuneSummary& s, const Evaluation& ev) {
    std::cout << std::setprecision(6);
    std::cout << "method           " << ToString(o.method) << " on " << ToString(o.objective) << ", box ["
              << o.lower << ", " << o.upper << "]^3, seed " << o.seed << "\n";
    if (!s.stable) {
      std::cout << "result           " << s.message << "\n";
      return;
    }
    std::cout << "search           kp = " << s.search_gains.kp << ", ki = " << s.search_gains.ki
              << ", kd = " << s.search_gains.kd << "  objective " << s.search_objective << "  ("
              << s.evaluations << " evaluations, " << s.optimizer.rejected_evaluations << " rejected, "
              << ToString(s.optimizer.termination) << ")\n";
    if (s.refine.ran)
      std::cout << "ceres            kp = " << s.refine.gains.kp << ", ki = " << s.refine.gains.ki
                << ", kd = " << s.refine.gains.kd << "  objective " << s.refine.objective << "  ("
                << ToString(s.refine.termination) << ", " << s.refine.iterations << " iterations)\n";
    std::cout << "verdict          " << ToString(s.refine.verdict, s.method)
              << (s.refine.message.empty() ? "" : ": ") << s.refine.message << "\n";
    if (o.robust_samples > 0)
      std::cout << "robust set       " << s.robust_set_size << " plants (nominal + " << o.robust_samples
                << " draws at " << 100.0 * o.robust_spread << " % spread"
                << (s.robust_invalid_draws > 0
                        ? ", " + std::to_string(s.robust_invalid_draws) + " invalid left out"
                        : std::string())
                << "): objective = quantile " << o.robust_quantile << "; nominal plant's "
                << s.nominal_objective << "\n";
    std::cout << "wall time        " << s.wall_time_s << " s\n\n";
    std::cout << FormatEvaluation(ev);
  }

  void WriteTrace(const TuneSummary& s) const {
    std::ofstream f(trace);
    if (!f) throw BadInput("--trace " + Quote(trace) + " cannot be written");
    f << std::setprecision(17) << "iteration,evaluations,best_objective,kp,ki,kd\n";
    for (const auto& tp : s.optimizer.trace) {
      f << tp.iteration << "," << tp.evaluations << "," << tp.best_f;
      for (int i = 0; i < 3; ++i) f << "," << (tp.best_x.size() == 3 ? tp.best_x(i) : NAN);
      f << "\n";
    }
  }
};

}  // namespace
std::function<int()> RegisterTune(CLI::App* app) {
  auto command = std::make_shared<TuneCommand>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

}  // namespace pidlab::cli
