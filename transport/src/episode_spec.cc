#include "pidlab/transport/episode_spec.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"

namespace pidlab::transport {
namespace {

bool IsWholeMultiple(double x, double step, long* count) {
  const double ratio = x / step;
  const double r = std::round(ratio);
  if (!std::isfinite(ratio) || std::abs(ratio - r) > 1e-9 * std::max(1.0, r)) return false;
  *count = static_cast<long>(r);
  return true;
}

bool Fail(const std::string& what, std::string* error) {
  if (error) *error = what;
  return false;
}

std::string FormatDouble(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

enum class Direction { kToMessage, kFromMessage };

// The configuration's real numbers and where an EpisodeSpec keeps them, one
// line a field, for both MakeEpisodeConfig and ParseEpisodeConfig: a number
// appended to lcmt_episode_config and to EpisodeShape is one line here. (The
// names, the options spelled as strings, the integers and the motor's
// fields are converted beside it.)
void CopyNumbers(EpisodeSpec* s, pidlab::lcmt_episode_config* m, Direction direction) {
  const auto field = [direction](double& in_spec, double& in_message) {
    if (direction == Direction::kToMessage)
      in_message = in_spec;
    else
      in_spec = in_message;
  };
  field(s->plant.delay_s, m->delay_s);
  field(s->gains.kp, m->kp);
  field(s->gains.ki, m->ki);
  field(s->gains.kd, m->kd);
  field(s->reference, m->reference);
  field(s->pid.derivative_filter_s, m->derivative_filter_s);
  field(s->pid.output_min, m->output_min);
  field(s->pid.output_max, m->output_max);
  field(s->pid.back_calculation_gain, m->back_calculation_gain);
  field(s->pid.setpoint_weight_b, m->setpoint_weight_b);
  field(s->pid.setpoint_weight_c, m->setpoint_weight_c);
  field(s->pid.setpoint_filter_s, m->setpoint_filter_s);
  field(s->dt_s, m->dt_s);
  field(s->sample_time_s, m->sample_time_s);
  field(s->horizon_s, m->horizon_s);
  field(s->disturbance.amplitude, m->disturbance_amplitude);
  field(s->disturbance.period_s, m->disturbance_period_s);
  field(s->disturbance.phase_s, m->disturbance_phase_s);
  field(s->disturbance.step_time_s, m->disturbance_step_time_s);
  field(s->disturbance.noise_hold_s, m->noise_hold_s);
  field(s->disturbance.chirp_f0_hz, m->chirp_f0_hz);
  field(s->disturbance.chirp_f1_hz, m->chirp_f1_hz);
  field(s->disturbance.chirp_duration_s, m->chirp_duration_s);
  field(s->measurement_noise.sigma, m->measurement_noise);
  field(s->measurement_noise.resolution, m->measurement_resolution);
  field(s->recovery.retransmit_interval_s, m->retransmit_interval_s);
  field(s->recovery.silence_deadline_s, m->silence_deadline_s);
  field(s->relay_tune.hold_s, m->relay_hold_s);
  field(s->relay_tune.u0, m->relay_u0);
  field(s->relay_tune.amplitude, m->relay_amplitude);
  field(s->relay_tune.bias, m->relay_bias);
  field(s->relay_tune.hysteresis, m->relay_hysteresis);
  field(s->relay_tune.noise_multiple, m->relay_noise_multiple);
  field(s->relay_tune.y_limit, m->relay_y_limit);
  field(s->relay_tune.tolerance, m->relay_tolerance);
  field(s->relay_tune.timeout_periods, m->relay_timeout_periods);
}

}  // namespace

bool RecoveryOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(retransmit_interval_s > 0.0) || !std::isfinite(retransmit_interval_s)) {
    os << "retransmit interval " << retransmit_interval_s << " s must be positive and finite";
  } else if (!(silence_deadline_s > retransmit_interval_s) || !std::isfinite(silence_deadline_s)) {
    os << "silence deadline " << silence_deadline_s
       << " s must be finite and longer than the retransmit interval";
  } else {
    return true;
  }
  return Fail(os.str(), error);
}

bool EpisodeSpec::IsValid(std::string* error) const {
  if (episode_id == 0) return Fail("episode id 0 is reserved", error);
  if (plant.nonlinear && !plant.nonlinear->IsValid(error)) return false;
  if (!plant.tf.IsValid(error)) return false;
  if (plant.tf.RelativeDegree() < 1)
    return Fail("plant " + plant.tf.ToString() + " must be strictly proper", error);
  if (!GainsAreValid(gains, error)) return false;
  if (!std::isfinite(reference) || reference == 0.0 || std::abs(reference) > kMaxCoefficientMagnitude)
    return Fail("reference must be finite, nonzero and at most 1e12 in magnitude", error);
  std::ostringstream os;
  long samples = 0, steps = 0;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    os << "dt " << dt_s << " s must be positive and finite";
  else if (!(sample_time_s > 0.0) || !IsWholeMultiple(sample_time_s, dt_s, &samples) || samples < 1)
    os << "sample time " << sample_time_s << " s must be a whole multiple of dt " << dt_s << " s";
  else if (!(horizon_s > 0.0) || !IsWholeMultiple(horizon_s, sample_time_s, &samples) || samples < 1)
    os << "horizon " << horizon_s << " s must be a whole multiple of the sample time " << sample_time_s
       << " s";
  else if (!IsWholeMultiple(horizon_s, dt_s, &steps) || steps != total_steps)
    os << "total steps " << total_steps << " != horizon / dt";
  else if (total_steps > kMaxEpisodeSteps)
    os << "total steps " << total_steps << " is more than " << kMaxEpisodeSteps;
  else if (pid.dt_s != dt_s)
    os << "PID period " << pid.dt_s << " s differs from dt " << dt_s << " s";
  if (!os.str().empty()) return Fail(os.str(), error);
  if (plant.delay_s != 0.0) {
    if (plant.nonlinear) return Fail("delay_s on plant '" + plant.name + "' (a linear plant only)", error);
    try {
      SplitDelay(plant.delay_s, dt_s);
    } catch (const std::invalid_argument& e) {
      return Fail(std::string("delay_s: ") + e.what(), error);
    }
  }
  if (!pid.IsValid(error) || !disturbance.IsValid(error)) return false;
  std::string why;
  if (!measurement_noise.IsValid(&why)) return Fail("measurement_noise: " + why, error);
  if (disturbance.kind == DisturbanceKind::kChirp && !(disturbance.chirp_f1_hz < 0.5 / dt_s))
    return Fail("chirp_f1_hz " + FormatDouble(disturbance.chirp_f1_hz) +
                    " Hz is not below the Nyquist frequency 1/(2 dt_s)",
                error);
  if (relay) {
    std::string bad;
    if (!relay_tune.IsValid(&bad)) return Fail("relay: " + bad, error);
  }
  return recovery.IsValid(error);
}

pidlab::lcmt_episode_config MakeEpisodeConfig(const EpisodeSpec& spec) {
  pidlab::lcmt_episode_config m;
  m.utime = 0;
  m.episode_id = spec.episode_id;
  m.step = 0;
  m.plant_name = spec.plant.name;
  m.num = spec.plant.tf.num;
  m.num_size = static_cast<int32_t>(m.num.size());
  m.den = spec.plant.tf.den;
  m.den_size = static_cast<int32_t>(m.den.size());
  EpisodeSpec numbers = spec;
  CopyNumbers(&numbers, &m, Direction::kToMessage);
  m.anti_windup = ToString(spec.pid.anti_windup);
  // derivative_on "measurement" is c = 0, kept for older readers of the log.
  m.derivative_on =
      ToString(spec.pid.setpoint_weight_c == 0.0 ? DerivativeOn::kMeasurement : DerivativeOn::kError);
  m.integral = ToString(spec.pid.integral);
  m.total_steps = spec.total_steps;
  m.disturbance_kind = ToString(spec.disturbance.kind);
  m.seed = static_cast<int64_t>(spec.disturbance.seed);
  m.measurement_noise_seed = static_cast<int64_t>(spec.measurement_noise.seed);
  m.motor_resistance_ohm = m.motor_self_inductance_h = m.motor_mutual_inductance_h = 0.0;
  m.motor_inertia_kg_m2 = m.motor_rotor_teeth = m.motor_viscous_friction = m.motor_tooth_pitch_rad = 0.0;
  m.motor_stationary_current_a = m.motor_flux_linkage = m.motor_detent_torque_nm = 0.0;
  m.motor_load_torque_nm = m.motor_load_step_nm = m.motor_load_step_time_s = 0.0;
  m.motor_voltage_limit_v = m.motor_input_scale = m.motor_abs_tolerance = m.motor_rel_tolerance = 0.0;
  m.motor_drive = "";
  if (spec.plant.nonlinear) {
    const NonlinearStepperOptions& o = *spec.plant.nonlinear;
    const StepperMotorParameters& p = o.motor;
    m.motor_resistance_ohm = p.resistance_ohm;
    m.motor_self_inductance_h = p.self_inductance_h;
    m.motor_mutual_inductance_h = p.mutual_inductance_h;
    m.motor_inertia_kg_m2 = p.inertia_kg_m2;
    m.motor_rotor_teeth = p.rotor_teeth;
    m.motor_viscous_friction = p.viscous_friction;
    m.motor_tooth_pitch_rad = p.tooth_pitch_rad;
    m.motor_stationary_current_a = p.stationary_current_a;
    m.motor_flux_linkage = p.flux_linkage;
    m.motor_detent_torque_nm = o.detent_torque_nm;
    m.motor_load_torque_nm = o.load_torque_nm;
    m.motor_load_step_nm = o.load_step_nm;
    m.motor_load_step_time_s = o.load_step_time_s;
    m.motor_voltage_limit_v = o.voltage_limit_v;
    m.motor_input_scale = o.input_scale;
    m.motor_abs_tolerance = o.abs_tolerance;
    m.motor_rel_tolerance = o.rel_tolerance;
    m.motor_drive = o.microstep_table ? "microstep" : "linear";
  }
  m.controller_mode = spec.relay ? "relay" : "pid";
  m.relay_settled_cycles = spec.relay_tune.settled_cycles;
  m.relay_max_restarts = spec.relay_tune.max_restarts;
  if (!spec.relay) {  // the relay_ fields are 0 outside a relay episode
    m.relay_hold_s = m.relay_u0 = m.relay_amplitude = m.relay_bias = m.relay_hysteresis = 0.0;
    m.relay_noise_multiple = m.relay_y_limit = m.relay_tolerance = m.relay_timeout_periods = 0.0;
    m.relay_settled_cycles = m.relay_max_restarts = 0;
  }
  return m;
}

namespace {

// The motor of a stepper_nonlinear configuration: its options from the
// message, its linearisation recomputed here and checked against num/den.
bool ParseMotor(const pidlab::lcmt_episode_config& m, Plant* plant, std::string* error) {
  NonlinearStepperOptions o;
  StepperMotorParameters& p = o.motor;
  p.resistance_ohm = m.motor_resistance_ohm;
  p.self_inductance_h = m.motor_self_inductance_h;
  p.mutual_inductance_h = m.motor_mutual_inductance_h;
  p.inertia_kg_m2 = m.motor_inertia_kg_m2;
  p.rotor_teeth = m.motor_rotor_teeth;
  p.viscous_friction = m.motor_viscous_friction;
  p.tooth_pitch_rad = m.motor_tooth_pitch_rad;
  p.stationary_current_a = m.motor_stationary_current_a;
  p.flux_linkage = m.motor_flux_linkage;
  o.detent_torque_nm = m.motor_detent_torque_nm;
  o.load_torque_nm = m.motor_load_torque_nm;
  o.load_step_nm = m.motor_load_step_nm;
  o.load_step_time_s = m.motor_load_step_time_s;
  o.voltage_limit_v = m.motor_voltage_limit_v;
  o.input_scale = m.motor_input_scale;
  o.abs_tolerance = m.motor_abs_tolerance;
  o.rel_tolerance = m.motor_rel_tolerance;
  if (m.motor_drive != "linear" && m.motor_drive != "microstep")
    return Fail("motor drive '" + m.motor_drive + "' unknown (linear or microstep)", error);
  o.microstep_table = m.motor_drive == "microstep";
  if (const Status st = MakeNonlinearStepperPlant(o, plant); !st.ok())
    return Fail("motor: " + st.message(), error);
  // num/den are the linearisation the sender computed: the same code gives
  // the same numbers (to rounding on another machine).
  const auto close = [](const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!(std::abs(a[i] - b[i]) <= 1e-9 * std::max(std::abs(a[i]), std::abs(b[i])))) return false;
    return true;
  };
  if (!close(plant->tf.num, m.num) || !close(plant->tf.den, m.den))
    return Fail("plant num/den are not the motor's linearisation " + plant->tf.ToString(), error);
  return true;
}

}  // namespace

namespace {

// ParseEpisodeConfig() with the refusal's message in *error.
bool ParseEpisodeConfigOrExplain(const pidlab::lcmt_episode_config& m, EpisodeSpec* spec,
                                 std::string* error) {
  EpisodeSpec s;
  s.episode_id = m.episode_id;
  s.plant.name = m.plant_name;
  s.plant.tf.num = m.num;
  s.plant.tf.den = m.den;
  if (m.plant_name == "stepper_nonlinear") {
    if (!ParseMotor(m, &s.plant, error)) return false;
  } else if (!m.motor_drive.empty()) {
    return Fail("motor fields on plant '" + m.plant_name + "' (only stepper_nonlinear has a motor)", error);
  }
  // The numbers after the motor's plant is made (it sets the plant whole,
  // the dead time included); IsValid checks them.
  s.pid = PidOptionsAt(s.pid, m.dt_s);
  pidlab::lcmt_episode_config numbers = m;
  CopyNumbers(&s, &numbers, Direction::kFromMessage);
  s.total_steps = static_cast<long>(std::clamp<int64_t>(m.total_steps, -1, kMaxEpisodeSteps + 1));
  PidOptions& pid = s.pid;
  if (!ParseAntiWindup(m.anti_windup, &pid.anti_windup))
    return Fail("anti-windup '" + m.anti_windup + "' unknown", error);
  DerivativeOn derivative_on = DerivativeOn::kError;
  if (!ParseDerivativeOn(m.derivative_on, &derivative_on))
    return Fail("derivative-on '" + m.derivative_on + "' unknown", error);
  if (derivative_on == DerivativeOn::kMeasurement && m.setpoint_weight_c != 0.0)
    return Fail("derivative-on measurement with setpoint weight c = " + std::to_string(m.setpoint_weight_c) +
                    " (measurement is c = 0)",
                error);
  if (!ParseIntegralMethod(m.integral, &pid.integral))
    return Fail("integral '" + m.integral + "' unknown", error);
  if (!ParseDisturbanceKind(m.disturbance_kind, &s.disturbance.kind))
    return Fail("disturbance '" + m.disturbance_kind + "' unknown", error);
  s.disturbance.seed = static_cast<uint64_t>(m.seed);
  s.measurement_noise.seed = static_cast<uint64_t>(m.measurement_noise_seed);
  if (m.controller_mode == "relay") {
    s.relay = true;
    s.relay_tune.settled_cycles = static_cast<int>(std::clamp<int64_t>(m.relay_settled_cycles, -1, 1000));
    s.relay_tune.max_restarts = static_cast<int>(std::clamp<int64_t>(m.relay_max_restarts, -1, 1000));
  } else if (m.controller_mode != "" && m.controller_mode != "pid") {
    return Fail("controller mode '" + m.controller_mode + "' unknown (pid or relay)", error);
  }
  if (!s.IsValid(error)) return false;
  *spec = s;
  return true;
}

}  // namespace

Status ParseEpisodeConfig(const pidlab::lcmt_episode_config& m, EpisodeSpec* spec) {
  std::string why;
  if (!ParseEpisodeConfigOrExplain(m, spec, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::transport
