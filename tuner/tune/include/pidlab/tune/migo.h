#pragma once
// `tune --method migo` (docs/tuning.md, "Any plant: the MIGO design"): the
// PID with the largest integral gain whose loop keeps its sensitivity and
// complementary sensitivity peaks under a bound (Astrom and Hagglund's MIGO,
// "Advanced PID Control", ISA 2006, section 7.3), with a derivative filter
// tf = Td / N, then a setpoint weight b (derivative on measurement, c = 0)
// that holds the setpoint overshoot at the bound given. Maximising ki at a
// fixed Ms minimises the integrated error of a load step (IE = 1 / ki), the
// response an engineer tunes for; the bound is the robustness knob
// (`--robustness`), and `--response-time` caps the speed below what the bound
// allows.
//
// Everything runs on the plant's frequency response G(jw) e^(-jwL) on a grid
// fitted to its poles, zeros, delay and gain crossover, so the design costs
// the same for a millisecond plant and a 1000 s one, with or without a dead
// time. The loop's time scale (the horizon and the sample spacing every
// result is evaluated on) follows from the design's closed loop.

#include <complex>
#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/two_dof.h"

namespace pidlab::tune {

/// The default bound on Ms and Mt (docs/tuning.md): 1.4, AMIGO's and MIGO's
/// design value (a gain margin of at least 3.5 and a phase margin of at least
/// 41 degrees), where the load response of first-order plants with dead time
/// is no worse than SIMC's at tau_c = L.
inline constexpr double kMigoDefaultMs = 1.4;
/// Without a response time, the loop's gain crossover is at most this many
/// times the plant's fastest rate (1 / its fastest time): a plant whose
/// sensitivity bound allows any speed (no dead time, relative degree 1) gets
/// a loop ten times faster than itself, not an infinite gain.
inline constexpr double kMigoSpeedCap = 10.0;
/// When b = 0 still lets the setpoint step overshoot more than this (%), the
/// tuner tightens the Ms bound in steps of 0.05 (down to 1.2).
inline constexpr double kMigoMaxOvershootAtZeroB = 30.0;
/// The default bound of `tune` on a plant other than the paper's: the Ms of
/// SIMC's loop (tau_c = L, the half-rule model, derivative filter Td / 10) on
/// the plant, within these limits, so that the design is as robust as the
/// industry's reference rule and rejects load steps better; the upper limit
/// where SIMC does not apply. (docs/tuning.md, "Any plant".)
inline constexpr double kMigoMinDefaultMs = 1.4;
inline constexpr double kMigoMaxDefaultMs = 1.6;
/// The derivative filter: tf = Td / N.
inline constexpr double kMigoFilterRatio = 10.0;

struct MigoOptions {
  /// Bound on Ms = ||1/(1+CG)||inf and Mt = ||CG/(1+CG)||inf, in (1, 4].
  double ms = kMigoDefaultMs;
  /// PI only (kd = 0).
  bool pi = false;
  /// 0, or a response time T > 0 (s): the loop's gain crossover at most 2/T
  /// (a slower design than the bound allows; faster is not possible). 0:
  /// at most kMigoSpeedCap times the plant's fastest rate.
  double response_time_s = 0.0;
  /// Largest setpoint overshoot the weight b allows (%).
  double max_overshoot_pct = 20.0;
  /// N of the derivative filter tf = Td / N.
  double filter_ratio = kMigoFilterRatio;

  bool IsValid(std::string* error) const;
};

struct MigoDesign {
  /// kp, ki, kd and tf = kd / (N kp).
  PidGains gains;
  /// The setpoint weights: b for the overshoot, c = 0 (no derivative kick).
  double b = 1.0, c = 0.0;
  /// The peaks reached on the design grid and the gain crossover (rad/s).
  double ms = 0.0, mt = 0.0, crossover_rad_s = 0.0;
  /// The bound designed for (MigoOptions::ms, or the tightened one).
  double ms_bound = 0.0;
  /// The plant's characteristic time (s): its slowest and fastest features
  /// and its dead time, as the design grid saw them.
  double plant_time_s = 0.0;
  /// One line: the rule, the bound, the gains.
  std::string message;
};

/// The design on `plant` (linear; its dead time included). kInvalidInput for
/// a nonlinear plant or invalid options; kInvalidInput naming the bound when
/// no PID with a positive ki meets it.
Status DesignMigo(const Plant& plant, const MigoOptions& options, MigoDesign* design);

/// The design's second stage: the setpoint weight b (c = 0) that holds the
/// setpoint step's overshoot on `loop` to options.max_overshoot_pct
/// (SetpointWeightForOvershoot), into design->b, design->c and *two_dof.
Status MigoSetpointWeights(const Plant& plant, const evaluation::LoopOptions& loop,
                           const MigoOptions& options, MigoDesign* design, TwoDofSummary* two_dof);

/// DesignMigo, then MigoSetpointWeights; where b = 0 still overshoots more
/// than kMigoMaxOvershootAtZeroB, the overshoot comes from the integral
/// action itself: the bound is tightened in steps of 0.05 (down to 1.2) and
/// the design's message says so. (tune --method migo.)
Status DesignMigoForSetpoint(const Plant& plant, const evaluation::LoopOptions& loop,
                             const MigoOptions& options, MigoDesign* design, TwoDofSummary* two_dof);

/// `--robustness` as a phase margin: the range it takes (deg); an Ms bound is
/// in (1, 4], so the two never meet.
inline constexpr double kMigoMinPhaseMarginDeg = 20.0;
inline constexpr double kMigoMaxPhaseMarginDeg = 80.0;

/// The largest Ms bound in [1.05, 4] whose design (DesignMigo with *options
/// otherwise) keeps a phase margin of at least `phase_margin_deg` (bisection
/// on log Ms, 10 designs), into options->ms. kInvalidInput naming the margin
/// when even Ms 1.05 does not keep it.
Status MigoMsForPhaseMargin(const Plant& plant, double phase_margin_deg, MigoOptions* options);

/// A time scale for evaluating a loop: the horizon and the sample spacing.
struct TimeScale {
  double horizon_s = 25.0, sample_time_s = 0.05;
  /// "given", "eq. (4)" (the paper's presets) or "plant" (derived here).
  std::string source = "eq. (4)";
  /// Why: one clause.
  std::string reason;
  /// migo: where its Ms bound came from ("given", or SIMC's Ms on the plant).
  std::string robustness_reason;
  /// optimal: where its noise-gain bound came from ("given", or migo's).
  std::string noise_gain_reason;
  /// Why the method is what it is: "given", the default (the design engine),
  /// or the flag that asked for the search instead, in one clause.
  std::string method_reason;
};

/// The horizon and sample spacing a loop with closed-loop time constants
/// between `fastest_s` and `slowest_s` and a dead time `delay_s` is evaluated
/// on: the horizon ten slowest time constants and the delay, rounded up to 1,
/// 2 or 5 times a power of ten; the spacing a 500th of it, or a fifth of the
/// fastest time constant where that is shorter (at most 20000 samples).
TimeScale LoopTimeScale(double fastest_s, double slowest_s, double delay_s);

/// 1, 2 or 5 times a power of ten, at least v > 0.
double NiceUp(double v);

/// The plant's characteristic times (s), slowest and fastest, from its poles,
/// zeros, dead time and gain crossover (never 0 or infinite).
void PlantTimes(const Plant& plant, double* fastest_s, double* slowest_s);

/// The roots of a polynomial (highest power first) with its exact roots at
/// the origin (trailing zero coefficients) taken out first, their number
/// into *at_origin (may be null): root finding scatters a multiple root.
std::vector<std::complex<double>> RootsOffTheOrigin(std::vector<double> coefficients, int* at_origin);

/// 1 / w at the plant's lowest unity-gain frequency |G(jw)| = 1 (s), by
/// bisection on a log scale over [1e-12, 1e12] rad/s.
double UnityGainTime(const Plant& plant);

}  // namespace pidlab::tune
