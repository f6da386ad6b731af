// LoopOptions::reference: a step of size A. A linear loop scales exactly with
// A (IAE(A) = |A| IAE(1)), the continuous and the sampled loop alike.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::SampledStep;

namespace pidlab {
namespace {

Plant Stepper() {
  Plant p;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant("stepper_motor", StepperMotorParameters{}, &p)));
  return p;
}

Evaluation EvaluateAt(const Plant& plant, const PidGains& gains, LoopOptions o, double reference) {
  o.reference = reference;
  Evaluation ev;
  std::string error;
  EXPECT_TRUE(IsOk(Evaluate(plant, gains, o, EvaluateOptions{}, &ev)));
  return ev;
}

const PidGains kPaperNelderMead{20.8836, 26.607, 12.4866};

TEST(Reference, ContinuousLoopScalesWithTheStepSize) {
  const LoopOptions o;
  const Evaluation one = EvaluateAt(Stepper(), kPaperNelderMead, o, 1.0);
  for (const double a : {0.001, 0.37, 3.5}) {
    const Evaluation dut = EvaluateAt(Stepper(), kPaperNelderMead, o, a);
    ASSERT_TRUE(dut.stability.stable);
    EXPECT_NEAR(dut.iae, a * one.iae, 1e-12 * a * one.iae) << "A = " << a;
    EXPECT_NEAR(dut.iae_per_unit, one.iae, 1e-12 * one.iae) << "A = " << a;
    EXPECT_NEAR(dut.ise, a * a * one.ise, 1e-11 * a * a * one.ise) << "A = " << a;
    EXPECT_NEAR(dut.iae_continuous, a * one.iae_continuous, 1e-9 * a * one.iae_continuous) << "A = " << a;
    ASSERT_TRUE(dut.step.valid) << dut.step.note;
    EXPECT_NEAR(dut.step.final_value, a, 1e-9 * a);
    EXPECT_NEAR(dut.step.overshoot_pct, one.step.overshoot_pct, 1e-6);
    EXPECT_NEAR(dut.step.rise_time_s, one.step.rise_time_s, 1e-9);
    EXPECT_NEAR(dut.step.settling_time_s, one.step.settling_time_s, 1e-9);
    for (std::size_t m = 0; m < dut.y.size(); ++m)
      ASSERT_NEAR(dut.y[m], a * one.y[m], 1e-12 * a + 1e-15) << "sample " << m;
  }
}

TEST(Reference, SampledLoopScalesWithTheStepSize) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  o.horizon_s = 2.0;
  const Evaluation one = EvaluateAt(Stepper(), kPaperNelderMead, o, 1.0);
  for (const double a : {0.001, 0.37, 3.5}) {
    const Evaluation dut = EvaluateAt(Stepper(), kPaperNelderMead, o, a);
    ASSERT_TRUE(dut.stability.stable);
    EXPECT_NEAR(dut.iae, a * one.iae, 1e-12 * a * one.iae) << "A = " << a;
    EXPECT_NEAR(dut.iae_per_unit, one.iae, 1e-12 * one.iae) << "A = " << a;
    EXPECT_NEAR(dut.iae_continuous, a * one.iae_continuous, 1e-12 * a * one.iae_continuous);
    ASSERT_TRUE(dut.step.valid) << dut.step.note;
    EXPECT_NEAR(dut.step.final_value, a, 1e-9 * a);
    EXPECT_NEAR(dut.step.overshoot_pct, one.step.overshoot_pct, 1e-6);
  }
}

TEST(Reference, PowerOfTwoStepScalesEveryOutputBitForBit) {
  // Multiplying by 2 is exact in binary floating point, so every sample is.
  for (const LoopKind kind : {LoopKind::kContinuous, LoopKind::kSampled}) {
    LoopOptions o;
    o.loop = kind;
    o.dt_s = 1e-4;
    o.horizon_s = 1.0;
    const Evaluation one = EvaluateAt(Stepper(), kPaperNelderMead, o, 1.0);
    const Evaluation dut = EvaluateAt(Stepper(), kPaperNelderMead, o, 2.0);
    ASSERT_EQ(dut.y.size(), one.y.size());
    for (std::size_t m = 0; m < dut.y.size(); ++m) ASSERT_EQ(dut.y[m], 2.0 * one.y[m]) << "sample " << m;
    EXPECT_EQ(dut.iae, 2.0 * one.iae);
    EXPECT_EQ(dut.iae_per_unit, one.iae);
  }
}

TEST(Reference, ObjectiveEvaluatorUsesTheStepSize) {
  for (const LoopKind kind : {LoopKind::kContinuous, LoopKind::kSampled}) {
    LoopOptions o;
    o.loop = kind;
    o.dt_s = 1e-4;
    o.horizon_s = 2.0;
    o.reference = 0.25;
    const ObjectiveEvaluator dut(Stepper(), o, ObjectiveKind::kIae);
    const Evaluation ev = EvaluateAt(Stepper(), kPaperNelderMead, o, 0.25);
    if (kind ==
        LoopKind::kContinuous)  // ObjectiveEvaluator's fast path (fast_objective.h) rounds differently
      EXPECT_NEAR(dut(kPaperNelderMead), ev.iae, 1e-12 * ev.iae);
    else
      EXPECT_EQ(dut(kPaperNelderMead), ev.iae);
  }
}

TEST(Reference, SampledTrajectoryCarriesTheReference) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  o.horizon_s = 0.1;
  o.reference = 0.01;
  Evaluation ev;
  std::string error;
  EvaluateOptions what;
  what.record_trajectory = true;
  ASSERT_TRUE(IsOk(Evaluate(Stepper(), kPaperNelderMead, o, what, &ev)));
  ASSERT_FALSE(ev.trajectory.empty());
  for (const SampledStep& s : ev.trajectory) ASSERT_EQ(s.r, 0.01);
}

TEST(LoopOptions, RejectsAZeroReference) {
  LoopOptions dut;
  dut.reference = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("reference"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsANonFiniteReference) {
  LoopOptions dut;
  dut.reference = std::nan("");
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("reference"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
