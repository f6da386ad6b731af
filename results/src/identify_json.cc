#include "pidlab/results/identify_json.h"

#include <Eigen/Dense>
#include <sstream>
#include <string>

#include "pidlab/plant_sim/transfer_function.h"
#include "pidlab/results/results_json.h"

namespace pidlab::results {

nlohmann::json WhitenessJson(const identify::Whiteness& w) {
  nlohmann::json r = nlohmann::json::array();
  for (double v : w.autocorrelation) r.push_back(JsonNumber(v));
  return {{"lags", w.lags},
          {"autocorrelation", r},
          {"band", JsonNumber(w.band)},
          {"outside_band", w.outside_band},
          {"ljung_box_q", JsonNumber(w.ljung_box_q)},
          {"p_value", JsonNumber(w.p_value)},
          {"white", w.white}};
}

namespace {

// The loss the fit minimised, its scale and the samples it down-weighted.
nlohmann::json LossJson(const identify::IdentifyResult& r) {
  return {{"name", identify::ToString(r.loss)},
          {"scale", JsonNumber(r.loss_scale)},
          {"scale_source", r.loss_scale_source},
          {"downweighted",
           {{"below_weight", identify::kDownweightedBelow},
            {"count", r.downweighted.size()},
            {"samples", r.downweighted}}}};
}

// u0 and how it was found: given, estimated, the first sample, or the rest
// chosen by AIC with both hypotheses.
nlohmann::json OperatingPointJson(const identify::IdentifyResult& r) {
  nlohmann::json hypotheses = nlohmann::json::array();
  for (const identify::IdentifyResult::RestHypothesis& h : r.rest_hypotheses) {
    nlohmann::json hj = {{"u0", JsonNumber(h.u0)}, {"aic", JsonNumber(h.aic)}};
    if (!h.message.empty()) hj["message"] = h.message;
    hypotheses.push_back(hj);
  }
  return {{"u0", JsonNumber(r.u0)}, {"source", r.u0_source}, {"hypotheses", hypotheses}};
}

// A record decimated by q sees its dynamics at q times the interval: a time
// constant under two of those intervals is said in a warning (fit a shorter
// stretch at full rate, or raise the limit).
void WarnIfTooCoarse(const identify::Decimation& d, identify::IdentifyResult* r) {
  if (d.factor == 1) return;
  for (std::size_t i = 0; i < r->names.size() && i < r->values.size(); ++i) {
    const std::string& name = r->names[i];
    if ((name != "Tp1" && name != "Tp2" && name != "Tw") || !(r->values[i] < 2.0 * r->dt_s)) continue;
    std::ostringstream os;
    os << name << " = " << r->values[i] << " s is under two intervals (" << r->dt_s
       << " s) of the record decimated by " << d.factor << " from " << d.samples_read
       << " samples: fit a shorter stretch at full rate or raise max_samples (" << d.max_samples << ")";
    r->warnings.push_back(os.str());
  }
}

}  // namespace

namespace {

// {name: {value, standard_error, at_bound if at one}}.
nlohmann::json ParametersJson(const identify::IdentifyResult& r) {
  nlohmann::json parameters = nlohmann::json::object();
  for (std::size_t i = 0; i < r.names.size(); ++i) {
    parameters[r.names[i]] = {{"value", JsonNumber(r.values[i])},
                              {"standard_error", JsonNumber(r.standard_errors.at(i))}};
    // A parameter at a bound: its interval is one-sided, so no standard error.
    if (i < r.at_bound.size() && !r.at_bound[i].empty()) parameters[r.names[i]]["at_bound"] = r.at_bound[i];
  }
  return parameters;
}

// [{parameter, reason, simpler_model or null}].
nlohmann::json NotIdentifiableJson(const identify::IdentifyResult& r) {
  nlohmann::json not_identifiable = nlohmann::json::array();
  for (const identify::IdentifyResult::NotIdentifiable& n : r.not_identifiable)
    not_identifiable.push_back(
        {{"parameter", n.parameter},
         {"reason", n.reason},
         {"simpler_model",
          n.simpler_model.empty() ? nlohmann::json(nullptr) : nlohmann::json(n.simpler_model)}});
  return not_identifiable;
}

}  // namespace

nlohmann::json IdentifyAutoJson(const identify::AutoResult& a) {
  nlohmann::json j = IdentifyResultJson(a.candidates.at(static_cast<std::size_t>(a.chosen)).result);
  nlohmann::json candidates = nlohmann::json::array();
  const double best = a.candidates.at(static_cast<std::size_t>(a.chosen)).result.aic;
  for (const identify::AutoCandidate& c : a.candidates) {
    nlohmann::json cj = {{"model", identify::ToString(c.kind)}, {"ok", c.status.ok()}};
    if (c.status.ok()) {
      cj["aic"] = JsonNumber(c.result.aic);
      cj["delta_aic"] = JsonNumber(c.result.aic - best);
      cj["fit_percent"] = JsonNumber(c.result.fit_percent);
      cj["operating_point"] = {{"u0", JsonNumber(c.result.u0)}, {"source", c.result.u0_source}};
      cj["parameters"] = ParametersJson(c.result);
    } else {
      cj["message"] = c.status.message();
    }
    cj["set_aside"] = c.set_aside.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.set_aside);
    candidates.push_back(cj);
  }
  j["auto"] = {{"chosen", identify::ToString(a.candidates.at(static_cast<std::size_t>(a.chosen)).kind)},
               {"reason", a.reason},
               {"candidates", candidates}};
  return j;
}

nlohmann::json IdentifyResultJson(const identify::IdentifyResult& r) {
  const nlohmann::json parameters = ParametersJson(r);
  const TransferFunction tf = r.model.ToTransferFunction();
  nlohmann::json num = nlohmann::json::array(), den = nlohmann::json::array();
  for (double c : tf.num) num.push_back(JsonNumber(c));
  for (double c : tf.den) den.push_back(JsonNumber(c));
  // The state's free response at t[0], C A^i x(t[0]) for i = 0 .. n-1: the
  // initial state in terms that need no particular realisation.
  nlohmann::json free_response = nlohmann::json::array();
  if (!r.initial_state.empty()) {
    const StateSpace ss = Realize(tf);
    if (ss.order() == static_cast<int>(r.initial_state.size())) {
      Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(r.initial_state.data(), ss.order());
      for (int i = 0; i < ss.order(); ++i, x = ss.a * x) free_response.push_back(JsonNumber(ss.c.dot(x)));
    }
  }
  nlohmann::json matrix = nlohmann::json::array();
  const std::size_t p = r.names.size();
  for (std::size_t i = 0; i < p && r.covariance.size() == p * p; ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (std::size_t j = 0; j < p; ++j) row.push_back(JsonNumber(r.covariance[i * p + j]));
    matrix.push_back(row);
  }
  nlohmann::json poles = nlohmann::json::array();
  for (const identify::PoleEstimate& pole : identify::PoleEstimates(r))
    poles.push_back({{"re", JsonNumber(pole.re)},
                     {"im", JsonNumber(pole.im)},
                     {"re_standard_error", JsonNumber(pole.re_se)},
                     {"im_standard_error", JsonNumber(pole.im_se)}});
  nlohmann::json j = {
      {"model", identify::ToString(r.model.kind)},
      {"parameters", parameters},
      {"transfer_function", {{"num", num}, {"den", den}, {"delay_s", JsonNumber(r.model.delay_s())}}},
      {"poles", poles},
      {"fit_percent", JsonNumber(r.fit_percent)},
      {"aic", JsonNumber(r.aic)},
      {"aic_form", "N log(2 cost / N) + 2 p"},
      {"cost", JsonNumber(r.cost)},
      {"samples", r.samples},
      {"dt_s", JsonNumber(r.dt_s)},
      {"sampling",
       {{"uniform", r.sampling.uniform},
        {"min_interval_s", JsonNumber(r.sampling.min_interval_s)},
        {"max_interval_s", JsonNumber(r.sampling.max_interval_s)}}},
      {"intersample", identify::ToString(r.intersample)},
      {"initial_condition", identify::ToString(r.initial_condition)},
      {"initial_state", r.initial_state},
      {"initial_free_response", free_response},
      {"u0", JsonNumber(r.u0)},
      {"y0", JsonNumber(r.y0)},
      {"y0_estimated", r.y0_estimated},
      {"y0_standard_error", JsonNumber(r.y0_standard_error)},
      {"u0_estimated", r.u0_estimated},
      {"u0_standard_error", JsonNumber(r.u0_standard_error)},
      {"starts", r.starts},
      {"starts_at_best", r.starts_at_best},
      {"seed", r.seed},
      {"arx_start", r.arx_start},
      {"nested_starts", r.nested_starts},
      {"starts_skipped", r.starts_skipped},
      {"not_identifiable", NotIdentifiableJson(r)},
      {"delay_profile_improved", r.delay_profile_improved},
      {"bounds_refit_improved", r.bounds_refit_improved},
      {"operating_point", OperatingPointJson(r)},
      {"loss", LossJson(r)},
      {"whiteness", WhitenessJson(r.whiteness)},
      {"warnings", r.warnings},
      {"covariance", {{"ok", r.covariance_ok}, {"message", r.covariance_message}, {"matrix", matrix}}}};
  // A tf's shape, which its parameters' names alone do not fix for a reader.
  if (r.model.kind == identify::ProcessModelKind::kTf) {
    j["poles"] = r.model.poles;
    j["zeros"] = r.model.zeros;
  }
  return j;
}

Status RunIdentify(const identify::IdentifyData& data, const std::string& model,
                   const identify::IdentifyOptions& options, IdentifyRun* run) {
  identify::ProcessModelKind kind = identify::ProcessModelKind::kP1D;
  if (model != "auto" && !identify::Parse(model, &kind))
    return Status::InvalidInput("model '" + model + "' must be one of " + identify::ProcessModelKindNames() +
                                "|auto");
  if (Status st = identify::DecimateRecord(data, options.max_samples, options.intersample, &run->data,
                                           &run->decimation);
      !st.ok())
    return st;
  identify::Decimation& d = run->decimation;
  // A decimated record's starts on an eighth of its samples, the best refitted on all.
  identify::IdentifyOptions fit = options;
  if (d.factor > 1)
    fit.start_samples = d.start_samples = identify::StartSamples(d.max_samples, model == "tf");
  const nlohmann::json decimation = {{"factor", d.factor},
                                     {"samples_read", d.samples_read},
                                     {"samples", d.samples},
                                     {"max_samples", d.max_samples},
                                     {"start_samples", d.start_samples}};
  if (model == "auto") {
    identify::AutoResult& a = run->automatic;
    if (Status st = identify::IdentifyAuto(run->data, fit, &a); !st.ok()) return st;
    WarnIfTooCoarse(d, &a.candidates[static_cast<std::size_t>(a.chosen)].result);
    run->result = a.candidates[static_cast<std::size_t>(a.chosen)].result;
    run->json = IdentifyAutoJson(a);
  } else {
    if (Status st = identify::Identify(run->data, kind, fit, &run->result); !st.ok()) return st;
    WarnIfTooCoarse(d, &run->result);
    run->json = IdentifyResultJson(run->result);
  }
  run->json["decimation"] = decimation;
  return Status::Ok();
}

nlohmann::json IdentifyFitSeries(const identify::IdentifyData& data, const identify::IdentifyResult& r) {
  const auto numbers = [](const std::vector<double>& v) {
    nlohmann::json out = nlohmann::json::array();
    for (double x : v) out.push_back(JsonNumber(x));
    return out;
  };
  return {{"t", numbers(data.t)},
          {"u", numbers(data.u)},
          {"y", numbers(data.y)},
          {"simulated", numbers(r.simulated)},
          {"residuals", numbers(r.residuals)}};
}

}  // namespace pidlab::results
