#include "spec_build.h"

#include <cmath>
#include <sstream>
#include <utility>

#include "pidlab/tune/model_file.h"

namespace pidlab::tune {

using spec::Quote;

static_assert(spec::kDefaultDesignPoints == kMultiStartDesignPoints,
              "the tuning spec's default design matches the multi-start's");

namespace {

// Sets *error and returns false: the one exit of every check below.
bool Bad(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

// A library's Status as this file's steps report it.
bool Into(const Status& st, std::string* error) { return st.ok() || Bad(error, st.message()); }

}  // namespace

namespace internal {

bool CheckNumber(const spec::Field& f, double v, NameStyle style, std::string* error) {
  const bool infinite_ok = f.Has(spec::kInfinite) && std::isinf(v);
  if (infinite_ok || (std::isfinite(v) && std::abs(v) <= spec::kMaxInputMagnitude)) return true;
  std::ostringstream os;
  os << spec::DisplayName(f.key, style) << " " << v << " is out of range: numbers must be finite and at most "
     << spec::kMaxInputMagnitude << " in magnitude";
  return Bad(error, os.str());
}

}  // namespace internal

bool BuildStepperParameters(const spec::PlantSpec& s, NameStyle style, StepperMotorParameters* out,
                            std::string* error) {
  const auto name = [style](const char* key) { return spec::DisplayName(key, style); };
  StepperMotorParameters sp;
  const std::pair<const char*, double*> table[] = {{"resistance_ohm", &sp.resistance_ohm},
                                                   {"self_inductance_h", &sp.self_inductance_h},
                                                   {"mutual_inductance_h", &sp.mutual_inductance_h},
                                                   {"inertia_kg_m2", &sp.inertia_kg_m2},
                                                   {"rotor_teeth", &sp.rotor_teeth},
                                                   {"viscous_friction", &sp.viscous_friction},
                                                   {"tooth_pitch_rad", &sp.tooth_pitch_rad},
                                                   {"stationary_current_a", &sp.stationary_current_a},
                                                   {"flux_linkage", &sp.flux_linkage}};
  for (const auto& [parameter, value] : s.stepper) {
    double* field = nullptr;
    for (const auto& [known, where] : table)
      if (parameter == known) field = where;
    if (!field) return Bad(error, name("stepper") + " parameter " + Quote(parameter) + " is unknown");
    *field = value;
  }
  if (!s.stepper.empty() && s.plant != "stepper_motor" && s.plant != "stepper" &&
      s.plant != "stepper_nonlinear")
    return Bad(error, name("stepper") + " overrides apply only to " + name("plant") +
                          " stepper_motor or stepper_nonlinear, not " + Quote(s.plant));
  if (!sp.IsValid(error)) return false;
  *out = sp;
  return true;
}

bool BuildNonlinearOptions(const spec::PlantSpec& s, NameStyle style, NonlinearStepperOptions* out,
                           std::string* error) {
  NonlinearStepperOptions o;
  if (!BuildStepperParameters(s, style, &o.motor, error)) return false;
  o.detent_torque_nm = s.detent_torque_nm;
  o.load_torque_nm = s.load_torque_nm;
  o.load_step_nm = s.load_step_nm;
  o.load_step_time_s = s.load_step_time_s;
  o.voltage_limit_v = s.voltage_limit_v;
  o.input_scale = s.input_scale;
  if (s.drive != "linear" && s.drive != "microstep")
    return Bad(error,
               spec::DisplayName("drive", style) + " " + Quote(s.drive) + " must be linear or microstep");
  o.microstep_table = s.drive == "microstep";
  if (!o.IsValid(error)) return false;
  *out = o;
  return true;
}

namespace {

// True when a stepper_nonlinear option differs from its default.
bool HasNonlinearOption(const spec::PlantSpec& s) {
  const spec::PlantSpec d;
  return s.detent_torque_nm != d.detent_torque_nm || s.load_torque_nm != d.load_torque_nm ||
         s.load_step_nm != d.load_step_nm || s.load_step_time_s != d.load_step_time_s ||
         s.voltage_limit_v != d.voltage_limit_v || s.input_scale != d.input_scale || s.drive != d.drive;
}

}  // namespace

namespace {

bool BuildPlantModel(const spec::PlantSpec& s, NameStyle style, Plant* out, std::string* error) {
  const auto name = [style](const char* key) { return spec::DisplayName(key, style); };
  const bool custom = !s.num.empty() || !s.den.empty();
  if (custom && !s.plant.empty() && s.plant != "custom")
    return Bad(error, name("plant") + " " + Quote(s.plant) + " cannot be combined with " + name("num") + "/" +
                          name("den") + " (use " + name("plant") + " custom or omit it)");
  if (custom) {
    if (s.num.empty() || s.den.empty())
      return Bad(error, "a custom plant needs both " + name("num") + " and " + name("den"));
    return Into(MakeCustomPlant(s.num, s.den, out), error);
  }
  if (s.plant.empty())
    return Bad(error, name("plant") + " is required (or " + name("num") + " and " + name("den") +
                          " for a custom plant)");
  if (s.plant == "custom")
    return Bad(error, name("plant") + " custom needs " + name("num") + " and " + name("den"));
  if (s.plant == "stepper_nonlinear") {
    NonlinearStepperOptions o;
    return BuildNonlinearOptions(s, style, &o, error) && Into(MakeNonlinearStepperPlant(o, out), error);
  }
  if (HasNonlinearOption(s))
    return Bad(error, name("detent_torque") + ", " + name("load_torque") + ", " + name("load_step") + ", " +
                          name("load_step_time") + ", " + name("voltage_limit") + ", " + name("input_scale") +
                          " and " + name("drive") + " apply only to " + name("plant") +
                          " stepper_nonlinear, not " + Quote(s.plant));
  StepperMotorParameters sp;
  if (!BuildStepperParameters(s, style, &sp, error)) return false;
  std::string path;
  if (IsModelPlant(s.plant, &path)) {
    if (path.empty()) return Bad(error, name("plant") + " " + Quote(s.plant) + " needs a file: model:FILE");
    if (const Status st = ReadModelFile(path, out); !st.ok())
      return Bad(error,
                 name("plant") + " " + Quote(s.plant) + ": model file " + Quote(path) + " " + st.message());
    return true;
  }
  // A plant name is printable and short, so Truncate leaves every valid one
  // as it is, and MakePlant's "unknown plant '...'" echoes at most 200 chars.
  return Into(MakePlant(spec::Truncate(s.plant), sp, out), error);
}

}  // namespace

bool BuildPlant(const spec::PlantSpec& typed, NameStyle style, Plant* out, std::string* error) {
  spec::PlantSpec s = typed;
  s.Normalize();
  if (!s.model.empty())
    return Bad(error, spec::DisplayName("model", style) + " " + Quote(s.model) + " cannot be combined with " +
                          spec::DisplayName("plant", style) + " " + Quote(s.plant));
  if (!CheckSpecNumbers(s, style, error)) return false;
  const std::string delay = spec::DisplayName("delay", style);
  if (!(s.delay_s >= 0.0) || !(s.delay_s <= kMaxDelaySeconds))
    return Bad(error, delay + " " + spec::FormatNumber(s.delay_s) + " s must be >= 0, finite and at most " +
                          spec::FormatNumber(kMaxDelaySeconds) + " s");
  if (IsModelPlant(s.plant) && s.delay_s != 0.0)
    return Bad(error, delay + " " + spec::FormatNumber(s.delay_s) +
                          " s: " + spec::DisplayName("plant", style) + " " + Quote(s.plant) +
                          " has its own dead time (the model's Td)");
  Plant p;
  if (!BuildPlantModel(s, style, &p, error)) return false;
  if (s.delay_s > 0.0 && p.nonlinear)
    return Bad(error, delay + " " + spec::FormatNumber(s.delay_s) +
                          " s: " + spec::DisplayName("plant", style) + " " + Quote(p.name) +
                          " with dead time is not supported yet");
  if (!p.model) p.delay_s = s.delay_s;
  *out = std::move(p);
  return true;
}

bool CheckPlantInLoop(const Plant& plant, const evaluation::LoopOptions& loop, NameStyle style,
                      std::string* error) {
  const Status st = evaluation::DelayIsValid(plant, loop, spec::DisplayName("delay", style));
  if (!st.ok() && error) *error = st.message();
  return st.ok();
}

bool BuildGains(const std::vector<double>& g, NameStyle style, PidGains* out, std::string* error) {
  if (g.size() != 3) {
    std::ostringstream os;
    os << spec::DisplayName("gains", style) << " ";
    for (std::size_t i = 0; i < g.size() && i < 8; ++i) os << (i ? "," : "") << g[i];
    if (g.size() > 8) os << ",...(" << g.size() << " numbers)";
    os << " must be three numbers KP,KI,KD";
    return Bad(error, os.str());
  }
  const PidGains gains{g[0], g[1], g[2]};
  if (!GainsAreValid(gains, error)) return false;
  *out = gains;
  return true;
}

namespace {

// A chirp's band and duration, named as the caller spells them.
bool CheckChirp(const spec::LoopSpec& s, NameStyle style, std::string* error) {
  const auto [f0, f1] = s.chirp_band;
  const std::string band =
      spec::DisplayName("chirp_band", style) + " " + spec::FormatNumber(f0) + "," + spec::FormatNumber(f1);
  if (s.loop != "sampled")
    return Bad(error, spec::DisplayName("disturbance", style) +
                          " 'chirp': the continuous loop cannot integrate a chirp exactly, use " +
                          spec::DisplayName("loop", style) + " sampled");
  if (!(f0 >= 0.0 && f0 < f1)) return Bad(error, band + " Hz must have 0 <= F0 < F1");
  if (!(f1 < 0.5 / s.dt_s))
    return Bad(error, band + " Hz: F1 must be below the Nyquist frequency 1/(2 dt) = " +
                          spec::FormatNumber(0.5 / s.dt_s) + " Hz");
  if (!(s.chirp_duration_s >= 0.0))
    return Bad(error, spec::DisplayName("chirp_duration", style) + " " +
                          spec::FormatNumber(s.chirp_duration_s) + " s must be >= 0 (0: the horizon)");
  return true;
}

bool BuildDisturbance(const spec::LoopSpec& s, NameStyle style, DisturbanceOptions* d, std::string* error) {
  if (s.disturbance.empty()) {
    d->kind = s.disturbance_amplitude != 0.0 ? DisturbanceKind::kSquare : DisturbanceKind::kNone;
  } else if (!ParseDisturbanceKind(s.disturbance, &d->kind)) {
    return Bad(error, spec::DisplayName("disturbance", style) + " " + Quote(s.disturbance) +
                          " must be none, square, step, sine, noise, prbs or chirp");
  }
  d->amplitude = s.disturbance_amplitude;
  d->period_s = s.disturbance_period_s;
  d->phase_s = s.disturbance_phase_s;
  d->step_time_s = s.disturbance_step_time_s;
  d->noise_hold_s = s.noise_hold_s;
  d->seed = s.seed;
  d->chirp_f0_hz = s.chirp_band.first;
  d->chirp_f1_hz = s.chirp_band.second;
  d->chirp_duration_s = s.chirp_duration_s == 0.0 ? s.horizon_s : s.chirp_duration_s;
  return d->kind != DisturbanceKind::kChirp || CheckChirp(s, style, error);
}

// The measurement noise: sigma >= 0 on the sampled loop, seeded by --seed.
bool BuildMeasurementNoise(const spec::LoopSpec& s, NameStyle style, MeasurementNoise* noise,
                           std::string* error) {
  const std::string name = spec::DisplayName("measurement_noise", style);
  const std::string value = name + " " + spec::FormatNumber(s.measurement_noise);
  if (!(s.measurement_noise >= 0.0)) return Bad(error, value + " must be >= 0");
  if (s.measurement_noise > 0.0 && s.loop != "sampled")
    return Bad(error,
               value + ": noise on the measured y needs " + spec::DisplayName("loop", style) + " sampled");
  noise->sigma = s.measurement_noise;
  noise->seed = s.seed;
  const std::string q =
      spec::DisplayName("measurement_resolution", style) + " " + spec::FormatNumber(s.measurement_resolution);
  if (!(s.measurement_resolution >= 0.0) || !std::isfinite(s.measurement_resolution))
    return Bad(error, q + " must be >= 0 and finite");
  if (s.measurement_resolution > 0.0 && s.loop != "sampled")
    return Bad(error, q + ": a quantised measured y needs " + spec::DisplayName("loop", style) + " sampled");
  noise->resolution = s.measurement_resolution;
  return true;
}

// b, c of the 2-DOF PID; derivative_on measurement is c = 0, the same code
// path (a c other than the default 1 next to it is refused).
bool BuildSetpointWeights(const spec::LoopSpec& s, DerivativeOn derivative_on, NameStyle style,
                          PidOptions* pid, std::string* error) {
  const auto [b, c] = s.setpoint_weights;
  const std::string name = spec::DisplayName("setpoint_weights", style);
  const std::string value = name + " " + spec::FormatNumber(b) + "," + spec::FormatNumber(c);
  if (!PidOptions::SetpointWeightIsValid(b) || !PidOptions::SetpointWeightIsValid(c))
    return Bad(error, value + ": each weight must be finite and in [0, 1]");
  pid->setpoint_weight_b = b;
  pid->setpoint_weight_c = c;
  if (!(s.setpoint_filter_s >= 0.0) || !std::isfinite(s.setpoint_filter_s))
    return Bad(error, spec::DisplayName("setpoint_filter", style) + " " +
                          spec::FormatNumber(s.setpoint_filter_s) + ": must be >= 0 and finite (s)");
  pid->setpoint_filter_s = s.setpoint_filter_s;
  if (derivative_on == DerivativeOn::kMeasurement) {
    if (c != 0.0 && c != 1.0)
      return Bad(error, value + ": " + spec::DisplayName("derivative_on", style) +
                            " measurement is c = 0; give one of the two");
    pid->setpoint_weight_c = 0.0;
  }
  return true;
}

bool BuildPidOptions(const spec::LoopSpec& s, NameStyle style, PidOptions* pid, std::string* error) {
  const auto name = [style](const char* key) { return spec::DisplayName(key, style); };
  pid->derivative_filter_s = s.derivative_filter_s;
  pid->output_min = s.output_limits.first;
  pid->output_max = s.output_limits.second;
  if (!ParseAntiWindup(s.anti_windup, &pid->anti_windup))
    return Bad(error, name("anti_windup") + " " + Quote(s.anti_windup) +
                          " must be none, clamping or back-calculation");
  DerivativeOn derivative_on = DerivativeOn::kError;
  if (!ParseDerivativeOn(s.derivative_on, &derivative_on))
    return Bad(error, name("derivative_on") + " " + Quote(s.derivative_on) + " must be error or measurement");
  if (!BuildSetpointWeights(s, derivative_on, style, pid, error)) return false;
  if (!ParseIntegralMethod(s.integral, &pid->integral))
    return Bad(error, name("integral") + " " + Quote(s.integral) +
                          " must be backward-euler, forward-euler or trapezoidal");
  return true;
}

}  // namespace

bool BuildLoopOptions(const spec::LoopSpec& s, NameStyle style, evaluation::LoopOptions* out,
                      std::string* error) {
  if (!CheckSpecNumbers(s, style, error)) return false;
  evaluation::LoopOptions o;
  if (!evaluation::ParseLoopKind(s.loop, &o.loop))
    return Bad(error,
               spec::DisplayName("loop", style) + " " + Quote(s.loop) + " must be continuous or sampled");
  o.dt_s = s.dt_s;
  o.sample_time_s = s.sample_time_s;
  o.horizon_s = s.horizon_s;
  o.stability_margin = s.stability_margin;
  o.reference = s.reference;
  o.derivative_filter_ratio = s.derivative_filter_ratio;
  if (!BuildDisturbance(s, style, &o.disturbance, error) || !BuildPidOptions(s, style, &o.pid, error) ||
      !BuildMeasurementNoise(s, style, &o.measurement_noise, error))
    return false;
  o.pid = PidOptionsAt(o.pid, o.dt_s);
  // A ratio's filter relative to the sample period (issue 40): at least dt.
  if (o.loop == evaluation::LoopKind::kSampled) o.derivative_filter_min_s = o.dt_s;
  if (!o.IsValid(error)) return false;
  *out = o;
  return true;
}

bool BuildBounds(const spec::BoundsSpec& s, NameStyle style, analysis::LoopBounds* out, std::string* error) {
  if (!CheckSpecNumbers(s, style, error)) return false;
  analysis::LoopBounds b;
  b.max_ms = s.max_ms;
  b.max_mt = s.max_mt;
  b.max_noise_gain = s.max_noise_gain;
  b.min_phase_margin_deg = s.min_phase_margin_deg;
  b.min_gain_margin = s.min_gain_margin;
  b.max_time_constant_s = s.max_time_constant_s;
  if (!b.IsValid(error)) return false;
  *out = b;
  return true;
}

namespace {

// A spread other than its default on a model whose draws come from its
// covariance (which no spread scales) is refused rather than ignored. The
// default passes, so that an echoed spec, which lists every field, runs again.
bool CheckSpreadOnModel(spec::PlantSpec plant, const char* key, double spread, double default_spread,
                        NameStyle style, std::string* error) {
  plant.Normalize();
  Plant p;
  if (!IsModelPlant(plant.plant) || spread == default_spread || !BuildPlant(plant, style, &p, nullptr) ||
      !analysis::DrawsFromCovariance(p))
    return true;
  return Bad(error, spec::DisplayName(key, style) + " " + spec::FormatNumber(spread) + ": " +
                        spec::DisplayName("plant", style) + " " + Quote(plant.plant) +
                        " is drawn from its parameter covariance, which no spread scales (leave " +
                        spec::DisplayName(key, style) + " at its default " +
                        spec::FormatNumber(default_spread) + ")");
}

}  // namespace

bool BuildMonteCarlo(const spec::EvaluateSpec& s, NameStyle style, analysis::MonteCarloOptions* out,
                     std::string* error) {
  const auto name = [style](const char* key) { return spec::DisplayName(key, style); };
  if (!CheckSpreadOnModel(s.plant, "spread", s.spread, spec::EvaluateSpec{}.spread, style, error))
    return false;
  if (s.monte_carlo < 0)
    return Bad(error, name("monte_carlo") + " " + std::to_string(s.monte_carlo) + " must be >= 0");
  if (!(s.spread >= 0.0) || !(s.spread < 1.0))
    return Bad(error, name("spread") + " " + spec::FormatNumber(s.spread) + " must be in [0, 1)");
  analysis::MonteCarloOptions mc;
  mc.samples = std::max(s.monte_carlo, 1);
  mc.spread = s.spread;
  mc.seed = s.loop.seed;
  std::string why;
  if (!mc.IsValid(&why))
    return Bad(error, name("spread") + " " + spec::FormatNumber(s.spread) + " / " + name("monte_carlo") +
                          ": " + why);
  *out = mc;
  return true;
}

void ResolveRobustPreset(spec::TuningSpec* s, const std::set<std::string>& given) {
  if (!s->tune.robust) return;
  const auto kept = [&given](const char* key) { return given.count(key) > 0; };
  if (!kept("objective")) s->tune.objective = ToString(evaluation::ObjectiveKind::kSetpointLoad);
  if (!kept("load_weight")) s->tune.load_weight = RobustPreset::kLoadWeight;
  if (!kept("derivative_filter") && !kept("derivative_filter_ratio")) {
    s->loop.derivative_filter_s = 0.0;
    s->loop.derivative_filter_ratio = RobustPreset::kFilterRatio;
  }
  if (!kept("max_ms")) s->bounds.max_ms = RobustPreset::kMaxMs;
  if (!kept("max_time_constant"))
    s->bounds.max_time_constant_s = RobustPreset::kTimeConstantFraction * s->loop.horizon_s;
}

namespace {

bool BuildSearch(const spec::TuneSpec& t, NameStyle style, TuneOptions* o, std::string* error) {
  const auto name = [style](const char* key) { return spec::DisplayName(key, style); };
  if (!ParseTuneMethod(t.method, &o->method))
    return Bad(
        error,
        name("method") + " " + Quote(t.method) +
            " must be multi-start, nelder-mead, paper-nm, ziegler-nichols, ga, pso-gsa, simc, amigo, migo or "
            "optimal");
  if (!evaluation::ParseObjectiveKind(t.objective, &o->objective))
    return Bad(error, name("objective") + " " + Quote(t.objective) +
                          " must be iae, ise, itae, iae-continuous, load-iae or setpoint-load");
  if (!(t.load_weight >= 0.0))
    return Bad(error, name("load_weight") + " " + spec::FormatNumber(t.load_weight) + " must be >= 0");
  o->load_weight = t.load_weight;
  if (!ParseZieglerNicholsRule(t.zn_rule, &o->zn_rule))
    return Bad(error, name("zn_rule") + " " + Quote(t.zn_rule) +
                          " must be classic, pessen, some-overshoot or no-overshoot");
  if (!ParseRuleForm(t.rule, &o->rule))
    return Bad(error, name("rule") + " " + Quote(t.rule) + " must be pi or pid");
  if (t.refine != "ceres" && t.refine != "none")
    return Bad(error, name("refine") + " " + Quote(t.refine) + " must be ceres or none");
  o->refine = t.refine == "ceres";
  o->lower = t.bounds.first;
  o->upper = t.bounds.second;
  o->max_iterations = t.max_iter;
  o->max_evaluations = t.max_evals;
  o->starts = t.starts;
  o->design_points = t.design_points;
  o->refine_starts = t.refine_starts;
  o->adaptive = t.adaptive;
  o->two_dof = t.two_dof;
  o->robustness_ms = t.robustness;
  o->response_time_s = t.response_time_s;
  o->tau_c_s = t.tau_c_s;
  if (!(t.crossover_rad_s >= 0.0) || !std::isfinite(t.crossover_rad_s))
    return Bad(error, name("crossover") + " " + spec::FormatNumber(t.crossover_rad_s) +
                          " must be >= 0 and finite (rad/s)");
  if (t.crossover_rad_s > 0.0 && t.response_time_s > 0.0)
    return Bad(error, name("crossover") + " " + spec::FormatNumber(t.crossover_rad_s) + " and " +
                          name("response_time") + " " + spec::FormatNumber(t.response_time_s) +
                          " say the same thing twice: give one");
  if (t.crossover_rad_s > 0.0) o->response_time_s = 2.0 / t.crossover_rad_s;
  if (!(t.tau_c_s >= 0.0) || !std::isfinite(t.tau_c_s))
    return Bad(error, name("tau_c") + " " + spec::FormatNumber(t.tau_c_s) + " must be >= 0 and finite (s)");
  const bool phase_margin = t.robustness >= kMigoMinPhaseMarginDeg && t.robustness <= kMigoMaxPhaseMarginDeg;
  if (!(t.robustness > 1.0 && t.robustness <= 4.0) && !phase_margin)
    return Bad(error, name("robustness") + " " + spec::FormatNumber(t.robustness) +
                          " must be an Ms bound in (1, 4] or a phase margin in [20, 80] deg");
  if (phase_margin) o->robustness_ms = kMigoDefaultMs, o->robustness_phase_margin_deg = t.robustness;
  if (!(t.response_time_s >= 0.0) || !std::isfinite(t.response_time_s))
    return Bad(error, name("response_time") + " " + spec::FormatNumber(t.response_time_s) +
                          " must be >= 0 and finite (s)");
  o->max_overshoot_pct = t.max_overshoot_pct;
  o->max_settling_time_s = t.max_settling_s;
  o->agree_tolerance = t.agree_tolerance;
  if (t.robust_samples < 0 || t.robust_samples > 10000)
    return Bad(error,
               name("robust_samples") + " " + std::to_string(t.robust_samples) + " must be in [0, 10000]");
  if (!(t.robust_spread >= 0.0) || !(t.robust_spread < 1.0))
    return Bad(error,
               name("robust_spread") + " " + spec::FormatNumber(t.robust_spread) + " must be in [0, 1)");
  if (!(t.robust_quantile > 0.0) || !(t.robust_quantile <= 1.0))
    return Bad(error,
               name("robust_quantile") + " " + spec::FormatNumber(t.robust_quantile) + " must be in (0, 1]");
  o->robust_samples = t.robust_samples;
  o->robust_spread = t.robust_spread;
  o->robust_quantile = t.robust_quantile;
  return true;
}

}  // namespace

bool BuildTuneOptions(const spec::TuningSpec& s, NameStyle style, TuneOptions* out, std::string* error) {
  TuneOptions o;
  if (!CheckSpecNumbers(s.tune, style, error) || !BuildLoopOptions(s.loop, style, &o.loop, error) ||
      !BuildSearch(s.tune, style, &o, error) || !BuildBounds(s.bounds, style, &o.bounds, error) ||
      !BuildStepperParameters(s.plant, style, &o.stepper, error) ||
      !CheckSpreadOnModel(s.plant, "robust_spread", s.tune.robust_spread, spec::TuneSpec{}.robust_spread,
                          style, error))
    return false;
  // The tuner's objective runs the noise-free loop: a noisy y would make the
  // IAE a random variable the search cannot minimise (evaluate and the trio
  // take it; docs/identify.md).
  if (o.loop.measurement_noise.resolution != 0.0)
    return Bad(error,
               spec::DisplayName("measurement_resolution", style) + " " +
                   spec::FormatNumber(s.loop.measurement_resolution) +
                   ": tune does not take a quantised measurement (evaluate and launch experiments do)");
  if (o.loop.measurement_noise.sigma != 0.0)
    return Bad(error, spec::DisplayName("measurement_noise", style) + " " +
                          spec::FormatNumber(s.loop.measurement_noise) +
                          ": tune does not take measurement noise (evaluate and launch experiments do)");
  o.seed = s.loop.seed;
  if (!o.IsValid(error)) return false;
  *out = o;
  return true;
}

}  // namespace pidlab::tune
