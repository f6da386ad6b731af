// The slowest time constant of the continuous loop with dead time: the
// spectral abscissa alpha = max Re s over the roots of 1 + C G e^{-sL} = 0 by
// Nyquist counts on shifted lines (a Newton guess certified by two of them,
// else bisection) and Newton, against the Lambert W
// roots of kp e^{-sL}/s, roots found independently for e^{-s}/(s + 1), and the
// delay-free loop's poles as L -> 0.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/loop_frequency.h"
#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::analysis::LoopBounds;
using pidlab::analysis::LoopBoundsViolations;
using pidlab::evaluation::ContinuousSpectralAbscissa;
using pidlab::evaluation::CountContinuousRootsRightOf;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::NyquistCount;
using pidlab::evaluation::SpectralAbscissa;

namespace pidlab {
namespace {

using cd = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

TransferFunction Tf(std::vector<double> num, std::vector<double> den) {
  TransferFunction tf;
  tf.num = std::move(num);
  tf.den = std::move(den);
  return tf;
}

PidGains P(double kp) {
  PidGains g;
  g.kp = kp;
  return g;
}

SpectralAbscissa AbscissaOrFail(const TransferFunction& tf, const PidGains& g, double delay_s) {
  SpectralAbscissa sa;
  std::string error;
  EXPECT_TRUE(IsOk(ContinuousSpectralAbscissa(tf, g, delay_s, 100.0, &sa)));
  EXPECT_TRUE(sa.found) << sa.note;
  return sa;
}

// W_k(x) by Halley's iteration on w e^w = x from `w`.
cd LambertW(cd x, cd w) {
  for (int i = 0; i < 100; ++i) {
    const cd e = std::exp(w), f = w * e - x;
    const cd step = f / (e * (w + 1.0) - (w + 2.0) * f / (2.0 * w + 2.0));
    w -= step;
    if (std::abs(step) < 1e-15 * std::max(1.0, std::abs(w))) break;
  }
  return w;
}

// The Lambert W roots s = W_k(-kp L)/L of s + kp e^{-sL} = 0, principal
// branch, hard-coded from scipy and the in-test Halley iteration agreeing:
//   /usr/bin/python3 -c "from scipy.special import lambertw
//   for L,kp in [(0.5,0.2),(0.5,0.6),(0.5,1.0),(1.0,1.0),(0.5,2.0),(0.25,6.0)]:
//       w=lambertw(-kp*L,0)/L; print(L,kp,repr(w.real),repr(w.imag))"
struct LambertCase {
  double delay_s, kp, re, im;
};
const LambertCase kLambert[] = {
    {0.5, 0.2, -0.22366511831792593, 0.0},                // kp L = 0.1: real roots
    {0.5, 0.6, -0.9788044543604298, 0.0},                 // 0.3 (< 1/e)
    {0.5, 1.0, -1.5880472646893786, 1.5402235010207581},  // 0.5: a complex pair
    {1.0, 1.0, -0.3181315052047642, 1.3372357014306893},  // 1.0
    {0.5, 2.0, -0.6362630104095284, 2.6744714028613785},  // 1.0
    {0.25, 6.0, -0.1311349436622901, 6.198575293400637},  // 1.5, near pi/2
};

TEST(SpectralAbscissa, IsThePrincipalLambertWRootForPControlOfADelayedIntegrator) {
  for (const LambertCase& c : kLambert) {
    const cd halley = LambertW(-c.kp * c.delay_s, c.im == 0.0 ? cd(-0.5, 0.0) : cd(0.5, 1.5)) / c.delay_s;
    ASSERT_NEAR(halley.real(), c.re, 1e-12) << "kp " << c.kp << " L " << c.delay_s;
    ASSERT_NEAR(std::abs(halley.imag()), c.im, 1e-12);
    const SpectralAbscissa sa = AbscissaOrFail(Tf({1.0}, {1.0, 0.0}), P(c.kp), c.delay_s);
    EXPECT_TRUE(sa.polished) << sa.note;
    EXPECT_NEAR(sa.alpha, c.re, 1e-9) << "kp " << c.kp << " L " << c.delay_s;
    EXPECT_NEAR(sa.root.imag(), c.im, 1e-9 * std::max(1.0, c.im));
  }
}

TEST(SpectralAbscissa, CertifiesNewtonsGuessWithThreeCountsInsteadOfBisecting) {
  // One count on the stable side, Newton from its line, and two counts that
  // bracket the guess within 0.4e-7 |alpha| each side: no walk, no bisection.
  for (const LambertCase& c : kLambert) {
    const SpectralAbscissa sa = AbscissaOrFail(Tf({1.0}, {1.0, 0.0}), P(c.kp), c.delay_s);
    EXPECT_EQ(sa.counts, 3) << "kp " << c.kp << " L " << c.delay_s;
    EXPECT_LE(sa.strip_width, 1e-7 * std::abs(c.re));
    EXPECT_NEAR(sa.alpha, c.re, 1e-12 * std::abs(c.re)) << "kp " << c.kp << " L " << c.delay_s;
  }
}

TEST(SpectralAbscissa, ShiftedCountsTheLambertRootsRightOfEachLine) {
  // kp L = 1: every root is W_k(-1)/L, k = 0, +-1, +-2, ... (conjugate pairs).
  const double delay = 1.0, kp = 1.0;
  std::vector<cd> roots;
  for (int k = 0; k < 40; ++k) {
    // W_k(-1) for k >= 0 from the asymptotic start log(x) + 2 pi i k - log(log(x) + 2 pi i k).
    const cd l1 = std::log(cd(-1.0, 0.0)) + cd(0.0, 2.0 * kPi * k);
    const cd w = LambertW(-kp * delay, k == 0 ? cd(-0.3, 1.3) : l1 - std::log(l1));
    ASSERT_LT(std::abs(w * std::exp(w) + kp * delay), 1e-12) << "branch " << k;
    ASSERT_GT(w.imag(), 2.0 * kPi * k - kPi) << "branch " << k;  // W_k, not another branch
    ASSERT_LT(w.imag(), 2.0 * kPi * k + kPi) << "branch " << k;
    roots.push_back(w / delay);
  }
  for (double sigma : {-0.2, -0.5, -2.0, -3.5, -5.0}) {
    int want = 0;
    for (const cd& r : roots)
      if (r.real() > sigma) want += 2;  // the pair r, conj(r)
    NyquistCount n;
    std::string error;
    ASSERT_TRUE(
        OkInto(CountContinuousRootsRightOf(Tf({1.0}, {1.0, 0.0}), P(kp), delay, sigma, 100.0, &n), &error))
        << error;
    EXPECT_TRUE(n.decided) << n.note;
    EXPECT_EQ(n.closed_loop_rhp_poles, want) << "sigma " << sigma << ": " << n.note;
  }
}

// The roots of (s + 1) + kp e^{-s} = 0 by Newton from a grid of starts.
std::vector<cd> FirstOrderDelayRoots(double kp) {
  std::vector<cd> roots;
  for (double re = -6.0; re <= 1.0; re += 0.5)
    for (double im = 0.0; im <= 40.0; im += 0.25) {
      cd s(re, im);
      for (int i = 0; i < 100; ++i) {
        const cd f = s + 1.0 + kp * std::exp(-s), df = 1.0 - kp * std::exp(-s);
        s -= f / df;
      }
      if (std::abs(s + 1.0 + kp * std::exp(-s)) < 1e-12 && std::isfinite(s.real())) roots.push_back(s);
    }
  return roots;
}

cd Rightmost(const std::vector<cd>& roots) {
  cd r = roots.front();
  for (const cd& x : roots)
    if (x.real() > r.real()) r = x;
  return r;
}

TEST(SpectralAbscissa, MatchesTheRightmostRootFoundByNewtonForAFirstOrderLagWithDeadTime) {
  for (double kp : {1.0, 2.0}) {
    const std::vector<cd> roots = FirstOrderDelayRoots(kp);
    ASSERT_GT(roots.size(), 10u);
    const cd rightmost = Rightmost(roots);
    const SpectralAbscissa sa = AbscissaOrFail(Tf({1.0}, {1.0, 1.0}), P(kp), 1.0);
    EXPECT_NEAR(sa.alpha, rightmost.real(), 1e-9) << "kp " << kp;
    EXPECT_NEAR(sa.root.imag(), std::abs(rightmost.imag()), 1e-9) << "kp " << kp;
    EXPECT_LT(sa.alpha, 0.0);  // stable below the ultimate gain 2.26183
  }
}

TEST(SpectralAbscissa, TendsToTheDelayFreeLoopsSlowestTimeConstantAsTheDelayVanishes) {
  const TransferFunction tf = Tf({1.0}, {0.5, 1.5, 1.0});  // 1/((s + 1)(0.5 s + 1))
  const PidGains pi{1.0, 0.5, 0.0}, pid{2.0, 1.5, 0.3, 0.03};
  for (const PidGains& g : {P(1.0), pi, pid}) {
    LoopAnalysis free, delayed;
    std::string error;
    Plant plant{"custom", tf};
    ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, LoopOptions{}, LoopAnalysisOptions{}, &free)));
    plant.delay_s = 1e-9;
    ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, LoopOptions{}, LoopAnalysisOptions{}, &delayed)));
    ASSERT_TRUE(delayed.stable);
    EXPECT_TRUE(delayed.time_constant_note.empty()) << delayed.time_constant_note;
    EXPECT_NEAR(delayed.slowest_time_constant_s, free.slowest_time_constant_s,
                1e-6 * free.slowest_time_constant_s)
        << "kp " << g.kp << " ki " << g.ki << " kd " << g.kd;
  }
}

TEST(SpectralAbscissa, GivesTheAnalysisAFiniteTimeConstantThatItsBoundReads) {
  Plant plant{"custom", Tf({1.0}, {1.0, 1.0})};
  plant.delay_s = 1.0;
  LoopAnalysis a;
  std::string error;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, P(1.0), LoopOptions{}, LoopAnalysisOptions{}, &a)));
  ASSERT_TRUE(std::isfinite(a.slowest_time_constant_s)) << a.time_constant_note;
  const double tau = -1.0 / Rightmost(FirstOrderDelayRoots(1.0)).real();
  EXPECT_NEAR(a.slowest_time_constant_s, tau, 1e-8 * tau);
  LoopBounds b;
  b.max_time_constant_s = 1.01 * a.slowest_time_constant_s;
  EXPECT_TRUE(LoopBoundsViolations(a, b).empty());
  b.max_time_constant_s = 0.99 * a.slowest_time_constant_s;
  ASSERT_EQ(LoopBoundsViolations(a, b).size(), 1u);
  EXPECT_EQ(LoopBoundsViolations(a, b)[0].rfind("time constant ", 0), 0u);
}

TEST(SpectralAbscissa, IsNotComputedForANeutralLoop) {
  // An ideal derivative on a plant of relative degree 1: deg a = deg b.
  const PidGains pd{1.0, 0.0, 0.2};
  SpectralAbscissa sa;
  std::string error;
  ASSERT_TRUE(IsOk(ContinuousSpectralAbscissa(Tf({1.0}, {1.0, 1.0}), pd, 0.5, 100.0, &sa)));
  EXPECT_FALSE(sa.found);
  EXPECT_NE(sa.note.find("neutral"), std::string::npos) << sa.note;
}

}  // namespace
}  // namespace pidlab
