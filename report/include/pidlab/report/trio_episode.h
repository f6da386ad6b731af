#pragma once
// The report's trio section: one episode of the sampled loop over the LCM
// trio, run in this process through the launcher library (processes started
// and supervised by pidlab::launcher::Launcher, the episode driven by the
// tuner's EpisodeClient), in a private network namespace.

#include <string>

#include "pidlab/report/report.h"

namespace pidlab::report {

struct TrioEpisodeOptions {
  /// Where the trio processes write their stderr (and the launcher its notes).
  std::string log_path;
  /// Enter a private network namespace first (root needed). The calling
  /// thread and every process it starts move into it.
  bool isolated = true;
  /// Where pidlab-plant and friends are; empty: this executable's directory.
  std::string bin_dir;
};

/// Runs `gains` on `plant` for horizon_s at dt_s as one trio episode and
/// fills *metrics from pidlab::Evaluate over it. False with *note (one line)
/// if the trio could not run; on success *note says how it ran.
bool RunTrioEpisode(const TrioEpisodeOptions& options, const Plant& plant, const PidGains& gains, double dt_s,
                    double horizon_s, Metrics* metrics, std::string* note);

}  // namespace pidlab::report
