#pragma once
// The relay experiment of an autotune (Åström and Hägglund's relay feedback,
// Berner's asymmetric relay): a relay with hysteresis around the operating
// point (u0, r) drives the process into a limit cycle; its cycles give the
// ultimate period and gain, and, for the asymmetric relay, a first-order plus
// dead-time model from the limit cycle's closed forms.
//
// In deviation variables e = y - r and v = u - u0, the relay puts out
// v = +d_high while -e > hysteresis (y below the band), v = -d_low while
// e > hysteresis, and holds in between (reverse acting: a process of positive
// gain). A cycle runs from one switch to high to the next.
//
// For K e^(-sL)/(Ts + 1) the limit cycle is, with E = e^(-L/T) and eps the
// hysteresis (each extreme is reached L after the switch):
//   e_min = -K d_low + (K d_low - eps) E,  t_on  = L + T ln((K d_high - e_min) / (K d_high - eps))
//   e_max =  K d_high - (K d_high - eps) E, t_off = L + T ln((K d_low + e_max) / (K d_low - eps))
// and, for any stable linear process, the mean of e over a cycle is K times
// the mean of v: K = (integral of e over a cycle) / (d_high t_on - d_low t_off),
// which the asymmetric relay makes nonzero.

#include <limits>
#include <string>
#include <vector>

#include "pidlab/controller/relay.h"
#include "pidlab/spec/status.h"

namespace pidlab::autotune {

struct RelayOptions {
  double setpoint = 0.0;    ///< r
  double u0 = 0.0;          ///< the operating point's input (y = r at rest)
  double d_high = 1.0;      ///< v = +d_high below the band, > 0
  double d_low = 1.0;       ///< v = -d_low above it, > 0 (d_low != d_high: asymmetric)
  double hysteresis = 0.0;  ///< the band's half width eps, >= 0
  /// Converged when the last `settled_cycles` cycles' periods and amplitudes
  /// each lie within `tolerance` (relative) of their mean.
  int settled_cycles = 3;
  double tolerance = 0.01;
  /// h > 0: the process is behind a sample-and-hold of period h (a PLC's
  /// scan, a sampled sensor) and the relay ran on its grid, so its half
  /// periods are whole samples; EstimateFromCycles then fits the sampled
  /// model (SampledFopdtFromCycle) and its ultimate point is the sampled
  /// loop's (SampledUltimate). 0: a continuous process.
  double sample_period_s = 0.0;
  bool IsValid(std::string* error) const;
};

using pidlab::RelayCycle;  // controller/relay.h

/// A first-order plus dead-time model K e^(-sL)/(Ts + 1); an integrating
/// one, K e^(-sL)/(s (Ts + 1)), when `integrating` (T = 0 from the closed
/// forms: K e^(-sL)/s).
struct FopdtModel {
  double gain = 0.0, time_constant_s = 0.0, delay_s = 0.0;
  bool integrating = false;
};

struct RelayEstimates {
  bool converged = false;
  int cycles = 0;            ///< the settled cycles averaged
  double period_s = 0.0;     ///< mean period of the settled cycles
  double period_ci_s = 0.0;  ///< its 95 % half width over those cycles
  double amplitude = 0.0;    ///< mean (e_max - e_min) / 2
  double amplitude_ci = 0.0;
  /// The describing function's ultimate gain 4 d / (pi sqrt(a^2 - eps^2)),
  /// d = (d_high + d_low) / 2: labelled as such; it is 10-20 % off on
  /// dead-time processes (the relay's output is no sine).
  double ku_describing_function = 0.0;
  bool model_found = false;
  /// From the settled cycles (closed forms above): integrating where the
  /// relay is asymmetric and its mean output over a cycle is zero (within
  /// 2 % of its mean magnitude), first order plus dead time otherwise.
  FopdtModel model;
  double ku = 0.0;      ///< the model's ultimate gain (its phase crossover)
  double pu_s = 0.0;    ///< the model's ultimate period
  /// 95 % half widths of Ku, Pu and the model's K, T and L: the same fit on
  /// each averaged cycle alone, their spread (Student's t; 0 over identical
  /// cycles, NaN where a cycle alone gives no model).
  double ku_ci = 0.0, pu_ci_s = 0.0, gain_ci = 0.0, time_constant_ci_s = 0.0, delay_ci_s = 0.0;
  /// How the FOPDT model was found: "extremes" (the cycle's extremes and
  /// integral, exact without noise) or "switching times and integrals" (its
  /// half periods and integrals, FopdtFromTimes: the extremes of a noisy y are
  /// biased).
  std::string model_from;
  std::string message;  ///< why something was not found
};

/// `options`' relay run by the one relay state machine, RelayTuner
/// (controller/relay.h), as the controller and the firmware run it: no hold,
/// so the relay is centred on the setpoint; open loop at u0 (no previous
/// PID); amplitude (d_high + d_low) / 2 and bias (d_high - d_low) / 2; the
/// hysteresis as given (no noise multiple); settled_cycles and tolerance as
/// given. Step it with r = options.setpoint at the period dt_s > 0; it is
/// done (RelayPhase::kDone) when its last cycles agree, and EstimateFromCycles
/// reads its cycles().
RelayTuner BareRelay(const RelayOptions& options, double dt_s);

/// EstimateFromCycles on a bare relay's cycles, converged when it is done.
RelayEstimates EstimateBare(const RelayOptions& options, const RelayTuner& relay);

/// The estimates from `cycles` (the first is the approach: the last
/// min(settled_cycles, size - 1) are averaged) under `options`' relay;
/// where 3 noise_sigma is more than 1 % of the amplitude, the FOPDT model
/// from the switching times (FopdtFromTimes), else from the extremes.
/// A symmetric relay (d_high == d_low) gives no FOPDT gain by its
/// integrals; with `delay_s`, the apparent delay from each switch to the
/// extreme that follows it (ApparentDelay), FopdtFromSymmetric gives one.
RelayEstimates EstimateFromCycles(const RelayOptions& options, const std::vector<RelayCycle>& cycles,
                                  bool converged, double noise_sigma,
                                  double delay_s = std::numeric_limits<double>::quiet_NaN());

/// K, T and L of K e^(-sL)/(Ts + 1) under a symmetric relay d with
/// hysteresis eps from the cycle's amplitude a, its half period h and the
/// delay L from a switch to the extreme after it (a FOPDT turns exactly L
/// after its input does): a = Kd - (Kd - eps) e^(-L/T) and
/// h = L + T ln((Kd + a) / (Kd - eps)), one equation in Kd > a solved by
/// bisection. kInvalidInput where no Kd solves it (h - L at least
/// L (a + eps) / (a - eps): an integrating or higher-order process).
Status FopdtFromSymmetric(const RelayOptions& options, const RelayCycle& cycle, double delay_s,
                          FopdtModel* model);

/// K, T and L from a cycle's mean t_on, t_off, integral of e and integral
/// over the part at +d_high, not its extremes: K from the integral; then,
/// for a switching level eps_eff (noise on y crosses the band early, so the
/// relay switches where the process is short of eps), tau = L/T from
/// t_on / t_off by bisection and T from t_on; eps_eff is the one (nearest
/// the hysteresis) whose model gives the measured integral over the part at
/// +d_high. Integrals average the noise out; extremes do not.
Status FopdtFromTimes(const RelayOptions& options, const RelayCycle& cycle, FopdtModel* model);

/// The ultimate gain and period of K e^(-sL)/(Ts + 1): the phase crossover
/// w (atan(wT) + wL = pi), Ku = sqrt(1 + (wT)^2) / |K|, Pu = 2 pi / w; of
/// K e^(-sL)/(s (Ts + 1)): atan(wT) + wL = pi / 2, Ku = w sqrt(1 + (wT)^2) / |K|
/// (T = 0: w = pi / (2L), Ku = w / |K|, Pu = 4L).
Status FopdtUltimate(const FopdtModel& model, double* ku, double* pu_s);

/// K and L of K e^(-sL)/s from a limit cycle (RelayCycle means): the process
/// integrates the relay's output, so y moves at K d_high, -K d_low, and
///   e_max - e_min = 2 eps + K L (d_high + d_low),
///   t_on = L + (2 eps + K L d_low) / (K d_high),  t_off = L + (2 eps + K L d_high) / (K d_low);
/// a periodic cycle needs d_high t_on = d_low t_off (the mean output zero).
Status IntegratingFromCycle(const RelayOptions& options, const RelayCycle& cycle, FopdtModel* model);

/// K, T and L of K e^(-sL)/(Ts + 1) behind a sample-and-hold of period
/// h = options.sample_period_s, the relay on its grid: the process seen at
/// the samples is y(k+1) = a y(k) + (1 - a) K v(k - n), a = e^(-h/T), L = n h
/// (the exact image of the ZOH, the hold in it). K from the cycle's
/// integral; a from each half period N h and the extremes,
///   a^N_on  = (K d_high - e_max) / (K d_high - e_min),
///   a^N_off = (K d_low + e_min) / (K d_low + e_max),
/// which agree for such a process; n is N less the samples the response
/// takes from its extreme across the band, the same in both halves.
/// kInvalidInput, naming why, where the half periods are not whole samples or
/// the halves disagree (no such process).
Status SampledFopdtFromCycle(const RelayOptions& options, const RelayCycle& cycle, FopdtModel* model);

/// The ultimate gain and period of the sampled loop: a gain k on `model`
/// behind a ZOH at h, G(z) = K (1 - a) z^-n / (z - a): the frequency where
/// its phase is -pi (n = 0: the Nyquist frequency), Ku = 1 / |G|,
/// Pu = 2 pi / w.
Status SampledUltimate(const FopdtModel& model, double h, double* ku, double* pu_s);

/// K, T and L from a limit cycle's mean t_on, t_off, e_max, e_min and
/// integral of e (RelayCycle) under `options`' relay: the closed forms above.
Status FopdtFromCycle(const RelayOptions& options, const RelayCycle& cycle, FopdtModel* model);

}  // namespace pidlab::autotune
