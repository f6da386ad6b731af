// The sampled loop with a plant dead time G(s) e^(-sL) (docs/deadtime.md, "In
// every loop"): the loop runs the plant's exact delayed step, its stability
// gate sees the stored inputs, and what is not supported yet is refused; the
// continuous loop with dead time is evaluated (tests/delayed_continuous_test.cc).

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::evaluation::DelayIsValid;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::kMaxAnalysedDelaySteps;
using pidlab::evaluation::LoadIntegralAbsError;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::RunSampledLoop;
using pidlab::evaluation::SampledPlant;
using pidlab::evaluation::SampledStability;
using pidlab::evaluation::SampledStep;

namespace pidlab {
namespace {

// 1/(s+1) e^(-sL): the first-order plant with dead time.
Plant Fopdt(double delay_s) {
  Plant p;
  p.name = "custom";
  p.tf = TransferFunction{{1.0}, {1.0, 1.0}};
  p.delay_s = delay_s;
  return p;
}

LoopOptions Sampled(double dt_s) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = dt_s;
  o.sample_time_s = 0.05;
  o.horizon_s = 10.0;
  return o;
}

bool StableUnderP(const Plant& plant, double kp, double dt_s) {
  const LoopOptions o = Sampled(dt_s);
  return SampledStability(SampledPlant(plant, dt_s), PidGains{kp, 0.0, 0.0}, o.Pid(), 0.0).stable;
}

// The sampled loop's ultimate gain under P control, by bisection on the
// stability gate: stable at lo, unstable at hi.
double SampledUltimateGain(const Plant& plant, double dt_s, double lo, double hi) {
  EXPECT_TRUE(StableUnderP(plant, lo, dt_s));
  EXPECT_FALSE(StableUnderP(plant, hi, dt_s));
  while (hi - lo > 1e-5) {
    const double mid = 0.5 * (lo + hi);
    (StableUnderP(plant, mid, dt_s) ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The continuous loop's ultimate gain for e^(-s)/(s+1): Ku = sqrt(1 + w^2)
// with atan(w) + w = pi (w = 2.02876).
constexpr double kUltimateGainOneSecond = 2.2618263341146516;
// The same for e^(-0.3 s)/(s+1): atan(w) + 0.3 w = pi, w = 5.80466.
constexpr double kUltimateGainThreeTenths = 5.8901652376171105;

TEST(DelayedSampledStability, UltimateGainApproachesTheContinuousLoopsAsDtShrinks) {
  // Independently: with L = d dt the loop's characteristic polynomial is
  // z^(d+1) - e^(-dt) z^d + kp (1 - e^(-dt)); its largest root reaches 1 at
  // kp = 2.254203 (dt = 0.01 s, d = 100) and 2.258018 (dt = 0.005 s, d = 200)
  // (numpy.roots and bisection).
  const Plant plant = Fopdt(1.0);
  const double coarse = SampledUltimateGain(plant, 0.01, 2.0, 2.5);
  const double fine = SampledUltimateGain(plant, 0.005, 2.0, 2.5);
  EXPECT_NEAR(coarse, 2.254203, 2e-5);
  EXPECT_NEAR(fine, 2.258018, 2e-5);
  EXPECT_LT(fine, kUltimateGainOneSecond);
  EXPECT_LT(kUltimateGainOneSecond - fine, kUltimateGainOneSecond - coarse) << "closer as dt shrinks";
  EXPECT_NEAR(fine, kUltimateGainOneSecond, 5e-3);
}

TEST(DelayedSampledStability, FirstOrderLagWithThreeTenthsDelayTurnsUnstableAtTheContinuousUltimateGain) {
  const Plant plant = Fopdt(0.3);
  EXPECT_TRUE(StableUnderP(plant, 0.97 * kUltimateGainThreeTenths, 0.01));
  EXPECT_FALSE(StableUnderP(plant, 1.03 * kUltimateGainThreeTenths, 0.01));
  EXPECT_TRUE(StableUnderP(Fopdt(0.0), 1.03 * kUltimateGainThreeTenths, 0.01))
      << "without the delay the same gain is far from the sampled loop's limit";
}

TEST(DelayedSampledStability, LoopMatrixHoldsTheStoredInputs) {
  const LoopOptions o = Sampled(0.01);
  const auto undelayed = SampledStability(SampledPlant(Fopdt(0.0), 0.01), {1.0, 0.5, 0.0}, o.Pid(), 0.0);
  const auto delayed = SampledStability(SampledPlant(Fopdt(0.123), 0.01), {1.0, 0.5, 0.0}, o.Pid(), 0.0);
  // n + d + 4: 1 + 0 + 4 and 1 + 13 + 4.
  EXPECT_EQ(undelayed.poles.size(), 5u);
  EXPECT_EQ(delayed.poles.size(), 18u);
}

// How far the eigenvalue verdict is from turning: the smallest slack of the
// criterion Re p < -m max(1, min(|p|, pi / L)) over the poles, relative to
// max(1, |p|). Loops within rounding of the boundary are not compared.
double SmallestSlack(const pidlab::evaluation::Stability& s, double dt, double margin, double delay) {
  const double cap = pidlab::evaluation::DelayedMarginModulus(delay);
  double slack = std::numeric_limits<double>::infinity();
  for (const auto& z : s.poles) {
    if (std::abs(z) == 0.0) continue;
    const std::complex<double> p = std::log(z) / dt;
    const double c = p.real() + margin * std::max(1.0, std::min(std::abs(p), cap));
    slack = std::min(slack, std::abs(c) / std::max(1.0, std::abs(p)));
  }
  return slack;
}

TEST(DelayedSampledStability, CountOnTheMarginsContourAgreesWithTheEigenvaluesOnRandomLoops) {
  // Plants with lags, an integrator, a right-half-plane zero, a lightly damped
  // pair, poles on the imaginary axis and a double integrator; random gains,
  // filters, integral methods, margins, dt and delays of 24 to 400 stored
  // inputs (the split fraction random too).
  const std::vector<TransferFunction> plants = {
      {{1.0}, {1.0, 1.0}},      {{1.0}, {1.0, 2.0, 1.0}},       {{1.0}, {1.0, 1.0, 0.0}},
      {{1.0}, {1.0, 0.4, 1.0}}, {{-0.5, 1.0}, {2.0, 3.0, 1.0}}, {{1.0}, {1.0, 0.0, 1.0}},
      {{1.0}, {1.0, 0.0, 0.0}}, {{2.0}, {1.0, 3.0, 3.0, 1.0}}};
  const double dts[] = {1e-3, 4e-3, 0.01, 0.02};
  const double margins[] = {1e-9, 0.01, 0.1};
  const pidlab::IntegralMethod methods[] = {pidlab::IntegralMethod::kBackwardEuler,
                                            pidlab::IntegralMethod::kForwardEuler,
                                            pidlab::IntegralMethod::kTrapezoidal};
  std::mt19937_64 rng(20261124);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto log_uniform = [&](double lo, double hi) { return lo * std::pow(hi / lo, unit(rng)); };
  int stable = 0, unstable = 0, compared = 0, decided = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Plant plant;
    plant.name = "custom";
    plant.tf = plants[trial % plants.size()];
    const double dt = dts[rng() % 4];
    const long d =
        (trial % 20 == 0) ? 300 + static_cast<long>(rng() % 101) : 24 + static_cast<long>(rng() % 130);
    plant.delay_s = (static_cast<double>(d) - unit(rng)) * dt;
    const double margin = margins[rng() % 3];
    LoopOptions o = Sampled(dt);
    PidOptions pid = o.Pid();
    pid.integral = methods[rng() % 3];
    const double scale = 1.0 / std::max(plant.delay_s, 0.05);
    PidGains g{log_uniform(0.01, 2.0) * scale, unit(rng) < 0.3 ? 0.0 : log_uniform(0.001, 1.0) * scale,
               unit(rng) < 0.4 ? 0.0 : log_uniform(0.001, 0.5) * scale};
    if (g.kd > 0.0 && unit(rng) < 0.7) g.tf = log_uniform(dt, 20.0 * dt);
    const pidlab::DiscretePlant discrete = SampledPlant(plant, dt);
    ASSERT_EQ(discrete.delay_steps(), d) << "trial " << trial;
    const auto eig = SampledStability(discrete, g, pid, margin);
    const auto counted = pidlab::evaluation::CountedSampledStability(discrete, g, pid, margin);
    decided += counted ? 1 : 0;
    EXPECT_EQ(pidlab::evaluation::SampledLoopIsStable(discrete, g, pid, margin), eig.stable)
        << "trial " << trial;
    if (!counted || SmallestSlack(eig, dt, margin, plant.delay_s) < 1e-6) continue;
    ++compared;
    (eig.stable ? stable : unstable) += 1;
    EXPECT_EQ(*counted, eig.stable) << "trial " << trial << ": plant " << trial % plants.size() << ", dt "
                                    << dt << ", d " << d << ", margin " << margin << ", gains " << g.kp << " "
                                    << g.ki << " " << g.kd << " tf " << g.tf;
  }
  std::cout << "count decided " << decided << " of 400 loops; compared " << compared << ": " << stable
            << " stable, " << unstable << " unstable\n";
  EXPECT_GE(decided, 390) << "the count decides nearly every loop itself";
  EXPECT_GE(compared, 380);
  EXPECT_GE(stable, 60) << "both verdicts are exercised";
  EXPECT_GE(unstable, 60);
}

TEST(DelayedSampledLoop, RunsThePlantsOwnDelayedStepBitForBit) {
  // The in-process loop's y_k against DiscretePlant::Step driven by the
  // loop's own u_k + n_k: what the plant process does.
  for (const double delay : {0.0, 0.0123, 0.3, 0.05}) {
    SCOPED_TRACE(delay);
    const Plant plant = Fopdt(delay);
    LoopOptions o = Sampled(0.01);
    o.disturbance.kind = DisturbanceKind::kSine;
    o.disturbance.amplitude = 0.2;
    const DiscretePlant discrete = SampledPlant(plant, o.dt_s);
    std::vector<double> y;
    std::vector<SampledStep> steps;
    RunSampledLoop<double>(discrete, PidGains{1.5, 1.0, 0.1}, o.Pid(), Disturbance(o.disturbance),
                           o.TotalSteps(), 1, &y, &steps);
    DiscretePlant dut(plant.tf, o.dt_s, delay);
    ASSERT_EQ(steps.size() + 1, y.size());
    long differ = 0;
    for (const SampledStep& st : steps) {
      if (!(dut.Output() == y[static_cast<std::size_t>(st.k)])) ++differ;
      dut.Step(st.u + st.n);
    }
    EXPECT_EQ(differ, 0);
  }
}

TEST(DelayedSampledLoop, OutputStaysAtRestForTheDeadTime) {
  LoopOptions o = Sampled(0.01);
  Evaluation dut;
  ASSERT_TRUE(Evaluate(Fopdt(0.3), {1.0, 1.0, 0.0}, o, EvaluateOptions{}, &dut).ok());
  ASSERT_TRUE(dut.stability.stable);
  for (std::size_t m = 0; m <= 6; ++m) EXPECT_EQ(dut.y[m], 0.0) << "t = " << dut.t[m];
  EXPECT_GT(dut.y[7], 0.0) << "t = 0.35 s, after the dead time";
  EXPECT_NEAR(dut.y.back(), 1.0, 1e-3) << "the integral action removes the offset";
}

TEST(DelayedSampledLoop, UnstableDelayedLoopIsFlaggedLikeAnUnstableUndelayedOne) {
  const LoopOptions o = Sampled(0.01);
  Evaluation delayed, undelayed;
  ASSERT_TRUE(Evaluate(Fopdt(1.0), {3.0, 0.0, 0.0}, o, EvaluateOptions{}, &delayed).ok());
  ASSERT_TRUE(Evaluate(Fopdt(0.0), {3.0, 0.0, 0.0}, o, EvaluateOptions{}, &undelayed).ok());
  EXPECT_TRUE(undelayed.stability.stable);
  EXPECT_FALSE(delayed.stability.stable) << "kp = 3 is above Ku = 2.26 of e^(-s)/(s+1)";
  EXPECT_GT(delayed.stability.abscissa, 1.0);
  EXPECT_TRUE(std::isinf(delayed.iae));
  const ObjectiveEvaluator objective(Fopdt(1.0), o, ObjectiveKind::kIae);
  EXPECT_TRUE(std::isinf(objective({3.0, 0.0, 0.0})));
  EXPECT_TRUE(std::isfinite(objective({1.0, 0.3, 0.0})));
}

TEST(DelayedSampledLoop, GainMarginOfTheSampledLoopIsItsUltimateGain) {
  const Plant plant = Fopdt(1.0);
  const double ku = SampledUltimateGain(plant, 0.01, 2.0, 2.5);
  LoopAnalysis dut;
  std::string error;
  ASSERT_TRUE(OkInto(AnalyzeLoop(plant, {1.0, 0.0, 0.0}, Sampled(0.01), LoopAnalysisOptions{}, &dut), &error))
      << error;
  EXPECT_NEAR(dut.gain_margin, ku, 1e-4 * ku);
}

TEST(DelayedLoop, ContinuousLoopWithDeadTimeIsEvaluatedAndItsNeutralCaseRefused) {
  LoopOptions o;  // continuous: the method of steps (delayed_loop.h)
  Evaluation ev;
  ASSERT_TRUE(Evaluate(Fopdt(0.3), {1.0, 1.0, 0.0}, o, EvaluateOptions{}, &ev).ok());
  EXPECT_TRUE(ev.stability.stable);
  EXPECT_TRUE(std::isfinite(ev.iae));
  const ObjectiveEvaluator objective(Fopdt(0.3), o, ObjectiveKind::kIae);
  EXPECT_NEAR(objective({1.0, 1.0, 0.0}), ev.iae, 1e-12 * ev.iae);
  EXPECT_NEAR(LoadIntegralAbsError(Fopdt(0.3), {1.0, 1.0, 0.0}, o), ev.load_iae, 1e-12 * ev.load_iae);
  // An ideal derivative on a plant of relative degree 1: a neutral loop.
  const auto status = Evaluate(Fopdt(0.3), {1.0, 1.0, 0.1}, o, EvaluateOptions{}, &ev);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find("derivative filter"), std::string::npos) << status.message();
  EXPECT_TRUE(std::isinf(objective({1.0, 1.0, 0.1})));
  // Past the ultimate gain the Nyquist count says unstable: +inf, not a number.
  ASSERT_TRUE(Evaluate(Fopdt(1.0), {2.3, 0.0, 0.0}, o, EvaluateOptions{}, &ev).ok());
  EXPECT_FALSE(ev.stability.stable);
  EXPECT_TRUE(std::isinf(ev.iae));
  LoopAnalysis analysis;
  std::string error;
  EXPECT_TRUE(IsOk(AnalyzeLoop(Fopdt(0.3), {1.0, 1.0, 0.0}, o, LoopAnalysisOptions{}, &analysis)));
}

TEST(DelayedLoop, DelayOutOfRangeIsRefusedNamingTheField) {
  const LoopOptions o = Sampled(0.01);
  std::string error;
  EXPECT_FALSE(OkInto(DelayIsValid(Fopdt(-1.0), o, "--delay"), &error));
  EXPECT_EQ(error.rfind("--delay -1 s must be", 0), 0u) << error;
  EXPECT_FALSE(OkInto(DelayIsValid(Fopdt(std::nan("")), o, "--delay"), &error));
  EXPECT_FALSE(OkInto(DelayIsValid(Fopdt(1e9), o, "--delay"), &error));
  EXPECT_FALSE(OkInto(DelayIsValid(Fopdt(0.01 * (kMaxAnalysedDelaySteps + 1)), o, "--delay"), &error));
  EXPECT_NE(error.find("stored inputs"), std::string::npos) << error;
  EXPECT_TRUE(IsOk(DelayIsValid(Fopdt(0.01 * kMaxAnalysedDelaySteps), o, "--delay")));
  EXPECT_TRUE(OkInto(DelayIsValid(Fopdt(0.0), LoopOptions{}, "--delay"), &error)) << "no delay: any loop";
}

}  // namespace
}  // namespace pidlab
