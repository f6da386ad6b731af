// Monte Carlo over plant parameters: seeded draws, a tiny spread, a spread
// that crosses a known stability boundary, order statistics.

#include "pidlab/analysis/monte_carlo.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::Distribution;
using pidlab::analysis::DrawPlants;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::analysis::MonteCarloOptions;
using pidlab::analysis::MonteCarloSummary;
using pidlab::analysis::RunMonteCarlo;
using pidlab::analysis::Summarize;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopOptions;

namespace pidlab {
namespace {

const Plant kDoubleIntegrator{"double_integrator", {{1.0}, {1.0, 0.0, 0.0}}};

MonteCarloSummary RunOrFail(const Plant& plant, const PidGains& g, const MonteCarloOptions& mc,
                            const StepperMotorParameters* stepper = nullptr) {
  MonteCarloSummary s;
  std::string error;
  EXPECT_TRUE(IsOk(RunMonteCarlo(plant, stepper, g, LoopOptions{}, mc, &s)));
  return s;
}

TEST(MonteCarlo, SameSeedGivesTheSameDrawsAndAnotherSeedOthers) {
  MonteCarloOptions mc;
  mc.samples = 20;
  const auto a = DrawPlants(kDoubleIntegrator, nullptr, mc), b = DrawPlants(kDoubleIntegrator, nullptr, mc);
  mc.seed = 2;
  const auto c = DrawPlants(kDoubleIntegrator, nullptr, mc);
  ASSERT_EQ(a.size(), 20u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].tf.num, b[i].tf.num);
    EXPECT_NE(a[i].tf.num, c[i].tf.num);
    EXPECT_EQ(a[i].tf.den, (std::vector<double>{1.0, 0.0, 0.0})) << "leading 1, zeros stay zero";
    EXPECT_LE(std::abs(a[i].tf.num[0] - 1.0), 0.1);
  }
}

TEST(MonteCarlo, TinySpreadGivesNearlyTheNominalValues) {
  const PidGains g{29.6558, 0.4977, 28.3216};
  Evaluation nominal;
  std::string error;
  ASSERT_TRUE(IsOk(Evaluate(kDoubleIntegrator, g, LoopOptions{}, EvaluateOptions{}, &nominal)));
  MonteCarloOptions mc;
  mc.samples = 10;
  mc.spread = 1e-7;
  const MonteCarloSummary s = RunOrFail(kDoubleIntegrator, g, mc);
  EXPECT_EQ(s.stable_fraction, 1.0);
  EXPECT_NEAR(s.iae.min, nominal.iae, 1e-5 * nominal.iae);
  EXPECT_NEAR(s.iae.max, nominal.iae, 1e-5 * nominal.iae);
  EXPECT_NEAR(s.overshoot_pct.median, nominal.step.overshoot_pct, 1e-4);
  LoopAnalysis a;
  ASSERT_TRUE(IsOk(AnalyzeLoop(kDoubleIntegrator, g, LoopOptions{}, LoopAnalysisOptions{}, &a)));
  EXPECT_NEAR(s.ms.median, a.ms, 1e-4 * a.ms);
}

TEST(MonteCarlo, SpreadAcrossTheRouthBoundaryGivesTheExpectedStableFraction) {
  // b/s^2 under kp = kd = 1, ki = 0.95: s^3 + b s^2 + b s + 0.95 b is stable
  // iff b > 0.95; b uniform in [0.8, 1.2] is stable with probability 0.625.
  MonteCarloOptions mc;
  mc.samples = 100;
  mc.spread = 0.2;
  const MonteCarloSummary s = RunOrFail(kDoubleIntegrator, {1.0, 0.95, 1.0}, mc);
  EXPECT_LT(s.stable_fraction, 1.0);
  EXPECT_NEAR(s.stable_fraction, 0.625, 0.12) << "binomial sd 0.048 for 100 draws";
  EXPECT_EQ(s.iae.count, s.stable);
  EXPECT_LE(s.iae.min, s.iae.median);
  EXPECT_LE(s.iae.median, s.iae.p95);
  EXPECT_LE(s.iae.p95, s.iae.max);
}

TEST(MonteCarlo, WithoutOvershootTheSameDrawsGiveTheSameStableFractionIaeAndMs) {
  MonteCarloOptions mc;
  mc.samples = 100;
  mc.spread = 0.2;
  const MonteCarloSummary with = RunOrFail(kDoubleIntegrator, {1.0, 0.95, 1.0}, mc);
  mc.overshoot = false;
  const MonteCarloSummary without = RunOrFail(kDoubleIntegrator, {1.0, 0.95, 1.0}, mc);
  EXPECT_EQ(without.stable, with.stable);
  EXPECT_EQ(without.iae.median, with.iae.median);
  EXPECT_EQ(without.ms.max, with.ms.max);
  EXPECT_GT(with.overshoot_pct.count, 0);
  EXPECT_EQ(without.overshoot_pct.count, 0);
}

TEST(MonteCarlo, StepperDrawsPerturbTableOneParameters) {
  Plant stepper;
  std::string error;
  const StepperMotorParameters p;
  ASSERT_TRUE(IsOk(MakePlant("stepper_motor", p, &stepper)));
  MonteCarloOptions mc;
  mc.samples = 30;
  const auto plants = DrawPlants(stepper, &p, mc);
  for (const Plant& d : plants) {
    ASSERT_FALSE(d.tf.den.empty()) << "10 % keeps every Table I parameter valid";
    EXPECT_NE(d.tf.num, stepper.tf.num);
    EXPECT_EQ(d.tf.den.size(), 4u);
  }
  const MonteCarloSummary s = RunOrFail(stepper, {0.93068, 0.75203, 0.74726}, mc, &p);
  EXPECT_EQ(s.perturbed, "Table I parameters");
  EXPECT_EQ(s.samples, 30);
  EXPECT_GT(s.stable, 0);
}

TEST(MonteCarlo, SummarizeGivesNearestRankPercentiles) {
  const Distribution odd = Summarize({5.0, 1.0, 4.0, 2.0, 3.0});
  EXPECT_EQ(odd.min, 1.0);
  EXPECT_EQ(odd.median, 3.0);
  EXPECT_EQ(odd.p95, 5.0);
  EXPECT_EQ(odd.max, 5.0);
  std::vector<double> many;
  for (int i = 1; i <= 100; ++i) many.push_back(i);
  EXPECT_EQ(Summarize(many).p95, 95.0);
  EXPECT_EQ(Summarize(many).median, 50.5);
  EXPECT_EQ(Summarize({}).count, 0);
}

TEST(MonteCarlo, RejectsASpreadOfOneAndZeroSamples) {
  MonteCarloOptions mc;
  std::string error;
  mc.spread = 1.0;
  EXPECT_FALSE(mc.IsValid(&error));
  EXPECT_NE(error.find("spread 1"), std::string::npos) << error;
  mc.spread = 0.1;
  mc.samples = 0;
  EXPECT_FALSE(mc.IsValid(&error));
  EXPECT_NE(error.find("samples 0"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
