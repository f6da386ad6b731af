#include "serve_requests.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/results/spec_run.h"
#include "pidlab/spec/field.h"
#include "serve_live.h"
#include "serve_logs.h"
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
#include "export_spec.h"
#include "pidlab/report/report.h"
#include "pidlab/spec/json.h"
#include "pidlab/tune/problem.h"
#endif

namespace pidlab::cli {
namespace {

constexpr int kMaxServedDraws = 1000;

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// {"type": "evaluate", "spec": SPEC, "series": true}: the result, the plot
// series (unless "series" is false) and the server's compute time.
server::Reply Evaluate(const nlohmann::json& request) {
  if (!request.contains("spec")) return {400, {{"error", "an evaluate request needs a spec"}}};
  const auto series_flag = request.find("series");
  if (series_flag != request.end() && !series_flag->is_boolean())
    return {400, {{"error", "series " + series_flag->dump() + " must be true or false"}}};
  const bool with_series = series_flag == request.end() || series_flag->get<bool>();
  // The server answers one request at a time: a Monte-Carlo run is bounded here.
  const nlohmann::json& spec = request["spec"];
  if (spec.is_object() && spec.contains("monte_carlo") && spec["monte_carlo"].is_number() &&
      spec["monte_carlo"].get<double>() > kMaxServedDraws)
    return {400,
            {{"error", "monte_carlo " + spec["monte_carlo"].dump() + " is more than the " +
                           std::to_string(kMaxServedDraws) +
                           " draws pidlab serve runs (pidlab evaluate takes more)"}}};
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json result, series;
  const Status status = results::EvaluateSpecJson(request["spec"], &result, with_series ? &series : nullptr);
  if (!status.ok()) return {400, {{"error", status.message()}}};
  nlohmann::json reply = {{"type", "evaluation"}, {"result", result}};
  if (with_series) reply["series"] = series;
  reply["compute_ms"] = MillisecondsSince(start);
  return {200, reply};
}

#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
// {"type": "export", "spec": SPEC}: the C module `pidlab export --spec SPEC
// --lang c --out DIR` writes (double), as text.
server::Reply Export(const nlohmann::json& request) {
  if (!request.contains("spec")) return {400, {{"error", "an export request needs a spec"}}};
  spec::EvaluateSpec s;
  std::string error;
  controller_export::Controller controller;
  if (const Status st = spec::FromJson(request["spec"], &s, nullptr); !st.ok())
    return {400, {{"error", st.message()}}};
  s.plant.Normalize();
  if (!ExportController(s, spec::NameStyle::kKey, &controller, &error)) return {400, {{"error", error}}};
  controller_export::Options options;
  options.plant = DescribePlant(s.plant);
  // The plant's sampled loop at dt, as pidlab export checks it.
  tune::SampledControllerCheck check;
  if (Status checked = tune::CheckSampledController(s, spec::NameStyle::kKey, &check); !checked.ok())
    return {400, {{"error", checked.message()}}};
  const bool force =
      request.contains("force") && request["force"].is_boolean() && request["force"].get<bool>();
  if (!check.stable && !force) return {400, {{"error", check.verdict}, {"unstable", true}}};
  options.dt_source = "from the spec";  // as pidlab export --spec says it
  options.loop_check = check.stable ? check.verdict : "UNSTABLE, written with force: " + check.verdict;
  options.spec_json = SpecText(spec::ToJson(s));
  options.pidlab_version = PIDLAB_VERSION;
  controller_export::GeneratedCode code;
  try {
    code = controller_export::Generate(options, controller);
  } catch (const std::invalid_argument& e) {
    return {400, {{"error", e.what()}}};
  }
  return {200,
          {{"type", "export"},
           {"loop_check", {{"checked", check.checked}, {"stable", check.stable}, {"verdict", check.verdict}}},
           {"files", {{"pidlab_pid.h", code.header}, {"pidlab_pid.c", code.source}}}}};
}
#endif

}  // namespace

nlohmann::json PaperDesigns() {
  nlohmann::json designs = nlohmann::json::array();
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
  std::vector<report::PaperRow> rows;
  if (const Status st = report::ParsePaperTables(report::BuiltinPaperTablesCsv(), "paper_tables.csv", &rows);
      !st.ok())
    throw std::runtime_error(st.message());
  for (const report::PaperRow& r : rows)
    designs.push_back({{"table", r.table},
                       {"plant", r.plant},
                       {"method", r.method},
                       {"disturbance_amplitude", r.disturbance_amplitude},
                       {"gains", {r.gains.kp, r.gains.ki, r.gains.kd}},
                       {"paper_iae", r.paper_iae}});
#endif
  return designs;
}

server::Reply AnswerWorkbenchRequest(const nlohmann::json& request,
                                     const std::shared_ptr<server::Connection>& connection,
                                     LiveService* live) {
  const auto type_field = request.find("type");
  if (type_field != request.end() && !type_field->is_string())
    return {400, {{"error", "request type " + spec::Truncate(type_field->dump()) + " must be a string"}}};
  const std::string type = request.value("type", std::string());
  if (type == "fields") return {200, {{"type", "fields"}, {"fields", results::EvaluateSpecFields()}}};
  if (type == "paper_designs") return {200, {{"type", "paper_designs"}, {"designs", PaperDesigns()}}};
  if (type == "evaluate") return Evaluate(request);
  if (type == "log_open") return AnswerLogOpen(request);
  if (type == "log_episode") return AnswerLogEpisode(request);
  if (IsLiveRequest(type)) return AnswerLive(live, type, request, connection);
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
  if (type == "export") return Export(request);
  if (type == "pil_cost") return AnswerPilCost(request, connection);
  if (type == "tune") return AnswerTune(request, connection);
  if (type == "tune_cancel") return AnswerTuneCancel(connection);
  if (type == "identify") return AnswerIdentify(request, connection);
  if (type == "identify_cancel")
    return {200, {{"type", "identify_cancel"}, {"cancelling", CancelConnectionJob(connection, "identify")}}};
#else
  (void)connection;
#endif
  return {
      400,
      {{"error", "request type '" + type +
                     "' is not one of evaluate, fields, paper_designs, export, pil_cost, tune, tune_cancel, "
                     "identify, identify_cancel, log_open, log_episode"}}};
}

}  // namespace pidlab::cli
