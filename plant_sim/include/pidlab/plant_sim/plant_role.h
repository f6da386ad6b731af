#pragma once
// pidlab-plant's protocol logic. Per step k of an episode it publishes
// y_k = C x_k (PLANT_OUTPUT), waits for u_k (CONTROL) and n_k (requested ahead
// in blocks: DISTURBANCE_REQUEST / DISTURBANCE_BLOCK), then steps
// x_{k+1} = Phi x_k + Gamma (u_k + n_k). It streams its trajectory (TRAJECTORY
// chunks, every 1000 steps or 0.1 s) and answers TRAJECTORY_REQUEST.
// Loss: after a resend timeout without u_k it resends y_k, without n_k it
// requests n again; the timeout comes from the measured round trips
// (RttEstimator, rtt.h: RFC 6298, Karn's rule, exponential backoff; the
// episode's retransmit_interval_s only until the first round trip), and n
// still missing a while after its request is asked for again before the
// lockstep reaches it. After silence_deadline_s without progress it publishes
// a FAILED summary naming the silent process(es). See docs/trio.md.

#include <cstddef>
#include <deque>
#include <memory>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>

#include "pidlab/transport/pacing.h"
#include "pidlab/transport/role.h"
#include "pidlab/transport/rtt.h"

namespace pidlab::plant_sim {

/// The plant answers TRAJECTORY_REQUEST for its current episode and for
/// finished ones it still holds: the trajectories (y, u, n) of the most
/// recent episodes are kept up to this many bytes in total (24 bytes a step:
/// 64 MiB hold about 2.8 million steps), the oldest dropped first; the last
/// finished episode is always kept. `pidlab launch --log` relies on this to
/// repair its log after COMMAND (docs/trio.md).
inline constexpr std::size_t kPlantHistoryBytes = std::size_t{64} << 20;

class PlantRole : public transport::Role {
 public:
  /// realtime_factor > 0 paces every episode: step k starts no earlier than
  /// t0 + k dt / realtime_factor (pacing.h); 0: as fast as the loop goes.
  PlantRole(transport::Transport* transport, transport::LogFn log = {}, bool verbose = false,
            double realtime_factor = 0.0);
  ~PlantRole() override;
  void Tick(double now_s) override;
  double MaxWait() const override;
  bool running() const { return running_; }
  /// The resend timer (measured round trips of y_k -> u_k).
  const transport::RttEstimator& rtt() const { return rtt_; }

 protected:
  void StartEpisode(const transport::EpisodeSpec& spec) override;

 private:
  void OnControl(const pidlab::lcmt_control_command& msg);
  void OnDisturbanceBlock(const pidlab::lcmt_disturbance_block& msg);
  void OnTrajectoryRequest(const pidlab::lcmt_trajectory_request& msg);
  void RequestNoise(long first, long samples);
  struct Episode;
  void PublishChunk(const Episode& ep, long first, long last);
  /// Publishes the current episode's trajectory of steps [streamed, upto) in chunks.
  void StreamTrajectory(long upto);
  void TryAdvance();
  void PublishOutput();
  void Finish(bool ok, const std::string& silent_role, const std::string& message);
  /// Two different payloads for the same episode, channel and step: the
  /// episode fails naming them (never silently the first one wins).
  void Conflict(const char* channel, int64_t step, const std::string& detail);

  const Episode* FindEpisode(int64_t episode_id) const;
  std::unique_ptr<Episode> ep_;
  std::deque<std::unique_ptr<Episode>> history_;  // finished or abandoned episodes, oldest first
  std::size_t history_bytes_ = 0;
  bool running_ = false;
  transport::RttEstimator rtt_;
  double realtime_factor_ = 0.0;
};

}  // namespace pidlab::plant_sim
