// pidlab::identify: process models fitted to a record (docs/identify.md,
// "Identifying a model from a CSV").

#include "pidlab/identify/identify.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "identify_records.h"
#include "pidlab/identify/csv_data.h"

namespace pidlab::identify {
namespace {
using test::kDt;
using test::StepRichInput;

// A noise-free record of `model` around the operating point (u0, y0).
IdentifyData RecordOf(const ProcessModel& model, std::size_t n = 400, double u0 = 0.5, double y0 = 2.0) {
  IdentifyData data;
  const std::vector<double> du = StepRichInput(n, 7);
  const std::vector<double> dy = SimulateModel(model, du, 0.0, kDt);
  for (std::size_t k = 0; k < n; ++k) {
    data.t.push_back(static_cast<double>(k) * kDt);
    data.u.push_back(u0 + du[k]);
    data.y.push_back(y0 + dy[k]);
  }
  return data;
}

ProcessModel Truth(ProcessModelKind kind) {
  ProcessModel m;
  m.kind = kind;
  m.td_s = 0.37;  // not a multiple of kDt
  switch (kind) {
    case ProcessModelKind::kP1D:
      m.kp = 2.5, m.tp1_s = 3.1;
      break;
    case ProcessModelKind::kP2D:
      m.kp = 1.7, m.tp1_s = 4.2, m.tp2_s = 1.3, m.td_s = 0.63;
      break;
    case ProcessModelKind::kP2DU:
      m.kp = 0.8, m.tw_s = 1.9, m.zeta = 0.35;
      break;
    case ProcessModelKind::kP1DI:
      m.kp = 0.45, m.tp1_s = 2.2;
      break;
    case ProcessModelKind::kP2DZ:  // a right-half-plane zero: an inverse response
      m.kp = 1.2, m.tp1_s = 3.0, m.tp2_s = 0.8, m.tz_s = -0.9;
      break;
    case ProcessModelKind::kTf:  // identify_tf_test.cc
      break;
  }
  return m;
}

class NoiseFree : public ::testing::TestWithParam<ProcessModelKind> {};

TEST_P(NoiseFree, EveryParameterIsRecoveredWithinOnePartInAMillion) {
  const ProcessModel truth = Truth(GetParam());
  IdentifyResult dut;
  const Status status = Identify(RecordOf(truth), GetParam(), IdentifyOptions{}, &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  const std::vector<double> expected = ParameterValues(truth);
  ASSERT_EQ(dut.values.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-6 * std::abs(expected[i])) << dut.names[i];
  EXPECT_GT(dut.fit_percent, 99.99);
  EXPECT_DOUBLE_EQ(dut.u0, 0.5);
  EXPECT_DOUBLE_EQ(dut.y0, 2.0);
  EXPECT_EQ(dut.samples, 400);
  EXPECT_NEAR(dut.dt_s, kDt, 1e-12);
  EXPECT_EQ(dut.standard_errors.size(), expected.size());
}

INSTANTIATE_TEST_SUITE_P(Models, NoiseFree,
                         ::testing::Values(ProcessModelKind::kP1D, ProcessModelKind::kP2D,
                                           ProcessModelKind::kP2DU, ProcessModelKind::kP1DI,
                                           ProcessModelKind::kP2DZ),
                         [](const auto& name_info) { return std::string(ToString(name_info.param)); });

class Delay : public ::testing::TestWithParam<double> {};

// The delay on the sample grid (where the delayed step stops splitting), at
// its bound 0 and within the first sample.
TEST_P(Delay, P1dIsRecoveredWhateverTheDelay) {
  ProcessModel truth = Truth(ProcessModelKind::kP1D);
  truth.td_s = GetParam();
  IdentifyResult dut;
  ASSERT_TRUE(Identify(RecordOf(truth), ProcessModelKind::kP1D, IdentifyOptions{}, &dut).ok());
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-6 * std::max(1.0, std::abs(expected[i]))) << dut.names[i];
  EXPECT_GT(dut.fit_percent, 99.99);
}

INSTANTIATE_TEST_SUITE_P(OnAndOffTheGrid, Delay, ::testing::Values(0.0, 0.05, 0.4));

TEST(Identify, TheMultiStartReportsHowManyStartsReachedTheOptimum) {
  IdentifyOptions options;
  options.starts = 8;
  const IdentifyData data = RecordOf(Truth(ProcessModelKind::kP2D));
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, options, &dut).ok());
  // The design's, the ARX start and the two from P1D's optimum.
  EXPECT_EQ(dut.nested_starts, 2);
  EXPECT_EQ(dut.starts, 8 + (dut.arx_start ? 1 : 0) + 2);
  ASSERT_EQ(dut.start_costs.size(), static_cast<std::size_t>(dut.starts));
  // The documented rule: within 1e-8 of the reported cost (after the delay's
  // profile), relative, measured against 1e-16 of the zero model's cost when
  // that is ~0.
  double scale = 0.0;
  for (double y : data.y) scale += 0.5 * (y - data.y[0]) * (y - data.y[0]);
  const double best = dut.cost;
  EXPECT_LE(best, *std::min_element(dut.start_costs.begin(), dut.start_costs.end()) * (1 + 1e-9));
  int counted = 0;
  for (double c : dut.start_costs) counted += c - best <= 1e-8 * std::max(best, 1e-16 * scale) ? 1 : 0;
  EXPECT_EQ(dut.starts_at_best, counted);
  EXPECT_GE(dut.starts_at_best, 2) << "noise-free P2D: more than one start should reach the optimum";

  // One start alone, without the ARX start, the nested starts and the profile.
  options.starts = 1;
  options.arx_start = false;
  options.nested_starts = false;
  options.delay_profile = false;
  options.bounds_refit = false;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, options, &dut).ok());
  EXPECT_EQ(dut.starts, 1);
  EXPECT_FALSE(dut.arx_start);
  EXPECT_EQ(dut.nested_starts, 0);
  EXPECT_FALSE(dut.delay_profile_improved);
  EXPECT_FALSE(dut.bounds_refit_improved);
  EXPECT_EQ(dut.starts_at_best, 1);
}

TEST(Identify, StartsAreCountedAtTheBestAgainstTheCostAfterTheDelaysProfile) {
  // P1D on P2D data without dead time, from one start: Td ends at or near
  // its bound 0, where the profile (Td held on a grid, then freed) runs.
  IdentifyOptions options;
  options.starts = 1;
  options.arx_start = false;
  IdentifyResult profiled, alone;
  ProcessModel truth = Truth(ProcessModelKind::kP2D);
  truth.td_s = 0.0;
  const IdentifyData data = RecordOf(truth);
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, options, &profiled).ok());
  options.delay_profile = false;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, options, &alone).ok());
  ASSERT_EQ(profiled.start_costs.size(), 1u);
  EXPECT_NEAR(profiled.start_costs[0], alone.cost, 1e-9 * alone.cost);
  EXPECT_LE(profiled.cost, alone.cost * (1 + 1e-12));
  const bool at_best = profiled.start_costs[0] - profiled.cost <= 1e-8 * profiled.cost;
  EXPECT_EQ(profiled.starts_at_best, at_best ? 1 : 0);
  EXPECT_EQ(alone.starts_at_best, 1);
  EXPECT_FALSE(alone.delay_profile_improved);
}

// eq. (3)'s mechanical mode: wn = 23.93 rad/s, Zeta = 0.0197, sampled at 1 ms
// for 10 s. Its cost is a comb of narrow valleys in Tw; the design's starts
// miss the true one, the ARX start (taken every 16 samples) lands in it.
TEST(Identify, ALightlyDampedPairIsFoundFromTheArxStart) {
  ProcessModel truth;
  truth.kind = ProcessModelKind::kP2DU;
  truth.kp = 0.926, truth.tw_s = 1.0 / 23.93, truth.zeta = 0.0197, truth.td_s = 0.00015;
  IdentifyData data;
  std::mt19937 rng(9);
  std::bernoulli_distribution bit(0.5);
  std::vector<double> u(10000);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = k % 10 == 0 ? (bit(rng) ? 0.002 : -0.002) : u[k - 1];
  const std::vector<double> y = SimulateModel(truth, u, 0.0, 1e-3);
  std::normal_distribution<double> noise(0.0, 2e-5);
  for (std::size_t k = 0; k < u.size(); ++k) {
    data.t.push_back(static_cast<double>(k) * 1e-3);
    data.u.push_back(u[k]);
    data.y.push_back(y[k] + (k ? noise(rng) : 0.0));
  }
  IdentifyOptions options;
  options.u0 = 0.0, options.y0 = 0.0;
  IdentifyResult with_arx, without;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2DU, options, &with_arx).ok());
  ASSERT_TRUE(with_arx.arx_start);
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(with_arx.values[i], expected[i], 4.0 * with_arx.standard_errors[i]) << with_arx.names[i];
  EXPECT_GT(with_arx.fit_percent, 99.0);
  // The design alone: without the ARX start, the starts from P2D's optimum
  // and the delay's profile.
  options.arx_start = false;
  options.nested_starts = false;
  options.delay_profile = false;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2DU, options, &without).ok());
  EXPECT_GT(without.cost, 100.0 * with_arx.cost) << "the design alone is expected to miss this valley";
}

TEST(Identify, NoisyDataGivesFiniteStandardErrorsThatCoverTheTruth) {
  const ProcessModel truth = Truth(ProcessModelKind::kP1D);
  IdentifyData data = RecordOf(truth);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double& y : data.y) y += noise(rng);
  data.y[0] = 2.0;  // the record starts at rest
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &dut).ok());
  ASSERT_TRUE(dut.covariance_ok) << dut.covariance_message;
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_TRUE(std::isfinite(dut.standard_errors[i])) << dut.names[i];
    EXPECT_GT(dut.standard_errors[i], 0.0) << dut.names[i];
    EXPECT_NEAR(dut.values[i], expected[i], 5.0 * dut.standard_errors[i]) << dut.names[i];
  }
  EXPECT_GT(dut.fit_percent, 95.0);
  EXPECT_LT(dut.fit_percent, 100.0);
  EXPECT_TRUE(std::isfinite(dut.aic));
}

TEST(Identify, TheCovarianceIsSymmetricAndItsDiagonalGivesTheStandardErrors) {
  IdentifyData data = RecordOf(Truth(ProcessModelKind::kP2D));
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::size_t k = 1; k < data.y.size(); ++k) data.y[k] += noise(rng);
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  ASSERT_TRUE(dut.covariance_ok) << dut.covariance_message;
  const std::size_t p = dut.names.size();
  ASSERT_EQ(dut.covariance.size(), p * p);
  for (std::size_t i = 0; i < p; ++i) {
    EXPECT_NEAR(std::sqrt(dut.covariance[i * p + i]), dut.standard_errors[i], 1e-12 * dut.standard_errors[i]);
    for (std::size_t j = 0; j < p; ++j) {
      EXPECT_NEAR(dut.covariance[i * p + j], dut.covariance[j * p + i],
                  1e-12 * std::abs(dut.covariance[i * p + j]) + 1e-300);
      // A correlation, so within [-1, 1].
      EXPECT_LE(std::abs(dut.covariance[i * p + j]),
                dut.standard_errors[i] * dut.standard_errors[j] * (1 + 1e-9));
    }
  }
}

TEST(Identify, AnotherSeedShiftsTheStartsButReachesTheSameOptimum) {
  const IdentifyData data = RecordOf(Truth(ProcessModelKind::kP2DU));
  IdentifyOptions options;
  IdentifyResult unshifted, shifted;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2DU, options, &unshifted).ok());
  options.seed = 12345;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2DU, options, &shifted).ok());
  EXPECT_EQ(shifted.seed, 12345u);
  EXPECT_NE(unshifted.start_costs, shifted.start_costs) << "the seed must move the starts";
  for (std::size_t i = 0; i < unshifted.values.size(); ++i)
    EXPECT_NEAR(shifted.values[i], unshifted.values[i], 1e-6 * std::abs(unshifted.values[i]))
        << unshifted.names[i];
}

TEST(Whiteness, WhiteNoisePassesTheLjungBoxTestAndAnAutoregressionFailsIt) {
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> white(2000), coloured(2000);
  double state = 0.0;
  for (std::size_t k = 0; k < white.size(); ++k) {
    white[k] = noise(rng);
    state = 0.5 * state + noise(rng);
    coloured[k] = state;
  }
  const Whiteness w = ResidualWhiteness(white);
  EXPECT_EQ(w.lags, 25);
  EXPECT_DOUBLE_EQ(w.band, 1.96 / std::sqrt(2000.0));
  EXPECT_TRUE(w.white) << "p = " << w.p_value;
  EXPECT_LE(w.outside_band, 4);
  const Whiteness c = ResidualWhiteness(coloured);
  EXPECT_FALSE(c.white) << "p = " << c.p_value;
  EXPECT_NEAR(c.autocorrelation[0], 0.5, 0.06);
  EXPECT_LT(c.p_value, 1e-6);
}

class AutoChoice : public ::testing::TestWithParam<ProcessModelKind> {};

TEST_P(AutoChoice, TheTrueKindHasTheLowestAicOnANoisyRecord) {
  const ProcessModel truth = Truth(GetParam());
  IdentifyData data = RecordOf(truth, 600);
  std::mt19937 rng(23);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (std::size_t k = 1; k < data.y.size(); ++k) data.y[k] += noise(rng);
  AutoResult dut;
  ASSERT_TRUE(IdentifyAuto(data, IdentifyOptions{}, &dut).ok());
  ASSERT_EQ(dut.candidates.size(), 5u);
  ASSERT_GE(dut.chosen, 0);
  EXPECT_EQ(dut.candidates[static_cast<std::size_t>(dut.chosen)].kind, GetParam()) << dut.reason;
  EXPECT_NE(dut.reason.find("AIC"), std::string::npos) << dut.reason;
}

INSTANTIATE_TEST_SUITE_P(Models, AutoChoice,
                         ::testing::Values(ProcessModelKind::kP1D, ProcessModelKind::kP2D,
                                           ProcessModelKind::kP2DU, ProcessModelKind::kP1DI,
                                           ProcessModelKind::kP2DZ),
                         [](const ::testing::TestParamInfo<ProcessModelKind>& param_info) {
                           return std::string(ToString(param_info.param));
                         });

Status Refusal(const IdentifyData& data) {
  IdentifyResult result;
  return Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &result);
}

void ExpectRefused(const IdentifyData& data, const std::string& reason) {
  const Status status = Refusal(data);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find(reason), std::string::npos) << status.message();
}

TEST(Identify, ANotANumberIsRefusedWithItsSample) {
  IdentifyData data = RecordOf(Truth(ProcessModelKind::kP1D));
  data.y[17] = std::numeric_limits<double>::quiet_NaN();
  ExpectRefused(data, "not finite: y at sample 17");
}

TEST(Identify, TimeGoingBackwardsIsRefused) {
  IdentifyData data = RecordOf(Truth(ProcessModelKind::kP1D));
  std::swap(data.t[30], data.t[31]);
  ExpectRefused(data, "t is not strictly increasing");
}

TEST(Identify, ARecordOfFewerThanTwentySamplesIsRefused) {
  ExpectRefused(RecordOf(Truth(ProcessModelKind::kP1D), 19), "too short: 19 samples");
}

TEST(Identify, AConstantInputIsRefused) {
  IdentifyData data = RecordOf(Truth(ProcessModelKind::kP1D));
  for (double& u : data.u) u = 0.5;
  ExpectRefused(data, "constant input");
}

TEST(Identify, AConstantInputWithAGivenU0IsAStepFromRest) {
  // A heater switched on at the first sample: u = 0.5 throughout, at rest
  // at u0 = 0 before the record.
  const ProcessModel truth = Truth(ProcessModelKind::kP1D);
  IdentifyData data;
  const std::vector<double> u(300, 0.5);
  const std::vector<double> y = SimulateModel(truth, u, 0.0, kDt);
  for (std::size_t k = 0; k < u.size(); ++k) {
    data.t.push_back(static_cast<double>(k) * kDt);
    data.u.push_back(u[k]);
    data.y.push_back(20.0 + y[k]);
  }
  IdentifyOptions options;
  options.u0 = 0.0;
  IdentifyResult dut;
  const Status status = Identify(data, ProcessModelKind::kP1D, options, &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-6 * std::abs(expected[i])) << dut.names[i];
}

TEST(Identify, ADelayOfZeroIsReachedAndSaidToBeAtItsBound) {
  ProcessModel truth = Truth(ProcessModelKind::kP2D);
  truth.td_s = 0.0;
  IdentifyResult dut;
  const Status status = Identify(RecordOf(truth), ProcessModelKind::kP2D, IdentifyOptions{}, &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  const std::vector<double> expected = ParameterValues(truth);
  for (std::size_t i = 0; i + 1 < expected.size(); ++i)
    EXPECT_NEAR(dut.values[i], expected[i], 1e-6 * std::abs(expected[i])) << dut.names[i];
  EXPECT_LE(dut.values.back(), 1e-9);
  EXPECT_EQ(dut.at_bound.back(), "lower");
  EXPECT_TRUE(std::isnan(dut.standard_errors.back()));
  EXPECT_TRUE(std::any_of(dut.warnings.begin(), dut.warnings.end(), [](const std::string& w) {
    return w.find("Td = 0 s is at its lower bound") == 0;
  }));
}

TEST(Identify, ABiggerModelStartsFromTheOptimumOfTheOneItContains) {
  // P1D data with noise: P2D contains P1D (Tp2 -> 0) and is not worse.
  const ProcessModel truth = Truth(ProcessModelKind::kP1D);
  IdentifyData data = RecordOf(truth, 300);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& y : data.y) y += noise(rng);
  IdentifyResult p1d, p2d;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &p1d).ok());
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, IdentifyOptions{}, &p2d).ok());
  EXPECT_EQ(p2d.nested_starts, 2);
  EXPECT_LE(p2d.cost, p1d.cost * (1 + 1e-9));
}

TEST(Identify, BadOptionsAreRefusedNamingTheField) {
  IdentifyOptions options;
  options.starts = 0;
  IdentifyResult result;
  const Status status =
      Identify(RecordOf(Truth(ProcessModelKind::kP1D)), ProcessModelKind::kP1D, options, &result);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find("starts = 0"), std::string::npos) << status.message();
}

TEST(ProcessModel, KindsRoundTripThroughTheirNames) {
  for (ProcessModelKind kind :
       {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU, ProcessModelKind::kP1DI}) {
    ProcessModelKind parsed = ProcessModelKind::kP1D;
    ASSERT_TRUE(Parse(ToString(kind), &parsed));
    EXPECT_EQ(parsed, kind);
  }
  ProcessModelKind untouched = ProcessModelKind::kP2DU;
  EXPECT_FALSE(Parse("auto", &untouched));
  EXPECT_EQ(untouched, ProcessModelKind::kP2DU);
}

TEST(ProcessModel, TheTransferFunctionIsIdprocs) {
  ProcessModel m = Truth(ProcessModelKind::kP2DU);
  const TransferFunction tf = m.ToTransferFunction();
  EXPECT_EQ(tf.num, std::vector<double>({0.8}));
  EXPECT_EQ(tf.den, std::vector<double>({1.9 * 1.9, 2 * 0.35 * 1.9, 1.0}));
  EXPECT_DOUBLE_EQ(m.delay_s(), 0.37);
  m = Truth(ProcessModelKind::kP1DI);
  EXPECT_EQ(m.ToTransferFunction().den, std::vector<double>({2.2, 1.0, 0.0}));
}

TEST(CsvData, ColumnsAreFoundByNameInAnyOrder) {
  const std::string path = ::testing::TempDir() + "/identify_columns.csv";
  std::ofstream(path) << "y,extra,t,u\n1,9,0,0.5\n2,9,0.1,0.7\n";
  IdentifyData data;
  ASSERT_TRUE(ReadCsvData(path, &data).ok());
  EXPECT_EQ(data.t, std::vector<double>({0.0, 0.1}));
  EXPECT_EQ(data.u, std::vector<double>({0.5, 0.7}));
  EXPECT_EQ(data.y, std::vector<double>({1.0, 2.0}));
}

TEST(CsvData, AMissingColumnOrABadCellIsNamed) {
  const std::string path = ::testing::TempDir() + "/identify_bad.csv";
  std::ofstream(path) << "t,u,z\n0,1,2\n";
  IdentifyData data;
  Status status = ReadCsvData(path, &data);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find("names no column y"), std::string::npos) << status.message();
  std::ofstream(path) << "t,u,y\n0,1,2\n0.1,abc,2\n";
  status = ReadCsvData(path, &data);
  EXPECT_NE(status.message().find("row 3, column u: 'abc' is not a number"), std::string::npos)
      << status.message();
}

TEST(IdentifyOptions, RefusesStartsOutsideOneToTheLimitInOneShape) {
  IdentifyOptions dut;
  std::string error;
  dut.starts = kMaxStarts;
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  dut.starts = kMaxStarts + 1;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_EQ(error, "starts = 1001 must be in [1, 1000]");
  dut.starts = 0;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_EQ(error, "starts = 0 must be in [1, 1000]");
}

}  // namespace
}  // namespace pidlab::identify
