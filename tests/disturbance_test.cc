// Disturbance signals: values, breakpoints, determinism of the noise.

#include "pidlab/plant_sim/disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace pidlab {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

DisturbanceOptions Square(double amplitude, double period_s, double phase_s = 0.0) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kSquare;
  o.amplitude = amplitude;
  o.period_s = period_s;
  o.phase_s = phase_s;
  return o;
}

DisturbanceOptions Noise(double amplitude, std::uint64_t seed, double hold_s = 0.01) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kNoise;
  o.amplitude = amplitude;
  o.seed = seed;
  o.noise_hold_s = hold_s;
  return o;
}

TEST(Disturbance, NoneIsZero) {
  const Disturbance dut(DisturbanceOptions{});
  for (double t : {0.0, 0.5, 3.0}) EXPECT_EQ(dut.Value(t), 0.0);
  EXPECT_TRUE(std::isinf(dut.NextBreakpoint(0.0)));
}

TEST(Disturbance, SquareIsPlusAOnTheFirstHalfPeriodAndMinusAOnTheSecond) {
  const Disturbance dut(Square(0.3, 2.0));
  EXPECT_EQ(dut.Value(0.0), 0.3);
  EXPECT_EQ(dut.Value(0.5), 0.3);
  EXPECT_EQ(dut.Value(0.999), 0.3);
  EXPECT_EQ(dut.Value(1.0), -0.3);
  EXPECT_EQ(dut.Value(1.5), -0.3);
  EXPECT_EQ(dut.Value(2.0), 0.3);
  EXPECT_EQ(dut.Value(3.25), -0.3);
}

TEST(Disturbance, SquareIsZeroBeforeTimeZero) {
  const Disturbance dut(Square(0.3, 2.0));
  EXPECT_EQ(dut.Value(-0.5), 0.0);
}

TEST(Disturbance, SquareValuesExactlyAtMillisecondBreakpointsFollowTheHalfPeriodIndex) {
  // Half period 0.1 s = 100 steps of 1 ms; t = k * 1e-3 is rounded, k is not.
  const Disturbance dut(Square(0.5, 0.2));
  for (int k = 0; k <= 2000; ++k) {
    const double expected = (k / 100) % 2 == 0 ? 0.5 : -0.5;
    ASSERT_EQ(dut.Value(k * 1e-3), expected) << "k = " << k;
  }
}

TEST(Disturbance, SquareWithPhaseIsShiftedByThePhase) {
  // Evaluated at t + phase: phase 0.03 s = 30 steps of 1 ms.
  const Disturbance dut(Square(0.5, 0.2, 0.03));
  for (int k = 0; k <= 2000; ++k) {
    const double expected = ((k + 30) / 100) % 2 == 0 ? 0.5 : -0.5;
    ASSERT_EQ(dut.Value(k * 1e-3), expected) << "k = " << k;
  }
}

TEST(Disturbance, SquareNextBreakpointIsTheNextHalfPeriod) {
  const Disturbance dut(Square(0.5, 0.2));
  EXPECT_NEAR(dut.NextBreakpoint(0.0), 0.1, 1e-15);
  EXPECT_NEAR(dut.NextBreakpoint(0.05), 0.1, 1e-15);
  EXPECT_NEAR(dut.NextBreakpoint(0.1), 0.2, 1e-15);  // strictly after t
  EXPECT_NEAR(dut.NextBreakpoint(100 * 1e-3), 0.2, 1e-15);
  EXPECT_NEAR(dut.NextBreakpoint(0.35), 0.4, 1e-15);
}

TEST(Disturbance, SquareNextBreakpointAccountsForThePhase) {
  const Disturbance dut(Square(0.5, 0.2, 0.03));
  EXPECT_NEAR(dut.NextBreakpoint(0.0), 0.07, 1e-15);
  EXPECT_NEAR(dut.NextBreakpoint(0.07), 0.17, 1e-15);
  EXPECT_TRUE(dut.IsPiecewiseConstant());
}

TEST(Disturbance, StepSwitchesAtTheStepTime) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kStep;
  o.amplitude = 0.7;
  o.step_time_s = 0.3;
  const Disturbance dut(o);
  for (int k = 0; k <= 1000; ++k) ASSERT_EQ(dut.Value(k * 1e-3), k >= 300 ? 0.7 : 0.0) << "k = " << k;
  EXPECT_NEAR(dut.NextBreakpoint(0.0), 0.3, 1e-15);
  EXPECT_TRUE(std::isinf(dut.NextBreakpoint(0.3)));
}

TEST(Disturbance, SineIsASineOfThePeriodAndPhase) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kSine;
  o.amplitude = 0.4;
  o.period_s = 0.5;
  o.phase_s = 0.1;
  const Disturbance dut(o);
  for (double t : {0.0, 0.013, 0.25, 1.7}) {
    EXPECT_NEAR(dut.Value(t), 0.4 * std::sin(2.0 * M_PI * (t + 0.1) / 0.5), 1e-14) << t;
  }
  EXPECT_FALSE(dut.IsPiecewiseConstant());
}

TEST(Disturbance, NoiseIsDeterministicForASeed) {
  const Disturbance dut(Noise(1.0, 42));
  const Disturbance again(Noise(1.0, 42));
  for (int k = 0; k < 1000; ++k) ASSERT_EQ(dut.Value(k * 1e-3), again.Value(k * 1e-3)) << k;
}

TEST(Disturbance, NoiseDiffersForAnotherSeed) {
  const Disturbance dut(Noise(1.0, 42));
  const Disturbance other(Noise(1.0, 43));
  int same = 0;
  for (int k = 0; k < 1000; ++k) same += dut.Value(k * 0.01) == other.Value(k * 0.01);
  EXPECT_EQ(same, 0);
}

TEST(Disturbance, NoiseIsHeldOverTheHoldInterval) {
  const double hold = 0.01;
  const Disturbance dut(Noise(1.0, 7, hold));
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> frac(0.0, 0.999);
  int changes = 0;
  for (int k = 0; k < 200; ++k) {
    const double start = k * hold;
    const double v = dut.Value(start);
    EXPECT_EQ(dut.Value(start + frac(rng) * hold), v) << "interval " << k;
    // Samples at 1 ms inside a 10 ms hold interval all agree.
    for (int j = 1; j < 10; ++j) ASSERT_EQ(dut.Value((10 * k + j) * 1e-3), v) << k << "," << j;
    changes += dut.Value(start + hold) != v;
    EXPECT_NEAR(dut.NextBreakpoint(start), start + hold, 1e-12);
  }
  EXPECT_GE(changes, 195);
}

TEST(Disturbance, NoiseHasZeroMeanAndTheAmplitudeAsStandardDeviation) {
  const double amplitude = 0.25;
  const int n = 200000;
  const Disturbance dut(Noise(amplitude, 99, 1.0));
  double sum = 0.0, sum2 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double v = dut.Value(k + 0.5);
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_LT(std::abs(mean), 5.0 * amplitude / std::sqrt(n));
  EXPECT_NEAR(sd, amplitude, 0.01 * amplitude);
}

TEST(DisturbanceOptions, DefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(DisturbanceOptions{}.IsValid(&error)) << error;
  EXPECT_TRUE(Square(0.2, 2.0).IsValid(&error)) << error;
}

TEST(DisturbanceOptions, RejectsANanAmplitude) {
  DisturbanceOptions dut = Square(kNaN, 2.0);
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("amplitude nan"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsANegativeNoiseStandardDeviation) {
  DisturbanceOptions dut = Noise(-0.5, 1);
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("-0.5"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsAZeroSquarePeriod) {
  DisturbanceOptions dut = Square(0.2, 0.0);
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("period 0"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsANegativeSinePeriod) {
  DisturbanceOptions dut = Square(0.2, -1.0);
  dut.kind = DisturbanceKind::kSine;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("period -1"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsAnInfinitePhase) {
  DisturbanceOptions dut = Square(0.2, 2.0, std::numeric_limits<double>::infinity());
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("phase inf"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsANegativeStepTime) {
  DisturbanceOptions dut;
  dut.kind = DisturbanceKind::kStep;
  dut.amplitude = 1.0;
  dut.step_time_s = -2.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("step time -2"), std::string::npos) << error;
}

TEST(DisturbanceOptions, RejectsAZeroNoiseHold) {
  DisturbanceOptions dut = Noise(1.0, 1, 0.0);
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("noise hold 0"), std::string::npos) << error;
}

TEST(DisturbanceKind, ParsesEveryKindAndRejectsOthers) {
  for (DisturbanceKind k : {DisturbanceKind::kNone, DisturbanceKind::kSquare, DisturbanceKind::kStep,
                            DisturbanceKind::kSine, DisturbanceKind::kNoise}) {
    DisturbanceKind dut = DisturbanceKind::kNone;
    EXPECT_TRUE(ParseDisturbanceKind(ToString(k), &dut)) << ToString(k);
    EXPECT_EQ(dut, k);
  }
  DisturbanceKind dut;
  EXPECT_FALSE(ParseDisturbanceKind("triangle", &dut));
}

}  // namespace
}  // namespace pidlab
