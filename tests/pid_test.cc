// The discrete PID of controller/pid.h against its closed forms.

#include "pidlab/controller/pid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace pidlab {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

PidOptions Options(double dt_s) {
  PidOptions o;
  o.dt_s = dt_s;
  return o;
}

TEST(DiscretePid, ProportionalOnlyIsKpTimesTheError) {
  DiscretePid<double> dut({2.0, 0.0, 0.0}, Options(0.01));
  double u = 0.0;
  EXPECT_EQ(dut.Step(1.0, 0.7, &u), PidStatus::kOk);
  EXPECT_NEAR(u, 0.6, 1e-15);
  EXPECT_EQ(dut.Step(1.0, 1.4, &u), PidStatus::kOk);
  EXPECT_NEAR(u, -0.8, 1e-15);
  EXPECT_EQ(dut.Step(1.0, 0.7, &u), PidStatus::kOk);
  EXPECT_NEAR(u, 0.6, 1e-15);
}

TEST(DiscretePid, BackwardEulerIntegralOfAConstantErrorIncludesTheCurrentSample) {
  const double ki = 3.0, dt = 0.01;
  PidOptions o = Options(dt);
  o.integral = IntegralMethod::kBackwardEuler;
  DiscretePid<double> dut({0.0, ki, 0.0}, o);
  for (int k = 0; k < 20; ++k) {
    double u = 0.0;
    dut.Step(1.0, 0.0, &u);
    EXPECT_NEAR(u, ki * dt * (k + 1), 1e-13) << "k = " << k;
  }
}

TEST(DiscretePid, ForwardEulerIntegralOfAConstantErrorLagsOneSample) {
  const double ki = 3.0, dt = 0.01;
  PidOptions o = Options(dt);
  o.integral = IntegralMethod::kForwardEuler;
  DiscretePid<double> dut({0.0, ki, 0.0}, o);
  for (int k = 0; k < 20; ++k) {
    double u = 0.0;
    dut.Step(1.0, 0.0, &u);
    EXPECT_NEAR(u, ki * dt * k, 1e-13) << "k = " << k;
  }
}

TEST(DiscretePid, TrapezoidalIntegralOfAConstantErrorAveragesTheTwoRules) {
  // The error is 0 before k = 0, so the first trapezoid has area dt / 2.
  const double ki = 3.0, dt = 0.01;
  PidOptions o = Options(dt);
  o.integral = IntegralMethod::kTrapezoidal;
  DiscretePid<double> dut({0.0, ki, 0.0}, o);
  for (int k = 0; k < 20; ++k) {
    double u = 0.0;
    dut.Step(1.0, 0.0, &u);
    EXPECT_NEAR(u, ki * dt * (k + 0.5), 1e-13) << "k = " << k;
  }
}

TEST(DiscretePid, DerivativeOnErrorGivesAKickOfAreaKdOnTheFirstStep) {
  const double kd = 0.5, dt = 1e-3;
  DiscretePid<double> dut({0.0, 0.0, kd}, Options(dt));
  double u = 0.0;
  dut.Step(1.0, 0.0, &u);
  EXPECT_NEAR(u, kd / dt, 1e-9);
  EXPECT_NEAR(u * dt, kd, 1e-15);
  dut.Step(1.0, 0.0, &u);
  EXPECT_NEAR(u, 0.0, 1e-15);
}

TEST(DiscretePid, DerivativeOnMeasurementGivesNoKick) {
  const double kd = 0.5, dt = 1e-3;
  PidOptions o = Options(dt);
  o.setpoint_weight_c = SetpointWeightC(DerivativeOn::kMeasurement);  // c = 0
  DiscretePid<double> dut({0.0, 0.0, kd}, o);
  double u = 1.0;
  EXPECT_EQ(dut.Step(1.0, 0.0, &u), PidStatus::kOk);
  EXPECT_EQ(u, 0.0);
  // A rising measurement gives -kd dy/dt.
  dut.Step(1.0, 0.1, &u);
  EXPECT_NEAR(u, -kd * 0.1 / dt, 1e-9);
}

TEST(DiscretePid, FilteredDerivativeOfAStepDecaysGeometricallyWithAreaKd) {
  // D_k = (tf / (tf + dt))^k kd / (tf + dt): the backward-Euler image of
  // kd / tf e^{-t / tf}, the filtered derivative's response to a unit step.
  const double kd = 2.0, dt = 1e-3, tf = 0.05;
  PidOptions o = Options(dt);
  o.derivative_filter_s = tf;
  DiscretePid<double> dut({0.0, 0.0, kd}, o);
  const double a = tf / (tf + dt);
  double area = 0.0;
  for (int k = 0; k < 5000; ++k) {
    double u = 0.0;
    dut.Step(1.0, 0.0, &u);
    const double expected = std::pow(a, k) * kd / (tf + dt);
    ASSERT_NEAR(u, expected, 1e-12 * kd / (tf + dt)) << "k = " << k;
    area += u * dt;
  }
  EXPECT_NEAR(area, kd, 1e-9);
  // Close to the continuous filter: at t = tf, kd / tf e^-1 within O(dt / tf).
  DiscretePid<double> again({0.0, 0.0, kd}, o);
  double u = 0.0;
  for (int k = 0; k <= 50; ++k) again.Step(1.0, 0.0, &u);
  EXPECT_NEAR(u, kd / tf * std::exp(-1.0), 0.03 * kd / tf);
}

TEST(DiscretePid, OutputIsClippedToTheUpperLimitAndReportsSaturation) {
  PidOptions o = Options(0.01);
  o.output_min = -3.0;
  o.output_max = 2.0;
  DiscretePid<double> dut({10.0, 0.0, 0.0}, o);
  double u = 0.0;
  EXPECT_EQ(dut.Step(1.0, 0.0, &u), PidStatus::kSaturated);
  EXPECT_EQ(u, 2.0);
}

TEST(DiscretePid, OutputIsClippedToTheLowerLimitAndReportsSaturation) {
  PidOptions o = Options(0.01);
  o.output_min = -3.0;
  o.output_max = 2.0;
  DiscretePid<double> dut({10.0, 0.0, 0.0}, o);
  double u = 0.0;
  EXPECT_EQ(dut.Step(0.0, 1.0, &u), PidStatus::kSaturated);
  EXPECT_EQ(u, -3.0);
}

TEST(DiscretePid, OutputInsideTheLimitsIsNotSaturated) {
  PidOptions o = Options(0.01);
  o.output_min = -3.0;
  o.output_max = 2.0;
  DiscretePid<double> dut({1.0, 0.0, 0.0}, o);
  double u = 0.0;
  EXPECT_EQ(dut.Step(1.0, 0.0, &u), PidStatus::kOk);
  EXPECT_EQ(u, 1.0);
}

// Five saturated steps with e = 1, then one with e = 0: u is the integral.
double IntegralAfterSaturation(AntiWindup anti_windup, double back_calculation_gain = 1.0) {
  PidOptions o = Options(0.1);
  o.output_min = -1.0;
  o.output_max = 1.0;
  o.anti_windup = anti_windup;
  o.back_calculation_gain = back_calculation_gain;
  DiscretePid<double> dut({10.0, 1.0, 0.0}, o);
  double u = 0.0;
  for (int k = 0; k < 5; ++k) EXPECT_EQ(dut.Step(1.0, 0.0, &u), PidStatus::kSaturated);
  EXPECT_EQ(dut.Step(0.0, 0.0, &u), PidStatus::kOk);
  return u;
}

TEST(DiscretePid, WithoutAntiWindupTheIntegralWindsUpWhileSaturated) {
  EXPECT_NEAR(IntegralAfterSaturation(AntiWindup::kNone), 5 * 1.0 * 0.1 * 1.0, 1e-12);
}

TEST(DiscretePid, ClampingStopsIntegratingWhileTheErrorPushesIntoTheLimit) {
  EXPECT_NEAR(IntegralAfterSaturation(AntiWindup::kClamping), 0.0, 1e-15);
}

TEST(DiscretePid, ClampingKeepsIntegratingWhenTheErrorPullsBackInside) {
  // Saturated high by a large kd kick while e < 0: the integral must move.
  PidOptions o = Options(0.1);
  o.output_min = -1.0;
  o.output_max = 1.0;
  o.anti_windup = AntiWindup::kClamping;
  o.setpoint_weight_c = SetpointWeightC(DerivativeOn::kMeasurement);  // c = 0
  DiscretePid<double> dut({0.0, 2.0, 5.0}, o);
  double u = 0.0;
  dut.Step(0.0, 0.0, &u);
  // y falls from 0 to -1 with r = -1.5: e = -0.5 < 0, D = -kd (-1 - 0) / dt = +50.
  EXPECT_EQ(dut.Step(-1.5, -1.0, &u), PidStatus::kSaturated);
  EXPECT_EQ(u, 1.0);
  // Next step, y unchanged: D = 0 and u = I, which kept the ki dt (-0.5) of the saturated step.
  dut.Step(0.0, -1.0, &u);
  // I = 2 * 0.1 * (-0.5) + 2 * 0.1 * 1.0 (e = 0 - (-1) = 1).
  EXPECT_NEAR(u, 2.0 * 0.1 * (-0.5) + 2.0 * 0.1 * 1.0, 1e-12);
}

TEST(DiscretePid, BackCalculationBleedsTheIntegralByTheSaturationExcess) {
  // Closed form: I_k = I_{k-1} + ki dt e + kb dt (u_sat - u_unsat), with
  // u_unsat = kp e + I_{k-1} + ki dt e.
  const double kp = 10.0, ki = 1.0, dt = 0.1, kb = 0.1;
  double integral = 0.0;
  for (int k = 0; k < 5; ++k) {
    const double candidate = integral + ki * dt;
    const double unsat = kp + candidate;
    integral = candidate + kb * dt * (1.0 - unsat);
  }
  const double dut = IntegralAfterSaturation(AntiWindup::kBackCalculation, kb);
  EXPECT_NEAR(dut, integral, 1e-12);
  EXPECT_LT(dut, IntegralAfterSaturation(AntiWindup::kNone));
}

TEST(DiscretePid, NanMeasurementIsRejectedAndLeavesTheStateUntouched) {
  PidOptions o = Options(0.01);
  DiscretePid<double> dut({1.0, 2.0, 0.1}, o);
  DiscretePid<double> reference({1.0, 2.0, 0.1}, o);
  double u = 0.0, u_ref = 0.0;
  dut.Step(1.0, 0.2, &u);
  reference.Step(1.0, 0.2, &u_ref);
  u = 42.0;
  EXPECT_EQ(dut.Step(1.0, kNaN, &u), PidStatus::kInvalidInput);
  EXPECT_EQ(u, 42.0);
  dut.Step(1.0, 0.3, &u);
  reference.Step(1.0, 0.3, &u_ref);
  EXPECT_EQ(u, u_ref);
}

TEST(DiscretePid, InfiniteReferenceIsRejected) {
  DiscretePid<double> dut({1.0, 0.0, 0.0}, Options(0.01));
  double u = 7.0;
  EXPECT_EQ(dut.Step(kInf, 0.0, &u), PidStatus::kInvalidInput);
  EXPECT_EQ(u, 7.0);
}

TEST(DiscretePid, ResetReturnsToRest) {
  DiscretePid<double> dut({1.0, 2.0, 0.1}, Options(0.01));
  double u = 0.0, first = 0.0;
  dut.Step(1.0, 0.0, &first);
  for (int k = 0; k < 10; ++k) dut.Step(1.0, 0.1 * k, &u);
  dut.Reset();
  dut.Step(1.0, 0.0, &u);
  EXPECT_EQ(u, first);
}

TEST(PidOptions, DefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(PidOptions{}.IsValid(&error)) << error;
}

TEST(PidOptions, RejectsAZeroDt) {
  PidOptions dut;
  dut.dt_s = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("dt 0"), std::string::npos) << error;
}

TEST(PidOptions, RejectsANanDt) {
  PidOptions dut;
  dut.dt_s = kNaN;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("dt nan"), std::string::npos) << error;
}

TEST(PidOptions, RejectsANegativeDerivativeFilter) {
  PidOptions dut;
  dut.derivative_filter_s = -0.5;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("derivative filter -0.5"), std::string::npos) << error;
}

TEST(PidOptions, RejectsEqualOutputLimits) {
  PidOptions dut;
  dut.output_min = 2.0;
  dut.output_max = 2.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("[2, 2]"), std::string::npos) << error;
}

TEST(PidOptions, RejectsANanOutputLimit) {
  PidOptions dut;
  dut.output_max = kNaN;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("nan"), std::string::npos) << error;
}

TEST(PidOptions, RejectsAZeroBackCalculationGain) {
  PidOptions dut;
  dut.anti_windup = AntiWindup::kBackCalculation;
  dut.back_calculation_gain = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("back-calculation gain 0"), std::string::npos) << error;
}

TEST(PidGains, RejectsGainsThatDifferInSign) {
  std::string error;
  EXPECT_FALSE(GainsAreValid({-1.0, 0.5, 0.0}, &error));
  EXPECT_NE(error.find("kp = -1"), std::string::npos) << error;
  EXPECT_NE(error.find("differ in sign"), std::string::npos) << error;
}

TEST(PidGains, AcceptsGainsAllAtMostZeroForAReverseActingPlant) {
  std::string error;
  EXPECT_TRUE(GainsAreValid({-1.0, -0.5, -0.1, 0.01}, &error)) << error;
  EXPECT_TRUE(GainsAreReverse({-1.0, 0.0, 0.0}));
  EXPECT_FALSE(GainsAreReverse({1.0, 0.0, 0.0}));
  EXPECT_FALSE(GainsAreValid({-1.0, -0.5, -0.1, -0.01}, &error));
  EXPECT_NE(error.find("tf"), std::string::npos) << error;
}

TEST(DiscretePid, AReverseActingPidOnANegatedErrorGivesTheNegatedOutputBitForBitUnderClamping) {
  // The mirror: gains -g on the error e give -(u of gains g on e), with the
  // clamping anti-windup's choices the same under mirrored limits.
  PidOptions o = Options(0.01);
  o.output_min = -0.4;
  o.output_max = 0.4;
  o.anti_windup = AntiWindup::kClamping;
  o.derivative_filter_s = 0.02;
  DiscretePid<double> direct({2.0, 3.0, 0.1}, o), reverse({-2.0, -3.0, -0.1}, o);
  int saturated = 0;
  for (int k = 0; k < 400; ++k) {
    const double y = 0.3 * std::sin(0.05 * k) + (k > 200 ? 0.5 : 0.0);
    double u = 0.0, v = 0.0;
    ASSERT_EQ(direct.Step(1.0, y, &u), reverse.Step(1.0, y, &v)) << "step " << k;
    ASSERT_EQ(v, -u) << "step " << k;
    saturated += std::fabs(u) == 0.4;
  }
  EXPECT_GT(saturated, 10);
}

TEST(PidGains, RejectsANanKi) {
  std::string error;
  EXPECT_FALSE(GainsAreValid({1.0, kNaN, 0.0}, &error));
  EXPECT_NE(error.find("ki = nan"), std::string::npos) << error;
}

TEST(PidGains, RejectsAnInfiniteKd) {
  std::string error;
  EXPECT_FALSE(GainsAreValid({1.0, 1.0, kInf}, &error));
  EXPECT_NE(error.find("kd = inf"), std::string::npos) << error;
}

TEST(PidGains, AcceptsZeroGains) {
  std::string error;
  EXPECT_TRUE(GainsAreValid({0.0, 0.0, 0.0}, &error)) << error;
}

TEST(PidGains, AcceptsGainsUpToTheLimitAndRejectsLargerOnes) {
  std::string error;
  EXPECT_TRUE(GainsAreValid({kMaxGain, kMaxGain, kMaxGain}, &error)) << error;
  EXPECT_FALSE(GainsAreValid({1.0, 1e13, 1.0}, &error));
  EXPECT_NE(error.find("ki = 1e+13"), std::string::npos) << error;
  EXPECT_FALSE(GainsAreValid({1e308, 1e308, 1e308}, &error));
  EXPECT_NE(error.find("kp = 1e+308"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
