#include "pidlab/results/tune_run.h"

#include <set>
#include <string>

#include "pidlab/results/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"

namespace pidlab::results {

nlohmann::json TuningJson(const tune::TuningProblem& problem, const tune::TuningResult& result,
                          const std::string& backend) {
  const tune::TuneSummary& s = result.summary;
  nlohmann::json j = TuneJson(problem.plant, result.options, s, result.evaluation, backend);
  if (!result.fallback.empty()) j["fallback"] = result.fallback;
  j["robustness"] =
      s.stable ? RobustnessJson(result.analysis, problem.options.bounds) : nlohmann::json(nullptr);
  j["spec"] = spec::ToJson(problem.spec);
  const tune::TimeScale& t = problem.time_scale;
  j["time_scale"] = TimeScaleJson(t);
  if (!result.widened_from.empty()) {
    j["box"]["upper"] = result.box_upper;
    j["box"]["widened_from"] = result.widened_from;
  }
  if (j.contains("migo")) j["migo"]["robustness_reason"] = t.robustness_reason;
  if (j.contains("design")) {
    j["design"]["robustness_reason"] = t.robustness_reason;
    j["design"]["noise_gain_reason"] = t.noise_gain_reason;
  }
  {}
  return j;
}

Status TuneSpecJson(const nlohmann::json& spec_json, const optim::ProgressCallback& progress,
                    nlohmann::json* result) {
  spec::TuningSpec ts;
  tune::BuildOptions build;
  if (Status st = spec::FromJson(spec_json, &ts, &build.given); !st.ok()) return st;
  tune::TuningProblem problem;
  const Status built = tune::BuildTuning(ts, build, &problem);
  if (!built.ok()) return built;
  tune::TuningRunOptions run;
  run.progress = progress;
  tune::TuningResult r;
  const Status ran = tune::RunTuning(problem, run, &r);
  if (!ran.ok()) return ran;
  *result = TuningJson(problem, r, "local");
  return Status::Ok();
}

}  // namespace pidlab::results
