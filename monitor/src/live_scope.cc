#include "pidlab/monitor/live_scope.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "pidlab/monitor/frames.h"

namespace pidlab::monitor {
namespace {

using Clock = std::chrono::steady_clock;

constexpr auto kStatusPeriod = std::chrono::milliseconds(100);  // at most 10 statuses a second
constexpr auto kFramePeriod = std::chrono::milliseconds(33);    // at most 30 frames a second

// The selected episode of a subscriber: the one chosen if still kept, else the newest.
const EpisodeInfo* Selected(const LiveView& v, const std::optional<int64_t>& chosen) {
  if (v.episodes.empty()) return nullptr;
  if (chosen)
    for (const EpisodeInfo& e : v.episodes)
      if (e.episode_id == *chosen) return &e;
  return chosen ? nullptr : &v.episodes.back();
}

// Which episodes there are and how each ended: a change posts the status at once.
std::string EpisodeSetKey(const LiveView& v) {
  std::string key;
  for (const EpisodeInfo& e : v.episodes)
    key += std::to_string(e.episode_id) + ":" + StatusName(e.status) + ",";
  return key;
}

FrameInfo InfoOf(const EpisodeInfo& e, long dropped_frames) {
  return {e.episode_id, e.dt_s, e.total_steps, e.steps_done, dropped_frames};
}

// One subscriber, touched by the sender thread (and by the caller's thread
// under the scope's mutex).
struct Subscriber {
  std::shared_ptr<LiveOutlet> outlet;
  int columns = LiveScope::kDefaultColumns;
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

struct LiveScope::State {
  std::vector<std::string> urls;  // one per trio
  std::vector<std::unique_ptr<LiveMonitor>> monitors;
  std::atomic<bool> stop{false};
  std::mutex mutex;  // subscribers, dirty
  std::condition_variable wake;
  std::map<const void*, Subscriber> subscribers;
  std::vector<std::thread> monitor_threads;
  std::thread sender_thread;
  bool dirty = false;  // a subscriber came or chose: serve it even if nothing was heard (under mutex)

  explicit State(const std::vector<LiveMonitorOptions>& trios) {
    for (const LiveMonitorOptions& o : trios) {
      urls.push_back(o.lcm_url);
      monitors.push_back(std::make_unique<LiveMonitor>(o));
    }
    for (const auto& m : monitors)
      monitor_threads.emplace_back([this, dut = m.get()] {
        while (!stop)
          if (dut->Poll(0.05) < 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      });
    sender_thread = std::thread([this] { SendLoop(); });
  }

  ~State() {
    stop = true;
    wake.notify_all();
    for (std::thread& t : monitor_threads) t.join();
    sender_thread.join();
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
      // Nothing heard and nobody new: nothing to send (a closed outlet is
      // let go within a second).
      const auto now = Clock::now();
      if (Version() == served_version && !dirty && now - served_at < std::chrono::seconds(1)) continue;
      dirty = false;
      served_at = now;
      const LiveView view = View();
      bool all_sent = true;
      for (auto it = subscribers.begin(); it != subscribers.end();) {
        if (!it->second.outlet->open()) {
          it = subscribers.erase(it);
          continue;
        }
        all_sent = Serve(view, &it->second) && all_sent;
        ++it;
      }
      served_version = all_sent ? view.version : -1;  // held back by a rate: look again
    }
  }

  // Posts the subscriber's status and frames that are due; false if a
  // change was held back by the rates (10 statuses, 30 frames a second).
  bool Serve(const LiveView& s, Subscriber* sub) {
    LiveOutlet& out = *sub->outlet;
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
      out.PostStatus(s, selected ? &id : nullptr);
      sub->episode_set = set, sub->status_version = version, sub->last_status = now;
    }
    if (!selected) return all_sent;
    const bool fresh =
        selected->episode_id != sub->framed_episode || selected->steps_done != sub->framed_steps;
    if (fresh && now - sub->last_frame < kFramePeriod) all_sent = false;
    if (fresh && now - sub->last_frame >= kFramePeriod) {
      std::string frame;
      WithEpisode(selected->episode_id, [&](const EpisodeTrace& e) {
        frame = EncodeViewFrame(InfoOf(e.info, out.dropped()), e.y.data(), e.u.data(), e.n.data(),
                                e.info.highest_step + 1, sub->columns);
      });
      out.PostView(std::move(frame));
      sub->framed_episode = selected->episode_id, sub->framed_steps = selected->steps_done;
      sub->last_frame = now;
    }
    // The whole episode once it has ended and every step is in (resent
    // chunks may follow the SUMMARY), never dropped: the page's final arrays.
    const bool whole =
        selected->steps_done == selected->total_steps + 1 || selected->status == EpisodeStatus::kFailed;
    if (selected->status != EpisodeStatus::kRunning && whole && !sub->final_sent[selected->episode_id]) {
      sub->final_sent[selected->episode_id] = true;
      out.PostData(DataFrame(selected->episode_id, out.dropped()));
    }
    if (sub->final_sent.size() > 2 * kMaxShownEpisodes) {  // forget the episodes no longer kept
      std::map<int64_t, bool> kept;
      for (const EpisodeInfo& e : s.episodes)
        if (sub->final_sent.count(e.episode_id)) kept[e.episode_id] = true;
      sub->final_sent = std::move(kept);
    }
    return all_sent;
  }

  std::string DataFrame(int64_t id, long dropped) const {
    std::string frame;
    WithEpisode(id, [&](const EpisodeTrace& e) {
      frame = EncodeDataFrame(InfoOf(e.info, dropped), 0, e.y.data(), e.u.data(), e.n.data(),
                              e.info.total_steps + 1);
    });
    return frame;
  }
};

LiveScope::LiveScope(const std::vector<LiveMonitorOptions>& trios) : state_(std::make_unique<State>(trios)) {}

Status LiveScope::status() const {
  for (const auto& m : state_->monitors)
    if (!m->status().ok()) return m->status();
  return Status::Ok();
}

LiveScope::~LiveScope() = default;

void LiveScope::Subscribe(const void* key, std::shared_ptr<LiveOutlet> outlet, int columns) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  Subscriber& sub = state_->subscribers[key];
  sub = Subscriber{};
  sub.outlet = std::move(outlet);
  sub.columns = std::clamp(columns, kMinColumns, kMaxColumns);
  state_->dirty = true;
  state_->wake.notify_all();
}

void LiveScope::Unsubscribe(const void* key) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->subscribers.erase(key);
}

LiveScope::SelectStatus LiveScope::Select(const void* key, int64_t episode_id) {
  if (!state_->WithEpisode(episode_id, [](const EpisodeTrace&) {})) return SelectStatus::kNotKept;
  std::lock_guard<std::mutex> lock(state_->mutex);
  auto it = state_->subscribers.find(key);
  if (it == state_->subscribers.end()) return SelectStatus::kNotSubscribed;
  it->second.chosen = episode_id;
  it->second.episode_set.clear();  // the status at once, with the new selection
  state_->dirty = true;
  return SelectStatus::kSelected;
}

std::string LiveScope::DataFrame(int64_t episode_id, long dropped) const {
  return state_->DataFrame(episode_id, dropped);
}

}  // namespace pidlab::monitor
