// SIMC and AMIGO: the published figures for K = 1, T = L = 1, the half rule
// worked by hand on two plants, the series-to-parallel conversion, the
// integrating variants, the plants the rules refuse, and Tune() with them.

#include "pidlab/tune/tuning_rules.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "pidlab/plant_sim/polynomial.h"
#include "pidlab/tune/tune.h"
#include "test_status.h"

using pidlab::tune::AmigoTune;
using pidlab::tune::ApplyTuningRule;
using pidlab::tune::ProcessModel;
using pidlab::tune::ProcessModelKind;
using pidlab::tune::ReduceModel;
using pidlab::tune::RuleForm;
using pidlab::tune::SeriesToParallel;
using pidlab::tune::SimcTune;
using pidlab::tune::Tune;
using pidlab::tune::TuneMethod;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;
using pidlab::tune::TuningRule;
using pidlab::tune::TuningRuleResult;

namespace pidlab {
namespace {

constexpr double kTol = 1e-9;

Plant MakePlantOrDie(const std::vector<double>& num, const std::vector<double>& den, double delay_s) {
  Plant p;
  std::string error;
  EXPECT_TRUE(IsOk(MakeCustomPlant(num, den, &p)));
  p.delay_s = delay_s;
  return p;
}

TuningRuleResult RuleOrDie(const Plant& plant, TuningRule rule, RuleForm form) {
  TuningRuleResult r;
  const Status s = ApplyTuningRule(plant, rule, form, &r);
  EXPECT_TRUE(s.ok()) << s.message();
  return r;
}

// K = 1, T = L = 1: e^(-s) / (s + 1).
Plant UnitFopdt() { return MakePlantOrDie({1.0}, {1.0, 1.0}, 1.0); }

TEST(TuningRules, AmigoPiOnTheUnitFopdtGivesKQuarterAndTiOne) {
  const TuningRuleResult dut = RuleOrDie(UnitFopdt(), TuningRule::kAmigo, RuleForm::kPi);
  EXPECT_NEAR(dut.kc, 0.25, kTol);
  EXPECT_NEAR(dut.ti_s, 1.0, kTol);
  EXPECT_EQ(dut.td_s, 0.0);
  EXPECT_NEAR(dut.gains.kp, 0.25, kTol);
  EXPECT_NEAR(dut.gains.ki, 0.25, kTol);
  EXPECT_EQ(dut.gains.kd, 0.0);
  EXPECT_EQ(dut.model.kind, ProcessModelKind::kFopdt);
  EXPECT_FALSE(dut.model.half_rule);
}

TEST(TuningRules, AmigoPidOnTheUnitFopdtGivesThePublishedFigures) {
  const TuningRuleResult dut = RuleOrDie(UnitFopdt(), TuningRule::kAmigo, RuleForm::kPid);
  EXPECT_NEAR(dut.kc, 0.65, kTol);
  EXPECT_NEAR(dut.ti_s, 12.0 / 11.0, kTol);  // 1.0909
  EXPECT_NEAR(dut.td_s, 5.0 / 13.0, kTol);   // 0.3846
  EXPECT_NEAR(dut.ti_s, 1.0909, 5e-5);
  EXPECT_NEAR(dut.td_s, 0.3846, 5e-5);
  // Parallel (ideal) form: kp = K, ki = K/Ti, kd = K Td.
  EXPECT_NEAR(dut.gains.kp, 0.65, kTol);
  EXPECT_NEAR(dut.gains.ki, 0.65 * 11.0 / 12.0, kTol);
  EXPECT_NEAR(dut.gains.kd, 0.65 * 5.0 / 13.0, kTol);
  EXPECT_EQ(dut.controller_form, "parallel");
}

TEST(TuningRules, SimcPiOnTheUnitFopdtGivesKcHalfAndTauIOne) {
  const TuningRuleResult dut = RuleOrDie(UnitFopdt(), TuningRule::kSimc, RuleForm::kPi);
  EXPECT_NEAR(dut.kc, 0.5, kTol);
  EXPECT_NEAR(dut.ti_s, 1.0, kTol);  // min(T = 1, 4 (tau_c + theta) = 8)
  EXPECT_NEAR(dut.gains.kp, 0.5, kTol);
  EXPECT_NEAR(dut.gains.ki, 0.5, kTol);
  EXPECT_EQ(dut.gains.kd, 0.0);
}

TEST(TuningRules, SimcPidOnAnFopdtHasNoDerivative) {
  const TuningRuleResult dut = RuleOrDie(UnitFopdt(), TuningRule::kSimc, RuleForm::kPid);
  EXPECT_EQ(dut.model.kind, ProcessModelKind::kFopdt);
  EXPECT_EQ(dut.td_s, 0.0);
  EXPECT_NEAR(dut.gains.kp, 0.5, kTol);
  EXPECT_EQ(dut.gains.kd, 0.0);
}

TEST(TuningRules, SimcIntegralTimeIsCappedAtFourTimesTauCPlusTheta) {
  // T = 20, L = 1, K = 2: Kc = 20 / (2 * 2) = 5, tau_I = min(20, 8) = 8.
  const TuningRuleResult dut =
      RuleOrDie(MakePlantOrDie({2.0}, {20.0, 1.0}, 1.0), TuningRule::kSimc, RuleForm::kPi);
  EXPECT_NEAR(dut.kc, 5.0, kTol);
  EXPECT_NEAR(dut.ti_s, 8.0, kTol);
}

// (-0.3 s + 1) e^(-0.5 s) / ((2 s + 1)(s + 1)(0.4 s + 1)), worked by hand:
// FOPDT: T = 2 + 1/2 = 2.5, L = 0.5 + 1/2 + 0.4 + 0.3 = 1.7;
// SOPDT: T1 = 2, T2 = 1 + 0.4/2 = 1.2, L = 0.5 + 0.4/2 + 0.3 = 1.0.
Plant InverseResponsePlant() { return MakePlantOrDie({-0.3, 1.0}, LagProduct({2.0, 1.0, 0.4}), 0.5); }

TEST(TuningRules, HalfRuleReducesAnInverseResponsePlantToFopdt) {
  ProcessModel dut;
  ASSERT_TRUE(ReduceModel(InverseResponsePlant(), TuningRule::kAmigo, RuleForm::kPi, &dut).ok());
  EXPECT_EQ(dut.kind, ProcessModelKind::kFopdt);
  EXPECT_NEAR(dut.gain, 1.0, 1e-9);
  ASSERT_EQ(dut.time_constants.size(), 1u);
  EXPECT_NEAR(dut.time_constants[0], 2.5, 1e-9);
  EXPECT_NEAR(dut.delay_s, 1.7, 1e-9);
  EXPECT_TRUE(dut.half_rule);
}

TEST(TuningRules, HalfRuleReducesAnInverseResponsePlantToSopdtForSimcPid) {
  ProcessModel dut;
  ASSERT_TRUE(ReduceModel(InverseResponsePlant(), TuningRule::kSimc, RuleForm::kPid, &dut).ok());
  EXPECT_EQ(dut.kind, ProcessModelKind::kSopdt);
  ASSERT_EQ(dut.time_constants.size(), 2u);
  EXPECT_NEAR(dut.time_constants[0], 2.0, 1e-9);
  EXPECT_NEAR(dut.time_constants[1], 1.2, 1e-9);
  EXPECT_NEAR(dut.delay_s, 1.0, 1e-9);
  // SIMC PID: Kc = T1 / (K 2 theta) = 1, tau_I = min(2, 8) = 2, tau_D = T2 = 1.2,
  // parallel: kp = 1 (1 + 1.2/2) = 1.6, ki = 0.5, kd = 1.2.
  TuningRuleResult r;
  ASSERT_TRUE(SimcTune(dut, RuleForm::kPid, &r).ok());
  EXPECT_NEAR(r.kc, 1.0, 1e-9);
  EXPECT_NEAR(r.ti_s, 2.0, 1e-9);
  EXPECT_NEAR(r.td_s, 1.2, 1e-9);
  EXPECT_NEAR(r.gains.kp, 1.6, 1e-9);
  EXPECT_NEAR(r.gains.ki, 0.5, 1e-9);
  EXPECT_NEAR(r.gains.kd, 1.2, 1e-9);
}

// 1 / ((s + 1)(0.2 s + 1)(0.04 s + 1)(0.008 s + 1)), no delay, by hand:
// FOPDT: T = 1 + 0.1 = 1.1, L = 0.1 + 0.04 + 0.008 = 0.148;
// SOPDT: T1 = 1, T2 = 0.2 + 0.02 = 0.22, L = 0.02 + 0.008 = 0.028.
TEST(TuningRules, HalfRuleSplitsOnlyTheLargestNeglectedLag) {
  const Plant plant = MakePlantOrDie({1.0}, LagProduct({1.0, 0.2, 0.04, 0.008}), 0.0);
  ProcessModel fopdt, sopdt;
  ASSERT_TRUE(ReduceModel(plant, TuningRule::kSimc, RuleForm::kPi, &fopdt).ok());
  ASSERT_TRUE(ReduceModel(plant, TuningRule::kSimc, RuleForm::kPid, &sopdt).ok());
  EXPECT_NEAR(fopdt.time_constants.at(0), 1.1, 1e-9);
  EXPECT_NEAR(fopdt.delay_s, 0.148, 1e-9);
  EXPECT_NEAR(sopdt.time_constants.at(0), 1.0, 1e-9);
  EXPECT_NEAR(sopdt.time_constants.at(1), 0.22, 1e-9);
  EXPECT_NEAR(sopdt.delay_s, 0.028, 1e-9);
}

TEST(TuningRules, ARepeatedRealPoleIsReal) {
  // (s + 1)^3: FOPDT T = 1.5, L = 1.5.
  ProcessModel dut;
  ASSERT_TRUE(ReduceModel(MakePlantOrDie({1.0}, LagProduct({1.0, 1.0, 1.0}), 0.0), TuningRule::kAmigo,
                          RuleForm::kPid, &dut)
                  .ok());
  EXPECT_NEAR(dut.time_constants.at(0), 1.5, 1e-4);
  EXPECT_NEAR(dut.delay_s, 1.5, 1e-4);
}

TEST(TuningRules, AnExactSopdtIsUsedAsItIsBySimcPid) {
  ProcessModel dut;
  ASSERT_TRUE(ReduceModel(MakePlantOrDie({3.0}, LagProduct({4.0, 0.5}), 0.25), TuningRule::kSimc,
                          RuleForm::kPid, &dut)
                  .ok());
  EXPECT_EQ(dut.kind, ProcessModelKind::kSopdt);
  EXPECT_FALSE(dut.half_rule);
  EXPECT_NEAR(dut.gain, 3.0, 1e-12);
  EXPECT_NEAR(dut.time_constants.at(0), 4.0, 1e-9);
  EXPECT_NEAR(dut.time_constants.at(1), 0.5, 1e-9);
  EXPECT_EQ(dut.delay_s, 0.25);
}

TEST(TuningRules, SeriesToParallelIsTheSameController) {
  const double kc = 2.0, ti = 4.0, td = 0.5;
  const PidGains dut = SeriesToParallel(kc, ti, td);
  EXPECT_NEAR(dut.kp, 2.25, 1e-12);
  EXPECT_NEAR(dut.ki, 0.5, 1e-12);
  EXPECT_NEAR(dut.kd, 1.0, 1e-12);
  for (double w : {0.01, 0.3, 1.0, 7.0, 100.0}) {
    const std::complex<double> s(0.0, w);
    const std::complex<double> series = kc * (1.0 + 1.0 / (ti * s)) * (td * s + 1.0);
    const std::complex<double> parallel = dut.kp + dut.ki / s + dut.kd * s;
    EXPECT_NEAR(std::abs(series - parallel), 0.0, 1e-12 * std::abs(series)) << "w = " << w;
  }
}

TEST(TuningRules, IntegratingPlusDeadTimeUsesTheIntegratingRules) {
  const Plant plant = MakePlantOrDie({2.0}, {1.0, 0.0}, 0.5);  // K' = 2, L = 0.5
  const TuningRuleResult simc = RuleOrDie(plant, TuningRule::kSimc, RuleForm::kPi);
  EXPECT_EQ(simc.model.kind, ProcessModelKind::kIntegrating);
  EXPECT_NEAR(simc.kc, 1.0 / (2.0 * 1.0), kTol);  // 1 / (K' (tau_c + theta))
  EXPECT_NEAR(simc.ti_s, 4.0, kTol);              // 4 (tau_c + theta)
  const TuningRuleResult amigo_pi = RuleOrDie(plant, TuningRule::kAmigo, RuleForm::kPi);
  EXPECT_NEAR(amigo_pi.kc, 0.35 / (2.0 * 0.5), kTol);
  EXPECT_NEAR(amigo_pi.ti_s, 13.4 * 0.5, kTol);
  const TuningRuleResult amigo_pid = RuleOrDie(plant, TuningRule::kAmigo, RuleForm::kPid);
  EXPECT_NEAR(amigo_pid.kc, 0.45 / (2.0 * 0.5), kTol);
  EXPECT_NEAR(amigo_pid.ti_s, 8.0 * 0.5, kTol);
  EXPECT_NEAR(amigo_pid.td_s, 0.5 * 0.5, kTol);
}

TEST(TuningRules, SimcPidOnAnIntegratorWithALagPutsTheLagInTauD) {
  // 1 / (s (s + 1)(0.2 s + 1)), no delay: T2 = 1 + 0.1, theta = 0.1.
  const Plant plant = MakePlantOrDie({1.0}, PolynomialProduct({1.0, 0.0}, LagProduct({1.0, 0.2})), 0.0);
  const TuningRuleResult dut = RuleOrDie(plant, TuningRule::kSimc, RuleForm::kPid);
  EXPECT_EQ(dut.model.kind, ProcessModelKind::kIntegrating);
  EXPECT_NEAR(dut.model.time_constants.at(0), 1.1, 1e-9);
  EXPECT_NEAR(dut.model.delay_s, 0.1, 1e-9);
  EXPECT_NEAR(dut.kc, 1.0 / 0.2, 1e-9);
  EXPECT_NEAR(dut.ti_s, 0.8, 1e-9);
  EXPECT_NEAR(dut.td_s, 1.1, 1e-9);
  // AMIGO and SIMC's PI neglect the lag: theta = 1/2 + 0.2.
  const TuningRuleResult pi = RuleOrDie(plant, TuningRule::kSimc, RuleForm::kPi);
  EXPECT_TRUE(pi.model.time_constants.empty());
  EXPECT_NEAR(pi.model.delay_s, 0.7, 1e-9);
}

void ExpectRefused(const Plant& plant, TuningRule rule, RuleForm form, const std::string& why) {
  TuningRuleResult r;
  const Status dut = ApplyTuningRule(plant, rule, form, &r);
  EXPECT_EQ(dut.code(), StatusCode::kInvalidInput);
  EXPECT_NE(dut.message().find(why), std::string::npos) << dut.message();
  EXPECT_EQ(dut.message().find('\n'), std::string::npos) << dut.message();
}

TEST(TuningRules, TheOscillatorIsRefusedForItsComplexPoles) {
  Plant oscillator;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("oscillator", StepperMotorParameters{}, &oscillator)));
  ExpectRefused(oscillator, TuningRule::kSimc, RuleForm::kPid, "complex poles");
  ExpectRefused(oscillator, TuningRule::kAmigo, RuleForm::kPi, "complex poles");
}

TEST(TuningRules, AnUnstablePlantIsRefused) {
  ExpectRefused(MakePlantOrDie({1.0}, {1.0, -1.0}, 1.0), TuningRule::kSimc, RuleForm::kPi, "unstable pole");
}

TEST(TuningRules, TheDoubleIntegratorIsRefused) {
  ExpectRefused(MakePlantOrDie({1.0}, {1.0, 0.0, 0.0}, 1.0), TuningRule::kAmigo, RuleForm::kPid,
                "2 poles at s = 0");
}

TEST(TuningRules, ALeftHalfPlaneZeroIsRefused) {
  ExpectRefused(MakePlantOrDie({1.0, 2.0}, LagProduct({1.0, 0.5, 0.1}), 0.1), TuningRule::kSimc,
                RuleForm::kPid, "(a lead)");
}

TEST(TuningRules, ANegativeGainIsRefused) {
  ExpectRefused(MakePlantOrDie({-1.0}, {1.0, 1.0}, 1.0), TuningRule::kAmigo, RuleForm::kPi, "positive gain");
}

TEST(TuningRules, AModelWithoutDeadTimeIsRefused) {
  ExpectRefused(MakePlantOrDie({1.0}, {1.0, 1.0}, 0.0), TuningRule::kSimc, RuleForm::kPi,
                "needs a dead time");
  ExpectRefused(MakePlantOrDie({1.0}, {1.0, 1.0}, 0.0), TuningRule::kAmigo, RuleForm::kPid,
                "needs a dead time");
  ExpectRefused(MakePlantOrDie({1.0}, LagProduct({1.0, 0.2}), 0.0), TuningRule::kSimc, RuleForm::kPid,
                "needs a dead time");
}

TEST(TuningRules, TuneEvaluatesTheRulesGainsOnceWithoutCeres) {
  // 1 / ((s + 1)(0.2 s + 1)): SIMC PI on T = 1.1, theta = 0.1: Kc = 5.5, tau_I = 0.8.
  const Plant plant = MakePlantOrDie({1.0}, LagProduct({1.0, 0.2}), 0.0);
  TuneOptions o;
  o.method = TuneMethod::kSimc;
  o.rule = RuleForm::kPi;
  TuneSummary dut;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(plant, o, &dut)));
  EXPECT_TRUE(dut.stable);
  EXPECT_EQ(dut.evaluations, 1);
  EXPECT_FALSE(dut.refine.ran);
  EXPECT_NEAR(dut.gains.kp, 5.5, 1e-9);
  EXPECT_NEAR(dut.gains.ki, 5.5 / 0.8, 1e-9);
  EXPECT_EQ(dut.gains.kd, 0.0);
  EXPECT_TRUE(std::isfinite(dut.objective));
  EXPECT_TRUE(dut.tuning_rule.model.half_rule);
  EXPECT_NEAR(dut.tuning_rule.model.delay_s, 0.1, 1e-9);
}

TEST(TuningRules, TuneScoresARuleOnADelayedPlantInBothLoops) {
  TuneOptions o;
  o.method = TuneMethod::kAmigo;
  TuneSummary dut;
  std::string error;
  // Continuous: the method of steps; the rule's ideal derivative on this plant
  // of relative degree 1 would make the loop neutral, so it needs a filter.
  EXPECT_FALSE(OkInto(Tune(UnitFopdt(), o, &dut), &error));
  EXPECT_NE(error.find("derivative filter"), std::string::npos) << error;
  o.loop.derivative_filter_ratio = 10.0;
  ASSERT_TRUE(IsOk(Tune(UnitFopdt(), o, &dut)));
  EXPECT_NEAR(dut.gains.kp, 0.65, 1e-9);
  EXPECT_TRUE(std::isfinite(dut.objective));
  EXPECT_EQ(dut.tuning_rule.plant_delay_s, 1.0);
  o.loop.derivative_filter_ratio = 0.0;
  o.loop.loop = evaluation::LoopKind::kSampled;
  o.loop.dt_s = 0.01;
  // The stored inputs add closed-loop poles whose s-plane images the tuner's
  // default relative margin (0.01) rejects (docs/deadtime.md).
  o.loop.stability_margin = 1e-4;
  ASSERT_TRUE(IsOk(Tune(UnitFopdt(), o, &dut)));
  EXPECT_NEAR(dut.gains.kp, 0.65, 1e-9);
  EXPECT_TRUE(std::isfinite(dut.objective));
  EXPECT_EQ(dut.tuning_rule.plant_delay_s, 1.0);
}

TEST(TuningRules, TuneRefusesTheOscillatorWithOneLine) {
  Plant oscillator;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("oscillator", StepperMotorParameters{}, &oscillator)));
  TuneOptions o;
  o.method = TuneMethod::kSimc;
  TuneSummary dut;
  EXPECT_FALSE(OkInto(Tune(oscillator, o, &dut), &error));
  EXPECT_NE(error.find("complex poles"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
