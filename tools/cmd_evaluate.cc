// pidlab evaluate: IAE, stability and step metrics of one gain set.

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <set>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/tune/problem.h"

using pidlab::episode_client::EpisodeClient;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledStep;

namespace pidlab::cli {
namespace {

struct EvaluateCommand {
  SpecFlags flags;
  bool json = false;
  std::string samples_csv;
  std::string trajectory_csv;
  // --backend lcm: run the sampled loop over a running process trio.
  std::string backend = "local";
  LcmFlags lcm;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Evaluate one PID gain set on a plant: the integral of |e| of the setpoint step and of a unit load "
        "step at the plant input (in the plant's units; on the paper's plants eq. (4)'s IAE first), the "
        "other error sums, closed-loop poles and strict stability, MATLAB-stepinfo rise/overshoot/settling "
        "of the unit-step response, margins, Ms, Mt, noise gain and the slowest time constant "
        "(docs/robustness.md).");
    flags.Register(app, spec::EvaluateSpec{});
    app->add_flag("--json", json,
                  "print one JSON object instead of the table (with the spec it ran, \"spec\")");
    app->add_option(
        "--samples-csv", samples_csv,
        "write t,r,y,e,n,u,y_load,u_load at the sample times to this CSV file (u and the load response "
        "of a unit step at the plant input)");
    app->add_option("--trajectory-csv", trajectory_csv,
                    "write k,t,r,y,u,n of every step of the sampled loop to this CSV file (%.17g)");
    app->add_option(
           "--backend", backend,
           "local (in process) or lcm (one episode over a running trio, see pidlab launch); lcm implies "
           "--loop sampled")
        ->check(CLI::IsMember({"local", "lcm"}))
        ->capture_default_str();
    lcm.Register(app);
    return [this] { return Run(); };
  }

  int Run() {
    spec::EvaluateSpec s;
    tune::BuildOptions build;
    build.style = spec::NameStyle::kFlag;
    build.backend = backend == "lcm" ? tune::Backend::kRunner : tune::Backend::kInProcess;
    flags.Apply(&s, &build.given);
    tune::EvaluationProblem problem;
    Require(flags.Named(tune::BuildEvaluation(s, build, &problem)));
    const LoopOptions& options = problem.loop;
    tune::EvaluationRunOptions run;
    run.what.record_trajectory = !trajectory_csv.empty();
    if (run.what.record_trajectory && options.loop != evaluation::LoopKind::kSampled)
      throw BadInput("--trajectory-csv needs --loop sampled");
    if (run.what.record_trajectory && options.TotalSteps() + 1 > kMaxRecordedPoints)
      throw BadInput(
          "--trajectory-csv would have horizon / dt + 1 = " + std::to_string(options.TotalSteps() + 1) +
          " rows, more than 1e7: use a coarser --dt or a shorter --horizon");
    // Unwritable output is bad input, found before any work.
    CheckOutputFile(samples_csv, "--samples-csv");
    CheckOutputFile(trajectory_csv, "--trajectory-csv");
    std::unique_ptr<EpisodeClient> client;
    if (backend == "lcm") {
      client = lcm.MakeClient();
      run.runner = [&client](const Plant& pl, const PidGains& ga, const LoopOptions& lo,
                             const DisturbanceOptions& d, std::vector<double>* y,
                             std::vector<SampledStep>* tr) { return client->Run(pl, ga, lo, d, y, tr); };
    }
    const bool tty = isatty(STDERR_FILENO) != 0;
    run.monte_carlo_progress = [tty](int done, int total) {
      if (tty && (done % 10 == 0 || done == total))
        std::fprintf(stderr, "\r  Monte Carlo %d / %d   ", done, total);
    };
    // A failed episode is a runtime failure (exit 1), bad input exit 2.
    tune::EvaluationResult result;
    Require(tune::RunEvaluation(problem, run, &result));
    if (tty && result.monte_carlo_ran) std::fprintf(stderr, "\r%40s\r", "");
    if (!samples_csv.empty()) {
      evaluation::CommandSeries series;
      evaluation::CommandAndLoadSeries(problem.plant, problem.gains, options, result.evaluation, &series);
      WriteSamplesCsv(result.evaluation, series, samples_csv);
    }
    if (!trajectory_csv.empty()) WriteTrajectoryCsv(result.evaluation, trajectory_csv);
    Print(problem, result, client.get());
    // -v: the episodes' ids, to find them in a log (pidlab replay --episode).
    if (client && lcm.verbose)
      for (const int64_t id : client->stats().episode_ids)
        std::fprintf(stderr, "pidlab: note: episode %lld ran\n", static_cast<long long>(id));
    return 0;
  }

  // The result: one JSON object (with the spec it ran) or the table.
  void Print(const tune::EvaluationProblem& problem, const tune::EvaluationResult& result,
             const EpisodeClient* client) const {
    if (json) {
      nlohmann::json j = results::EvaluationJson(problem, result, backend);
      if (client) j["steps_per_second"] = JsonNumber(client->stats().StepsPerSecond());
      if (client && client->stats().realtime.paced()) j["realtime"] = RealtimeJson(client->stats().realtime);
      std::cout << j.dump() << "\n";
      return;
    }
    std::cout << FormatEvaluation(result.evaluation) << FormatRobustness(result.analysis, problem.bounds);
    const tune::TimeScale& t = problem.time_scale;
    std::cout << "time scale     n = " << t.horizon_s << " s, ts = " << t.sample_time_s << " s (" << t.source
              << "): " << t.reason << "\n";
    if (result.monte_carlo_ran) std::cout << FormatMonteCarlo(problem.monte_carlo, result.monte_carlo);
    if (client) {
      std::printf("backend: lcm, %ld steps in %ld episode(s), %.0f steps/s\n", client->stats().steps,
                  client->stats().episodes, client->stats().StepsPerSecond());
      if (client->stats().realtime.paced())
        std::printf("realtime: %s\n", transport::DescribeRealtime(client->stats().realtime).c_str());
    }
  }

  // 100 x, as %g prints it (10, not 10.000000000000002).
  static std::string Percent(double fraction) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", 100.0 * fraction);
    return text;
  }

  static std::string FormatMonteCarlo(const analysis::MonteCarloOptions& mc, const analysis::MonteCarloSummary& s) {
    char line[256];
    std::string out;
    if (s.perturbed == analysis::kCovariancePerturbed)
      out += "monte carlo      " + std::to_string(s.samples) + " plants from the " + s.perturbed + " (" +
             std::to_string(s.redrawn) + " redrawn), seed " + std::to_string(mc.seed) + "\n";
    else
      out += "monte carlo      " + std::to_string(s.samples) + " plants, " + s.perturbed + " within +/-" +
             Percent(mc.spread) + " %, seed " + std::to_string(mc.seed) + "\n";
    std::snprintf(line, sizeof line, "  stable         %d of %d (%.4g %%)%s\n", s.stable, s.samples,
                  100.0 * s.stable_fraction,
                  s.invalid ? (" (" + std::to_string(s.invalid) + " invalid draws)").c_str() : "");
    out += line;
    out += "                 min          median       p95          max\n";
    const std::pair<const char*, const analysis::Distribution*> rows[] = {
        {"  IAE          ", &s.iae}, {"  overshoot %  ", &s.overshoot_pct}, {"  Ms           ", &s.ms}};
    for (const auto& [name, d] : rows) {
      std::snprintf(line, sizeof line, "%s  %-12.6g %-12.6g %-12.6g %-12.6g\n", name, d->min, d->median,
                    d->p95, d->max);
      out += line;
    }
    return out;
  }

  static void WriteTrajectoryCsv(const evaluation::Evaluation& ev, const std::string& path) {
    std::unique_ptr<io::AtomicFile> f;
    Status opened = io::AtomicFile::Open(path, &f);
    if (!opened.ok()) Require(Status(opened.code(), "--trajectory-csv " + opened.message()));
    f->Write("k,t,r,y,u,n\n");
    char row[200];
    for (const SampledStep& s : ev.trajectory) {
      const int n =
          std::snprintf(row, sizeof row, "%ld,%.17g,%.17g,%.17g,%.17g,%.17g\n", s.k, s.t, s.r, s.y, s.u, s.n);
      f->Write(std::string_view(row, static_cast<std::size_t>(n)));
    }
    Require(f->Commit());
  }
};

}  // namespace
std::function<int()> RegisterEvaluate(CLI::App* app) { return RegisterCommand<EvaluateCommand>(app); }

}  // namespace pidlab::cli
