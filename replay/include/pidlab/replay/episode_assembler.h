#pragma once
// Building Episodes from decoded pidlab messages, in log order.
//
// An episode is identified by (channel prefix, episode id). Its per-step
// vectors are sized by its configuration's total_steps (at most
// transport::kMaxEpisodeSteps), never by a step number in a message: steps
// outside 0..total_steps are counted as beyond_end, not stored in the
// vectors, and an episode without a valid configuration (an orphan) gets no
// per-step vectors at all. A step no episode can have (negative, beyond
// kMaxEpisodeSteps, or past the largest long in a block or chunk) is counted
// at every arrival and otherwise ignored: it is not kept, and it does not make
// later steps out of order. Memory is bounded by the messages added, whatever
// steps they claim.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/replay/decoder_table.h"
#include "pidlab/replay/log_reader.h"

namespace pidlab::replay {

/// What EpisodeAssembler::Finish built.
struct AssembledEpisodes {
  /// Every episode with a configuration (valid or not) or step data, in
  /// order of first appearance.
  std::vector<Episode> episodes;
  /// One line per configuration logged again with different content.
  std::vector<std::string> notes;
  /// "<prefix> episode <id>" for each episode without a valid configuration.
  std::vector<std::string> orphans;
};

class EpisodeAssembler {
 public:
  EpisodeAssembler();
  ~EpisodeAssembler();
  EpisodeAssembler(const EpisodeAssembler&) = delete;
  EpisodeAssembler& operator=(const EpisodeAssembler&) = delete;

  /// Adds one message of the trio on channel prefix `prefix`. Ready
  /// messages and requests change nothing.
  void Add(const std::string& prefix, const PidlabMessage& message);
  /// Uses `config` for its episode unless one was added (Episode::config_supplied).
  void Supply(const std::string& prefix, const pidlab::lcmt_episode_config& config);

  /// The episodes. For an episode with a valid configuration, total_steps is
  /// the configuration's and y, u, n, u_input_y, status and has_* hold
  /// total_steps + 1 entries. For an orphan, total_steps is the highest step
  /// of its data within 0..kMaxEpisodeSteps (a count for the listing only)
  /// and those vectors are empty; its stream statistics are still complete.
  AssembledEpisodes Finish();

 private:
  struct Building;
  Building& EpisodeOf(const std::string& prefix, int64_t episode_id);
  void On(const std::string& prefix, const pidlab::lcmt_episode_config& m);
  void On(const std::string& prefix, const pidlab::lcmt_plant_output& m);
  void On(const std::string& prefix, const pidlab::lcmt_control_command& m);
  void On(const std::string& prefix, const pidlab::lcmt_disturbance_sample& m);
  void On(const std::string& prefix, const pidlab::lcmt_disturbance_block& m);
  void On(const std::string& prefix, const pidlab::lcmt_episode_summary& m);
  void On(const std::string& prefix, const pidlab::lcmt_trajectory_chunk& m);
  void On(const std::string&, const pidlab::lcmt_ready&) {}
  void On(const std::string&, const pidlab::lcmt_disturbance_request&) {}
  void On(const std::string&, const pidlab::lcmt_trajectory_request&) {}
  void On(const std::string&, const pidlab::lcmt_pacing_progress&) {}
  void On(const std::string&, const pidlab::lcmt_tune_progress&) {}

  std::map<std::pair<std::string, int64_t>, std::size_t> index_;
  std::vector<std::unique_ptr<Building>> building_;
};

}  // namespace pidlab::replay
