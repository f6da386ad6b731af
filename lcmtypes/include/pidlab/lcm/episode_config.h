#pragma once
// The episode configuration as it travels in lcmt_episode_config: built by the
// client from a plant, gains and loop options, and turned back into them by
// each process (and by a log replay), so the processes keep no state between
// episodes.

#include <cstdint>
#include <pidlab/lcmt_episode_config.hpp>
#include <string>

#include "pidlab/tuner/closed_loop.h"

namespace pidlab::lcm_trio {

/// How the trio recovers from loss and when it gives up.
struct RecoveryOptions {
  /// Resend the last message after this long without an answer, s (> 0).
  double retransmit_interval_s = 0.002;
  /// Give up after this long without progress, naming the silent process, s.
  double silence_deadline_s = 1.0;

  bool IsValid(std::string* error) const;
};

/// One episode, decoded.
struct EpisodeSpec {
  int64_t episode_id = 0;
  Plant plant;
  PidGains gains;
  /// options.pid.dt_s equals options.dt_s; options.disturbance is the
  /// disturbance of this episode.
  LoopOptions options;
  double reference = 1.0;
  long total_steps = 0;
  RecoveryOptions recovery;
};

/// The message for an episode. `disturbance` replaces options.disturbance.
pidlab::lcmt_episode_config MakeEpisodeConfig(int64_t episode_id, const Plant& plant, const PidGains& gains,
                                              const LoopOptions& options,
                                              const DisturbanceOptions& disturbance,
                                              const RecoveryOptions& recovery);

/// Decodes and validates a configuration. Returns false with *error naming
/// the offending field (a stranger's malformed config must not crash a process).
bool ParseEpisodeConfig(const pidlab::lcmt_episode_config& msg, EpisodeSpec* spec, std::string* error);

}  // namespace pidlab::lcm_trio
