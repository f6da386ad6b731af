#pragma once
// The resend timer of the trio: an RFC 6298 round-trip estimator. The plant
// resends y_k (and asks again for n) after Timeout() without an answer, a
// time derived from the round trips it measured, not a fixed wait: on a
// loopback a round trip takes about 70-100 us, so a fixed wait of a few ms
// dominated an episode with loss (docs/trio.md, "Loss recovery").
//
//   first sample R:   SRTT = R, RTTVAR = R / 2
//   later samples R:  RTTVAR = 3/4 RTTVAR + 1/4 |SRTT - R|, SRTT = 7/8 SRTT + 1/8 R
//   RTO = SRTT + 4 RTTVAR, clamped to [floor_s, ceiling_s], doubled per
//   Backoff() (exponential backoff, capped at ceiling_s) until the next
//   sample or EndBackoff().
//
// Karn's rule is the caller's: no sample from an exchange that was resent
// (its answer may belong to either transmission).

#include <string>

namespace pidlab::transport {

struct RttOptions {
  /// The timeout before the first sample (RFC 6298: 1 s; here the episode's
  /// retransmit_interval_s, 2 ms by default), s.
  double initial_s = 0.002;
  /// The lowest timeout, s. 200 us: two to three idle loopback round trips,
  /// and above the wake-up jitter of an idle 2-core machine (tens of us), so
  /// that a run of equal samples (RTTVAR near 0) does not turn every
  /// scheduling hiccup into a resend; low enough that a loss costs about
  /// 3 round trips rather than 30 (docs/trio.md).
  double floor_s = 150e-6;
  /// The highest timeout, backoff included, s: a dead peer is asked about 10
  /// times a second until the silence deadline (which is independent).
  double ceiling_s = 0.1;

  bool IsValid(std::string* error) const;
};

class RttEstimator {
 public:
  explicit RttEstimator(const RttOptions& options = {});
  /// A round trip of an exchange that was sent once (Karn), s. Ignored if not
  /// finite or negative. Ends any backoff.
  void Sample(double rtt_s);
  /// A resend: the timeout doubles (capped at ceiling_s) until the next
  /// sample or EndBackoff().
  void Backoff();
  /// The exchange completed (even without a sample, Karn): back to the
  /// estimate.
  void EndBackoff();
  /// The current timeout, backoff included, in [floor_s, ceiling_s].
  double Timeout() const { return timeout_s_; }
  /// The timeout without backoff.
  double BaseTimeout() const;
  bool has_sample() const { return samples_ > 0; }
  long samples() const { return samples_; }
  double srtt_s() const { return srtt_s_; }
  double rttvar_s() const { return rttvar_s_; }
  int backoffs() const { return backoffs_; }
  const RttOptions& options() const { return options_; }

 private:
  void Update();
  RttOptions options_;
  double srtt_s_ = 0, rttvar_s_ = 0;
  long samples_ = 0;
  int backoffs_ = 0;
  double timeout_s_ = 0;
};

}  // namespace pidlab::transport
