#pragma once
// Runs one episode of the sampled loop over a running trio: the LCM backend of
// `pidlab evaluate`. Publishes the configuration until the plant, controller
// and disturbance acknowledge it, records y, u and n of every step from the
// trajectory chunks the plant streams (it does not wake for every lockstep
// message), asks the plant to resend whatever it missed, and reports a silent
// process by name.

#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/episode_start.h"
#include "pidlab/transport/pacing.h"
#include "pidlab/transport/transport.h"

namespace pidlab::episode_client {

/// The episode of `options` (a sampled loop) under `disturbance`, as the trio
/// runs it. Throws std::invalid_argument if it is not a valid episode.
transport::EpisodeSpec MakeEpisodeSpec(int64_t episode_id, const Plant& plant, const PidGains& gains,
                                       const evaluation::LoopOptions& options,
                                       const DisturbanceOptions& disturbance,
                                       const transport::RecoveryOptions& recovery);

/// The sampled loop options of an episode (for Evaluate on a logged episode).
evaluation::LoopOptions SampledLoopOptions(const transport::EpisodeSpec& spec);

struct EpisodeClientOptions {
  std::string lcm_url = transport::kDefaultLcmUrl;
  transport::TransportOptions transport;
  transport::RecoveryOptions recovery;
  /// How long to wait for all three acknowledgements, s.
  double start_timeout_s = 3.0;
  /// Upper bound on one episode, s.
  double episode_timeout_s = 600.0;
  /// An episode that fails (a silent or dead process, a timeout) is run again
  /// as a new episode, up to this many attempts in all. Episodes are
  /// deterministic, so a re-run gives the result the first run would have.
  /// Conflicting messages (a forgery, docs/security.md) are never re-run.
  int max_attempts = 3;
  /// Where a re-run is noted (one line each). May be empty.
  std::function<void(const std::string& note)> on_note;

  bool IsValid(std::string* error) const;
};

struct EpisodeClientStats {
  long episodes = 0;
  /// The ids of the episodes completed, in order (`pidlab replay --episode`).
  std::vector<int64_t> episode_ids;
  long steps = 0;            // lockstep steps run
  double seconds = 0.0;      // wall time from the first acknowledgement to the last step
  long resend_requests = 0;  // TRAJECTORY_REQUESTs for steps the client missed
  long reruns = 0;           // episodes run again after a failure
  /// Of the paced episodes (pidlab-plant --realtime), as their SUMMARYs
  /// reported them, combined (CombineRealtime); unpaced: factor 0.
  transport::RealtimeStats realtime;
  double StepsPerSecond() const { return seconds > 0.0 ? static_cast<double>(steps) / seconds : 0.0; }
};

class EpisodeClient {
 public:
  /// Throws std::invalid_argument for invalid options (a caller's mistake).
  /// If LCM cannot start on the URL, status() says so (kRunnerFailed) and
  /// every Run returns it.
  explicit EpisodeClient(const EpisodeClientOptions& options);
  /// On `lcm` (not owned: it must outlive the client, and not be handled
  /// once the client is gone, as a Transport does not unsubscribe) instead of
  /// an instance of its own on options.lcm_url, which then only names it in
  /// messages. For roles run in this process (tests): every memq:// instance
  /// is a queue of its own, so they must share the client's, whose waits then
  /// handle their messages too.
  EpisodeClient(const EpisodeClientOptions& options, lcm::LCM* lcm);
  ~EpisodeClient();

  /// Ok, or why the client cannot run episodes (LCM did not start).
  const Status& status() const { return status_; }

  /// A SampledRunner: y at every step k = 0..TotalSteps() in *y_all, every
  /// step in *trajectory when not null. kRunnerFailed with one line naming
  /// the silent process on failure.
  Status Run(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
             const DisturbanceOptions& disturbance, std::vector<double>* y_all,
             std::vector<evaluation::SampledStep>* trajectory);

  /// A relay episode (controller/relay.h): the controller runs a
  /// RelayTuner with `relay` and `previous` as the loop in place; every step
  /// in *trajectory. Ok, or kRunnerFailed/kInvalidInput as Run.
  Status RunRelay(const Plant& plant, const PidGains& previous, const evaluation::LoopOptions& options,
                  const DisturbanceOptions& disturbance, const RelayTuneOptions& relay,
                  std::vector<evaluation::SampledStep>* trajectory);

  evaluation::SampledRunner AsRunner();
  const EpisodeClientStats& stats() const { return stats_; }
  /// After Run failed: true if the trio went silent or died (the episode may
  /// run elsewhere), false if the episode itself failed (a conflict, a
  /// FAILED summary): it would fail anywhere.
  bool last_failure_retryable() const { return last_failure_retryable_; }
  const EpisodeClientOptions& options() const { return options_; }
  const transport::TransportCounters& counters() const;

 private:
  struct State;
  // The transport on `lcm` and the subscriptions, or status_.
  void Start(lcm::LCM* lcm);
  bool RunOrExplain(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                    const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                    std::vector<evaluation::SampledStep>* trajectory, std::string* error,
                    const RelayTuneOptions* relay = nullptr);
  bool StartEpisode(const pidlab::lcmt_episode_config& config, std::string* error);
  /// Waits for every step (asking the plant again for what was missed) from
  /// t0 on; *done_s is when the last step was heard.
  bool FollowEpisode(double t0, double* done_s, long* requests, std::string* error);
  /// One attempt: a fresh episode id, start, follow. *retryable is false for
  /// failures a re-run cannot mend (invalid episode, conflicting messages).
  bool RunOnce(const transport::EpisodeSpec& spec, std::string* error, bool* retryable);
  std::string Where() const;
  /// The starter, the state and the subscriptions on transport_.
  void Listen();

  std::unique_ptr<lcm::LCM> own_lcm_;
  std::unique_ptr<transport::Transport> transport_;
  Status status_;
  std::unique_ptr<transport::EpisodeStarter> starter_;
  std::unique_ptr<State> state_;
  EpisodeClientOptions options_;
  EpisodeClientStats stats_;
  bool last_failure_retryable_ = false;
};

}  // namespace pidlab::episode_client
