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
#include "pidlab/replay/log_reader.h"
#include "pidlab/replay/replay.h"
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
  const replay::LogContents* log_ = nullptr;  // --log: the log read
  std::size_t log_index_ = 0;                 // its relay episode
  double amplitude = 0.0;  // 0: from the output range
  std::string bias_text;   // "": amplitude / 3
  double hysteresis = -1.0;
  double first_window_s = 60.0, max_window_s = 7200.0;
  std::string method = "amigo";
  mutable double max_ms = 2.0;
  double robustness = 1.4, response_time_s = 0.0, max_overshoot_pct = 60.0;

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

  int Run() {
    if (!log_path.empty()) return RunFromLog();
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
    Require(GainsAreValid(previous, &why), "--gains: " + why);
    const PidOptions pid = PidOptionsAt(loop.pid, loop.dt_s);
    const double range = pid.output_max - pid.output_min;
    relay.amplitude = amplitude > 0.0 ? amplitude : std::isfinite(range) ? 0.2 * range : 1.0;
    if (amplitude < 0.0)
      throw BadInput("--relay-amplitude " + Quote(std::to_string(amplitude)) + " must be > 0");
    relay.bias = bias_text.empty() ? relay.amplitude / 3.0 : ParseDouble(bias_text, "--relay-bias");
    if (hysteresis >= 0.0) {
      relay.hysteresis = hysteresis;
      relay.noise_multiple = 0.0;
    } else {
      if (flags.Given("hysteresis")) throw BadInput("--hysteresis must be >= 0");
      relay.hysteresis = 0.0;
      relay.noise_multiple = 3.0;
    }
    ExperimentOptions xo;
    xo.relay = relay;
    xo.previous = previous;
    xo.pid = pid;
    xo.first_window_s = first_window_s;
    xo.max_window_s = max_window_s;
    Require(xo.IsValid(&why), why);
    if (!(max_ms > 1.0)) throw BadInput("--max-ms " + std::to_string(max_ms) + " must be > 1");

    std::unique_ptr<EpisodeClient> client = lcm.MakeClient();
    const bool quiet_progress = json_out && isatty(STDERR_FILENO) == 0 && false;
    const auto say = [quiet_progress](const std::string& line) {
      if (!quiet_progress) std::fprintf(stderr, "%s\n", line.c_str());
    };
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
    Require(autotune::RunExperiment(xo, runner, &x, say));
    std::vector<int64_t> ids = client->stats().episode_ids;
    return Finish(x, previous, s, given, loop, client.get(), ids, say);
  }

  // From a log: its relay episode's record analysed again, the design, the
  // logged verification step.
  int RunFromLog() {
    replay::LogContents contents;
    if (const Status st = replay::ReadLog(log_path, replay::ReadOptions{}, &contents); !st.ok())
      throw BadInput("--log " + Quote(log_path) + ": " + st.message());
    long index = -1;
    for (std::size_t i = 0; i < contents.episodes.size(); ++i) {
      const replay::Episode& e = contents.episodes[i];
      if (e.has_config && e.spec.relay && (episode_id == 0 || e.episode_id == episode_id))
        index = static_cast<long>(i);
    }
    if (index < 0)
      throw BadInput("--log " + Quote(log_path) + ": " +
                     (episode_id == 0 ? std::string("no relay episode in it")
                                      : "no relay episode " + std::to_string(episode_id) + " in it"));
    const replay::Episode& e = contents.episodes[static_cast<std::size_t>(index)];
    if (!e.Complete())
      throw std::runtime_error("relay episode " + std::to_string(e.episode_id) +
                               " is incomplete in the log: " + e.CompletenessNote());
    ExperimentOptions xo;
    xo.relay = e.spec.relay_tune;
    xo.previous = e.spec.gains;
    xo.pid = PidOptionsAt(e.spec.pid, e.spec.dt_s);
    std::vector<RelaySample> samples;
    for (long k = 0; k < e.total_steps; ++k) {
      const auto i = static_cast<std::size_t>(k);
      samples.push_back({static_cast<double>(k) * e.spec.dt_s, e.spec.reference, e.y[i], e.u[i]});
    }
    const auto say = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
    ExperimentSummary x;
    Require(autotune::AnalyzeRelayRecord(xo, std::move(samples), &x));
    x.episodes = 1;
    autotune::EstimateFromRecord(xo, &x, say);
    log_ = &contents;
    log_index_ = static_cast<std::size_t>(index);
    spec::EvaluateSpec s;
    const LoopOptions loop = episode_client::SampledLoopOptions(e.spec);
    return Finish(x, e.spec.gains, s, {}, loop, nullptr, {e.episode_id}, say);
  }

  template <typename Say>
  int Finish(const ExperimentSummary& x, const PidGains& previous, const spec::EvaluateSpec& s,
             const std::set<std::string>& given, const LoopOptions& loop, EpisodeClient* client,
             const std::vector<int64_t>& episode_ids, const Say& say) {
    json out;
    out["backend"] = log_ ? "log" : "lcm";
    if (log_) out["log"] = log_path;
    out["previous_gains"] = ToJson(previous);
    out["experiment"] = ExperimentJson(x);
    out["estimates"] = EstimatesJson(x);
    PidGains adopted = previous;
    bool ok = false;
    std::string verdict;
    if (x.end != RelayPhase::kDone) {
      verdict = "the relay did not converge: " + x.why;
    } else if (!x.estimates.model_found) {
      verdict = "no model from the cycles: " + x.estimates.message;
    } else {
      ok = DesignAndVerify(s, given, loop, x, client, say, &out, &adopted, &verdict);
    }
    out["adopted"] = ok;
    out["verdict"] = verdict;
    out["gains"] = ToJson(adopted);
    out["episode_ids"] = episode_ids;
    if (json_out) {
      std::cout << out.dump(2) << "\n";
    } else {
      PrintTable(out);
    }
    FlushRunNotes();
    if (!ok) {
      std::fprintf(stderr, "pidlab autotune: %s; the previous gains stay\n", verdict.c_str());
      return 1;
    }
    return 0;
  }

  static json ExperimentJson(const ExperimentSummary& x) {
    json e;
    e["end"] = ToString(x.end);
    e["why"] = x.why;
    e["episodes"] = x.episodes;
    e["u0"] = JsonNumber(x.u0);
    e["y0"] = JsonNumber(x.y0);
    e["noise_sigma"] = JsonNumber(x.noise_sigma);
    e["hysteresis"] = JsonNumber(x.hysteresis);
    e["d_high"] = JsonNumber(x.d_high);
    e["d_low"] = JsonNumber(x.d_low);
    e["relay_start_s"] = JsonNumber(x.relay_start_s);
    e["end_s"] = JsonNumber(x.end_s);
    e["horizon_s"] = JsonNumber(x.horizon_s);
    e["restarts"] = x.restarts;
    e["load_changes_s"] = x.load_changes_s;
    json cycles = json::array();
    for (const RelayCycle& c : x.cycles)
      cycles.push_back({{"start_s", c.start_s},
                        {"t_on_s", c.t_on_s},
                        {"t_off_s", c.t_off_s},
                        {"e_max", c.e_max},
                        {"e_min", c.e_min},
                        {"integral_e", c.integral_e}});
    e["cycles"] = cycles;
    return e;
  }

  static json EstimatesJson(const ExperimentSummary& x) {
    const autotune::RelayEstimates& r = x.estimates;
    if (x.end != RelayPhase::kDone) return nullptr;
    json e;
    e["converged"] = r.converged;
    e["cycles"] = r.cycles;
    e["period_s"] = JsonNumber(r.period_s);
    e["period_ci_s"] = JsonNumber(r.period_ci_s);
    e["amplitude"] = JsonNumber(r.amplitude);
    e["amplitude_ci"] = JsonNumber(r.amplitude_ci);
    e["ku_describing_function"] = JsonNumber(r.ku_describing_function);
    e["model_found"] = r.model_found;
    e["message"] = r.message;
    if (r.model_found) {
      e["ku"] = JsonNumber(r.ku);
      e["ku_ci"] = JsonNumber(r.ku_ci);
      e["pu_s"] = JsonNumber(r.pu_s);
      e["pu_ci_s"] = JsonNumber(r.pu_ci_s);
      e["model"] = {{"kind", r.model.integrating ? "ipdt" : "fopdt"},
                    {"gain", r.model.gain},
                    {"time_constant_s", r.model.time_constant_s},
                    {"delay_s", r.model.delay_s},
                    {"gain_ci", JsonNumber(r.gain_ci)},
                    {"time_constant_ci_s", JsonNumber(r.time_constant_ci_s)},
                    {"delay_ci_s", JsonNumber(r.delay_ci_s)},
                    {"from", r.model_from}};
    }
    return e;
  }

  template <typename Say>
  bool DesignAndVerify(spec::EvaluateSpec s, const std::set<std::string>& given, const LoopOptions& loop,
                       const ExperimentSummary& x, EpisodeClient* client, const Say& say, json* out,
                       PidGains* adopted, std::string* verdict) const {
    const autotune::FopdtModel& m = x.estimates.model;
    // The design: the assembly's tune on the identified model.
    json spec = {{"num", {m.gain}},
                 {"delay", m.delay_s},
                 {"method", method},
                 {"robustness", robustness},
                 {"response_time", response_time_s}};
    spec["den"] = m.integrating ? json::array({1.0, 0.0}) : json::array({m.time_constant_s, 1.0});
    json design;
    const Status designed = results::TuneSpecJson(spec, nullptr, &design);
    if (!designed.ok()) {
      *verdict = "no design on the identified model: " + designed.message();
      (*out)["design"] = {{"spec", spec}, {"error", designed.message()}};
      return false;
    }
    const json& g = design["gains"];
    PidGains gains{g.value("kp", 0.0), g.value("ki", 0.0), g.value("kd", 0.0), g.value("tf", 0.0)};
    const double ms = design["robustness"].is_object() && design["robustness"]["ms"].is_number()
                          ? design["robustness"]["ms"].get<double>()
                          : kInf;
    (*out)["design"] = {{"method", method},
                        {"spec", spec},
                        {"gains", design["gains"]},
                        {"ms", JsonNumber(ms)},
                        {"robustness", design["robustness"]},
                        {"stable", design["stable"]}};
    say("design (" + method + " on the identified model): kp " + std::to_string(gains.kp) + ", ki " +
        std::to_string(gains.ki) + ", kd " + std::to_string(gains.kd) + ", Ms " + std::to_string(ms));
    if (!(ms <= max_ms) || !design.value("stable", false)) {
      *verdict = "the design's Ms on the identified model is " + std::to_string(ms) + ", above --max-ms " +
                 std::to_string(max_ms);
      return false;
    }
    // The verification: a closed-loop step on the trio with the new gains.
    const double pu = x.estimates.pu_s;
    s.gains = {gains.kp, gains.ki, gains.kd};
    s.loop.loop = "sampled";
    if (gains.tf > 0.0) {
      s.loop.derivative_filter_s = gains.tf;
      s.loop.derivative_filter_ratio = 0.0;
    }
    std::set<std::string> keys = given;
    if (!given.count("sample_time")) s.loop.sample_time_s = CeilTo(pu / 100.0, loop.dt_s);
    if (!given.count("horizon")) s.loop.horizon_s = CeilTo(15.0 * pu, s.loop.sample_time_s);
    keys.insert("sample_time");
    keys.insert("horizon");
    keys.insert("gains");
    keys.insert("loop");
    tune::BuildOptions build;
    build.style = NameStyle::kFlag;
    build.backend = tune::Backend::kRunner;
    build.given = keys;
    tune::EvaluationProblem problem;
    Status st = tune::BuildEvaluation(s, build, &problem);
    if (!st.ok() && !log_) {
      *verdict = "the verification step does not build: " + st.message();
      return false;
    }
    evaluation::Evaluation ev;
    json v;
    if (log_) {
      // From the log: the first episode after the relay's that ran these gains.
      const replay::Episode* step = nullptr;
      for (std::size_t i = log_index_ + 1; i < log_->episodes.size() && !step; ++i) {
        const replay::Episode& e = log_->episodes[i];
        if (e.has_config && !e.spec.relay && e.spec.gains.kp == gains.kp && e.spec.gains.ki == gains.ki &&
            e.spec.gains.kd == gains.kd)
          step = &e;
      }
      if (!step) {
        *verdict = "the log holds no verification step with these gains after the relay episode";
        return false;
      }
      st = replay::EvaluateEpisode(*step, &ev);
      if (!st.ok()) {
        *verdict = "the logged verification step cannot be evaluated: " + st.message();
        return false;
      }
      s.loop.horizon_s = step->spec.horizon_s;
      v = ToJson(ev);
      v["episode_id"] = step->episode_id;
    } else {
      tune::EvaluationRunOptions run;
      run.monte_carlo = false;
      run.runner = [client](const Plant& pl, const PidGains& ga, const LoopOptions& lo,
                            const DisturbanceOptions& d, std::vector<double>* y,
                            std::vector<SampledStep>* tr) { return client->Run(pl, ga, lo, d, y, tr); };
      say("verification: a closed-loop step on the trio, " + std::to_string(s.loop.horizon_s) + " s");
      tune::EvaluationResult result;
      st = tune::RunEvaluation(problem, run, &result);
      if (!st.ok()) {
        *verdict = "the verification step failed: " + st.message();
        return false;
      }
      ev = result.evaluation;
      v = results::EvaluationJson(problem, result, "lcm");
    }
    const double overshoot = ev.step.overshoot_pct;
    const double settling = ev.step.settling_time_s;
    const bool settled = std::isfinite(ev.iae) && std::isfinite(settling) && settling < s.loop.horizon_s;
    const bool calm = overshoot <= max_overshoot_pct;
    (*out)["verification"] = {{"iae", JsonNumber(ev.iae)},
                              {"overshoot_pct", JsonNumber(overshoot)},
                              {"settling_time_s", JsonNumber(settling)},
                              {"horizon_s", s.loop.horizon_s},
                              {"settled", settled},
                              {"overshoot_ok", calm},
                              {"evaluation", v}};
    say("  step on the trio: IAE " + std::to_string(ev.iae) + ", overshoot " + std::to_string(overshoot) +
        " %, settling " + std::to_string(settling) + " s");
    if (!settled) {
      *verdict = "the step on the trio with the new gains did not settle within " +
                 std::to_string(s.loop.horizon_s) + " s";
      return false;
    }
    if (!calm) {
      *verdict = "the step on the trio overshoots " + std::to_string(overshoot) +
                 " %, above --max-overshoot " + std::to_string(max_overshoot_pct);
      return false;
    }
    *adopted = gains;
    *verdict = "adopted: " + method + " on the identified model, Ms " + std::to_string(ms) +
               ", verified on the trio";
    return true;
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
