#pragma once
// Disturbance signals n(t), added to the plant input as in eq. (18):
// the plant sees u(t) + n(t).

#include <cmath>
#include <cstdint>
#include <string>

namespace pidlab {

enum class DisturbanceKind { kNone, kSquare, kStep, kSine, kNoise, kPrbs, kChirp };

/// Parses none|square|step|sine|noise|prbs|chirp.
bool ParseDisturbanceKind(const std::string& s, DisturbanceKind* kind);
std::string ToString(DisturbanceKind kind);

/// Bound on |amplitude|, period, |phase|, step time and noise hold (README.md,
/// "Exit status and limits"): beyond it t + phase loses the precision the
/// breakpoints need.
inline constexpr double kMaxDisturbanceMagnitude = 1e12;

struct DisturbanceOptions {
  DisturbanceKind kind = DisturbanceKind::kNone;
  /// Square and prbs: +/-amplitude. Step: final value. Sine: peak. Noise:
  /// std deviation.
  double amplitude = 0.0;
  /// Square and sine period in s. The paper does not state its period; 2 s
  /// (a switch every second) is pidlab's choice.
  double period_s = 2.0;
  /// Time shift in s: the signal is evaluated at t + phase_s.
  double phase_s = 0.0;
  /// Step time in s (step only).
  double step_time_s = 0.0;
  /// Noise is white, Gaussian and held constant over this interval in s; it
  /// is also the clock period of the prbs (one bit per interval).
  double noise_hold_s = 0.01;
  /// Seed of the noise and of the prbs; the value at t depends only on
  /// (seed, t).
  std::uint64_t seed = 1;
  /// Chirp: the linear sweep's start and end frequencies in Hz
  /// (0 <= f0 < f1) and its duration T in s (> 0; the spec's default is
  /// the horizon).
  double chirp_f0_hz = 0.0;
  double chirp_f1_hz = 0.0;
  double chirp_duration_s = 0.0;

  /// Finite amplitude and phase, a positive finite period (square, sine),
  /// step time >= 0 (step) or hold (noise, prbs), a band 0 <= f0 < f1 and a
  /// positive duration (chirp), and no finite value beyond
  /// kMaxDisturbanceMagnitude. Names the offending value on failure.
  bool IsValid(std::string* error) const;
};

/// n(t) for t >= 0 (zero before). Stateless: Value(t) is a pure function, so a
/// separate disturbance process computes exactly what an in-process loop does.
/// The square wave is +amplitude on [0, period/2) (after the phase shift) and
/// -amplitude on [period/2, period). The prbs is the maximal-length sequence
/// of the 15-bit shift register x^15 + x^14 + 1 (period 2^15 - 1 = 32767
/// bits), +amplitude for a 1 and -amplitude for a 0, bit k held over
/// [k hold, (k + 1) hold), starting at bit (seed mod 32767) of the sequence
/// (PrbsBit): an excitation for identification experiments, flat in
/// spectrum up to about 0.4 / hold Hz. The chirp is the linear sweep
/// amplitude sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))) for 0 <= t <= T, its
/// instantaneous frequency f0 + (f1 - f0) t / T, and 0 after T (the
/// experiment ends with the sweep); its phase is computed from t alone,
/// never accumulated, so that sample k at t = k dt is the same bits in every
/// process.
class Disturbance {
 public:
  explicit Disturbance(const DisturbanceOptions& options);

  double Value(double t) const;
  /// True for none, square, step, noise and prbs: constant between
  /// breakpoints (not sine and chirp).
  bool IsPiecewiseConstant() const;
  /// The first breakpoint strictly after t (+infinity if none). Only for
  /// piecewise-constant signals. Breakpoints closer than 1e-9 s to t count as t.
  double NextBreakpoint(double t) const;
  const DisturbanceOptions& options() const { return options_; }

 private:
  /// Index of the piece of length `piece` that t + shift falls in, robust to
  /// rounding at the piece boundaries.
  static double PieceIndex(double t, double piece);
  DisturbanceOptions options_;
};

/// The order of the prbs's shift register and the length of its sequence.
inline constexpr int kPrbsOrder = 15;
inline constexpr std::int64_t kPrbsLength = (std::int64_t{1} << kPrbsOrder) - 1;

/// Bit i (0 <= i < kPrbsLength) of the maximal-length sequence of
/// x^15 + x^14 + 1 from the register state 1, computed once.
bool PrbsBit(std::int64_t i);

/// Seeded Gaussian noise on the measured output: the plant reports
/// y_k + v_k, v_k = sigma N(0, 1) drawn from (seed, k) by a counter-based
/// generator (no state: a step sent again or replayed gets the same v_k).
/// Its stream differs from the noise disturbance's for the same seed: the
/// draw is the noise disturbance's with the seed SplitMix64(seed ^
/// kMeasurementNoiseStream). With a resolution q (a sensor's or an ADC's
/// step), the report is then rounded to the nearest multiple of q, halves
/// away from zero: q round((y_k + v_k) / q).
struct MeasurementNoise {
  /// Standard deviation of v_k, in the output's unit; 0 = none.
  double sigma = 0.0;
  std::uint64_t seed = 1;
  /// Resolution q of the measured y, in the output's unit; 0 = exact.
  double resolution = 0.0;

  /// sigma and resolution >= 0, finite, at most kMaxDisturbanceMagnitude.
  bool IsValid(std::string* error) const;
  bool enabled() const { return sigma != 0.0 || resolution != 0.0; }
  /// v_k (0 when sigma is 0).
  double Value(std::int64_t k) const;
  /// q round((y + v_k) / q); y + v_k without a resolution; y itself (the
  /// same bits) with neither.
  double Measured(double y, std::int64_t k) const {
    if (!enabled()) return y;
    const double noisy = sigma != 0.0 ? y + Value(k) : y;
    return resolution != 0.0 ? resolution * std::round(noisy / resolution) : noisy;
  }
};

inline constexpr std::uint64_t kMeasurementNoiseStream = 0x6d65617375726564ULL;  // "measured"

}  // namespace pidlab
