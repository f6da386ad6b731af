// See time_scale.h.
#include "pidlab/tune/time_scale.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/spec/field.h"
#include "pidlab/tune/design.h"
#include "pidlab/tune/problem.h"
#include "spec_build.h"

namespace pidlab::tune {

namespace {

// TimeScaleScope::kFigure's frame of `t` (see there).
// On the sampled loop (dt_s > 0) the frame stays on its grid (OnSampledGrid).
TimeScale Framed(const Plant& plant, const std::vector<PidGains>& gains, evaluation::LoopOptions loop,
                 double dt_s, const TimeScale& t, const KnownEvaluation& known) {
  loop.horizon_s = t.horizon_s;
  loop.sample_time_s = t.sample_time_s;
  double settling = 0.0;
  for (const PidGains& g : gains) {
    evaluation::Evaluation ev;
    const evaluation::Evaluation* e = &ev;
    if (known.Matches(g, loop)) {
      e = known.evaluation;
    } else {
      evaluation::EvaluateOptions what;
      what.compute_iae_continuous = false;
      if (!evaluation::Evaluate(plant, g, loop, what, &ev).ok()) return t;
    }
    if (!e->step.valid || !std::isfinite(e->step.settling_time_s)) return t;
    settling = std::max(settling, e->step.settling_time_s);
  }
  const double horizon = NiceUp(3.0 * settling + plant.delay_s);
  if (!(settling > 0.0) || !(horizon < t.horizon_s)) return t;
  TimeScale f = t;
  f.horizon_s = horizon;
  while (f.sample_time_s > horizon / 500.0 && horizon / f.sample_time_s < 20000.0) f.sample_time_s /= 2.0;
  OnSampledGrid(dt_s, &f.sample_time_s, &f.horizon_s);
  f.reason = "framed for the figure: 3 x the 2 % settling time " + spec::FormatNumber(settling) +
             " s, rounded up, of " + t.reason;
  return f;
}

}  // namespace

void OnSampledGrid(double dt_s, double* sample_time_s, double* horizon_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  *sample_time_s = dt_s * std::max(1.0, std::round(*sample_time_s / dt_s));
  *horizon_s = *sample_time_s * std::ceil(*horizon_s / *sample_time_s - 1e-9);
}

bool KnownEvaluation::Matches(const PidGains& g, const evaluation::LoopOptions& l) const {
  if (!gains || !loop || !evaluation) return false;
  const double a[] = {g.kp, g.ki, g.kd, g.tf}, b[] = {gains->kp, gains->ki, gains->kd, gains->tf};
  const std::vector<double> x = evaluation::LoopOptionsKey(l), y = evaluation::LoopOptionsKey(*loop);
  return std::memcmp(a, b, sizeof a) == 0 && x.size() == y.size() &&
         std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0;
}

TimeScale GainsTimeScale(const Plant& plant, const std::vector<PidGains>& gains,
                         const evaluation::LoopOptions& loop) {
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  double loop_slowest = 0.0, loop_fastest = fastest;
  bool analysed = false;
  for (const PidGains& g : gains) {
    analysis::LoopAnalysis a;
    if (plant.nonlinear || !analysis::AnalyzeLoop(plant, g, loop, analysis::LoopAnalysisOptions{}, &a).ok() ||
        !a.stable || !std::isfinite(a.slowest_time_constant_s) || !(a.slowest_time_constant_s > 0.0))
      continue;
    analysed = true;
    loop_slowest = std::max(loop_slowest, a.slowest_time_constant_s);
    if (a.gain_crossover_rad_s > 0.0 && std::isfinite(a.gain_crossover_rad_s))
      loop_fastest = std::min(loop_fastest, 1.0 / a.gain_crossover_rad_s);
  }
  TimeScale t = analysed ? LoopTimeScale(loop_fastest, loop_slowest, plant.delay_s)
                         : LoopTimeScale(fastest, slowest, plant.delay_s);
  t.reason = (analysed ? std::string("the closed loop of the gains: ") : "the plant's own time constants: ") +
             t.reason;
  return t;
}

TimeScale ResolveGainsTimeScale(const spec::PlantSpec& plant_spec, const Plant& plant,
                                const std::vector<PidGains>& gains, const std::set<std::string>& given,
                                TimeScaleScope scope, spec::LoopSpec* loop, const KnownEvaluation& known) {
  const bool paper = IsPaperPlant(plant_spec);
  TimeScale t;
  t.horizon_s = loop->horizon_s;
  t.sample_time_s = loop->sample_time_s;
  const spec::LoopSpec defaults;
  const bool eq4 = loop->horizon_s == defaults.horizon_s && loop->sample_time_s == defaults.sample_time_s;
  t.source = paper && eq4 ? "eq. (4)" : "given";
  t.reason = paper && eq4 ? "the paper's eq. (4): n = 25 s, ts = 0.05 s" : "given";
  evaluation::LoopOptions options;
  std::string error;
  const bool timed = given.count("horizon") > 0 || given.count("sample_time") > 0;
  if ((paper && scope == TimeScaleScope::kNotPaper) || (timed && scope == TimeScaleScope::kFigure) ||
      plant.nonlinear)
    return t;
  if (!BuildLoopOptions(*loop, spec::NameStyle::kKey, &options, &error)) {
    // The sampled loop at a dt that eq. (4)'s spacing is no multiple of
    // (dt = 1 s on a thermal plant): the loop is analysed at the spacing dt,
    // which the derived time scale then replaces.
    const bool sampled_default = !timed && loop->loop == "sampled" && loop->dt_s > 0.0;
    spec::LoopSpec probe = *loop;
    probe.sample_time_s = loop->dt_s;
    probe.horizon_s = loop->dt_s * std::ceil(loop->horizon_s / loop->dt_s - 1e-9);
    if (!sampled_default || !BuildLoopOptions(probe, spec::NameStyle::kKey, &options, &error))
      return t;  // (a loop that does not build is reported by its caller)
  }
  TimeScale derived = GainsTimeScale(plant, gains, options);
  const double dt_s = loop->loop == "sampled" ? loop->dt_s : 0.0;
  OnSampledGrid(dt_s, &derived.sample_time_s, &derived.horizon_s);
  if (scope == TimeScaleScope::kFigure) derived = Framed(plant, gains, options, dt_s, derived, known);
  if (timed) {
    // Given as the loop gives them (a result's echo): the loop's still.
    const bool same = loop->horizon_s == derived.horizon_s && loop->sample_time_s == derived.sample_time_s;
    return same ? derived : t;
  }
  loop->horizon_s = derived.horizon_s;
  loop->sample_time_s = derived.sample_time_s;
  return derived;
}

namespace {

// The 1-2-5 value at most x (up: at least x).
double OneTwoFive(double x, bool up) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  const double steps[] = {1.0, 2.0, 5.0, 10.0};
  if (up) {
    for (double m : steps)
      if (m * decade >= x * (1 - 1e-12)) return m * decade;
  }
  double best = decade;
  for (double m : steps)
    if (m * decade <= x * (1 + 1e-12)) best = m * decade;
  return best;
}

}  // namespace

double SampledDtFromPlant(const Plant& plant, std::string* why) {
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  const double l = plant.delay_s;
  const double base = l > 0.0 ? std::min(l, fastest) : fastest;
  double dt = OneTwoFive(base / kDtPerFastestTime, false);
  std::string reason = "min(L, the plant's fastest time " + spec::FormatNumber(fastest) + " s) / " +
                       spec::FormatNumber(kDtPerFastestTime) + ", a 1-2-5 value";
  if (l > 0.0 && std::ceil(l / dt - 1e-9) > static_cast<double>(evaluation::kMaxAnalysedDelaySteps)) {
    dt = OneTwoFive(l / static_cast<double>(evaluation::kMaxAnalysedDelaySteps), true);
    reason = "L / " + std::to_string(evaluation::kMaxAnalysedDelaySteps) +
             " (the delay line the analysis takes), a 1-2-5 value";
  }
  if (why) *why = "dt " + spec::FormatNumber(dt) + " s: " + reason + " (give --dt to choose)";
  return dt;
}

std::string SampledDtFromSpec(spec::EvaluateSpec* s, std::set<std::string>* given) {
  spec::LoopSpec continuous = s->loop;
  continuous.loop = "continuous";
  continuous.measurement_noise = 0.0;
  Plant plant;
  evaluation::LoopOptions loop;
  std::string line;
  if (given->count("dt") || IsPaperPlant(s->plant) ||
      !BuildPlantInLoop(s->plant, continuous, spec::NameStyle::kFlag, &plant, &loop).ok() || plant.nonlinear)
    return line;
  s->loop.dt_s = SampledDtFromPlant(plant, &line);
  given->insert("dt");
  double sample_time = s->loop.sample_time_s, horizon = s->loop.horizon_s;
  OnSampledGrid(s->loop.dt_s, &sample_time, &horizon);
  if (!given->count("sample_time")) s->loop.sample_time_s = sample_time;
  if (!given->count("horizon")) s->loop.horizon_s = horizon;
  return line;
}

double RelayYLimitFromPlant(const Plant& plant, double d, double noise_sigma, std::string* why) {
  const double widen = noise_sigma > 0.0 ? kRelayYLimitSigmas * noise_sigma : 0.0;
  const std::string set =
      (widen > 0.0 ? ", widened by " + spec::FormatNumber(kRelayYLimitSigmas) +
                         " sigma of the measurement noise " + spec::FormatNumber(noise_sigma)
                   : std::string()) +
      " (give --y-limit to choose, inf for none)";
  if (plant.nonlinear || plant.tf.num.empty() || plant.tf.den.size() < 2) {
    if (why) *why = "no y limit: plant " + plant.name + " is not linear" + set;
    return std::numeric_limits<double>::infinity();
  }
  Plant forward = plant;
  const double dc = plant.tf.DcGain();
  if (dc < 0.0 || (std::isinf(dc) && plant.tf.num.back() * plant.tf.den[plant.tf.den.size() - 2] < 0.0))
    for (double& n : forward.tf.num) n = -n;
  double w180 = 0.0;
  const double ku = UltimateGain(forward, &w180);
  if (std::isfinite(ku) && ku > 0.0) {
    const double a = 4.0 * d / (M_PI * ku);
    if (why)
      *why = "y limit " + spec::FormatNumber(kRelayYLimitAmplitudes * a + widen) +
             " from the hold's level: " + spec::FormatNumber(kRelayYLimitAmplitudes) +
             " x the relay's expected amplitude 4 d / (pi Ku) = " + spec::FormatNumber(a) + " (d " +
             spec::FormatNumber(d) + ", Ku " + spec::FormatNumber(ku) + " at " + spec::FormatNumber(w180) +
             " rad/s)" + set;
    return kRelayYLimitAmplitudes * a + widen;
  }
  if (std::isfinite(dc) && dc != 0.0) {
    const double span = 2.0 * std::abs(dc) * d + widen;
    if (why)
      *why = "y limit " + spec::FormatNumber(span) +
             " from the hold's level: 2 x the static response |K| d (K " + spec::FormatNumber(dc) + ", d " +
             spec::FormatNumber(d) + "; no ultimate gain)" + set;
    return span;
  }
  if (why) *why = "no y limit: plant " + plant.name + " has no ultimate gain and no finite static gain" + set;
  return std::numeric_limits<double>::infinity();
}

}  // namespace pidlab::tune
