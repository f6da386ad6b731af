#pragma once
// The autotune's verification step read through the measurement noise
// (docs/autotune.md, "The verification"): a measured step under noise has a
// peak that is a noise spike and a band it leaves at random, so overshoot and
// settling are read from the step smoothed by a centred moving average whose
// width follows the noise the hold measured, within a band widened by the
// noise left after it.

#include <vector>

namespace pidlab::autotune {

/// The band's widening in residual sigmas: a record's tail holds tens of
/// independent windows, and 3 sigma is crossed by one of them about one time
/// in eight by chance; 4 sigma about one in three hundred.
inline constexpr double kBandSigmas = 4.0;

/// What the verification step's reading did and found.
struct StepReading {
  int window = 1;                ///< samples of the centred moving average (1: no noise, no filter)
  double noise_sigma = 0.0;      ///< the hold's measured noise
  double residual_sigma = 0.0;   ///< noise_sigma / sqrt(window): the noise the smoothing leaves
  double band = 0.0;             ///< the settling band's half-width: 2 % of the step + widening
  double widening = 0.0;         ///< kBandSigmas residual_sigma: the band's part from the noise
  double overshoot_pct = 0.0;    ///< of the smoothed response, % of the step (0 when below it)
  double settling_time_s = 0.0;  ///< from then on the smoothed response stays in the band
  /// In the band from settling_time_s to the end, for at least the last
  /// tail_s (an ultimate period): a loop that rings or drifts is not.
  bool settled = false;
  double tail_s = 0.0;
};

/// Reads a step from 0 to `reference` sampled uniformly at `t` (y the
/// measured output). The window is the least that brings kBandSigmas sigma / sqrt(w)
/// under 1 % of the step, at most a quarter of the ultimate period `pu_s`
/// (so the smoothing keeps the loop's own dynamics) and a tenth of the
/// record; 1 with no noise. Empty or mismatched input reads as not settled.
StepReading ReadVerificationStep(const std::vector<double>& t, const std::vector<double>& y, double reference,
                                 double noise_sigma, double pu_s);

}  // namespace pidlab::autotune
