#pragma once
// Starting an episode: publish its configuration until the roles that must
// run it have acknowledged it (lcmt_ready CONFIG_ACK). Shared by the tuner's
// episode client (all three roles) and `pidlab replay --redrive --backend lcm`
// (the controller alone).

#include <cstdint>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <set>
#include <string>
#include <vector>

#include "pidlab/transport/transport.h"

namespace pidlab::transport {

/// A READY message from this process (its pid), step -1: PING, ALIVE,
/// CONFIG_ACK (with the episode id) or MARKER (with a nonce in `detail`).
pidlab::lcmt_ready MakeReady(int8_t state, const std::string& role, int64_t episode_id = 0,
                             const std::string& detail = "");

/// A fresh, non-zero episode id: an identifier, not an input of the
/// computation (random device, clock and pid mixed).
int64_t NewEpisodeId();

enum class StartStatus { kStarted, kTimedOut, kLcmError };

class EpisodeStarter {
 public:
  /// Subscribes to READY on `transport`, which must outlive this object.
  explicit EpisodeStarter(Transport* transport);

  /// Publishes `config` (again after 5, 10, 20 and 40 ms, then every
  /// resend_period_s at most) until every role named in
  /// `roles` (e.g. "plant") has acknowledged this episode id, or timeout_s
  /// has passed. On kTimedOut, *missing lists the silent roles ("pidlab-x, ...").
  StartStatus Start(const pidlab::lcmt_episode_config& config, const std::vector<std::string>& roles,
                    double timeout_s, std::string* missing, double resend_period_s = 0.05);

 private:
  Transport* transport_;
  int64_t episode_id_ = 0;
  std::set<std::string> acked_;
};

}  // namespace pidlab::transport
