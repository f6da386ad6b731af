#pragma once
// The live scope's requests of `pidlab serve --lcm-url URL` (docs/live.md):
// server_info, live_subscribe, live_unsubscribe, live_select, live_data and
// run_on_trio. The scope's state (the monitors, the subscribers, the rates
// of what is streamed) is a monitor::LiveScope; this is the request side.

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
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
/// A live request to `live`, or without it (null: `pidlab serve` without
/// --lcm-url) 400 "live: pidlab serve was started without --lcm-url"
/// (server_info answers live: false).
server::Reply AnswerLive(LiveService* live, const std::string& type, const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection);

}  // namespace pidlab::cli
