#include "serve_logs.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "cli_common.h"
#include "pidlab/io/files.h"
#include "pidlab/replay/replay.h"
#include "pidlab/results/replay_json.h"
#include "pidlab/results/results_json.h"

namespace pidlab::cli {
namespace {

namespace fs = std::filesystem;

LogStore* g_store = nullptr;

server::Reply Bad(const std::string& why) { return {400, {{"error", why}}}; }

// An upload's name: a plain file name of at most 100 characters.
bool GoodUploadName(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.') return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) return false;
  return true;
}

// Inclusive ranges [first, last] of the steps where `in(k)` holds.
template <typename In>
nlohmann::json Ranges(std::size_t size, In in) {
  nlohmann::json out = nlohmann::json::array();
  long first = -1;
  for (std::size_t i = 0; i <= size; ++i) {
    const bool inside = i < size && in(i);
    const auto k = static_cast<long>(i);
    if (inside && first < 0) first = k;
    if (!inside && first >= 0) {
      out.push_back({first, k - 1});
      first = -1;
    }
  }
  return out;
}

// Steps missing on any stream (the streams' `missing`, merged).
nlohmann::json Gaps(const replay::Episode& e) {
  const auto size = static_cast<std::size_t>(e.total_steps + 1);
  std::vector<char> missing(size, 0);
  for (const replay::StreamStats* s : {&e.outputs, &e.commands, &e.disturbances})
    for (const auto& [a, b] : s->missing)
      for (long k = std::max(0L, a); k <= b && k < static_cast<long>(size); ++k) missing[k] = 1;
  return Ranges(size, [&](std::size_t k) { return missing[k] != 0; });
}

// Commands filled from the plant's trajectory chunks (a command message
// always carries its status; a filled step has none). The log reader does not
// say which y and n steps were filled, only how many (the streams'
// filled_from_chunks in the replay object).
nlohmann::json Repairs(const replay::Episode& e) {
  return Ranges(e.u.size(), [&](std::size_t k) { return e.has_u[k] && e.status[k] < 0; });
}

// An episode may have up to transport::kMaxEpisodeSteps steps: above this
// many the series holds every stride-th step (the replay object's metrics are
// still the whole episode's).
constexpr std::size_t kMaxSeriesSteps = 500000;

nlohmann::json Series(const replay::Episode& e) {
  nlohmann::json t = nlohmann::json::array(), y = t, u = t, n = t;
  const double dt = e.has_config ? e.spec.dt_s : std::nan("");
  const std::size_t stride = std::max<std::size_t>(1, (e.y.size() + kMaxSeriesSteps - 1) / kMaxSeriesSteps);
  for (std::size_t i = 0; i < e.y.size(); i += stride) {
    t.push_back(results::JsonNumber(static_cast<double>(i) * dt));
    y.push_back(results::JsonNumber(e.y[i]));
    u.push_back(results::JsonNumber(e.u[i]));
    n.push_back(results::JsonNumber(e.n[i]));
  }
  return {{"t", t}, {"stride", stride},
          {"y", y}, {"u", u},
          {"n", n}, {"r", e.has_config ? results::JsonNumber(e.spec.reference) : nlohmann::json(nullptr)}};
}

}  // namespace

LogStore::LogStore(const std::string& log_dir) : log_dir_(log_dir) {
  std::string pattern = (fs::temp_directory_path() / "pidlab-serve-uploads-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("cannot make a directory for uploads: " + pattern);
  upload_dir_ = pattern;
}

LogStore::~LogStore() {
  std::error_code ignored;
  fs::remove_all(upload_dir_, ignored);
}

std::string LogStore::NewId() { return "log" + std::to_string(++next_id_); }

void LogStore::Remember(const std::string& id, std::shared_ptr<OpenLog> log) {
  if (open_.emplace(id, std::move(log)).second) open_order_.push_back(id);
  while (open_order_.size() > kMaxOpenLogs) {
    open_.erase(open_order_.front());
    open_order_.pop_front();
  }
}

server::Reply LogStore::OpenFile(const std::string& file, const std::string& name) {
  auto log = std::make_shared<OpenLog>();
  log->name = name;
  replay::ReadOptions options;  // every prefix, as `pidlab replay` without flags
  if (const Status st = replay::ReadLog(file, options, &log->contents); !st.ok()) {
    std::string error = st.message();
    // The page is told the name it gave, never the server's own path.
    for (std::size_t at; (at = error.find(file)) != std::string::npos;) error.replace(at, file.size(), name);
    return Bad("log " + Quote(name) + ": " + Truncate(error, 200));
  }
  const std::string id = NewId();
  nlohmann::json reply = results::LogJson(log->contents, name);
  reply["type"] = "log";
  reply["log_id"] = id;
  reply["name"] = name;
  for (const replay::Episode& e : log->contents.episodes)
    reply["episodes"].push_back(results::EvaluatedEpisodeJson(e));
  Remember(id, std::move(log));
  return {200, reply};
}

// `path` relative to the log directory; refused if it resolves (symbolic
// links followed) outside it or is not a regular file.
server::Reply LogStore::OpenPath(const std::string& path) {
  std::error_code ec;
  const fs::path root = fs::canonical(log_dir_, ec);
  if (ec) return Bad("the log directory cannot be read: " + ec.message());
  if (path.empty() || path.find('\0') != std::string::npos)
    return Bad("log path " + Quote(path) + " is empty");
  const fs::path target = fs::weakly_canonical(root / path, ec);
  const fs::path relative = ec ? fs::path() : target.lexically_relative(root);
  if (ec || relative.empty() || *relative.begin() == "..")
    return Bad("log path " + Quote(Truncate(path, 200)) + " is outside the log directory");
  if (!fs::is_regular_file(target, ec))
    return Bad("log path " + Quote(Truncate(path, 200)) + " is not a file in the log directory");
  return OpenFile(target.string(), relative.string());
}

server::Reply LogStore::Open(const nlohmann::json& request) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto path = request.find("path");
  const auto id = request.find("log_id");
  if ((path == request.end()) == (id == request.end()))
    return Bad("a log_open request needs either a path or a log_id");
  if (path != request.end()) {
    if (!path->is_string()) return Bad("log path " + Truncate(path->dump(), 200) + " must be a string");
    return OpenPath(path->get<std::string>());
  }
  const std::string key = id->is_string() ? id->get<std::string>() : id->dump();
  const auto upload = uploads_.find(key);
  if (upload == uploads_.end())
    return Bad("log_id " + Quote(Truncate(key, 200)) + " is no uploaded log (at most " +
               std::to_string(kMaxUploads) + " are kept)");
  return OpenFile(upload->second.path, upload->second.name);
}

server::Reply LogStore::Episode(const nlohmann::json& request) {
  std::shared_ptr<OpenLog> log;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto id = request.find("log_id");
    const std::string key = id == request.end() ? "" : id->is_string() ? id->get<std::string>() : id->dump();
    const auto it = open_.find(key);
    if (it == open_.end())
      return Bad("log_id " + Quote(Truncate(key, 200)) + " is not open (at most " +
                 std::to_string(kMaxOpenLogs) + " logs are kept open: open it again)");
    log = it->second;
  }
  const auto index = request.find("index");
  const long count = static_cast<long>(log->contents.episodes.size());
  if (index == request.end() || !index->is_number_integer() || index->get<long>() < 0 ||
      index->get<long>() >= count)
    return Bad("index " + (index == request.end() ? std::string("(none)") : Truncate(index->dump(), 50)) +
               " is not an episode of the log (0.." + std::to_string(count - 1) + ")");
  const auto redrive = request.find("redrive");
  if (redrive != request.end() && !redrive->is_boolean())
    return Bad("redrive " + Truncate(redrive->dump(), 50) + " must be true or false");
  const replay::Episode& e = log->contents.episodes[static_cast<std::size_t>(index->get<long>())];
  nlohmann::json replayed = results::EvaluatedEpisodeJson(e);
  if (redrive != request.end() && redrive->get<bool>())
    replayed["redrive"] = results::RedriveJson(replay::Redrive(e));
  return {200,
          {{"type", "log_episode"},
           {"log_id", request["log_id"]},
           {"index", index->get<long>()},
           {"replay", replayed},
           {"series", Series(e)},
           {"gaps", Gaps(e)},
           {"repairs", Repairs(e)}}};
}

server::Reply LogStore::Upload(const std::string& name, const std::string& body) {
  if (!GoodUploadName(name))
    return Bad("upload name " + Quote(Truncate(name, 100)) +
               " must be a file name of letters, digits, '.', '_' and '-' (at most 100)");
  if (body.empty()) return Bad("log " + Quote(name) + " holds no LCM event (an empty file)");
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string id = NewId();
  const std::string file = (fs::path(upload_dir_) / (id + "-" + name)).string();
  // Whole or not at all: a full disk leaves no half log to be opened later.
  if (const Status stored = io::WriteFile(file, body); !stored.ok())
    return {500, {{"error", "the upload could not be stored: " + stored.message()}}};
  uploads_[id] = {name, file};
  upload_order_.push_back(id);
  while (upload_order_.size() > kMaxUploads) {
    std::error_code ignored;
    fs::remove(uploads_[upload_order_.front()].path, ignored);
    uploads_.erase(upload_order_.front());
    upload_order_.pop_front();
  }
  return {200, {{"log_id", id}, {"name", name}, {"bytes", body.size()}}};
}

// An id as the page sent it: a string, or any other JSON as its text.
static std::string IdText(const nlohmann::json& id) {
  return id.is_string() ? id.get<std::string>() : id.dump();
}

bool LogStore::UploadedFile(const nlohmann::json& id, std::string* path, std::string* name,
                            std::string* error) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string key = IdText(id);
  const auto upload = uploads_.find(key);
  if (upload == uploads_.end()) {
    *error = "upload_id " + Quote(Truncate(key, 200)) + " is no upload (at most " +
             std::to_string(kMaxUploads) + " are kept: upload it again)";
    return false;
  }
  *path = upload->second.path;
  *name = upload->second.name;
  return true;
}

bool LogStore::OpenedEpisode(const nlohmann::json& log_id, const nlohmann::json& index,
                             replay::Episode* episode, std::string* name, std::string* error) {
  std::shared_ptr<OpenLog> log;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = open_.find(IdText(log_id));
    if (it == open_.end()) {
      *error = "log_id " + Quote(Truncate(IdText(log_id), 200)) + " is not open (at most " +
               std::to_string(kMaxOpenLogs) + " logs are kept open: open it again)";
      return false;
    }
    log = it->second;
  }
  const long count = static_cast<long>(log->contents.episodes.size());
  if (!index.is_number_integer() || index.get<long>() < 0 || index.get<long>() >= count) {
    *error = "index " + Truncate(index.dump(), 50) + " is not an episode of the log (0.." +
             std::to_string(count - 1) + ")";
    return false;
  }
  *episode = log->contents.episodes[static_cast<std::size_t>(index.get<long>())];
  *name = log->name;
  return true;
}

std::string LogStore::StoreModel(const std::string& text, std::string* error) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string file =
      (fs::path(upload_dir_) / ("model" + std::to_string(++next_model_) + ".json")).string();
  if (const Status stored = io::WriteFile(file, text); !stored.ok()) {
    *error = "the model could not be stored: " + stored.message();
    return "";
  }
  models_.push_back(file);
  while (models_.size() > kMaxModels) {
    std::error_code ignored;
    fs::remove(models_.front(), ignored);
    models_.pop_front();
  }
  return file;
}

void ServeLogs(LogStore* store) { g_store = store; }

LogStore* ServedLogs() { return g_store; }

server::Reply AnswerLogOpen(const nlohmann::json& request) {
  return g_store ? g_store->Open(request) : Bad("logs are not served here");
}

server::Reply AnswerLogEpisode(const nlohmann::json& request) {
  return g_store ? g_store->Episode(request) : Bad("logs are not served here");
}

}  // namespace pidlab::cli
