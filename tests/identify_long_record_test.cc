// A record longer than IdentifyOptions::max_samples (docs/identify.md, "Long
// records"): Identify refuses it naming the limit, DecimateRecord shortens it
// by an anti-alias average without a shift, the fit of the decimated record
// lands close to the parameters the full record was made with, its starts
// on an eighth of its samples (IdentifyOptions::start_samples) reach the fit
// whose every start ran on all of them, and a cancelled fit stops at its
// next solver iteration.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <string>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/status.h"

namespace pidlab::identify {
namespace {

// P1D Kp = 2, Tp1 = 4 s, Td = 0.5 s at dt = 1 ms, a step at 2 s, white
// noise of 0.02 (seeded): the exact ZOH recurrence.
IdentifyData LongStep(std::size_t n) {
  std::mt19937 rng(59);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double dt = 1e-3, a = std::exp(-dt / 4.0);
  IdentifyData d;
  double y = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = dt * static_cast<double>(k);
    d.t.push_back(t);
    d.u.push_back(t >= 2.0 - 1e-9 ? 1.0 : 0.0);
    d.y.push_back(y + noise(rng));
    y = a * y + 2.0 * (1.0 - a) * (t - 0.5 >= 2.0 - 1e-9 ? 1.0 : 0.0);
  }
  return d;
}

TEST(LongRecord, IdentifyRefusesARecordBeyondMaxSamplesNamingTheLimit) {
  IdentifyOptions options;
  options.max_samples = 1000;
  IdentifyResult result;
  const Status status = Identify(LongStep(1001), ProcessModelKind::kP1D, options, &result);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find("1001 samples, more than max_samples = 1000"), std::string::npos)
      << status.message();
}

TEST(LongRecord, MaxSamplesOutOfRangeIsNamedByIsValid) {
  IdentifyOptions options;
  options.max_samples = 99;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error, "max_samples = 99 must be in [100, 10000000]");
}

TEST(LongRecord, ARecordWithinTheLimitIsKeptAsItIs) {
  const IdentifyData data = LongStep(500);
  IdentifyData dut;
  Decimation decimation;
  ASSERT_TRUE(DecimateRecord(data, 500, Intersample::kZoh, &dut, &decimation).ok());
  EXPECT_EQ(decimation.factor, 1);
  EXPECT_EQ(dut.y, data.y);
  EXPECT_EQ(dut.u, data.u);
}

TEST(LongRecord, DecimationAveragesUOverItsIntervalAndYCentredOnItsSample) {
  IdentifyData data;
  for (int k = 0; k < 1000; ++k) {
    data.t.push_back(0.1 * k);
    data.u.push_back(k % 10 == 9 ? 10.0 : 0.0);  // one sample of 10 in every 10
    data.y.push_back(3.0 * k);                   // a ramp: its centred mean is itself
  }
  IdentifyData dut;
  Decimation decimation;
  ASSERT_TRUE(DecimateRecord(data, 100, Intersample::kZoh, &dut, &decimation).ok());
  EXPECT_EQ(decimation.factor, 10);
  EXPECT_EQ(decimation.samples, 100u);
  ASSERT_EQ(dut.t.size(), 100u);
  for (std::size_t k = 0; k < dut.t.size(); ++k) {
    EXPECT_NEAR(dut.t[k], 0.1 * static_cast<double>(10 * k), 1e-12);
    EXPECT_NEAR(dut.u[k], 1.0, 1e-12) << k;  // the held input's integral kept
    EXPECT_NEAR(dut.y[k], 3.0 * static_cast<double>(10 * k), 1e-9) << k;
  }
  EXPECT_EQ(DecimationFactor(200000, 10000), 20u);
  EXPECT_EQ(DecimationFactor(200001, 10000), 21u);
}

TEST(LongRecord, TheFitOfTheDecimatedRecordIsCloseToTheFullRecordsParameters) {
  IdentifyData decimated;
  Decimation decimation;
  ASSERT_TRUE(DecimateRecord(LongStep(40000), 2000, Intersample::kZoh, &decimated, &decimation).ok());
  ASSERT_EQ(decimation.factor, 20);
  IdentifyOptions options;
  options.u0 = 0.0;
  IdentifyResult result;
  ASSERT_TRUE(Identify(decimated, ProcessModelKind::kP1D, options, &result).ok());
  EXPECT_NEAR(result.values[0], 2.0, 0.03 * 2.0);  // Kp
  EXPECT_NEAR(result.values[1], 4.0, 0.03 * 4.0);  // Tp1
  EXPECT_NEAR(result.values[2], 0.5, 0.03 * 0.5);  // Td
}

// The record of 40000 samples decimated to 1000 (dt 40 ms), fitted with
// every start on all 1000 and with the starts on an eighth of them
// (StartSamples(1000) = 125), the best refitted on the 1000: Kp within 1e-4
// relative and the cost within a chi-square of 0.01 (2 (cost - cost_all) /
// sigma^2, sigma^2 = 2 cost_all / n) for every kind but P2DZ, whose zero
// and second lag (a nearly cancelling pair under 0.2 s, which only 1 of the
// 18 starts on all samples found) the starts on 125 samples cannot see: its
// chi-square within 3.84 (the 95 % point of one parameter). P1D's
// parameters within 1e-6 (docs/identify.md, "Long records"). A record
// within start_samples is fitted as without, bit for bit.
TEST(LongRecord, StartsOnAnEighthOfTheSamplesReachTheFitWhoseStartsRanOnAll) {
  IdentifyData decimated;
  Decimation decimation;
  ASSERT_TRUE(DecimateRecord(LongStep(40000), 1000, Intersample::kZoh, &decimated, &decimation).ok());
  for (ProcessModelKind kind : {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU,
                                ProcessModelKind::kP1DI, ProcessModelKind::kP2DZ}) {
    IdentifyOptions options;
    options.u0 = 0.0;
    IdentifyResult all, eighth, within;
    ASSERT_TRUE(Identify(decimated, kind, options, &all).ok()) << ToString(kind);
    options.start_samples = StartSamples(1000);
    ASSERT_TRUE(Identify(decimated, kind, options, &eighth).ok()) << ToString(kind);
    const double sigma2 = 2.0 * all.cost / static_cast<double>(all.samples);
    EXPECT_LT(2.0 * (eighth.cost - all.cost) / sigma2, kind == ProcessModelKind::kP2DZ ? 3.84 : 0.01)
        << ToString(kind) << ": " << eighth.cost << " against " << all.cost;
    EXPECT_NEAR(eighth.values[0], all.values[0], 1e-4 * std::abs(all.values[0])) << ToString(kind);
    if (kind != ProcessModelKind::kP1D) continue;
    for (std::size_t i = 0; i < all.values.size(); ++i)
      EXPECT_NEAR(eighth.values[i], all.values[i], 1e-6 * std::abs(all.values[i])) << i;
    options.start_samples = 1000;
    ASSERT_TRUE(Identify(decimated, kind, options, &within).ok());
    EXPECT_EQ(within.values, all.values);
    EXPECT_EQ(within.cost, all.cost);
  }
  IdentifyOptions bad;
  bad.start_samples = 99;
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_EQ(error, "start_samples = 99 must be 0 or in [100, 10000000]");
}

TEST(LongRecord, ACancelledFitStopsAtItsNextIterationAndSaysSo) {
  IdentifyData decimated;
  Decimation decimation;
  ASSERT_TRUE(DecimateRecord(LongStep(40000), 2000, Intersample::kZoh, &decimated, &decimation).ok());
  IdentifyOptions options;
  options.u0 = 0.0;
  int asked = 0, asked_after = 0;
  options.cancelled = [&] {
    ++asked;
    if (asked > 5) ++asked_after;
    return asked > 5;
  };
  // With the starts on an eighth of the samples (a decimated record's) too.
  for (std::size_t start_samples : {std::size_t{0}, std::size_t{500}}) {
    options.start_samples = start_samples;
    asked = asked_after = 0;
    IdentifyResult result;
    const Status status = Identify(decimated, ProcessModelKind::kP2D, options, &result);
    EXPECT_EQ(status.code(), StatusCode::kRunnerFailed) << start_samples;
    EXPECT_EQ(status.message(), "cancelled") << start_samples;
    // Once cancelled, every solve ends at its first iteration and no start
    // begins: a handful of questions, not a fit's hundreds.
    EXPECT_LT(asked_after, 20) << start_samples;
  }
}

}  // namespace
}  // namespace pidlab::identify
