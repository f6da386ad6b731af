// The sampled period autotune takes from the plant when --dt is not given,
// and its relay's y limit when --y-limit is not (tune/time_scale.h,
// SampledDtFromPlant, RelayYLimitFromPlant; issue 60, "Settings from the
// process").

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/tune/time_scale.h"

namespace pidlab::tune {
namespace {

Plant Make(std::vector<double> num, std::vector<double> den, double delay_s) {
  Plant p;
  p.name = "custom";
  p.tf.num = std::move(num);
  p.tf.den = std::move(den);
  p.delay_s = delay_s;
  return p;
}

TEST(SampledDt, IsTheShorterOfTheDelayAndTheFastestTimeOver400OnAOneTwoFiveGrid) {
  std::string why;
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {1, 1}, 2.0), &why), 0.002) << why;
  EXPECT_NE(why.find("dt 0.002 s"), std::string::npos) << why;
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {1, 1}, 0.5), &why), 0.001) << why;
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {1, 1}, 0.1), &why), 0.0002) << why;
  // No delay: the fastest lag, 0.1 s.
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {0.1, 1.1, 1}, 0.0), &why), 0.0002) << why;
}

TEST(SampledDt, KeepsTheDelayLineWithinWhatTheAnalysisTakes) {
  std::string why;
  // 10 s of delay over a 1 s lag: 1 / 400 would store 4000 inputs; 10 / 1000 = 0.01.
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {1, 1}, 10.0), &why), 0.01) << why;
  EXPECT_NE(why.find("delay line"), std::string::npos) << why;
  // 3 s: 3 / 1000 = 0.003, up to 0.005.
  EXPECT_DOUBLE_EQ(SampledDtFromPlant(Make({1}, {0.5, 1}, 3.0), &why), 0.005) << why;
}

TEST(RelayYLimit, IsTenExpectedAmplitudesOfTheRelayOnThePlantsUltimateGain) {
  std::string why;
  // e^(-s pi/2) / s reaches -180 deg at w = 1, where |G| = 1: Ku = 1, and
  // the limit is 10 x 4 d / pi.
  const double d = 4.0 / 3.0;
  EXPECT_NEAR(RelayYLimitFromPlant(Make({1}, {1, 0}, M_PI / 2), d, 0.0, &why), 10 * 4 * d / M_PI, 1e-6)
      << why;
  EXPECT_NE(why.find("expected amplitude"), std::string::npos) << why;
  // A reverse-acting plant: its mirror's.
  EXPECT_NEAR(RelayYLimitFromPlant(Make({-1}, {1, 0}, M_PI / 2), d, 0.0, &why), 10 * 4 * d / M_PI, 1e-6)
      << why;
  EXPECT_DOUBLE_EQ(RelayYLimitFromPlant(Make({-1}, {1, 1}, 2.0), d, 0.0, &why),
                   RelayYLimitFromPlant(Make({1}, {1, 1}, 2.0), d, 0.0, &why));
  // Measurement noise widens it by 6 sigma, said so.
  EXPECT_NEAR(RelayYLimitFromPlant(Make({1}, {1, 0}, M_PI / 2), d, 0.05, &why), 10 * 4 * d / M_PI + 0.3,
              1e-6);
  EXPECT_NE(why.find("6 sigma"), std::string::npos) << why;
}

TEST(RelayYLimit, IsTwiceTheStaticResponseWithoutAnUltimateGainAndNoneWithNeither) {
  std::string why;
  // 2 / (s + 1) never reaches -180 deg: 2 x |K| d.
  EXPECT_DOUBLE_EQ(RelayYLimitFromPlant(Make({2}, {1, 1}, 0.0), 0.5, 0.0, &why), 2.0) << why;
  EXPECT_NE(why.find("static response"), std::string::npos) << why;
  // 1 / s: neither.
  EXPECT_TRUE(std::isinf(RelayYLimitFromPlant(Make({1}, {1, 0}, 0.0), 0.5, 0.0, &why))) << why;
  EXPECT_NE(why.find("no y limit"), std::string::npos) << why;
}

}  // namespace
}  // namespace pidlab::tune
