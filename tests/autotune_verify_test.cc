// The autotune's verification step read through the noise (autotune/verify.h,
// issue 60): a step under noise reads its smoothed overshoot and a settling
// time that is not 0; a loop that rings or drifts under the same noise is not
// settled; a clean step is read as it is.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pidlab/autotune/verify.h"

namespace pidlab::autotune {
namespace {

constexpr double kTs = 0.05, kEnd = 40.0, kZeta = 0.6;

// The unit step of w0^2 / (s^2 + 2 zeta w0 s + w0^2), w0 = 1: overshoot
// exp(-pi zeta / sqrt(1 - zeta^2)) = 9.48 %.
double SecondOrder(double t) {
  const double wd = std::sqrt(1.0 - kZeta * kZeta);
  return 1.0 - std::exp(-kZeta * t) * (std::cos(wd * t) + kZeta / wd * std::sin(wd * t));
}

struct Record {
  std::vector<double> t, y;
};

template <typename F>
Record Sampled(F f, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Record r;
  for (int k = 0; k * kTs <= kEnd + 1e-9; ++k) {
    r.t.push_back(k * kTs);
    r.y.push_back(f(k * kTs) + (sigma > 0.0 ? noise(rng) : 0.0));
  }
  return r;
}

TEST(VerificationStep, ANoisyStepReadsItsSmoothedOvershootAndASettlingTimeThatIsNotZero) {
  const double truth = 100.0 * std::exp(-M_PI * kZeta / std::sqrt(1.0 - kZeta * kZeta));
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    const Record r = Sampled(SecondOrder, 0.05, seed);
    double raw_peak = 0.0;
    for (double v : r.y) raw_peak = std::max(raw_peak, v);
    const StepReading s = ReadVerificationStep(r.t, r.y, 1.0, 0.05, 6.0);
    EXPECT_GT(100.0 * (raw_peak - 1.0), truth + 5.0) << "the raw peak is a noise spike, seed " << seed;
    EXPECT_NEAR(s.overshoot_pct, truth, 3.5) << "seed " << seed;
    EXPECT_EQ(s.window, 29) << "a quarter of the ultimate period, 6 s / 4 at 0.05 s, odd";
    EXPECT_NEAR(s.widening, kBandSigmas * 0.05 / std::sqrt(29.0), 1e-12);
    EXPECT_NEAR(s.band, 0.02 + s.widening, 1e-12);
    // The envelope 1.25 e^(-0.6 t) enters the band of 0.057 near 5.1 s.
    EXPECT_GT(s.settling_time_s, 2.0) << "seed " << seed;
    EXPECT_LT(s.settling_time_s, 9.0) << "seed " << seed;
    EXPECT_TRUE(s.settled) << "seed " << seed;
  }
}

TEST(VerificationStep, ALoopThatRingsOrDriftsUnderTheSameNoiseIsNotSettled) {
  const auto rings = [](double t) { return SecondOrder(t) + 0.1 * std::sin(1.3 * t); };
  const auto drifts = [](double t) { return SecondOrder(t) + 0.004 * t; };
  const StepReading ringing =
      ReadVerificationStep(Sampled(rings, 0.05, 9).t, Sampled(rings, 0.05, 9).y, 1.0, 0.05, 6.0);
  const StepReading drifting =
      ReadVerificationStep(Sampled(drifts, 0.05, 9).t, Sampled(drifts, 0.05, 9).y, 1.0, 0.05, 6.0);
  EXPECT_FALSE(ringing.settled) << ringing.settling_time_s;
  EXPECT_FALSE(drifting.settled) << drifting.settling_time_s;
  EXPECT_GT(ringing.settling_time_s, kEnd - 6.0);
}

TEST(VerificationStep, ACleanStepIsReadUnsmoothedInTheTwoPercentBand) {
  const Record r = Sampled(SecondOrder, 0.0, 0);
  const StepReading s = ReadVerificationStep(r.t, r.y, 1.0, 0.0, 6.0);
  const double truth = 100.0 * std::exp(-M_PI * kZeta / std::sqrt(1.0 - kZeta * kZeta));
  EXPECT_EQ(s.window, 1);
  EXPECT_EQ(s.widening, 0.0);
  EXPECT_EQ(s.band, 0.02);
  EXPECT_NEAR(s.overshoot_pct, truth, 0.05) << "the samples' peak, 0.05 s apart";
  EXPECT_TRUE(s.settled);
  EXPECT_FALSE(ReadVerificationStep({}, {}, 1.0, 0.0, 6.0).settled) << "no record";
}

}  // namespace
}  // namespace pidlab::autotune
