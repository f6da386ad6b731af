// pidlab tune: a multi-start from a space-filling design (or Nelder-Mead, the
// paper's variant, a baseline, a tuning rule) on the paper's objective, with a
// Ceres least-squares cross-check.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <set>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/episode_client/tune_progress.h"
#include "pidlab/results/tune_run.h"
#include "pidlab/tune/problem.h"

using pidlab::episode_client::EpisodePool;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::SampledRunner;
using pidlab::optim::ProgressCallback;
using pidlab::optim::TracePoint;
using pidlab::spec::NameStyle;
using pidlab::tune::SearchBox;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;

namespace pidlab::cli {
namespace {

std::string Join(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// 100 x, as %g prints it (10, not 10.000000000000002).
std::string Percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", 100.0 * fraction);
  return text;
}

struct TuneCommand {
  SpecFlags flags;
  std::string backend = "local", trace;
  bool json = false;
  LcmFlags lcm;
  std::unique_ptr<EpisodePool> pool;
  std::unique_ptr<pidlab::episode_client::TuneProgressPublisher> publisher;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Tune PID gains. On a linear plant the default is the design engine (--method optimal): the least "
        "integral |e| dt of a unit load step under Ms, Mt and noise-gain bounds, on the exact loop with its "
        "dead time, then setpoint weights b, c (and a setpoint filter where they cannot) for at most 10 % "
        "overshoot, --max-overshoot (docs/tuning.md, \"The design "
        "engine\"); --loop sampled --dt D designs the sampled loop at D the same way. A flag that asks for "
        "a search (an objective, a box, a budget, a margin, --robust, --backend lcm) runs the multi-start "
        "on the paper's objective (IAE of the unit step, eq. 4) with a Ceres cross-check, as --method "
        "multi-start, nelder-mead, paper-nm or a baseline do, and the line 'method chosen' says which flag.");
    // The tuner's acceptance margin is 0.01 (spec::LoopSpec::ForTuning, docs/tuning.md).
    flags.Register(app, spec::TuningSpec{});
    app->add_option("--backend", backend, "local (in-process) or lcm (episodes over a running trio)")
        ->capture_default_str();
    app->add_option("--trace", trace, "write the best-so-far trajectory of the search to this CSV file");
    app->add_flag("--json", json, "print one JSON object (with the spec it ran, \"spec\")");
    lcm.Register(app);
    return [this] { return Run(); };
  }

  int Run() {
    spec::TuningSpec ts;
    tune::BuildOptions build;
    build.style = NameStyle::kFlag;
    build.backend = backend == "lcm" ? tune::Backend::kRunner : tune::Backend::kInProcess;
    flags.Apply(&ts, &build.given);
    tune::TuningProblem problem;
    Require(flags.Named(tune::BuildTuning(ts, build, &problem)));
    CheckOutputFile(trace, "--trace");  // before the search, not after it
    const TuneOptions& o = problem.options;
    tune::TuningRunOptions run;
    run.runner = MakeRunner();
    if (pool) run.parallel_for = pool->AsParallelFor();  // the starts on idle trios
    const bool tty = isatty(STDERR_FILENO) != 0;
    run.progress = MakeProgress(tty);
    if (pool) {  // watchers of the first trio see the search as it runs (docs/live.md)
      publisher = std::make_unique<pidlab::episode_client::TuneProgressPublisher>(
          lcm.ClientOptions(lcm.Url()), pool->size(), ToString(o.method), ToString(o.objective));
      run.progress = [terminal = run.progress, this](const TracePoint& tp) {
        terminal(tp);
        publisher->Running(tp);
      };
    }
    tune::TuningResult result;
    const Status tuned = tune::RunTuning(problem, run, &result);
    const TuneSummary& s = result.summary;
    if (publisher) publisher->Finished(tuned.ok() && s.stable, s.gains, s.objective, s.evaluations);
    Require(tuned);
    if (tty) std::fprintf(stderr, "\r%70s\r", "");
    if (!trace.empty()) WriteTrace(s);
    if (json) {
      std::cout << results::TuningJson(problem, result, backend).dump() << "\n";
    } else {
      if (!result.fallback.empty()) std::cout << "fallback         " << result.fallback << "\n";
      PrintText(o, s, result.evaluation, problem.box, result.widened_from, result.box_upper);
      if (s.stable) std::cout << FormatRobustness(result.analysis, o.bounds);
      const pidlab::tune::TimeScale& t = problem.time_scale;
      std::cout << "time scale       n = " << t.horizon_s << " s, ts = " << t.sample_time_s << " s ("
                << t.source << "): " << t.reason << "\n";
      if (!t.method_reason.empty() && t.method_reason != "given")
        std::cout << "method chosen    " << ToString(o.method) << ": " << t.method_reason << "\n";
      if (o.method == pidlab::tune::TuneMethod::kMigo && o.robustness_phase_margin_deg > 0.0)
        std::cout << "robustness       phase margin >= " << o.robustness_phase_margin_deg
                  << " deg (given): the largest Ms bound whose design keeps it, " << s.migo.ms_bound << "\n";
      else if (o.method == pidlab::tune::TuneMethod::kOptimal)
        std::cout << "robustness       Ms <= " << s.design.ms_bound << ": " << t.robustness_reason
                  << "; noise gain <= " << o.bounds.max_noise_gain << ": " << t.noise_gain_reason << "\n";
      else if (o.method == pidlab::tune::TuneMethod::kMigo && !t.robustness_reason.empty())
        std::cout << "robustness       Ms <= " << o.robustness_ms << ": " << t.robustness_reason << "\n";
    }
    return s.stable ? 0 : 1;
  }

  // The sampled-loop runner of --backend (BuildTuning checked its loop); throws BadInput.
  SampledRunner MakeRunner() {
    if (backend == "local") return nullptr;  // in process
    if (backend != "lcm") throw BadInput("--backend " + Quote(backend) + " must be local or lcm");
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
  static void PrintText(const TuneOptions& o, const TuneSummary& s, const Evaluation& ev,
                        const SearchBox& box, const std::vector<double>& widened_from, double box_upper) {
    std::cout << std::setprecision(6);
    if (o.method == pidlab::tune::TuneMethod::kOptimal)
      std::cout << "method           optimal (the design engine) on the load integral |e| dt\n";
    else
      std::cout << "method           " << ToString(o.method) << " on " << ToString(o.objective) << ", box ["
                << o.lower << ", " << box_upper << "]^3, seed " << o.seed << "\n";
    if (o.method == pidlab::tune::TuneMethod::kSimc || o.method == pidlab::tune::TuneMethod::kAmigo)
      std::cout << "rule             " << s.tuning_rule.message << "\n";
    if (o.method == pidlab::tune::TuneMethod::kMigo)
      std::cout << "design           " << s.migo.message << "\n";
    if (o.method == pidlab::tune::TuneMethod::kOptimal && s.stable) {
      PrintDesign(s);
      std::cout << "wall time        " << s.wall_time_s << " s\n\n" << FormatEvaluation(ev);
      return;
    }
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
    // The message may start with the verdict itself ("not run: ...").
    const std::string verdict = ToString(s.refine.verdict, s.method);
    std::string message = s.refine.message;
    if (message.rfind(verdict + ": ", 0) == 0) message.erase(0, verdict.size() + 2);
    std::cout << "verdict          " << verdict << (message.empty() ? "" : ": ") << message << "\n";
    if (o.robust_samples > 0)
      std::cout << "robust set       " << s.robust_set_size << " plants (nominal + " << o.robust_samples
                << " draws "
                << (s.robust_perturbed == analysis::kCovariancePerturbed
                        ? "from the " + s.robust_perturbed + " (" + std::to_string(s.robust_redrawn) +
                              " redrawn)"
                        : "at " + Percent(o.robust_spread) + " % spread")
                << (s.robust_invalid_draws > 0
                        ? ", " + std::to_string(s.robust_invalid_draws) + " invalid left out"
                        : std::string())
                << "): objective = quantile " << o.robust_quantile << "; nominal plant's "
                << s.nominal_objective << "\n";
    if (box.source == "plant") std::cout << "box              " << box.message << "\n";
    if (!widened_from.empty()) {
      std::cout << "box widened      ";
      for (double u : widened_from) std::cout << "[0, " << u << "] -> ";
      std::cout << "[0, " << box_upper
                << "]  (the optimum was on the upper edge of a box not given: docs/tuning.md)\n";
    }
    if (!s.at_bounds.empty()) {
      std::cout << "at bounds        ";
      for (std::size_t i = 0; i < s.at_bounds.size(); ++i) std::cout << (i ? ", " : "") << s.at_bounds[i];
      std::cout << "  (an optimum on the box's edge: widen it with --bounds)\n";
    }
    if (o.two_dof || s.two_dof.ran) PrintTwoDof(s.two_dof);
    std::cout << "wall time        " << s.wall_time_s << " s\n\n";
    std::cout << FormatEvaluation(ev);
  }

  // The design engine's result: its bounds, what was active, the setpoint stage.
  static void PrintDesign(const TuneSummary& s) {
    std::cout << "design           " << s.design.message << "\n";
    std::cout << "active bounds    "
              << (s.design.active.empty() ? std::string("none") : Join(s.design.active)) << "\n";
    std::cout << "unconstrained    " << s.design.unconstrained_note << "\n";
    std::cout << "setpoint         b = " << s.design.b << ", c = " << s.design.c;
    if (s.design.setpoint_filter_s > 0.0) std::cout << ", filter " << s.design.setpoint_filter_s << " s";
    std::cout << ": " << s.two_dof.message << "\n";
    std::cout << "response time    " << s.design.response_time_s << " s (2 / the crossover "
              << s.design.crossover_rad_s << " rad/s)\n";
    if (s.design.reverse_acting)
      std::cout << "note             the loop acts in reverse: the plant's gain is negative, so are kp, ki "
                   "and kd\n";
  }

  static void PrintTwoDof(const pidlab::tune::TwoDofSummary& t) {
    if (!t.ran) {
      std::cout << "two-dof          not run: " << t.message << "\n";
      return;
    }
    std::cout << "two-dof          setpoint weights b = " << t.b << ", c = " << t.c << "  (" << t.evaluations
              << " evaluations)\n";
    for (const auto* r : {&t.before, &t.after})
      std::cout << "  b = " << std::setw(8) << r->b << ", c = " << std::setw(8) << r->c << "  setpoint IAE "
                << r->setpoint_iae << ", overshoot " << r->overshoot_pct << " %, settling "
                << r->settling_time_s << " s;  load IAE " << r->load_iae << ", Ms " << r->ms << "\n";
  }

  void WriteTrace(const TuneSummary& s) const {
    std::ostringstream f;
    f << std::setprecision(17) << "iteration,evaluations,best_objective,kp,ki,kd\n";
    for (const auto& tp : s.optimizer.trace) {
      f << tp.iteration << "," << tp.evaluations << "," << tp.best_f;
      for (int i = 0; i < 3; ++i) f << "," << (tp.best_x.size() == 3 ? tp.best_x(i) : NAN);
      f << "\n";
    }
    WriteOutputFile(trace, f.str());
  }
};

}  // namespace
std::function<int()> RegisterTune(CLI::App* app) { return RegisterCommand<TuneCommand>(app); }

}  // namespace pidlab::cli
