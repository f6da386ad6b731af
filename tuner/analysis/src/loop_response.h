#pragma once
// Internal to the analysis library: the loop's frequency response and the
// searches over it shared by loop_analysis.cc (AnalyzeLoop),
// loop_response.cc (peaks, H-infinity norm) and loop_margins.cc (crossovers,
// margins, bounds).

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"

namespace pidlab::analysis::loop_internal {

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

enum class Peak { kS, kT, kCs };

inline double Magnitude(const Point& p, Peak which) {
  const cd den = p.a + p.b;
  switch (which) {
    case Peak::kS:
      return std::abs(p.b / den);
    case Peak::kT:
      return std::abs(p.a / den);
    case Peak::kCs:
      return std::abs(p.c / den);
  }
  return kNaN;
}

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

class SampledResponse : public Response {
 public:
  SampledResponse(const DiscretePlant& plant, const PidGains& g, const PidOptions& o)
      : phi_(plant.phi()),
        gamma1_(plant.gamma1()),
        gamma0_(plant.gamma0().size() > 0 ? Eigen::VectorXd(plant.gamma0())
                                          : Eigen::VectorXd::Zero(plant.gamma1().size())),
        c_(plant.c()),
        dt_(o.dt_s),
        delay_steps_(plant.delay_steps()) {
    // C(z) = kp + I(z) + b (z - 1)/(z - a) over the common denominator.
    const double tf = EffectiveDerivativeFilter(g, o), dt = o.dt_s;
    const double a = tf / (tf + dt), b = g.kd / (tf + dt);
    Polynomial num{g.kp}, den{1.0};
    if (g.ki > 0.0) {
      Polynomial inum;
      switch (o.integral) {
        case IntegralMethod::kBackwardEuler:
          inum = {g.ki * dt, 0.0};
          break;
        case IntegralMethod::kForwardEuler:
          inum = {g.ki * dt};
          break;
        case IntegralMethod::kTrapezoidal:
          inum = {0.5 * g.ki * dt, 0.5 * g.ki * dt};
          break;
      }
      num = Add(Mul(num, {1.0, -1.0}), inum);
      den = {1.0, -1.0};
    }
    if (g.kd > 0.0) {
      num = Add(Mul(num, {1.0, -a}), Mul(Mul({b}, {1.0, -1.0}), den));
      den = Mul(den, {1.0, -a});
    }
    nc_ = num;
    dc_ = den;
  }
  Point At(double w) const override {
    const cd z = std::polar(1.0, w * dt_);
    const int n = static_cast<int>(phi_.rows());
    Eigen::MatrixXcd m = -phi_.cast<cd>();
    for (int i = 0; i < n; ++i) m(i, i) += z;
    // The plant with its dead time: z^-d C (zI - Phi)^-1 (Gamma0 z + Gamma1)
    // (docs/deadtime.md); without one, C (zI - Phi)^-1 Gamma.
    const Eigen::VectorXcd x =
        delay_steps_ == 0 ? m.partialPivLu().solve(gamma1_.cast<cd>()).eval()
                          : m.partialPivLu().solve(gamma1_.cast<cd>() + gamma0_.cast<cd>() * z).eval();
    cd g = (c_.cast<cd>() * x)(0);
    if (delay_steps_ > 0) g *= std::polar(1.0, -w * dt_ * static_cast<double>(delay_steps_));
    const cd nc = Eval(nc_, z);
    return {nc * g, Eval(dc_, z), nc};
  }
  const Polynomial& controller_num() const { return nc_; }

 private:
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma1_, gamma0_;
  Eigen::RowVectorXd c_;
  double dt_;
  long delay_steps_;
  Polynomial nc_, dc_;
};

// loop_response.cc

// Log grid over [lo, hi] merged with the special frequencies inside it.
std::vector<double> Grid(double lo, double hi, double per_decade, const std::vector<double>& special);

// Every frequency a narrow feature can sit at.
std::vector<double> SpecialFrequencies(const std::vector<cd>& roots);

// The grid's largest value, refined at every local maximum when `refine`
// (only at those above `refine_above`).
double PeakOnGrid(const Response& r, const std::vector<double>& w, const std::vector<Point>& pts, Peak which,
                  bool refine, double refine_above, double* w_peak);

// loop_margins.cc

struct Crossings {
  std::vector<double> gain, phase;
};

// Gain crossovers (|L| = 1) and phase crossovers (L real negative).
Crossings FindCrossings(const Response& r, const std::vector<double>& w, const std::vector<Point>& pts);

// The margins at the crossings, their frequencies and notes, into *a.
void SetMargins(const Response& r, const Crossings& c, LoopAnalysis* a);

// loop_nyquist.cc

// Dead time: the analysis grid `base` (the loop's features) with points added
// below *w_top so that e^{-jwL} turns by at most pi/16 between neighbours;
// *w_top is where |L| falls below kSmallLoopGain for good on `base`, raised
// until the band holds a phase crossover. False with *error when that takes
// more than kMaxDelayGridPoints.
inline constexpr double kSmallLoopGain = 0.01;
inline constexpr std::size_t kMaxDelayGridPoints = 2000000;
bool DelayGrid(const ContinuousResponse& r, const std::vector<double>& base, std::vector<double>* w,
               std::vector<Point>* pts, double* w_top, std::string* error);

// The Nyquist count of the continuous loop over the grid `w` (increasing,
// reaching where |L| < 1 for good) with its points: encirclements of -1 by
// L(jw), w from -inf to inf, the open-loop poles on the axis indented.
NyquistCount CountEncirclements(const ContinuousResponse& r, const std::vector<double>& w,
                                const std::vector<Point>& pts);

// loop_analysis.cc

// 1 / min |Re p| over the s-plane poles (NaN for none).
double SlowestTimeConstant(const std::vector<cd>& s_poles);

}  // namespace pidlab::analysis::loop_internal
