#include "pidlab/results/spec_run.h"

#include <cmath>
#include <set>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/results/plot_series.h"
#include "pidlab/results/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/time_scale.h"

namespace pidlab::results {
using analysis::AnalyzeLoop;
using analysis::LoopAnalysis;
using analysis::LoopAnalysisOptions;
using analysis::LoopBounds;
using evaluation::Evaluate;
using evaluation::Evaluation;

namespace {

// The nonlinear motor's plot: the linear model of eq. (3) (plant
// stepper_motor with the same Table I) run on the same loop, its y in
// (*series)["linear_y"] (null if it does not run).
void AddLinearMotor(const tune::EvaluationProblem& problem, const evaluation::LoopOptions& loop,
                    nlohmann::json* series) {
  Plant p;
  Evaluation ev;
  evaluation::EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  const bool ran = MakePlant("stepper_motor", problem.stepper, &p).ok() &&
                   Evaluate(p, problem.gains, loop, what, &ev).ok();
  (*series)["linear_y"] = ran ? nlohmann::json(ev.y) : nlohmann::json(nullptr);
}

// The most sample intervals of a derived figure frame (FigureFrame).
constexpr double kMaxFigureIntervals = 4000.0;

// The figures' frame, as `pidlab plot` draws them (tune/time_scale.h,
// kFigure): with neither horizon nor sample_time given, on every plant the
// closed loop's transient fills it. The result's numbers keep the
// evaluation's own time scale; only the series moves. *loop and *figure
// are the evaluation's when the frame is its own.
Status FigureFrame(const tune::EvaluationProblem& problem, const std::set<std::string>& given,
                   const Evaluation& evaluated, evaluation::LoopOptions* loop, Evaluation* figure,
                   tune::TimeScale* frame) {
  spec::LoopSpec framed = problem.spec.loop;
  *frame = tune::ResolveGainsTimeScale(problem.spec.plant, problem.plant, {problem.gains}, given,
                                       tune::TimeScaleScope::kFigure, &framed,
                                       {&problem.gains, &problem.loop, &evaluated});
  // A derived frame is drawn with at most kMaxFigureIntervals + 1 points a
  // curve (a loop whose fast rise and slow tail both stay in it would send
  // the page tens of thousands): its spacing doubled (a multiple of dt still),
  // the horizon rounded up to a multiple of it.
  if (frame->source == "plant" && framed.horizon_s / framed.sample_time_s > kMaxFigureIntervals + 0.5) {
    while (framed.horizon_s / framed.sample_time_s > kMaxFigureIntervals + 0.5) framed.sample_time_s *= 2.0;
    framed.horizon_s = std::ceil(framed.horizon_s / framed.sample_time_s - 1e-9) * framed.sample_time_s;
    frame->horizon_s = framed.horizon_s;
    frame->sample_time_s = framed.sample_time_s;
    frame->reason += "; spaced for at most " + std::to_string(static_cast<int>(kMaxFigureIntervals)) +
                     " intervals a curve";
  }
  *loop = problem.loop;
  *figure = evaluated;
  if (framed.horizon_s == problem.spec.loop.horizon_s &&
      framed.sample_time_s == problem.spec.loop.sample_time_s)
    return Status::Ok();
  Plant plant;
  const Status built =
      tune::BuildPlantInLoop(problem.spec.plant, framed, spec::NameStyle::kKey, &plant, loop);
  if (!built.ok()) return built;
  evaluation::EvaluateOptions what;
  what.record_trajectory = loop->loop == evaluation::LoopKind::kSampled;
  return evaluation::Evaluate(problem.plant, problem.gains, *loop, what, figure);
}

}  // namespace

nlohmann::json EvaluationJson(const tune::EvaluationProblem& problem, const tune::EvaluationResult& result,
                              const std::string& backend) {
  nlohmann::json j = ToJson(result.evaluation);
  j["backend"] = backend;
  j["robustness"] = RobustnessJson(result.analysis, problem.bounds);
  if (result.monte_carlo_ran) j["monte_carlo"] = MonteCarloJson(problem.monte_carlo, result.monte_carlo);
  j["spec"] = spec::ToJson(problem.spec);
  j["time_scale"] = TimeScaleJson(problem.time_scale);
  return j;
}

Status EvaluateSpecJson(const nlohmann::json& spec_json, nlohmann::json* result, nlohmann::json* series,
                        const std::set<std::string>* given) {
  spec::EvaluateSpec s;
  tune::BuildOptions build;
  if (Status st = spec::FromJson(spec_json, &s, &build.given); !st.ok()) return st;
  if (given) build.given = *given;
  tune::EvaluationProblem problem;
  const Status built = tune::BuildEvaluation(s, build, &problem);
  if (!built.ok()) return built;
  tune::EvaluationRunOptions run;
  run.what.record_trajectory = series != nullptr && problem.loop.loop == evaluation::LoopKind::kSampled;
  tune::EvaluationResult r;
  const Status ran = tune::RunEvaluation(problem, run, &r);
  if (!ran.ok()) return ran;
  *result = EvaluationJson(problem, r, "local");
  if (!series) return Status::Ok();
  evaluation::LoopOptions loop;
  Evaluation figure;
  tune::TimeScale frame;
  const Status framed = FigureFrame(problem, build.given, r.evaluation, &loop, &figure, &frame);
  if (!framed.ok()) return framed;
  const Status plotted =
      PlotSeries(problem.plant, problem.gains, loop, figure, r.analysis, PlotSeriesOptions{}, series);
  if (!plotted.ok()) return plotted;
  (*series)["time_scale"] = TimeScaleJson(frame);
  if (problem.plant.nonlinear) AddLinearMotor(problem, loop, series);
  if (!r.monte_carlo_ran) return Status::Ok();
  const StepperMotorParameters* motor = problem.plant.name == "stepper_motor" ? &problem.stepper : nullptr;
  return MonteCarloBand(problem.plant, motor, problem.gains, loop, problem.monte_carlo,
                        &(*series)["monte_carlo"]);
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
