#pragma once
// The result object of `pidlab autotune --json` (docs/autotune.md), shared by
// the command line and Python's pidlab.autotune: the relay experiment, its
// estimates, the design on the identified model (the assembly's tune,
// tune_run.h) and the verification step's verdict; and the same recomputed
// from a log (AutotuneLogJson), with no trio.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "pidlab/autotune/experiment.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/spec/autotune_spec.h"
#include "pidlab/spec/field.h"
#include "pidlab/spec/status.h"

namespace pidlab::results {

/// The design on the identified model and what adopting it takes.
struct AutotuneDesignOptions {
  std::string method = "optimal";   ///< optimal | amigo | simc | migo
  double robustness = 1.4;          ///< optimal, migo: the Ms they design to
  double response_time_s = 0.0;     ///< optimal, migo: the response time (0: fastest)
  double max_ms = 2.0;              ///< the design's Ms on the model at most this (> 1)
  double max_overshoot_pct = 60.0;  ///< the verification step's overshoot at most this
  /// Given (verify_gains), these gains are verified and adopted or refused
  /// instead of the design's, under the same verdict.
  bool verify_given = false;
  PidGains verify_gains;
  bool IsValid(std::string* error) const;
};

/// What an autotune spec asks for (spec/autotune_spec.h): the relay
/// experiment and the design on its model.
struct AutotuneRun {
  autotune::ExperimentOptions experiment;
  AutotuneDesignOptions design;
};

/// The one function that turns an autotune spec into a run, for the loop's
/// PID `pid` with the `previous` gains the hold runs: the relay sized from
/// the output range where the spec leaves it (20 %, 1 if unlimited; the bias
/// d/3; the hysteresis 3 sigma of the hold's noise unless given, and a
/// negative one `given` is refused), its fixed-point grids for scalar q31 or
/// q15 (AutotuneFixedPoint), the windows, and the design with the loop's Ms
/// bound `max_ms`. kInvalidInput names the bad field as `style` does.
Status BuildAutotune(const spec::AutotuneSpec& spec, const std::set<std::string>& given,
                     const PidGains& previous, const PidOptions& pid, double max_ms, spec::NameStyle style,
                     AutotuneRun* run);
/// The design alone (a log's recomputation: the relay is the log's).
Status BuildAutotuneDesign(const spec::AutotuneSpec& spec, double max_ms, spec::NameStyle style,
                           AutotuneDesignOptions* design);
/// Checks scalar and input_range alone (double, or q31/q15 with LO,HI), so
/// that a command refuses them before it reads a log or starts a trio.
Status CheckAutotuneScalar(const spec::AutotuneSpec& spec, spec::NameStyle style);
/// For scalar q31 or q15, the exported relay's grids (pidlab export
/// --autotune --scalar with the spec's input_range, for `previous` on
/// `pid`) set in *relay; nothing for double.
Status AutotuneFixedPoint(const spec::AutotuneSpec& spec, const PidGains& previous, const PidOptions& pid,
                          spec::NameStyle style, RelayTuneOptions* relay);

/// A closed-loop step with the designed gains: its evaluation, the horizon it
/// ran and its JSON.
struct StepRun {
  evaluation::Evaluation evaluation;
  double horizon_s = 0.0;
  nlohmann::json json;
};
/// Runs (or finds) the verification step of `gains`; `pu_s` is the
/// estimated ultimate period, to size it. A failed Status: no step (the
/// verdict says why, the previous gains stay).
using StepRunner = std::function<Status(const PidGains& gains, double pu_s, StepRun* run)>;

/// {"experiment", "estimates"} of an experiment.
nlohmann::json ExperimentJson(const autotune::ExperimentSummary& x);
nlohmann::json EstimatesJson(const autotune::ExperimentSummary& x);

/// The whole object for experiment `x` run with `previous` gains: experiment,
/// estimates, design, verification (by `step`), adopted, verdict, gains (the
/// adopted or the previous ones), previous_gains. *adopted says whether the
/// design was adopted. `say` gets progress lines (may be empty).
nlohmann::json AutotuneJson(const autotune::ExperimentSummary& x, const PidGains& previous,
                            const AutotuneDesignOptions& options, const StepRunner& step,
                            const std::function<void(const std::string&)>& say, bool* adopted);

/// The same from the log at `path`: its relay episode (`episode_id`, or 0 for
/// the last one) analysed again, the design made again, the verification the
/// first later episode that ran the designed gains. Adds "backend": "log",
/// "log" and "episode_ids". kInvalidInput for an unreadable log or no such
/// relay episode; kRunnerFailed for an incomplete episode or a relay that is
/// not the logged one. `fixed_point`, when given, sets the relay's
/// fixed-point grids (RelayTuneOptions::q_bits) for the loop the episode ran:
/// a log of an exported q31/q15 relay (`pidlab autotune --log --scalar`).
using FixedPointRelay =
    std::function<Status(const PidGains& previous, const PidOptions& pid, RelayTuneOptions* relay)>;
Status AutotuneLogJson(const std::string& path, int64_t episode_id, const AutotuneDesignOptions& options,
                       const std::function<void(const std::string&)>& say, nlohmann::json* result,
                       bool* adopted, const FixedPointRelay& fixed_point = {});

}  // namespace pidlab::results
