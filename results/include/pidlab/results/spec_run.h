#pragma once
// A spec in its JSON form run to its result's JSON form: what `pidlab serve`
// answers (docs/workbench.md), built from the same pieces as `pidlab evaluate
// --spec FILE --json` and Python's pidlab.evaluate (the spec built and run
// by tune/problem.h, the object of results_json.h with "robustness" and the
// "spec" echo).

#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "pidlab/spec/status.h"
#include "pidlab/tune/problem.h"

namespace pidlab::results {

/// The object of `pidlab evaluate --json` for a run of `problem` on
/// `backend` ("local" or "lcm"): the evaluation, "backend", "robustness",
/// "monte_carlo" when the draws ran, and the "spec" it ran.
nlohmann::json EvaluationJson(const tune::EvaluationProblem& problem, const tune::EvaluationResult& result,
                              const std::string& backend);

/// The object of `pidlab evaluate --json` (backend "local") for the
/// EvaluateSpec `spec` (keys as the spec's JSON form; a --json result's
/// "spec" runs again). Status kInvalidInput with one line naming the key and
/// value for a spec that does not validate (tune::BuildEvaluation) or a loop
/// the analysis or the draws refuse; kRunnerFailed if the evaluation fails. With `series`, also the plot data
/// of that loop there (plot_series.h: PlotSeries), for the workbench's plots; for the nonlinear stepper also
/// "linear_y", the linear model of eq. (3) on the same loop. The keys given
/// are those of `spec` (or *given, a caller's own list): off the paper's
/// plants, with neither horizon nor sample_time given, the time scale comes
/// from the closed loop (tune/time_scale.h).
Status EvaluateSpecJson(const nlohmann::json& spec, nlohmann::json* result, nlohmann::json* series = nullptr,
                        const std::set<std::string>* given = nullptr);

/// The fields of EvaluateSpec: [{key, flag, help, unit, default, example}].
nlohmann::json EvaluateSpecFields();

}  // namespace pidlab::results
