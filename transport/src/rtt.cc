#include "pidlab/transport/rtt.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pidlab::transport {

bool RttOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(floor_s > 0.0) || !std::isfinite(floor_s))
    os << "resend timeout floor " << floor_s << " s must be positive and finite";
  else if (!(ceiling_s >= floor_s) || !std::isfinite(ceiling_s))
    os << "resend timeout ceiling " << ceiling_s << " s must be finite and at least the floor " << floor_s
       << " s";
  else if (!(initial_s > 0.0) || !std::isfinite(initial_s))
    os << "initial resend timeout " << initial_s << " s must be positive and finite";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

RttEstimator::RttEstimator(const RttOptions& options) : options_(options) { Update(); }

double RttEstimator::BaseTimeout() const {
  const double raw = samples_ > 0 ? srtt_s_ + 4.0 * rttvar_s_ : options_.initial_s;
  return std::clamp(raw, options_.floor_s, options_.ceiling_s);
}

void RttEstimator::Update() {
  double t = BaseTimeout();
  for (int i = 0; i < backoffs_ && t < options_.ceiling_s; ++i) t *= 2.0;
  timeout_s_ = std::min(t, options_.ceiling_s);
}

void RttEstimator::Sample(double rtt_s) {
  if (!std::isfinite(rtt_s) || rtt_s < 0.0) return;
  if (samples_ == 0) {
    srtt_s_ = rtt_s;
    rttvar_s_ = rtt_s / 2.0;
  } else {
    rttvar_s_ = 0.75 * rttvar_s_ + 0.25 * std::abs(srtt_s_ - rtt_s);
    srtt_s_ = 0.875 * srtt_s_ + 0.125 * rtt_s;
  }
  ++samples_;
  backoffs_ = 0;
  Update();
}

void RttEstimator::EndBackoff() {
  backoffs_ = 0;
  Update();
}

void RttEstimator::Backoff() {
  if (timeout_s_ < options_.ceiling_s) ++backoffs_;
  Update();
}

}  // namespace pidlab::transport
