#pragma once
// The JSON objects of `pidlab batch --json` (one per plant, and the
// summary), built here so that any front end gives the same keys
// (docs/deadtime.md, "The AMIGO test batch").

#include <nlohmann/json.hpp>

#include "pidlab/tune/batch.h"

namespace pidlab::results {

/// One plant: family, parameter, value, label, plant_tf, delay_s, model,
/// tau, dt_s, horizon_s, box, amigo {k, ti_s, td_s, gains, ms, load_iae,
/// feasible}, pidlab {gains, ms, load_iae, feasible, source, at_bounds},
/// ratio, wall_time_s, message (null for NaN and +-inf).
nlohmann::json BatchResultJson(const tune::BatchResult& r);
/// The summary: plants, amigo_feasible, pidlab_feasible, wins, ties,
/// losses, best_ratio, worst_ratio, max_ms.
nlohmann::json BatchTallyJson(const tune::BatchTally& t);

}  // namespace pidlab::results
