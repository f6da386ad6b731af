// Disturbance signals: values, breakpoints, determinism of the noise.

#include "pidlab/plant_sim/disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

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
                            DisturbanceKind::kSine, DisturbanceKind::kNoise, DisturbanceKind::kPrbs}) {
    DisturbanceKind dut = DisturbanceKind::kNone;
    EXPECT_TRUE(ParseDisturbanceKind(ToString(k), &dut)) << ToString(k);
    EXPECT_EQ(dut, k);
  }
  DisturbanceKind dut;
  EXPECT_FALSE(ParseDisturbanceKind("triangle", &dut));
}

DisturbanceOptions Prbs(double amplitude, std::uint64_t seed, double clock_s) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kPrbs;
  o.amplitude = amplitude;
  o.seed = seed;
  o.noise_hold_s = clock_s;
  return o;
}

// A maximal-length sequence of order 15: period 2^15 - 1, 2^14 ones and
// 2^14 - 1 zeros in a period, and no shorter period (a shorter one would
// divide 32767 = 7 * 31 * 151).
TEST(Prbs, IsTheMaximalLengthSequenceOfOrderFifteen) {
  ASSERT_EQ(kPrbsLength, 32767);
  long ones = 0;
  for (std::int64_t i = 0; i < kPrbsLength; ++i) ones += PrbsBit(i) ? 1 : 0;
  EXPECT_EQ(ones, 16384);
  for (std::int64_t divisor : {7, 31, 151, 7 * 31, 7 * 151, 31 * 151}) {
    bool repeats = true;
    for (std::int64_t i = 0; i + divisor < kPrbsLength && repeats; ++i)
      repeats = PrbsBit(i) == PrbsBit(i + divisor);
    EXPECT_FALSE(repeats) << divisor;
  }
}

// The circular autocorrelation of the +/-1 sequence is N at lag 0 and -1 at
// every other lag: the property that makes a PRBS a white excitation.
TEST(Prbs, HasTheTwoValuedAutocorrelation) {
  std::vector<int> x(static_cast<std::size_t>(kPrbsLength));
  for (std::int64_t i = 0; i < kPrbsLength; ++i) x[static_cast<std::size_t>(i)] = PrbsBit(i) ? 1 : -1;
  for (std::int64_t lag : {0, 1, 2, 15, 100, 4096, 32766}) {
    long sum = 0;
    for (std::int64_t i = 0; i < kPrbsLength; ++i)
      sum += x[static_cast<std::size_t>(i)] * x[static_cast<std::size_t>((i + lag) % kPrbsLength)];
    EXPECT_EQ(sum, lag == 0 ? kPrbsLength : -1) << lag;
  }
}

TEST(Prbs, HoldsEachBitOverOneClockAndSwitchesOnlyAtClockMultiples) {
  const Disturbance dut(Prbs(0.5, 0, 0.1));
  for (int k = 0; k < 200; ++k) {
    const double level = PrbsBit(k) ? 0.5 : -0.5;
    EXPECT_EQ(dut.Value(k * 0.1), level) << k;
    EXPECT_EQ(dut.Value(k * 0.1 + 0.05), level) << k;
    EXPECT_EQ(dut.Value(k * 0.1 + 0.0999), level) << k;
    EXPECT_NEAR(dut.NextBreakpoint(k * 0.1 + 0.03), (k + 1) * 0.1, 1e-12) << k;
  }
  EXPECT_TRUE(dut.IsPiecewiseConstant());
  EXPECT_EQ(dut.Value(-1.0), 0.0);
}

TEST(Prbs, StartsAtTheSeedsBitAndWrapsAfterAPeriod) {
  const Disturbance from0(Prbs(1.0, 0, 1.0)), from5(Prbs(1.0, 5, 1.0)), wrapped(Prbs(1.0, 5 + 32767, 1.0));
  for (int k = 0; k < 100; ++k) {
    EXPECT_EQ(from5.Value(k), from0.Value(k + 5)) << k;
    EXPECT_EQ(wrapped.Value(k), from5.Value(k)) << k;
  }
  EXPECT_EQ(from0.Value(32767.0), from0.Value(0.0));
  EXPECT_EQ(from0.Value(32768.5), from0.Value(1.5));
}

TEST(DisturbanceOptions, RejectsAPrbsWithoutAPositiveClockNamingIt) {
  std::string error;
  EXPECT_FALSE(Prbs(1.0, 1, 0.0).IsValid(&error));
  EXPECT_NE(error.find("prbs clock (noise hold) 0 s must be positive"), std::string::npos) << error;
  EXPECT_TRUE(Prbs(1.0, 1, 0.05).IsValid(&error)) << error;
}

}  // namespace
}  // namespace pidlab
