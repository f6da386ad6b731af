// The page's tune and tune_cancel requests (docs/workbench.md): a tuning runs
// on a thread of its own, one at a time per WebSocket connection, sends its
// progress at most ten times a second and ends with the object of `pidlab
// tune --json` (results::TuneSpecJson) or an error.

#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "pidlab/results/tune_run.h"
#include "serve_requests.h"

namespace pidlab::cli {
namespace {

// The connection's jobs, one per kind, cancelled when the connection closes.
struct ConnectionJobs {
  std::map<std::string, std::shared_ptr<ConnectionJob>> jobs;
  ~ConnectionJobs() {
    for (auto& [kind, job] : jobs) job->cancel = true;
  }
};

optim::ProgressCallback ProgressPoster(std::shared_ptr<ConnectionJob> job,
                                       std::shared_ptr<server::Connection> out, nlohmann::json id) {
  return [job, out, id](const optim::TracePoint& tp) {
    if (!job->ProgressDue(*out)) return;
    nlohmann::json m = {
        {"type", "tune_progress"}, {"iteration", tp.iteration}, {"evaluations", tp.evaluations}};
    m["best"] = std::isfinite(tp.best_f) ? nlohmann::json(tp.best_f) : nlohmann::json(nullptr);
    m["id"] = id;
    out->Post(m, "tune_progress");
  };
}

// The job's thread: its reply, or the words of its cancellation or failure.
void RunJob(std::shared_ptr<ConnectionJob> job, std::shared_ptr<server::Connection> out, JobKind kind,
            std::function<nlohmann::json(const std::shared_ptr<ConnectionJob>&)> work, nlohmann::json id) {
  nlohmann::json reply;
  try {
    reply = work(job);
  } catch (const JobCancelled&) {
    reply = {{"type", kind.kind + "_cancelled"}, {"error", "the " + kind.noun + " was cancelled"}};
  } catch (const std::exception& e) {
    reply = {{"type", kind.result_type}, {"error", "the " + kind.noun + " failed: " + e.what()}};
  }
  reply["id"] = id;
  job->done = true;
  out->Post(reply);
}

}  // namespace

bool ConnectionJob::ProgressDue(const server::Connection& out) {
  if (cancel || out.closed()) throw JobCancelled{};
  const auto now = std::chrono::steady_clock::now();
  if (now - last_progress_ < std::chrono::milliseconds(100)) return false;
  last_progress_ = now;
  return true;
}

server::Reply StartJob(const nlohmann::json& request, const std::shared_ptr<server::Connection>& connection,
                       const JobKind& kind,
                       std::function<nlohmann::json(const std::shared_ptr<ConnectionJob>&)> work) {
  std::string refusal;
  const std::shared_ptr<ConnectionJob> job = StartConnectionJob(connection, kind.kind, &refusal);
  if (!job) return {400, {{"error", refusal}}};
  std::thread(RunJob, job, connection, kind, std::move(work), request.value("id", nlohmann::json(nullptr)))
      .detach();
  return {200, nullptr};  // the progress and the result follow on the connection
}

std::shared_ptr<ConnectionJob> StartConnectionJob(const std::shared_ptr<server::Connection>& connection,
                                                  const std::string& kind, std::string* refusal) {
  auto jobs = std::static_pointer_cast<ConnectionJobs>(connection->state);
  if (!jobs) {
    jobs = std::make_shared<ConnectionJobs>();
    connection->state = jobs;
  }
  std::shared_ptr<ConnectionJob>& job = jobs->jobs[kind];
  if (job && !job->done) {
    *refusal = "a " + kind + " job is already running on this connection: " + kind + "_cancel it first";
    return nullptr;
  }
  job = std::make_shared<ConnectionJob>();
  return job;
}

bool CancelConnectionJob(const std::shared_ptr<server::Connection>& connection, const std::string& kind) {
  auto jobs = connection ? std::static_pointer_cast<ConnectionJobs>(connection->state) : nullptr;
  if (!jobs) return false;
  const auto it = jobs->jobs.find(kind);
  const bool running = it != jobs->jobs.end() && it->second && !it->second->done;
  if (running) it->second->cancel = true;
  return running;
}

server::Reply AnswerTune(const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection) {
  if (!connection) return {400, {{"error", "tune runs over the WebSocket /ws, which carries its progress"}}};
  if (!request.contains("spec") || !request["spec"].is_object())
    return {400, {{"error", "a tune request needs a spec object"}}};
  return StartJob(request, connection, {"tune", "tune_result", "tuning"},
                  [connection, spec = request["spec"], id = request.value("id", nlohmann::json(nullptr))](
                      const std::shared_ptr<ConnectionJob>& job) -> nlohmann::json {
                    nlohmann::json result;
                    const Status status =
                        results::TuneSpecJson(spec, ProgressPoster(job, connection, id), &result);
                    if (!status.ok()) return {{"type", "tune_result"}, {"error", status.message()}};
                    return {{"type", "tune_result"}, {"result", result}};
                  });
}

server::Reply AnswerTuneCancel(const std::shared_ptr<server::Connection>& connection) {
  return {200, {{"type", "tune_cancel"}, {"cancelling", CancelConnectionJob(connection, "tune")}}};
}

}  // namespace pidlab::cli
