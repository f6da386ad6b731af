#pragma once
// The episode configuration as it travels in lcmt_episode_config: everything
// the three processes need to run one episode of the sampled loop, so that
// they keep no state between episodes and a log alone rebuilds the episode.
// Built by the tuner's episode client (tuner/episode_client.h), decoded and
// validated by every process and by a log replay.

#include <cstdint>
#include <pidlab/lcmt_episode_config.hpp>
#include <string>

#include "pidlab/controller/pid.h"
#include "pidlab/controller/relay.h"
#include "pidlab/plant_sim/disturbance.h"
#include "pidlab/plant_sim/episode_shape.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"

namespace pidlab::transport {

/// How the trio recovers from loss and when it gives up.
struct RecoveryOptions {
  /// The resend timeout before the plant has measured a round trip, s (> 0);
  /// after that the timeout follows the measured round trips (rtt.h).
  double retransmit_interval_s = 0.002;
  /// Give up after this long without progress, naming the silent process, s.
  /// Long enough that a loaded machine does not trip it (a process starved
  /// of CPU for a second is not dead); independent of the resend timer.
  double silence_deadline_s = 5.0;

  bool IsValid(std::string* error) const;
};

/// Longest episode a process accepts: the plant keeps the whole trajectory
/// (3 doubles a step) for resends.
inline constexpr int64_t kMaxEpisodeSteps = 50000000;

/// One episode, decoded: the sampled loop x_{k+1} = Phi x_k + Gamma (u_k + n_k),
/// u_k = PID(reference, y_k), n_k = n(k dt_s), for k = 0..total_steps-1; with
/// a plant dead time (plant.delay_s: finite, >= 0, ceil(delay / dt) at most
/// kMaxDelaySteps, linear plants only) the delayed step of docs/deadtime.md.
struct EpisodeSpec : EpisodeShape {
  int64_t episode_id = 0;
  Plant plant;
  PidGains gains;
  /// The EpisodeShape's pid.dt_s equals dt_s here.
  long total_steps = 0;  // horizon_s / dt_s
  RecoveryOptions recovery;
  /// The relay autotune in place of the PID (controller/relay.h,
  /// docs/autotune.md): the controller runs a RelayTuner with `gains` as the
  /// previous PID. Carried as controller_mode "relay" and the relay_ fields.
  bool relay = false;
  RelayTuneOptions relay_tune;

  /// A failed Status (kInvalidInput) naming the field (a stranger's malformed config must
  /// not crash a process).
  bool IsValid(std::string* error) const;
};

/// The message for an episode (utime 0; Transport::Publish stamps it).
pidlab::lcmt_episode_config MakeEpisodeConfig(const EpisodeSpec& spec);

/// Decodes and validates a configuration. A failed Status (kInvalidInput) naming
/// the offending field.
Status ParseEpisodeConfig(const pidlab::lcmt_episode_config& msg, EpisodeSpec* spec);

}  // namespace pidlab::transport
