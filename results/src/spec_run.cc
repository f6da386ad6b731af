#include "pidlab/results/spec_run.h"

#include <set>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/results/plot_series.h"
#include "pidlab/results/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/spec_build.h"

namespace pidlab::results {
using analysis::AnalyzeLoop;
using analysis::LoopAnalysis;
using analysis::LoopAnalysisOptions;
using analysis::LoopBounds;
using evaluation::Evaluate;
using evaluation::EvaluateOptions;
using evaluation::Evaluation;
using evaluation::LoopOptions;
using spec::NameStyle;

namespace {

// `evaluate --monte-carlo`'s object in (*result)["monte_carlo"] and, with
// `series`, the band of the draws' step responses in (*series)["monte_carlo"].
Status AddMonteCarlo(const spec::EvaluateSpec& s, const Plant& p, const PidGains& g,
                     const LoopOptions& options, nlohmann::json* result, nlohmann::json* series) {
  std::string error;
  StepperMotorParameters stepper;
  analysis::MonteCarloOptions mc;
  if (!(tune::BuildStepperParameters(s.plant, NameStyle::kKey, &stepper, &error) &&
        tune::BuildMonteCarlo(s, NameStyle::kKey, &mc, &error)))
    return Status::InvalidInput(error);
  if (p.delay_s > 0.0 && !p.model)
    return Status::InvalidInput(
        "monte_carlo with delay is not supported yet (its draws are undelayed plants)");
  if (p.nonlinear)
    return Status::InvalidInput("monte_carlo draws linear plants: it does not take plant '" + p.name + "'");
  const StepperMotorParameters* motor = p.name == "stepper_motor" ? &stepper : nullptr;
  analysis::MonteCarloSummary summary;
  if (!analysis::RunMonteCarlo(p, motor, g, options, mc, &summary, &error))
    return Status::RunnerFailed(error);
  (*result)["monte_carlo"] = MonteCarloJson(mc, summary);
  if (!series) return Status::Ok();
  return MonteCarloBand(p, motor, g, options, mc, &(*series)["monte_carlo"]);
}

// The nonlinear motor's plot: the linear model of eq. (3) (plant
// stepper_motor with the same Table I) run on the same loop, its y in
// (*series)["linear_y"] (null if it does not run).
void AddLinearMotor(const spec::PlantSpec& motor, const PidGains& g, const LoopOptions& options,
                    nlohmann::json* series) {
  spec::PlantSpec linear;
  linear.plant = "stepper_motor";
  linear.stepper = motor.stepper;
  Plant p;
  Evaluation ev;
  std::string error;
  evaluation::EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  const bool ran =
      tune::BuildPlant(linear, NameStyle::kKey, &p, &error) && Evaluate(p, g, options, what, &ev, &error);
  (*series)["linear_y"] = ran ? nlohmann::json(ev.y) : nlohmann::json(nullptr);
}

}  // namespace

Status EvaluateSpecJson(const nlohmann::json& spec_json, nlohmann::json* result, nlohmann::json* series) {
  spec::EvaluateSpec s;
  std::string error;
  if (!spec::FromJson(spec_json, &s, nullptr, &error)) return Status::InvalidInput(error);
  s.plant.Normalize();
  Plant p;
  PidGains g;
  LoopOptions options;
  LoopBounds bounds;
  if (!(tune::BuildPlant(s.plant, NameStyle::kKey, &p, &error) &&
        tune::BuildGains(s.gains, NameStyle::kKey, &g, &error) &&
        tune::BuildLoopOptions(s.loop, NameStyle::kKey, &options, &error) &&
        tune::CheckPlantInLoop(p, options, NameStyle::kKey, &error) &&
        tune::BuildBounds(s.bounds, NameStyle::kKey, &bounds, &error)))
    return Status::InvalidInput(error);
  Evaluation ev;
  LoopAnalysis analysis;
  EvaluateOptions what;
  what.record_trajectory = series != nullptr && options.loop == evaluation::LoopKind::kSampled;
  if (!(Evaluate(p, g, options, what, &ev, &error) &&
        AnalyzeLoop(p, g, options, LoopAnalysisOptions{}, &analysis, &error)))
    return Status::RunnerFailed(error);
  *result = ToJson(ev);
  (*result)["backend"] = "local";
  (*result)["robustness"] = RobustnessJson(analysis, bounds);
  (*result)["spec"] = spec::ToJson(s);
  if (series) {
    const Status plotted = PlotSeries(p, g, options, ev, analysis, PlotSeriesOptions{}, series);
    if (!plotted.ok()) return plotted;
    if (p.nonlinear) AddLinearMotor(s.plant, g, options, series);
  }
  return s.monte_carlo > 0 ? AddMonteCarlo(s, p, g, options, result, series) : Status::Ok();
}

nlohmann::json EvaluateSpecFields() {
  nlohmann::json rows = nlohmann::json::array();
  for (const spec::FieldEntry& e : spec::Fields<spec::EvaluateSpec>())
    rows.push_back({{"key", e.field.key},
                    {"flag", spec::FlagName(e.field.key)},
                    {"help", e.field.help},
                    {"unit", e.field.unit},
                    {"default", e.default_value},
                    {"example", nlohmann::json::parse(e.field.example)}});
  return rows;
}

}  // namespace pidlab::results
