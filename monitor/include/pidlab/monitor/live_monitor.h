#pragma once
// LiveMonitor: a running trio as a watcher hears it (docs/live.md). It joins
// the trio's LCM group on the base URL only and subscribes to the channels
// that carry an episode's story: EPISODE_CONFIG, READY, TRAJECTORY, SUMMARY,
// PACING, DISTURBANCE_REQUEST, DISTURBANCE_BLOCK and TRAJECTORY_REQUEST,
// and TUNE_PROGRESS (a tuning over the trio, as `pidlab tune --backend lcm`
// publishes it).
// It never listens to the step lanes (PLANT_OUTPUT, CONTROL): a watcher
// that woke for every lockstep message would slow the lockstep; the plant's
// TRAJECTORY chunks carry every y_k, u_k and n_k on the base URL anyway.
//
// Everything it hears is untrusted: a chunk whose steps fall outside its
// episode, or an episode longer than max_total_steps, is counted and
// ignored; with an auth key, a message without a valid MAC never reaches it
// (the transport counts it as unauthenticated).
//
// Threads: Poll() on one thread (the one that owns the LCM instance),
// Snapshot() and WithEpisode() from any other.

#include <array>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"
#include "pidlab/transport/pacing.h"
#include "pidlab/transport/protocol.h"
#include "pidlab/transport/transport.h"

namespace pidlab::monitor {

struct LiveMonitorOptions {
  /// The trio's LCM URL (its base URL: the step lanes are never joined).
  std::string lcm_url = transport::kDefaultLcmUrl;
  /// The trio's channel prefix and auth key (fault injection stays off).
  transport::TransportOptions transport;
  /// Episodes kept, oldest dropped first. 1..1024.
  int max_episodes = 32;
  /// Longest episode kept (total_steps); a configuration beyond it is
  /// counted in rejected and not shown. 1..1e8 (three doubles per step).
  long max_total_steps = 10000000;
  /// Steps of all the episodes kept together: the oldest are dropped to
  /// make room for a new one (memory: about 25 bytes a step, so at most
  /// about 500 MB however many configurations a stranger sends).
  /// max_total_steps..1e9.
  long max_kept_steps = 20000000;

  /// Names the field, its value and the rule on failure.
  bool IsValid(std::string* error) const;
};

enum class EpisodeStatus { kRunning, kComplete, kFailed };
/// "running", "complete", "failed".
const char* StatusName(EpisodeStatus status);

/// A relay episode (docs/autotune.md) as the watcher follows it: a
/// RelayTuner stepped over the steps received in order, its cycles, and the
/// estimates of its latest cycles as they converge (autotune::
/// EstimateFromCycles, from the second cycle after the approach on).
struct RelayView {
  bool active = false;  ///< a relay episode
  std::string phase;    ///< hold | relay | done | aborted
  std::string why;      ///< how it ended
  double u0 = 0.0, y0 = 0.0, noise_sigma = 0.0, hysteresis = 0.0, d_high = 0.0, d_low = 0.0;
  int cycles = 0, restarts = 0;
  double last_period_s = std::numeric_limits<double>::quiet_NaN();
  double last_amplitude = std::numeric_limits<double>::quiet_NaN();
  long steps_followed = 0;
  bool estimates = false;  ///< the fields below are set
  bool converged = false;
  double period_s = 0.0, period_ci_s = 0.0, ku = 0.0, pu_s = 0.0, ku_describing_function = 0.0;
  double gain = 0.0, time_constant_s = 0.0, delay_s = 0.0;
  bool integrating = false;
  std::string model_from, message;
};

/// One episode's figures, without its trajectory.
struct EpisodeInfo {
  int64_t episode_id = 0;
  /// transport::NowSeconds() when its configuration was heard (orders the
  /// episodes of several monitors).
  double first_heard_s = 0.0;
  std::string plant;
  double kp = 0.0, ki = 0.0, kd = 0.0;
  double r = 0.0;
  double dt_s = 0.0;
  long total_steps = 0;
  /// Steps k in 0..total_steps whose y, u and n have arrived.
  long steps_done = 0;
  /// The highest step received, -1 before any.
  long highest_step = -1;
  EpisodeStatus status = EpisodeStatus::kRunning;
  std::string message;                // the SUMMARY's
  transport::RealtimeStats realtime;  // from the SUMMARY (unpaced before it)
  /// The latest lcmt_pacing_progress of the episode.
  std::optional<transport::PacingProgress> pacing;
  /// A relay episode's relay, as far as its steps have arrived in order.
  RelayView relay;
};

/// An episode with its trajectory: y, u, n of steps 0..total_steps, the
/// chunks' doubles bit for bit, NaN where a step has not arrived.
struct RelayFollower;  // live_monitor.cc: a relay episode's RelayTuner
struct EpisodeTrace {
  EpisodeInfo info;
  std::vector<double> y, u, n;
  std::vector<bool> received;
  std::shared_ptr<RelayFollower> relay;  // a relay episode's, else null
};

enum class TuningStatus { kRunning, kDone, kFailed };
/// "running", "done", "failed".
const char* TuningStatusName(TuningStatus status);

/// A tuning over the trio as its latest lcmt_tune_progress tells it.
struct TuningInfo {
  int64_t tuning_id = 0;
  /// transport::NowSeconds() when first and last heard.
  double first_heard_s = 0.0, last_heard_s = 0.0;
  TuningStatus status = TuningStatus::kRunning;
  long iterations = 0;
  long evaluations = 0;
  /// +inf before a feasible point; its gains NaN then.
  double best_objective = std::numeric_limits<double>::infinity();
  std::array<double, 3> best_gains{};
  int trios = 0;
  std::string method, objective;
};

enum class Role { kPlant, kController, kDisturbance, kClient };
inline constexpr int kRoleCount = 4;
/// "plant", "controller", "disturbance", "client".
const char* RoleName(Role role);

struct RoleHealth {
  /// transport::NowSeconds() when last heard, NaN if never.
  double last_heard_s = std::numeric_limits<double>::quiet_NaN();
  /// From the role's READY; 0 if none heard.
  int pid = 0;
};

struct MonitorSnapshot {
  /// Oldest first.
  std::vector<EpisodeInfo> episodes;
  /// Oldest first, at most kMaxTunings.
  std::vector<TuningInfo> tunings;
  std::array<RoleHealth, kRoleCount> roles;
  transport::TransportCounters counters;
  long trajectory_requests = 0;
  /// Chunks outside their episode, chunks of an unknown episode, and
  /// configurations longer than max_total_steps.
  long rejected = 0;
  /// transport::NowSeconds() when taken.
  double now_s = 0.0;
};

class LiveMonitor {
 public:
  /// Tunings kept, oldest dropped first.
  static constexpr std::size_t kMaxTunings = 8;
  /// Joins options.lcm_url. Options must be valid (std::invalid_argument
  /// otherwise: a caller's mistake). If LCM cannot start on the URL, status()
  /// says so (kRunnerFailed) and Poll returns -1.
  explicit LiveMonitor(const LiveMonitorOptions& options);
  /// On an LCM instance of the caller's (memq:// tests), which must outlive it.
  LiveMonitor(lcm::LCM* lcm, const LiveMonitorOptions& options);
  ~LiveMonitor();
  LiveMonitor(const LiveMonitor&) = delete;
  LiveMonitor& operator=(const LiveMonitor&) = delete;

  /// Ok, or why this monitor hears nothing (LCM did not start).
  const Status& status() const { return status_; }

  /// Waits at most timeout_s for traffic and handles it: the number of
  /// messages handled, -1 on an LCM error. One thread only.
  int Poll(double timeout_s);

  /// The episodes and the health, from any thread.
  MonitorSnapshot Snapshot() const;
  /// Calls `read` with the episode under the monitor's lock (keep it short:
  /// Poll waits); false if the episode is not kept.
  bool WithEpisode(int64_t episode_id, const std::function<void(const EpisodeTrace&)>& read) const;
  /// A counter that moves whenever anything the snapshot shows has changed.
  long version() const;

  const LiveMonitorOptions& options() const { return options_; }

 private:
  struct State;
  void Subscribe();

  LiveMonitorOptions options_;
  std::unique_ptr<lcm::LCM> own_lcm_;
  std::unique_ptr<transport::Transport> transport_;
  Status status_;
  std::unique_ptr<State> state_;
};

}  // namespace pidlab::monitor
