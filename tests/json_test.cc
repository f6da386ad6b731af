// The JSON builders of results/ (pidlab/results/results_json.h,
// pidlab/results/batch_json.h): the keys the command line and Python print,
// null for numbers JSON cannot hold, and the numbers themselves.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/results/batch_json.h"
#include "pidlab/results/results_json.h"

namespace pidlab::results {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(JsonNumber, IsNullForNaNAndInfinities) {
  EXPECT_TRUE(JsonNumber(kNaN).is_null());
  EXPECT_TRUE(JsonNumber(kInf).is_null());
  EXPECT_TRUE(JsonNumber(-kInf).is_null());
  EXPECT_EQ(JsonNumber(0.25).get<double>(), 0.25);
}

TEST(GainsJson, HoldsTheFourGainsUnderTheirNames) {
  const nlohmann::json j = ToJson(PidGains{1.5, 0.25, 0.125, 0.01});
  EXPECT_EQ(j.size(), 4u);
  EXPECT_EQ(j.at("kp").get<double>(), 1.5);
  EXPECT_EQ(j.at("ki").get<double>(), 0.25);
  EXPECT_EQ(j.at("kd").get<double>(), 0.125);
  EXPECT_EQ(j.at("tf").get<double>(), 0.01);
}

TEST(EvaluationJson, CarriesTheEvaluationsNumbersAndNullsAnUnstableLoopsObjectives) {
  Plant plant;
  plant.name = "custom";
  plant.tf = TransferFunction{{1.0}, {1.0, 0.0, 0.0}};  // 1/s^2
  evaluation::LoopOptions o;
  evaluation::Evaluation ev;
  ASSERT_TRUE(evaluation::Evaluate(plant, PidGains{2.0, 1.0, 1.5}, o, {}, &ev).ok());
  nlohmann::json j = ToJson(ev);
  for (const char* key : {"plant",
                          "plant_tf",
                          "gains",
                          "loop",
                          "reference",
                          "sample_time_s",
                          "horizon_s",
                          "samples",
                          "disturbance",
                          "stable",
                          "closed_loop_poles",
                          "pole_domain",
                          "iae",
                          "iae_per_unit",
                          "iae_undisturbed",
                          "load_iae",
                          "ise",
                          "itae",
                          "iae_continuous",
                          "rise_time_s",
                          "overshoot_pct",
                          "settling_time_s",
                          "peak",
                          "peak_time_s",
                          "final_value"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j.at("stable").get<bool>());
  EXPECT_EQ(j.at("iae").get<double>(), ev.iae);
  EXPECT_EQ(j.at("samples").get<long>(), 501);
  EXPECT_EQ(j.at("closed_loop_poles").size(), ev.stability.poles.size());
  ASSERT_TRUE(
      evaluation::Evaluate(plant, PidGains{2.0, 1.0, 0.0}, o, {}, &ev).ok());  // PI on 1/s^2: unstable
  j = ToJson(ev);
  EXPECT_FALSE(j.at("stable").get<bool>());
  EXPECT_TRUE(j.at("iae").is_null()) << "an unstable loop's +inf IAE is null, not a number";
}

tune::BatchResult Result(bool amigo_feasible, bool feasible, double ratio, double ms) {
  tune::BatchResult r;
  r.plant.family = "P1";
  r.plant.label = "P1 T=1";
  r.amigo_feasible = amigo_feasible;
  r.feasible = feasible;
  r.ratio = ratio;
  r.ms = ms;
  return r;
}

TEST(BatchTally, CountsWinsTiesAndLossesOnlyWhereBothMeetTheBound) {
  const std::vector<tune::BatchResult> results = {Result(true, true, 0.5, 1.39), Result(true, true, 1.0, 1.2),
                                                  Result(true, true, 1.1, 1.3), Result(false, true, 0.1, 1.4),
                                                  Result(true, false, kNaN, kNaN)};
  const tune::BatchTally t = tune::TallyBatch(results);
  EXPECT_EQ(t.plants, 5);
  EXPECT_EQ(t.amigo_feasible, 4);
  EXPECT_EQ(t.pidlab_feasible, 4);
  EXPECT_EQ(t.wins, 1);
  EXPECT_EQ(t.ties, 1);
  EXPECT_EQ(t.losses, 1);
  EXPECT_EQ(t.best_ratio, 0.5) << "the infeasible rule's plant does not count";
  EXPECT_EQ(t.worst_ratio, 1.1);
  EXPECT_EQ(t.max_ms, 1.4);
  const nlohmann::json j = BatchTallyJson(t);
  EXPECT_EQ(j.at("wins").get<int>(), 1);
  EXPECT_EQ(j.at("best_ratio").get<double>(), 0.5);
}

TEST(BatchTally, OfNoComparablePlantHasNullRatios) {
  const tune::BatchTally t = tune::TallyBatch({Result(false, false, kNaN, kNaN)});
  EXPECT_TRUE(std::isnan(t.best_ratio));
  EXPECT_TRUE(std::isnan(t.max_ms));
  const nlohmann::json j = BatchTallyJson(t);
  EXPECT_TRUE(j.at("best_ratio").is_null());
  EXPECT_TRUE(j.at("worst_ratio").is_null());
  EXPECT_TRUE(j.at("max_ms").is_null());
}

TEST(BatchResultJson, NamesTheRuleAndTheOptimumAndNullsMissingNumbers) {
  const nlohmann::json j = BatchResultJson(Result(true, false, kNaN, kNaN));
  for (const char* key : {"family", "parameter", "value", "label", "plant_tf", "delay_s", "model", "tau",
                          "dt_s", "horizon_s", "box", "amigo", "pidlab", "ratio", "wall_time_s", "message"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j.at("family").get<std::string>(), "P1");
  EXPECT_TRUE(j.at("ratio").is_null());
  EXPECT_TRUE(j.at("pidlab").at("ms").is_null());
  EXPECT_TRUE(j.at("amigo").at("feasible").get<bool>());
  for (const char* key : {"kp", "ki", "kd", "tf"})
    EXPECT_TRUE(j.at("pidlab").at("gains").contains(key)) << key;
}

}  // namespace
}  // namespace pidlab::results
