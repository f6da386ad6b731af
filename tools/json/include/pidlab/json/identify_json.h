#pragma once
// The JSON object of `pidlab identify --json` (docs/identify.md,
// "Identifying a model from a CSV"), built here so that any front end gives
// the same keys.

#include <nlohmann/json.hpp>

#include "pidlab/identify/identify.h"

namespace pidlab::json {

/// model (p1d|p2d|p2du|p1di), parameters {name: {value, standard_error}},
/// transfer_function {num, den, delay_s}, fit_percent, aic, aic_form, cost,
/// samples, dt_s, u0, y0, starts, starts_at_best, covariance {ok, message}
/// (null for NaN and +-inf).
nlohmann::json IdentifyResultJson(const identify::IdentifyResult& r);

}  // namespace pidlab::json
