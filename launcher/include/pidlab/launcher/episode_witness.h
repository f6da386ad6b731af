#pragma once
// What `pidlab launch --log` hears of the trio's episodes itself, to check
// its log against: the first copy of every episode configuration
// (EPISODE_CONFIG) and the id of every episode the plant ended (SUMMARY).
//
// lcm-logger 1.3.1 holds at most 30 messages between LCM's receive thread and
// its own and drops the rest silently; a configuration is published until the
// three roles acknowledge it, often once, so a starved logger can lose every
// copy. launch's own subscriptions hold 4096 (TransportOptions::
// queue_capacity): a configuration the logger lost is almost always here, and
// an episode the plant ran is known even when the log holds nothing of it.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <pidlab/lcmt_episode_config.hpp>
#include <set>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"
#include "pidlab/transport/auth.h"
#include "pidlab/transport/transport.h"

namespace pidlab::launcher {

class EpisodeWitness {
 public:
  /// Episodes remembered (configurations and ended ids each), the oldest
  /// forgotten first: a configuration is about 1 kB, so at most 16 MiB.
  static constexpr std::size_t kMaxEpisodes = std::size_t{1} << 14;

  /// Subscribes on `transport`, which must outlive this object. With a key
  /// (the transport's) only authenticated messages count.
  explicit EpisodeWitness(transport::Transport* transport, std::size_t max_episodes = kMaxEpisodes);
  EpisodeWitness(const EpisodeWitness&) = delete;
  EpisodeWitness& operator=(const EpisodeWitness&) = delete;

  /// The first copy heard of episode `episode_id`'s configuration, or nullptr.
  const pidlab::lcmt_episode_config* Config(int64_t episode_id) const;
  /// The episodes whose SUMMARY the plant published, in the order heard.
  const std::deque<int64_t>& ended() const { return ended_order_; }
  bool Ended(int64_t episode_id) const { return ended_.count(episode_id) > 0; }

 private:
  void OnConfig(const pidlab::lcmt_episode_config& config);
  void OnEnded(int64_t episode_id);

  std::size_t max_episodes_;
  std::map<int64_t, pidlab::lcmt_episode_config> configs_;
  std::deque<int64_t> config_order_;
  std::set<int64_t> ended_;
  std::deque<int64_t> ended_order_;
};

/// Writes `configs` into `file` (an LCM log, overwritten) on `channel`, each
/// event at the configuration's utime, in time order, every payload with its
/// tag when `key` is given (as the client sent it). A failed Status
/// (kIoFailed) naming the file if it cannot be written.
Status WriteConfigLog(std::vector<pidlab::lcmt_episode_config> configs, const std::string& channel,
                      const std::optional<transport::AuthKey>& key, const std::string& file);

/// "ID", "ID and ID", "ID, ID, ID and N more" (at most `shown` ids).
std::string EpisodeList(const std::vector<int64_t>& ids, std::size_t shown = 3);

}  // namespace pidlab::launcher
