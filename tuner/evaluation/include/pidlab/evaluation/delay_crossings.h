#pragma once
// Stability of the retarded continuous loop with dead time by its crossing
// frequencies (docs/deadtime.md, "Stability: the crossing frequencies"): the
// closed-loop roots are those of f(s) = b(s) + a(s) e^(-sL), L = a / b the
// loop without its delay, deg a < deg b. As the delay grows from 0 (where f
// is the polynomial a + b) the roots move continuously and reach the
// imaginary axis only at the frequencies w_c > 0 where |a(jw)| = |b(jw)|,
// the positive roots in nu = w^2 of the polynomial
//
//   F(nu) = |b(jw)|^2 - |a(jw)|^2,
//
// at the delays tau_k = (theta_c + 2 pi k) / w_c, e^(-j w_c tau) = -b/a, and a
// pair crosses to the right when F'(nu_c) > 0, to the left when F'(nu_c) < 0
// (Cooke and van den Driessche, 1986). So the number of roots right of the
// axis at the delay L is
//
//   Z(L) = Z(0) + sum_c 2 sign F'(nu_c) #{k >= 0 : tau_k < L},
//
// a few polynomial roots instead of a Nyquist plot resolved in e^(-jwL): the
// same verdict as the Nyquist count wherever the loop is not within the
// tolerances below of the boundary, where this test leaves the decision to
// the count (kUndecided).

#include <limits>
#include <vector>

namespace pidlab::evaluation {

enum class CrossingVerdict { kStable, kUnstable, kUndecided };

/// A crossing of the axis whose phase w_c L - theta_c lies within this of a
/// multiple of 2 pi, relative to max(1, w_c L), is a root within rounding of
/// the axis: undecided (rad).
inline constexpr double kCrossingPhaseTolerance = 1e-8;
/// Roots of F or of a + b this close (relative) to the axis, to one another
/// or to being real are left undecided: a tangency of |L| = 1 or a loop
/// marginal without its delay.
inline constexpr double kCrossingRootTolerance = 1e-7;

struct CrossingCount {
  CrossingVerdict verdict = CrossingVerdict::kUndecided;
  int roots_without_delay = 0;  // Z(0): roots of a + b with Re s > 0
  int roots_right = 0;          // Z(L)
  int crossings = 0;            // crossing frequencies w_c > 0
  /// min over the crossings and k of |w_c L - theta_c - 2 pi k| / max(1, w_c L):
  /// how far the loop is from a root on the axis, in phase.
  double phase_gap = std::numeric_limits<double>::infinity();
};

/// The verdict on f(s) = b(s) + a(s) e^(-s delay_s) (coefficients in
/// descending powers, delay_s > 0): kStable when no root has Re s >= 0,
/// kUnstable when one has Re s > 0, kUndecided for a neutral loop (deg a >=
/// deg b) or within the tolerances above of the boundary.
CrossingCount CountRootsByCrossings(const std::vector<double>& a, const std::vector<double>& b,
                                    double delay_s);

}  // namespace pidlab::evaluation
