#pragma once
// K trios serving one tune: one EpisodeClient per trio, a ParallelFor with one
// worker thread per trio (the independent evaluations of a tune run on idle
// trios at the same time), and a SampledRunner that sends each episode to
// the trio of the worker that runs it. A trio that goes silent or dies (its
// client's own re-runs spent) is named once and left out; its episode, and
// every later one, runs on the trios still alive. Episodes are
// deterministic, so where an episode runs never changes its result.

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/optim/optimizer.h"

namespace pidlab::episode_client {

/// The trios' URLs from a list separated by white space or commas (as
/// `pidlab launch --trios K` exports PIDLAB_LCM_URLS). Empty items are skipped.
std::vector<std::string> SplitUrlList(const std::string& list);

class EpisodePool {
 public:
  /// One client per entry (at least one: std::invalid_argument otherwise, as
  /// for invalid options). A trio whose LCM does not start makes status()
  /// fail (kRunnerFailed, naming its URL).
  explicit EpisodePool(const std::vector<EpisodeClientOptions>& trios);
  ~EpisodePool();
  EpisodePool(const EpisodePool&) = delete;
  EpisodePool& operator=(const EpisodePool&) = delete;

  int size() const { return static_cast<int>(trios_.size()); }
  /// Ok, or the first trio whose client cannot run (EpisodeClient::status).
  const Status& status() const { return status_; }
  /// One worker thread per trio still alive; body(i) runs on a worker, and
  /// the episodes it starts go to that worker's trio.
  optim::ParallelFor AsParallelFor();
  /// Runs an episode on the calling worker's trio (the first live one off a
  /// worker). On a trio failure (silence, a dead process) the trio is named
  /// and left out, and the episode runs on another; an episode that fails
  /// by itself (a conflict, a FAILED summary) is not moved. False with
  /// *error when no trio is left.
  evaluation::SampledRunner AsRunner();

  /// Trios left out, one line each (URL and why).
  std::vector<std::string> lost() const;
  /// Summed over the trios.
  EpisodeClientStats stats() const;

 private:
  struct Trio;
  bool Run(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
           const DisturbanceOptions& disturbance, std::vector<double>* y_all,
           std::vector<evaluation::SampledStep>* trajectory, std::string* error);
  int Pick(int preferred) const;  // a live trio, preferring `preferred`; -1 if none

  std::vector<std::unique_ptr<Trio>> trios_;
  mutable std::mutex mutex_;  // guards Trio::alive and lost_
  std::vector<std::string> lost_;
  std::function<void(const std::string&)> on_note_;
  Status status_;
};

}  // namespace pidlab::episode_client
