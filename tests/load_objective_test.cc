// The load objectives: IAE of the response to a unit step at the plant input
// with r = 0, against closed forms and a fine sampled simulation.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/tune/tune.h"
#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoadIntegralAbsError;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::tune::RefineVerdict;
using pidlab::tune::Tune;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;

namespace pidlab {
namespace {

Plant Custom(std::vector<double> num, std::vector<double> den) {
  Plant plant;
  std::string error;
  EXPECT_TRUE(IsOk(MakeCustomPlant(num, den, &plant)));
  return plant;
}

// sum_{m=0}^{500} |y(m ts)| of y(t) = c (e^{-t} - e^{-2t}).
double ClosedFormLoadIae(double c) {
  double sum = 0.0;
  for (int m = 0; m <= 500; ++m) sum += std::abs(c * (std::exp(-0.05 * m) - std::exp(-0.1 * m)));
  return sum;
}

TEST(LoadIntegralAbsError, OnOneOverSWithPiIsTheClosedFormOfTwoExponentials) {
  // Y/N = s / (s^2 + kp s + ki): a unit input step gives 1/((s+1)(s+2)).
  const Plant plant = Custom({1.0}, {1.0, 0.0});
  const PidGains pi{3.0, 2.0, 0.0};
  const double expected = ClosedFormLoadIae(1.0);
  EXPECT_NEAR(LoadIntegralAbsError(plant, pi, LoopOptions{}), expected, 1e-12 * expected);
  const ObjectiveEvaluator dut(plant, LoopOptions{}, ObjectiveKind::kLoadIae);
  EXPECT_NEAR(dut(pi), expected, 1e-12 * expected);
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(plant, pi, LoopOptions{}, EvaluateOptions{}, &ev)));
  EXPECT_NEAR(ev.load_iae, expected, 1e-12 * expected);
  EXPECT_EQ(ev.Objective(ObjectiveKind::kLoadIae), ev.load_iae);
}

TEST(LoadIntegralAbsError, OnOneOverSWithAnIdealPidHasNoDerivativeKick) {
  // Y/N = s / ((1 + kd) s^2 + kp s + ki) = s / (2 (s+1)(s+2)): r does not move,
  // so nothing jumps at t = 0 and y = (e^{-t} - e^{-2t}) / 2.
  const Plant plant = Custom({1.0}, {1.0, 0.0});
  const double expected = ClosedFormLoadIae(0.5);
  EXPECT_NEAR(LoadIntegralAbsError(plant, PidGains{6.0, 4.0, 1.0}, LoopOptions{}), expected,
              1e-12 * expected);
}

TEST(LoadIntegralAbsError, IgnoresTheReferenceSizeAndTheLoopsOwnDisturbance) {
  const Plant plant = Custom({1.0}, {1.0, 0.0});
  LoopOptions options;
  options.reference = 3.0;
  options.disturbance.kind = DisturbanceKind::kSine;
  options.disturbance.amplitude = 0.5;
  const double expected = ClosedFormLoadIae(1.0);
  EXPECT_NEAR(LoadIntegralAbsError(plant, PidGains{3.0, 2.0, 0.0}, options), expected, 1e-12 * expected);
}

TEST(LoadIntegralAbsError, AgreesWithAFineSampledSimulationOfTheDoubleIntegrator) {
  // 1/s^2 with kp = 2, ki = 1, kd = 3 (s^3 + 3 s^2 + 2 s + 1: stable). The
  // sampled loop at dt = 1e-4 (discrete PID, exact ZOH plant, r_k = 0,
  // n_k = 1) converges to the exact continuous response as dt -> 0.
  const Plant plant = Custom({1.0}, {1.0, 0.0, 0.0});
  const PidGains g{2.0, 1.0, 3.0};
  const double exact = LoadIntegralAbsError(plant, g, LoopOptions{});
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  sampled.dt_s = 1e-4;
  const double fine = LoadIntegralAbsError(plant, g, sampled);
  ASSERT_TRUE(std::isfinite(exact));
  EXPECT_NEAR(fine, exact, 1e-3 * exact) << "exact " << exact << " sampled " << fine;
  sampled.dt_s = 1e-3;
  EXPECT_GT(std::abs(LoadIntegralAbsError(plant, g, sampled) - exact), std::abs(fine - exact));
}

TEST(LoadIntegralAbsError, IsInfiniteForAnUnstableLoop) {
  const Plant plant = Custom({1.0}, {1.0, 0.0, 0.0});
  EXPECT_TRUE(std::isinf(LoadIntegralAbsError(plant, PidGains{1.0, 10.0, 0.1}, LoopOptions{})));
  const ObjectiveEvaluator dut(plant, LoopOptions{}, ObjectiveKind::kSetpointLoad);
  EXPECT_TRUE(std::isinf(dut(PidGains{1.0, 10.0, 0.1})));
}

TEST(SetpointLoadObjective, IsTheSetpointIaePlusTheWeightedLoadIae) {
  Plant plant;
  ASSERT_TRUE(IsOk(MakePlant("stepper_motor", StepperMotorParameters{}, &plant)));
  const PidGains g{20.8836, 26.607, 12.4866};  // the paper's Table IV Nelder-Mead gains
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(plant, g, LoopOptions{}, EvaluateOptions{}, &ev)));
  for (double w : {0.0, 0.5, 2.0}) {
    const ObjectiveEvaluator dut(plant, LoopOptions{}, ObjectiveKind::kSetpointLoad, nullptr, w);
    EXPECT_NEAR(dut(g), ev.iae + w * ev.load_iae, 1e-12 * (ev.iae + w * ev.load_iae)) << "W = " << w;
    EXPECT_NEAR(ev.Objective(ObjectiveKind::kSetpointLoad, w), dut(g), 1e-12 * dut(g));
  }
  EXPECT_THROW(ObjectiveEvaluator(plant, LoopOptions{}, ObjectiveKind::kSetpointLoad, nullptr, -1.0),
               std::invalid_argument);
}

TEST(Tune, OnTheLoadIaeOfTheDoubleIntegratorUsesIntegralAction) {
  // The paper's objective's optimum (0.2999, 0, 30) leaves a steady error of
  // 1/kp under a load: its load IAE is in the hundreds. Tuned for the load,
  // the integral action removes it.
  Plant plant;
  ASSERT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &plant)));
  TuneOptions options;
  options.objective = ObjectiveKind::kLoadIae;
  TuneSummary dut;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  EXPECT_GT(dut.gains.ki, 1.0);
  EXPECT_EQ(dut.refine.verdict, RefineVerdict::kNotRun);
  const double paper_objective_optimum =
      LoadIntegralAbsError(plant, PidGains{0.2999, 0.0, 30.0}, options.loop);
  EXPECT_GT(paper_objective_optimum, 100.0);
  EXPECT_LT(dut.objective, 0.01 * paper_objective_optimum);
  EXPECT_NEAR(LoadIntegralAbsError(plant, dut.gains, options.loop), dut.objective, 1e-12 * dut.objective);
}

}  // namespace
}  // namespace pidlab
