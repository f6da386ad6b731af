// pidlab::identify: the general transfer function, ProcessModelKind::kTf
// (docs/identify.md, "A general transfer function").

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "identify_records.h"
#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {
using test::kDt;
using test::StepRichInput;

// A record of `model` around (0.5, 2.0); with `snr_db`, white noise whose
// RMS is the output's (about its mean) over 10^(snr_db / 20), from sample 1.
IdentifyData RecordOf(const ProcessModel& model, double snr_db = 0.0, std::size_t n = 600) {
  IdentifyData data;
  const std::vector<double> du = StepRichInput(n, 7);
  const std::vector<double> dy = SimulateModel(model, du, 0.0, kDt);
  double mean = 0.0, power = 0.0;
  for (double v : dy) mean += v / static_cast<double>(n);
  for (double v : dy) power += (v - mean) * (v - mean) / static_cast<double>(n);
  std::mt19937 rng(13);
  std::normal_distribution<double> noise(0.0,
                                         snr_db > 0.0 ? std::sqrt(power) / std::pow(10.0, snr_db / 20) : 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    data.t.push_back(static_cast<double>(k) * kDt);
    data.u.push_back(0.5 + du[k]);
    data.y.push_back(2.0 + dy[k] + (k > 0 && snr_db > 0.0 ? noise(rng) : 0.0));
  }
  return data;
}

// (0.8 s + 1.2) e^(-0.37 s) / (s^3 + 2.6 s^2 + 2.1 s + 0.5): three stable
// poles, a left-half-plane zero, a delay off the sample grid.
ProcessModel ThreePolesOneZero() {
  return ModelFromValues(ProcessModelKind::kTf, {1.2, 0.8, 0.5, 2.1, 2.6, 0.37}, 3, 1);
}

IdentifyOptions TfOptions(int poles, int zeros) {
  IdentifyOptions options;
  options.poles = poles;
  options.zeros = zeros;
  return options;
}

TEST(IdentifyTf, ThreePolesAndOneZeroAreRecoveredNoiseFreeWithinOnePartInAMillion) {
  const ProcessModel truth = ThreePolesOneZero();
  IdentifyResult dut;
  const Status status = Identify(RecordOf(truth), ProcessModelKind::kTf, TfOptions(3, 1), &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(dut.names, (std::vector<std::string>{"b0", "b1", "a0", "a1", "a2", "Td"}));
  const std::vector<double> expected = ParameterValues(truth);
  ASSERT_EQ(dut.values.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-6 * std::abs(expected[i])) << dut.names[i];
  EXPECT_GT(dut.fit_percent, 99.99);
  EXPECT_EQ(dut.model.poles, 3);
  EXPECT_EQ(dut.model.zeros, 1);
  const TransferFunction tf = dut.model.ToTransferFunction();
  ASSERT_EQ(tf.num.size(), 2u);
  ASSERT_EQ(tf.den.size(), 4u);
  EXPECT_EQ(tf.den[0], 1.0);
  EXPECT_EQ(PoleEstimates(dut).size(), 3u);
}

TEST(IdentifyTf, TwoPolesWithoutZerosFitP2dDataAsTheP2dFitDoes) {
  ProcessModel p2d;
  p2d.kind = ProcessModelKind::kP2D;
  p2d.kp = 1.7, p2d.tp1_s = 4.2, p2d.tp2_s = 1.3, p2d.td_s = 0.63;
  const IdentifyData data = RecordOf(p2d, 30.0);
  IdentifyResult by_p2d, dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, IdentifyOptions{}, &by_p2d).ok());
  const Status status = Identify(data, ProcessModelKind::kTf, TfOptions(2, 0), &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(dut.cost, by_p2d.cost, 1e-8 * by_p2d.cost);
  // The same transfer function: Kp / (T1 T2 s^2 + (T1 + T2) s + 1), made monic.
  const double t1 = by_p2d.model.tp1_s, t2 = by_p2d.model.tp2_s;
  const std::vector<double> expected = {by_p2d.model.kp / (t1 * t2), 1.0 / (t1 * t2), (t1 + t2) / (t1 * t2),
                                        by_p2d.model.td_s};
  ASSERT_EQ(dut.values.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-5 * std::abs(expected[i])) << dut.names[i];
  EXPECT_NEAR(dut.y0, by_p2d.y0, 1e-6);
}

TEST(IdentifyTf, StandardErrorsAreFiniteAndCoverTheTruthAtThirtyDecibels) {
  const ProcessModel truth = ThreePolesOneZero();
  IdentifyResult dut;
  ASSERT_TRUE(Identify(RecordOf(truth, 30.0), ProcessModelKind::kTf, TfOptions(3, 1), &dut).ok());
  ASSERT_TRUE(dut.covariance_ok) << dut.covariance_message;
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_TRUE(std::isfinite(dut.standard_errors[i])) << dut.names[i];
    EXPECT_GT(dut.standard_errors[i], 0.0) << dut.names[i];
    EXPECT_NEAR(dut.values[i], expected[i], 5.0 * dut.standard_errors[i]) << dut.names[i];
  }
  EXPECT_GT(dut.fit_percent, 90.0);
  EXPECT_LT(dut.fit_percent, 100.0);
}

TEST(IdentifyTf, TheFitIsStableAndOscillatesNoFasterThanTheSamplesShow) {
  IdentifyResult dut;
  ASSERT_TRUE(
      Identify(RecordOf(ThreePolesOneZero(), 30.0), ProcessModelKind::kTf, TfOptions(3, 1), &dut).ok());
  EXPECT_TRUE(plant_sim::IsHurwitz(dut.model.a));
  for (const PoleEstimate& p : PoleEstimates(dut)) {
    EXPECT_LT(p.re, 0.0);
    EXPECT_LT(std::abs(p.im), M_PI / kDt);
  }
}

// The Sobol' design has two coordinates for the lags whatever their number
// (optim/sobol.h has at most four), so every order up to six runs.
TEST(IdentifyTf, EveryOrderUpToSixGivesAStableModel) {
  const IdentifyData data = RecordOf(ThreePolesOneZero(), 30.0, 300);
  for (int poles = 1; poles <= plant_sim::kMaxTfPoles; ++poles) {
    SCOPED_TRACE(poles);
    IdentifyOptions options = TfOptions(poles, poles - 1);
    options.starts = 4;
    IdentifyResult dut;
    const Status status = Identify(data, ProcessModelKind::kTf, options, &dut);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(dut.values.size(), static_cast<std::size_t>(2 * poles + 1));
    EXPECT_TRUE(plant_sim::IsHurwitz(dut.model.a));
  }
}

void ExpectRefused(ProcessModelKind kind, int poles, int zeros, const std::string& message) {
  IdentifyResult result;
  const Status status = Identify(RecordOf(ThreePolesOneZero()), kind, TfOptions(poles, zeros), &result);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find(message), std::string::npos) << status.message();
}

TEST(IdentifyTf, NoPolesAreRefused) {
  ExpectRefused(ProcessModelKind::kTf, 0, 0, "poles = 0 must be in 1..6");
}
TEST(IdentifyTf, SevenPolesAreRefused) {
  ExpectRefused(ProcessModelKind::kTf, 7, 0, "poles = 7 must be in 1..6");
}
TEST(IdentifyTf, AsManyZerosAsPolesAreRefused) {
  ExpectRefused(ProcessModelKind::kTf, 2, 2, "zeros = 2 must be in 0..1");
}
TEST(IdentifyTf, NegativeZerosAreRefused) { ExpectRefused(ProcessModelKind::kTf, 2, -1, "zeros = -1"); }
TEST(IdentifyTf, PolesForAnotherKindAreRefused) {
  ExpectRefused(ProcessModelKind::kP2D, 2, 0, "apply to the model tf only, not p2d");
}

TEST(TfModel, NamesValuesAndTheTransferFunctionAgree) {
  const ProcessModel m = ThreePolesOneZero();
  EXPECT_EQ(ParameterNames(ProcessModelKind::kTf, 3, 1),
            (std::vector<std::string>{"b0", "b1", "a0", "a1", "a2", "Td"}));
  EXPECT_EQ(ParameterValues(m), (std::vector<double>{1.2, 0.8, 0.5, 2.1, 2.6, 0.37}));
  const TransferFunction tf = m.ToTransferFunction();
  EXPECT_EQ(tf.num, (std::vector<double>{0.8, 1.2}));
  EXPECT_EQ(tf.den, (std::vector<double>{1.0, 2.6, 2.1, 0.5}));
  EXPECT_EQ(m.delay_s(), 0.37);
  std::string error;
  EXPECT_TRUE(plant_sim::ParametersAreValid(ProcessModelKind::kTf, ParameterValues(m), &error, 3, 1))
      << error;
}

TEST(TfModel, AnUnstableDenominatorIsNotAValidModel) {
  std::string error;
  // s^3 + s^2 + s + 2: Routh's first column 1, 1, -1, 2.
  EXPECT_FALSE(plant_sim::ParametersAreValid(ProcessModelKind::kTf, {1.0, 2.0, 1.0, 1.0, 0.0}, &error, 3, 0));
  EXPECT_NE(error.find("real part >= 0"), std::string::npos) << error;
  EXPECT_FALSE(plant_sim::IsHurwitz({0.0, 1.0}));  // a pole at 0
  EXPECT_FALSE(plant_sim::IsHurwitz({1.0, 0.0}));  // poles at +-j
  EXPECT_TRUE(plant_sim::IsHurwitz({2.0, 3.0}));   // -1, -2
  EXPECT_TRUE(plant_sim::IsHurwitz({0.5, 2.1, 2.6}));
}

TEST(TfModel, AShapeOutsideItsLimitsIsNotAValidModel) {
  std::string error;
  EXPECT_FALSE(plant_sim::ParametersAreValid(ProcessModelKind::kTf, {1.0, 1.0, 0.0}, &error, 1, 1));
  EXPECT_NE(error.find("zeros in 0..poles-1"), std::string::npos) << error;
  EXPECT_TRUE(ParameterNames(ProcessModelKind::kTf, 7, 0).empty());
}

}  // namespace
}  // namespace pidlab::identify
