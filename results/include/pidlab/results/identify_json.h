#pragma once
// The JSON object of `pidlab identify --json` (docs/identify.md,
// "Identifying a model from a CSV"), built here so that any front end gives
// the same keys.

#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/status.h"

namespace pidlab::results {

/// model (p1d|p2d|p2du|p1di|p2dz), parameters {name: {value, standard_error, at_bound if at one}},
/// transfer_function {num, den, delay_s}, fit_percent, aic, aic_form, cost,
/// samples, dt_s (the mean interval), sampling {uniform, min_interval_s,
/// max_interval_s}, u0, y0, operating_point {u0, source, hypotheses [{u0,
/// aic, message if not fitted}]}, loss {name, scale, scale_source,
/// downweighted {below_weight, count, samples}}, starts, starts_at_best, seed, starts_skipped,
/// not_identifiable [{parameter, reason, simpler_model or null}], whiteness {lags,
/// autocorrelation, band, outside_band, ljung_box_q, p_value, white},
/// warnings [text], covariance {ok, message, matrix} (null for NaN and +-inf).
nlohmann::json IdentifyResultJson(const identify::IdentifyResult& r);
nlohmann::json WhitenessJson(const identify::Whiteness& w);
/// The chosen kind's IdentifyResultJson with "auto" {chosen, reason,
/// candidates [{model, ok, aic, delta_aic, fit_percent, operating_point,
/// parameters | message, set_aside (why auto did not choose it, or null)}]}.
nlohmann::json IdentifyAutoJson(const identify::AutoResult& a);

/// One fit as `pidlab identify --model MODEL` makes it: its JSON (the
/// object of --json and --out) and the result it describes (auto: the
/// chosen candidate's).
struct IdentifyRun {
  nlohmann::json json;
  identify::IdentifyResult result;
  /// "auto": every candidate (empty otherwise).
  identify::AutoResult automatic;
  /// The record fitted (the given one, or it decimated to
  /// options.max_samples: identify::DecimateRecord) and how it was shortened.
  identify::IdentifyData data;
  identify::Decimation decimation;
};

/// Fits `data` with `model`, one of identify::ProcessModelKindNames() or
/// "auto" (every process kind, the lowest AIC kept; tf needs
/// options.poles), decimated first when longer than options.max_samples
/// (json "decimation" {factor, samples_read, samples, max_samples,
/// start_samples}, factor 1 and start_samples 0 when not; a decimated
/// record's starts run on an eighth of max_samples, the best refitted on
/// the decimated record: IdentifyOptions::start_samples; a time constant
/// under two decimated intervals is added to the warnings). kInvalidInput
/// names a bad model or record; the fit's own failures keep their code.
/// The command line and the page's identify request both run it.
Status RunIdentify(const identify::IdentifyData& data, const std::string& model,
                   const identify::IdentifyOptions& options, IdentifyRun* run);

/// The fit's curves for a plot: {t, u, y, simulated, residuals} (null
/// where a number is not finite), the record's samples in order.
nlohmann::json IdentifyFitSeries(const identify::IdentifyData& data, const identify::IdentifyResult& r);

}  // namespace pidlab::results
