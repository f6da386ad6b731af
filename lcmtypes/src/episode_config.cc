#include "pidlab/lcm/episode_config.h"

#include <cmath>
#include <sstream>

namespace pidlab::lcm_trio {
namespace {
// The plant keeps the whole trajectory (3 doubles a step) for resends.
constexpr int64_t kMaxTotalSteps = 50000000;
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
  if (error) *error = os.str();
  return false;
}

pidlab::lcmt_episode_config MakeEpisodeConfig(int64_t episode_id, const Plant& plant, const PidGains& gains,
                                              const LoopOptions& options,
                                              const DisturbanceOptions& disturbance,
                                              const RecoveryOptions& recovery) {
  pidlab::lcmt_episode_config m;
  m.utime = 0;
  m.episode_id = episode_id;
  m.step = 0;
  m.plant_name = plant.name;
  m.num = plant.tf.num;
  m.num_size = static_cast<int32_t>(m.num.size());
  m.den = plant.tf.den;
  m.den_size = static_cast<int32_t>(m.den.size());
  m.kp = gains.kp;
  m.ki = gains.ki;
  m.kd = gains.kd;
  m.reference = 1.0;
  const PidOptions& pid = options.pid;
  m.derivative_filter_s = pid.derivative_filter_s;
  m.output_min = pid.output_min;
  m.output_max = pid.output_max;
  m.anti_windup = ToString(pid.anti_windup);
  m.back_calculation_gain = pid.back_calculation_gain;
  m.derivative_on = ToString(pid.derivative_on);
  m.integral = ToString(pid.integral);
  m.dt_s = options.dt_s;
  m.sample_time_s = options.sample_time_s;
  m.horizon_s = options.horizon_s;
  m.total_steps = options.TotalSteps();
  m.disturbance_kind = ToString(disturbance.kind);
  m.disturbance_amplitude = disturbance.amplitude;
  m.disturbance_period_s = disturbance.period_s;
  m.disturbance_phase_s = disturbance.phase_s;
  m.disturbance_step_time_s = disturbance.step_time_s;
  m.noise_hold_s = disturbance.noise_hold_s;
  m.seed = static_cast<int64_t>(disturbance.seed);
  m.retransmit_interval_s = recovery.retransmit_interval_s;
  m.silence_deadline_s = recovery.silence_deadline_s;
  return m;
}

bool ParseEpisodeConfig(const pidlab::lcmt_episode_config& m, EpisodeSpec* spec, std::string* error) {
  auto fail = [error](const std::string& what) {
    if (error) *error = what;
    return false;
  };
  if (m.episode_id == 0) return fail("episode id 0 is reserved");
  EpisodeSpec s;
  s.episode_id = m.episode_id;
  s.plant.name = m.plant_name;
  s.plant.tf.num = m.num;
  s.plant.tf.den = m.den;
  if (!s.plant.tf.IsValid(error)) return false;
  if (s.plant.tf.RelativeDegree() < 1)
    return fail("plant " + s.plant.tf.ToString() + " must be strictly proper");
  s.gains = PidGains{m.kp, m.ki, m.kd};
  if (!GainsAreValid(s.gains, error)) return false;
  if (!std::isfinite(m.reference)) return fail("reference must be finite");
  s.reference = m.reference;
  LoopOptions& o = s.options;
  o.loop = LoopKind::kSampled;
  o.dt_s = m.dt_s;
  o.sample_time_s = m.sample_time_s;
  o.horizon_s = m.horizon_s;
  o.pid.dt_s = m.dt_s;
  o.pid.derivative_filter_s = m.derivative_filter_s;
  o.pid.output_min = m.output_min;
  o.pid.output_max = m.output_max;
  o.pid.back_calculation_gain = m.back_calculation_gain;
  if (!ParseAntiWindup(m.anti_windup, &o.pid.anti_windup))
    return fail("anti-windup '" + m.anti_windup + "' unknown");
  if (!ParseDerivativeOn(m.derivative_on, &o.pid.derivative_on))
    return fail("derivative-on '" + m.derivative_on + "' unknown");
  if (!ParseIntegralMethod(m.integral, &o.pid.integral)) return fail("integral '" + m.integral + "' unknown");
  DisturbanceOptions& d = o.disturbance;
  if (!ParseDisturbanceKind(m.disturbance_kind, &d.kind))
    return fail("disturbance '" + m.disturbance_kind + "' unknown");
  d.amplitude = m.disturbance_amplitude;
  d.period_s = m.disturbance_period_s;
  d.phase_s = m.disturbance_phase_s;
  d.step_time_s = m.disturbance_step_time_s;
  d.noise_hold_s = m.noise_hold_s;
  d.seed = static_cast<uint64_t>(m.seed);
  if (!o.IsValid(error)) return false;
  if (m.total_steps != o.TotalSteps()) {
    std::ostringstream os;
    os << "total steps " << m.total_steps << " != horizon / dt = " << o.TotalSteps();
    return fail(os.str());
  }
  if (m.total_steps > kMaxTotalSteps) {
    std::ostringstream os;
    os << "total steps " << m.total_steps << " is more than " << kMaxTotalSteps;
    return fail(os.str());
  }
  s.total_steps = static_cast<long>(m.total_steps);
  s.recovery.retransmit_interval_s = m.retransmit_interval_s;
  s.recovery.silence_deadline_s = m.silence_deadline_s;
  if (!s.recovery.IsValid(error)) return false;
  *spec = s;
  return true;
}

}  // namespace pidlab::lcm_trio
