#pragma once
// A tuning spec in its JSON form run to the object of `pidlab tune --json`
// (backend "local"): what `pidlab serve` answers a tune request with
// (docs/workbench.md). The same steps as the command: the spec read with
// the keys it has counted as given (the --robust preset and the search box
// resolved from them), built and run by tune/problem.h (BuildTuning,
// RunTuning: Tune, then the evaluation and the loop analysis of the gains
// found).

#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/optim/optimizer.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/problem.h"

namespace pidlab::results {

/// The object of `pidlab tune --json` for a run of `problem` on `backend`
/// ("local" or "lcm"): TuneJson, "robustness" (null unless stable) and the
/// "spec" it ran.
nlohmann::json TuningJson(const tune::TuningProblem& problem, const tune::TuningResult& result,
                          const std::string& backend);

/// The object of `pidlab tune --spec FILE --json` for the TuningSpec `spec`;
/// `progress` is called once per iteration of the search (it may throw to
/// stop the tuning: the exception leaves this function). kInvalidInput with
/// one line naming the key and value for a spec that does not validate or a
/// method that does not apply; kRunnerFailed if the evaluation fails.
Status TuneSpecJson(const nlohmann::json& spec, const optim::ProgressCallback& progress,
                    nlohmann::json* result);

}  // namespace pidlab::results
