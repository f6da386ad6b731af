#pragma once
// A tuning over the trio as it runs, told to live watchers (`pidlab serve
// --lcm-url`, docs/live.md): lcmt_tune_progress on <prefix>TUNE_PROGRESS of
// the first trio's URL, at most every min_interval_s while the search runs and
// always once at the end. Nothing in the lockstep listens to it, and a failed
// send never stops the tuning.

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/optim/optimizer.h"

namespace pidlab::episode_client {

class TuneProgressPublisher {
 public:
  /// On `trio`'s URL, prefix and key. `trios` is how many trios run the
  /// episodes; `method` and `objective` name the search. Throws
  /// std::runtime_error if LCM cannot start on the URL.
  TuneProgressPublisher(const EpisodeClientOptions& trio, int trios, std::string method,
                        std::string objective, double min_interval_s = 0.1);
  /// On `lcm` (not owned; it must outlive the publisher) instead of an
  /// instance of its own on trio.lcm_url (memq:// tests).
  TuneProgressPublisher(lcm::LCM* lcm, const EpisodeClientOptions& trio, int trios, std::string method,
                        std::string objective, double min_interval_s = 0.1);
  ~TuneProgressPublisher();

  /// The search's progress (an optim::ProgressCallback's point): sent unless
  /// one was sent less than min_interval_s ago.
  void Running(const optim::TracePoint& point);
  /// The end: the result's gains and objective (ok), or a failure.
  /// The final message: `evaluations` the tuning's own count (its summary,
  /// what `pidlab tune` reports), which the last trace point may fall short of.
  void Finished(bool ok, const PidGains& gains, double objective, long evaluations);
  /// The tuning's id, the messages' episode_id.
  int64_t id() const { return id_; }

 private:
  void Send(int8_t status, double best_objective, const double* gains);

  std::unique_ptr<lcm::LCM> own_lcm_;
  std::unique_ptr<transport::Transport> transport_;
  int64_t id_ = 0;
  int trios_ = 1;
  std::string method_, objective_;
  double min_interval_s_, last_sent_s_ = -1e300;
  optim::TracePoint last_;
};

}  // namespace pidlab::episode_client
