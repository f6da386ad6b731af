// The resend timer (transport/rtt.h): RFC 6298's estimator, its clamps, its
// backoff and Karn's rule left to the caller.

#include "pidlab/transport/rtt.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace pidlab::transport {
namespace {

constexpr double kTol = 1e-15;

RttOptions Wide() {  // clamps out of the way of the arithmetic
  RttOptions o;
  o.initial_s = 0.002;
  o.floor_s = 1e-9;
  o.ceiling_s = 10.0;
  return o;
}

TEST(RttEstimator, BeforeAnySampleTheTimeoutIsTheInitialOne) {
  const RttEstimator dut(Wide());
  EXPECT_FALSE(dut.has_sample());
  EXPECT_EQ(dut.samples(), 0);
  EXPECT_EQ(dut.Timeout(), 0.002);
  EXPECT_EQ(dut.BaseTimeout(), 0.002);
}

TEST(RttEstimator, FirstSampleSetsSrttToItAndRttvarToHalfOfIt) {
  RttEstimator dut(Wide());
  dut.Sample(100e-6);
  EXPECT_TRUE(dut.has_sample());
  EXPECT_NEAR(dut.srtt_s(), 100e-6, kTol);
  EXPECT_NEAR(dut.rttvar_s(), 50e-6, kTol);
  EXPECT_NEAR(dut.Timeout(), 100e-6 + 4 * 50e-6, kTol);  // SRTT + 4 RTTVAR
}

TEST(RttEstimator, LaterSamplesFollowRfc6298Gains) {
  RttEstimator dut(Wide());
  dut.Sample(100e-6);
  dut.Sample(200e-6);
  // RTTVAR = 3/4 * 50 + 1/4 * |100 - 200| = 62.5 us; SRTT = 7/8 * 100 + 1/8 * 200 = 112.5 us.
  EXPECT_NEAR(dut.rttvar_s(), 62.5e-6, kTol);
  EXPECT_NEAR(dut.srtt_s(), 112.5e-6, kTol);
  EXPECT_NEAR(dut.Timeout(), 112.5e-6 + 4 * 62.5e-6, kTol);
  EXPECT_EQ(dut.samples(), 2);
}

TEST(RttEstimator, ARunOfEqualSamplesConvergesToTheFloor) {
  RttEstimator dut;  // the defaults: floor 150 us
  for (int i = 0; i < 200; ++i) dut.Sample(20e-6);
  EXPECT_NEAR(dut.srtt_s(), 20e-6, 1e-12);
  EXPECT_LT(dut.rttvar_s(), 1e-12);
  EXPECT_EQ(dut.Timeout(), dut.options().floor_s);
}

TEST(RttEstimator, ALongRoundTripIsClampedToTheCeiling) {
  RttEstimator dut;  // ceiling 100 ms
  dut.Sample(1.0);
  EXPECT_EQ(dut.Timeout(), 0.1);
  EXPECT_NEAR(dut.srtt_s(), 1.0, kTol);  // the estimate itself is not clamped
}

TEST(RttEstimator, IgnoresNonFiniteAndNegativeSamples) {
  RttEstimator dut(Wide());
  dut.Sample(std::numeric_limits<double>::quiet_NaN());
  dut.Sample(std::numeric_limits<double>::infinity());
  dut.Sample(-1e-6);
  EXPECT_FALSE(dut.has_sample());
  EXPECT_EQ(dut.Timeout(), 0.002);
  dut.Sample(0.0);  // a zero round trip is a sample
  EXPECT_EQ(dut.samples(), 1);
}

TEST(RttEstimator, BackoffDoublesTheTimeoutUpToTheCeiling) {
  RttOptions o = Wide();
  o.ceiling_s = 0.01;
  RttEstimator dut(o);
  dut.Sample(1e-3);  // base 3 ms
  ASSERT_NEAR(dut.BaseTimeout(), 3e-3, kTol);
  dut.Backoff();
  EXPECT_NEAR(dut.Timeout(), 6e-3, kTol);
  dut.Backoff();
  EXPECT_EQ(dut.Timeout(), 0.01);  // 12 ms capped
  const int backoffs = dut.backoffs();
  dut.Backoff();  // at the ceiling: no further count
  EXPECT_EQ(dut.backoffs(), backoffs);
  EXPECT_EQ(dut.Timeout(), 0.01);
  EXPECT_NEAR(dut.BaseTimeout(), 3e-3, kTol);
}

TEST(RttEstimator, EndBackoffAndANewSampleReturnToTheEstimate) {
  RttEstimator dut(Wide());
  dut.Sample(1e-3);
  dut.Backoff();
  dut.Backoff();
  EXPECT_NEAR(dut.Timeout(), 12e-3, kTol);
  dut.EndBackoff();  // Karn: the exchange completed, no sample from it
  EXPECT_EQ(dut.backoffs(), 0);
  EXPECT_NEAR(dut.Timeout(), 3e-3, kTol);
  EXPECT_EQ(dut.samples(), 1);
  dut.Backoff();
  dut.Sample(1e-3);
  EXPECT_EQ(dut.backoffs(), 0);
  EXPECT_NEAR(dut.Timeout(), dut.BaseTimeout(), kTol);
}

TEST(RttOptions, DefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(RttOptions{}.IsValid(&error)) << error;
}

TEST(RttOptions, ANonPositiveFloorIsInvalidNamingIt) {
  RttOptions o;
  o.floor_s = 0.0;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("floor 0 s"), std::string::npos) << error;
}

TEST(RttOptions, ACeilingBelowTheFloorIsInvalidNamingBoth) {
  RttOptions o;
  o.floor_s = 0.01;
  o.ceiling_s = 0.001;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("ceiling 0.001 s"), std::string::npos) << error;
  EXPECT_NE(error.find("floor 0.01 s"), std::string::npos) << error;
}

TEST(RttOptions, ANonFiniteInitialTimeoutIsInvalidNamingIt) {
  RttOptions o;
  o.initial_s = std::numeric_limits<double>::infinity();
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("initial resend timeout inf"), std::string::npos) << error;
  EXPECT_FALSE(o.IsValid(nullptr));
}

}  // namespace
}  // namespace pidlab::transport
