// Objectives and MATLAB-stepinfo metrics on responses with closed forms.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveFromSamples;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::ParseObjectiveKind;
using pidlab::evaluation::SampledStepInfo;
using pidlab::evaluation::StepInfo;

namespace pidlab {
namespace {

Evaluation EvaluateOrFail(const TransferFunction& tf, const PidGains& gains,
                          const LoopOptions& options = {}) {
  Evaluation ev;
  std::string error;
  EXPECT_TRUE(IsOk(Evaluate(Plant{"custom", tf}, gains, options, EvaluateOptions{}, &ev)));
  return ev;
}

// ---- Sample sums ----

TEST(ObjectiveFromSamples, SumsAbsoluteSquaredAndTimeWeightedErrors) {
  const std::vector<double> y = {0.0, 0.5, 1.5, 1.0};  // e = 1, 0.5, -0.5, 0
  EXPECT_DOUBLE_EQ(ObjectiveFromSamples(ObjectiveKind::kIae, y, 0.1), 2.0);
  EXPECT_DOUBLE_EQ(ObjectiveFromSamples(ObjectiveKind::kIse, y, 0.1), 1.5);
  EXPECT_DOUBLE_EQ(ObjectiveFromSamples(ObjectiveKind::kItae, y, 0.1), 0.1 * 0.5 + 0.2 * 0.5);
}

TEST(ObjectiveFromSamples, NonFiniteOutputGivesInfinity) {
  const std::vector<double> y = {0.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_TRUE(std::isinf(ObjectiveFromSamples(ObjectiveKind::kIae, y, 0.1)));
}

TEST(ObjectiveKind, ParsesEveryKindAndRejectsOthers) {
  for (ObjectiveKind k :
       {ObjectiveKind::kIae, ObjectiveKind::kIse, ObjectiveKind::kItae, ObjectiveKind::kIaeContinuous,
        ObjectiveKind::kLoadIae, ObjectiveKind::kSetpointLoad}) {
    ObjectiveKind dut = ObjectiveKind::kIae;
    EXPECT_TRUE(ParseObjectiveKind(ToString(k), &dut)) << ToString(k);
    EXPECT_EQ(dut, k);
  }
  ObjectiveKind dut;
  EXPECT_FALSE(ParseObjectiveKind("mse", &dut));
}

// ---- First-order loop: 1/(s+1), kp = K (and the PI loop cancelling the lag) ----

// y(t) = yf (1 - e^{-a t}) sampled at m ts, m = 0..500: e_m = (1 - yf) + yf q^m,
// q = e^{-a ts}, so sum e_m = 501 (1 - yf) + yf (1 - q^501) / (1 - q).
double FirstOrderIae(double yf, double a) {
  const double q = std::exp(-a * 0.05);
  return 501.0 * (1.0 - yf) + yf * (1.0 - std::pow(q, 501)) / (1.0 - q);
}

TEST(Metrics, FirstOrderProportionalLoopMatchesTheClosedForms) {
  const double k = 4.0, a = 1.0 + k, yf = k / (1.0 + k);
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {k, 0.0, 0.0});
  ASSERT_TRUE(dut.stability.stable);
  EXPECT_NEAR(dut.iae, FirstOrderIae(yf, a), 1e-10 * FirstOrderIae(yf, a));
  EXPECT_NEAR(dut.step.final_value, yf, 1e-12);
  EXPECT_NEAR(dut.step.rise_time_s, std::log(9.0) / a, 1e-9);
  EXPECT_NEAR(dut.step.settling_time_s, std::log(50.0) / a, 1e-9);
  EXPECT_NEAR(dut.step.overshoot_pct, 0.0, 1e-9);
}

TEST(Metrics, FirstOrderPiLoopMatchesTheClosedForms) {
  // kp (s + 1)/s cancels 1/(s+1): y = 1 - e^{-kp t}, final value 1.
  const double kp = 3.0;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {kp, kp, 0.0});
  ASSERT_TRUE(dut.stability.stable);
  ASSERT_TRUE(dut.step.valid) << dut.step.note;
  EXPECT_NEAR(dut.iae, FirstOrderIae(1.0, kp), 1e-10 * FirstOrderIae(1.0, kp));
  double ise = 0.0, itae = 0.0;
  for (int m = 0; m <= 500; ++m) {
    const double e = std::exp(-kp * 0.05 * m);
    ise += e * e;
    itae += 0.05 * m * e;
  }
  EXPECT_NEAR(dut.ise, ise, 1e-10 * ise);
  EXPECT_NEAR(dut.itae, itae, 1e-10 * itae);
  EXPECT_NEAR(dut.iae_continuous, 1.0 / kp, 1e-3 / kp);  // \int e^{-kp t} dt, grid trapezoid
  EXPECT_NEAR(dut.step.final_value, 1.0, 1e-12);
  EXPECT_NEAR(dut.step.rise_time_s, std::log(9.0) / kp, 1e-9);
  EXPECT_NEAR(dut.step.settling_time_s, std::log(50.0) / kp, 1e-9);
  EXPECT_NEAR(dut.step.overshoot_pct, 0.0, 1e-9);
}

TEST(Metrics, FirstOrderContinuousIntegralOfTheErrorMatchesTheClosedForm) {
  // With a steady-state error: \int_0^25 (1 - yf) + yf e^{-a t} dt.
  const double k = 4.0, a = 1.0 + k, yf = k / (1.0 + k);
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {k, 0.0, 0.0});
  ASSERT_TRUE(dut.stability.stable);
  const double expected = 25.0 * (1.0 - yf) + yf / a * (1.0 - std::exp(-25.0 * a));
  EXPECT_NEAR(dut.iae_continuous, expected, 1e-3 * expected);
}

// ---- Second-order loop: wn^2 / (s^2 + 2 zeta wn s + wn^2) ----

double SecondOrderStep(double zeta, double wn, double t) {
  const double s = std::sqrt(1.0 - zeta * zeta);
  return 1.0 - std::exp(-zeta * wn * t) * (std::cos(wn * s * t) + zeta / s * std::sin(wn * s * t));
}

// First t with g(t) >= 0 scanning from t0 by h, then bisection.
template <typename G>
double FirstRoot(const G& g, double t0, double h) {
  double a = t0;
  while (g(a + h) < 0.0) a += h;
  double b = a + h;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (a + b);
    (g(mid) < 0.0 ? a : b) = mid;
  }
  return 0.5 * (a + b);
}

struct SecondOrderReference {
  double overshoot_pct, peak_time_s, rise_time_s, settling_time_s;
};

SecondOrderReference SecondOrderMetrics(double zeta, double wn) {
  SecondOrderReference r;
  const double s = std::sqrt(1.0 - zeta * zeta);
  r.overshoot_pct = 100.0 * std::exp(-zeta * M_PI / s);
  r.peak_time_s = M_PI / (wn * s);
  auto y = [&](double t) { return SecondOrderStep(zeta, wn, t); };
  r.rise_time_s = FirstRoot([&](double t) { return y(t) - 0.9; }, 0.0, 1e-3) -
                  FirstRoot([&](double t) { return y(t) - 0.1; }, 0.0, 1e-3);
  // Last exit from the 2 % band: scan backwards from where the envelope is inside it.
  const double t_end = std::log(50.0 / s) / (zeta * wn) + 1.0;
  double t = t_end;
  const double h = 1e-4;
  while (std::abs(y(t) - 1.0) <= 0.02) t -= h;
  double a = t, b = t + h;  // |y(a) - 1| > 0.02 >= |y(b) - 1|
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (a + b);
    (std::abs(y(mid) - 1.0) > 0.02 ? a : b) = mid;
  }
  r.settling_time_s = 0.5 * (a + b);
  return r;
}

void ExpectSecondOrderMetrics(const Evaluation& dut, double zeta, double wn) {
  ASSERT_TRUE(dut.stability.stable);
  ASSERT_TRUE(dut.step.valid) << dut.step.note;
  const SecondOrderReference ref = SecondOrderMetrics(zeta, wn);
  EXPECT_NEAR(dut.step.final_value, 1.0, 1e-12);
  EXPECT_NEAR(dut.step.overshoot_pct, ref.overshoot_pct, 1e-6 * ref.overshoot_pct);
  EXPECT_NEAR(dut.step.peak, 1.0 + ref.overshoot_pct / 100.0, 1e-6);
  EXPECT_NEAR(dut.step.peak_time_s, ref.peak_time_s, 1e-6 * ref.peak_time_s);
  EXPECT_NEAR(dut.step.rise_time_s, ref.rise_time_s, 1e-6 * ref.rise_time_s);
  EXPECT_NEAR(dut.step.settling_time_s, ref.settling_time_s, 1e-6 * ref.settling_time_s);
  double iae = 0.0;
  for (int m = 0; m <= 500; ++m) iae += std::abs(1.0 - SecondOrderStep(zeta, wn, 0.05 * m));
  EXPECT_NEAR(dut.iae, iae, 1e-10 * iae);
}

TEST(Metrics, UnderdampedSecondOrderProportionalLoopMatchesTheClosedForms) {
  const double zeta = 0.3, wn = 2.0;
  ExpectSecondOrderMetrics(EvaluateOrFail({{wn * wn}, {1.0, 2.0 * zeta * wn, 0.0}}, {1.0, 0.0, 0.0}), zeta,
                           wn);
}

TEST(Metrics, UnderdampedSecondOrderPiLoopMatchesTheClosedForms) {
  // wn^2 / ((s + 1)(s + 2 zeta wn)) under kp = ki = 1: the PI zero cancels s + 1.
  for (const auto& [zeta, wn] : {std::pair{0.3, 2.0}, std::pair{0.6, 5.0}, std::pair{0.1, 1.0}}) {
    SCOPED_TRACE("zeta = " + std::to_string(zeta) + ", wn = " + std::to_string(wn));
    ExpectSecondOrderMetrics(
        EvaluateOrFail({{wn * wn}, {1.0, 1.0 + 2.0 * zeta * wn, 2.0 * zeta * wn}}, {1.0, 1.0, 0.0}), zeta,
        wn);
  }
}

// ---- stepinfo on sampled responses ----

TEST(SampledStepInfo, FirstOrderSamplesGiveTheClosedFormsToInterpolationAccuracy) {
  std::vector<double> t, y;
  for (int k = 0; k <= 10000; ++k) {
    t.push_back(k * 1e-3);
    y.push_back(1.0 - std::exp(-t.back()));
  }
  const StepInfo dut = SampledStepInfo(t, y, 1.0);
  ASSERT_TRUE(dut.valid) << dut.note;
  EXPECT_NEAR(dut.rise_time_s, std::log(9.0), 1e-6);
  EXPECT_NEAR(dut.settling_time_s, std::log(50.0), 1e-6);
  EXPECT_EQ(dut.overshoot_pct, 0.0);
}

TEST(SampledStepInfo, OvershootIsThePeakAboveTheFinalValueInPercent) {
  const std::vector<double> t = {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0};
  const std::vector<double> y = {0.0, 1.0, 2.5, 1.5, 2.1, 1.99, 2.0};
  const StepInfo dut = SampledStepInfo(t, y, 2.0);
  ASSERT_TRUE(dut.valid) << dut.note;
  EXPECT_DOUBLE_EQ(dut.overshoot_pct, 25.0);
  EXPECT_DOUBLE_EQ(dut.peak, 2.5);
  EXPECT_DOUBLE_EQ(dut.peak_time_s, 2.0);
  // 10 % = 0.2 at t = 0.2, 90 % = 1.8 at t = 1 + 0.8/1.5; band 0.04: last out at t = 4 (2.1).
  EXPECT_NEAR(dut.rise_time_s, 1.0 + 0.8 / 1.5 - 0.2, 1e-12);
  EXPECT_NEAR(dut.settling_time_s, 4.0 + (0.1 - 0.04) / (0.1 - 0.01 + 0.0), 1e-12);
}

TEST(SampledStepInfo, ZeroFinalValueIsNotValid) {
  const StepInfo dut = SampledStepInfo({0.0, 1.0}, {0.0, 0.0}, 0.0);
  EXPECT_FALSE(dut.valid);
  EXPECT_FALSE(dut.note.empty());
}

TEST(SampledStepInfo, ResponseNotSettledAtTheEndIsNotValid) {
  const StepInfo dut = SampledStepInfo({0.0, 1.0, 2.0}, {0.0, 1.0, 1.5}, 1.0);
  EXPECT_FALSE(dut.valid);
}

}  // namespace
}  // namespace pidlab
