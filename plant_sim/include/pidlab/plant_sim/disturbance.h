#pragma once
// Disturbance signals n(t), added to the plant input as in eq. (18):
// the plant sees u(t) + n(t).

#include <cstdint>
#include <string>

namespace pidlab {

enum class DisturbanceKind { kNone, kSquare, kStep, kSine, kNoise, kPrbs };

/// Parses none|square|step|sine|noise|prbs.
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

  /// Finite amplitude and phase, a positive finite period (square, sine),
  /// step time >= 0 (step) or hold (noise, prbs), and no finite value beyond
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
/// spectrum up to about 0.4 / hold Hz.
class Disturbance {
 public:
  explicit Disturbance(const DisturbanceOptions& options);

  double Value(double t) const;
  /// True for none, square, step, noise and prbs: constant between breakpoints.
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

}  // namespace pidlab
