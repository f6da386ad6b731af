#pragma once
// Frequency-domain analysis of a PID loop: margins, sensitivity peaks, noise
// gain, the slowest closed-loop time constant and near pole-zero
// cancellations (docs/robustness.md).
//
// Loops, both with the gains of LoopGains (so with the loop's derivative filter):
//  * continuous: L(s) = C(s) G(s), C(s) = kp + ki/s + kd s/(tf s + 1)
//    (tf = 0: the ideal kp + ki/s + kd s), G the plant's transfer function;
//  * sampled: L(z) = C(z) G(z) at z = e^{j w dt}, 0 < w <= pi/dt (Nyquist),
//    C(z) the DiscretePid's transfer function (its integral rule, its
//    derivative filter D(z) = kd/(tf+dt) (z-1)/(z - tf/(tf+dt))), G(z) the
//    exact ZOH plant C (zI - Phi)^-1 Gamma of the lockstep loop.
// S = 1/(1+L), T = L/(1+L), noise gain = |C S| (measurement noise to u).
// A plant with dead time (Plant::delay_s = L > 0) multiplies the continuous
// L(s) by e^{-sL} exactly (docs/deadtime.md, "Analysis: exact in frequency"):
// its stability is the Nyquist count (CountNyquist), its crossovers are
// bracketed on a grid on which e^{-jwL} turns by at most pi/16 per point, and
// no closed-loop pole is computed (no time constant, no cancellation). The
// sampled loop with dead time holds it as z^{-d} times the ZOH plant of the
// remaining fraction of a step (plant_sim/discrete_plant.h).
//
// Peaks are found by a method that cannot miss a narrow one: a log grid
// (points_per_decade) merged with every frequency where a narrow feature can
// sit (|p| and |Im p| of every closed-loop pole, |p| of every open-loop pole
// and zero), golden-section refinement on log w at every local maximum of the
// grid, and for the continuous loop a Bruinsma-Steinbuch Hamiltonian
// iteration started from that value, which ends only when no frequency has a
// larger gain (it raises the value if the grid missed anything). Crossovers
// are sign changes of log|L| and of sin(arg L) on the same grid, refined by
// bisection.

#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/loop_frequency.h"
#include "pidlab/spec/status.h"

namespace pidlab::analysis {

struct LoopAnalysisOptions {
  /// Log-grid density; the grid spans 1e-3 x the slowest to 1e3 x the fastest
  /// characteristic frequency (sampled loop: up to pi/dt). > 0, <= 10000.
  double points_per_decade = 100.0;
  /// Golden-section refinement of every local maximum (false: the grid value).
  bool refine_peaks = true;
  /// Confirm the continuous peaks by the Bruinsma-Steinbuch iteration.
  bool hamiltonian_check = true;
  /// A closed-loop pole p and a controller zero q cancel nearly when
  /// |p - q| <= cancellation_tolerance * |q| (s-plane; sampled: log(z)/dt).
  double cancellation_tolerance = 0.02;
  /// With dead time (continuous loop), the slowest time constant -1/alpha from
  /// the spectral abscissa alpha (evaluation::ContinuousSpectralAbscissa, about
  /// 30 shifted Nyquist counts). False leaves it NaN with a note (the tuner's
  /// gate counts once on the line of its bound instead).
  bool delayed_time_constant = true;

  bool IsValid(std::string* error) const;
};

/// A closed-loop pole near a controller zero (s-plane values).
struct Cancellation {
  std::complex<double> pole, zero;
  double relative_distance = 0.0;  // |pole - zero| / |zero|
};

/// Infinite values mean "none" (no crossover: an infinite margin) or
/// "unbounded" (noise gain of the ideal derivative); *_note says which.
struct LoopAnalysis {
  evaluation::LoopKind loop = evaluation::LoopKind::kContinuous;
  bool stable = false;
  /// Gain margin as a factor (not dB): the phase crossover whose 1/|L| is
  /// closest to 1 on a log scale; < 1 is a gain-reduction margin. +inf: none.
  double gain_margin = std::numeric_limits<double>::infinity();
  double phase_crossover_rad_s = std::numeric_limits<double>::quiet_NaN();
  /// The phase margin, degrees, >= 0: min over the gain crossovers of
  /// |arg L + 180 deg| wrapped to [0, 180] (MATLAB's `margin`: the smallest
  /// distance in phase to the critical point). +inf: no gain crossover.
  double phase_margin_deg = std::numeric_limits<double>::infinity();
  double gain_crossover_rad_s = std::numeric_limits<double>::quiet_NaN();
  /// min over gain crossovers of PM_i / w_i, s (sampled loop too). +inf: none.
  double delay_margin_s = std::numeric_limits<double>::infinity();
  std::vector<double> gain_crossovers_rad_s, phase_crossovers_rad_s;
  /// Every crossover's own margin (MATLAB's `allmargin`), in the order of the
  /// crossovers: arg L + 180 deg wrapped to (-180, 180] at each gain
  /// crossover, and 1/|L| at each phase crossover.
  std::vector<double> phase_margins_deg, gain_margins;
  /// The plant's dead time the analysis used, s (0: rational loop).
  double delay_s = 0.0;
  /// Peaks and where they are (frequency +inf: approached as w -> inf).
  double ms = std::numeric_limits<double>::quiet_NaN(), ms_rad_s = 0.0;
  double mt = std::numeric_limits<double>::quiet_NaN(), mt_rad_s = 0.0;
  double noise_gain = std::numeric_limits<double>::quiet_NaN(), noise_gain_rad_s = 0.0;
  /// 1 / min |Re p| over the closed-loop poles (s-plane), s.
  double slowest_time_constant_s = std::numeric_limits<double>::quiet_NaN();
  std::vector<Cancellation> cancellations;
  std::string gain_margin_note, phase_margin_note, noise_gain_note;
  /// Set when slowest_time_constant_s is not known (NaN): why. With dead time
  /// it comes from the spectral abscissa (no pole is listed, so no
  /// cancellation either), and stays NaN for an unstable or a neutral loop.
  std::string time_constant_note;
  /// How stability was decided with dead time (the Nyquist count), else "".
  std::string stability_note;
  /// How the peaks were found (for the report and JSON).
  std::string method;
};

/// The Nyquist count (pidlab/evaluation/loop_frequency.h, where the evaluation
/// of the delayed loop needs it).
using evaluation::NyquistCount;

/// The Nyquist count of the continuous loop of `plant` (with plant.delay_s)
/// with `gains` (LoopGains of `options`). kInvalidInput naming the value for
/// invalid input, as AnalyzeLoop.
Status CountNyquist(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                    NyquistCount* count);

/// Analyses the loop of `plant` with `gains` (LoopGains of `options`) for
/// options.loop. kInvalidInput naming the value for invalid input (as
/// Evaluate). An unstable loop is not an error: analysis->stable is false
/// and only the poles' time constant and cancellations are filled.
Status AnalyzeLoop(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                   const LoopAnalysisOptions& analysis_options, LoopAnalysis* analysis);

/// The loop at one frequency: L = C G, S = 1/(1+L), T = L/(1+L) and the
/// noise gain's C S (the report's Bode and Nyquist figures, the workbench's plots).
struct LoopFrequencyPoint {
  double w_rad_s = 0.0;
  std::complex<double> l, s, t, cs;
  /// The phase of the pure delay in l, rad (<= 0): -w L of the continuous
  /// loop's e^{-jwL}, -w d dt of the sampled loop's z^{-d} (d the whole steps
  /// of DiscretePlant::delay_steps(); the fraction of a step is in the ZOH
  /// plant's rational part). 0 without dead time.
  double delay_phase_rad = 0.0;
};

/// L, S, T and C S of the loop of `plant` with `gains` (LoopGains of
/// `options`, so with its derivative filter) at every w of `w_rad_s`, in that
/// order: the continuous loop at s = jw (L with e^{-jw plant.delay_s}; w
/// finite, > 0), or the sampled loop options.loop names at z = e^{jw dt}
/// (the DiscretePid and the exact ZOH plant, as AnalyzeLoop; 0 < w <= pi/dt).
/// S, T and C S are computed as b/(a+b), a/(a+b) and c/(a+b) from L = a/b,
/// so they stay finite where L has a pole on the axis (L infinite, S = 0,
/// T = 1). kInvalidInput for invalid input or a frequency out of range.
Status LoopFrequencyResponse(const Plant& plant, const PidGains& gains,
                             const evaluation::LoopOptions& options, const std::vector<double>& w_rad_s,
                             std::vector<LoopFrequencyPoint>* response);

/// The phase of L in degrees at every point of `response` (LoopFrequencyResponse
/// of this loop at increasing frequencies), continuous in w: the phase of L's
/// rational part, l e^{-j delay_phase_rad}, followed from its low-frequency
/// asymptote c (jw)^-k (taken in (-315, 45] degrees; six decades below the
/// first point) and along the points, each step of more than 45 degrees
/// bisected until it is resolved; plus the pure delay's phase exactly, in
/// degrees. Equal to arg l modulo 360 at every point; NaN where l is not
/// finite. Every figure of a loop's phase uses it (docs/workbench.md, "The
/// phase"). kInvalidInput as LoopFrequencyResponse, or for frequencies that
/// do not increase.
Status LoopPhaseDeg(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                    const std::vector<LoopFrequencyPoint>& response, std::vector<double>* phase_deg);

/// Bounds on a loop (+inf / 0 = none), checked by LoopBoundsViolation.
struct LoopBounds {
  double max_ms = std::numeric_limits<double>::infinity();
  double max_mt = std::numeric_limits<double>::infinity();
  double max_noise_gain = std::numeric_limits<double>::infinity();
  /// Degrees; a loop without a gain crossover meets any bound.
  double min_phase_margin_deg = 0.0;
  /// Factor (> 1 or 0); every phase crossover must have 1/|L| >= g or <= 1/g.
  double min_gain_margin = 0.0;
  double max_time_constant_s = std::numeric_limits<double>::infinity();

  bool Any() const;
  bool IsValid(std::string* error) const;
};

/// Every bound `a` breaks, one line each ("Ms 1.83 > 1.6"); empty if it meets
/// them all. An unstable loop breaks them all at once ("unstable loop").
std::vector<std::string> LoopBoundsViolations(const LoopAnalysis& a, const LoopBounds& bounds);
/// The first of LoopBoundsViolations, or "".
std::string LoopBoundsViolation(const LoopAnalysis& a, const LoopBounds& bounds);

/// The tuner's cheap check of the continuous loop (a coarse grid, refinement
/// only of peaks within 10 % of their bound, no Hamiltonian iteration, an early
/// exit at the first bound clearly broken). True if every bound is met.
/// `loop` and `stability` are those of the candidate (stable).
bool ContinuousLoopMeetsBounds(const TransferFunction& plant, const PidGains& loop_gains,
                               const evaluation::Stability& stability, const LoopBounds& bounds);

// ---- Building blocks, public for tests.

/// Polynomials in descending powers.
using Polynomial = std::vector<double>;
/// The reduced controller C = num/den of the continuous PID (loop_frequency.h).
using evaluation::ContinuousPidPolynomials;
/// The H-infinity norm of the stable num/den (deg num <= deg den) by the
/// Bruinsma-Steinbuch iteration from the lower bound `gamma_lower`; the
/// frequency of the peak in *w_peak (+inf if at infinity). Relative accuracy `tol`.
double HinfNormBruinsmaSteinbuch(const Polynomial& num, const Polynomial& den, double gamma_lower,
                                 double w_lower, double tol, double* w_peak);

}  // namespace pidlab::analysis
