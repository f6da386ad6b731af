// pidlab evaluate: IAE, stability and step metrics of one gain set.

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/tuner/episode_client.h"

namespace pidlab::cli {
namespace {

struct EvaluateCommand {
  PlantFlags plant;
  LoopFlags loop;
  std::string gains;
  bool json = false;
  std::string samples_csv;
  std::string trajectory_csv;
  // --backend lcm: run the sampled loop over a running process trio.
  std::string backend = "local";
  LcmFlags lcm;
  CLI::App* app_ = nullptr;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Evaluate one PID gain set on a plant: the paper's IAE (eq. 4) and other error sums, closed-loop "
        "poles and strict stability, MATLAB-stepinfo rise/overshoot/settling of the unit-step response.");
    plant.Register(app);
    loop.Register(app);
    app->add_option("--gains", gains, "KP,KI,KD (each finite and >= 0)")->required();
    app->add_flag("--json", json, "print one JSON object instead of the table");
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
    app_ = app;
    return [this] { return Run(); };
  }

  int Run() {
    const Plant p = plant.Build();
    const PidGains g = ParseGains(gains);
    LoopOptions options = loop.Build();
    EvaluateOptions what;
    what.record_trajectory = !trajectory_csv.empty();
    if (what.record_trajectory && options.loop != LoopKind::kSampled && backend == "local")
      throw BadInput("--trajectory-csv needs --loop sampled");
    if (what.record_trajectory && options.TotalSteps() + 1 > kMaxRecordedPoints)
      throw BadInput(
          "--trajectory-csv would have horizon / dt + 1 = " + std::to_string(options.TotalSteps() + 1) +
          " rows, more than 1e7: use a coarser --dt or a shorter --horizon");
    // Unwritable output is bad input, found before any work.
    CheckOutputFile(samples_csv, "--samples-csv");
    CheckOutputFile(trajectory_csv, "--trajectory-csv");
    Evaluation ev;
    std::string error;
    std::unique_ptr<EpisodeClient> client;
    if (backend == "lcm") {
      if (app_->count("--loop") > 0 && options.loop != LoopKind::kSampled)
        throw BadInput("--backend lcm runs the sampled loop, not --loop " + Quote(loop.loop));
      options.loop = LoopKind::kSampled;
      client = lcm.MakeClient();
      std::string runner_error;
      const bool ok = Evaluate(
          p, g, options, what, &ev, &error,
          [&](const Plant& pl, const PidGains& ga, const LoopOptions& lo, const DisturbanceOptions& d,
              std::vector<double>* y, std::vector<SampledStep>* tr, std::string* err) {
            const bool run_ok = client->Run(pl, ga, lo, d, y, tr, err);
            if (!run_ok && err) runner_error = *err;
            return run_ok;
          });
      // A failed episode is a runtime failure (exit 1), not bad input.
      if (!ok && !runner_error.empty()) throw std::runtime_error(runner_error);
      if (!ok) throw BadInput(error);
    } else if (!Evaluate(p, g, options, what, &ev, &error)) {
      throw BadInput(error);
    }
    if (!samples_csv.empty()) WriteSamplesCsv(ev, samples_csv);
    if (!trajectory_csv.empty()) WriteTrajectoryCsv(ev, trajectory_csv);
    if (json) {
      nlohmann::json j = ToJson(ev);
      j["backend"] = backend;
      if (client) j["steps_per_second"] = JsonNumber(client->stats().StepsPerSecond());
      if (client && client->stats().realtime.paced()) j["realtime"] = RealtimeJson(client->stats().realtime);
      std::cout << j.dump() << "\n";
    } else {
      std::cout << FormatEvaluation(ev);
      if (client) {
        std::printf("backend: lcm, %ld steps in %ld episode(s), %.0f steps/s\n", client->stats().steps,
                    client->stats().episodes, client->stats().StepsPerSecond());
        if (client->stats().realtime.paced())
          std::printf("realtime: %s\n", transport::DescribeRealtime(client->stats().realtime).c_str());
      }
    }
    return 0;
  }

  static void WriteTrajectoryCsv(const Evaluation& ev, const std::string& path) {
    FILE* f = std::fopen(path.c_str(), "w");
    if (!f) throw BadInput("--trajectory-csv " + Quote(path) + " cannot be written");
    std::fprintf(f, "k,t,r,y,u,n\n");
    for (const SampledStep& s : ev.trajectory)
      std::fprintf(f, "%ld,%.17g,%.17g,%.17g,%.17g,%.17g\n", s.k, s.t, s.r, s.y, s.u, s.n);
    if (std::fclose(f) != 0) throw std::runtime_error("writing " + path + " failed");
  }
};

}  // namespace
std::function<int()> RegisterEvaluate(CLI::App* app) {
  auto command = std::make_shared<EvaluateCommand>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

}  // namespace pidlab::cli
