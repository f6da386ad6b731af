// pidlab::identify on records that least squares from u[0] gets wrong: a
// sensor's dropouts (a robust loss) and a record that starts at rest at
// u = 0 under a nonzero first input (docs/identify.md, "Robust losses for
// dropouts", "Step tests, bounds and real records").

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "identify_records.h"
#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {
using test::kDt;
using test::StepRichInput;

ProcessModel P1d() {
  ProcessModel m;
  m.kind = ProcessModelKind::kP1D;
  m.kp = 2.5, m.tp1_s = 3.1, m.td_s = 0.37;
  return m;
}

// The worst |estimate / truth - 1| over the parameters.
double WorstRelativeError(const IdentifyResult& r, const ProcessModel& truth) {
  const std::vector<double> expected = ParameterValues(truth);
  double worst = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i)
    worst = std::max(worst, std::abs(r.values.at(i) / expected[i] - 1.0));
  return worst;
}

// 400 samples of the P1D's response to the step-rich input from rest at
// u = 0, y0 = 2, with tiny noise (1e-4) and 2 % of the samples (8, seeded)
// dropped out to y + 10.
IdentifyData RecordWithDropouts(std::vector<int>* dropouts) {
  const std::size_t n = 400;
  const std::vector<double> u = StepRichInput(n, 7);
  const std::vector<double> y = SimulateModel(P1d(), u, 0.0, kDt);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1e-4);
  std::vector<int> all(n);
  for (std::size_t k = 0; k < n; ++k) all[k] = static_cast<int>(k);
  std::shuffle(all.begin(), all.end(), rng);
  dropouts->assign(all.begin(), all.begin() + n / 50);
  std::sort(dropouts->begin(), dropouts->end());
  IdentifyData data;
  for (std::size_t k = 0; k < n; ++k) {
    data.t.push_back(static_cast<double>(k) * kDt);
    data.u.push_back(u[k]);
    const bool dropped = std::binary_search(dropouts->begin(), dropouts->end(), static_cast<int>(k));
    data.y.push_back(2.0 + y[k] + noise(rng) + (dropped ? 10.0 : 0.0));
  }
  return data;
}

TEST(RobustLoss, CauchyRecoversAP1dWithTwoPercentDropoutsWithinOnePercentWhereL2MissesByMoreThanFive) {
  std::vector<int> dropouts;
  const IdentifyData data = RecordWithDropouts(&dropouts);
  IdentifyResult l2, dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &l2).ok());
  IdentifyOptions options;
  options.loss = Loss::kCauchy;
  const Status status = Identify(data, ProcessModelKind::kP1D, options, &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_GT(WorstRelativeError(l2, P1d()), 0.05);
  EXPECT_LT(WorstRelativeError(dut, P1d()), 0.01);
  EXPECT_EQ(dut.loss, Loss::kCauchy);
  EXPECT_GT(dut.loss_scale, 0.0);
  EXPECT_NE(dut.loss_scale_source.find("l2 fit's residuals"), std::string::npos) << dut.loss_scale_source;
  // Exactly the dropouts are down-weighted, and the cost is the loss's.
  EXPECT_EQ(dut.downweighted, dropouts);
  ASSERT_EQ(dut.weights.size(), data.y.size());
  double cost = 0.0;
  for (double r : dut.residuals)
    cost += 0.5 * dut.loss_scale * dut.loss_scale * std::log1p(r * r / (dut.loss_scale * dut.loss_scale));
  EXPECT_NEAR(dut.cost, cost, 1e-9 * cost);
  EXPECT_TRUE(l2.downweighted.empty());
}

TEST(RobustLoss, HuberWithAGivenScaleDownWeightsTheDropoutsAndSaysTheScaleWasGiven) {
  std::vector<int> dropouts;
  const IdentifyData data = RecordWithDropouts(&dropouts);
  IdentifyOptions options;
  options.loss = Loss::kHuber;
  options.loss_scale = 0.01;
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, options, &dut).ok());
  EXPECT_EQ(dut.loss_scale, 0.01);
  EXPECT_EQ(dut.loss_scale_source, "given");
  EXPECT_EQ(dut.downweighted, dropouts);
  EXPECT_LT(WorstRelativeError(dut, P1d()), 0.01);
}

TEST(IdentifyOptions, ALossScaleThatIsNotPositiveOrComesWithL2IsRefusedByName) {
  IdentifyOptions options;
  options.loss = Loss::kCauchy;
  std::string why;
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(), 2e12}) {
    options.loss_scale = bad;
    EXPECT_FALSE(options.IsValid(&why)) << bad;
    EXPECT_EQ(why.rfind("loss_scale = ", 0), 0u) << why;
  }
  options.loss = Loss::kL2;
  options.loss_scale = 1.0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("not l2"), std::string::npos) << why;
}

TEST(RobustLoss, NamesParseAndPrintBack) {
  for (Loss loss : {Loss::kL2, Loss::kHuber, Loss::kCauchy}) {
    Loss back = Loss::kL2;
    EXPECT_TRUE(ParseLoss(ToString(loss), &back));
    EXPECT_EQ(back, loss);
  }
  Loss v;
  EXPECT_FALSE(ParseLoss("tukey", &v));
}

// A PRBS of +-1 (its first level +1, levels held 3 to 12 samples) through
// `model` from rest at u = 0, y0 = 3, noise-free.
IdentifyData PrbsFromRestAtZero(const ProcessModel& model, double rest_u = 0.0) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> hold(3, 12);
  std::vector<double> u;
  for (double level = 1.0; u.size() < 300; level = -level)
    for (int i = hold(rng); i > 0 && u.size() < 300; --i) u.push_back(level);
  const std::vector<double> y = SimulateModel(model, u, rest_u, kDt);
  IdentifyData data;
  for (std::size_t k = 0; k < u.size(); ++k) {
    data.t.push_back(static_cast<double>(k) * kDt);
    data.u.push_back(u[k]);
    data.y.push_back(3.0 + y[k]);
  }
  return data;
}

TEST(Rest, APrbsThatStartsAtRestAtZeroIsFittedFromZeroWithoutU0ToOnePartInAMillion) {
  const IdentifyData data = PrbsFromRestAtZero(P1d());
  IdentifyResult dut;
  const Status status = Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_LT(WorstRelativeError(dut, P1d()), 1e-6);
  EXPECT_EQ(dut.u0, 0.0);
  EXPECT_EQ(dut.u0_source.rfind("at rest at u = 0", 0), 0u) << dut.u0_source;
  ASSERT_EQ(dut.rest_hypotheses.size(), 2u);
  EXPECT_EQ(dut.rest_hypotheses[0].u0, 1.0);
  EXPECT_EQ(dut.rest_hypotheses[1].u0, 0.0);
  EXPECT_LT(dut.rest_hypotheses[1].aic, dut.rest_hypotheses[0].aic);
}

TEST(Rest, ARecordThatRestsUnderItsFirstInputKeepsU0AtThatInput) {
  // The same PRBS, the plant at rest under u = +1 before the record.
  const IdentifyData data = PrbsFromRestAtZero(P1d(), 1.0);
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, IdentifyOptions{}, &dut).ok());
  EXPECT_LT(WorstRelativeError(dut, P1d()), 1e-6);
  EXPECT_EQ(dut.u0, 1.0);
  EXPECT_EQ(dut.u0_source.rfind("at rest under its first input u[0] = 1", 0), 0u) << dut.u0_source;
}

TEST(Rest, AGivenU0IsUsedAsGivenWithoutHypotheses) {
  const IdentifyData data = PrbsFromRestAtZero(P1d());
  IdentifyOptions options;
  options.u0 = 1.0;
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP1D, options, &dut).ok());
  EXPECT_EQ(dut.u0, 1.0);
  EXPECT_EQ(dut.u0_source, "given");
  EXPECT_TRUE(dut.rest_hypotheses.empty());
  EXPECT_LT(dut.fit_percent, 99.0);  // the wrong rest, as given
}

TEST(Rest, AutoFitsEveryKindAtTheRestTheRecordImplies) {
  const IdentifyData data = PrbsFromRestAtZero(P1d());
  IdentifyOptions options;
  options.starts = 4;
  AutoResult dut;
  ASSERT_TRUE(IdentifyAuto(data, options, &dut).ok());
  const IdentifyResult& chosen = dut.candidates.at(static_cast<std::size_t>(dut.chosen)).result;
  EXPECT_EQ(ToString(chosen.model.kind), "p1d");
  EXPECT_LT(WorstRelativeError(chosen, P1d()), 1e-6);
  for (const AutoCandidate& c : dut.candidates) {
    if (!c.status.ok()) continue;
    EXPECT_EQ(c.result.rest_hypotheses.size(), 2u) << ToString(c.kind);
  }
  EXPECT_EQ(chosen.u0, 0.0);
}

}  // namespace
}  // namespace pidlab::identify
