#pragma once
// `tune --method optimal` (docs/tuning.md, "The design engine"): the PI or
// PID with a first-order derivative filter that minimises the integrated
// absolute error of a unit load step at the plant input,
//
//   minimise   \int_0^inf |y_L(t)| dt        (r = 0, a unit step d at u)
//   subject to ||S||inf <= Ms,  ||T||inf <= Mt,  ||C S||inf <= noise gain,
//              Td = kd/kp <= the plant's dominant time constant,
//              the closed loop strictly stable,
//
// on the exact continuous loop, the plant's dead time included (JuliaSimControl's
// autotuning problem; Grimholt and Skogestad, J. Process Control 70, 2018).
// Then a second stage shapes the setpoint response: the weights b, c in
// [0, 1]^2 with the smallest setpoint \int|e|dt whose overshoot is within a
// target, and where no weights meet it (the integral action's own
// overshoot), a first-order setpoint filter r / (tr s + 1) with them; none
// of them can move the load response.
//
// The load response is simulated on a uniform grid whose step divides the
// dead time: the plant and the controller are discretised exactly (matrix
// exponentials), and the delayed controller output is linear between samples,
// so the error is second order in the step (about 1e-5 of the IAE here).
// The peaks are taken on the design's frequency grid, bounded above where the
// grid is too coarse for the delay's phase; the result is then checked by
// the exact analysis (AnalyzeLoop) and its gain scaled back until that meets
// the bounds too.
//
// The knobs move along the optimal front, the designs of every Ms bound:
// a response time T (or a gain crossover W = 2/T) is reached by the Ms bound
// whose optimal design crosses over at W, so slower always means a lower Ms
// and a larger load IAE.

#include <limits>
#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

/// The Ms range of the optimal front (`--response-time` and `--crossover`
/// move along it when `--robustness` is not given).
inline constexpr double kFrontMinMs = 1.1;
inline constexpr double kFrontMaxMs = 2.0;
/// The derivative filter's N = Td / tf is searched in [kDesignMinFilterRatio,
/// kDesignMaxFilterRatio].
inline constexpr double kDesignMinFilterRatio = 2.0;
inline constexpr double kDesignMaxFilterRatio = 50.0;
/// The default setpoint overshoot target of the second stage (%).
inline constexpr double kDesignDefaultOvershootPct = 10.0;

struct DesignOptions {
  /// Bound on ||S||inf, in (1, 4].
  double max_ms = 1.4;
  /// Bound on ||T||inf, >= 1; NaN: the same as max_ms.
  double max_mt = std::numeric_limits<double>::quiet_NaN();
  /// Bound on the noise gain ||C S||inf (> 0; +inf: none).
  double max_noise_gain = std::numeric_limits<double>::infinity();
  /// PI only (kd = 0).
  bool pi = false;
  /// 0, or the gain crossover (rad/s) to reach by moving along the front:
  /// the Ms bound in [kFrontMinMs, max_ms] whose design crosses over there.
  double crossover_rad_s = 0.0;
  /// The largest derivative time Td = kd / kp (s); 0: the plant's dominant
  /// time constant (DominantTimeConstant).
  double max_td_s = 0.0;
  /// The setpoint stage's overshoot target (%), >= 0; +inf: no target (the
  /// weights of the smallest setpoint IAE).
  double max_overshoot_pct = kDesignDefaultOvershootPct;
  /// Along a knob (`--robustness`, `--response-time`, `--crossover`): the
  /// overshoot target is also capped by the overshoot of the front's designs
  /// at the knots Ms = 2.0, 1.9, ... above this design's Ms bound, each
  /// capped the same way from the top, so a slower design never overshoots
  /// more (the knots' designs cost a design each).
  bool monotone_front = false;
  /// Search for the gap to the unconstrained design (DesignSummary::
  /// unconstrained_*; a short search where a bound but Ms is active). Off
  /// for the front's knots, whose overshoot alone is used.
  bool unconstrained_gap = true;
  /// The loop designed for: continuous (default), or the sampled loop at
  /// loop.dt_s (the ZOH plant and the discrete PID the trio and the exported
  /// C run): designed with the hold's half sample of delay, tf >= dt, and
  /// its bounds met by the sampled loop's exact analysis.
  evaluation::LoopOptions loop;

  /// Names the field, its value and the rule broken.
  bool IsValid(std::string* error) const;
  /// max_mt, or max_ms when NaN.
  double Mt() const;
};

/// One design of the engine.
struct DesignSummary {
  /// kp, ki, kd and the filter tf.
  PidGains gains;
  /// The setpoint weights b, c of the second stage, and its first-order
  /// setpoint filter's time constant tr (s; 0 = none), where b and c alone
  /// cannot meet the overshoot target.
  double b = 1.0, c = 1.0;
  double setpoint_filter_s = 0.0;
  /// \int|y|dt of the unit load step, and of the setpoint error 1 - y with
  /// the weights found; the setpoint step's overshoot (%) with them, and
  /// with b = c = 1.
  double load_iae = std::numeric_limits<double>::infinity();
  double setpoint_iae = std::numeric_limits<double>::infinity();
  double overshoot_pct = 0.0, overshoot_unit_weights_pct = 0.0;
  /// The setpoint stage met its overshoot target (false: the smallest
  /// overshoot b and c reach, said in `setpoint_note`).
  bool overshoot_met = true;
  std::string setpoint_note;
  /// The overshoot target the stage ran under (%): max_overshoot_pct, or
  /// along a knob the front's cap below it, said in `overshoot_cap_note`.
  double overshoot_target_pct = kDesignDefaultOvershootPct;
  std::string overshoot_cap_note;
  /// The exact analysis of the loop (AnalyzeLoop): Ms, Mt, the noise gain,
  /// the highest gain crossover (rad/s) and the phase margin (deg).
  double ms = 0.0, mt = 0.0, noise_gain = 0.0, crossover_rad_s = 0.0, phase_margin_deg = 0.0;
  /// The response time 2 / crossover (s), the one the knob moves.
  double response_time_s = 0.0;
  /// The Ms bound the design ran under (max_ms, or the front's point for a
  /// crossover), and the bounds as given.
  double ms_bound = 0.0, mt_bound = 0.0, noise_gain_bound = 0.0, td_bound_s = 0.0;
  /// The constraints within 1 % of their bound at the optimum: "ms", "mt",
  /// "noise_gain", "td".
  std::vector<std::string> active;
  /// The gap to the unconstrained design: the least load \int|e|dt under
  /// the same Ms bound alone, the other bounds active at the optimum
  /// ("mt", "noise_gain", "td") dropped (`dropped`), searched from this
  /// design; the gap is 100 (load_iae / unconstrained_load_iae - 1) %. Where
  /// none of them is active, the same design (gap 0, nothing dropped).
  double unconstrained_load_iae = std::numeric_limits<double>::quiet_NaN();
  double unconstrained_gap_pct = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::string> dropped;
  /// One clause: what the bounds cost, or why the gap is 0.
  std::string unconstrained_note;
  /// A crossover asked for that the front does not reach within 1 % (it
  /// jumps there: another optimum takes over): the nearest design, said so.
  std::string front_note;
  /// The plant acts in reverse (a negative gain): designed as -G, the gains
  /// all <= 0 (said in `message`).
  bool reverse_acting = false;
  /// Candidates evaluated (each a load-step simulation).
  int evaluations = 0;
  /// One line: the engine, the bounds, the gains and the load IAE.
  std::string message;
};

/// The plant's dominant time constant: its slowest stable pole off the
/// origin (s); where it has none, its slowest characteristic time (PlantTimes).
double DominantTimeConstant(const Plant& plant);

/// The design on `plant` (linear, strictly proper or proper, its dead time
/// included; a reverse-acting plant gets gains <= 0). kInvalidInput naming
/// the cause: invalid options, a nonlinear plant, no stable loop that meets
/// the bounds, or a crossover outside the front's reachable range (the
/// range named).
Status DesignOptimal(const Plant& plant, const DesignOptions& options, DesignSummary* summary);

/// `--robustness` as a phase margin (deg, in [20, 80]): the largest Ms
/// bound in [1.05, 4] whose design (with *options otherwise) keeps it
/// (bisection, 12 designs), into options->max_ms. kInvalidInput naming the
/// margin when even Ms 1.05 does not keep it.
Status DesignMsForPhaseMargin(const Plant& plant, double phase_margin_deg, DesignOptions* options);

/// The default noise-gain bound of the design engine, per unit of the
/// plant's ultimate gain (docs/tuning.md, "The design engine").
inline constexpr double kDefaultNoiseGainPerUltimateGain = 10.0;

/// The plant's ultimate gain Ku = 1 / |G(j w180)| at the lowest frequency
/// w180 (into *w180) where its phase, dead time included, reaches -180 deg;
/// +inf (w180 = 0) where it never does.
double UltimateGain(const Plant& plant, double* w180);

/// The default noise-gain bound: kDefaultNoiseGainPerUltimateGain x Ku
/// (+inf where the plant has no ultimate gain); *why says so in one clause.
double DefaultNoiseGain(const Plant& plant, std::string* why);

/// The unit load step's \int|y|dt of `gains` on the continuous loop of
/// `plant` (dead time included), by the engine's simulation; +inf when the
/// response does not settle (an unstable loop). Independent of the
/// evaluation library's, for cross-checks.
double DesignLoadIae(const Plant& plant, const PidGains& gains);

}  // namespace pidlab::tune
