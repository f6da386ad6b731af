#pragma once
// The requests of the workbench page (docs/workbench.md, "The protocol"),
// answered with the code of the command line: evaluate (with the plot
// series), fields, paper_designs. `pidlab serve` passes Answer to the server.

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/server/server.h"

namespace pidlab::cli {

class LiveService;

/// One request object of the page, with the WebSocket connection it came on
/// (null over HTTP); 400 with one line for a bad one. The live requests go
/// to `live` (null: `pidlab serve` without --lcm-url).
server::Reply AnswerWorkbenchRequest(const nlohmann::json& request,
                                     const std::shared_ptr<server::Connection>& connection,
                                     LiveService* live);

/// tune (serve_tune.cc): starts the tuning of request["spec"] on a thread;
/// no reply now, its progress and result are posted on `connection`.
server::Reply AnswerTune(const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection);
/// tune_cancel: stops the connection's running tuning at its next iteration.
server::Reply AnswerTuneCancel(const std::shared_ptr<server::Connection>& connection);

/// A job on a thread of its own for one connection (a tuning, a fit): at
/// most one of each kind per connection, cancelled when it closes.
struct ConnectionJob {
  std::atomic<bool> cancel{false};
  std::atomic<bool> done{false};
  /// For the job's progress callback, on its thread: throws JobCancelled once
  /// the job is cancelled or `out` has closed; else whether a progress
  /// message is due (at most ten a second).
  bool ProgressDue(const server::Connection& out);

 private:
  std::chrono::steady_clock::time_point last_progress_;
};
/// What a job's progress callback throws to stop it (StartJob answers it).
struct JobCancelled {};
/// A new job of `kind` ("tune", "identify") on `connection`, or null with
/// *refusal set when one of that kind is still running.
std::shared_ptr<ConnectionJob> StartConnectionJob(const std::shared_ptr<server::Connection>& connection,
                                                  const std::string& kind, std::string* refusal);
/// Asks the connection's running job of `kind` to stop; false if none runs.
bool CancelConnectionJob(const std::shared_ptr<server::Connection>& connection, const std::string& kind);

/// How a kind of job names itself in its replies.
struct JobKind {
  std::string kind;         // "tune": the request, "tune_cancelled" when cancelled
  std::string result_type;  // "tune_result": the reply of a job that failed
  std::string noun;         // "tuning": "the tuning was cancelled", "the tuning failed: ..."
};
/// Runs `work` as the connection's job of `kind` on a thread of its own:
/// {200, null} now (400 while one of that kind runs), and later on
/// `connection` the reply `work` returns, or one naming its cancellation
/// (JobCancelled) or its exception, with the request's id.
server::Reply StartJob(const nlohmann::json& request, const std::shared_ptr<server::Connection>& connection,
                       const JobKind& kind,
                       std::function<nlohmann::json(const std::shared_ptr<ConnectionJob>&)> work);

/// identify (serve_identify.cc): fits request["model"] to an uploaded CSV
/// (upload_id) or an opened log's episode (log_id, index) on a thread, as
/// `pidlab identify` does; progress and result are posted on `connection`.
server::Reply AnswerIdentify(const nlohmann::json& request,
                             const std::shared_ptr<server::Connection>& connection);

/// pil_cost (serve_pil.cc): the design's controller on the emulated
/// Cortex-M3 and M4F in every scalar, its cost per step, stack and size, on a
/// thread; the table is posted on `connection` (docs/pil.md).
server::Reply AnswerPilCost(const nlohmann::json& request,
                            const std::shared_ptr<server::Connection>& connection);

/// The paper's published gains (Tables II-VI, the report's built-in
/// data/paper_tables.csv): [{table, plant, method, disturbance_amplitude,
/// gains: [kp, ki, kd]}].
nlohmann::json PaperDesigns();

}  // namespace pidlab::cli
