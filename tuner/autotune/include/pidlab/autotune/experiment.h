#pragma once
// The relay experiment run on a process (docs/autotune.md): relay episodes
// (the controller steps a RelayTuner, controller/relay.h) until the relay
// ends, each measured input checked against a RelayTuner stepped here over
// the same measurements, then the estimates of its settled cycles.
//
// The relay's window is not known before the process is: the first episode
// runs the hold and `first_window_s` of relay; while the relay is still
// running at the episode's end, the next runs a window long enough for the
// timeout the last period sets (timeout_periods periods), or twice as long
// before any cycle, up to `max_window_s`. Episodes start over from the
// process's rest, as a new test on a real process starts from where it is.

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/autotune/relay.h"
#include "pidlab/controller/relay.h"
#include "pidlab/spec/status.h"

namespace pidlab::autotune {

/// One step of a relay episode as the process saw it.
struct RelaySample {
  double t_s = 0.0, r = 0.0, y = 0.0, u = 0.0;
};

/// Runs one relay episode of `horizon_s` with `relay` (and the experiment's
/// previous gains and output range) and fills every step. A failed Status
/// ends the experiment with it.
using RelayEpisodeRunner =
    std::function<Status(const RelayTuneOptions& relay, double horizon_s, std::vector<RelaySample>* samples)>;

struct ExperimentOptions {
  RelayTuneOptions relay;
  PidGains previous;             ///< the loop in place (all 0: none, an open-loop hold)
  PidOptions pid;                ///< its options and the output range (dt_s the loop's)
  double first_window_s = 60.0;  ///< > 0
  double max_window_s = 7200.0;  ///< >= first_window_s
  bool IsValid(std::string* error) const;
};

struct ExperimentSummary {
  /// kDone: the estimates are from converged cycles; kAborted: `why`; kRelay:
  /// the window reached max_window_s with the relay still running.
  RelayPhase end = RelayPhase::kRelay;
  std::string why;
  double u0 = 0.0, y0 = 0.0, noise_sigma = 0.0, hysteresis = 0.0, d_high = 0.0, d_low = 0.0;
  /// The relay's limit on |y - y0| (RelayTuneOptions::y_limit; +inf: none).
  double y_limit = std::numeric_limits<double>::infinity();
  double relay_start_s = 0.0, end_s = 0.0, horizon_s = 0.0;
  int restarts = 0;
  std::vector<double> load_changes_s;
  std::vector<RelayCycle> cycles;  ///< since the relay's last start (the approach first)
  int episodes = 0;
  /// The last episode, every step.
  std::vector<RelaySample> samples;
  RelayEstimates estimates;  ///< kDone only (estimates.converged)
  /// The estimates' relay (setpoint, u0, d_high, d_low, hysteresis).
  RelayOptions relay;
  /// The hold before the relay's last start: the drift of y over its second
  /// half (a least-squares line's slope times that half), and where it is
  /// both significant (4 standard errors of the slope) and more than 2
  /// sigma of the noise, the hysteresis and 5 % of the last cycle's
  /// amplitude, one line naming a drifting or disturbed hold: its y0 is no
  /// resting operating point ("" otherwise).
  double hold_drift = 0.0;
  std::string hold_note;
  /// The last episode's hold (s): the one given, or where the hold drifted,
  /// doubled episode by episode until it did not (at most 16 times the one
  /// given), so the relay starts from a resting operating point.
  double hold_s = 0.0;
  /// Where the output limits cut the relay asked for (amplitude +- bias
  /// about u0): one line saying what was asked and what was used; "" if
  /// nothing was cut.
  std::string clipped;
};

/// Progress: one line per episode and per end.
using ExperimentProgress = std::function<void(const std::string& line)>;

/// kInvalidInput for invalid options; the runner's failure; kRunnerFailed if
/// a measured input is not the relay's (the controller runs another relay).
/// Ok otherwise, with summary->end saying how the relay ended.
Status RunExperiment(const ExperimentOptions& options, const RelayEpisodeRunner& runner,
                     ExperimentSummary* summary, const ExperimentProgress& progress = nullptr);

/// One relay episode's record (every step, as the controller saw it):
/// ReplayRelay, then the tuner's end, operating point, relay and cycles into
/// *summary (its estimates untouched), the hold's drift, and, where the relay
/// has run no full cycle and y has settled on one side of its band, the end
/// aborted naming why (a reverse-acting process, or a relay too small for its
/// band). The runner's failure or ReplayRelay's.
Status AnalyzeRelayRecord(const ExperimentOptions& options, std::vector<RelaySample> samples,
                          ExperimentSummary* summary);

/// summary->relay from its operating point and relay, and, where the relay
/// is done, summary->estimates from its cycles (every settled one after the
/// approach under noise).
void EstimateFromRecord(const ExperimentOptions& options, ExperimentSummary* summary,
                        const ExperimentProgress& progress = nullptr);

/// Steps a RelayTuner over `samples` (y, r, t), as the controller did, and
/// checks each u bit for bit. kRunnerFailed naming the first step that
/// differs.
Status ReplayRelay(const RelayTuneOptions& relay, const PidGains& previous, const PidOptions& pid,
                   const std::vector<RelaySample>& samples, RelayTuner* tuner);

}  // namespace pidlab::autotune
