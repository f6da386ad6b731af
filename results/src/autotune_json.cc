// The result object of pidlab autotune (autotune_json.h).

#include "pidlab/results/autotune_json.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pidlab/autotune/verify.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/replay/replay.h"
#include "pidlab/results/results_json.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/results/tune_run.h"

namespace pidlab::results {
namespace {

using autotune::ExperimentSummary;
using nlohmann::json;

std::string Num(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

}  // namespace

bool AutotuneDesignOptions::IsValid(std::string* error) const {
  std::string e;
  if (method != "amigo" && method != "simc" && method != "migo" && method != "optimal")
    e = "method '" + method + "' is not amigo, simc, migo or optimal";
  else if (!(max_ms > 1.0) || !std::isfinite(max_ms))
    e = "max Ms " + Num(max_ms) + " must be > 1 and finite";
  else if (!(max_overshoot_pct >= 0.0))
    e = "max overshoot " + Num(max_overshoot_pct) + " % must be >= 0";
  else if (!(robustness > 1.0) || !std::isfinite(robustness))
    e = "robustness " + Num(robustness) + " must be > 1 and finite";
  else if (!(response_time_s >= 0.0) || !std::isfinite(response_time_s))
    e = "response time " + Num(response_time_s) + " s must be >= 0 and finite";
  else
    return true;
  if (error) *error = e;
  return false;
}

json ExperimentJson(const ExperimentSummary& x) {
  json e;
  e["end"] = ToString(x.end);
  e["why"] = x.why;
  e["episodes"] = x.episodes;
  e["u0"] = JsonNumber(x.u0);
  e["y0"] = JsonNumber(x.y0);
  e["noise_sigma"] = JsonNumber(x.noise_sigma);
  e["hysteresis"] = JsonNumber(x.hysteresis);
  e["y_limit"] = JsonNumber(x.y_limit);
  e["d_high"] = JsonNumber(x.d_high);
  e["d_low"] = JsonNumber(x.d_low);
  e["clipped"] = x.clipped;
  e["hold_drift"] = JsonNumber(x.hold_drift);
  e["hold_note"] = x.hold_note;
  e["hold_s"] = JsonNumber(x.hold_s);
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
                      {"integral_e", c.integral_e},
                      {"integral_on_e", c.integral_on_e}});
  e["cycles"] = cycles;
  return e;
}

// What the 95 % intervals hold (issue 60, "honest intervals").
constexpr const char* kIntervalsAre =
    "the cycle-to-cycle spread only (95 %, Student's t): the model-structure error of a FOPDT fitted to "
    "another process is not in them";

json EstimatesJson(const ExperimentSummary& x) {
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
    e["intervals"] = kIntervalsAre;
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

namespace {

json ReadingJson(const autotune::StepReading& r) {
  return {{"window_samples", r.window},
          {"noise_sigma", JsonNumber(r.noise_sigma)},
          {"residual_sigma", JsonNumber(r.residual_sigma)},
          {"band", JsonNumber(r.band)},
          {"band_widening", JsonNumber(r.widening)},
          {"tail_s", JsonNumber(r.tail_s)},
          {"overshoot_pct", JsonNumber(r.overshoot_pct)},
          {"settling_time_s", JsonNumber(r.settling_time_s)},
          {"settled", r.settled}};
}

// The identified model K e^(-Ls)/(Ts+1), or K e^(-Ls)/s, as a plant.
Plant ModelAsPlant(const autotune::FopdtModel& m) {
  Plant model;
  model.name = "custom";
  model.tf.num = {m.gain};
  model.tf.den = m.integrating ? std::vector<double>{1.0, 0.0} : std::vector<double>{m.time_constant_s, 1.0};
  model.delay_s = m.delay_s;
  return model;
}

// The identified model as a spec's plant keys.
json ModelPlant(const autotune::FopdtModel& m) {
  const Plant model = ModelAsPlant(m);
  return {{"num", model.tf.num}, {"den", model.tf.den}, {"delay", model.delay_s}};
}

double MsOf(const json& result) {
  return result["robustness"].is_object() && result["robustness"]["ms"].is_number()
             ? result["robustness"]["ms"].get<double>()
             : std::numeric_limits<double>::infinity();
}

// The design on the model (out["design"]); false with *verdict.
bool DesignOnModel(const ExperimentSummary& x, const AutotuneDesignOptions& o, json* out, PidGains* gains,
                   double* ms, bool* stable, std::string* verdict) {
  json spec = ModelPlant(x.estimates.model);
  spec.update({{"method", o.method}, {"robustness", o.robustness}, {"response_time", o.response_time_s}});
  json design;
  const Status designed = TuneSpecJson(spec, nullptr, &design);
  if (!designed.ok()) {
    *verdict = "no design on the identified model: " + designed.message();
    (*out)["design"] = {{"spec", spec}, {"error", designed.message()}};
    return false;
  }
  const json& g = design["gains"];
  *gains = PidGains{g.value("kp", 0.0), g.value("ki", 0.0), g.value("kd", 0.0), g.value("tf", 0.0)};
  *ms = MsOf(design);
  *stable = design.value("stable", false);
  (*out)["design"] = {{"method", o.method},
                      {"spec", spec},
                      {"gains", design["gains"]},
                      {"ms", JsonNumber(*ms)},
                      {"robustness", design["robustness"]},
                      {"stable", design["stable"]}};
  return true;
}

// The given gains (verify_gains) on the model (out["verify_gains"]).
void GivenOnModel(const ExperimentSummary& x, const AutotuneDesignOptions& o, json* out, double* ms,
                  bool* stable) {
  json spec = ModelPlant(x.estimates.model);
  const PidGains& g = o.verify_gains;
  spec.update({{"gains", {g.kp, g.ki, g.kd}}, {"derivative_filter", g.tf}});
  json result;
  const Status st = EvaluateSpecJson(spec, &result);
  *ms = st.ok() ? MsOf(result) : std::numeric_limits<double>::infinity();
  *stable = st.ok() && result["robustness"].is_object() && result["robustness"].value("stable", false);
  (*out)["verify_gains"] = {{"gains", ToJson(g)},
                            {"ms", JsonNumber(*ms)},
                            {"stable", *stable},
                            {"robustness", st.ok() ? result["robustness"] : json(st.message())}};
}

// How far the measured step's overshoot may exceed the predicted one, in
// points of the step, besides the noise's widening: a first-order model of a
// higher-order process under-predicts the overshoot by a few points; a loop
// near instability rings by tens.
constexpr double kModelOvershootPoints = 10.0;
// The step the design predicts: the same loop, gains and step on the
// identified model, without the measurement noise.
bool PredictedStep(const ExperimentSummary& x, const PidGains& gains, const evaluation::Evaluation& measured,
                   evaluation::Evaluation* predicted) {
  const Plant model = ModelAsPlant(x.estimates.model);
  evaluation::LoopOptions loop = measured.options;
  loop.measurement_noise = MeasurementNoise{};
  if (evaluation::Evaluate(model, gains, loop, evaluation::EvaluateOptions{}, predicted).ok() &&
      predicted->step.valid)
    return true;
  // A delay of more than 1000 samples (2 s at 2 ms) is past the sampled
  // loop's analysis: the continuous loop, whose hold of dt is nothing to it.
  loop.loop = evaluation::LoopKind::kContinuous;
  return evaluation::Evaluate(model, gains, loop, evaluation::EvaluateOptions{}, predicted).ok() &&
         predicted->step.valid;
}

// The measured step against the predicted one: "" if it rings no more than
// the model and the noise allow, else why. (A drift is the band's: the
// smoothed step leaves it over the tail. Settling is not compared: a load
// change during the step moves it, not the gains.)
std::string AgainstPrediction(const evaluation::Evaluation& predicted, double overshoot,
                              const autotune::StepReading& reading, double reference, json* out) {
  const double noise_points = 100.0 * reading.widening / std::max(std::abs(reference), 1e-300);
  const double os_bound = predicted.step.overshoot_pct + kModelOvershootPoints + noise_points;
  (*out) = {{"overshoot_pct", JsonNumber(predicted.step.overshoot_pct)},
            {"settling_time_s", JsonNumber(predicted.step.settling_time_s)},
            {"overshoot_bound_pct", JsonNumber(os_bound)}};
  if (!(overshoot <= os_bound))
    return "rings: it overshoots " + Num(overshoot) + " % where the design predicts " +
           Num(predicted.step.overshoot_pct) + " % (at most " + Num(os_bound) +
           " %: " + Num(kModelOvershootPoints) + " points for the model and " + Num(noise_points) +
           " for the noise)";
  return "";
}

// The verification step of `gains` (`who` names them); false with *verdict.
bool VerifyStep(const ExperimentSummary& x, const AutotuneDesignOptions& o, const StepRunner& step,
                const std::function<void(const std::string&)>& say, const PidGains& gains,
                const std::string& who, json* out, std::string* verdict) {
  StepRun run;
  if (const Status st = step(gains, x.estimates.pu_s, &run); !st.ok()) {
    *verdict = st.message();
    return false;
  }
  const evaluation::Evaluation& ev = run.evaluation;
  // Under noise the step is read smoothed, in a band widened by the noise
  // (autotune/verify.h); a clean one by stepinfo, as evaluate reads it.
  const autotune::StepReading reading =
      autotune::ReadVerificationStep(ev.t, ev.y, ev.options.reference, x.noise_sigma, x.estimates.pu_s);
  const bool noisy = x.noise_sigma > 0.0;
  const double overshoot = noisy ? reading.overshoot_pct : ev.step.overshoot_pct;
  const double settling = noisy ? reading.settling_time_s : ev.step.settling_time_s;
  const bool settled = std::isfinite(ev.iae) && std::isfinite(settling) &&
                       (noisy ? reading.settled : settling < run.horizon_s);
  const bool calm = overshoot <= o.max_overshoot_pct;
  (*out)["verification"] = {{"gains", who},
                            {"iae", JsonNumber(ev.iae)},
                            {"overshoot_pct", JsonNumber(overshoot)},
                            {"settling_time_s", JsonNumber(settling)},
                            {"horizon_s", run.horizon_s},
                            {"settled", settled},
                            {"overshoot_ok", calm},
                            {"read", noisy ? "smoothed" : "stepinfo"},
                            {"smoothing", ReadingJson(reading)},
                            {"stepinfo",
                             {{"overshoot_pct", JsonNumber(ev.step.overshoot_pct)},
                              {"settling_time_s", JsonNumber(ev.step.settling_time_s)}}},
                            {"evaluation", run.json}};
  if (say)
    say("  step: IAE " + Num(ev.iae) + ", overshoot " + Num(overshoot) + " %, settling " + Num(settling) +
        " s" +
        (noisy ? " (smoothed over " + std::to_string(reading.window) + " samples, the band ±2 % widened by " +
                     Num(reading.widening) + " for the noise)"
               : ""));
  if (!settled) {
    *verdict = noisy
                   ? "the step with " + who + ", smoothed, does not stay in the band ±" + Num(reading.band) +
                         " (2 % widened by " + Num(reading.widening) + " for the noise) over the last " +
                         Num(reading.tail_s) + " s of " + Num(run.horizon_s) + " s"
                   : "the step with " + who + " did not settle within " + Num(run.horizon_s) + " s";
    return false;
  }
  if (!calm) {
    *verdict = "the step with " + who + " overshoots " + Num(overshoot) + " %, above the bound " +
               Num(o.max_overshoot_pct) + " %";
    return false;
  }
  evaluation::Evaluation predicted;
  if (!PredictedStep(x, gains, ev, &predicted)) {
    *verdict = "the step with " + who + " has no prediction on the identified model to compare with";
    return false;
  }
  json against;
  const std::string off = AgainstPrediction(predicted, overshoot, reading, ev.options.reference, &against);
  (*out)["verification"]["predicted"] = against;
  if (say)
    say("  predicted on the model: overshoot " + Num(predicted.step.overshoot_pct) + " %, settling " +
        Num(predicted.step.settling_time_s) + " s");
  if (!off.empty()) {
    *verdict = "the step with " + who + " " + off;
    return false;
  }
  return true;
}

// The design on the model and the verification of its gains, or of the
// given ones (verify_gains) under the same verdict; false with *verdict.
bool DesignAndVerify(const ExperimentSummary& x, const AutotuneDesignOptions& o, const StepRunner& step,
                     const std::function<void(const std::string&)>& say, json* out, PidGains* adopted,
                     std::string* verdict) {
  PidGains gains;
  double ms = 0.0;
  bool stable = false;
  if (!DesignOnModel(x, o, out, &gains, &ms, &stable, verdict)) return false;
  if (say)
    say("design (" + o.method + " on the identified model): kp " + Num(gains.kp) + ", ki " + Num(gains.ki) +
        ", kd " + Num(gains.kd) + ", Ms " + Num(ms));
  std::string who = "the new gains", whose = "the design's";
  if (o.verify_given) {
    gains = o.verify_gains;
    GivenOnModel(x, o, out, &ms, &stable);
    who = "the given gains";
    whose = "the given gains'";
    if (say)
      say("verify_gains: kp " + Num(gains.kp) + ", ki " + Num(gains.ki) + ", kd " + Num(gains.kd) + ", tf " +
          Num(gains.tf) + ", Ms " + Num(ms) + " on the identified model");
  }
  if (!stable) {
    *verdict = whose + " loop on the identified model is unstable" +
               (o.verify_given && gains.kd != 0.0 && gains.tf == 0.0
                    ? std::string(" (an ideal derivative against the model's dead time: give KP,KI,KD,TF)")
                    : std::string());
    return false;
  }
  if (!(ms <= o.max_ms)) {
    *verdict = whose + " Ms on the identified model is " + Num(ms) + ", above the bound " + Num(o.max_ms);
    return false;
  }
  if (!VerifyStep(x, o, step, say, gains, who, out, verdict)) return false;
  *adopted = gains;
  *verdict =
      o.verify_given
          ? "adopted: the given gains, Ms " + Num(ms) + " on the identified model, verified by a step"
          : "adopted: " + o.method + " on the identified model, Ms " + Num(ms) + ", verified by a step";
  return true;
}

}  // namespace

json AutotuneJson(const ExperimentSummary& x, const PidGains& previous, const AutotuneDesignOptions& options,
                  const StepRunner& step, const std::function<void(const std::string&)>& say, bool* adopted) {
  json out;
  out["previous_gains"] = ToJson(previous);
  out["experiment"] = ExperimentJson(x);
  out["estimates"] = EstimatesJson(x);
  PidGains gains = previous;
  bool ok = false;
  std::string verdict;
  if (x.end != RelayPhase::kDone)
    verdict = "the relay did not converge: " + x.why;
  else if (!x.estimates.model_found)
    verdict = "no model from the cycles: " + x.estimates.message;
  else
    ok = DesignAndVerify(x, options, step, say, &out, &gains, &verdict);
  // A refusal after a drifting hold says so: the hold's y0 centred the relay.
  if (!ok && !x.hold_note.empty()) verdict += "; " + x.hold_note;
  out["adopted"] = ok;
  out["verdict"] = verdict;
  out["gains"] = ToJson(gains);
  *adopted = ok;
  return out;
}

Status AutotuneLogJson(const std::string& path, int64_t episode_id, const AutotuneDesignOptions& options,
                       const std::function<void(const std::string&)>& say, json* result, bool* adopted,
                       const FixedPointRelay& fixed_point) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  replay::LogContents log;
  if (const Status st = replay::ReadLog(path, replay::ReadOptions{}, &log); !st.ok())
    return Status::InvalidInput("log '" + path + "': " + st.message());
  long index = -1;
  for (std::size_t i = 0; i < log.episodes.size(); ++i) {
    const replay::Episode& e = log.episodes[i];
    if (e.has_config && e.spec.relay && (episode_id == 0 || e.episode_id == episode_id))
      index = static_cast<long>(i);
  }
  if (index < 0)
    return Status::InvalidInput("log '" + path + "': " +
                                (episode_id == 0
                                     ? std::string("no relay episode in it")
                                     : "no relay episode " + std::to_string(episode_id) + " in it"));
  const replay::Episode& e = log.episodes[static_cast<std::size_t>(index)];
  if (!e.Complete())
    return Status::RunnerFailed("relay episode " + std::to_string(e.episode_id) +
                                " is incomplete in the log: " + e.CompletenessNote());
  autotune::ExperimentOptions xo;
  xo.relay = e.spec.relay_tune;
  xo.previous = e.spec.gains;
  xo.pid = PidOptionsAt(e.spec.pid, e.spec.dt_s);
  if (fixed_point)
    if (const Status st = fixed_point(xo.previous, xo.pid, &xo.relay); !st.ok()) return st;
  std::vector<autotune::RelaySample> samples;
  samples.reserve(static_cast<std::size_t>(e.total_steps));
  for (long k = 0; k < e.total_steps; ++k) {
    const auto i = static_cast<std::size_t>(k);
    samples.push_back({static_cast<double>(k) * e.spec.dt_s, e.spec.reference, e.y[i], e.u[i]});
  }
  autotune::ExperimentSummary x;
  if (const Status st = autotune::AnalyzeRelayRecord(xo, std::move(samples), &x); !st.ok()) return st;
  x.episodes = 1;
  autotune::EstimateFromRecord(xo, &x, say);
  // The verification: the first later episode that ran these gains.
  const StepRunner step = [&](const PidGains& gains, double, StepRun* run) {
    for (std::size_t i = static_cast<std::size_t>(index) + 1; i < log.episodes.size(); ++i) {
      const replay::Episode& s = log.episodes[i];
      if (!s.has_config || s.spec.relay || s.spec.gains.kp != gains.kp || s.spec.gains.ki != gains.ki ||
          s.spec.gains.kd != gains.kd)
        continue;
      if (const Status st = replay::EvaluateEpisode(s, &run->evaluation); !st.ok())
        return Status::RunnerFailed("the logged verification step cannot be evaluated: " + st.message());
      run->horizon_s = s.spec.horizon_s;
      run->json = ToJson(run->evaluation);
      run->json["episode_id"] = s.episode_id;
      return Status::Ok();
    }
    return Status::RunnerFailed(
        "the log holds no verification step with these gains after the relay episode");
  };
  *result = AutotuneJson(x, e.spec.gains, options, step, say, adopted);
  (*result)["backend"] = "log";
  (*result)["log"] = path;
  (*result)["episode_ids"] = json::array({e.episode_id});
  return Status::Ok();
}

}  // namespace pidlab::results
