// The relay experiment over relay episodes (experiment.h).

#include "pidlab/autotune/experiment.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace pidlab::autotune {
namespace {

std::string Num(double v) {
  std::ostringstream os;
  os.precision(5);
  os << v;
  return os.str();
}

}  // namespace

bool ExperimentOptions::IsValid(std::string* error) const {
  std::string e;
  if (!relay.IsValid(&e)) {
  } else if (!GainsAreValid(previous, &e)) {
  } else if (!pid.IsValid(&e)) {
  } else if (!(first_window_s > 0.0) || !std::isfinite(first_window_s)) {
    e = "the first relay window " + Num(first_window_s) + " s must be > 0 and finite";
  } else if (!(max_window_s >= first_window_s) || !std::isfinite(max_window_s)) {
    e = "the longest relay window " + Num(max_window_s) + " s must be finite and at least the first " +
        Num(first_window_s) + " s";
  } else {
    return true;
  }
  if (error) *error = e;
  return false;
}

Status ReplayRelay(const RelayTuneOptions& relay, const PidGains& previous, const PidOptions& pid,
                   const std::vector<RelaySample>& samples, RelayTuner* tuner) {
  *tuner = RelayTuner(relay, previous, pid);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const RelaySample& s = samples[k];
    if (!std::isfinite(s.y))
      return Status::RunnerFailed("the measurement at t = " + Num(s.t_s) +
                                  " s is not finite: the test stops");
    const double u = tuner->Step(s.t_s, s.r, s.y);
    // Double: bit for bit. Fixed point: within the exported relay's bound
    // (its previous PID rounds), where a switch at another step differs by
    // the relay's whole amplitude.
    const double tolerance = tuner->input_tolerance();
    if (tolerance == 0.0 ? std::memcmp(&u, &s.u, sizeof u) != 0 : !(std::abs(u - s.u) <= tolerance))
      return Status::RunnerFailed(
          "step " + std::to_string(k) + " (t = " + Num(s.t_s) + " s): the controller put out " + Num(s.u) +
          ", the relay gives " + Num(u) +
          (tolerance == 0.0 ? std::string() : " (bound " + Num(tolerance) + ")") +
          ": the controller does not run this relay" +
          (relay.q_bits == 0 ? std::string() : " in q" + std::to_string(relay.q_bits)));
  }
  return Status::Ok();
}

namespace {

// The mean time from each of the last `halves` switches of u after the
// relay's start to the extreme of y before the next switch (NaN if there
// are fewer).
double ApparentDelay(const std::vector<RelaySample>& samples, double relay_start_s, int halves) {
  std::vector<std::size_t> switches;
  for (std::size_t k = 1; k < samples.size(); ++k)
    if (samples[k].t_s >= relay_start_s && samples[k].u != samples[k - 1].u) switches.push_back(k);
  if (static_cast<int>(switches.size()) < halves + 1) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (std::size_t i = switches.size() - 1 - halves; i + 1 < switches.size(); ++i) {
    const std::size_t from = switches[i], to = switches[i + 1];
    const bool rising = samples[from].u > samples[from - 1].u;  // y turns at its minimum
    std::size_t at = from;
    for (std::size_t k = from; k < to; ++k)
      if (rising ? samples[k].y < samples[at].y : samples[k].y > samples[at].y) at = k;
    // The new u is applied from its own sample on.
    sum += samples[at].t_s - samples[from].t_s;
  }
  return sum / halves;
}

// The line that names a relay the output limits cut ("" if none): the
// asked +(d + b) / -(d - b), what was used about u0, and the limits.
std::string ClippedNote(const ExperimentOptions& options, const ExperimentSummary& out) {
  const double asked_high = options.relay.amplitude + options.relay.bias;
  const double asked_low = options.relay.amplitude - options.relay.bias;
  if (!(out.d_high > 0.0) || !(out.d_low > 0.0)) return "";
  // A fixed-point relay rounds its amplitudes to the output grid: a cut is
  // more than that rounding.
  const double slack = 1e-9 * std::max({1.0, std::abs(asked_high), std::abs(asked_low)}) +
                       (options.relay.q_bits > 0 ? 1e-6 * std::max(asked_high, asked_low) : 0.0);
  const bool high = out.d_high < asked_high - slack, low = out.d_low < asked_low - slack;
  if (!high && !low) return "";
  std::string line = "the relay +" + Num(asked_high) + " / -" + Num(asked_low) + " about u0 " + Num(out.u0) +
                     " was clipped by the output limits " + Num(options.pid.output_min) + ", " +
                     Num(options.pid.output_max) + ": +" + Num(out.d_high) + " / -" + Num(out.d_low) +
                     " used" +
                     (high && low ? " (both sides cut)"
                      : high      ? " (the high side cut)"
                                  : " (the low side cut)");
  if (options.relay.bias != 0.0 && std::abs(out.d_high - out.d_low) <= slack)
    line += "; cut to a symmetric relay: its model needs clean extremes (the delay to them)";
  return line;
}

// A hold's drift is named past this fraction of the relay's oscillation.
constexpr double kHoldDriftOfAmplitude = 0.05;

// A drifting hold is doubled, episode by episode, up to this many times the
// hold given (RunExperiment).
constexpr double kMaxHoldGrowth = 16.0;

// The hold's drift and its note (ExperimentSummary::hold_drift).
void HoldDrift(double hold_s, ExperimentSummary* out) {
  const std::vector<RelaySample>& s = out->samples;
  const double from = out->relay_start_s - 0.5 * hold_s;
  double n = 0.0, st = 0.0, sy = 0.0;
  for (const RelaySample& k : s)
    if (k.t_s >= from && k.t_s < out->relay_start_s) n += 1.0, st += k.t_s, sy += k.y;
  out->hold_drift = 0.0;
  out->hold_note.clear();
  if (n < 8.0) return;
  const double tm = st / n, ym = sy / n;
  double stt = 0.0, sty = 0.0;
  for (const RelaySample& k : s)
    if (k.t_s >= from && k.t_s < out->relay_start_s)
      stt += (k.t_s - tm) * (k.t_s - tm), sty += (k.t_s - tm) * (k.y - ym);
  if (!(stt > 0.0)) return;
  const double slope = sty / stt;
  double ss = 0.0;
  for (const RelaySample& k : s)
    if (k.t_s >= from && k.t_s < out->relay_start_s) ss += std::pow(k.y - ym - slope * (k.t_s - tm), 2);
  const double se = std::sqrt(ss / (n - 2.0) / stt), half = 0.5 * hold_s;
  out->hold_drift = slope * half;
  // It matters against the noise, the band and the oscillation it centres.
  const double amplitude = out->cycles.empty() ? 0.0 : out->cycles.back().amplitude();
  const double floor = std::max({2.0 * out->noise_sigma, out->hysteresis, kHoldDriftOfAmplitude * amplitude,
                                 1e-9 * std::max(1.0, std::abs(out->y0))});
  if (!(std::abs(slope) > 4.0 * se) || !(std::abs(out->hold_drift) > floor)) return;
  out->hold_note = "the hold drifts or was disturbed: y moved " + Num(out->hold_drift) + " over its last " +
                   Num(half) + " s (" + Num(slope) + " per s, noise sigma " + Num(out->noise_sigma) +
                   "), so y0 " + Num(out->y0) +
                   " is no resting operating point and the relay's centre and the estimates are biased; a "
                   "longer --hold lets the process settle first";
}

// The time from the relay's start to its first switch (0: none).
double FirstSwitchAfter(const std::vector<RelaySample>& s, double relay_start_s) {
  for (std::size_t k = 1; k < s.size(); ++k)
    if (s[k - 1].t_s >= relay_start_s && s[k].u != s[k - 1].u) return s[k].t_s - relay_start_s;
  return 0.0;
}

// Where the relay has sat on one side since its last switch (no full cycle
// yet) and y has settled there: the last quarter of that stretch moves y by
// at most a tenth of its whole move there, and by no more than the noise
// allows (6 sigma). A process that has settled will not switch the relay by
// waiting longer. "" otherwise (y still moving: a longer window may do).
std::string StuckRelay(const ExperimentSummary& out) {
  const std::vector<RelaySample>& s = out.samples;
  std::size_t from = 0;
  double t_switch = out.relay_start_s, longest = 0.0;  // the longest stretch between switches before the last
  for (std::size_t k = 1; k < s.size(); ++k)
    if (s[k].t_s > out.relay_start_s && s[k].u != s[k - 1].u) {
      longest = std::max(longest, s[k].t_s - t_switch);
      t_switch = s[k].t_s;
      from = k;
    }
  if (from == 0) {  // no switch: from the relay's start
    while (from < s.size() && s[from].t_s < out.relay_start_s) ++from;
  }
  if (from + 8 >= s.size()) return "";
  const double e_from = s[from].y - out.y0, e_end = s.back().y - out.y0;
  const double move = e_end - e_from, t_from = s[from].t_s, span_s = s.back().t_s - t_from;
  // After a switch, y runs on its old course for the dead time, which is
  // shorter than the stretch before it (the process answered within it):
  // a stretch not twice that long may still be the old course settling.
  if (!(span_s >= 2.0 * longest)) return "";
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (std::size_t k = from; k < s.size(); ++k)
    if (s[k].t_s >= t_from + 0.75 * span_s) lo = std::min(lo, s[k].y), hi = std::max(hi, s[k].y);
  const double noise = 6.0 * out.noise_sigma;
  if (!(std::abs(move) > noise) || !(hi - lo <= std::max(0.1 * std::abs(move), noise))) return "";
  const bool high = s[from].u > out.u0;  // the relay pushes y up (a direct-acting process)
  const std::string side = high ? "high (u = u0 + " + Num(out.d_high) : "low (u = u0 - " + Num(out.d_low);
  const std::string moved = "with the relay " + side + ") for " + Num(span_s) + " s, y moved from " +
                            Num(s[from].y) + " to " + Num(s.back().y) + " and settled there";
  if ((move > 0.0) != high)
    return "the process acts in reverse: " + moved +
           ", away from its band; the relay needs a y that rises with u: for a reverse-acting process "
           "negate u or y at the process, or check the actuator's and the sensor's wiring";
  const double needed = std::abs((high ? out.hysteresis : -out.hysteresis) - e_from);
  // Both sides scale with the amplitude (d +- b, b a fraction of d or 0).
  const double amplitude = 0.5 * (out.d_high + out.d_low);
  return "the relay is too small to cross its band: " + moved + ", short of y0 " + (high ? "+ " : "- ") +
         Num(out.hysteresis) + " (the hysteresis); a relay amplitude of about " +
         Num(2.0 * amplitude * needed / std::abs(move)) + " (now " + Num(amplitude) + ") would cross it";
}

}  // namespace

Status AnalyzeRelayRecord(const ExperimentOptions& options, std::vector<RelaySample> samples,
                          ExperimentSummary* summary) {
  ExperimentSummary& out = *summary;
  if (samples.empty()) return Status::RunnerFailed("the relay episode gave no steps");
  RelayTuner tuner(options.relay, options.previous, options.pid);
  if (const Status st = ReplayRelay(options.relay, options.previous, options.pid, samples, &tuner); !st.ok())
    return st;
  out.end = tuner.phase();
  out.why = tuner.why();
  out.u0 = tuner.u0();
  out.y0 = tuner.y0();
  out.noise_sigma = tuner.noise_sigma();
  out.hysteresis = tuner.hysteresis();
  out.y_limit = options.relay.y_limit;
  out.d_high = tuner.d_high();
  out.d_low = tuner.d_low();
  out.relay_start_s = tuner.relay_start_s();
  out.end_s = tuner.end_s();
  out.horizon_s = samples.back().t_s;
  out.restarts = tuner.restarts();
  out.load_changes_s = tuner.load_changes_s();
  out.cycles = tuner.cycles();
  out.samples = std::move(samples);
  out.clipped = ClippedNote(options, out);
  out.hold_s = options.relay.hold_s;
  HoldDrift(options.relay.hold_s, &out);
  // A relay stuck on one side ends here, for the live run and its log alike.
  if (out.end == RelayPhase::kRelay && out.cycles.empty()) {
    if (std::string stuck = StuckRelay(out); !stuck.empty()) {
      out.end = RelayPhase::kAborted;
      out.why = std::move(stuck);
    }
  }
  return Status::Ok();
}

void EstimateFromRecord(const ExperimentOptions& options, ExperimentSummary* summary,
                        const ExperimentProgress& progress) {
  ExperimentSummary& out = *summary;
  const auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  out.relay.setpoint = out.y0;
  out.relay.u0 = out.u0;
  out.relay.d_high = out.d_high > 0.0 ? out.d_high : 1.0;
  out.relay.d_low = out.d_low > 0.0 ? out.d_low : 1.0;
  out.relay.hysteresis = out.hysteresis;
  out.relay.settled_cycles = options.relay.settled_cycles;
  out.relay.tolerance = options.relay.tolerance;
  if (out.end == RelayPhase::kDone) {
    // Under noise every settled cycle after the approach is averaged.
    RelayOptions averaged = out.relay;
    if (3.0 * out.noise_sigma > 0.01 * out.cycles.back().amplitude())
      averaged.settled_cycles = std::max(averaged.settled_cycles, static_cast<int>(out.cycles.size()) - 1);
    // A symmetric relay's model needs the delay to the extremes, which
    // noise hides: only where the extremes are clean.
    const bool clean = !(3.0 * out.noise_sigma > 0.01 * out.cycles.back().amplitude());
    const double delay = out.d_high == out.d_low && clean
                             ? ApparentDelay(out.samples, out.relay_start_s, 2 * averaged.settled_cycles)
                             : std::numeric_limits<double>::quiet_NaN();
    out.estimates = EstimateFromCycles(averaged, out.cycles, true, out.noise_sigma, delay);
    if (out.estimates.model_found)
      say("  estimates: period " + Num(out.estimates.period_s) + " +- " + Num(out.estimates.period_ci_s) +
          " s, Ku " + Num(out.estimates.ku) + " (describing function " +
          Num(out.estimates.ku_describing_function) + "), model K " + Num(out.estimates.model.gain) +
          (out.estimates.model.integrating ? std::string()
                                           : ", T " + Num(out.estimates.model.time_constant_s) + " s") +
          ", L " + Num(out.estimates.model.delay_s) + " s");
  }
}

Status RunExperiment(const ExperimentOptions& options, const RelayEpisodeRunner& runner,
                     ExperimentSummary* summary, const ExperimentProgress& progress) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  const auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  ExperimentSummary& out = *summary;
  out = ExperimentSummary{};
  double window = options.first_window_s;
  // The hold grows while it drifts (HoldDrift): doubled, up to
  // kMaxHoldGrowth times the one given, so the relay starts from rest.
  ExperimentOptions episode = options;
  for (;;) {
    const double horizon = episode.relay.hold_s + window;
    say("relay episode " + std::to_string(out.episodes + 1) + ": hold " + Num(episode.relay.hold_s) +
        " s, then up to " + Num(window) + " s of relay");
    std::vector<RelaySample> samples;
    if (const Status st = runner(episode.relay, horizon, &samples); !st.ok()) return st;
    ++out.episodes;
    if (const Status st = AnalyzeRelayRecord(episode, std::move(samples), &out); !st.ok()) return st;
    const double dt = out.samples.size() > 1 ? out.samples[1].t_s - out.samples[0].t_s : 0.0;
    say("  " + std::string(ToString(out.end)) + ": u0 " + Num(out.u0) + ", y0 " + Num(out.y0) +
        ", noise sigma " + Num(out.noise_sigma) + ", hysteresis " + Num(out.hysteresis) + ", " +
        std::to_string(out.cycles.size()) + " cycles" +
        (out.cycles.empty() ? std::string() : ", last period " + Num(out.cycles.back().period_s()) + " s") +
        (out.why.empty() ? std::string() : ": " + out.why));
    if (!out.clipped.empty() && out.episodes == 1) say("  " + out.clipped);
    if (!out.hold_note.empty()) say("  " + out.hold_note);
    if (!out.hold_note.empty() && episode.relay.hold_s > 0.0 &&
        2.0 * episode.relay.hold_s <= kMaxHoldGrowth * options.relay.hold_s * (1.0 + 1e-12)) {
      episode.relay.hold_s *= 2.0;
      say("  the hold drifts: the next episode holds " + Num(episode.relay.hold_s) + " s");
      continue;
    }
    if (out.end == RelayPhase::kDone || out.end == RelayPhase::kAborted) break;
    if (window >= options.max_window_s) {
      out.why = "the relay ran " + Num(window) + " s (the longest window, --max-time) without " +
                (out.cycles.empty() ? std::string("a single cycle: the process did not oscillate")
                                    : "converging (" + std::to_string(out.cycles.size()) + " cycles)");
      break;
    }
    double next = 2.0 * window;
    if (!out.cycles.empty()) {  // the timeout the last period sets, and a little more
      const double needed = options.relay.timeout_periods * out.cycles.back().period_s() + 2.0 * dt + 1e-9;
      if (needed > window) next = needed;
    } else if (const double first = FirstSwitchAfter(out.samples, out.relay_start_s); first > 0.0) {
      // No full cycle, but a switch: a period is at least twice the time to
      // it (the approach from rest to the band is shorter than a half
      // period's swing across it), so the timeout that period would set.
      next = std::max(next, options.relay.timeout_periods * 2.0 * first + 2.0 * dt + 1e-9);
    }
    if (out.end == RelayPhase::kHold) next = 2.0 * window;  // a restart's hold at the end
    window = std::min(next, options.max_window_s);
  }
  EstimateFromRecord(episode, &out, say);
  return Status::Ok();
}

}  // namespace pidlab::autotune
