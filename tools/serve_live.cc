#include "serve_live.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/monitor/frames.h"
#include "pidlab/monitor/live_scope.h"
#include "pidlab/results/live_json.h"
#include "pidlab/results/replay_json.h"
#include "pidlab/results/results_json.h"
#include "pidlab/spec/json.h"
#include "pidlab/tune/problem.h"

namespace pidlab::cli {
namespace {

using results::JsonNumber;

// request["episode_id"]: a whole number, or its decimal text (JavaScript's
// numbers hold only 53 bits of a 64-bit id). False if neither.
bool EpisodeIdOf(const nlohmann::json& request, int64_t* id) {
  const auto v = request.find("episode_id");
  if (v == request.end()) return false;
  if (v->is_number_integer()) {
    *id = v->get<int64_t>();
    return true;
  }
  if (!v->is_string()) return false;
  const std::string& text = v->get_ref<const std::string&>();
  if (text.empty() || text.size() > 20 || text.find_first_not_of("-0123456789") != std::string::npos)
    return false;
  try {
    std::size_t used = 0;
    *id = std::stoll(text, &used);
    return used == text.size();
  } catch (const std::exception&) {
    return false;
  }
}

// A page's WebSocket as the live scope's outlet: the status as live_status
// (latest wins), view frames latest wins, data frames never dropped.
class ConnectionOutlet final : public monitor::LiveOutlet {
 public:
  ConnectionOutlet(const std::shared_ptr<server::Connection>& connection, std::string lcm_url,
                   std::string channel_prefix)
      : connection_(connection), lcm_url_(std::move(lcm_url)), channel_prefix_(std::move(channel_prefix)) {}

  bool open() const override {
    const auto c = connection_.lock();
    return c && !c->closed();
  }
  long dropped() const override {
    const auto c = connection_.lock();
    return c ? c->dropped() : 0;
  }
  void PostStatus(const monitor::LiveView& view, const int64_t* selected_episode_id) override {
    if (const auto c = connection_.lock())
      c->Post(results::LiveStatusJson(view, lcm_url_, channel_prefix_, selected_episode_id, c->dropped()),
              "live_status");
  }
  void PostView(std::string frame) override {
    if (const auto c = connection_.lock()) c->PostBinary(std::move(frame), "live_view");
  }
  void PostData(std::string frame) override {
    if (const auto c = connection_.lock()) c->PostBinary(std::move(frame));
  }

 private:
  std::weak_ptr<server::Connection> connection_;
  std::string lcm_url_, channel_prefix_;
};

std::vector<monitor::LiveMonitorOptions> MonitorOptions(
    const std::vector<episode_client::EpisodeClientOptions>& trios) {
  std::vector<monitor::LiveMonitorOptions> out;
  for (const episode_client::EpisodeClientOptions& c : trios) {
    monitor::LiveMonitorOptions o;
    o.lcm_url = c.lcm_url;
    o.transport.channel_prefix = c.transport.channel_prefix;
    o.transport.auth_key = c.transport.auth_key;
    out.push_back(o);
  }
  return out;
}

}  // namespace

struct LiveService::Impl {
  episode_client::EpisodeClientOptions client;  // the first trio's: run_on_trio
  std::string lcm_url;                          // as given
  monitor::LiveScope scope;
  std::mutex mutex;  // the worker
  std::thread worker;
  std::atomic<bool> worker_busy{false};

  Impl(const std::vector<episode_client::EpisodeClientOptions>& trios, const std::string& url_text)
      : client(trios.at(0)), lcm_url(url_text), scope(MonitorOptions(trios)) {}

  ~Impl() {
    if (worker.joinable()) worker.join();
  }

  server::Reply Subscribe(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int columns = monitor::LiveScope::kDefaultColumns;
    if (request.contains("columns")) {
      const nlohmann::json& v = request["columns"];
      if (!v.is_number_integer() || v.get<long>() < monitor::kMinColumns ||
          v.get<long>() > monitor::kMaxColumns)
        return {400,
                {{"error", "live_subscribe: columns " + v.dump() + " must be a whole number in " +
                               std::to_string(monitor::kMinColumns) + ".." +
                               std::to_string(monitor::kMaxColumns)}}};
      columns = v.get<int>();
    }
    scope.Subscribe(c.get(), std::make_shared<ConnectionOutlet>(c, lcm_url, client.transport.channel_prefix),
                    columns);
    return {200, {{"type", "live_subscribed"}, {"columns", columns}}};
  }

  server::Reply Select(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int64_t id = 0;
    if (!EpisodeIdOf(request, &id))
      return {400, {{"error", "live_select needs an episode_id (a whole number or its decimal text)"}}};
    switch (scope.Select(c.get(), id)) {
      case monitor::LiveScope::SelectStatus::kNotKept:
        return {400,
                {{"error",
                  "live_select: episode_id " + std::to_string(id) + " is not one of the episodes kept"}}};
      case monitor::LiveScope::SelectStatus::kNotSubscribed:
        return {400, {{"error", "live_select: live_subscribe first"}}};
      case monitor::LiveScope::SelectStatus::kSelected:
        break;
    }
    return {200, {{"type", "live_selected"}, {"episode_id", id}, {"episode_id_text", std::to_string(id)}}};
  }

  server::Reply Data(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int64_t id = 0;
    if (!EpisodeIdOf(request, &id))
      return {400, {{"error", "live_data needs an episode_id (a whole number or its decimal text)"}}};
    std::string frame = scope.DataFrame(id, c->dropped());
    if (frame.empty())
      return {
          400,
          {{"error", "live_data: episode_id " + std::to_string(id) + " is not one of the episodes kept"}}};
    c->PostBinary(std::move(frame));
    return {200, nullptr};  // the frame is the answer
  }

  server::Reply RunOnTrio(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c);
};

namespace {

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// The spec on the trio and in process, both on the sampled loop: the trio_result object.
nlohmann::json TrioResult(const nlohmann::json& spec_json,
                          const episode_client::EpisodeClientOptions& client) {
  spec::EvaluateSpec s;
  if (const Status st = spec::FromJson(spec_json, &s, nullptr); !st.ok())
    throw std::invalid_argument(st.message());
  s.loop.loop = "sampled";  // the trio runs the sampled loop
  tune::EvaluationProblem problem;
  if (Status built = tune::BuildEvaluation(s, tune::BuildOptions{}, &problem); !built.ok())
    throw std::invalid_argument(built.message());
  tune::EvaluationRunOptions run;
  run.monte_carlo = false;  // one loop on each side, no draws
  tune::EvaluationResult local, trio;
  if (Status ran = tune::RunEvaluation(problem, run, &local); !ran.ok())
    throw std::invalid_argument(ran.message());
  episode_client::EpisodeClient runner(client);
  run.runner = runner.AsRunner();
  if (Status ran = tune::RunEvaluation(problem, run, &trio); !ran.ok())
    throw std::runtime_error(ran.message());
  nlohmann::json result = results::EvaluationJson(problem, trio, "lcm");
  result["steps_per_second"] = JsonNumber(runner.stats().StepsPerSecond());
  if (runner.stats().realtime.paced()) result["realtime"] = results::RealtimeJson(runner.stats().realtime);
  const std::vector<double>&ty = trio.evaluation.y, &ly = local.evaluation.y;
  double max_diff = 0.0;
  for (std::size_t i = 0; i < std::min(ty.size(), ly.size()); ++i)
    max_diff = std::max(max_diff, std::fabs(ty[i] - ly[i]));
  return {{"type", "trio_result"},
          {"loop", "sampled"},
          {"result", result},
          {"prediction", results::EvaluationJson(problem, local, "local")},
          {"series", {{"t", trio.evaluation.t}, {"y", ty}}},
          {"prediction_series", {{"t", local.evaluation.t}, {"y", ly}}},
          {"max_abs_difference", JsonNumber(max_diff)},
          {"bit_identical", SameBits(trio.evaluation.t, local.evaluation.t) && SameBits(ty, ly)}};
}

}  // namespace

server::Reply LiveService::Impl::RunOnTrio(const nlohmann::json& request,
                                           const std::shared_ptr<server::Connection>& c) {
  if (!c) return {400, {{"error", "run_on_trio runs over the WebSocket /ws, which carries its result"}}};
  if (!request.contains("spec") || !request["spec"].is_object())
    return {400, {{"error", "a run_on_trio request needs a spec object"}}};
  std::lock_guard<std::mutex> lock(mutex);
  if (worker_busy) return {400, {{"error", "run_on_trio: an episode is already running on the trio"}}};
  if (worker.joinable()) worker.join();  // the last one, finished
  worker_busy = true;
  const nlohmann::json id = request.contains("id") ? request["id"] : nlohmann::json(nullptr);
  worker = std::thread([this, spec = request["spec"], out = c, id] {
    nlohmann::json reply;
    try {
      reply = TrioResult(spec, client);
    } catch (const std::exception& e) {
      reply = {{"type", "trio_error"}, {"error", std::string("run_on_trio: ") + e.what()}};
    }
    if (!id.is_null()) reply["id"] = id;
    out->Post(reply);
    worker_busy = false;
  });
  return {200, {{"type", "run_on_trio_started"}, {"loop", "sampled"}}};
}

LiveService::LiveService(const std::vector<episode_client::EpisodeClientOptions>& trios,
                         const std::string& lcm_url)
    : impl_(std::make_unique<Impl>(trios, lcm_url)) {
  // LCM did not start on a URL: cmd_serve names --lcm-url (exit 2).
  if (const Status st = impl_->scope.status(); !st.ok()) throw std::runtime_error(st.message());
}

LiveService::~LiveService() = default;

server::Reply LiveService::Answer(const std::string& type, const nlohmann::json& request,
                                  const std::shared_ptr<server::Connection>& connection) {
  const bool auth = impl_->client.transport.auth_key.has_value();
  if (type == "server_info")
    return {200,
            {{"type", "server_info"},
             {"live", true},
             {"lcm_url", impl_->lcm_url},
             {"channel_prefix", impl_->client.transport.channel_prefix},
             {"auth", auth}}};
  if (type == "run_on_trio") return impl_->RunOnTrio(request, connection);
  if (!connection) return {400, {{"error", type + " runs over the WebSocket /ws, which carries its frames"}}};
  if (type == "live_subscribe") return impl_->Subscribe(request, connection);
  if (type == "live_select") return impl_->Select(request, connection);
  if (type == "live_data") return impl_->Data(request, connection);
  impl_->scope.Unsubscribe(connection.get());
  return {200, {{"type", "live_unsubscribed"}}};
}

bool IsLiveRequest(const std::string& type) {
  return type == "server_info" || type == "live_subscribe" || type == "live_unsubscribe" ||
         type == "live_select" || type == "live_data" || type == "run_on_trio";
}

server::Reply AnswerLive(LiveService* live, const std::string& type, const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection) {
  if (live) return live->Answer(type, request, connection);
  if (type == "server_info")
    return {
        200,
        {{"type", "server_info"}, {"live", false}, {"lcm_url", ""}, {"channel_prefix", ""}, {"auth", false}}};
  return {400, {{"error", "live: pidlab serve was started without --lcm-url"}}};
}

}  // namespace pidlab::cli
