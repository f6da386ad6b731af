// pidlab autotune: the relay experiment on a running trio, its estimates, a
// design on the identified model and a verified adoption (docs/autotune.md).

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <set>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "pidlab/autotune/experiment.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/episode_client/tune_progress.h"
#include "pidlab/results/autotune_json.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/results/tune_run.h"
#include "pidlab/tune/problem.h"
#include "pidlab/tune/time_scale.h"

using nlohmann::json;
using pidlab::autotune::ExperimentOptions;
using pidlab::autotune::ExperimentSummary;
using pidlab::autotune::RelaySample;
using pidlab::episode_client::EpisodeClient;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledStep;
using pidlab::spec::NameStyle;

namespace pidlab::cli {
namespace {

// A multiple of `step` at least `x`.
double CeilTo(double x, double step) { return std::ceil(x / step - 1e-9) * step; }

struct AutotuneCommand {
  SpecFlags flags;           // the loop: plant, PID options, the previous gains
  SpecFlags autotune_flags;  // the relay and the design (spec/autotune_spec.h)
  bool json_out = false;
  std::string backend = "lcm";
  LcmFlags lcm;
  std::string log_path;
  int64_t episode_id = 0;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Autotune on the running process: a hold (the previous PID of --gains, or the open-loop input "
        "--u0) that finds the operating point and the noise, a relay with hysteresis around it until the "
        "oscillation converges, the ultimate gain and period and a FOPDT or integrating model from its "
        "cycles (with intervals), a design on that model (--method) and a closed-loop step on the trio "
        "before the gains are adopted (docs/autotune.md). Run under `pidlab launch`.");
    spec::EvaluateSpec defaults;
    defaults.gains = {0.0, 0.0, 0.0};
    // --max-ms: adopt only a design with Ms on the identified model at most this.
    defaults.bounds.max_ms = results::AutotuneDesignOptions{}.max_ms;
    flags.Register(app, defaults);
    autotune_flags.Register(app, spec::AutotuneSpec{}, false);
    app->add_option("--backend", backend, "lcm: the relay episodes run over a running trio (pidlab launch)")
        ->check(CLI::IsMember({"lcm"}))
        ->capture_default_str();
    app->add_option("--log", log_path,
                    "recompute from a log instead (pidlab launch --log): its relay episode's record analysed "
                    "again, the design, and the logged verification step; no trio is needed");
    app->add_option("--episode", episode_id, "--log: this relay episode (default: the last one)");
    app->add_flag("--json", json_out, "print one JSON object (experiment, estimates, design, verification)");
    lcm.Register(app);
    return [this] { return Run(); };
  }

  static void Say(const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }

  int Run() {
    spec::AutotuneSpec a;
    std::set<std::string> a_given;
    autotune_flags.Apply(&a, &a_given);
    spec::EvaluateSpec s;
    s.gains = {0.0, 0.0, 0.0};
    s.bounds.max_ms = results::AutotuneDesignOptions{}.max_ms;
    std::set<std::string> given;
    flags.Apply(&s, &given);
    if (!log_path.empty()) {
      // Bad --scalar or --input-range: exit 2 before the log is read.
      Require(results::CheckAutotuneScalar(a, NameStyle::kFlag));
      results::AutotuneDesignOptions design;
      Require(results::BuildAutotuneDesign(a, s.bounds.max_ms, NameStyle::kFlag, &design));
      const results::FixedPointRelay fixed = [&a](const PidGains& previous, const PidOptions& pid,
                                                  RelayTuneOptions* r) {
        return results::AutotuneFixedPoint(a, previous, pid, NameStyle::kFlag, r);
      };
      json out;
      bool adopted = false;
      Require(results::AutotuneLogJson(log_path, episode_id, design, Say, &out, &adopted, fixed));
      return Print(out, adopted);
    }
    if (s.gains.size() != 3) throw BadInput("--gains needs KP,KI,KD");
    s.loop.loop = "sampled";
    Plant plant;
    LoopOptions loop;
    const std::string dt_line = tune::SampledDtFromSpec(&s, &given);  // said once the input is known good
    Require(tune::BuildPlantInLoop(s.plant, s.loop, NameStyle::kFlag, &plant, &loop));
    loop.loop = LoopKind::kSampled;
    const PidGains previous{s.gains[0], s.gains[1], s.gains[2]};
    std::string why;
    if (!GainsAreValid(previous, &why)) throw BadInput("--gains: " + why);
    const PidOptions pid = PidOptionsAt(loop.pid, loop.dt_s);
    results::AutotuneRun autotune_run;
    Require(
        results::BuildAutotune(a, a_given, previous, pid, s.bounds.max_ms, NameStyle::kFlag, &autotune_run));
    if (!dt_line.empty()) Say(dt_line);
    // --y-limit not given: from the plant's expected relay amplitude.
    RelayTuneOptions& relay = autotune_run.experiment.relay;
    std::string y_line = "y limit " + spec::FormatNumber(relay.y_limit) + " from the hold's level (given)";
    if (!a_given.count("y_limit")) {
      relay.y_limit = tune::RelayYLimitFromPlant(plant, relay.amplitude + std::abs(relay.bias),
                                                 s.loop.measurement_noise, &y_line);
      Say(y_line);
    }
    const ExperimentOptions& xo = autotune_run.experiment;
    const results::AutotuneDesignOptions& design = autotune_run.design;

    std::unique_ptr<EpisodeClient> client = lcm.MakeClient();
    const auto runner = [&](const RelayTuneOptions& r, double horizon_s, std::vector<RelaySample>* out) {
      LoopOptions lo = loop;
      lo.sample_time_s = lo.dt_s;
      lo.horizon_s = CeilTo(horizon_s, lo.dt_s);
      std::vector<SampledStep> steps;
      const Status st = client->RunRelay(plant, previous, lo, DisturbanceOptions(lo.disturbance), r, &steps);
      if (!st.ok()) return st;
      out->clear();
      for (const SampledStep& k : steps) out->push_back({k.t, k.r, k.y, k.u});
      return Status::Ok();
    };
    ExperimentSummary x;
    Require(autotune::RunExperiment(xo, runner, &x, Say));
    const results::StepRunner step = VerificationStep(s, given, loop.dt_s, client.get());
    bool adopted = false;
    json out = results::AutotuneJson(x, previous, design, step, Say, &adopted);
    out["backend"] = "lcm";
    out["y_limit_note"] = y_line;
    out["episode_ids"] = client->stats().episode_ids;
    // The verdict to live watchers (pidlab serve --lcm-url: the Live tab's
    // tunings): the adopted gains (or the previous ones) and the design's Ms.
    try {
      episode_client::TuneProgressPublisher verdict(
          lcm.ClientOptions(lcm.Url()), 1, "autotune " + design.method, "Ms on the identified model");
      const json& ms = out.contains("design") ? out["design"]["ms"] : json(nullptr);
      const json& g = out["gains"];
      verdict.Finished(adopted, PidGains{g.value("kp", 0.0), g.value("ki", 0.0), g.value("kd", 0.0)},
                       ms.is_number() ? ms.get<double>() : std::numeric_limits<double>::infinity(),
                       static_cast<long>(client->stats().episodes));
    } catch (const std::exception&) {
      // A watcher's message never stops the command.
    }
    return Print(out, adopted);
  }

  // The verification: a closed-loop step on the trio, the spec of the flags
  // `s` with the new gains, 15 Pu at Pu/100 unless given.
  static results::StepRunner VerificationStep(const spec::EvaluateSpec& s, const std::set<std::string>& given,
                                              double dt_s, EpisodeClient* client) {
    return [s, given, dt_s, client](const PidGains& gains, double pu, results::StepRun* run) {
      spec::EvaluateSpec v = s;
      v.gains = {gains.kp, gains.ki, gains.kd};
      v.loop.loop = "sampled";
      if (gains.tf > 0.0) {
        v.loop.derivative_filter_s = gains.tf;
        v.loop.derivative_filter_ratio = 0.0;
      }
      std::set<std::string> keys = given;
      if (!given.count("sample_time")) v.loop.sample_time_s = CeilTo(pu / 100.0, dt_s);
      if (!given.count("horizon")) v.loop.horizon_s = CeilTo(15.0 * pu, v.loop.sample_time_s);
      for (const char* k : {"sample_time", "horizon", "gains", "loop"}) keys.insert(k);
      tune::BuildOptions build;
      build.style = NameStyle::kFlag;
      build.backend = tune::Backend::kRunner;
      build.given = keys;
      tune::EvaluationProblem problem;
      if (const Status st = tune::BuildEvaluation(v, build, &problem); !st.ok())
        return Status::RunnerFailed("the verification step does not build: " + st.message());
      tune::EvaluationRunOptions options;
      options.monte_carlo = false;
      options.runner = [client](const Plant& pl, const PidGains& ga, const LoopOptions& lo,
                                const DisturbanceOptions& d, std::vector<double>* y,
                                std::vector<SampledStep>* tr) { return client->Run(pl, ga, lo, d, y, tr); };
      Say("verification: a closed-loop step on the trio, " + spec::FormatNumber(v.loop.horizon_s) + " s");
      tune::EvaluationResult result;
      if (const Status st = tune::RunEvaluation(problem, options, &result); !st.ok())
        return Status::RunnerFailed("the verification step failed: " + st.message());
      run->evaluation = result.evaluation;
      run->horizon_s = v.loop.horizon_s;
      run->json = results::EvaluationJson(problem, result, "lcm");
      return Status::Ok();
    };
  }

  int Print(const json& out, bool adopted) const {
    if (json_out)
      std::cout << out.dump(2) << "\n";
    else
      PrintTable(out);
    FlushRunNotes();
    if (!adopted) {
      std::fprintf(stderr, "pidlab autotune: %s; the previous gains stay\n",
                   out["verdict"].get<std::string>().c_str());
      return 1;
    }
    return 0;
  }

  static void PrintTable(const json& out) {
    const json& x = out["experiment"];
    std::printf("relay:        %s after %d episode(s)%s\n", x["end"].get<std::string>().c_str(),
                x["episodes"].get<int>(),
                x["why"].get<std::string>().empty() ? "" : (": " + x["why"].get<std::string>()).c_str());
    std::printf("operating:    u0 %.6g, noise sigma %.3g, hysteresis %.3g, relay +%.6g / -%.6g\n",
                x["u0"].is_number() ? x["u0"].get<double>() : NAN,
                x["noise_sigma"].is_number() ? x["noise_sigma"].get<double>() : NAN,
                x["hysteresis"].is_number() ? x["hysteresis"].get<double>() : NAN,
                x["d_high"].is_number() ? x["d_high"].get<double>() : NAN,
                x["d_low"].is_number() ? x["d_low"].get<double>() : NAN);
    if (x.value("clipped", std::string()) != "")
      std::printf("clipped:      %s\n", x["clipped"].get<std::string>().c_str());
    const json& e = out["estimates"];
    if (e.is_object()) {
      std::printf("period:       %.6g +- %.2g s (95 %%, %d cycles)\n", e["period_s"].get<double>(),
                  e["period_ci_s"].get<double>(), e["cycles"].get<int>());
      std::printf("amplitude:    %.6g +- %.2g\n", e["amplitude"].get<double>(),
                  e["amplitude_ci"].get<double>());
      if (e["model_found"].get<bool>()) {
        const json& m = e["model"];
        const auto ci = [](const json& v) { return v.is_number() ? v.get<double>() : NAN; };
        std::printf(
            "Ku, Pu:       %.6g +- %.2g, %.6g +- %.2g s (the model's phase crossover; 95 %% over the "
            "cycles: their spread only, not the model-structure error)\n",
            e["ku"].get<double>(), ci(e["ku_ci"]), e["pu_s"].get<double>(), ci(e["pu_ci_s"]));
        std::printf("Ku (DF):      %.6g (describing function 4d/(pi a), labelled: no correction)\n",
                    e["ku_describing_function"].get<double>());
        if (m["kind"] == "ipdt")
          std::printf("model:        %.6g e^(-%.6gs) / s (from the %s)\n", m["gain"].get<double>(),
                      m["delay_s"].get<double>(), m["from"].get<std::string>().c_str());
        else
          std::printf("model:        %.6g e^(-%.6gs) / (%.6g s + 1) (from the %s)\n", m["gain"].get<double>(),
                      m["delay_s"].get<double>(), m["time_constant_s"].get<double>(),
                      m["from"].get<std::string>().c_str());
      }
    }
    if (out.contains("verification")) {
      const json& v = out["verification"];
      std::printf("verification: IAE %.6g, overshoot %.3g %%, settling %.4g s on the trio\n",
                  v["iae"].is_number() ? v["iae"].get<double>() : NAN,
                  v["overshoot_pct"].is_number() ? v["overshoot_pct"].get<double>() : NAN,
                  v["settling_time_s"].is_number() ? v["settling_time_s"].get<double>() : NAN);
    }
    const json& g = out["gains"];
    std::printf("%s\n", out["verdict"].get<std::string>().c_str());
    std::printf("gains:        kp %.17g, ki %.17g, kd %.17g, tf %.17g\n", g.value("kp", 0.0),
                g.value("ki", 0.0), g.value("kd", 0.0), g.value("tf", 0.0));
  }
};

}  // namespace

std::function<int()> RegisterAutotune(CLI::App* app) {
  static AutotuneCommand command;
  return command.Register(app);
}

}  // namespace pidlab::cli
