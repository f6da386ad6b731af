// The search box from the plant, at_bounds, and the AMIGO test batch
// (pidlab/tune/search_box.h, pidlab/tune/batch.h).

#include "pidlab/tune/batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "pidlab/tune/search_box.h"
#include "pidlab/tune/tune.h"
#include "spec_build.h"  // internal to pidlab::tune: the steps tested one by one
#include "test_status.h"

namespace pidlab::tune {
namespace {

Plant Fopdt(double t, double l) {
  Plant p;
  std::string error;
  EXPECT_TRUE(IsOk(MakeCustomPlant({1.0}, {t, 1.0}, &p)));
  p.delay_s = l;
  return p;
}

TEST(SearchBox, OfAnFopdtIsTenTimesAmigosLargestPidGain) {
  // T = L = 1: AMIGO PID K = 0.65, Ti = 1.2/1.1, Td = 0.5/1.3, so ki = 0.5958 < kp.
  SearchBox dut;
  ASSERT_TRUE(PlantSearchBox(Fopdt(1.0, 1.0), &dut).ok());
  EXPECT_EQ(dut.source, "plant");
  EXPECT_EQ(dut.lower, 0.0);
  EXPECT_NEAR(dut.upper, 6.5, 1e-12);
}

TEST(SearchBox, ScalesWithThePlantsGain) {
  Plant p = Fopdt(1.0, 1.0);
  p.tf.num = {0.01};
  SearchBox dut;
  ASSERT_TRUE(PlantSearchBox(p, &dut).ok());
  EXPECT_NEAR(dut.upper, 650.0, 1e-9);
}

TEST(SearchBox, KeepsThePapersBoxOnThePapersPlants) {
  for (const char* name : {"double_integrator", "oscillator", "stepper_motor"}) {
    Plant p;
    std::string error;
    ASSERT_TRUE(IsOk(MakePlant(name, StepperMotorParameters{}, &p)));
    SearchBox dut;
    EXPECT_FALSE(PlantSearchBox(p, &dut).ok()) << name;
    EXPECT_EQ(dut.upper, 30.0) << name;
    EXPECT_EQ(dut.source, "default") << name;
  }
}

TEST(SearchBox, ResolvedIntoTheSpecOnlyWhenNoBoundsAreGiven) {
  spec::TuningSpec s;
  s.plant.num = {1.0};
  s.plant.den = {1.0, 3.0, 3.0, 1.0};
  s.plant.Normalize();
  spec::TuningSpec given = s;
  EXPECT_EQ(ResolveSearchBox(&s, {}).source, "plant");
  EXPECT_NEAR(s.tune.bounds.second, 6.5, 1e-4);  // (s + 1)^3: FOPDT T = L = 1.5 (roots to 1e-5), kp = 0.65
  EXPECT_EQ(ResolveSearchBox(&given, {"bounds"}).source, "given");
  EXPECT_EQ(given.tune.bounds.second, 30.0);
  spec::TuningSpec rule = given;
  rule.tune.method = "amigo";
  ResolveSearchBox(&rule, {});
  EXPECT_EQ(rule.tune.bounds.second, 30.0);
}

TEST(AtBounds, NamesEveryGainOnAnEnd) {
  EXPECT_EQ(GainsAtBounds(PidGains{30.0, 30.0, 0.5}, 0.0, 30.0),
            (std::vector<std::string>{"kp_hi", "ki_hi"}));
  EXPECT_EQ(GainsAtBounds(PidGains{1.0, 0.0, 0.0}, 0.0, 30.0), (std::vector<std::string>{"ki_lo", "kd_lo"}));
  EXPECT_TRUE(GainsAtBounds(PidGains{1.0, 2.0, 3.0}, 0.0, 30.0).empty());
}

TEST(AtBounds, TheRobustDoubleIntegratorSaysItsGainsLieOnTheBox) {
  Plant p;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &p)));
  TuneOptions o;
  ApplyRobustPreset(&o);
  TuneSummary s;
  ASSERT_TRUE(IsOk(Tune(p, o, &s)));
  ASSERT_TRUE(s.stable);
  EXPECT_NE(std::find(s.at_bounds.begin(), s.at_bounds.end(), "kp_hi"), s.at_bounds.end());
  EXPECT_NE(std::find(s.at_bounds.begin(), s.at_bounds.end(), "ki_hi"), s.at_bounds.end());
}

TEST(TuneStart, ANelderMeadStartOutsideTheBoxIsInvalid) {
  TuneOptions o;
  o.method = TuneMethod::kNelderMead;
  o.start = {1.0, 40.0, 0.0};
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("start"), std::string::npos);
}

TEST(TestBatch, HoldsTheNineFamiliesOverTheirGrids) {
  std::vector<BatchPlant> dut;
  ASSERT_TRUE(TestBatchPlants("amigo", &dut));
  EXPECT_EQ(dut.size(), 133u);
  std::set<std::string> families;
  for (const BatchPlant& p : dut) {
    families.insert(p.family);
    std::string error;
    EXPECT_TRUE(p.plant.tf.IsValid(&error)) << p.plant.name << ": " << error;
  }
  EXPECT_EQ(families.size(), 9u);
  EXPECT_FALSE(TestBatchPlants("foo", &dut));
}

TEST(TestBatch, SelectsFamiliesAndRefusesAnUnknownOne) {
  std::vector<BatchPlant> all, dut;
  ASSERT_TRUE(TestBatchPlants("amigo", &all));
  ASSERT_TRUE(SelectFamilies(all, {"P4", "P9"}, &dut).ok());
  EXPECT_EQ(dut.size(), 16u);
  const Status bad = SelectFamilies(all, {"P10"}, &dut);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("P10"), std::string::npos);
}

TEST(TestBatch, AmigosGainsOnP1WithTEqualOneAreTheClosedForm) {
  std::vector<BatchPlant> all, p1;
  ASSERT_TRUE(TestBatchPlants("amigo", &all));
  ASSERT_TRUE(SelectFamilies(all, {"P1"}, &p1).ok());
  const auto it = std::find_if(p1.begin(), p1.end(), [](const BatchPlant& p) { return p.value == 1.0; });
  ASSERT_NE(it, p1.end());
  BatchOptions o;
  o.search_evaluations = 60;
  o.polish_evaluations = 30;
  BatchResult dut;
  ASSERT_TRUE(RunBatchPlant(*it, o, &dut).ok());
  EXPECT_NEAR(dut.amigo_k, 0.65, 1e-12);
  EXPECT_NEAR(dut.amigo_ti_s, 1.2 / 1.1, 1e-12);
  EXPECT_NEAR(dut.amigo_td_s, 0.5 / 1.3, 1e-12);
  EXPECT_NEAR(dut.amigo_gains.tf, 0.5 / 1.3 / 10.0, 1e-12);  // Tf = Td / N, N = 10
  EXPECT_NEAR(dut.tau, 0.5, 1e-12);
  EXPECT_NEAR(dut.box_upper, 6.5, 1e-12);
}

// pidlab never loses to a feasible AMIGO and meets Ms <= 1.4 (tolerance
// 1e-3) by the full analysis, on a few plants of different kinds.
TEST(TestBatch, PidlabMeetsMsAndNeverLosesToAFeasibleAmigo) {
  std::vector<BatchPlant> all, dut;
  ASSERT_TRUE(TestBatchPlants("amigo", &all));
  for (const BatchPlant& p : all)
    if ((p.family == "P4" && p.value == 3.0) || (p.family == "P8" && p.value == 0.5) ||
        (p.family == "P6" && p.value == 0.5))
      dut.push_back(p);
  ASSERT_EQ(dut.size(), 3u);
  BatchOptions o;
  o.search_evaluations = 300;
  o.polish_evaluations = 150;
  std::vector<BatchResult> results;
  ASSERT_TRUE(RunBatch(dut, o, &results).ok());
  for (const BatchResult& r : results) {
    ASSERT_TRUE(r.feasible) << r.plant.plant.name << ": " << r.message;
    EXPECT_LE(r.ms, 1.4 + 1e-3) << r.plant.plant.name;
    if (r.amigo_feasible) {
      EXPECT_LE(r.load_iae, r.amigo_load_iae) << r.plant.plant.name;
    }
  }
}

}  // namespace
}  // namespace pidlab::tune
