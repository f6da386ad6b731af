// Ziegler-Nichols ultimate gain: textbook plants, the paper's plants, and the
// cases where the method does not apply.

#include "pidlab/tune/ziegler_nichols.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>

#include "pidlab/plant_sim/plants.h"
#include "test_status.h"

using pidlab::tune::ParseZieglerNicholsRule;
using pidlab::tune::ZieglerNicholsResult;
using pidlab::tune::ZieglerNicholsRule;
using pidlab::tune::ZieglerNicholsTune;

namespace pidlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Independent check for a third-order plant b0 / (a3 s^3 + a2 s^2 + a1 s + a0)
// under P control: the Routh array of a3 s^3 + a2 s^2 + a1 s + (a0 + K b0) is
//   a3        a1
//   a2        a0 + K b0
//   (a2 a1 - a3 (a0 + K b0)) / a2
//   a0 + K b0
// so the loop is stable iff a2 a1 > a3 (a0 + K b0): Ku = (a2 a1 / a3 - a0) / b0,
// and on the boundary the auxiliary polynomial a2 s^2 + a0 + Ku b0 gives
// wu^2 = (a0 + Ku b0) / a2 = a1 / a3.
struct RouthThirdOrder {
  double ku, wu;
};
RouthThirdOrder RouthUltimate(double b0, double a3, double a2, double a1, double a0) {
  const double ku = (a2 * a1 / a3 - a0) / b0;
  return {ku, std::sqrt((a0 + ku * b0) / a2)};
}

TEST(ZieglerNichols, ThirdOrderLagMatchesTextbook) {
  const TransferFunction tf{{1.0}, {1.0, 3.0, 3.0, 1.0}};  // 1/(s+1)^3
  ZieglerNicholsResult dut;
  std::string error;
  ASSERT_TRUE(IsOk(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut)));
  std::cout << "1/(s+1)^3: " << dut.message << "\n";
  EXPECT_TRUE(dut.applicable);
  EXPECT_NEAR(dut.ultimate_gain, 8.0, 1e-9);
  EXPECT_NEAR(dut.crossover_rad_s, std::sqrt(3.0), 1e-9);
  const double tu = 2.0 * kPi / std::sqrt(3.0);
  EXPECT_NEAR(dut.ultimate_period_s, tu, 1e-9);
  EXPECT_NEAR(dut.gains.kp, 4.8, 1e-9);
  EXPECT_NEAR(dut.gains.ki, 4.8 / (tu / 2.0), 1e-9);
  EXPECT_NEAR(dut.gains.kd, 4.8 * tu / 8.0, 1e-9);
}

TEST(ZieglerNichols, FourthOrderLagPutsPolesOnTheAxisAtKu) {
  // 1/(s+1)^4: phase -180 deg at w = 1 (45 deg per pole), |(1+j)^4| = 4.
  const TransferFunction tf{{1.0}, {1.0, 4.0, 6.0, 4.0, 1.0}};
  ZieglerNicholsResult dut;
  std::string error;
  ASSERT_TRUE(IsOk(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut)));
  EXPECT_NEAR(dut.ultimate_gain, 4.0, 1e-9);
  EXPECT_NEAR(dut.crossover_rad_s, 1.0, 1e-9);
  // And the closed-loop polynomial at Ku really has the roots +/- j wu.
  std::vector<double> p = tf.den;
  p.back() += dut.ultimate_gain;
  double closest = 1e9;
  for (const auto& r : PolynomialRoots(p))
    closest = std::min(closest, std::abs(r - std::complex<double>(0.0, dut.crossover_rad_s)));
  EXPECT_LT(closest, 1e-6);
}

TEST(ZieglerNichols, StepperMotorMatchesRouthArray) {
  const TransferFunction tf = StepperMotorTransferFunction(StepperMotorParameters{});
  ASSERT_EQ(tf.den.size(), 4u);
  ASSERT_EQ(tf.num.size(), 1u);
  const RouthThirdOrder routh = RouthUltimate(tf.num[0], tf.den[0], tf.den[1], tf.den[2], tf.den[3]);
  ZieglerNicholsResult dut;
  std::string error;
  ASSERT_TRUE(IsOk(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut)));
  std::cout << "stepper motor: " << dut.message << "\n"
            << "  Routh array: Ku = " << routh.ku << ", wu = " << routh.wu << " rad/s\n";
  EXPECT_NEAR(dut.ultimate_gain, routh.ku, 1e-7 * routh.ku);
  EXPECT_NEAR(dut.crossover_rad_s, routh.wu, 1e-7 * routh.wu);
  EXPECT_NEAR(dut.gains.kp, 0.6 * routh.ku, 1e-7 * routh.ku);
  EXPECT_NEAR(dut.ultimate_period_s, 2.0 * kPi / routh.wu, 1e-7);
}

TEST(ZieglerNichols, RulesScaleTheUltimateValues) {
  const TransferFunction tf{{1.0}, {1.0, 3.0, 3.0, 1.0}};
  struct Case {
    ZieglerNicholsRule rule;
    double kp_over_ku, ti_over_tu, td_over_tu;
  };
  const Case cases[] = {{ZieglerNicholsRule::kClassic, 0.6, 0.5, 0.125},
                        {ZieglerNicholsRule::kPessen, 0.7, 0.4, 0.15},
                        {ZieglerNicholsRule::kSomeOvershoot, 0.33, 0.5, 1.0 / 3.0},
                        {ZieglerNicholsRule::kNoOvershoot, 0.2, 0.5, 1.0 / 3.0}};
  for (const Case& c : cases) {
    ZieglerNicholsResult dut;
    std::string error;
    ASSERT_TRUE(IsOk(ZieglerNicholsTune(tf, c.rule, &dut)));
    const double ku = 8.0, tu = 2.0 * kPi / std::sqrt(3.0), kp = c.kp_over_ku * ku;
    EXPECT_NEAR(dut.gains.kp, kp, 1e-9) << ToString(c.rule);
    EXPECT_NEAR(dut.gains.ki, kp / (c.ti_over_tu * tu), 1e-9) << ToString(c.rule);
    EXPECT_NEAR(dut.gains.kd, kp * c.td_over_tu * tu, 1e-9) << ToString(c.rule);
  }
}

TEST(ZieglerNichols, RuleNamesRoundTrip) {
  for (const char* name : {"classic", "pessen", "some-overshoot", "no-overshoot"}) {
    ZieglerNicholsRule rule;
    ASSERT_TRUE(ParseZieglerNicholsRule(name, &rule)) << name;
    EXPECT_EQ(ToString(rule), name);
  }
  ZieglerNicholsRule rule;
  EXPECT_FALSE(ParseZieglerNicholsRule("tyreus-luyben", &rule));
}

TEST(ZieglerNichols, DoubleIntegratorIsNotApplicable) {
  const TransferFunction tf{{1.0}, {1.0, 0.0, 0.0}};  // 1/s^2: s^2 + K, poles +/- j sqrt(K)
  ZieglerNicholsResult dut;
  dut.applicable = true;
  std::string error;
  EXPECT_FALSE(OkInto(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut), &error));
  std::cout << "1/s^2: " << error << "\n";
  EXPECT_FALSE(dut.applicable);
  EXPECT_NE(error.find("marginally stable"), std::string::npos) << error;
  EXPECT_NE(error.find("no finite ultimate gain"), std::string::npos) << error;
  EXPECT_EQ(dut.message, error);
  EXPECT_EQ(dut.ultimate_gain, 0.0);
}

TEST(ZieglerNichols, OscillatorIsNotApplicable) {
  // 1/(s^2+1): s^2 + 1 + K, poles +/- j sqrt(1 + K) for every K > 0.
  const TransferFunction tf{{1.0}, {1.0, 0.0, 1.0}};
  ZieglerNicholsResult dut;
  std::string error;
  EXPECT_FALSE(OkInto(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut), &error));
  std::cout << "1/(s^2+1): " << error << "\n";
  EXPECT_FALSE(dut.applicable);
  EXPECT_NE(error.find("marginally stable"), std::string::npos) << error;
}

TEST(ZieglerNichols, PlantsThatNeverReachTheBoundaryAreNotApplicable) {
  for (const TransferFunction& tf : {TransferFunction{{1.0}, {1.0, 1.0}},          // 1/(s+1)
                                     TransferFunction{{1.0}, {1.0, 1.0, 0.0}},     // 1/(s(s+1))
                                     TransferFunction{{1.0}, {1.0, 3.0, 2.0}}}) {  // 1/((s+1)(s+2))
    ZieglerNicholsResult dut;
    std::string error;
    EXPECT_FALSE(OkInto(ZieglerNicholsTune(tf, ZieglerNicholsRule::kClassic, &dut), &error)) << tf.ToString();
    EXPECT_NE(error.find("never reaches the stability boundary"), std::string::npos) << error;
  }
}

TEST(ZieglerNichols, InvalidPlantIsRejected) {
  ZieglerNicholsResult dut;
  std::string error;
  EXPECT_FALSE(OkInto(
      ZieglerNicholsTune(TransferFunction{{1.0, 0.0, 0.0}, {1.0, 1.0}}, ZieglerNicholsRule::kClassic, &dut),
      &error));
  EXPECT_NE(error.find("improper"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
