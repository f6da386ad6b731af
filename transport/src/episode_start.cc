#include "pidlab/transport/episode_start.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <pidlab/lcmt_ready.hpp>
#include <random>

namespace pidlab::transport {

pidlab::lcmt_ready MakeReady(int8_t state, const std::string& role, int64_t episode_id,
                             const std::string& detail) {
  pidlab::lcmt_ready r;
  r.episode_id = episode_id;
  r.step = -1;
  r.state = state;
  r.role = role;
  r.pid = static_cast<int32_t>(getpid());
  r.detail = detail;
  return r;
}

int64_t NewEpisodeId() {
  std::random_device rd;
  const uint64_t a = (static_cast<uint64_t>(rd()) << 32) ^ rd();
  const auto t = static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  const auto id =
      static_cast<int64_t>((a ^ (t * 0x9E3779B97F4A7C15ull) ^ static_cast<uint64_t>(getpid())) >> 1);
  return id == 0 ? 1 : id;
}

EpisodeStarter::EpisodeStarter(Transport* transport) : transport_(transport) {
  transport_->Subscribe<pidlab::lcmt_ready>(kReadyChannel, [this](const pidlab::lcmt_ready& m) {
    if (m.state == pidlab::lcmt_ready::CONFIG_ACK && episode_id_ != 0 && m.episode_id == episode_id_)
      acked_.insert(m.role);
  });
}

StartStatus EpisodeStarter::Start(const pidlab::lcmt_episode_config& config,
                                  const std::vector<std::string>& roles, double timeout_s,
                                  std::string* missing, double resend_period_s) {
  pidlab::lcmt_episode_config message = config;
  episode_id_ = config.episode_id;
  acked_.clear();
  auto all_acked = [&] {
    for (const std::string& r : roles)
      if (!acked_.count(r)) return false;
    return true;
  };
  const double start = NowSeconds();
  double last_sent = -1e9;
  int sent = 0;
  StartStatus status = StartStatus::kStarted;
  while (!all_acked()) {
    const double now = NowSeconds();
    if (now - start > timeout_s) {
      status = StartStatus::kTimedOut;
      break;
    }
    // The first repeats come quickly (5, 10, 20, 40 ms, then every
    // resend_period_s): a lost configuration or acknowledgement costs a few
    // ms, not a whole period, and a process that is still starting is not
    // flooded.
    const double period = std::min(resend_period_s, 0.005 * static_cast<double>(1 << std::min(sent, 10)));
    if (now - last_sent >= period) {
      transport_->Publish(kEpisodeConfigChannel, &message);
      last_sent = now;
      ++sent;
    }
    if (transport_->WaitAndHandle(std::min({0.005, period, last_sent + period - NowSeconds()})) < 0) {
      status = StartStatus::kLcmError;
      break;
    }
  }
  if (status == StartStatus::kTimedOut && missing) {
    missing->clear();
    for (const std::string& r : roles)
      if (!acked_.count(r)) *missing += (missing->empty() ? "pidlab-" : ", pidlab-") + r;
  }
  episode_id_ = 0;
  return status;
}

}  // namespace pidlab::transport
