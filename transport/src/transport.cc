#include "pidlab/transport/transport.h"

#include <poll.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

namespace pidlab::transport {

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
    os << "channel prefix '" << channel_prefix.substr(0, 80) << "' must not contain white space";
  } else if (channel_prefix.size() > kMaxChannelPrefixBytes) {
    // LCM refuses channel names longer than 63 bytes; the longest pidlab
    // channel name (DISTURBANCE_REQUEST) is 19.
    os << "channel prefix '" << channel_prefix.substr(0, 80) << "' is longer than " << kMaxChannelPrefixBytes
       << " bytes";
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

const std::string& Transport::CachedChannel(const char* name) {
  // A handful of short names: a linear strcmp is cheaper than building the
  // prefixed name (a heap allocation) for every message.
  for (const auto& entry : channel_cache_)
    if (std::strcmp(entry.first.c_str(), name) == 0) return entry.second;
  if (channel_cache_.size() >= 64) channel_cache_.clear();  // bounded, whatever the callers pass
  channel_cache_.emplace_back(name, Channel(name));
  return channel_cache_.back().second;
}

void Transport::Subscription::HandleC(const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) {
  auto* sub = static_cast<Subscription*>(self);
  TransportCounters& c = sub->owner->counters_;
  ++c.received;
  if (sub->owner->ShouldDrop()) {
    ++c.dropped;
    return;
  }
  int size = static_cast<int>(rbuf->data_size);
  Transport* owner = sub->owner;
  if (owner->options_.auth_key) {
    switch (owner->replay_guard_.Check(*owner->options_.auth_key, sub->channel, rbuf->data, rbuf->data_size,
                                       NowUtime(), NowSeconds())) {
      case AuthResult::kAccepted:
        size -= static_cast<int>(kAuthTagBytes);
        break;
      case AuthResult::kUnauthenticated:
        ++c.unauthenticated;
        return;
      case AuthResult::kReplayed:
        ++c.replayed;
        return;
    }
  }
  if (!sub->decode_and_call(rbuf->data, size)) ++c.undecodable;
}

int Transport::WaitAndHandle(double timeout_s) {
  const int fd = lcm_->getFileno();
  const double wait = timeout_s > 0.0 ? timeout_s : 0.0;
  // One poll and one handle per message: no extra zero-timeout poll to drain
  // the queue (the caller's loop comes straight back here).
  pollfd pfd{fd, POLLIN, 0};
  const int ready = poll(&pfd, 1, static_cast<int>(std::ceil(wait * 1000.0)));
  if (ready < 0) return errno == EINTR ? 0 : -1;
  if (ready == 0) return 0;
  if (lcm_handle(lcm_->getUnderlyingLCM()) != 0) return -1;
  return 1;
}

}  // namespace pidlab::transport
