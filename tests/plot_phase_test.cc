// The phase of L the workbench serves (pidlab/results/plot_series.h,
// l_phase_deg; analysis::LoopPhaseDeg) on loops with dead time: continuous
// along the grid, on a grid that resolves e^{-jwL}, and arg L at every point.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/results/plot_series.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/spec/json.h"
#include "pidlab/tune/problem.h"
#include "test_status.h"

namespace pidlab::results {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct DeadTimeLoop {
  std::string name;
  nlohmann::json spec;
};

// Stable PI(D) loops (SIMC-like gains) on the plants of issue 58, each
// continuous and sampled (a dt the delay is a whole number of steps of, and
// one it is not).
std::vector<DeadTimeLoop> DeadTimeLoops() {
  const std::vector<DeadTimeLoop> plants = {
      {"FOPDT e^-2s/(5s+1)",
       {{"plant", "custom"}, {"num", {1}}, {"den", {5, 1}}, {"delay", 2}, {"gains", {1.25, 0.25, 0}}}},
      {"tank 0.8 e^-150s/((120s+1)(10s+1))",
       {{"plant", "custom"},
        {"num", {0.8}},
        {"den", {1200, 130, 1}},
        {"delay", 150},
        {"gains", {0.5, 0.5 / 120, 5}},
        {"derivative_filter_ratio", 10}}},
      {"motor 4 e^-0.025s/((0.35s+1)(0.004s+1))",
       {{"plant", "custom"},
        {"num", {4}},
        {"den", {0.0014, 0.354, 1}},
        {"delay", 0.025},
        {"gains", {1.75, 8.75, 0.007}},
        {"derivative_filter_ratio", 10}}},
      {"integrating e^-s/s",
       {{"plant", "custom"}, {"num", {1}}, {"den", {1, 0}}, {"delay", 1}, {"gains", {0.5, 0.0625, 0}}}},
  };
  const std::vector<std::vector<double>> dts = {{0.25, 0.3}, {1.0, 4.0}, {1e-3, 4e-4 * 3}, {0.1, 0.07}};
  std::vector<DeadTimeLoop> loops;
  for (std::size_t i = 0; i < plants.size(); ++i) {
    loops.push_back({plants[i].name + ", continuous", plants[i].spec});
    for (double dt : dts[i]) {
      DeadTimeLoop sampled{plants[i].name + ", sampled at dt " + std::to_string(dt), plants[i].spec};
      sampled.spec["loop"] = "sampled";
      sampled.spec["dt"] = dt;
      loops.push_back(sampled);
    }
  }
  return loops;
}

// The delay whose phase is -w delay exactly: L, or the sampled loop's whole
// steps d dt (the fraction of a step is in the ZOH plant's rational part).
double PureDelay(const nlohmann::json& spec) {
  const double delay = spec["delay"].get<double>();
  if (!spec.contains("loop")) return delay;
  const double dt = spec["dt"].get<double>();
  return static_cast<double>(SplitDelay(delay, dt).steps) * dt;
}

struct Served {
  nlohmann::json result, series;
  std::vector<double> w, phase, re, im;
};

Served Serve(const nlohmann::json& spec) {
  Served s;
  const Status status = EvaluateSpecJson(spec, &s.result, &s.series);
  EXPECT_TRUE(IsOk(status)) << spec;
  if (!status.ok()) return s;
  s.w = s.series["w"].get<std::vector<double>>();
  s.phase = s.series["l_phase_deg"].get<std::vector<double>>();
  s.re = s.series["l_re"].get<std::vector<double>>();
  s.im = s.series["l_im"].get<std::vector<double>>();
  return s;
}

// The served phase at w, linear between the grid's points.
double PhaseAt(const Served& s, double w) {
  const auto it = std::lower_bound(s.w.begin(), s.w.end(), w);
  if (it == s.w.begin()) return s.phase.front();
  if (it == s.w.end()) return s.phase.back();
  const std::size_t i = static_cast<std::size_t>(it - s.w.begin());
  const double f = (w - s.w[i - 1]) / (s.w[i] - s.w[i - 1]);
  return s.phase[i - 1] + f * (s.phase[i] - s.phase[i - 1]);
}

TEST(PlotPhase, DeadTimeLoopsPhaseIsContinuousResolvedAndArgLAtEveryPoint) {
  for (const DeadTimeLoop& loop : DeadTimeLoops()) {
    SCOPED_TRACE(loop.name);
    const Served s = Serve(loop.spec);
    ASSERT_TRUE(s.result["stable"].get<bool>()) << "the case is a stable loop";
    ASSERT_EQ(s.phase.size(), s.w.size());
    ASSERT_EQ(s.re.size(), s.w.size());
    const nlohmann::json& rb = s.result["robustness"];
    std::vector<double> crossovers = rb["gain_crossovers_rad_s"].get<std::vector<double>>();
    for (double x : rb["phase_crossovers_rad_s"].get<std::vector<double>>()) crossovers.push_back(x);
    ASSERT_FALSE(crossovers.empty());
    EXPECT_EQ(s.series["gain_crossovers_rad_s"], rb["gain_crossovers_rad_s"]);
    EXPECT_EQ(s.series["phase_crossover_rad_s"], rb["phase_crossover_rad_s"]);
    const double near_lo = *std::min_element(crossovers.begin(), crossovers.end()) / 3.0;
    const double near_hi = *std::max_element(crossovers.begin(), crossovers.end()) * 3.0;
    const double delay = PureDelay(loop.spec);
    double largest_step = 0.0, fewest_per_turn = 1e300, worst_mod = 0.0;
    int near = 0;
    for (std::size_t i = 0; i < s.w.size(); ++i) {
      ASSERT_TRUE(std::isfinite(s.phase[i])) << "w " << s.w[i];
      const double arg = std::atan2(s.im[i], s.re[i]) * 180.0 / kPi;
      worst_mod = std::max(worst_mod, std::abs(std::remainder(s.phase[i] - arg, 360.0)));
      if (i == 0) continue;
      largest_step = std::max(largest_step, std::abs(s.phase[i] - s.phase[i - 1]));
      if (s.w[i - 1] >= near_lo && s.w[i] <= near_hi) {
        ++near;
        fewest_per_turn = std::min(fewest_per_turn, 2.0 * kPi / ((s.w[i] - s.w[i - 1]) * delay));
      }
    }
    std::printf(
        "%-58s %5zu points, phase %8.1f..%6.1f deg, largest step %5.1f deg, >= %.2f points per "
        "turn of the delay near the crossovers, |phase - arg L| mod 360 <= %.1e deg\n",
        loop.name.c_str(), s.w.size(), *std::min_element(s.phase.begin(), s.phase.end()),
        *std::max_element(s.phase.begin(), s.phase.end()), largest_step, fewest_per_turn, worst_mod);
    EXPECT_LE(largest_step, 180.0) << "no neighbouring points more than half a turn apart";
    EXPECT_GT(near, 10) << "grid points near the crossovers";
    EXPECT_GE(fewest_per_turn, 4.0 * (1.0 - 1e-9))
        << "points per 2 pi of the delay's phase near the crossovers";
    EXPECT_LE(worst_mod, 1e-6) << "the served phase is arg L modulo 360";
    // The continuous phase starts on the asymptote's branch, so the loop's
    // first phase crossover is where it passes -180 degrees, not -540.
    const double first_phase_crossover =
        *std::min_element(rb["phase_crossovers_rad_s"].begin(), rb["phase_crossovers_rad_s"].end());
    EXPECT_NEAR(PhaseAt(s, first_phase_crossover), -180.0, 2.0) << "at " << first_phase_crossover << " rad/s";
  }
}

TEST(PlotPhase, ALoopWithoutDeadTimeKeepsTheLogGridAndItsUnwrappedPhase) {
  const Served s = Serve({{"plant", "custom"},
                          {"num", {1}},
                          {"den", {1, 3, 3, 1}},
                          {"gains", {2.72, 0.985, 1.72}},
                          {"derivative_filter", 0.0316}});
  ASSERT_FALSE(s.w.empty());
  EXPECT_LE(s.w.size(), 303u) << "300 points and the peaks' frequencies, none inserted";
  // PID on (s+1)^-3 with its filter: -90 at DC (the integrator), -270 at infinity (C is flat past its
  // filter).
  EXPECT_NEAR(s.phase.front(), -90.0, 1.0);
  EXPECT_NEAR(s.phase.back(), -270.0, 3.0);
  for (std::size_t i = 1; i < s.w.size(); ++i)
    EXPECT_LE(std::abs(s.phase[i] - s.phase[i - 1]), 30.0) << s.w[i];
}

TEST(PlotPhase, AGridOverThePointsCapIsCutBelowItsTopWithANote) {
  const nlohmann::json spec = {{"plant", "custom"},
                               {"num", {0.8}},
                               {"den", {1200, 130, 1}},
                               {"delay", 150},
                               {"gains", {0.5, 0.5 / 120, 5}},
                               {"derivative_filter_ratio", 10}};
  spec::EvaluateSpec s;
  tune::BuildOptions build;
  ASSERT_TRUE(IsOk(spec::FromJson(spec, &s, &build.given)));
  tune::EvaluationProblem problem;
  ASSERT_TRUE(IsOk(tune::BuildEvaluation(s, build, &problem)));
  tune::EvaluationResult r;
  ASSERT_TRUE(IsOk(tune::RunEvaluation(problem, tune::EvaluationRunOptions{}, &r)));
  PlotSeriesOptions options;
  options.max_frequency_points = 400;
  nlohmann::json series;
  ASSERT_TRUE(IsOk(
      PlotSeries(problem.plant, problem.gains, problem.loop, r.evaluation, r.analysis, options, &series)));
  const std::vector<double> w = series["w"].get<std::vector<double>>();
  const std::vector<double> phase = series["l_phase_deg"].get<std::vector<double>>();
  EXPECT_LE(w.size(), 400u);
  EXPECT_LT(w.back(), r.analysis.gain_crossover_rad_s * 1e3 * (1.0 - 1e-6))
      << "cut below the six decades' top";
  EXPECT_GT(w.back(), r.analysis.phase_crossover_rad_s * 3.0) << "the crossovers stay in";
  for (std::size_t i = 1; i < w.size(); ++i) ASSERT_LE(std::abs(phase[i] - phase[i - 1]), 180.0) << w[i];
  bool noted = false;
  for (const auto& note : series["notes"])
    noted = noted || note.get<std::string>().find("the frequency plots end at") != std::string::npos;
  EXPECT_TRUE(noted) << series["notes"];
}

TEST(PlotPhase, RefusesACapBelowTheGrid) {
  PlotSeriesOptions options;
  options.max_frequency_points = 100;
  nlohmann::json series;
  const Status status = PlotSeries(Plant{}, PidGains{}, evaluation::LoopOptions{}, evaluation::Evaluation{},
                                   analysis::LoopAnalysis{}, options, &series);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("max_frequency_points 100"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace pidlab::results
