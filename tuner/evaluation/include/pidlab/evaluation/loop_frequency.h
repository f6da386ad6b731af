#pragma once
// The continuous loop's frequency response L(jw) = C(jw) G(jw) e^(-jwL) and
// the Nyquist count of its encirclements of -1 (docs/deadtime.md, "Stability:
// the Nyquist count"): the stability test of the continuous loop with dead
// time, used by the evaluation (the delayed loop) and by the analysis
// (margins, peaks), which builds on the same response.

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/transfer_function.h"
#include "pidlab/spec/status.h"

namespace pidlab::evaluation {

/// The Nyquist criterion for the continuous loop (with its dead time): Z = N + P
/// closed-loop poles in the open right half-plane, N the clockwise
/// encirclements of -1 by L(jw), w from -inf to inf, P the open-loop poles in
/// the open right half-plane; open-loop poles on the imaginary axis (the
/// integrators, the oscillator's +-j) are passed on the right by small
/// semicircles.
struct NyquistCount {
  /// False when 1 + L(jw) comes within 1e-12 of 0 (a pole on the axis) or the
  /// count is not an integer to 0.1: then stable is false.
  bool decided = false;
  bool stable = false;
  int open_loop_rhp_poles = 0;    // P
  int open_loop_axis_poles = 0;   // on the imaginary axis, with multiplicity
  int encirclements = 0;          // N, clockwise
  int closed_loop_rhp_poles = 0;  // Z = N + P
  double winding_turns = 0.0;     // -N before rounding
  std::string note;
};

/// The reduced controller C = num/den of the continuous PID in descending
/// powers (no factor common to both: ki = 0 drops the integrator, kd = 0 the
/// filter).
void ContinuousPidPolynomials(const PidGains& loop_gains, std::vector<double>* num, std::vector<double>* den);

/// The Nyquist count of the continuous loop of tf e^(-s delay_s) with the
/// loop's gains (LoopGains) on the analysis grid of `points_per_decade`. A failed Status
/// (kInvalidInput) when resolving e^(-jwL) takes more than kMaxDelayGridPoints.
Status CountContinuousNyquist(const TransferFunction& tf, const PidGains& loop_gains, double delay_s,
                              double points_per_decade, NyquistCount* count);

/// The closed-loop roots of 1 + C(s) G(s) e^(-s delay_s) = 0 right of the line
/// Re s = sigma: the Nyquist count of the loop on that line (s = sigma + jw,
/// the shifted polynomials a(s), b(s) and e^(-sigma L) e^(-jwL)), P the
/// open-loop poles right of the line, Z = N + P the closed-loop roots right of
/// it. sigma = 0 is CountContinuousNyquist. A line within 1e-8 max(1, |p|) of
/// an open-loop pole p's real part is moved left by that much
/// (frequency::LineClearOfPoles). A failed Status (kInvalidInput) as CountContinuousNyquist.
Status CountContinuousRootsRightOf(const TransferFunction& tf, const PidGains& loop_gains, double delay_s,
                                   double sigma, double points_per_decade, NyquistCount* count);

/// The spectral abscissa of the continuous loop with dead time: alpha = max Re s
/// over the roots of 1 + C(s) G(s) e^(-sL) = 0 (docs/deadtime.md, "The slowest
/// time constant with dead time").
struct SpectralAbscissa {
  /// False when it is not computed (a neutral loop, a count that does not
  /// decide, a grid too large): then `note` says why and alpha is NaN.
  bool found = false;
  double alpha = std::numeric_limits<double>::quiet_NaN();  // 1/s
  /// The rightmost root (Im >= 0) when Newton's polish converged inside the
  /// bisection's strip, else NaN.
  std::complex<double> root{std::numeric_limits<double>::quiet_NaN(), 0.0};
  /// The width of the last strip [lo, hi] known to hold alpha (the bisection's
  /// tolerance; with a polished root, alpha is that root's real part).
  double strip_width = std::numeric_limits<double>::quiet_NaN();
  bool polished = false;
  int counts = 0;  // shifted Nyquist counts taken
  std::string note;
};

/// The spectral abscissa of the retarded continuous loop of tf e^(-s delay_s)
/// (delay_s > 0) with `loop_gains`, known to be stable (Z = 0 on the
/// imaginary axis): counts on shifted lines (CountContinuousRootsRightOf)
/// walk left from 0 until a line has a root right of it, bisection narrows the
/// strip to 1e-7 of its distance from 0, and Newton on b(s) + a(s) e^(-sL)
/// from the strip's best points polishes the rightmost root. False with
/// *error for invalid input; true with abscissa->found false when the loop
/// is neutral or a count fails.
Status ContinuousSpectralAbscissa(const TransferFunction& tf, const PidGains& loop_gains, double delay_s,
                                  double points_per_decade, SpectralAbscissa* abscissa);

namespace frequency {

using Polynomial = std::vector<double>;
using cd = std::complex<double>;
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kPi = 3.14159265358979323846;

inline Polynomial Trim(Polynomial p) {
  std::size_t i = 0;
  while (i + 1 < p.size() && p[i] == 0.0) ++i;
  p.erase(p.begin(), p.begin() + static_cast<long>(i));
  if (p.empty()) p.push_back(0.0);
  return p;
}

inline Polynomial Mul(const Polynomial& a, const Polynomial& b) {
  Polynomial r(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return Trim(r);
}

inline Polynomial Add(const Polynomial& a, const Polynomial& b) {
  const std::size_t n = std::max(a.size(), b.size());
  Polynomial r(n, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) r[n - a.size() + i] += a[i];
  for (std::size_t i = 0; i < b.size(); ++i) r[n - b.size() + i] += b[i];
  return Trim(r);
}

inline int Degree(const Polynomial& p) {
  const Polynomial t = Trim(p);
  return t.size() == 1 && t[0] == 0.0 ? -1 : static_cast<int>(t.size()) - 1;
}

inline cd Eval(const Polynomial& p, cd s) {
  cd v = 0.0;
  for (double c : p) v = v * s + c;
  return v;
}

// The loop at one frequency: L = a / b, S = b / (a + b), T = a / (a + b),
// C S = c / (a + b). Non-finite where L has a pole on the axis.
struct Point {
  cd a, b, c;
  bool Finite() const {
    return std::isfinite(std::abs(a)) && std::isfinite(std::abs(b)) && std::isfinite(std::abs(c)) &&
           std::abs(a + b) > 0.0;
  }
};

// The frequency response of one loop, continuous or sampled.
class Response {
 public:
  virtual ~Response() = default;
  virtual Point At(double w) const = 0;
};

// L = C G e^{-s delay}: the dead time multiplies a (its |.| is 1 on the axis).
class ContinuousResponse : public Response {
 public:
  ContinuousResponse(const TransferFunction& plant, const PidGains& g, double delay_s = 0.0)
      : delay_(delay_s) {
    ContinuousPidPolynomials(g, &nc_, &dc_);
    ng_ = Trim(plant.num);
    dg_ = Trim(plant.den);
    a_ = Mul(nc_, ng_);
    b_ = Mul(dc_, dg_);
    c_ = Mul(nc_, dg_);
    p_ = Add(a_, b_);
  }
  // The loop on the line Re s = sigma as a loop in p = s - sigma: a(p +
  // sigma) e^{-sigma L}, b(p + sigma), c(p + sigma) (Taylor shifts), the same
  // delay. At(w) of the result is the loop at s = sigma + jw.
  ContinuousResponse Shifted(double sigma) const;
  Point At(double w) const override {
    const cd s(0.0, w);
    if (delay_ > 0.0) return {Eval(a_, s) * std::polar(1.0, -w * delay_), Eval(b_, s), Eval(c_, s)};
    return {Eval(a_, s), Eval(b_, s), Eval(c_, s)};
  }
  double delay() const { return delay_; }
  const Polynomial& a() const { return a_; }
  const Polynomial& b() const { return b_; }
  const Polynomial& c() const { return c_; }
  const Polynomial& p() const { return p_; }
  const Polynomial& controller_num() const { return nc_; }
  // The limit of |x / p| as w -> inf (x of degree <= deg p, else +inf). With
  // dead time and deg a = deg b, p = a e^{-jwL} + b has no limit: the supremum
  // of |x / p| at infinity, |x0| / (|b0| - |a0|) (leading coefficients).
  double AtInfinity(const Polynomial& x) const {
    if (delay_ > 0.0 && Degree(a_) == Degree(b_)) {
      const int dx = Degree(x), db = Degree(b_);
      if (dx < db) return 0.0;
      const double gap = std::abs(Trim(b_)[0]) - std::abs(Trim(a_)[0]);
      return dx > db || !(gap > 0.0) ? kInf : std::abs(Trim(x)[0]) / gap;
    }
    const int dx = Degree(x), dp = Degree(p_);
    if (dx < dp) return 0.0;
    if (dx > dp) return kInf;
    return std::abs(Trim(x)[0] / Trim(p_)[0]);
  }

 private:
  Polynomial nc_, dc_, ng_, dg_, a_, b_, c_, p_;
  double delay_ = 0.0;
};

// Log grid over [lo, hi] merged with the special frequencies inside it.
std::vector<double> Grid(double lo, double hi, double per_decade, const std::vector<double>& special);

// Every frequency a narrow feature can sit at.
std::vector<double> SpecialFrequencies(const std::vector<cd>& roots);

// The open-loop poles' and zeros' frequencies and 1/L.
std::vector<double> OpenLoopFrequencies(const ContinuousResponse& r);

// Dead time: the analysis grid `base` (the loop's features) with points added
// below *w_top so that e^{-jwL} turns by at most pi/16 between neighbours;
// *w_top is where |L| falls below kSmallLoopGain for good on `base`, raised
// until the band holds a phase crossover. A failed Status (kInvalidInput) when that takes
// more than kMaxDelayGridPoints.
inline constexpr double kSmallLoopGain = 0.01;
inline constexpr std::size_t kMaxDelayGridPoints = 2000000;
Status DelayGrid(const ContinuousResponse& r, const std::vector<double>& base, std::vector<double>* w,
                 std::vector<Point>* pts, double* w_top);

// sigma, or, within kLineGapFromPoles max(1, |p|) of an open-loop pole p's
// real part, that far left of it (repeated while another pole is that near):
// a line through a pole would need an indentation of a pole that the shift
// leaves a rounding error off the axis.
inline constexpr double kLineGapFromPoles = 1e-8;
double LineClearOfPoles(const std::vector<cd>& poles, double sigma);

// The Nyquist count of r on its analysis grid (1e-3 x the slowest to 1e3 x
// the fastest open-loop feature at `per_decade`, e^{-jwL} resolved by
// DelayGrid), the grid and its points left in *w and *pts. A failed Status (kInvalidInput)
// as DelayGrid.
Status CountOnAnalysisGrid(const ContinuousResponse& r, double per_decade, std::vector<double>* w,
                           std::vector<Point>* pts, NyquistCount* count);

// The Nyquist count of the continuous loop over the grid `w` (increasing,
// reaching where |L| < 1 for good) with its points: encirclements of -1 by
// L(jw), w from -inf to inf, the open-loop poles on the axis indented.
NyquistCount CountEncirclements(const ContinuousResponse& r, const std::vector<double>& w,
                                const std::vector<Point>& pts);

}  // namespace frequency
}  // namespace pidlab::evaluation
