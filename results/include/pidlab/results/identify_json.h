#pragma once
// The JSON object of `pidlab identify --json` (docs/identify.md,
// "Identifying a model from a CSV"), built here so that any front end gives
// the same keys.

#include <nlohmann/json.hpp>

#include "pidlab/identify/identify.h"

namespace pidlab::results {

/// model (p1d|p2d|p2du|p1di|p2dz), parameters {name: {value, standard_error, at_bound if at one}},
/// transfer_function {num, den, delay_s}, fit_percent, aic, aic_form, cost,
/// samples, dt_s (the mean interval), sampling {uniform, min_interval_s,
/// max_interval_s}, u0, y0, operating_point {u0, source, hypotheses [{u0,
/// aic, message if not fitted}]}, loss {name, scale, scale_source,
/// downweighted {below_weight, count, samples}}, starts, starts_at_best, seed, whiteness {lags,
/// autocorrelation, band, outside_band, ljung_box_q, p_value, white},
/// warnings [text], covariance {ok, message, matrix} (null for NaN and +-inf).
nlohmann::json IdentifyResultJson(const identify::IdentifyResult& r);
nlohmann::json WhitenessJson(const identify::Whiteness& w);
/// The chosen kind's IdentifyResultJson with "auto" {chosen, reason,
/// candidates [{model, ok, aic, delta_aic, fit_percent | message}]}.
nlohmann::json IdentifyAutoJson(const identify::AutoResult& a);

}  // namespace pidlab::results
