#include "pidlab/replay/decoder_table.h"

#include <climits>
#include <exception>
#include <pidlab/lcmt_episode_config_v1.hpp>
#include <pidlab/lcmt_episode_config_v2.hpp>
#include <pidlab/lcmt_episode_config_v3.hpp>
#include <pidlab/lcmt_episode_config_v4.hpp>

#include "pidlab/transport/wire.h"

namespace pidlab::replay {
namespace {

template <typename Msg>
bool DecodeAs(const uint8_t* data, std::size_t size, Msg* m) {
  if (size > INT_MAX || !PayloadLayoutOk(Msg::getHash(), data, size)) return false;
  try {
    if (m->decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return false;
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

template <typename Msg>
bool Decode(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  Msg m{};
  if (!DecodeAs(data, size, &m)) return false;
  *message = std::move(m);
  return true;
}

// The fields every older configuration has (lcmt_episode_config_v1's) into
// *m.
template <typename Old>
void CopyCommonConfig(const Old& o, pidlab::lcmt_episode_config* out) {
  pidlab::lcmt_episode_config& m = *out;
  m.utime = o.utime;
  m.episode_id = o.episode_id;
  m.step = o.step;
  m.plant_name = o.plant_name;
  m.num_size = o.num_size;
  m.num = o.num;
  m.den_size = o.den_size;
  m.den = o.den;
  m.kp = o.kp;
  m.ki = o.ki;
  m.kd = o.kd;
  m.reference = o.reference;
  m.derivative_filter_s = o.derivative_filter_s;
  m.output_min = o.output_min;
  m.output_max = o.output_max;
  m.anti_windup = o.anti_windup;
  m.back_calculation_gain = o.back_calculation_gain;
  m.derivative_on = o.derivative_on;
  m.integral = o.integral;
  m.dt_s = o.dt_s;
  m.sample_time_s = o.sample_time_s;
  m.horizon_s = o.horizon_s;
  m.total_steps = o.total_steps;
  m.disturbance_kind = o.disturbance_kind;
  m.disturbance_amplitude = o.disturbance_amplitude;
  m.disturbance_period_s = o.disturbance_period_s;
  m.disturbance_phase_s = o.disturbance_phase_s;
  m.disturbance_step_time_s = o.disturbance_step_time_s;
  m.noise_hold_s = o.noise_hold_s;
  m.seed = o.seed;
  m.retransmit_interval_s = o.retransmit_interval_s;
  m.silence_deadline_s = o.silence_deadline_s;
  // Before the setpoint weights: the 1-DOF PID, its derivative on the
  // measurement being c = 0.
  m.setpoint_weight_b = 1.0;
  m.setpoint_weight_c = o.derivative_on == "measurement" ? 0.0 : 1.0;
}

// A configuration written before the motor's fields were appended: decoded
// with its own layout, read as an lcmt_episode_config of a linear plant (the
// motor's fields 0, motor_drive "", no delay).
bool DecodeConfigV1(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  pidlab::lcmt_episode_config_v1 o{};
  if (!DecodeAs(data, size, &o)) return false;
  pidlab::lcmt_episode_config m{};
  CopyCommonConfig(o, &m);
  *message = std::move(m);
  return true;
}

// The motor's fields of lcmt_episode_config_v2 and later into *m.
template <typename Old>
void CopyMotorConfig(const Old& o, pidlab::lcmt_episode_config* m) {
  m->motor_resistance_ohm = o.motor_resistance_ohm;
  m->motor_self_inductance_h = o.motor_self_inductance_h;
  m->motor_mutual_inductance_h = o.motor_mutual_inductance_h;
  m->motor_inertia_kg_m2 = o.motor_inertia_kg_m2;
  m->motor_rotor_teeth = o.motor_rotor_teeth;
  m->motor_viscous_friction = o.motor_viscous_friction;
  m->motor_tooth_pitch_rad = o.motor_tooth_pitch_rad;
  m->motor_stationary_current_a = o.motor_stationary_current_a;
  m->motor_flux_linkage = o.motor_flux_linkage;
  m->motor_detent_torque_nm = o.motor_detent_torque_nm;
  m->motor_load_torque_nm = o.motor_load_torque_nm;
  m->motor_load_step_nm = o.motor_load_step_nm;
  m->motor_load_step_time_s = o.motor_load_step_time_s;
  m->motor_voltage_limit_v = o.motor_voltage_limit_v;
  m->motor_input_scale = o.motor_input_scale;
  m->motor_abs_tolerance = o.motor_abs_tolerance;
  m->motor_rel_tolerance = o.motor_rel_tolerance;
  m->motor_drive = o.motor_drive;
}

// A configuration written before delay_s was appended: read as an
// lcmt_episode_config without a delay (delay_s 0), chirp or measurement
// noise.
bool DecodeConfigV2(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  pidlab::lcmt_episode_config_v2 o{};
  if (!DecodeAs(data, size, &o)) return false;
  pidlab::lcmt_episode_config m{};
  CopyCommonConfig(o, &m);
  CopyMotorConfig(o, &m);
  m.delay_s = 0.0;
  *message = std::move(m);
  return true;
}

// A configuration written before the chirp's band and the measurement noise
// were appended: read as an lcmt_episode_config with those 0 (no chirp, no
// noise on y).
bool DecodeConfigV3(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  pidlab::lcmt_episode_config_v3 o{};
  if (!DecodeAs(data, size, &o)) return false;
  pidlab::lcmt_episode_config m{};
  CopyCommonConfig(o, &m);
  CopyMotorConfig(o, &m);
  m.delay_s = o.delay_s;
  m.chirp_f0_hz = m.chirp_f1_hz = m.chirp_duration_s = 0.0;
  m.measurement_noise = 0.0;
  m.measurement_noise_seed = 0;
  *message = std::move(m);
  return true;
}

// A configuration written before the setpoint weights were appended: read
// as an lcmt_episode_config of the 1-DOF PID (CopyCommonConfig's b, c).
bool DecodeConfigV4(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  pidlab::lcmt_episode_config_v4 o{};
  if (!DecodeAs(data, size, &o)) return false;
  pidlab::lcmt_episode_config m{};
  CopyCommonConfig(o, &m);
  CopyMotorConfig(o, &m);
  m.delay_s = o.delay_s;
  m.chirp_f0_hz = o.chirp_f0_hz;
  m.chirp_f1_hz = o.chirp_f1_hz;
  m.chirp_duration_s = o.chirp_duration_s;
  m.measurement_noise = o.measurement_noise;
  m.measurement_noise_seed = o.measurement_noise_seed;
  *message = std::move(m);
  return true;
}

template <typename Msg>
MessageType Type(const char* name, const char* channel_suffix) {
  return MessageType{name, channel_suffix, Msg::getHash(), &Decode<Msg>};
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string MessageType::PrefixOf(const std::string& channel) const {
  return EndsWith(channel, channel_suffix) ? channel.substr(0, channel.size() - channel_suffix.size())
                                           : channel + "/";
}

DecoderTable::DecoderTable()
    : types_{
          Type<pidlab::lcmt_episode_config>("lcmt_episode_config", "EPISODE_CONFIG"),
          MessageType{"lcmt_episode_config", "EPISODE_CONFIG", pidlab::lcmt_episode_config_v1::getHash(),
                      &DecodeConfigV1},  // older logs
          MessageType{"lcmt_episode_config", "EPISODE_CONFIG", pidlab::lcmt_episode_config_v2::getHash(),
                      &DecodeConfigV2},  // logs written before the plant's dead time
          MessageType{"lcmt_episode_config", "EPISODE_CONFIG", pidlab::lcmt_episode_config_v3::getHash(),
                      &DecodeConfigV3},  // logs written before the chirp and the measurement noise
          MessageType{"lcmt_episode_config", "EPISODE_CONFIG", pidlab::lcmt_episode_config_v4::getHash(),
                      &DecodeConfigV4},  // logs written before the setpoint weights
          Type<pidlab::lcmt_ready>("lcmt_ready", "READY"),
          Type<pidlab::lcmt_plant_output>("lcmt_plant_output", "PLANT_OUTPUT"),
          Type<pidlab::lcmt_control_command>("lcmt_control_command", "CONTROL"),
          Type<pidlab::lcmt_disturbance_sample>("lcmt_disturbance_sample", "DISTURBANCE"),  // older logs
          Type<pidlab::lcmt_disturbance_block>("lcmt_disturbance_block", "DISTURBANCE_BLOCK"),
          Type<pidlab::lcmt_disturbance_request>("lcmt_disturbance_request", "DISTURBANCE_REQUEST"),
          Type<pidlab::lcmt_episode_summary>("lcmt_episode_summary", "SUMMARY"),
          Type<pidlab::lcmt_trajectory_request>("lcmt_trajectory_request", "TRAJECTORY_REQUEST"),
          Type<pidlab::lcmt_trajectory_chunk>("lcmt_trajectory_chunk", "TRAJECTORY"),
          Type<pidlab::lcmt_pacing_progress>("lcmt_pacing_progress",
                                             "PACING"),  // live figures: the SUMMARY's are final
          Type<pidlab::lcmt_tune_progress>("lcmt_tune_progress", "TUNE_PROGRESS"),  // a tuning's progress
      } {}

const MessageType* DecoderTable::Find(int64_t fingerprint) const {
  for (const MessageType& t : types_)
    if (t.fingerprint == fingerprint) return &t;
  return nullptr;
}

bool DecoderTable::NamedLikePidlab(const std::string& channel) const {
  for (const MessageType& t : types_)
    if (EndsWith(channel, t.channel_suffix)) return true;
  return false;
}

bool DecoderTable::Fingerprint(const uint8_t* data, std::size_t size, int64_t* fingerprint) {
  if (size < 8) return false;
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | data[i];
  *fingerprint = static_cast<int64_t>(h);
  return true;
}

bool PayloadLayoutOk(int64_t fingerprint, const uint8_t* data, std::size_t size) {
  // The transport's check: the same layouts, and the protocol's limits.
  return size <= INT_MAX && transport::WireLayoutOk(fingerprint, data, static_cast<int>(size));
}

}  // namespace pidlab::replay
