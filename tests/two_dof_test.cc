// The 2-DOF PID (docs/two_dof.md): setpoint weights b, c in the discrete PID,
// the exact continuous loop (ideal, filtered, with dead time) and the sampled
// loop; what they change (the response to r) and what they cannot (the
// poles, the load response, Ms, Mt, the margins); MATLAB's PIDF2 example
// against an independent simulation (tests/python/two_dof_reference.py).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iterator>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/controller/pid.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::evaluation::BuildContinuousClosedLoop;
using pidlab::evaluation::ContinuousClosedLoop;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SetpointWeights;

namespace pidlab {
namespace {

// The discrete PID's step as it was before the setpoint weights (derivative
// on error), kept here as the 1-DOF reference.
struct OneDofPid {
  PidGains g;
  PidOptions o;
  double integral = 0, derivative = 0, prev_error = 0, prev_signal = 0;

  double Step(double r, double y) {
    const double dt = o.dt_s, e = r - y, p = g.kp * e;
    double in = integral;
    if (o.integral == IntegralMethod::kBackwardEuler) in += g.ki * dt * e;
    if (o.integral == IntegralMethod::kForwardEuler) in += g.ki * dt * prev_error;
    if (o.integral == IntegralMethod::kTrapezoidal) in += g.ki * (dt * 0.5) * (e + prev_error);
    const double tf = EffectiveDerivativeFilter(g, o);
    const double d = tf / (tf + dt) * derivative + g.kd * (e - prev_signal) * (1.0 / (tf + dt));
    const double unsat = p + in + d;
    double out = unsat;
    bool saturated = false;
    if (out > o.output_max) out = o.output_max, saturated = true;
    if (out < o.output_min) out = o.output_min, saturated = true;
    if (saturated && o.anti_windup == AntiWindup::kClamping) {
      if ((unsat > o.output_max && e > 0.0) || (unsat < o.output_min && e < 0.0)) {
        in = integral;
      }
    } else if (saturated && o.anti_windup == AntiWindup::kBackCalculation) {
      in += (o.back_calculation_gain * dt) * (out - unsat);
    }
    integral = in, derivative = d, prev_error = e, prev_signal = e;
    return out;
  }
};

Plant Custom(std::vector<double> num, std::vector<double> den, double delay_s = 0.0) {
  Plant p;
  p.name = "custom";
  p.tf = TransferFunction{std::move(num), std::move(den)};
  p.delay_s = delay_s;
  return p;
}

Evaluation EvaluateWith(const Plant& plant, const PidGains& g, LoopOptions o, double b, double c) {
  o.pid.setpoint_weight_b = b;
  o.pid.setpoint_weight_c = c;
  Evaluation ev;
  std::string error;
  EXPECT_TRUE(IsOk(Evaluate(plant, g, o, EvaluateOptions{}, &ev)));
  return ev;
}

TEST(TwoDofPid, UnitWeightsAreTheOneDofPidBitForBit) {
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> uni(-2.0, 2.0);
  for (const IntegralMethod im :
       {IntegralMethod::kBackwardEuler, IntegralMethod::kForwardEuler, IntegralMethod::kTrapezoidal}) {
    for (const AntiWindup aw : {AntiWindup::kNone, AntiWindup::kClamping, AntiWindup::kBackCalculation}) {
      PidOptions o;
      o.dt_s = 0.01;
      o.derivative_filter_s = 0.03;
      o.output_min = -1.5;
      o.output_max = 1.5;
      o.integral = im;
      o.anti_windup = aw;
      const PidGains g{2.0, 1.5, 0.2};
      DiscretePid<double> dut(g, o);
      OneDofPid ref{g, o};
      for (int k = 0; k < 2000; ++k) {
        const double r = uni(rng), y = uni(rng);
        double u = 0.0;
        dut.Step(r, y, &u);
        ASSERT_EQ(u, ref.Step(r, y)) << "step " << k;
      }
    }
  }
}

TEST(TwoDofPid, UnitWeightsBuildTheOneDofContinuousLoops) {
  const StateSpace ss = Realize({{1.0}, {1.0, 0.5, 0.1}});
  const Disturbance none{DisturbanceOptions{}};
  for (const double tf : {0.0, 0.122}) {
    const PidGains g{1.12, 0.23, 1.3, tf};
    ContinuousClosedLoop<double> dut;
    ASSERT_TRUE(OkInto(BuildContinuousClosedLoop<double>(ss, g, none, &dut, 1.0, SetpointWeights{1.0, 1.0}),
                       nullptr));
    const int ir = dut.reference_index();
    const double cb = ss.c.dot(ss.b), alpha = 1.0 / (1.0 + g.kd * cb);
    for (int i = 0; i < ss.order(); ++i) {
      // The 1-DOF formulas: u = (kp + kd/tf) r + ..., or alpha kp r and the kick alpha kd A B.
      EXPECT_EQ(dut.m(i, ir), ss.b(i) * (tf > 0.0 ? g.kp + g.kd / tf : alpha * g.kp));
      EXPECT_EQ(dut.w0(i), tf > 0.0 ? 0.0 : alpha * g.kd * (1.0 * ss.b(i)));
    }
    if (tf > 0.0) {
      EXPECT_EQ(dut.m(ir - 1, ir), 1.0 / tf);
    }
  }
}

TEST(TwoDofPid, WithCZeroTheFirstSampleOfAUnitStepAtRestIsKpB) {
  for (const double b : {0.0, 0.3, 0.664, 1.0}) {
    PidOptions o;
    o.dt_s = 0.01;
    o.integral = IntegralMethod::kForwardEuler;  // no integral at k = 0
    o.setpoint_weight_b = b;
    o.setpoint_weight_c = 0.0;
    DiscretePid<double> dut({1.12, 0.23, 1.3, 0.122}, o);
    double u = -1.0;
    ASSERT_EQ(dut.Step(1.0, 0.0, &u), PidStatus::kOk);
    EXPECT_EQ(u, 1.12 * b) << "b = " << b;
  }
}

TEST(TwoDofPid, WithCZeroTheIdealDerivativeGivesTheContinuousLoopNoKick) {
  const StateSpace ss = Realize({{1.0}, {1.0, 0.5, 0.1}});
  ContinuousClosedLoop<double> dut;
  ASSERT_TRUE(
      IsOk(BuildContinuousClosedLoop<double>(ss, PidGains{1.12, 0.23, 1.3}, Disturbance(DisturbanceOptions{}),
                                             &dut, 1.0, SetpointWeights{0.664, 0.0})));
  for (int i = 0; i < ss.order(); ++i) EXPECT_EQ(dut.w0(i), 0.0);
}

TEST(TwoDofPid, DerivativeOnMeasurementIsTheSetpointWeightCZero) {
  EXPECT_EQ(SetpointWeightC(DerivativeOn::kMeasurement), 0.0);
  EXPECT_EQ(SetpointWeightC(DerivativeOn::kError), 1.0);
}

TEST(TwoDofPid, WeightsOutsideTheUnitIntervalOrNotFiniteAreRefused) {
  for (const double w : {-0.1, 1.5, std::nan(""), static_cast<double>(INFINITY)}) {
    PidOptions o;
    o.setpoint_weight_b = w;
    std::string error;
    EXPECT_FALSE(o.IsValid(&error));
    EXPECT_NE(error.find("setpoint weight b"), std::string::npos) << error;
    o.setpoint_weight_b = 1.0;
    o.setpoint_weight_c = w;
    EXPECT_FALSE(o.IsValid(&error));
    EXPECT_NE(error.find("setpoint weight c"), std::string::npos) << error;
  }
}

// MATLAB's documented PIDF2 example (pid2: Kp 1.12, Ki 0.23, Kd 1.3, Tf 0.122,
// b 0.664, c 0.0136 on G = 1/(s^2 + 0.5 s + 0.1)): the exact continuous loop
// against scipy.signal's step of G Cr / (1 + G C) built from polynomials.
TEST(TwoDofPid, MatlabPidf2ExampleAgreesWithAnIndependentSimulation) {
  const std::pair<double, double> kScipy[] = {
#include "two_dof_matlab_table.inc"
  };
  LoopOptions o;
  o.sample_time_s = 0.5;
  o.horizon_s = 25.0;
  const Evaluation ev =
      EvaluateWith(Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3, 0.122}, o, 0.664, 0.0136);
  ASSERT_TRUE(ev.stability.stable);
  ASSERT_EQ(ev.y.size(), std::size(kScipy));
  for (std::size_t m = 0; m < ev.y.size(); ++m) {
    EXPECT_EQ(ev.t[m], kScipy[m].first);
    EXPECT_NEAR(ev.y[m], kScipy[m].second, 1e-9) << "t = " << ev.t[m];
  }
}

// Every loop kind: the load response and the frequency analysis do not move
// with b and c; the setpoint response does.
void ExpectOnlyTheSetpointResponseMoves(const Plant& plant, const PidGains& g, const LoopOptions& o) {
  const Evaluation one = EvaluateWith(plant, g, o, 1.0, 1.0);
  LoopAnalysis a1;
  std::string error;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, o, LoopAnalysisOptions{}, &a1)));
  ASSERT_TRUE(one.stability.stable);
  for (const auto& [b, c] : std::vector<std::pair<double, double>>{{0.5, 0.0}, {0.0, 0.3}, {0.664, 0.0136}}) {
    const Evaluation two = EvaluateWith(plant, g, o, b, c);
    LoopOptions ow = o;
    ow.pid.setpoint_weight_b = b;
    ow.pid.setpoint_weight_c = c;
    LoopAnalysis a2;
    ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, ow, LoopAnalysisOptions{}, &a2)));
    EXPECT_EQ(two.load_iae, one.load_iae) << b << "," << c;
    EXPECT_EQ(a2.ms, a1.ms);
    EXPECT_EQ(a2.mt, a1.mt);
    EXPECT_EQ(a2.gain_margin, a1.gain_margin);
    EXPECT_EQ(a2.phase_margin_deg, a1.phase_margin_deg);
    EXPECT_EQ(two.stability.stable, one.stability.stable);
    EXPECT_GT(std::abs(two.iae - one.iae), 1e-6) << b << "," << c;
  }
}

TEST(TwoDofPid, LoadIaeMsMtAndMarginsDoNotDependOnTheWeightsInTheFilteredContinuousLoop) {
  LoopOptions o;
  o.sample_time_s = 0.1;
  o.horizon_s = 40.0;
  ExpectOnlyTheSetpointResponseMoves(Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3, 0.122}, o);
}

TEST(TwoDofPid, LoadIaeMsMtAndMarginsDoNotDependOnTheWeightsInTheIdealContinuousLoop) {
  LoopOptions o;
  o.sample_time_s = 0.1;
  o.horizon_s = 40.0;
  ExpectOnlyTheSetpointResponseMoves(Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3}, o);
}

TEST(TwoDofPid, LoadIaeMsMtAndMarginsDoNotDependOnTheWeightsWithDeadTime) {
  LoopOptions o;
  o.sample_time_s = 0.1;
  o.horizon_s = 40.0;
  ExpectOnlyTheSetpointResponseMoves(Custom({1.0}, {1.0, 0.5, 0.1}, 0.3), {0.6, 0.12, 0.6, 0.1}, o);
}

TEST(TwoDofPid, LoadIaeMsMtAndMarginsDoNotDependOnTheWeightsInTheSampledLoop) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 0.01;
  o.sample_time_s = 0.1;
  o.horizon_s = 40.0;
  ExpectOnlyTheSetpointResponseMoves(Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3, 0.122}, o);
}

// The sampled 2-DOF PID converges to the exact continuous 2-DOF loop as dt
// shrinks, with and without dead time: both put r through b and c alike.
TEST(TwoDofPid, TheSampledLoopApproachesTheContinuousLoopWithTheSameWeights) {
  for (const double delay : {0.0, 0.3}) {
    LoopOptions c;
    c.sample_time_s = 0.1;
    c.horizon_s = 20.0;
    LoopOptions s = c;
    s.loop = LoopKind::kSampled;
    s.dt_s = 5e-4;
    const Plant plant = Custom({1.0}, {1.0, 0.5, 0.1}, delay);
    const PidGains g{0.8, 0.2, 0.9, 0.122};
    const Evaluation ec = EvaluateWith(plant, g, c, 0.4, 0.2), es = EvaluateWith(plant, g, s, 0.4, 0.2);
    const Evaluation e1 = EvaluateWith(plant, g, c, 1.0, 1.0);
    ASSERT_EQ(ec.y.size(), es.y.size());
    double worst = 0.0, moved = 0.0;
    for (std::size_t m = 0; m < ec.y.size(); ++m) {
      worst = std::max(worst, std::abs(ec.y[m] - es.y[m]));
      moved = std::max(moved, std::abs(ec.y[m] - e1.y[m]));
    }
    EXPECT_LT(worst, 1e-3) << "delay " << delay;
    std::printf("delay %g s: sampled (dt 5e-4) vs continuous 2-DOF loop, largest |dy| %.3g\n", delay, worst);
    EXPECT_GT(moved, 0.05) << "delay " << delay;
  }
}

}  // namespace
}  // namespace pidlab
