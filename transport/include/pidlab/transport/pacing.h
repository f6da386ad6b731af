#pragma once
// Real-time pacing of the lockstep (`pidlab launch --realtime [FACTOR]`,
// `pidlab-plant --realtime [FACTOR]`): the plant starts step k (publishes
// y_k) no earlier than t0 + k dt / FACTOR on CLOCK_MONOTONIC, sleeping with an
// absolute clock_nanosleep(TIMER_ABSTIME) so that errors do not accumulate,
// and records how late each step started. t0 is when step 0 starts (the
// plant received the episode's configuration). A step that could not start on
// time (a late answer, a lost message) is started as soon as it can: the
// schedule is absolute, so the steps after it run unpaced until the loop has
// caught up. Pacing changes when steps happen, never what they compute.
//
// Definitions (docs/trio.md, "Real-time pacing"):
//   period        P = dt / FACTOR
//   lateness_k    start of step k - (t0 + k P), k = 1..N (step 0 defines t0)
//   missed        lateness_k > P: step k started after step k + 1 was due,
//                 i.e. outside its own period
//   p50, p99      nearest-rank percentiles of lateness_1..N
//   rate_hz       N / (start of step N - t0): steps per second achieved

#include <array>
#include <cstdint>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_pacing_progress.hpp>
#include <string>
#include <vector>

namespace pidlab::transport {

/// What the SUMMARY, `evaluate`, `replay` and the JSON `realtime` object
/// report of a paced episode.
struct RealtimeStats {
  double factor = 0.0;  // 0: the episode was not paced (the rest is 0)
  long steps = 0;       // steps whose lateness was recorded (1..k)
  long missed_deadlines = 0;
  double lateness_p50_s = 0.0;
  double lateness_p99_s = 0.0;
  double lateness_max_s = 0.0;
  double rate_hz = 0.0;
  bool paced() const { return factor > 0.0; }
};

/// "paced 1x: 0 missed deadlines, lateness p50 12 us, p99 40 us, max 85 us,
/// 1000.0 steps/s" (empty if not paced).
std::string DescribeRealtime(const RealtimeStats& stats);

/// Several episodes (a disturbance evaluation runs two) as one: missed
/// deadlines summed, each lateness figure the largest of the episodes', the
/// rate the lowest. Unpaced inputs are skipped.
RealtimeStats CombineRealtime(const RealtimeStats& a, const RealtimeStats& b);

/// The statistics a SUMMARY carries (unpaced if its factor is not positive
/// and finite), and into a SUMMARY.
RealtimeStats RealtimeFromSummary(const pidlab::lcmt_episode_summary& summary);
void SetRealtime(const RealtimeStats& stats, pidlab::lcmt_episode_summary* summary);

/// True if `factor` can pace an episode (positive and finite), else false
/// with *error naming it.
bool RealtimeFactorIsValid(double factor, std::string* error);

/// Bins of the live lateness histogram (lcmt_pacing_progress): bin 0 holds
/// lateness below 1 us, bin i (1..22) [2^(i-1), 2^i) us, bin 23 at least 2^22 us.
inline constexpr int kLatenessBins = 24;
static_assert(kLatenessBins == pidlab::lcmt_pacing_progress::HISTOGRAM_BINS);
/// The histogram bin of a lateness in seconds.
int LatenessBin(double lateness_s);
/// The upper edge of a bin in seconds (+inf for the last).
double LatenessBinUpperEdge(int bin);

/// What a paced episode's plant publishes while it runs (PACING), kept up to
/// date in O(1) per step: counts, the exact maximum and the rate, with p50 and
/// p99 read off the histogram as upper bounds (the SUMMARY's exact
/// nearest-rank figures come at the end, from Pacer::Stats).
struct PacingProgress {
  double factor = 0.0;
  double period_s = 0.0;
  long steps = 0;
  long missed_deadlines = 0;
  double lateness_max_s = 0.0;
  double rate_hz = 0.0;
  std::array<long, kLatenessBins> histogram{};
  /// The upper edge of the bin holding the nearest-rank q-quantile, at most
  /// the maximum (0 with no steps).
  double UpperPercentile(double q) const;
};
void SetPacingProgress(const PacingProgress& progress, pidlab::lcmt_pacing_progress* message);
/// The figures a PACING message carries (its p50 and p99 upper bounds are
/// UpperPercentile of these, as the plant computed them).
PacingProgress PacingProgressFromMessage(const pidlab::lcmt_pacing_progress& message);

class Pacer {
 public:
  /// factor > 0 (RealtimeFactorIsValid), dt_s > 0.
  Pacer(double factor, double dt_s, long total_steps);
  /// Step 0 starts now: t0.
  void Start();
  /// Sleeps until step k (>= 1) is due, then records its lateness.
  void WaitForStep(long k);
  /// The statistics of the steps waited for so far.
  RealtimeStats Stats() const;
  /// The live figures of the steps waited for so far (no sorting: cheap
  /// enough to publish with every trajectory chunk).
  PacingProgress Progress() const;
  double period_s() const { return period_s_; }

 private:
  double factor_, period_s_;
  int64_t t0_ns_ = 0, last_start_ns_ = 0;
  long last_step_ = 0;
  std::vector<double> lateness_s_;  // of steps 1..last_step_
  PacingProgress progress_;         // counts, max and histogram, updated per step
};

}  // namespace pidlab::transport
