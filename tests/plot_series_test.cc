// The workbench's plot series (pidlab/results/plot_series.h): the step response
// is the evaluation's own samples, the |S| curve peaks at the analysis's Ms,
// and the command and load response agree with the loop's steady state.

#include "pidlab/results/plot_series.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pidlab/results/spec_run.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "spec_build.h"  // internal to pidlab::tune: the steps tested one by one
#include "test_status.h"

namespace pidlab::results {
namespace {

// The evaluation of `spec` by the library pieces `pidlab evaluate` uses.
evaluation::Evaluation EvaluateDirectly(const nlohmann::json& spec_json) {
  spec::EvaluateSpec s;
  std::string error;
  EXPECT_TRUE(IsOk(spec::FromJson(spec_json, &s, nullptr)));
  s.plant.Normalize();
  Plant p;
  PidGains g;
  evaluation::LoopOptions options;
  EXPECT_TRUE(tune::BuildPlant(s.plant, spec::NameStyle::kKey, &p, &error) &&
              tune::BuildGains(s.gains, spec::NameStyle::kKey, &g, &error) &&
              tune::BuildLoopOptions(s.loop, spec::NameStyle::kKey, &options, &error))
      << error;
  evaluation::Evaluation ev;
  EXPECT_TRUE(IsOk(evaluation::Evaluate(p, g, options, evaluation::EvaluateOptions{}, &ev)));
  return ev;
}

nlohmann::json SeriesOf(const nlohmann::json& spec, nlohmann::json* result = nullptr) {
  nlohmann::json r, series;
  const Status status = EvaluateSpecJson(spec, &r, &series);
  EXPECT_TRUE(status.ok()) << status.message();
  if (result) *result = r;
  return series;
}

TEST(PlotSeries, StepResponseIsTheEvaluationsSamplesOnTheFiguresFrameBitForBit) {
  for (const nlohmann::json& spec :
       {nlohmann::json{{"plant", "double_integrator"}, {"gains", {3.9, 0.06, 4.9}}},
        nlohmann::json{{"plant", "oscillator"}, {"gains", {2, 1, 1.5}}, {"loop", "sampled"}},
        nlohmann::json{{"plant", "stepper_motor"}, {"gains", {20.8836, 26.607, 12.4866}}},
        // A fast rise and a slow integral tail: the frame's spacing is widened to 4000 intervals.
        nlohmann::json{{"plant", "custom"}, {"num", {1}}, {"den", {1, 1}}, {"gains", {1, 0.001, 0}}}}) {
    const nlohmann::json series = SeriesOf(spec);
    const nlohmann::json& frame = series["time_scale"];
    ASSERT_EQ(frame["source"], "plant") << spec << ": no horizon given, the figure's frame";
    EXPECT_LE(series["t"].size(), 4001u) << spec << frame;
    if (spec["plant"] == "custom") {
      EXPECT_NE(frame["reason"].get<std::string>().find("spaced for at most 4000 intervals"),
                std::string::npos)
          << frame;
    }
    nlohmann::json on_frame = spec;
    on_frame["horizon"] = frame["horizon_s"];
    on_frame["sample_time"] = frame["sample_time_s"];
    const evaluation::Evaluation ev = EvaluateDirectly(on_frame);
    ASSERT_EQ(series["y"].size(), ev.y.size()) << spec;
    for (std::size_t m = 0; m < ev.y.size(); ++m) {
      ASSERT_EQ(series["t"][m].get<double>(), ev.t[m]) << spec << " sample " << m;
      ASSERT_EQ(series["y"][m].get<double>(), ev.y[m]) << spec << " sample " << m;
    }
    EXPECT_EQ(series["u"].size(), ev.y.size()) << spec;
    EXPECT_EQ(series["load_y"].size(), ev.y.size()) << spec;
  }
}

TEST(PlotSeries, TheFrameFitsTheTransientAndAGivenHorizonIsKept) {
  nlohmann::json result;
  const nlohmann::json stepper =
      SeriesOf({{"plant", "stepper_motor"}, {"gains", {2.185, 97.62, 0.1356}}}, &result);
  EXPECT_LE(stepper["time_scale"]["horizon_s"].get<double>(), 2.0) << stepper["time_scale"];
  EXPECT_EQ(result["time_scale"]["source"], "eq. (4)") << "the numbers keep eq. (4)";
  const nlohmann::json thermal = SeriesOf({{"plant", "custom"},
                                           {"num", {2}},
                                           {"den", {60, 1}},
                                           {"delay", 8},
                                           {"gains", {1.9, 0.07, 5.6}},
                                           {"derivative_filter_ratio", 10}});
  EXPECT_GE(thermal["time_scale"]["horizon_s"].get<double>(), 100.0) << thermal["time_scale"];
  const nlohmann::json given =
      SeriesOf({{"plant", "double_integrator"}, {"gains", {3.9, 0.06, 4.9}}, {"horizon", 25}});
  EXPECT_EQ(given["t"].size(), 501u);
  EXPECT_EQ(given["time_scale"]["horizon_s"], 25.0);
}

TEST(PlotSeries, SensitivityPeakOnTheGridIsTheReportedMs) {
  for (const char* loop : {"continuous", "sampled"}) {
    nlohmann::json result;
    const nlohmann::json series =
        SeriesOf({{"plant", "oscillator"}, {"gains", {2, 1, 1.5}}, {"loop", loop}, {"dt", 0.01}}, &result);
    const std::vector<double> s = series["s"].get<std::vector<double>>();
    const double ms = result["robustness"]["ms"].get<double>();
    EXPECT_GT(ms, 1.0) << loop;
    EXPECT_NEAR(*std::max_element(s.begin(), s.end()), ms, 1e-9 * ms) << loop;
    EXPECT_EQ(series["ms"].get<double>(), ms) << loop;
    EXPECT_EQ(series["frequency_loop"], loop);
    EXPECT_EQ(series["w"].size(), s.size()) << loop;
    EXPECT_EQ(series["l_re"].size(), s.size()) << loop;
  }
}

TEST(PlotSeries, TheFrequencyGridSpansSixDecadesAroundTheCrossoverWhereMtPeaksAtDc) {
  // A slow thermal loop whose |T| peaks at DC: analysis puts Mt's frequency
  // near 1e-23 rad/s, which the grid leaves out rather than span 20 decades.
  nlohmann::json result;
  const nlohmann::json series =
      SeriesOf({{"plant", "custom"},
                {"num", {1}},
                {"den", {1000, 1}},
                {"delay", 100},
                {"gains", {0.3832272962062109, 0.0003790998403732822, 1198.2716840666376}},
                {"derivative_filter", 312.6791060890034}},
               &result);
  const std::vector<double> w = series["w"].get<std::vector<double>>();
  const double crossover = result["robustness"]["gain_crossover_rad_s"].get<double>();
  ASSERT_FALSE(w.empty());
  EXPECT_LT(result["robustness"]["mt_rad_s"].get<double>(), 1e-15) << "the case the grid must leave out";
  EXPECT_GE(w.front(), crossover * 1e-3 * (1 - 1e-9));
  EXPECT_LE(w.back(), crossover * 1e3 * (1 + 1e-9));
}

TEST(PlotSeries, CommandCancelsTheLoadStepAtSteadyState) {
  // With integral action, the unit step at the plant input ends with u = -1
  // and y = 0, on both loops.
  for (const char* loop : {"continuous", "sampled"}) {
    const nlohmann::json series = SeriesOf({{"plant", "oscillator"}, {"gains", {2, 1, 1.5}}, {"loop", loop}});
    EXPECT_NEAR(series["load_u"].back().get<double>(), -1.0, 1e-3) << loop;
    EXPECT_NEAR(series["load_y"].back().get<double>(), 0.0, 1e-3) << loop;
    // The step response's command settles where the plant holds y = 1: u = den(0)/num(0) = 1.
    EXPECT_NEAR(series["u"].back().get<double>(), 1.0, 1e-3) << loop;
  }
}

TEST(PlotSeries, TheLoadResponseAndTheCommandsOfADeadTimeLoopAreDrawnAsTheSampledLoopAtAFinePeriodSeesThem) {
  // The continuous loop with dead time: series.load_y (its samples are those
  // the load IAE sums), series.u and series.load_u are filled and agree with
  // the sampled loop at dt = 5e-4, an independent computation (ZOH and the
  // discrete PID).
  const nlohmann::json spec = {{"plant", "custom"},      {"num", {1}},
                               {"den", {1, 1}},          {"delay", 0.5},
                               {"gains", {1, 0.8, 0.1}}, {"derivative_filter_ratio", 10},
                               {"horizon", 20},          {"sample_time", 0.04}};
  nlohmann::json result;
  const nlohmann::json series = SeriesOf(spec, &result);
  for (const char* key : {"load_y", "u", "load_u"}) {
    ASSERT_TRUE(series[key].is_array()) << key << ": " << series["notes"];
    ASSERT_EQ(series[key].size(), series["t"].size()) << key;
  }
  double sum = 0.0;
  for (const auto& v : series["load_y"]) sum += std::abs(v.get<double>());
  EXPECT_NEAR(sum, result["load_iae"].get<double>(), 1e-9 * sum);
  nlohmann::json sampled = spec;
  sampled["loop"] = "sampled";
  sampled["dt"] = 5e-4;
  const nlohmann::json fine = SeriesOf(sampled);
  // u jumps at t = 0 (the filtered derivative's kick, kp + kd / tf = 11) and
  // decays with tf = 0.01 s: the sampled loop's u is held over dt, so the
  // first samples differ by the kick's decay over dt; from t = 0.2 s on, the
  // loops agree to the ZOH's error.
  const auto worst = [&](const char* key, std::size_t from) {
    double w = 0.0;
    for (std::size_t m = from; m < fine[key].size(); ++m)
      w = std::max(w, std::abs(fine[key][m].get<double>() - series[key][m].get<double>()));
    return w;
  };
  std::printf("dead-time series against the sampled loop at dt 5e-4: load_y %.3g, u %.3g, load_u %.3g\n",
              worst("load_y", 0), worst("u", 5), worst("load_u", 0));
  EXPECT_LT(worst("load_y", 0), 5e-4) << "the largest difference from the sampled loop at dt 5e-4";
  EXPECT_LT(worst("load_u", 0), 5e-3);
  EXPECT_LT(worst("u", 5), 5e-3);
  EXPECT_NEAR(series["u"][0].get<double>(), 1.0 + 0.1 / 0.01, 1e-12) << "u(0+) = kp b + kd c / tf, b = c = 1";
  EXPECT_NEAR(series["load_u"][0].get<double>(), 0.0, 1e-12)
      << "y is 0 at t = 0: the controller has not moved";
  EXPECT_GT(std::abs(series["load_y"][25].get<double>()), 0.1) << "the response has moved by t = 1 s";
  EXPECT_NEAR(series["load_y"].back().get<double>(), 0.0, 1e-3) << "integral action returns y to 0";
  EXPECT_NEAR(series["load_u"].back().get<double>(), -1.0, 1e-3) << "u cancels the unit load";
  EXPECT_NEAR(series["u"].back().get<double>(), 1.0, 1e-3) << "u holds y = 1 on a plant of DC gain 1";
  // \int y_L dt = 1 / ki with integral action (the final value theorem on
  // y_L / s), and y_L >= 0 here: the load's \int|e|dt is 1.25 but for the
  // tail past 20 s.
  EXPECT_NEAR(result["load_iae_continuous"].get<double>(), 1.0 / 0.8, 1e-4);
  EXPECT_NEAR(sum * 0.04, result["load_iae_continuous"].get<double>(), 1e-3);
}

TEST(PlotSeries, TheContinuousLoadIntegralIsMatlabsFigureForItsPidfOnTheThirdOrderLag) {
  // pidtune's PIDF on 1/(s+1)^3 at wc = 1 (kp 2.72, ki 0.985, kd 1.72, and
  // its filter Tf = 0.0316 s): MATLAB's documentation gives a load \int|e|dt
  // of 1.015 (issue 57); the sampled loop has none.
  nlohmann::json result;
  SeriesOf({{"plant", "custom"},
            {"num", {1}},
            {"den", {1, 3, 3, 1}},
            {"gains", {2.72, 0.985, 1.72}},
            {"derivative_filter", 0.0316}},
           &result);
  EXPECT_NEAR(result["load_iae_continuous"].get<double>(), 1.015, 1e-3);
  SeriesOf({{"plant", "custom"},
            {"num", {1}},
            {"den", {1, 3, 3, 1}},
            {"gains", {2.72, 0.985, 1.72}},
            {"derivative_filter", 0.0316},
            {"loop", "sampled"},
            {"dt", 0.01}},
           &result);
  EXPECT_TRUE(result["load_iae_continuous"].is_null());
}

TEST(PlotSeries, MonteCarloBandOfZeroSpreadIsTheNominalResponse) {
  nlohmann::json result;
  const nlohmann::json series = SeriesOf(
      {{"plant", "oscillator"}, {"gains", {2, 1, 1.5}}, {"monte_carlo", 4}, {"spread", 0.0}}, &result);
  const nlohmann::json& band = series["monte_carlo"];
  EXPECT_EQ(band["draws"], 4);
  EXPECT_EQ(band["stable"], 4);
  EXPECT_EQ(band["y_min"], series["y"]);
  EXPECT_EQ(band["y_max"], series["y"]);
  EXPECT_EQ(result["monte_carlo"]["samples"], 4);
}

TEST(PlotSeries, MonteCarloBandHoldsEveryDrawsResponse) {
  const nlohmann::json series =
      SeriesOf({{"plant", "oscillator"}, {"gains", {2, 1, 1.5}}, {"monte_carlo", 10}, {"spread", 0.2}});
  const nlohmann::json& band = series["monte_carlo"];
  ASSERT_EQ(band["y_min"].size(), series["y"].size());
  bool wider = false;
  for (std::size_t m = 0; m < series["y"].size(); ++m) {
    EXPECT_LE(band["y_min"][m].get<double>(), band["y_max"][m].get<double>());
    wider = wider || band["y_max"][m].get<double>() > band["y_min"][m].get<double>();
  }
  EXPECT_TRUE(wider);
}

TEST(PlotSeries, NonlinearMotorComesWithTheLinearModelOfEq3) {
  const nlohmann::json loop = {{"gains", {20.8836, 26.607, 12.4866}},
                               {"loop", "sampled"},
                               {"dt", 1e-4},
                               {"horizon", 0.01},
                               {"sample_time", 1e-4}};
  nlohmann::json nonlinear = loop, linear = loop;
  nonlinear["plant"] = "stepper_nonlinear";
  linear["plant"] = "stepper_motor";
  const nlohmann::json series = SeriesOf(nonlinear);
  const evaluation::Evaluation ev = EvaluateDirectly(linear);
  ASSERT_EQ(series["linear_y"].size(), ev.y.size());
  for (std::size_t m = 0; m < ev.y.size(); ++m) ASSERT_EQ(series["linear_y"][m].get<double>(), ev.y[m]) << m;
  EXPECT_TRUE(SeriesOf(linear)["linear_y"].is_null() || !SeriesOf(linear).contains("linear_y"));
}

TEST(PlotSeries, RefusesAGridOfFewerThanTenPoints) {
  PlotSeriesOptions options;
  options.frequency_points = 3;
  nlohmann::json series;
  const Status status = PlotSeries(Plant{}, PidGains{}, evaluation::LoopOptions{}, evaluation::Evaluation{},
                                   analysis::LoopAnalysis{}, options, &series);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("frequency_points 3"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace pidlab::results
