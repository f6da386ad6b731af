// The relay autotune's state machine (relay.h).

#include "pidlab/controller/relay.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pidlab {
namespace {

std::string Num(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

double Clip(double u, double lo, double hi) { return std::min(std::max(u, lo), hi); }

// Fixed point: floor(x + 0.5) clamped to [lo, hi], as the exported relay's
// pidlab_relay_round does it.
std::int64_t RoundClamp(double x, double lo, double hi) {
  const double r = std::floor(x + 0.5);
  return static_cast<std::int64_t>(r < lo ? lo : (r > hi ? hi : r));
}

// The second differences' scale: 2^shift grid units (q31's 2^33 would
// overflow their squares' sum).
int DiffShift(int q_bits) { return q_bits > 23 ? q_bits - 23 : 0; }

std::int64_t ShiftRound(std::int64_t d, int shift) {
  if (shift == 0) return d;
  const std::int64_t half = std::int64_t{1} << (shift - 1);
  return d >= 0 ? (d + half) >> shift : -((-d + half) >> shift);
}

// The abort of a relay with no room around u0 within the output range.
std::string NoRoom(double u0, double out_min, double out_max) {
  return "no room for a relay around u0 = " + Num(u0) + " within the output range [" + Num(out_min) + ", " +
         Num(out_max) + "]";
}

// The relay that cannot beat the noise: e is smoothed by f += (e - f) /
// 2^kQuietShift (a 16-sample lag; its noise is 0.18 sigma). A cycle of at
// least kQuietMinSteps steps is quiet when its smoothed e's half range
// stays under kQuietFraction of the hysteresis: its switches came from the
// noise, not from the oscillation. Under noise (sigma > 0), kQuietCycles
// quiet cycles in a row end the relay, naming the smoothed amplitude, the
// hysteresis and the relay amplitude that would beat it. The lag passes a
// real oscillation of kQuietMinSteps samples at 0.79 of its amplitude (at
// least the hysteresis), above kQuietFraction.
constexpr int kQuietShift = 4;
constexpr long kQuietMinSteps = 128;
constexpr double kQuietFraction = 0.6;
constexpr int kQuietCycles = 2;

// [*lo, *hi] widened to hold v: a cycle's extremes.
template <typename T>
void Widen(T v, T* lo, T* hi) {
  *lo = std::min(*lo, v);
  *hi = std::max(*hi, v);
}

// The smoothing of e: f += (e - f) * kQuietGain (exact: a power of 2).
constexpr double kQuietGain = 1.0 / static_cast<double>(1 << kQuietShift);
static_assert(kQuietFraction == 0.6, "the fixed point's quiet rule is 5 range < 6 eps");

}  // namespace

const char* ToString(RelayPhase phase) {
  switch (phase) {
    case RelayPhase::kHold:
      return "hold";
    case RelayPhase::kRelay:
      return "relay";
    case RelayPhase::kDone:
      return "done";
    case RelayPhase::kAborted:
      break;
  }
  return "aborted";
}

bool RelayTuneOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(hold_s >= 0.0) || !std::isfinite(hold_s))
    os << "hold " << hold_s << " s must be >= 0 and finite";
  else if (!std::isfinite(u0))
    os << "u0 " << u0 << " must be finite";
  else if (!(amplitude > 0.0) || !std::isfinite(amplitude))
    os << "relay amplitude " << amplitude << " must be > 0 and finite";
  else if (!(std::abs(bias) < amplitude))
    os << "relay bias " << bias << " must be smaller in magnitude than the amplitude " << amplitude;
  else if (!(hysteresis >= 0.0) || !std::isfinite(hysteresis))
    os << "hysteresis " << hysteresis << " must be >= 0 and finite";
  else if (!(noise_multiple >= 0.0) || !std::isfinite(noise_multiple))
    os << "noise multiple " << noise_multiple << " must be >= 0 and finite";
  else if (!(y_limit > 0.0))
    os << "y limit " << y_limit << " must be > 0";
  else if (settled_cycles < 2 || settled_cycles > 100)
    os << "settled cycles " << settled_cycles << " must be in [2, 100]";
  else if (!(tolerance > 0.0 && tolerance < 1.0))
    os << "tolerance " << tolerance << " must be in (0, 1)";
  else if (!(timeout_periods > settled_cycles + 1) || !std::isfinite(timeout_periods))
    os << "timeout " << timeout_periods << " periods must be finite and more than settled cycles + 1";
  else if (max_restarts < 0 || max_restarts > 100)
    os << "max restarts " << max_restarts << " must be in [0, 100]";
  else if (q_bits != 0 && q_bits != 15 && q_bits != 31)
    os << "fixed-point bits " << q_bits << " must be 0 (double), 15 or 31";
  else if (q_bits != 0 && (!(input_full_scale > 0.0) || !std::isfinite(input_full_scale)))
    os << "input full scale " << input_full_scale << " must be > 0 and finite";
  else if (q_bits != 0 && (!(output_full_scale > 0.0) || !std::isfinite(output_full_scale)))
    os << "output full scale " << output_full_scale << " must be > 0 and finite";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

RelayTuner::RelayTuner(const RelayTuneOptions& options, const PidGains& previous, const PidOptions& pid)
    : o_(options),
      previous_(previous),
      pid_(previous, pid),
      out_min_(pid.output_min),
      out_max_(pid.output_max) {
  if (o_.q_bits == 0) return;
  const int n = o_.q_bits;
  const double top = std::ldexp(1.0, n);
  qy_ = std::ldexp(o_.input_full_scale, -n);
  qu_ = std::ldexp(o_.output_full_scale, -n);
  hold_steps_ = RoundClamp(o_.hold_s / pid.dt_s, 0.0, 4e18);
  out_min_q_ = QOut(out_min_);
  out_max_q_ = QOut(out_max_);
  hyst_q_ = RoundClamp(std::ldexp(o_.hysteresis / o_.input_full_scale, n), 0.0, top);
  dh_q_ = RoundClamp(std::ldexp((o_.amplitude + o_.bias) / o_.output_full_scale, n), 0.0, 2.0 * top);
  dl_q_ = RoundClamp(std::ldexp((o_.amplitude - o_.bias) / o_.output_full_scale, n), 0.0, 2.0 * top);
  y_limit_q_ = static_cast<std::int64_t>(
      std::floor(std::min(std::ldexp(o_.y_limit / o_.input_full_scale, n), 4611686018427387904.0)));
  u0_cfg_q_ = std::min(std::max(QOut(o_.u0), out_min_q_), out_max_q_);
}

int FixedRelayLsb(int q_bits) { return q_bits == 31 ? 3 : q_bits == 15 ? 2 : 0; }

double RelayTuner::input_tolerance() const { return FixedRelayLsb(o_.q_bits) * qu_; }

std::int64_t RelayTuner::QIn(double v) const {
  const double top = std::ldexp(1.0, o_.q_bits);
  return RoundClamp(std::ldexp(v / o_.input_full_scale, o_.q_bits), -top, top - 1.0);
}

std::int64_t RelayTuner::QOut(double v) const {
  const double top = std::ldexp(1.0, o_.q_bits);
  return RoundClamp(std::ldexp(v / o_.output_full_scale, o_.q_bits), -top, top - 1.0);
}

bool RelayTuner::HasPid() const { return previous_.kp != 0.0 || previous_.ki != 0.0 || previous_.kd != 0.0; }

void RelayTuner::StartHold(double t_s) {
  phase_ = RelayPhase::kHold;
  hold_start_s_ = t_s;
  sum_u_ = sum_y_ = sum_d_ = sum_d2_ = 0.0;
  n_u_ = n_d_ = 0;
  n_prev_ = 0;
  hold_start_k_ = k_;
  sum_u_q_ = sum_y_q_ = sum_d_q_ = 0;
  sum_d2_q_ = 0;
}

double RelayTuner::After(double r, double y) {
  if (!HasPid()) return Clip(phase_ == RelayPhase::kHold ? o_.u0 : u0_, out_min_, out_max_);
  double u = 0.0;
  pid_.Step(r, y, &u);
  return u;
}

void RelayTuner::End(RelayPhase phase, double t_s, const std::string& why) {
  phase_ = phase;
  end_s_ = t_s;
  why_ = why;
}

void RelayTuner::EndTimedOut(double t_s, double timeout_s) {
  End(RelayPhase::kAborted, t_s,
      "the oscillation did not converge within " + Num(o_.timeout_periods) + " periods (" + Num(timeout_s) +
          " s): " + std::to_string(cycles_.size()) +
          " cycles, the last periods and amplitudes differ by more than " + Num(100.0 * o_.tolerance) + " %");
}

double RelayTuner::Step(double t_s, double r, double y) {
  if (o_.q_bits != 0) return FixedStep(t_s, r, y);
  if (first_) {
    first_ = false;
    StartHold(t_s);
  }
  if (phase_ == RelayPhase::kHold && t_s - hold_start_s_ >= o_.hold_s) EndHold(t_s, r, y);
  if (phase_ == RelayPhase::kRelay) return RelayStep(t_s, r, y);
  if (phase_ != RelayPhase::kHold) {  // done or aborted: the loop as before
    if (HasPid()) return After(r, y);
    return Clip(u0_, out_min_, out_max_);
  }
  const double u = After(r, y);
  if (2.0 * (t_s - hold_start_s_) >= o_.hold_s) {  // the hold's second half
    sum_u_ += u;
    sum_y_ += y;
    ++n_u_;
    if (n_prev_ >= 2) {  // second differences: a smooth drift gives ~0, white noise 6 sigma^2
      const double d = y - 2.0 * y_prev_ + y_prev2_;
      sum_d_ += d;
      sum_d2_ += d * d;
      ++n_d_;
    }
    y_prev2_ = y_prev_;
    y_prev_ = y;
    ++n_prev_;
  }
  return u;
}

void RelayTuner::EndHold(double t_s, double r, double y) {
  u0_ = HasPid() && n_u_ > 0 ? sum_u_ / static_cast<double>(n_u_) : Clip(o_.u0, out_min_, out_max_);
  y0_ = n_u_ > 0 ? sum_y_ / static_cast<double>(n_u_) : r;
  sigma_ = 0.0;
  if (n_d_ > 1) {
    const double n = static_cast<double>(n_d_);
    const double var = (sum_d2_ - sum_d_ * sum_d_ / n) / (n - 1.0);
    sigma_ = var > 0.0 ? std::sqrt(var / 6.0) : 0.0;
  }
  eps_ = o_.hysteresis + o_.noise_multiple * sigma_;
  d_high_ = std::min(o_.amplitude + o_.bias, out_max_ - u0_);
  d_low_ = std::min(o_.amplitude - o_.bias, u0_ - out_min_);
  if (!(d_high_ > 0.0) || !(d_low_ > 0.0) || !std::isfinite(u0_)) {
    End(RelayPhase::kAborted, t_s, NoRoom(u0_, out_min_, out_max_));
    return;
  }
  StartRelay(t_s);
  high_ = y - y0_ < 0.0;  // towards the operating point
  t_prev_ = t_s;
  e_prev_ = y - y0_;
  t_high_ = t_low_ = -1.0;
  integral_ = 0.0;
  f_ = f_max_ = f_min_ = 0.0;
}

void RelayTuner::StartRelay(double t_s) {
  phase_ = RelayPhase::kRelay;
  relay_start_s_ = t_s;
  cycle_steps_ = 0;
  quiet_ = 0;
  longest_period_s_ = 0.0;
  timeout_q_ = 0;
  cycles_.clear();
  changes_.clear();
}

double RelayTuner::RelayStep(double t_s, double r, double y) {
  const double e = y - y0_;
  if (t_s > relay_start_s_) {
    if (!(std::abs(e) <= o_.y_limit)) {
      End(RelayPhase::kAborted, t_s,
          "y - y0 = " + Num(e) + " at t = " + Num(t_s) + " s is beyond the limit " + Num(o_.y_limit));
      return After(r, y);
    }
    f_ += (e - f_) * kQuietGain;
    if (t_high_ >= 0.0) {  // inside a cycle: its integral and extremes
      integral_ += 0.5 * (e + e_prev_) * (t_s - t_prev_);
      Widen(e, &e_min_, &e_max_);
      Widen(f_, &f_min_, &f_max_);
      ++cycle_steps_;
    }
    if (!high_ && e < -eps_) {
      const bool complete = t_high_ >= 0.0 && t_low_ > t_high_;
      const RelayCycle c =
          complete ? RelayCycle::Closed(t_high_, t_low_, t_s, e_max_, e_min_, integral_, integral_on_) : RelayCycle{};
      const double smoothed = 0.5 * (f_max_ - f_min_);
      const bool quiet = cycle_steps_ >= kQuietMinSteps && smoothed < kQuietFraction * eps_;
      high_ = true;
      t_high_ = t_s;
      t_low_ = -1.0;
      integral_ = 0.0;
      e_max_ = e_min_ = e;
      f_max_ = f_min_ = f_;
      cycle_steps_ = 0;
      if (complete) OnCycle(c, t_s, quiet, smoothed);
      if (phase_ == RelayPhase::kHold) return After(r, y);  // restarted
      if (phase_ != RelayPhase::kRelay) return After(r, y);
    } else if (high_ && e > eps_) {
      high_ = false;
      if (t_high_ >= 0.0) {
        t_low_ = t_s;
        integral_on_ = integral_;
      }
    }
    if (!cycles_.empty() && t_s - relay_start_s_ > o_.timeout_periods * longest_period_s_) {
      EndTimedOut(t_s, o_.timeout_periods * longest_period_s_);
      return After(r, y);
    }
  }
  t_prev_ = t_s;
  e_prev_ = e;
  return u0_ + (high_ ? d_high_ : -d_low_);
}

std::string RelayTuner::NoiseBeatsRelay(double smoothed) const {
  // A relay's oscillation grows with its amplitude: twice the hysteresis.
  const double d = 0.5 * (d_high_ + d_low_);
  const double needed = d * 2.0 * eps_ / std::max(smoothed, 1e-3 * eps_);
  return "the relay cannot beat the noise: over its last " + std::to_string(kQuietCycles) +
         " cycles its oscillation, smoothed, is about " + Num(smoothed) + ", under the hysteresis " +
         Num(eps_) + " (noise sigma " + Num(sigma_) +
         "), so the noise switches it; a relay amplitude of about " + Num(needed) + " (now " + Num(d) +
         ") would beat it";
}

double RelayTuner::Tolerance(const RelayCycle& c) const {
  // The extremes of a noisy y, and the switching times with them, jitter by
  // about sigma / amplitude: a cycle agrees within that as well.
  return o_.tolerance + (c.amplitude() > 0.0 ? 2.0 * sigma_ / c.amplitude() : 0.0);
}

void RelayTuner::OnCycle(const RelayCycle& c, double t_s, bool quiet, double smoothed) {
  if (sigma_ > 0.0 && quiet) {
    if (++quiet_ >= kQuietCycles) {
      End(RelayPhase::kAborted, t_s, NoiseBeatsRelay(smoothed));
      return;
    }
  } else {
    quiet_ = 0;
  }
  if (!cycles_.empty()) {
    const RelayCycle& p = cycles_.back();
    const double change = std::max({std::abs(c.period_s() - p.period_s()) / p.period_s(),
                                    std::abs(c.amplitude() - p.amplitude()) / p.amplitude(),
                                    std::abs(c.t_on_s / c.period_s() - p.t_on_s / p.period_s())});
    // A change that grows where a converging oscillation's shrink, after the
    // approach (cycles_[0]) and one cycle to compare with.
    if (changes_.size() >= 2 && change > 5.0 * Tolerance(p) && change > 2.0 * changes_.back()) {
      load_changes_s_.push_back(c.start_s);
      if (!HasPid()) {
        End(RelayPhase::kAborted, t_s,
            "a load change near t = " + Num(c.start_s) +
                " s (the oscillation changed after settling); with no previous PID to hold the process, the "
                "test "
                "stops");
        return;
      }
      if (restarts_ >= o_.max_restarts) {
        End(RelayPhase::kAborted, t_s,
            "a load change near t = " + Num(c.start_s) + " s after " + std::to_string(restarts_) +
                " restarts: the process does not stay at its operating point");
        return;
      }
      ++restarts_;
      StartHold(t_s);
      return;
    }
    changes_.push_back(change);
  } else {
    changes_.push_back(0.0);
  }
  cycles_.push_back(c);
  longest_period_s_ = std::max(longest_period_s_, c.period_s());
  // Under noise the estimates average more cycles: a noisy cycle does not
  // start where the last one did, and only a sum over many telescopes that out.
  const int n = 3.0 * sigma_ > 0.01 * c.amplitude() ? std::max(o_.settled_cycles, kNoisySettledCycles)
                                                    : o_.settled_cycles;
  double period = 0.0, amplitude = 0.0;
  if (!LastCyclesAgree(
          cycles_, n, [this](const RelayCycle& k) { return Tolerance(k); }, &period, &amplitude))
    return;
  End(RelayPhase::kDone, t_s,
      "converged after " + std::to_string(cycles_.size()) + " cycles: period " + Num(period) +
          " s, amplitude " + Num(amplitude));
}

}  // namespace pidlab

namespace pidlab {

// Fixed point: the exported q31/q15 relay (c_relay_fixed_template.cc) line
// for line. y and r on the input grid qy_, u on the output grid qu_, time in
// steps k_; doubles only where the exported relay uses them too, once per
// hold (its mean u and y, sigma) and once per cycle (the cycle in seconds,
// OnCycle's tests), with the same operations in the same order.
double RelayTuner::FixedAfter(double r, double y) {
  if (!HasPid()) return static_cast<double>(phase_ == RelayPhase::kHold ? u0_cfg_q_ : u0_q_) * qu_;
  double u = 0.0;
  pid_.Step(static_cast<double>(QIn(r)) * qy_, static_cast<double>(QIn(y)) * qy_, &u);
  return static_cast<double>(QOut(u)) * qu_;
}

double RelayTuner::FixedStep(double t_s, double r, double y) {
  if (first_) {
    first_ = false;
    k_ = 0;
    StartHold(t_s);
  } else {
    ++k_;
  }
  const std::int64_t yq = QIn(y);
  if (phase_ == RelayPhase::kHold && k_ - hold_start_k_ >= hold_steps_) FixedEndHold(t_s, QIn(r), yq);
  if (phase_ == RelayPhase::kRelay) return FixedRelayStep(t_s, r, yq);
  if (phase_ != RelayPhase::kHold) return FixedAfter(r, y);
  const double u = FixedAfter(r, y);
  if (2 * (k_ - hold_start_k_) >= hold_steps_) {
    sum_u_q_ += QOut(u);
    sum_y_q_ += yq;
    ++n_u_;
    if (n_prev_ >= 2) {
      const std::int64_t d = ShiftRound(yq - 2 * y_prev_q_ + y_prev2_q_, DiffShift(o_.q_bits));
      const auto d2 = static_cast<std::uint64_t>(d * d);
      sum_d_q_ += d;
      sum_d2_q_ = d2 > UINT64_MAX - sum_d2_q_ ? UINT64_MAX : sum_d2_q_ + d2;
      ++n_d_;
    }
    y_prev2_q_ = y_prev_q_;
    y_prev_q_ = yq;
    ++n_prev_;
  }
  return u;
}

void RelayTuner::FixedEndHold(double t_s, std::int64_t r, std::int64_t y) {
  const double top = std::ldexp(1.0, o_.q_bits);
  u0_q_ = HasPid() && n_u_ > 0
              ? RoundClamp(static_cast<double>(sum_u_q_) / static_cast<double>(n_u_), -top, top - 1.0)
              : u0_cfg_q_;
  y0_q_ =
      n_u_ > 0 ? RoundClamp(static_cast<double>(sum_y_q_) / static_cast<double>(n_u_), -top, top - 1.0) : r;
  double sigma_d = 0.0;  // in units of 2^shift grid steps
  if (n_d_ > 1) {
    const double n = static_cast<double>(n_d_);
    const double sum = static_cast<double>(sum_d_q_);
    const double var = (static_cast<double>(sum_d2_q_) - sum * sum / n) / (n - 1.0);
    sigma_d = var > 0.0 ? std::sqrt(var / 6.0) : 0.0;
  }
  const int shift = DiffShift(o_.q_bits);
  sigma_ = sigma_d * std::ldexp(qy_, shift);
  eps_q_ = hyst_q_ + RoundClamp(o_.noise_multiple * std::ldexp(sigma_d, shift), 0.0, top);
  d_high_q_ = std::min(dh_q_, out_max_q_ - u0_q_);
  d_low_q_ = std::min(dl_q_, u0_q_ - out_min_q_);
  u0_ = static_cast<double>(u0_q_) * qu_;
  y0_ = static_cast<double>(y0_q_) * qy_;
  eps_ = static_cast<double>(eps_q_) * qy_;
  d_high_ = static_cast<double>(d_high_q_) * qu_;
  d_low_ = static_cast<double>(d_low_q_) * qu_;
  if (d_high_q_ <= 0 || d_low_q_ <= 0) {
    End(RelayPhase::kAborted, t_s, NoRoom(u0_, out_min_, out_max_));
    return;
  }
  StartRelay(t_s);
  relay_start_k_ = k_;
  high_ = y - y0_q_ < 0;
  e_prev_q_ = y - y0_q_;
  k_high_ = k_low_ = -1;
  integral_q_ = 0;
  f_q_ = f_max_q_ = f_min_q_ = 0;
}

double RelayTuner::FixedRelayStep(double t_s, double r, std::int64_t y) {
  const std::int64_t e = y - y0_q_;
  if (k_ > relay_start_k_) {
    if (!((e < 0 ? -e : e) <= y_limit_q_)) {
      End(RelayPhase::kAborted, t_s,
          "y - y0 = " + Num(static_cast<double>(e) * qy_) + " at t = " + Num(t_s) +
              " s is beyond the limit " + Num(o_.y_limit));
      return FixedAfter(r, static_cast<double>(y) * qy_);
    }
    f_q_ += ShiftRound(e - f_q_, kQuietShift);
    if (k_high_ >= 0) {
      integral_q_ += e + e_prev_q_;
      Widen(e, &e_min_q_, &e_max_q_);
      Widen(f_q_, &f_min_q_, &f_max_q_);
      ++cycle_steps_;
    }
    if (!high_ && e < -eps_q_) {
      const bool complete = k_high_ >= 0 && k_low_ > k_high_;
      const double dt = pid_.options().dt_s;
      RelayCycle c;
      if (complete) {
        c.start_s = static_cast<double>(k_high_) * dt;
        c.t_on_s = static_cast<double>(k_low_ - k_high_) * dt;
        c.t_off_s = static_cast<double>(k_ - k_low_) * dt;
        c.e_max = static_cast<double>(e_max_q_) * qy_;
        c.e_min = static_cast<double>(e_min_q_) * qy_;
        c.integral_e = static_cast<double>(integral_q_) * (0.5 * dt * qy_);
        c.integral_on_e = static_cast<double>(integral_on_q_) * (0.5 * dt * qy_);
      }
      const std::int64_t period_k = k_ - k_high_;
      // 0.5 range < kQuietFraction (0.6) eps, in integers.
      const bool quiet = cycle_steps_ >= kQuietMinSteps && 5 * (f_max_q_ - f_min_q_) < 6 * eps_q_;
      cycle_steps_ = 0;
      const double smoothed = 0.5 * static_cast<double>(f_max_q_ - f_min_q_) * qy_;
      f_max_q_ = f_min_q_ = f_q_;
      high_ = true;
      k_high_ = k_;
      k_low_ = -1;
      integral_q_ = 0;
      e_max_q_ = e_min_q_ = e;
      if (complete) {
        const std::size_t before = cycles_.size();
        OnCycle(c, t_s, quiet, smoothed);
        if (phase_ != RelayPhase::kRelay) return FixedAfter(r, static_cast<double>(y) * qy_);
        if (cycles_.size() > before)
          timeout_q_ = std::max(
              timeout_q_,
              static_cast<std::int64_t>(std::floor(o_.timeout_periods * static_cast<double>(period_k))));
      }
    } else if (high_ && e > eps_q_) {
      high_ = false;
      if (k_high_ >= 0) {
        k_low_ = k_;
        integral_on_q_ = integral_q_;
      }
    }
    if (!cycles_.empty() && k_ - relay_start_k_ > timeout_q_) {
      EndTimedOut(t_s, static_cast<double>(timeout_q_) * pid_.options().dt_s);
      return FixedAfter(r, static_cast<double>(y) * qy_);
    }
  }
  e_prev_q_ = e;
  return static_cast<double>(u0_q_ + (high_ ? d_high_q_ : -d_low_q_)) * qu_;
}

}  // namespace pidlab
