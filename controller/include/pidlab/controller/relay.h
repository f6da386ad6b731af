#pragma once
// The relay autotune as the controller runs it (docs/autotune.md): the state
// machine that pidlab-controller steps in place of the PID in a relay episode,
// and that `pidlab autotune` steps again over the logged measurements to find
// the same cycles (it checks that every input is the controller's, bit for
// bit).
//
//   hold   the previous PID (or the open-loop input u0 when the previous gains
//          are all 0) for hold_s; over its second half the mean input is the
//          operating point's u0, the mean y its y0 (r near enough under the
//          previous PID; the process's own resting value in open loop), and the second differences of y give
//          the measurement noise sigma = sd(y_k - 2 y_(k-1) + y_(k-2)) / sqrt(6); the hysteresis is
//          hysteresis + noise_multiple sigma.
//   relay  v = u - u0 = +d_high while e = y - y0 < -eps, -d_low while e > eps,
//          held in between (reverse acting: a process of positive gain), with
//          d_high = amplitude + bias and d_low = amplitude - bias cut to the
//          output range (a heat-only actuator gets a one-sided relay). A cycle
//          runs from one switch to high to the next; the first is the
//          approach. It ends:
//            done     the last settled_cycles (under noise at least
//                     kNoisySettledCycles) cycles' periods and amplitudes
//                     lie within tolerance + 2 sigma / amplitude (relative:
//                     a noisy y's extremes and switches jitter) of their mean;
//            aborted  |y - y0| > y_limit; or no convergence within timeout_periods
//                     of the last period after the relay's start; or a load
//                     change with no previous PID to hold the process again;
//                     or, under noise, kQuietCycles cycles whose smoothed e
//                     stays inside the hysteresis (the noise switches the
//                     relay: kQuietShift).
//          A load change (a cycle that differs from the one before by more
//          than 5 times that tolerance, twice as much as that one differed from its own
//          predecessor, where a converging oscillation's changes shrink)
//          restarts the test from the hold, at most max_restarts times.
//   after  the previous PID again (the same instance, bumpless), or u0.
//
// Every decision reads only the measurements and the options, so a log of
// the episode gives the same cycles and the same end.

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/controller/pid.h"

namespace pidlab {

/// Under noise (3 sigma above 1 % of a cycle's amplitude) the relay runs at
/// least this many settled cycles.
inline constexpr int kNoisySettledCycles = 10;

struct RelayTuneOptions {
  double hold_s = 10.0;         ///< the hold before the relay, s, >= 0
  double u0 = 0.0;              ///< the open-loop hold's input (previous gains all 0)
  double amplitude = 1.0;       ///< d > 0
  double bias = 0.0;            ///< b, |b| < d: d_high = d + b, d_low = d - b
  double hysteresis = 0.0;      ///< >= 0, in units of y
  double noise_multiple = 0.0;  ///< >= 0: eps = hysteresis + noise_multiple sigma
  double y_limit = std::numeric_limits<double>::infinity();  ///< on |y - y0|, > 0
  int settled_cycles = 3;                                    ///< >= 2
  double tolerance = 0.02;                                   ///< in (0, 1)
  double timeout_periods = 20.0;                             ///< > settled_cycles + 1
  int max_restarts = 2;                                      ///< >= 0
  /// Fixed point: the exported q31/q15 relay's arithmetic (docs/autotune.md,
  /// "In the firmware"). 0: double. 31 or 15: y is rounded to the grid
  /// input_full_scale 2^-q_bits and u to output_full_scale 2^-q_bits, time
  /// counts steps, and every decision is the integer one the exported
  /// fixed-point relay makes; only the previous PID stays in double, so its
  /// input is the exported one's within kFixedRelayLsb LSB.
  int q_bits = 0;
  double input_full_scale = 1.0;   ///< X > 0 (q_bits != 0): the input's full scale
  double output_full_scale = 1.0;  ///< U > 0 (q_bits != 0): the output's full scale

  bool IsValid(std::string* error) const;
};

/// In fixed point, the exported relay's input and RelayTuner's differ by at
/// most this many LSB of the output (u0 is the mean of the PID's input over
/// the hold, each within the PID's test bound: 2 LSB in q31, 1 in q15; its
/// rounding adds 1). Every switch is at the same step.
int FixedRelayLsb(int q_bits);

enum class RelayPhase { kHold, kRelay, kDone, kAborted };
/// hold | relay | done | aborted
const char* ToString(RelayPhase phase);

/// One cycle of the limit cycle: from a switch to high to the next.
struct RelayCycle {
  double start_s = 0.0;
  double t_on_s = 0.0, t_off_s = 0.0;  ///< time at +d_high, at -d_low
  double e_max = 0.0, e_min = 0.0;     ///< extremes of e = y - r
  double integral_e = 0.0;             ///< of e over the cycle (trapezoids)
  double integral_on_e = 0.0;          ///< of e over its first part, at +d_high
  double period_s() const { return t_on_s + t_off_s; }
  double amplitude() const { return 0.5 * (e_max - e_min); }
  /// The cycle from the switch to high at t_high, to low at t_low, to high
  /// again at t_end, with its extremes and integrals.
  static RelayCycle Closed(double t_high, double t_low, double t_end, double e_max, double e_min,
                           double integral_e, double integral_on_e) {
    return RelayCycle{t_high, t_low - t_high, t_end - t_low, e_max, e_min, integral_e, integral_on_e};
  }
};

/// The mean period and amplitude of the last n cycles, and whether each of
/// them lies within tolerance(cycle) (relative) of both: false with fewer than
/// n + 1 cycles (the first is the approach). *period and *amplitude are
/// written whenever there are enough cycles.
template <typename Tolerance>
bool LastCyclesAgree(const std::vector<RelayCycle>& cycles, int n, Tolerance tolerance, double* period,
                     double* amplitude) {
  if (n < 1 || static_cast<int>(cycles.size()) < n + 1) return false;
  *period = *amplitude = 0.0;
  for (int i = 0; i < n; ++i) {
    const RelayCycle& c = cycles[cycles.size() - 1 - i];
    *period += c.period_s() / n;
    *amplitude += c.amplitude() / n;
  }
  for (int i = 0; i < n; ++i) {
    const RelayCycle& c = cycles[cycles.size() - 1 - i];
    const double tol = tolerance(c);
    if (!(std::abs(c.period_s() - *period) <= tol * *period) ||
        !(std::abs(c.amplitude() - *amplitude) <= tol * *amplitude))
      return false;
  }
  return true;
}

class RelayTuner {
 public:
  /// `previous` and `pid` (its dt_s the loop's): the loop in place before,
  /// held before and resumed after. Options must be valid.
  RelayTuner(const RelayTuneOptions& options, const PidGains& previous, const PidOptions& pid);
  /// The input for measurement y at time t_s (strictly increasing) and
  /// reference r.
  double Step(double t_s, double r, double y);

  RelayPhase phase() const { return phase_; }
  /// The operating point and the relay, found by the last hold (from the
  /// relay's start on).
  double u0() const { return u0_; }
  /// The relay's centre: the hold's mean y (r with hold_s 0).
  double y0() const { return y0_; }
  double noise_sigma() const { return sigma_; }
  double hysteresis() const { return eps_; }
  double d_high() const { return d_high_; }
  double d_low() const { return d_low_; }
  double relay_start_s() const { return relay_start_s_; }
  /// The cycles since the relay's last start (the approach first).
  const std::vector<RelayCycle>& cycles() const { return cycles_; }
  int restarts() const { return restarts_; }
  /// When and why the relay ended (done or aborted), one line.
  double end_s() const { return end_s_; }
  const std::string& why() const { return why_; }
  /// Where load changes restarted the test, s.
  const std::vector<double>& load_changes_s() const { return load_changes_s_; }
  const RelayTuneOptions& options() const { return o_; }
  /// How far the controller's input may be from Step's: 0 (bit for bit) in
  /// double, FixedRelayLsb(q_bits) LSB of the output in fixed point.
  double input_tolerance() const;

 private:
  void StartHold(double t_s);
  void EndHold(double t_s, double r, double y);
  // The relay's start, both scalars: the phase, and no cycle yet.
  void StartRelay(double t_s);
  double RelayStep(double t_s, double r, double y);
  // `quiet`: the cycle's smoothed e stayed inside the hysteresis
  // (kQuietFraction), its half range `smoothed` in units of y.
  void OnCycle(const RelayCycle& c, double t_s, bool quiet, double smoothed);
  double Tolerance(const RelayCycle& c) const;
  // The abort of a relay the noise switches, `smoothed` its oscillation.
  std::string NoiseBeatsRelay(double smoothed) const;
  void End(RelayPhase phase, double t_s, const std::string& why);
  // Ends the relay as aborted: no convergence within `timeout_s`.
  void EndTimedOut(double t_s, double timeout_s);
  double After(double r, double y);
  bool HasPid() const;
  // Fixed point (q_bits != 0): the same machine in the exported relay's
  // integers (relay.cc, "Fixed point").
  double FixedStep(double t_s, double r, double y);
  void FixedEndHold(double t_s, std::int64_t r, std::int64_t y);
  double FixedRelayStep(double t_s, double r, std::int64_t y);
  double FixedAfter(double r, double y);
  std::int64_t QIn(double v) const;
  std::int64_t QOut(double v) const;

  RelayTuneOptions o_;
  PidGains previous_;
  DiscretePid<double> pid_;
  double out_min_, out_max_;
  RelayPhase phase_ = RelayPhase::kHold;
  bool first_ = true;
  // The hold.
  double hold_start_s_ = 0.0;
  double sum_u_ = 0.0, sum_y_ = 0.0, sum_d_ = 0.0, sum_d2_ = 0.0, y_prev_ = 0.0, y_prev2_ = 0.0;
  long n_u_ = 0, n_d_ = 0, n_prev_ = 0;
  // The relay.
  double u0_ = 0.0, y0_ = 0.0, sigma_ = 0.0, eps_ = 0.0, d_high_ = 0.0, d_low_ = 0.0;
  double relay_start_s_ = -1.0;
  bool high_ = false;
  double t_prev_ = 0.0, e_prev_ = 0.0;
  double t_high_ = -1.0, t_low_ = -1.0;
  double e_max_ = 0.0, e_min_ = 0.0, integral_ = 0.0, integral_on_ = 0.0;
  double f_ = 0.0, f_max_ = 0.0, f_min_ = 0.0;  // the smoothed e, its extremes in the cycle
  long cycle_steps_ = 0;
  int quiet_ = 0;  // quiet cycles in a row
  // The timeout counts periods of the longest cycle since the relay's start:
  // noise cuts a cycle short, never long.
  double longest_period_s_ = 0.0;
  std::vector<RelayCycle> cycles_;
  std::vector<double> changes_;  // each cycle's change from the one before
  int restarts_ = 0;
  std::vector<double> load_changes_s_;
  double end_s_ = -1.0;
  std::string why_;
  // Fixed point: steps, and values in grid units.
  double qy_ = 0.0, qu_ = 0.0;
  std::int64_t k_ = 0, hold_steps_ = 0, hold_start_k_ = 0, out_min_q_ = 0, out_max_q_ = 0;
  std::int64_t hyst_q_ = 0, dh_q_ = 0, dl_q_ = 0, y_limit_q_ = 0, u0_cfg_q_ = 0;
  std::int64_t sum_u_q_ = 0, sum_y_q_ = 0, sum_d_q_ = 0, y_prev_q_ = 0, y_prev2_q_ = 0;
  std::uint64_t sum_d2_q_ = 0;
  std::int64_t u0_q_ = 0, y0_q_ = 0, eps_q_ = 0, d_high_q_ = 0, d_low_q_ = 0, relay_start_k_ = 0;
  std::int64_t e_prev_q_ = 0, k_high_ = -1, k_low_ = -1, e_max_q_ = 0, e_min_q_ = 0, integral_q_ = 0,
               integral_on_q_ = 0, timeout_q_ = 0;
  std::int64_t f_q_ = 0, f_max_q_ = 0, f_min_q_ = 0;
};

}  // namespace pidlab
