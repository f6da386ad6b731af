// The 2-DOF PID's first-order setpoint filter (docs/two_dof.md,
// PidOptions::setpoint_filter_s): r_f = r / (tr s + 1) in r's place in all
// three terms. The discrete PID is the PID of the filtered setpoint; the
// exact continuous loops (ideal, filtered, with dead time) give the
// unfiltered response filtered; the sampled loop converges to them; the
// filter moves no pole, not the load response and not Ms.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/controller/pid.h"
#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;

namespace pidlab {
namespace {

Plant Custom(std::vector<double> num, std::vector<double> den, double delay_s = 0.0) {
  Plant p;
  p.name = "custom";
  p.tf = TransferFunction{std::move(num), std::move(den)};
  p.delay_s = delay_s;
  return p;
}

Evaluation EvaluateWith(const Plant& plant, const PidGains& g, LoopOptions o, double b, double c, double tr) {
  o.pid.setpoint_weight_b = b;
  o.pid.setpoint_weight_c = c;
  o.pid.setpoint_filter_s = tr;
  Evaluation ev;
  EXPECT_TRUE(IsOk(Evaluate(plant, g, o, EvaluateOptions{}, &ev)));
  return ev;
}

// x (samples h apart, from rest) through 1 / (tr s + 1), exact for x linear
// between samples: the reference the continuous loops are checked against.
std::vector<double> Filter(const std::vector<double>& x, double tr, double h) {
  std::vector<double> y(x.size(), 0.0);
  const double a = std::exp(-h / tr);
  for (std::size_t k = 1; k < x.size(); ++k) {
    const double slope = (x[k] - x[k - 1]) / h;
    y[k] = x[k] - tr * slope + (y[k - 1] - x[k - 1] + tr * slope) * a;
  }
  return y;
}

TEST(SetpointFilter, TheFilteredPidIsThePidOfTheFilteredSetpointBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> r_dist(-2.0, 2.0), y_dist(-1.5, 1.5);
  PidOptions with;
  with.dt_s = 0.01;
  with.derivative_filter_s = 0.05;
  with.output_min = -3.0;
  with.output_max = 3.0;
  with.setpoint_weight_b = 0.6;
  with.setpoint_weight_c = 0.3;
  with.setpoint_filter_s = 0.4;
  PidOptions without = with;
  without.setpoint_filter_s = 0.0;
  const PidGains g{2.0, 1.5, 0.3, 0.0};
  DiscretePid<double> filtered(g, with), plain(g, without);
  double f = 0.0;  // the filter, by its definition in pid.h
  int saturated = 0;
  for (int k = 0; k < 5000; ++k) {
    const double r = k % 700 < 350 ? r_dist(rng) : 1.0, y = y_dist(rng);
    f = f + with.dt_s / (with.setpoint_filter_s + with.dt_s) * (r - f);
    double u1 = 0.0, u2 = 0.0;
    const PidStatus s1 = filtered.Step(r, y, &u1), s2 = plain.Step(f, y, &u2);
    ASSERT_EQ(u1, u2) << "k " << k;
    ASSERT_EQ(s1, s2);
    saturated += s1 == PidStatus::kSaturated;
  }
  EXPECT_GT(saturated, 100);  // the clamping path ran too
  filtered.Reset();
  double u = 0.0;
  filtered.Step(1.0, 0.0, &u);
  EXPECT_DOUBLE_EQ(
      u, g.kp * (0.6 * 0.01 / 0.41) + g.ki * 0.01 * (0.01 / 0.41) + g.kd * 0.3 * (0.01 / 0.41) / 0.06);
}

TEST(SetpointFilter, ANegativeOrNotFiniteTimeConstantIsRefusedInOneLine) {
  for (const double tr : {-1.0, std::nan(""), HUGE_VAL}) {
    PidOptions o;
    o.setpoint_filter_s = tr;
    std::string error;
    EXPECT_FALSE(o.IsValid(&error));
    EXPECT_NE(error.find("setpoint filter"), std::string::npos) << error;
  }
}

// The continuous loop is linear and time invariant, so filtering r is
// filtering the response: each loop against its unfiltered response filtered.
TEST(SetpointFilter, TheContinuousLoopsGiveTheUnfilteredResponseFiltered) {
  struct Case {
    const char* name;
    Plant plant;
    PidGains g;
  };
  const std::vector<Case> cases = {
      {"ideal PID", Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3, 0.0}},
      {"filtered PID", Custom({1.0}, {1.0, 0.5, 0.1}), {1.12, 0.23, 1.3, 0.122}},
      {"dead time", Custom({1.0}, {1.0, 0.5, 0.1}, 0.3), {0.6, 0.12, 0.6, 0.1}},
  };
  for (const Case& c : cases) {
    LoopOptions o;
    o.sample_time_s = 0.001;
    o.horizon_s = 40.0;
    const double tr = 1.7;
    const Evaluation unfiltered = EvaluateWith(c.plant, c.g, o, 0.5, 0.8, 0.0);
    const Evaluation filtered = EvaluateWith(c.plant, c.g, o, 0.5, 0.8, tr);
    ASSERT_TRUE(filtered.stability.stable) << c.name;
    const std::vector<double> expected = Filter(unfiltered.y, tr, o.sample_time_s);
    double worst = 0.0;
    for (std::size_t m = 0; m < expected.size(); ++m)
      worst = std::max(worst, std::abs(filtered.y[m] - expected[m]));
    EXPECT_LT(worst, 2e-6) << c.name;
    std::printf("%s: filtered loop vs the unfiltered response filtered, largest |dy| %.3g\n", c.name, worst);
    EXPECT_NEAR(filtered.step.final_value, 1.0, 1e-9) << c.name;
    EXPECT_LE(filtered.step.overshoot_pct, unfiltered.step.overshoot_pct) << c.name;
    EXPECT_GT(filtered.step.rise_time_s, unfiltered.step.rise_time_s) << c.name;
  }
}

TEST(SetpointFilter, TheFilterMovesNoPoleNotTheLoadResponseAndNotMs) {
  for (const double delay : {0.0, 0.3}) {
    const Plant plant = Custom({1.0}, {1.0, 0.5, 0.1}, delay);
    const PidGains g{0.6, 0.12, 0.6, 0.1};
    LoopOptions o;
    o.sample_time_s = 0.1;
    o.horizon_s = 40.0;
    const Evaluation one = EvaluateWith(plant, g, o, 1.0, 1.0, 0.0);
    const Evaluation two = EvaluateWith(plant, g, o, 1.0, 1.0, 2.5);
    LoopOptions of = o;
    of.pid.setpoint_filter_s = 2.5;
    LoopAnalysis a1, a2;
    ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, o, LoopAnalysisOptions{}, &a1)));
    ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, of, LoopAnalysisOptions{}, &a2)));
    EXPECT_EQ(two.load_iae, one.load_iae) << delay;
    EXPECT_EQ(a2.ms, a1.ms);
    EXPECT_EQ(a2.mt, a1.mt);
    EXPECT_EQ(a2.phase_margin_deg, a1.phase_margin_deg);
    EXPECT_GT(two.iae, one.iae + 0.1) << delay;  // the setpoint response did move
  }
}

// The sampled PID's backward-Euler filter converges to the continuous one.
TEST(SetpointFilter, TheSampledLoopApproachesTheContinuousLoopWithTheSameFilter) {
  for (const double delay : {0.0, 0.3}) {
    LoopOptions c;
    c.sample_time_s = 0.1;
    c.horizon_s = 20.0;
    LoopOptions s = c;
    s.loop = LoopKind::kSampled;
    s.dt_s = 5e-4;
    const Plant plant = Custom({1.0}, {1.0, 0.5, 0.1}, delay);
    const PidGains g{0.8, 0.2, 0.9, 0.122};
    const Evaluation ec = EvaluateWith(plant, g, c, 0.4, 0.2, 0.8);
    const Evaluation es = EvaluateWith(plant, g, s, 0.4, 0.2, 0.8);
    ASSERT_EQ(ec.y.size(), es.y.size());
    double worst = 0.0;
    for (std::size_t m = 0; m < ec.y.size(); ++m) worst = std::max(worst, std::abs(ec.y[m] - es.y[m]));
    EXPECT_LT(worst, 1e-3) << "delay " << delay;
    std::printf("delay %g s: sampled (dt 5e-4) vs continuous loop with tr 0.8 s, largest |dy| %.3g\n", delay,
                worst);
  }
}

}  // namespace
}  // namespace pidlab
