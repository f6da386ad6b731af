#pragma once
// The three processes of the trio as event-driven state machines over a
// Transport: pure protocol logic (no threads, no printing), so that tests can
// run all three and a client inside one memq:// LCM instance.
//
// Lockstep, per step k of an episode:
//   plant       publishes y_k = C x_k                       (PLANT_OUTPUT)
//   controller  answers u_k = PID(r, y_k)                    (CONTROL)
//   plant       waits for u_k and n_k, x_{k+1} = Phi x_k + Gamma (u_k + n_k)
// n does not depend on y: the plant requests it ahead in blocks
// (DISTURBANCE_REQUEST), the disturbance answers n_k = n(k dt) for a block of
// steps (DISTURBANCE_BLOCK). The plant streams its trajectory (TRAJECTORY
// chunks, every 1000 steps or 0.1 s) and answers TRAJECTORY_REQUEST.
// Loss: after retransmit_interval_s without u_k the plant resends y_k, without
// n_k it requests n again; the controller answers a repeated y_k with the u_k
// it already computed (never steps its PID twice); the disturbance is
// stateless. After silence_deadline_s without progress the plant publishes a
// FAILED summary naming the silent process(es).

#include <csignal>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <string>
#include <vector>

#include "pidlab/lcm/episode_config.h"
#include "pidlab/lcm/transport.h"

namespace pidlab::lcm_trio {

/// Where a role reports (one line per episode unless verbose). May be empty.
using LogFn = std::function<void(const std::string& line)>;

struct RoleCounters {
  long episodes = 0;
  long foreign = 0;      // messages of another episode (or before any config)
  long duplicates = 0;   // repeated or out-of-order steps, ignored or re-answered
  long bad_configs = 0;  // configurations that failed validation
  long retransmits = 0;  // messages resent after a silence
};

/// Common part: answers PING with ALIVE, acknowledges configurations.
class Role {
 public:
  Role(Transport* transport, std::string role, LogFn log, bool verbose);
  virtual ~Role() = default;
  /// Time-driven work (resends, deadlines). Call at least every
  /// retransmit interval; `now_s` is NowSeconds().
  virtual void Tick(double now_s) { (void)now_s; }
  /// The longest a caller may wait before the next Tick.
  virtual double MaxWait() const { return 0.05; }
  const RoleCounters& counters() const { return counters_; }
  const std::string& role() const { return role_; }

 protected:
  /// Called for a configuration of a new episode id, already validated.
  virtual void StartEpisode(const EpisodeSpec& spec) = 0;
  void Ack(int64_t episode_id);
  void Log(const std::string& line) const;
  void Verbose(const std::string& line) const;

  Transport* transport_;
  std::string role_;
  LogFn log_;
  bool verbose_;
  RoleCounters counters_;
  int64_t episode_id_ = 0;  // current episode, 0 before the first

 private:
  void OnConfig(const pidlab::lcmt_episode_config& msg);
  void OnReady(const pidlab::lcmt_ready& msg);
};

/// The plant answers TRAJECTORY_REQUEST for its current episode and for
/// finished ones it still holds: the trajectories (y, u, n) of the most
/// recent episodes are kept up to this many bytes in total (24 bytes a step:
/// 64 MiB hold about 2.8 million steps), the oldest dropped first; the last
/// finished episode is always kept. `pidlab launch --log` relies on this to
/// repair its log after COMMAND (docs/trio.md).
inline constexpr std::size_t kPlantHistoryBytes = std::size_t{64} << 20;

class PlantRole : public Role {
 public:
  PlantRole(Transport* transport, LogFn log = {}, bool verbose = false);
  ~PlantRole() override;
  void Tick(double now_s) override;
  double MaxWait() const override;
  bool running() const { return running_; }

 protected:
  void StartEpisode(const EpisodeSpec& spec) override;

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

  const Episode* FindEpisode(int64_t episode_id) const;
  std::unique_ptr<Episode> ep_;
  std::deque<std::unique_ptr<Episode>> history_;  // finished or abandoned episodes, oldest first
  std::size_t history_bytes_ = 0;
  bool running_ = false;
};

class ControllerRole : public Role {
 public:
  ControllerRole(Transport* transport, LogFn log = {}, bool verbose = false);
  ~ControllerRole() override;

 protected:
  void StartEpisode(const EpisodeSpec& spec) override;

 private:
  void OnOutput(const pidlab::lcmt_plant_output& msg);
  struct Episode;
  std::unique_ptr<Episode> ep_;
};

class DisturbanceRole : public Role {
 public:
  DisturbanceRole(Transport* transport, LogFn log = {}, bool verbose = false);
  ~DisturbanceRole() override;

 protected:
  void StartEpisode(const EpisodeSpec& spec) override;

 private:
  void OnRequest(const pidlab::lcmt_disturbance_request& msg);
  struct Episode;
  std::unique_ptr<Episode> ep_;
};

/// Serves `role` until *stop becomes true (checked between waits). Returns 0,
/// or 1 on an LCM error.
int ServeRole(Transport* transport, Role* role, const volatile std::sig_atomic_t* stop);

}  // namespace pidlab::lcm_trio
