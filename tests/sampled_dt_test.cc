// The sampled period autotune takes from the plant when --dt is not given
// (tune/time_scale.h, SampledDtFromPlant; issue 60, "Settings from the
// process").

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pidlab::tune
