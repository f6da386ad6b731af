// identify --model auto's choice (identify.h's IdentifyAuto; docs/identify.md,
// "Choosing the model"): candidates with a parameter the record does not
// identify are set aside and say why, a kind the data rule out has its
// design's starts pruned by AIC, and the response every fit simulates gives
// DiscretePlant's bits.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/identify/identify.h"
#include "pidlab/plant_sim/discrete_plant.h"

namespace pidlab::identify {
namespace {

// The motor of bench/identify_motor_record.py: 4 e^(-0.025 s) / ((0.35 s +
// 1)(0.004 s + 1)) at dt 2 ms, a step at 0.1 s, its output quantised to
// 0.05 (a coarse encoder). The second lag, two samples long, hides behind
// the delay and the quantisation.
IdentifyData MotorStep() {
  const ProcessModel motor = ModelFromValues(ProcessModelKind::kP2D, {4.0, 0.35, 0.004, 0.025});
  IdentifyData d;
  for (int k = 0; k < 1501; ++k) {
    d.t.push_back(0.002 * k);
    d.u.push_back(k < 50 ? 0.0 : 1.0);
  }
  for (double y : SimulateModel(motor, d.u, 0.0, 0.002)) d.y.push_back(0.05 * std::round(y / 0.05));
  return d;
}

const AutoResult& MotorAuto() {
  static const AutoResult result = [] {
    AutoResult r;
    EXPECT_TRUE(IdentifyAuto(MotorStep(), IdentifyOptions{}, &r).ok());
    return r;
  }();
  return result;
}

const AutoCandidate& Candidate(const AutoResult& a, ProcessModelKind kind) {
  for (const AutoCandidate& c : a.candidates)
    if (c.kind == kind) return c;
  ADD_FAILURE() << "no candidate " << ToString(kind);
  return a.candidates.front();
}

// At a bound, Td at 0 excepted (a record without dead time).
bool AtABound(const IdentifyResult& r) {
  for (std::size_t i = 0; i < r.at_bound.size(); ++i)
    if (!r.at_bound[i].empty() && !(r.names[i] == "Td" && r.at_bound[i] == "lower")) return true;
  return false;
}

TEST(IdentifyAuto, SetsAsideAP2dWhoseSecondLagIsNotIdentifiableAndKeepsP1d) {
  const AutoResult& dut = MotorAuto();
  ASSERT_GE(dut.chosen, 0);
  const AutoCandidate& chosen = dut.candidates[static_cast<std::size_t>(dut.chosen)];
  EXPECT_EQ(chosen.kind, ProcessModelKind::kP1D) << dut.reason;
  EXPECT_TRUE(chosen.set_aside.empty()) << chosen.set_aside;
  EXPECT_NEAR(chosen.result.values[1], 0.35, 0.01);
  const AutoCandidate& p2d = Candidate(dut, ProcessModelKind::kP2D);
  ASSERT_TRUE(p2d.status.ok());
  EXPECT_EQ(p2d.set_aside.rfind("Tp2 is not identifiable (", 0), 0u) << p2d.set_aside;
  EXPECT_NE(p2d.set_aside.find("p1d describes the record without it"), std::string::npos) << p2d.set_aside;
  EXPECT_NE(dut.reason.find("set aside: p2d"), std::string::npos) << dut.reason;
}

TEST(IdentifyAuto, NeverChoosesAModelWithAParameterAtItsBoundAndSaysWhyEachWasSetAside) {
  const AutoResult& dut = MotorAuto();
  ASSERT_GE(dut.chosen, 0);
  EXPECT_FALSE(AtABound(dut.candidates[static_cast<std::size_t>(dut.chosen)].result));
  int at_bound = 0;
  for (const AutoCandidate& c : dut.candidates) {
    if (!c.status.ok() || !AtABound(c.result)) continue;
    ++at_bound;
    EXPECT_FALSE(c.set_aside.empty()) << ToString(c.kind) << " has a parameter at a bound";
  }
  EXPECT_GE(at_bound, 1) << "the motor's p2du runs Zeta to 1, its p1di Tp1 to dt/1000";
}

TEST(IdentifyAuto, SetsAsideAP2dzWhoseZeroMayCancelAPole) {
  const AutoCandidate& p2dz = Candidate(MotorAuto(), ProcessModelKind::kP2DZ);
  ASSERT_TRUE(p2dz.status.ok());
  ASSERT_FALSE(p2dz.result.not_identifiable.empty());
  EXPECT_EQ(p2dz.result.not_identifiable[0].parameter, "Tz");
  EXPECT_NE(p2dz.set_aside.find("may cancel"), std::string::npos) << p2dz.set_aside;
}

TEST(IdentifyAuto, PrunesTheStartsOfAKindTheDataRuleOutByAic) {
  const AutoResult& dut = MotorAuto();
  const AutoCandidate& p1di = Candidate(dut, ProcessModelKind::kP1DI);
  const AutoCandidate& p1d = Candidate(dut, ProcessModelKind::kP1D);
  ASSERT_TRUE(p1di.status.ok());
  EXPECT_GT(p1di.result.aic, p1d.result.aic + 10.0);
  EXPECT_GT(p1di.result.starts_skipped, 0);
  EXPECT_EQ(p1d.result.starts_skipped, 0) << "the first kind has no AIC to beat";
  EXPECT_EQ(p1di.result.starts + p1di.result.starts_skipped, p1d.result.starts)
      << "the ARX start and the 16 of the design, run or skipped";
}

TEST(IdentifyAuto, ChoosesTheSameFitAsIdentifyOfThatKind) {
  const AutoCandidate& p1d = Candidate(MotorAuto(), ProcessModelKind::kP1D);
  IdentifyResult alone;
  ASSERT_TRUE(Identify(MotorStep(), ProcessModelKind::kP1D, IdentifyOptions{}, &alone).ok());
  EXPECT_NEAR(p1d.result.cost, alone.cost, 1e-12 * alone.cost);
  for (std::size_t i = 0; i < alone.values.size(); ++i)
    EXPECT_NEAR(p1d.result.values[i], alone.values[i], 1e-9 * std::abs(alone.values[i])) << alone.names[i];
}

TEST(Identify, NamesASecondLagTheRecordDoesNotIdentifyAndTheSmallerModel) {
  IdentifyResult dut;
  ASSERT_TRUE(Identify(MotorStep(), ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  ASSERT_EQ(dut.not_identifiable.size(), 1u);
  EXPECT_EQ(dut.not_identifiable[0].parameter, "Tp2");
  EXPECT_EQ(dut.not_identifiable[0].simpler_model, "p1d");
  bool said = false;
  for (const std::string& w : dut.warnings)
    said = said || (w.rfind("Tp2 is not identifiable (", 0) == 0 &&
                    w.find("the p1d model fits as well") != std::string::npos);
  EXPECT_TRUE(said) << "no warning names Tp2 and p1d";
}

TEST(Identify, FindsEveryParameterOfAWellExcitedP2dIdentifiable) {
  // The same motor under a square wave of 0.3 s levels: its second lag shows.
  IdentifyData d = MotorStep();
  for (std::size_t k = 0; k < d.u.size(); ++k) d.u[k] = (k / 150) % 2 == 0 ? 0.0 : 1.0;
  const ProcessModel motor = ModelFromValues(ProcessModelKind::kP2D, {4.0, 0.35, 0.004, 0.025});
  d.y = SimulateModel(motor, d.u, 0.0, 0.002);
  IdentifyResult dut;
  ASSERT_TRUE(Identify(d, ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  EXPECT_TRUE(dut.not_identifiable.empty()) << dut.not_identifiable[0].reason;
  EXPECT_NEAR(dut.values[2], 0.004, 1e-6);
}

TEST(SimulateModel, GivesDiscretePlantsBitsForEveryOrderAndDelay) {
  std::vector<double> u;
  for (int k = 0; k < 300; ++k) u.push_back(std::sin(0.05 * k) + (k % 17 < 8 ? 0.5 : -0.25));
  const std::vector<ProcessModel> models = {
      ModelFromValues(ProcessModelKind::kP1D, {1.5, 0.7, 0.0}),
      ModelFromValues(ProcessModelKind::kP1D, {1.5, 0.7, 0.1}),         // a whole sample
      ModelFromValues(ProcessModelKind::kP2D, {2.0, 0.9, 0.2, 0.137}),  // split
      ModelFromValues(ProcessModelKind::kP2DZ, {2.0, 0.9, 0.2, -0.3, 0.05}),
      ModelFromValues(ProcessModelKind::kTf, {1.2, 0.8, 0.5, 2.1, 2.6, 0.37}, 3, 1),
  };
  for (const ProcessModel& m : models) {
    DiscretePlant plant(m.ToTransferFunction(), 0.1, m.delay_s());
    const std::vector<double> dut = SimulateModel(m, u, 0.25, 0.1);
    for (std::size_t k = 0; k < u.size(); ++k) {
      ASSERT_EQ(dut[k], plant.Output()) << ToString(m.kind) << " sample " << k;
      plant.Step(u[k] - 0.25);
    }
  }
}

}  // namespace
}  // namespace pidlab::identify
