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
#include "pidlab/controller_export/export.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/episode_client/tune_progress.h"
#include "pidlab/results/autotune_json.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/results/tune_run.h"
#include "pidlab/tune/problem.h"

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

constexpr double kInf = std::numeric_limits<double>::infinity();

// A multiple of `step` at least `x`.
double CeilTo(double x, double step) { return std::ceil(x / step - 1e-9) * step; }

struct AutotuneCommand {
  SpecFlags flags;
  bool json_out = false;
  std::string backend = "lcm";
  LcmFlags lcm;
  RelayTuneOptions relay;
  std::string log_path;
  int64_t episode_id = 0;
  double amplitude = 0.0;  // 0: from the output range
  std::string bias_text;   // "": amplitude / 3
  double hysteresis = -1.0;
  double first_window_s = 60.0, max_window_s = 7200.0;
  std::string method = "amigo";
  double max_ms = 2.0;
  double robustness = 1.4, response_time_s = 0.0, max_overshoot_pct = 60.0;
  std::string scalar = "double";
  std::vector<double> input_range;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Autotune on the running process: a hold (the previous PID of --gains, or the open-loop input "
        "--u0) that finds the operating point and the noise, a relay with hysteresis around it until the "
        "oscillation converges, the ultimate gain and period and a FOPDT or integrating model from its "
        "cycles (with intervals), a design on that model (--method) and a closed-loop step on the trio "
        "before the gains are adopted (docs/autotune.md). Run under `pidlab launch`.");
    spec::EvaluateSpec defaults;
    defaults.gains = {0.0, 0.0, 0.0};
    defaults.bounds.max_ms =
        2.0;  // --max-ms: adopt only a design with Ms on the identified model at most this
    flags.Register(app, defaults);
    app->add_option("--backend", backend, "lcm: the relay episodes run over a running trio (pidlab launch)")
        ->check(CLI::IsMember({"lcm"}))
        ->capture_default_str();
    app->add_option("--relay-amplitude", amplitude,
                    "relay amplitude d (units of u) > 0; default 20 % of the output range, 1 if unlimited")
        ->check(FiniteNumber());
    app->add_option("--relay-bias", bias_text,
                    "relay bias b, |b| < d: +d+b above, -(d-b) below the operating point's input; default "
                    "d/3 (an asymmetric relay, which identifies a FOPDT model); 0 is the symmetric relay");
    app->add_option("--hysteresis", hysteresis,
                    "relay hysteresis eps (units of y) >= 0; default 3 sigma of the noise the hold measures")
        ->check(FiniteNumber());
    app->add_option("--hold", relay.hold_s,
                    "the hold before the relay, s (the operating point and the noise)")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--u0", relay.u0, "the open-loop hold's input (when --gains are 0,0,0)")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--y-limit", relay.y_limit,
                    "stop the relay when |y - y0| (from the operating point) exceeds this (default: none)")
        ->check(NumberOrInfinity());
    app->add_option("--settled-cycles", relay.settled_cycles,
                    "converged when this many cycles' periods and amplitudes agree")
        ->capture_default_str();
    app->add_option("--tolerance", relay.tolerance, "their relative agreement")->capture_default_str();
    app->add_option("--timeout-periods", relay.timeout_periods,
                    "stop the relay if it has not converged within this many of its own periods")
        ->capture_default_str();
    app->add_option("--max-restarts", relay.max_restarts, "restarts after a load change")
        ->capture_default_str();
    app->add_option("--scalar", scalar,
                    "the controller's relay: double (pidlab-controller's, checked bit for bit), q31 or q15 "
                    "(pidlab export --autotune --scalar's in pidlab-controller-c: every switch checked, the "
                    "input within 3 or 2 LSB; needs --input-range and finite --output-limits)")
        ->capture_default_str();
    app->add_option("--input-range", input_range,
                    "fixed point: LO,HI, the --input-range the controller was exported with")
        ->delimiter(',');
    app->add_option("--relay-time", first_window_s, "the first relay episode's relay window, s")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--max-time", max_window_s, "the longest relay window, s")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--method", method, "the design on the identified model: amigo, simc or migo (pidlab's)")
        ->check(CLI::IsMember({"amigo", "simc", "migo"}))
        ->capture_default_str();
    app->add_option("--robustness", robustness, "migo: the Ms bound it designs to")->capture_default_str();
    app->add_option("--response-time", response_time_s, "migo: the response time it designs to (0: fastest)")
        ->capture_default_str();
    app->add_option("--max-overshoot", max_overshoot_pct,
                    "adopt only gains whose step on the trio overshoots at most this, %")
        ->capture_default_str();
    app->add_option("--log", log_path,
                    "recompute from a log instead (pidlab launch --log): its relay episode's record analysed "
                    "again, the design, and the logged verification step; no trio is needed");
    app->add_option("--episode", episode_id, "--log: this relay episode (default: the last one)");
    app->add_flag("--json", json_out, "print one JSON object (experiment, estimates, design, verification)");
    lcm.Register(app);
    return [this] { return Run(); };
  }

  results::AutotuneDesignOptions Design() const {
    results::AutotuneDesignOptions o;
    o.method = method;
    o.robustness = robustness;
    o.response_time_s = response_time_s;
    o.max_ms = max_ms;
    o.max_overshoot_pct = max_overshoot_pct;
    std::string why;
    if (!o.IsValid(&why)) throw BadInput(why);
    return o;
  }

  // --scalar q31|q15: the exported fixed-point relay's grids, as pidlab
  // export scales them.
  controller_export::Scalar ParseScalar() const {
    controller_export::Scalar v = controller_export::Scalar::kDouble;
    if (!controller_export::ParseScalar(scalar, &v) || v == controller_export::Scalar::kFloat)
      throw BadInput("--scalar " + Quote(scalar) + " is not one of double, q31, q15");
    if (v == controller_export::Scalar::kDouble && !input_range.empty())
      throw BadInput("--input-range is for --scalar q31 or q15");
    if (v != controller_export::Scalar::kDouble && input_range.size() != 2)
      throw BadInput("--scalar " + scalar + " needs --input-range LO,HI (the export's)");
    return v;
  }

  void SetFixedPoint(const PidGains& previous, const PidOptions& pid) {
    controller_export::Options o;
    o.scalar = ParseScalar();
    if (o.scalar == controller_export::Scalar::kDouble) return;
    o.input_min = input_range[0];
    o.input_max = input_range[1];
    controller_export::Controller c;
    c.gains = previous;
    c.pid = pid;
    controller_export::FixedScale scale;
    try {
      scale = controller_export::FixedPointScale(o, c);
    } catch (const std::invalid_argument& e) {
      throw BadInput(e.what());
    }
    relay.q_bits = scale.bits;
    relay.input_full_scale = scale.input_full_scale;
    relay.output_full_scale = scale.output_full_scale;
  }

  static void Say(const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }

  int Run() {
    if (!log_path.empty()) {
      spec::EvaluateSpec unused;
      std::set<std::string> given;
      flags.Apply(&unused, &given);
      max_ms = given.count("max_ms") ? unused.bounds.max_ms : 2.0;
      json out;
      bool adopted = false;
      ParseScalar();  // bad --scalar or --input-range: exit 2 before the log is read
      const results::FixedPointRelay fixed = [this](const PidGains& previous, const PidOptions& pid,
                                                    RelayTuneOptions* r) {
        try {
          SetFixedPoint(previous, pid);
        } catch (const std::exception& e) {
          return Status::InvalidInput(e.what());
        }
        r->q_bits = relay.q_bits;
        r->input_full_scale = relay.input_full_scale;
        r->output_full_scale = relay.output_full_scale;
        return Status::Ok();
      };
      Require(results::AutotuneLogJson(log_path, episode_id, Design(), Say, &out, &adopted, fixed));
      return Print(out, adopted);
    }
    spec::EvaluateSpec s;
    s.gains = {0.0, 0.0, 0.0};
    s.bounds.max_ms = 2.0;
    std::set<std::string> given;
    flags.Apply(&s, &given);
    max_ms = s.bounds.max_ms;
    if (s.gains.size() != 3) throw BadInput("--gains needs KP,KI,KD");
    s.loop.loop = "sampled";
    Plant plant;
    LoopOptions loop;
    Require(tune::BuildPlantInLoop(s.plant, s.loop, NameStyle::kFlag, &plant, &loop));
    loop.loop = LoopKind::kSampled;
    const PidGains previous{s.gains[0], s.gains[1], s.gains[2]};
    std::string why;
    if (!GainsAreValid(previous, &why)) throw BadInput("--gains: " + why);
    const PidOptions pid = PidOptionsAt(loop.pid, loop.dt_s);
    const double range = pid.output_max - pid.output_min;
    if (amplitude < 0.0)
      throw BadInput("--relay-amplitude " + Quote(std::to_string(amplitude)) + " must be > 0");
    relay.amplitude = amplitude > 0.0 ? amplitude : std::isfinite(range) ? 0.2 * range : 1.0;
    relay.bias = bias_text.empty() ? relay.amplitude / 3.0 : ParseDouble(bias_text, "--relay-bias");
    if (hysteresis >= 0.0) {
      relay.hysteresis = hysteresis;
      relay.noise_multiple = 0.0;
    } else {
      if (flags.Given("hysteresis"))
        throw BadInput("--hysteresis " + spec::FormatNumber(hysteresis) + " must be >= 0");
      relay.hysteresis = 0.0;
      relay.noise_multiple = 3.0;
    }
    SetFixedPoint(previous, pid);
    ExperimentOptions xo;
    xo.relay = relay;
    xo.previous = previous;
    xo.pid = pid;
    xo.first_window_s = first_window_s;
    xo.max_window_s = max_window_s;
    if (!xo.IsValid(&why)) throw BadInput(why);
    const results::AutotuneDesignOptions design = Design();

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
    // The verification: a closed-loop step on the trio, the spec of the
    // flags with the new gains, 15 Pu at Pu/100 unless given.
    const results::StepRunner step = [&](const PidGains& gains, double pu, results::StepRun* run) {
      spec::EvaluateSpec v = s;
      v.gains = {gains.kp, gains.ki, gains.kd};
      v.loop.loop = "sampled";
      if (gains.tf > 0.0) {
        v.loop.derivative_filter_s = gains.tf;
        v.loop.derivative_filter_ratio = 0.0;
      }
      std::set<std::string> keys = given;
      if (!given.count("sample_time")) v.loop.sample_time_s = CeilTo(pu / 100.0, loop.dt_s);
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
      options.runner = [&client](const Plant& pl, const PidGains& ga, const LoopOptions& lo,
                                 const DisturbanceOptions& d, std::vector<double>* y,
                                 std::vector<SampledStep>* tr) { return client->Run(pl, ga, lo, d, y, tr); };
      Say("verification: a closed-loop step on the trio, " + std::to_string(v.loop.horizon_s) + " s");
      tune::EvaluationResult result;
      if (const Status st = tune::RunEvaluation(problem, options, &result); !st.ok())
        return Status::RunnerFailed("the verification step failed: " + st.message());
      run->evaluation = result.evaluation;
      run->horizon_s = v.loop.horizon_s;
      run->json = results::EvaluationJson(problem, result, "lcm");
      return Status::Ok();
    };
    bool adopted = false;
    json out = results::AutotuneJson(x, previous, design, step, Say, &adopted);
    out["backend"] = "lcm";
    out["episode_ids"] = client->stats().episode_ids;
    // The verdict to live watchers (pidlab serve --lcm-url: the Live tab's
    // tunings): the adopted gains (or the previous ones) and the design's Ms.
    try {
      episode_client::TuneProgressPublisher verdict(lcm.ClientOptions(lcm.Url()), 1, "autotune " + method,
                                                    "Ms on the identified model");
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
            "cycles)\n",
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
