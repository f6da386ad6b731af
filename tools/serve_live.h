#pragma once
// The live scope's requests of `pidlab serve --lcm-url URL` (docs/live.md):
// server_info, live_subscribe, live_unsubscribe, live_select, live_data and
// run_on_trio, answered from a monitor::LiveMonitor on its own thread (the
// server's thread never waits on LCM) and streamed to every subscribed
// connection by one sender thread: live_status at most 10 times a second,
// binary view frames at most 30 times a second, latest wins.

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/monitor/live_monitor.h"
#include "pidlab/server/server.h"

namespace pidlab::cli {

class LiveService {
 public:
  /// Watches the trio of each entry's lcm_url (one or several: `pidlab
  /// launch --trios K`) with its prefix and key; run_on_trio runs its
  /// episodes on the first. `lcm_url` is the --lcm-url text, echoed.
  /// Throws std::runtime_error if LCM cannot start on a URL.
  LiveService(const std::vector<episode_client::EpisodeClientOptions>& trios, const std::string& lcm_url);
  /// Stops the monitor and sender threads and joins them, and the
  /// run_on_trio worker (after its episode).
  ~LiveService();
  LiveService(const LiveService&) = delete;
  LiveService& operator=(const LiveService&) = delete;

  /// One live request (IsLiveRequest); 400 with one line for a bad one.
  server::Reply Answer(const std::string& type, const nlohmann::json& request,
                       const std::shared_ptr<server::Connection>& connection);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Whether `type` is one of the live requests.
bool IsLiveRequest(const std::string& type);
/// The service the live requests go to (null: `pidlab serve` without
/// --lcm-url); set by cmd_serve.cc for the server's lifetime.
void SetLiveService(LiveService* service);
/// A live request to the service set, else 400 "live: pidlab serve was
/// started without --lcm-url" (server_info answers live: false).
server::Reply AnswerLive(const std::string& type, const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection);

/// What the monitors of the trios watched hear, merged.
struct LiveView {
  /// Each trio's snapshot, in --lcm-url's order, and its URL.
  std::vector<monitor::MonitorSnapshot> trios;
  std::vector<std::string> trio_urls;
  /// The episodes of every trio, oldest first (by when their configuration
  /// was heard), at most kMaxShownEpisodes; trio_of[i] is episodes[i]'s trio, 1..K.
  std::vector<monitor::EpisodeInfo> episodes;
  std::vector<int> trio_of;
  /// Moves when anything shown changes.
  long version = 0;
};
inline constexpr std::size_t kMaxShownEpisodes = 32;
/// Merges the trios' snapshots (taken in that order) into a LiveView.
LiveView MergeTrios(std::vector<monitor::MonitorSnapshot> trios, std::vector<std::string> urls, long version);

/// The live_status object of `view` (docs/live.md): health is the first
/// trio's, and with several trios "trios" lists each one's URL and health.
nlohmann::json LiveStatusJson(const LiveView& view, const std::string& lcm_url,
                              const std::string& channel_prefix, const int64_t* selected_episode_id,
                              long dropped_frames);

}  // namespace pidlab::cli
