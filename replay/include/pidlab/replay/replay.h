#pragma once
// Replaying a logged episode: its trajectory, its metrics recomputed through
// pidlab::Evaluate (bit-identical to the live run), and a fresh controller
// re-driven with the logged plant outputs.

#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/spec/status.h"

namespace pidlab::replay {

/// The logged trajectory as SampledSteps (k, t = k dt, r, y, u, n) for
/// k = 0..total_steps-1; false if the episode is not complete.
bool EpisodeTrajectory(const Episode& episode, std::vector<evaluation::SampledStep>* trajectory);

/// Recomputes the episode's metrics with pidlab::Evaluate, the code of
/// `pidlab evaluate`: the logged plant outputs stand in for the sampled loop
/// (so the IAE is the live episode's IAE exactly); the undisturbed companion
/// run that Evaluate also needs is simulated in process. Records the logged
/// trajectory in evaluation->trajectory. A failed Status (kInvalidInput) if the episode has
/// no valid configuration or is not complete.
Status EvaluateEpisode(const Episode& episode, evaluation::Evaluation* evaluation);

/// Result of re-driving a fresh controller with the logged plant outputs.
struct RedriveResult {
  bool ok = false;
  long steps_checked = 0;
  long first_mismatch = -1;  // step of the first differing command, -1 if none
  double logged_u = 0, recomputed_u = 0;
  std::string message;  // one line
};

/// Feeds y_0..y_{N-1} of the log to a new DiscretePid<double> with the
/// episode's gains and options and compares every command with the logged
/// one bit for bit. Stops at the first mismatch or missing step.
RedriveResult Redrive(const Episode& episode);

/// Re-drives a live pidlab-controller (started alone, without plant and
/// disturbance) on `lcm_url` / `channel_prefix` with the logged plant
/// outputs, one step at a time: publish y_k, wait for the command of step k
/// (resending y_k on silence), compare bits into *result. A failed Status:
/// kInvalidInput if LCM cannot start on the URL, kRunnerFailed if the
/// controller does not acknowledge or answer within deadline_s.
Status RedriveOverLcm(const Episode& episode, const std::string& lcm_url, const std::string& channel_prefix,
                      double deadline_s, RedriveResult* result);

}  // namespace pidlab::replay
