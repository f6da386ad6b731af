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
#include "pidlab/evaluation/loop_frequency.h"

namespace pidlab::analysis::loop_internal {

// The continuous loop's response and the Nyquist count live in the
// evaluation library (pidlab/evaluation/loop_frequency.h), which needs them
// for the stability of the delayed loop.
using evaluation::NyquistCount;
using evaluation::frequency::Add;
using evaluation::frequency::cd;
using evaluation::frequency::ContinuousResponse;
using evaluation::frequency::CountEncirclements;
using evaluation::frequency::Degree;
using evaluation::frequency::DelayGrid;
using evaluation::frequency::Eval;
using evaluation::frequency::Grid;
using evaluation::frequency::kInf;
using evaluation::frequency::kMaxDelayGridPoints;
using evaluation::frequency::kNaN;
using evaluation::frequency::kPi;
using evaluation::frequency::kSmallLoopGain;
using evaluation::frequency::Mul;
using evaluation::frequency::Point;
using evaluation::frequency::Response;
using evaluation::frequency::SpecialFrequencies;
using evaluation::frequency::Trim;

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
    if (g.ki != 0.0) {
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
    if (g.kd != 0.0) {
      num = Add(Mul(num, {1.0, -a}), Mul(Mul({b}, {1.0, -1.0}), den));
      den = Mul(den, {1.0, -a});
    }
    nc_ = num;
    dc_ = den;
  }
  Point At(double w) const override {
    const cd z = std::polar(1.0, w * dt_);
    // The plant with its dead time: z^-d C (zI - Phi)^-1 (Gamma0 z + Gamma1)
    // (docs/deadtime.md); without one, C (zI - Phi)^-1 Gamma.
    cd g = static_cast<int>(phi_.rows()) <= kSmallOrder ? SmallPlantAt(z) : PlantAt(z);
    if (delay_steps_ > 0) g *= std::polar(1.0, DelayPhase(w));
    const cd nc = Eval(nc_, z);
    return {nc * g, Eval(dc_, z), nc};
  }
  const Polynomial& controller_num() const { return nc_; }
  // The phase of z^{-d} at w, rad.
  double DelayPhase(double w) const { return -w * dt_ * static_cast<double>(delay_steps_); }

 private:
  // Up to this order the plant's response is solved on the stack: the
  // analysis asks for it at thousands of frequencies per loop (a tuning's
  // Ms bound at every evaluation), where Eigen's dynamic LU spent more time
  // allocating and scoring pivots by hypot than solving.
  static constexpr int kSmallOrder = 8;

  cd PlantAt(cd z) const {
    const int n = static_cast<int>(phi_.rows());
    Eigen::MatrixXcd m = -phi_.cast<cd>();
    for (int i = 0; i < n; ++i) m(i, i) += z;
    const Eigen::VectorXcd x =
        delay_steps_ == 0 ? m.partialPivLu().solve(gamma1_.cast<cd>()).eval()
                          : m.partialPivLu().solve(gamma1_.cast<cd>() + gamma0_.cast<cd>() * z).eval();
    return (c_.cast<cd>() * x)(0);
  }

  // (zI - Phi) x = Gamma1 + z Gamma0 by Gaussian elimination with partial
  // pivoting on |Re| + |Im| (LAPACK's zgetrf choice), then C x.
  cd SmallPlantAt(cd z) const {
    const int n = static_cast<int>(phi_.rows());
    cd m[kSmallOrder][kSmallOrder], x[kSmallOrder];
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) m[i][j] = cd(-phi_(i, j), 0.0);
      m[i][i] += z;
      x[i] = delay_steps_ == 0 ? cd(gamma1_(i), 0.0) : gamma1_(i) + gamma0_(i) * z;
    }
    const auto modulus1 = [](cd v) { return std::abs(v.real()) + std::abs(v.imag()); };
    for (int k = 0; k < n; ++k) {
      int p = k;
      for (int i = k + 1; i < n; ++i)
        if (modulus1(m[i][k]) > modulus1(m[p][k])) p = i;
      if (p != k) {
        for (int j = k; j < n; ++j) std::swap(m[k][j], m[p][j]);
        std::swap(x[k], x[p]);
      }
      if (m[k][k] == cd(0.0, 0.0)) return PlantAt(z);  // singular here: Eigen's answer (inf or NaN)
      const cd inverse = 1.0 / m[k][k];
      for (int i = k + 1; i < n; ++i) {
        const cd f = m[i][k] * inverse;
        for (int j = k + 1; j < n; ++j) m[i][j] -= f * m[k][j];
        x[i] -= f * x[k];
      }
    }
    cd g = 0.0;
    for (int i = n - 1; i >= 0; --i) {
      for (int j = i + 1; j < n; ++j) x[i] -= m[i][j] * x[j];
      x[i] /= m[i][i];
      g += c_(i) * x[i];
    }
    return g;
  }

  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma1_, gamma0_;
  Eigen::RowVectorXd c_;
  double dt_;
  long delay_steps_;
  Polynomial nc_, dc_;
};

// loop_response.cc

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

// loop_analysis.cc

// 1 / min |Re p| over the s-plane poles (NaN for none).
double SlowestTimeConstant(const std::vector<cd>& s_poles);

}  // namespace pidlab::analysis::loop_internal
