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
#include "pidlab/tune/spec_build.h"

using pidlab::analysis::Distribution;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopBounds;
using pidlab::analysis::MonteCarloOptions;
using pidlab::analysis::MonteCarloSummary;
using pidlab::analysis::RunMonteCarlo;
using pidlab::episode_client::EpisodeClient;
using pidlab::evaluation::EvaluateLoop;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledRunner;
using pidlab::evaluation::SampledStep;
using pidlab::spec::NameStyle;
using pidlab::tune::BuildBounds;
using pidlab::tune::BuildGains;
using pidlab::tune::BuildLoopOptions;
using pidlab::tune::BuildMonteCarlo;
using pidlab::tune::BuildPlant;
using pidlab::tune::BuildStepperParameters;
using pidlab::tune::CheckPlantInLoop;

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
        "Evaluate one PID gain set on a plant: the paper's IAE (eq. 4) and other error sums, closed-loop "
        "poles and strict stability, MATLAB-stepinfo rise/overshoot/settling of the unit-step response, "
        "margins, Ms, Mt, noise gain and the slowest time constant (docs/robustness.md).");
    flags.Register(app, spec::EvaluateSpec{});
    app->add_flag("--json", json,
                  "print one JSON object instead of the table (with the spec it ran, \"spec\")");
    app->add_option("--samples-csv", samples_csv, "write t,r,y,e,n at the sample times to this CSV file");
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
    std::set<std::string> given;
    flags.Apply(&s, &given);
    s.plant.Normalize();
    std::string error;
    Plant p;
    Require(BuildPlant(s.plant, NameStyle::kFlag, &p, &error), error);
    StepperMotorParameters stepper;
    Require(BuildStepperParameters(s.plant, NameStyle::kFlag, &stepper, &error), error);
    MonteCarloOptions mc;
    Require(BuildMonteCarlo(s, NameStyle::kFlag, &mc, &error), error);
    if (s.gains.empty()) throw BadInput("--gains is required (or --spec FILE)");
    PidGains g;
    Require(BuildGains(s.gains, NameStyle::kFlag, &g, &error), error);
    if (backend == "lcm") {
      if (given.count("loop") > 0 && s.loop.loop != "sampled")
        throw BadInput("--backend lcm runs the sampled loop, not --loop " + Quote(s.loop.loop));
      s.loop.loop = "sampled";
    }
    LoopOptions options;
    Require(BuildLoopOptions(s.loop, NameStyle::kFlag, &options, &error), error);
    Require(CheckPlantInLoop(p, options, NameStyle::kFlag, &error), error);
    LoopBounds loop_bounds;
    Require(BuildBounds(s.bounds, NameStyle::kFlag, &loop_bounds, &error), error);
    EvaluateOptions what;
    what.record_trajectory = !trajectory_csv.empty();
    if (what.record_trajectory && options.loop != LoopKind::kSampled)
      throw BadInput("--trajectory-csv needs --loop sampled");
    if (what.record_trajectory && options.TotalSteps() + 1 > kMaxRecordedPoints)
      throw BadInput(
          "--trajectory-csv would have horizon / dt + 1 = " + std::to_string(options.TotalSteps() + 1) +
          " rows, more than 1e7: use a coarser --dt or a shorter --horizon");
    if (s.monte_carlo > 0 && backend == "lcm")
      throw BadInput("--monte-carlo runs in process: use --backend local");
    if (s.monte_carlo > 0 && p.delay_s > 0.0 && !p.model)
      throw BadInput("--monte-carlo with --delay is not supported yet (its draws are undelayed plants)");
    if (s.monte_carlo > 0 && p.nonlinear)
      throw BadInput("--monte-carlo draws linear plants: it does not take --plant " + Quote(p.name));
    // Unwritable output is bad input, found before any work.
    CheckOutputFile(samples_csv, "--samples-csv");
    CheckOutputFile(trajectory_csv, "--trajectory-csv");
    Evaluation ev;
    std::unique_ptr<EpisodeClient> client;
    SampledRunner runner;  // null: in process
    if (backend == "lcm") {
      client = lcm.MakeClient();
      runner = [&client](const Plant& pl, const PidGains& ga, const LoopOptions& lo,
                         const DisturbanceOptions& d, std::vector<double>* y, std::vector<SampledStep>* tr,
                         std::string* err) { return client->Run(pl, ga, lo, d, y, tr, err); };
    }
    // A failed episode is a runtime failure (exit 1), bad input exit 2.
    Require(EvaluateLoop(p, g, options, what, &ev, runner));
    // Margins, peaks, noise gain and time constants of the loop evaluated.
    const LoopAnalysis analysis = AnalyzeOrThrow(p, g, options);
    MonteCarloSummary mc_summary;
    if (s.monte_carlo > 0) {
      const bool tty = isatty(STDERR_FILENO) != 0;
      const auto progress = [tty](int done, int total) {
        if (tty && (done % 10 == 0 || done == total))
          std::fprintf(stderr, "\r  Monte Carlo %d / %d   ", done, total);
      };
      Require(RunMonteCarlo(p, p.name == "stepper_motor" ? &stepper : nullptr, g, options, mc, &mc_summary,
                            &error, progress),
              error);
      if (tty) std::fprintf(stderr, "\r%40s\r", "");
    }
    if (!samples_csv.empty()) WriteSamplesCsv(ev, samples_csv);
    if (!trajectory_csv.empty()) WriteTrajectoryCsv(ev, trajectory_csv);
    Print(s, ev, analysis, loop_bounds, mc, mc_summary, client.get());
    return 0;
  }

  // The result: one JSON object (with the spec it ran) or the table.
  void Print(const spec::EvaluateSpec& s, const Evaluation& ev, const LoopAnalysis& analysis,
             const LoopBounds& loop_bounds, const MonteCarloOptions& mc, const MonteCarloSummary& mc_summary,
             const EpisodeClient* client) const {
    if (json) {
      nlohmann::json j = ToJson(ev);
      j["backend"] = backend;
      j["robustness"] = RobustnessJson(analysis, loop_bounds);
      if (s.monte_carlo > 0) j["monte_carlo"] = results::MonteCarloJson(mc, mc_summary);
      if (client) j["steps_per_second"] = JsonNumber(client->stats().StepsPerSecond());
      if (client && client->stats().realtime.paced()) j["realtime"] = RealtimeJson(client->stats().realtime);
      j["spec"] = spec::ToJson(s);
      std::cout << j.dump() << "\n";
      return;
    }
    std::cout << FormatEvaluation(ev) << FormatRobustness(analysis, loop_bounds);
    if (s.monte_carlo > 0) std::cout << FormatMonteCarlo(mc, mc_summary);
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

  static std::string FormatMonteCarlo(const MonteCarloOptions& mc, const MonteCarloSummary& s) {
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
    const std::pair<const char*, const Distribution*> rows[] = {
        {"  IAE          ", &s.iae}, {"  overshoot %  ", &s.overshoot_pct}, {"  Ms           ", &s.ms}};
    for (const auto& [name, d] : rows) {
      std::snprintf(line, sizeof line, "%s  %-12.6g %-12.6g %-12.6g %-12.6g\n", name, d->min, d->median,
                    d->p95, d->max);
      out += line;
    }
    return out;
  }

  static void WriteTrajectoryCsv(const Evaluation& ev, const std::string& path) {
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
std::function<int()> RegisterEvaluate(CLI::App* app) {
  auto command = std::make_shared<EvaluateCommand>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

}  // namespace pidlab::cli
