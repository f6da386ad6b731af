#include "pidlab/results/tune_run.h"

#include <set>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/results/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/search_box.h"
#include "pidlab/tune/spec_build.h"
#include "pidlab/tune/tune.h"
#include "pidlab/tune/two_dof.h"

namespace pidlab::results {

Status TuneSpecJson(const nlohmann::json& spec_json, const optim::ProgressCallback& progress,
                    nlohmann::json* result) {
  spec::TuningSpec ts;
  std::set<std::string> given;
  std::string error;
  if (!spec::FromJson(spec_json, &ts, &given, &error)) return Status::InvalidInput(error);
  ts.plant.Normalize();
  tune::ResolveRobustPreset(&ts, given);
  tune::ResolveSearchBox(&ts, given);
  Plant p;
  tune::TuneOptions o;
  if (!(tune::BuildPlant(ts.plant, spec::NameStyle::kKey, &p, &error) &&
        tune::BuildTuneOptions(ts, spec::NameStyle::kKey, &o, &error) &&
        tune::CheckPlantInLoop(p, o.loop, spec::NameStyle::kKey, &error)))
    return Status::InvalidInput(error);
  if (p.nonlinear && o.loop.loop != evaluation::LoopKind::kSampled)
    return Status::InvalidInput("plant " + p.name +
                                " is nonlinear: tune it on the sampled loop (loop sampled)");
  tune::TuneSummary s;
  if (!tune::Tune(p, o, &s, &error, progress)) return Status::InvalidInput(error);
  evaluation::Evaluation ev;
  analysis::LoopAnalysis analysis;
  if (s.stable) {
    const evaluation::LoopOptions loop = tune::WithSetpointWeights(o.loop, s.two_dof);
    if (!(evaluation::Evaluate(p, s.gains, loop, evaluation::EvaluateOptions{}, &ev, &error) &&
          analysis::AnalyzeLoop(p, s.gains, loop, analysis::LoopAnalysisOptions{}, &analysis, &error)))
      return Status::RunnerFailed(error);
  }
  *result = TuneJson(p, o, s, ev, "local");
  (*result)["robustness"] = s.stable ? RobustnessJson(analysis, o.bounds) : nlohmann::json(nullptr);
  (*result)["spec"] = spec::ToJson(ts);
  return Status::Ok();
}

}  // namespace pidlab::results
