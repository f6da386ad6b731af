#include "serve_live.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/json/replay_json.h"
#include "pidlab/json/results_json.h"
#include "pidlab/json/spec_run.h"
#include "pidlab/monitor/frames.h"
#include "pidlab/spec/json.h"
#include "pidlab/tune/problem.h"

namespace pidlab::cli {
namespace {

using json::JsonNumber;
using monitor::EpisodeInfo;
using monitor::EpisodeTrace;
using monitor::MonitorSnapshot;
using Clock = std::chrono::steady_clock;

constexpr auto kStatusPeriod = std::chrono::milliseconds(100);  // at most 10 live_status a second
constexpr auto kFramePeriod = std::chrono::milliseconds(33);    // at most 30 frames a second
constexpr int kDefaultColumns = 1000;

nlohmann::json PacingJson(const transport::PacingProgress& p) {
  return {{"step", p.steps},
          {"realtime_factor", JsonNumber(p.factor)},
          {"period_s", JsonNumber(p.period_s)},
          {"missed_deadlines", p.missed_deadlines},
          {"lateness_max_s", JsonNumber(p.lateness_max_s)},
          {"rate_hz", JsonNumber(p.rate_hz)},
          {"lateness_p50_upper_s", JsonNumber(p.UpperPercentile(0.50))},
          {"lateness_p99_upper_s", JsonNumber(p.UpperPercentile(0.99))},
          {"histogram", p.histogram}};
}

nlohmann::json EpisodeJson(const EpisodeInfo& e, int trio) {
  return {{"episode_id", e.episode_id},
          {"trio", trio},
          {"episode_id_text", std::to_string(e.episode_id)},  // exact where a JSON number is not (JavaScript)
          {"plant", e.plant},
          {"gains", {JsonNumber(e.kp), JsonNumber(e.ki), JsonNumber(e.kd)}},
          {"r", JsonNumber(e.r)},
          {"dt_s", JsonNumber(e.dt_s)},
          {"total_steps", e.total_steps},
          {"steps_done", e.steps_done},
          {"status", monitor::StatusName(e.status)},
          {"message", e.message},
          {"realtime", e.realtime.paced() ? json::RealtimeJson(e.realtime) : nlohmann::json(nullptr)},
          {"pacing", e.pacing ? PacingJson(*e.pacing) : nlohmann::json(nullptr)}};
}

// The selected episode of a subscriber: the one chosen if still kept, else the newest.
const EpisodeInfo* Selected(const LiveView& v, const std::optional<int64_t>& chosen) {
  if (v.episodes.empty()) return nullptr;
  if (chosen)
    for (const EpisodeInfo& e : v.episodes)
      if (e.episode_id == *chosen) return &e;
  return chosen ? nullptr : &v.episodes.back();
}

// Which episodes there are and how each ended: a change posts live_status at once.
std::string EpisodeSetKey(const LiveView& v) {
  std::string key;
  for (const EpisodeInfo& e : v.episodes)
    key += std::to_string(e.episode_id) + ":" + monitor::StatusName(e.status) + ",";
  return key;
}

monitor::FrameInfo InfoOf(const EpisodeInfo& e, long dropped_frames) {
  return {e.episode_id, e.dt_s, e.total_steps, e.steps_done, dropped_frames};
}

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

// One subscribed connection, touched by the sender thread (and by the
// server's thread under the service's mutex).
struct Subscriber {
  std::weak_ptr<server::Connection> connection;
  int columns = kDefaultColumns;
  std::optional<int64_t> chosen;
  Clock::time_point last_status{}, last_frame{};
  long status_version = -1;
  std::string episode_set;
  int64_t framed_episode = 0;
  long framed_steps = -1;
  std::map<int64_t, bool> final_sent;
};

}  // namespace

LiveView MergeTrios(std::vector<MonitorSnapshot> trios, std::vector<std::string> urls, long version) {
  LiveView v;
  std::vector<std::pair<const EpisodeInfo*, int>> all;
  for (std::size_t t = 0; t < trios.size(); ++t)
    for (const EpisodeInfo& e : trios[t].episodes) all.push_back({&e, static_cast<int>(t) + 1});
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.first->first_heard_s < b.first->first_heard_s;
  });
  const std::size_t first = all.size() > kMaxShownEpisodes ? all.size() - kMaxShownEpisodes : 0;
  for (std::size_t i = first; i < all.size(); ++i) {
    v.episodes.push_back(*all[i].first);
    v.trio_of.push_back(all[i].second);
  }
  v.trios = std::move(trios);
  v.trio_urls = std::move(urls);
  v.version = version;
  return v;
}

namespace {

nlohmann::json HealthJson(const MonitorSnapshot& s) {
  nlohmann::json roles = nlohmann::json::object();
  for (int r = 0; r < monitor::kRoleCount; ++r) {
    const monitor::RoleHealth& h = s.roles[static_cast<std::size_t>(r)];
    roles[monitor::RoleName(static_cast<monitor::Role>(r))] = {
        {"last_heard_s", std::isnan(h.last_heard_s)
                             ? nlohmann::json(nullptr)
                             : nlohmann::json(std::max(0.0, s.now_s - h.last_heard_s))},
        {"pid", h.pid != 0 ? nlohmann::json(h.pid) : nlohmann::json(nullptr)}};
  }
  return {{"roles", roles},
          {"received", s.counters.received},
          {"undecodable", s.counters.undecodable},
          {"unauthenticated", s.counters.unauthenticated},
          {"replayed", s.counters.replayed},
          {"trajectory_requests", s.trajectory_requests}};
}

// The tunings the trios' monitors heard (a tuning publishes on its first
// trio), oldest first.
nlohmann::json TuningsJson(const LiveView& v) {
  std::vector<monitor::TuningInfo> all;
  for (const MonitorSnapshot& s : v.trios) all.insert(all.end(), s.tunings.begin(), s.tunings.end());
  std::stable_sort(all.begin(), all.end(),
                   [](const auto& a, const auto& b) { return a.first_heard_s < b.first_heard_s; });
  nlohmann::json out = nlohmann::json::array();
  for (const monitor::TuningInfo& t : all) {
    const bool any = std::isfinite(t.best_objective);
    out.push_back({{"tuning_id", t.tuning_id},
                   {"tuning_id_text", std::to_string(t.tuning_id)},
                   {"status", monitor::TuningStatusName(t.status)},
                   {"method", t.method},
                   {"objective", t.objective},
                   {"trios", t.trios},
                   {"iterations", t.iterations},
                   {"evaluations", t.evaluations},
                   {"best_objective", any ? nlohmann::json(t.best_objective) : nlohmann::json(nullptr)},
                   {"best_gains", any ? nlohmann::json(t.best_gains) : nlohmann::json(nullptr)}});
  }
  return out;
}

}  // namespace

nlohmann::json LiveStatusJson(const LiveView& v, const std::string& lcm_url,
                              const std::string& channel_prefix, const int64_t* selected_episode_id,
                              long dropped_frames) {
  nlohmann::json episodes = nlohmann::json::array();
  for (std::size_t i = 0; i < v.episodes.size(); ++i)
    episodes.push_back(EpisodeJson(v.episodes[i], v.trio_of[i]));
  nlohmann::json status = {
      {"type", "live_status"},
      {"lcm_url", lcm_url},
      {"channel_prefix", channel_prefix},
      {"selected_episode_id",
       selected_episode_id ? nlohmann::json(*selected_episode_id) : nlohmann::json(nullptr)},
      {"selected_episode_id_text",
       selected_episode_id ? nlohmann::json(std::to_string(*selected_episode_id)) : nlohmann::json(nullptr)},
      {"episodes", episodes},
      {"tunings", TuningsJson(v)},
      {"health", v.trios.empty() ? nlohmann::json(nullptr) : HealthJson(v.trios.front())},
      {"dropped_frames", dropped_frames}};
  if (v.trios.size() > 1) {
    nlohmann::json trios = nlohmann::json::array();
    for (std::size_t t = 0; t < v.trios.size(); ++t)
      trios.push_back({{"trio", t + 1}, {"lcm_url", v.trio_urls[t]}, {"health", HealthJson(v.trios[t])}});
    status["trios"] = trios;
  }
  return status;
}

struct LiveService::Impl {
  episode_client::EpisodeClientOptions client;  // the first trio's: run_on_trio
  std::string lcm_url;                          // as given
  std::vector<std::string> urls;                // one per trio
  std::vector<std::unique_ptr<monitor::LiveMonitor>> monitors;
  std::atomic<bool> stop{false};
  std::mutex mutex;  // subscribers, the worker
  std::condition_variable wake;
  std::map<const server::Connection*, Subscriber> subscribers;
  std::vector<std::thread> monitor_threads;
  std::thread sender_thread, worker;
  std::atomic<bool> worker_busy{false};
  bool dirty = false;  // a subscriber came or chose: serve it even if nothing was heard (under mutex)

  static monitor::LiveMonitorOptions MonitorOptions(const episode_client::EpisodeClientOptions& c) {
    monitor::LiveMonitorOptions o;
    o.lcm_url = c.lcm_url;
    o.transport.channel_prefix = c.transport.channel_prefix;
    o.transport.auth_key = c.transport.auth_key;
    return o;
  }

  Impl(const std::vector<episode_client::EpisodeClientOptions>& trios, const std::string& url_text)
      : client(trios.at(0)), lcm_url(url_text) {
    for (const episode_client::EpisodeClientOptions& c : trios) {
      urls.push_back(c.lcm_url);
      monitors.push_back(std::make_unique<monitor::LiveMonitor>(MonitorOptions(c)));
    }
    for (const auto& m : monitors)
      monitor_threads.emplace_back([this, dut = m.get()] {
        while (!stop)
          if (dut->Poll(0.05) < 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      });
    sender_thread = std::thread([this] { SendLoop(); });
  }

  ~Impl() {
    stop = true;
    wake.notify_all();
    for (std::thread& t : monitor_threads) t.join();
    sender_thread.join();
    if (worker.joinable()) worker.join();
  }

  long Version() const {
    long version = 0;
    for (const auto& m : monitors) version += m->version();
    return version;
  }

  LiveView View() const {
    long version = 0;
    std::vector<MonitorSnapshot> trios;
    for (const auto& m : monitors) {
      version += m->version();  // before the snapshot: a change in between shows next time
      trios.push_back(m->Snapshot());
    }
    return MergeTrios(std::move(trios), urls, version);
  }

  bool WithEpisode(int64_t id, const std::function<void(const EpisodeTrace&)>& read) const {
    for (const auto& m : monitors)
      if (m->WithEpisode(id, read)) return true;
    return false;
  }

  void SendLoop() {
    std::unique_lock<std::mutex> lock(mutex);
    long served_version = -1;
    auto served_at = Clock::now();
    while (!stop) {
      wake.wait_for(lock, std::chrono::milliseconds(10));
      if (stop || subscribers.empty()) continue;
      // Nothing heard and nobody new: nothing to send (a closed connection
      // is let go within a second).
      const auto now = Clock::now();
      if (Version() == served_version && !dirty && now - served_at < std::chrono::seconds(1)) continue;
      dirty = false;
      served_at = now;
      const LiveView view = View();
      bool all_sent = true;
      for (auto it = subscribers.begin(); it != subscribers.end();) {
        auto connection = it->second.connection.lock();
        if (!connection || connection->closed()) {
          it = subscribers.erase(it);
          continue;
        }
        all_sent = Serve(view, connection, &it->second) && all_sent;
        ++it;
      }
      served_version = all_sent ? view.version : -1;  // held back by a rate: look again
    }
  }

  // Posts the subscriber's live_status and frames that are due; false if a
  // change was held back by the rates (10 statuses, 30 frames a second).
  bool Serve(const LiveView& s, const std::shared_ptr<server::Connection>& out, Subscriber* sub) {
    bool all_sent = true;
    const long version = s.version;
    const auto now = Clock::now();
    const EpisodeInfo* selected = Selected(s, sub->chosen);
    const std::string set = EpisodeSetKey(s);
    const bool status_due = set != sub->episode_set || version != sub->status_version;
    if (status_due && set == sub->episode_set && now - sub->last_status < kStatusPeriod) all_sent = false;
    if (set != sub->episode_set ||
        (version != sub->status_version && now - sub->last_status >= kStatusPeriod)) {
      const int64_t id = selected ? selected->episode_id : 0;
      out->Post(LiveStatusJson(s, lcm_url, client.transport.channel_prefix, selected ? &id : nullptr,
                               out->dropped()),
                "live_status");
      sub->episode_set = set, sub->status_version = version, sub->last_status = now;
    }
    if (!selected) return all_sent;
    const bool fresh =
        selected->episode_id != sub->framed_episode || selected->steps_done != sub->framed_steps;
    if (fresh && now - sub->last_frame < kFramePeriod) all_sent = false;
    if (fresh && now - sub->last_frame >= kFramePeriod) {
      std::string frame;
      WithEpisode(selected->episode_id, [&](const EpisodeTrace& e) {
        frame = monitor::EncodeViewFrame(InfoOf(e.info, out->dropped()), e.y.data(), e.u.data(), e.n.data(),
                                         e.info.highest_step + 1, sub->columns);
      });
      out->PostBinary(std::move(frame), "live_view");
      sub->framed_episode = selected->episode_id, sub->framed_steps = selected->steps_done;
      sub->last_frame = now;
    }
    // The whole episode once it has ended and every step is in (resent
    // chunks may follow the SUMMARY), never dropped: the page's final arrays.
    const bool whole = selected->steps_done == selected->total_steps + 1 ||
                       selected->status == monitor::EpisodeStatus::kFailed;
    if (selected->status != monitor::EpisodeStatus::kRunning && whole &&
        !sub->final_sent[selected->episode_id]) {
      sub->final_sent[selected->episode_id] = true;
      out->PostBinary(DataFrame(selected->episode_id, out->dropped()));
    }
    if (sub->final_sent.size() > 2 * kMaxShownEpisodes) {  // forget the episodes no longer kept
      std::map<int64_t, bool> kept;
      for (const EpisodeInfo& e : s.episodes)
        if (sub->final_sent.count(e.episode_id)) kept[e.episode_id] = true;
      sub->final_sent = std::move(kept);
    }
    return all_sent;
  }

  // A kind-2 frame of the whole episode (empty if it is not kept).
  std::string DataFrame(int64_t id, long dropped) const {
    std::string frame;
    WithEpisode(id, [&](const EpisodeTrace& e) {
      frame = monitor::EncodeDataFrame(InfoOf(e.info, dropped), 0, e.y.data(), e.u.data(), e.n.data(),
                                       e.info.total_steps + 1);
    });
    return frame;
  }

  server::Reply Subscribe(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int columns = kDefaultColumns;
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
    std::lock_guard<std::mutex> lock(mutex);
    Subscriber& sub = subscribers[c.get()];
    sub = Subscriber{};
    sub.connection = c;
    sub.columns = columns;
    dirty = true;
    wake.notify_all();
    return {200, {{"type", "live_subscribed"}, {"columns", columns}}};
  }

  server::Reply Select(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int64_t id = 0;
    if (!EpisodeIdOf(request, &id))
      return {400, {{"error", "live_select needs an episode_id (a whole number or its decimal text)"}}};
    if (!WithEpisode(id, [](const EpisodeTrace&) {}))
      return {
          400,
          {{"error", "live_select: episode_id " + std::to_string(id) + " is not one of the episodes kept"}}};
    std::lock_guard<std::mutex> lock(mutex);
    auto it = subscribers.find(c.get());
    if (it == subscribers.end()) return {400, {{"error", "live_select: live_subscribe first"}}};
    it->second.chosen = id;
    it->second.episode_set.clear();  // live_status at once, with the new selection
    dirty = true;
    return {200, {{"type", "live_selected"}, {"episode_id", id}, {"episode_id_text", std::to_string(id)}}};
  }

  server::Reply Data(const nlohmann::json& request, const std::shared_ptr<server::Connection>& c) {
    int64_t id = 0;
    if (!EpisodeIdOf(request, &id))
      return {400, {{"error", "live_data needs an episode_id (a whole number or its decimal text)"}}};
    std::string frame = DataFrame(id, c->dropped());
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
  std::string error;
  if (!spec::FromJson(spec_json, &s, nullptr, &error)) throw std::invalid_argument(error);
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
  nlohmann::json result = json::EvaluationJson(problem, trio, "lcm");
  result["steps_per_second"] = JsonNumber(runner.stats().StepsPerSecond());
  if (runner.stats().realtime.paced()) result["realtime"] = json::RealtimeJson(runner.stats().realtime);
  const std::vector<double>&ty = trio.evaluation.y, &ly = local.evaluation.y;
  double max_diff = 0.0;
  for (std::size_t i = 0; i < std::min(ty.size(), ly.size()); ++i)
    max_diff = std::max(max_diff, std::fabs(ty[i] - ly[i]));
  return {{"type", "trio_result"},
          {"loop", "sampled"},
          {"result", result},
          {"prediction", json::EvaluationJson(problem, local, "local")},
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
    : impl_(std::make_unique<Impl>(trios, lcm_url)) {}

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
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->subscribers.erase(connection.get());
  return {200, {{"type", "live_unsubscribed"}}};
}

namespace {
std::atomic<LiveService*> g_live{nullptr};
}

bool IsLiveRequest(const std::string& type) {
  return type == "server_info" || type == "live_subscribe" || type == "live_unsubscribe" ||
         type == "live_select" || type == "live_data" || type == "run_on_trio";
}

void SetLiveService(LiveService* service) { g_live = service; }

server::Reply AnswerLive(const std::string& type, const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection) {
  if (LiveService* live = g_live.load()) return live->Answer(type, request, connection);
  if (type == "server_info")
    return {
        200,
        {{"type", "server_info"}, {"live", false}, {"lcm_url", ""}, {"channel_prefix", ""}, {"auth", false}}};
  return {400, {{"error", "live: pidlab serve was started without --lcm-url"}}};
}

}  // namespace pidlab::cli
