#include "pidlab/lcm/transport.h"

#include <sys/select.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <sstream>

namespace pidlab::lcm_trio {

int64_t NowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool TransportOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(drop_rate >= 0.0 && drop_rate < 1.0)) {
    os << "drop rate " << drop_rate << " must be in [0, 1)";
  } else if (channel_prefix.find_first_of(" \t\n") != std::string::npos) {
    os << "channel prefix '" << channel_prefix << "' must not contain white space";
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

Transport::Transport(lcm::LCM* lcm, const TransportOptions& options)
    : lcm_(lcm), options_(options), drop_rng_(options.drop_seed) {}

bool Transport::ShouldDrop() {
  if (options_.drop_rate <= 0.0) return false;
  // Uniform in [0, 1) from the top 53 bits: the same on every platform.
  const double r = static_cast<double>(drop_rng_() >> 11) * 0x1.0p-53;
  return r < options_.drop_rate;
}

void Transport::Subscription::Handle(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
  TransportCounters& c = owner->counters_;
  ++c.received;
  if (owner->ShouldDrop()) {
    ++c.dropped;
    return;
  }
  if (!decode_and_call(rbuf->data, static_cast<int>(rbuf->data_size))) ++c.undecodable;
}

int Transport::WaitAndHandle(double timeout_s) {
  const int fd = lcm_->getFileno();
  int handled = 0;
  double wait = timeout_s > 0.0 ? timeout_s : 0.0;
  for (;;) {
    fd_set fds;
    FD_ZERO(&fds);
    FD_SET(fd, &fds);
    timeval tv;
    tv.tv_sec = static_cast<long>(std::floor(wait));
    tv.tv_usec = static_cast<long>((wait - std::floor(wait)) * 1e6);
    const int ready = select(fd + 1, &fds, nullptr, nullptr, &tv);
    if (ready < 0) return errno == EINTR ? handled : -1;
    if (ready == 0) return handled;
    if (lcm_->handle() != 0) return -1;
    ++handled;
    wait = 0.0;  // then drain what is already queued, without waiting
  }
}

}  // namespace pidlab::lcm_trio
