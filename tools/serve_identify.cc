// The page's identify and identify_cancel requests (docs/workbench.md, "Data
// and model"): a process model fitted on a thread of its own, as `pidlab
// identify --model MODEL --json` fits it (results::RunIdentify, the same
// record readers, a record beyond max_samples decimated), with its progress
// at most ten times a second, cancelled within one solver iteration. The
// result carries the fit's curves and the path of a model file written in
// the uploads' directory: the plant "model:PATH" of the page's next specs,
// and that file's text, which the page offers as a download.

#include <cmath>
#include <memory>
#include <string>

#include "cli_common.h"
#include "identify_record.h"
#include "pidlab/results/identify_json.h"
#include "pidlab/tune/model_file.h"
#include "serve_logs.h"
#include "serve_requests.h"

namespace pidlab::cli {
namespace {

server::Reply Bad(const std::string& why) { return {400, {{"error", why}}}; }

// The record and how the reply names it: an uploaded CSV, or an episode of
// an opened log (its operating point 0, as `pidlab identify --log` takes it).
struct Record {
  identify::IdentifyData data;
  nlohmann::json source;
  bool from_log = false;
};

bool ReadRecord(const nlohmann::json& request, Record* record, std::string* error) {
  LogStore* store = ServedLogs();
  if (!store) {
    *error = "uploads are not served here";
    return false;
  }
  const bool by_upload = request.contains("upload_id"), by_log = request.contains("log_id");
  if (by_upload == by_log) {
    *error = "an identify request needs either an upload_id (a CSV) or a log_id with an index";
    return false;
  }
  std::string name;
  if (by_upload) {
    std::string path;
    if (!store->UploadedFile(request["upload_id"], &path, &name, error)) return false;
    const Status read = ReadCsvRecord(path, "csv " + Quote(name), &record->data);
    if (!read.ok()) {
      std::string why = read.message();
      // The page is told the name it gave, never the server's own path.
      for (std::size_t at; (at = why.find(path)) != std::string::npos;) why.replace(at, path.size(), name);
      *error = Truncate(why, 300);
      return false;
    }
    record->source = {{"csv", name}};
    return true;
  }
  replay::Episode episode;
  if (!store->OpenedEpisode(request["log_id"], request.value("index", nlohmann::json(nullptr)), &episode,
                            &name, error))
    return false;
  if (!episode.has_config || !episode.Complete()) {
    *error = "episode " + std::to_string(episode.episode_id) + " of log " + Quote(name) +
             " is incomplete: " + Truncate(episode.CompletenessNote(), 200);
    return false;
  }
  if (!EpisodeInputVaries(episode)) {
    *error = "episode " + std::to_string(episode.episode_id) + " of log " + Quote(name) +
             " has a constant input u + n: nothing to identify from";
    return false;
  }
  record->data = EpisodeRecord(episode);
  record->source = {{"log", name}, {"episode", episode.episode_id}};
  record->from_log = true;
  return true;
}

// The options the request may set: model (required), poles and zeros (tf), u0.
bool ReadOptions(const nlohmann::json& request, std::string* model, identify::IdentifyOptions* options,
                 std::string* error) {
  const auto m = request.find("model");
  if (m == request.end() || !m->is_string()) {
    *error = "an identify request needs a model: " + identify::ProcessModelKindNames() + "|auto";
    return false;
  }
  *model = m->get<std::string>();
  identify::ProcessModelKind kind = identify::ProcessModelKind::kP1D;
  if (*model != "auto" && !identify::Parse(*model, &kind)) {
    *error = "model " + Quote(Truncate(*model, 50)) + " must be one of " + identify::ProcessModelKindNames() +
             "|auto";
    return false;
  }
  const bool tf = *model != "auto" && kind == identify::ProcessModelKind::kTf;
  for (const char* key : {"poles", "zeros"}) {
    const auto v = request.find(key);
    if (v == request.end()) continue;
    if (!tf) {
      *error = std::string(key) + " applies to model tf only";
      return false;
    }
    if (!v->is_number_integer() || v->get<long>() < 0 || v->get<long>() > plant_sim::kMaxTfPoles) {
      *error = std::string(key) + " " + Truncate(v->dump(), 50) + " must be an integer in 0.." +
               std::to_string(plant_sim::kMaxTfPoles);
      return false;
    }
    (std::string(key) == "poles" ? options->poles : options->zeros) = v->get<int>();
  }
  // u0: the input before the record (a step test that starts at the step needs it), or "estimate".
  if (const auto u0 = request.find("u0"); u0 != request.end() && !u0->is_null()) {
    if (u0->is_string() && u0->get<std::string>() == "estimate") {
      options->estimate_u0 = true;
    } else if (u0->is_number() && std::isfinite(u0->get<double>())) {
      options->u0 = u0->get<double>();
    } else {
      *error = "u0 " + Truncate(u0->dump(), 50) + " must be a finite number or \"estimate\"";
      return false;
    }
  }
  if (tf && !request.contains("poles")) {
    *error = "model tf needs poles (1.." + std::to_string(plant_sim::kMaxTfPoles) + ")";
    return false;
  }
  return options->IsValid(error);
}

std::function<void(identify::ProcessModelKind, int, int, double)> ProgressPoster(
    std::shared_ptr<ConnectionJob> job, std::shared_ptr<server::Connection> out, nlohmann::json id) {
  return [job, out, id](identify::ProcessModelKind kind, int done, int total, double best) {
    if (!job->ProgressDue(*out)) return;
    out->Post({{"type", "identify_progress"},
               {"model", identify::ToString(kind)},
               {"done", done},
               {"total", total},
               {"best_cost", results::JsonNumber(best)},
               {"id", id}},
              "identify_progress");
  };
}

nlohmann::json Fit(const Record& record, const std::string& model, const identify::IdentifyOptions& options) {
  results::IdentifyRun run;
  const Status status = results::RunIdentify(record.data, model, options, &run);
  if (!status.ok()) return {{"type", "identify_result"}, {"error", Truncate(status.message(), 300)}};
  run.json["source"] = record.source;
  std::string error;
  const std::string text = run.json.dump(1) + "\n";
  const std::string path = ServedLogs()->StoreModel(text, &error);
  if (path.empty()) return {{"type", "identify_result"}, {"error", error}};
  return {{"type", "identify_result"},
          {"result", run.json},
          {"fit", results::IdentifyFitSeries(run.data, run.result)},
          {"plant", std::string(tune::kModelPlantPrefix) + path},
          {"model_file", text}};
}

// The fit on the job's thread: cancelled within one iteration of every
// solve (a record is at most options.max_samples long).
nlohmann::json RunFit(const std::shared_ptr<ConnectionJob>& job,
                      const std::shared_ptr<server::Connection>& out, const Record& record,
                      const std::string& model, identify::IdentifyOptions options, const nlohmann::json& id) {
  options.progress = ProgressPoster(job, out, id);
  options.cancelled = [job, out] { return job->cancel || out->closed(); };
  nlohmann::json reply = Fit(record, model, options);
  if (job->cancel || out->closed()) throw JobCancelled{};
  return reply;
}

}  // namespace

server::Reply AnswerIdentify(const nlohmann::json& request,
                             const std::shared_ptr<server::Connection>& connection) {
  if (!connection) return Bad("identify runs over the WebSocket /ws, which carries its progress");
  std::string model, error;
  identify::IdentifyOptions options;
  if (!ReadOptions(request, &model, &options, &error)) return Bad(error);
  Record record;
  if (!ReadRecord(request, &record, &error)) return Bad(error);
  if (record.from_log) options.u0 = options.y0 = 0.0;
  return StartJob(
      request, connection, {"identify", "identify_result", "fit"},
      [connection, record = std::move(record), model, options,
       id = request.value("id", nlohmann::json(nullptr))](const std::shared_ptr<ConnectionJob>& job) {
        return RunFit(job, connection, record, model, options, id);
      });
}

}  // namespace pidlab::cli
