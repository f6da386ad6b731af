// The continuous loop with dead time, fast and lean (docs/deadtime.md): the
// crossing-frequency test against the Nyquist count near the stability
// boundary, the exact steps and the uniform Hermite grid against the node-by-
// node method of steps, and the tuner's objective against the reference path
// on random loops of four plant families.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "pidlab/evaluation/delay_crossings.h"
#include "pidlab/evaluation/delayed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/evaluation/loop_frequency.h"
#include "test_status.h"

using pidlab::evaluation::BuildDelayedClosedLoop;
using pidlab::evaluation::ContinuousPidPolynomials;
using pidlab::evaluation::CountContinuousNyquist;
using pidlab::evaluation::CountRootsByCrossings;
using pidlab::evaluation::CrossingCount;
using pidlab::evaluation::CrossingVerdict;
using pidlab::evaluation::DelayedClosedLoop;
using pidlab::evaluation::DelayedTrace;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::NyquistCount;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::ReferenceDelayedObjective;
using pidlab::evaluation::SampleDelayedLoop;

namespace pidlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

Plant Delayed(const TransferFunction& tf, double delay_s) {
  Plant p{"custom", tf};
  p.delay_s = delay_s;
  return p;
}

CrossingCount Crossings(const TransferFunction& tf, const PidGains& g, double delay_s) {
  std::vector<double> num, den;
  ContinuousPidPolynomials(g, &num, &den);
  using evaluation::frequency::Mul;
  using evaluation::frequency::Trim;
  return CountRootsByCrossings(Mul(num, Trim(tf.num)), Mul(den, Trim(tf.den)), delay_s);
}

// The four families of the issue: first order, second order, integrating,
// underdamped, each with a random gain, time constants and dead time.
TransferFunction RandomPlant(int family, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double k = 0.5 + 2.0 * u(*rng), t1 = 1.0 + 20.0 * u(*rng), t2 = 0.5 + 5.0 * u(*rng);
  switch (family) {
    case 0:
      return {{k}, {t1, 1.0}};
    case 1:
      return {{k}, {t1 * t2, t1 + t2, 1.0}};
    case 2:
      return {{k}, {t2, 1.0, 0.0}};
    default: {
      const double w = 0.2 + u(*rng), zeta = 0.1 + 0.3 * u(*rng);
      return {{k * w * w}, {1.0, 2.0 * zeta * w, w * w}};
    }
  }
}

// Gains of a random shape (kp, ki, kd ratios) at a random scale; tf > 0.
PidGains RandomGains(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PidGains g;
  g.kp = std::pow(10.0, -1.0 + 1.5 * u(*rng));
  g.ki = g.kp * std::pow(10.0, -2.0 + 1.5 * u(*rng));
  g.kd = u(*rng) < 0.2 ? 0.0 : g.kp * std::pow(10.0, -1.0 + 1.5 * u(*rng));
  g.tf = g.kd > 0.0 ? std::max(0.1 * g.kd / g.kp, 0.01) : 0.0;
  return g;
}

PidGains Scaled(PidGains g, double s) {
  g.kp *= s;
  g.ki *= s;
  g.kd *= s;
  return g;
}

TEST(CrossingCount, DelayedIntegratorUnderPControlIsStableExactlyBelowKLEqualsHalfPi) {
  // y' = k (r - y(t - L)): stable iff k L < pi / 2, one crossing at w = k.
  const TransferFunction integrator{{1.0}, {1.0, 0.0}};
  const double delay = 0.8, ku = kPi / (2.0 * delay);
  for (double f : {0.5, 0.99, 1.0 - 1e-6, 1.0 + 1e-6, 1.01, 3.0}) {
    const CrossingCount dut = Crossings(integrator, {f * ku, 0.0, 0.0}, delay);
    ASSERT_NE(dut.verdict, CrossingVerdict::kUndecided) << f;
    EXPECT_EQ(dut.verdict == CrossingVerdict::kStable, f < 1.0) << f;
    EXPECT_EQ(dut.crossings, 1);
  }
  // At the ultimate gain itself the root is on the axis: left to the count.
  EXPECT_EQ(Crossings(integrator, {ku, 0.0, 0.0}, delay).verdict, CrossingVerdict::kUndecided);
}

TEST(CrossingCount, StabilitySwitchesOfAnUnstablePlantAreCountedBothWays) {
  // 1/(s - 0.1) under P: unstable without delay for kp < 0.1, and with a
  // delay large enough for every kp; in between, stable.
  const TransferFunction unstable{{1.0}, {1.0, -0.1}};
  EXPECT_EQ(Crossings(unstable, {0.05, 0.0, 0.0}, 0.5).verdict, CrossingVerdict::kUnstable);
  EXPECT_EQ(Crossings(unstable, {0.5, 0.0, 0.0}, 0.5).verdict, CrossingVerdict::kStable);
  EXPECT_EQ(Crossings(unstable, {0.5, 0.0, 0.0}, 20.0).verdict, CrossingVerdict::kUnstable);
}

TEST(CrossingCount, NeutralLoopIsLeftToTheNyquistCount) {
  // An ideal derivative on a plant of relative degree 1: deg a = deg b.
  EXPECT_EQ(Crossings(TransferFunction{{1.0}, {1.0, 1.0}}, {1.0, 0.5, 0.2}, 0.3).verdict,
            CrossingVerdict::kUndecided);
}

TEST(CrossingCount, AgreesWithTheNyquistCountNearTheBoundaryOnThousandsOfRandomLoops) {
  // For each random plant and gain shape, the boundary scale s* (where the
  // verdict changes) by bisection, then scales s* (1 +- d), d log-uniform in
  // [1e-7, 0.3]: the two tests must agree wherever the crossing test
  // decides; it leaves undecided only loops whose critical phase is within
  // kCrossingPhaseTolerance, i.e. a root within about 1e-8 / L of the axis.
  std::mt19937 rng(40);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0, undecided = 0, stable = 0;
  for (int loop = 0; loop < 100; ++loop) {
    const TransferFunction tf = RandomPlant(loop % 4, &rng);
    const double delay = 0.1 + 3.0 * u(rng);
    const PidGains shape = RandomGains(&rng);
    double lo = 1e-3, hi = 1e3;  // stable at lo, unstable at hi (checked below)
    if (Crossings(tf, Scaled(shape, lo), delay).verdict != CrossingVerdict::kStable ||
        Crossings(tf, Scaled(shape, hi), delay).verdict != CrossingVerdict::kUnstable)
      continue;
    for (int i = 0; i < 60; ++i) {
      const double mid = std::sqrt(lo * hi);
      (Crossings(tf, Scaled(shape, mid), delay).verdict == CrossingVerdict::kStable ? lo : hi) = mid;
    }
    for (int i = 0; i < 25; ++i) {
      const double d = std::pow(10.0, -7.0 + 6.5 * u(rng)) * (i % 2 == 0 ? 1.0 : -1.0);
      const PidGains g = Scaled(shape, lo * (1.0 + d));
      const CrossingCount dut = Crossings(tf, g, delay);
      NyquistCount ref;
      std::string error;
      ASSERT_TRUE(IsOk(CountContinuousNyquist(tf, g, delay, 100.0, &ref)));
      if (dut.verdict == CrossingVerdict::kUndecided) {
        ++undecided;  // DelayedStability asks the Nyquist count
        continue;
      }
      if (!ref.decided) continue;
      ++compared;
      stable += dut.verdict == CrossingVerdict::kStable ? 1 : 0;
      EXPECT_EQ(dut.verdict == CrossingVerdict::kStable, ref.stable)
          << "loop " << loop << " d " << d << " kp " << g.kp << " ki " << g.ki << " kd " << g.kd << " tf "
          << g.tf << " L " << delay << ": Z " << dut.roots_right << ", gap " << dut.phase_gap << "; "
          << ref.note;
    }
  }
  std::cout << "crossing test vs Nyquist count: " << compared << " compared (" << stable << " stable), "
            << undecided << " undecided\n";
  EXPECT_GE(compared, 2000);
  EXPECT_GE(stable, 500);
  EXPECT_LE(undecided, compared / 100);
}

// IAE of the samples of one run with trace options `trace`.
double SampledIae(const DelayedClosedLoop& loop, double ts, int n, DelayedTrace trace) {
  std::vector<double> y;
  std::string error;
  EXPECT_TRUE(IsOk(SampleDelayedLoop(loop, Disturbance(DisturbanceOptions{}), ts, n, &y, &trace)));
  double sum = 0.0;
  for (double v : y) sum += std::abs(1.0 - v);
  return sum;
}

TEST(DelayedContinuous, ExactStepsMatchTheHermiteStoreAsItsStepShrinks) {
  // The Hermite store's error falls as h^4 to its rounding floor: a quarter
  // of its own step is within 1e-11 of the exact steps, which have no step
  // error at all.
  std::mt19937 rng(7);
  for (int i = 0; i < 12; ++i) {
    const TransferFunction tf = RandomPlant(i % 4, &rng);
    const PidGains g = Scaled(RandomGains(&rng), 0.3);
    DelayedClosedLoop loop;
    std::string error;
    ASSERT_TRUE(
        OkInto(BuildDelayedClosedLoop(tf, Realize(tf), g, Disturbance(DisturbanceOptions{}), 1.5, 1.0, &loop),
               &error))
        << error;
    DelayedTrace fine;
    fine.force_step_s = 1.5 / std::ceil(1.5 / (0.25 * evaluation::DelayedStepSize(loop)));
    const double exact = SampledIae(loop, 0.05, 401, DelayedTrace{});
    EXPECT_NEAR(SampledIae(loop, 0.05, 401, fine), exact, 1e-11 * exact) << i;
  }
}

TEST(DelayedContinuous, UniformHermiteGridEqualsTheNodeByNodeIntegratorToRounding) {
  // L / ts irrational: no exact steps; the uniform grid runs the Hermite
  // store on the same nodes as the node-by-node integrator.
  std::mt19937 rng(11);
  for (int i = 0; i < 8; ++i) {
    const TransferFunction tf = RandomPlant(i % 4, &rng);
    const PidGains g = Scaled(RandomGains(&rng), 0.3);
    const double delay = std::sqrt(2.0);
    DelayedClosedLoop loop;
    std::string error;
    ASSERT_TRUE(OkInto(
        BuildDelayedClosedLoop(tf, Realize(tf), g, Disturbance(DisturbanceOptions{}), delay, 1.0, &loop),
        &error))
        << error;
    DelayedTrace reference;
    reference.node_by_node = true;
    const double node_by_node = SampledIae(loop, 0.05, 301, reference);
    EXPECT_NEAR(SampledIae(loop, 0.05, 301, DelayedTrace{}), node_by_node, 1e-12 * node_by_node) << i;
  }
}

TEST(DelayedObjective, FastPathEqualsTheReferenceOnRandomLoopsOfFourPlantFamilies) {
  // The tuner's objective (crossing test, exact steps or uniform grid)
  // against the reference path (Nyquist count, node by node): the same
  // verdict, and the same objective to 1e-9 relative (the reference's own
  // step error is about 5e-11).
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const ObjectiveKind kinds[] = {ObjectiveKind::kIae, ObjectiveKind::kIse, ObjectiveKind::kItae,
                                 ObjectiveKind::kLoadIae, ObjectiveKind::kSetpointLoad};
  int finite = 0, infinite = 0;
  double worst = 0.0;
  for (int i = 0; i < 80; ++i) {
    const Plant plant = Delayed(RandomPlant(i % 4, &rng), 0.1 * std::floor(3.0 + 20.0 * u(rng)));
    LoopOptions o;
    o.horizon_s = 20.0;
    o.sample_time_s = i % 3 == 0 ? 0.1 : 0.05;
    if (i % 2 == 0) o.derivative_filter_ratio = 10.0;
    PidGains g = Scaled(RandomGains(&rng), 0.2 + 2.0 * u(rng));
    if (i % 2 == 0) g.tf = 0.0;  // the ratio sets it
    if (g.kd > 0.0 && g.tf == 0.0 && o.derivative_filter_ratio == 0.0) g.tf = 0.05;
    const ObjectiveKind kind = kinds[i % 5];
    const double fast = ObjectiveEvaluator(plant, o, kind)(g);
    const double reference = ReferenceDelayedObjective(plant, o, kind, g);
    ASSERT_EQ(std::isinf(fast), std::isinf(reference)) << i << " fast " << fast << " reference " << reference;
    (std::isinf(fast) ? infinite : finite) += 1;
    if (std::isinf(fast)) continue;
    EXPECT_NEAR(fast, reference, 1e-9 * reference) << i;
    worst = std::max(worst, std::abs(fast - reference) / reference);
  }
  std::cout << "fast vs reference objective: " << finite << " finite, " << infinite
            << " unstable; largest relative difference " << worst << "\n";
  EXPECT_GE(finite, 40);
  EXPECT_GE(infinite, 5);
}

}  // namespace
}  // namespace pidlab
