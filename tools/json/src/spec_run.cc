#include "pidlab/json/spec_run.h"

#include <set>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/json/plot_series.h"
#include "pidlab/json/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/spec_build.h"

namespace pidlab::json {
using analysis::AnalyzeLoop;
using analysis::LoopAnalysis;
using analysis::LoopAnalysisOptions;
using analysis::LoopBounds;
using evaluation::Evaluate;
using evaluation::EvaluateOptions;
using evaluation::Evaluation;
using evaluation::LoopOptions;
using spec::NameStyle;

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
  if (series) return PlotSeries(p, g, options, ev, analysis, PlotSeriesOptions{}, series);
  return Status::Ok();
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

}  // namespace pidlab::json
