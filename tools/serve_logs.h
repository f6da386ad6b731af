#pragma once
// The log requests of the workbench page (docs/workbench.md, "The Logs
// tab"): log_open (a path under --log-dir, or an uploaded log), log_episode
// (one episode's `pidlab replay --json` object with its series, gaps and
// repairs) and the upload route (POST /api/upload). Every reply is built with
// the code of `pidlab replay --json` (results/include/pidlab/results/replay_json.h), and logs are
// read by the same reader (replay/log_reader.h), hostile logs included.

#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/replay/log_reader.h"
#include "pidlab/server/server.h"

namespace pidlab::cli {

/// The logs one `pidlab serve` has opened.
class LogStore {
 public:
  /// Uploaded logs kept on disk at once (the oldest is deleted first).
  static constexpr std::size_t kMaxUploads = 4;
  /// Opened logs kept in memory at once (the oldest is forgotten first).
  static constexpr std::size_t kMaxOpenLogs = 4;

  /// `log_dir`: the directory log_open paths are relative to (must exist).
  /// The uploads' temporary directory is made at once; throws
  /// std::runtime_error if it cannot be.
  explicit LogStore(const std::string& log_dir);
  /// Removes the uploads' temporary directory and everything in it.
  ~LogStore();
  LogStore(const LogStore&) = delete;
  LogStore& operator=(const LogStore&) = delete;

  /// {"type": "log_open", "path": P} or {"type": "log_open", "log_id": ID}.
  server::Reply Open(const nlohmann::json& request);
  /// {"type": "log_episode", "log_id": ID, "index": I, "redrive": bool}.
  server::Reply Episode(const nlohmann::json& request);
  /// POST /api/upload?name=NAME: stores the body as an uploaded log.
  server::Reply Upload(const std::string& name, const std::string& body);

  const std::string& upload_dir() const { return upload_dir_; }

  /// The file of upload `id` and the name it was uploaded as; 400 text in
  /// *error when there is none.
  bool UploadedFile(const nlohmann::json& id, std::string* path, std::string* name, std::string* error);
  /// A copy of episode `index` of the opened log `log_id`, and the log's name.
  bool OpenedEpisode(const nlohmann::json& log_id, const nlohmann::json& index, replay::Episode* episode,
                     std::string* name, std::string* error);
  /// Writes `text` as a new model file in the uploads' directory (at most
  /// kMaxModels kept, the oldest deleted first); its path, or "" when it
  /// could not be written (*error says why).
  std::string StoreModel(const std::string& text, std::string* error);
  static constexpr std::size_t kMaxModels = 32;

 private:
  struct OpenLog {
    std::string name;
    replay::LogContents contents;
  };
  struct StoredUpload {
    std::string name, path;
  };
  server::Reply OpenPath(const std::string& path);
  server::Reply OpenFile(const std::string& file, const std::string& name);
  std::string NewId();

  std::string log_dir_, upload_dir_;
  long next_id_ = 0;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<OpenLog>> open_;  // log id -> log
  std::deque<std::string> open_order_;                    // ids in open_, oldest first
  std::map<std::string, StoredUpload> uploads_;           // upload's log id -> file
  std::deque<std::string> upload_order_;                  // ids in uploads_, oldest first
  std::deque<std::string> models_;                        // model files written, oldest first
  long next_model_ = 0;
  void Remember(const std::string& id, std::shared_ptr<OpenLog> log);
};

/// The store log_open, log_episode and uploads use (null: not served).
void ServeLogs(LogStore* store);
/// The store of ServeLogs (null: logs and uploads are not served).
LogStore* ServedLogs();
/// The log requests' answers through the store of ServeLogs (400 without one).
server::Reply AnswerLogOpen(const nlohmann::json& request);
server::Reply AnswerLogEpisode(const nlohmann::json& request);

}  // namespace pidlab::cli
