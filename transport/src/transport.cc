#include "pidlab/transport/transport.h"

#include <poll.h>
#include <time.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

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
  } else if (queue_capacity < 1) {
    os << "queue capacity " << queue_capacity << " must be at least 1";
  } else if (channel_prefix.find_first_of(" \t\n") != std::string::npos) {
    os << "channel prefix '" << channel_prefix.substr(0, 80) << "' must not contain white space";
  } else if (!step_lane_base_url.empty() && step_lane_base_url.rfind("udpm://", 0) == 0 &&
             StepLaneUrl(step_lane_base_url, kControlLane).empty()) {
    os << "LCM URL '" << step_lane_base_url.substr(0, 120)
       << "': its port must be a number at most 65533 (the step lanes use the next two)";
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

int LaneOf(const char* name) {
  if (std::strcmp(name, kPlantOutputChannel) == 0) return kPlantOutputLane;
  if (std::strcmp(name, kControlChannel) == 0) return kControlLane;
  return 0;
}

std::string StepLaneUrl(const std::string& base_url, int lane) {
  const std::string scheme = "udpm://";
  if (base_url.rfind(scheme, 0) != 0) return "";
  const std::size_t query = base_url.find('?');
  const std::string address =
      base_url.substr(scheme.size(), query == std::string::npos ? std::string::npos : query - scheme.size());
  const std::string rest = query == std::string::npos ? "" : base_url.substr(query);
  const std::size_t colon = address.rfind(':');
  long port = 7667;  // LCM's default
  std::string group = address;
  if (colon != std::string::npos) {
    group = address.substr(0, colon);
    const std::string digits = address.substr(colon + 1);
    if (digits.empty() || digits.size() > 5 || digits.find_first_not_of("0123456789") != std::string::npos)
      return "";
    port = std::stol(digits);
  }
  if (group.empty() || port < 1 || port + lane > 65535) return "";
  return scheme + group + ":" + std::to_string(port + lane) + rest;
}

namespace {
/// SplitMix64's finaliser: every input bit moves about half the output bits.
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

int64_t BigEndianInt64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<int64_t>(v);
}
}  // namespace

uint64_t ChannelNameHash(const std::string& name) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : name) {
    h ^= static_cast<uint8_t>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

bool DropDecision(uint64_t seed, double drop_rate, uint64_t name_hash, int64_t step, uint64_t attempt) {
  if (drop_rate <= 0.0) return false;
  const uint64_t h = Mix(Mix(Mix(Mix(seed) ^ name_hash) ^ static_cast<uint64_t>(step)) ^ attempt);
  // Uniform in [0, 1) from the top 53 bits: the same on every platform.
  const double r = static_cast<double>(h >> 11) * 0x1.0p-53;
  return r < drop_rate;
}

bool PeekEpisodeAndStep(const void* data, std::size_t size, int64_t* episode_id, int64_t* step) {
  *episode_id = *step = 0;
  // fingerprint (8), utime (8), episode_id (8), step (8)
  if (size < 32) return false;
  const auto* p = static_cast<const uint8_t*>(data);
  *episode_id = BigEndianInt64(p + 16);
  *step = BigEndianInt64(p + 24);
  return true;
}

std::size_t Transport::DropKeyHash::operator()(const DropKey& k) const {
  return static_cast<std::size_t>(
      Mix(Mix(reinterpret_cast<uintptr_t>(k.sub) ^ static_cast<uint64_t>(k.episode_id)) ^
          static_cast<uint64_t>(k.step)));
}

Transport::Transport(lcm::LCM* lcm, const TransportOptions& options) : lcm_(lcm), options_(options) {}

lcm::LCM* Transport::LcmFor(int lane) {
  if (lane == 0) return lcm_;
  auto& instance = lanes_[lane];
  if (!instance) {
    const std::string url = StepLaneUrl(options_.step_lane_base_url, lane);
    if (url.empty()) return lcm_;  // no lanes: everything on the base instance
    instance = std::make_unique<lcm::LCM>(url);
    if (!instance->good()) throw std::runtime_error("cannot start LCM on the step lane '" + url + "'");
  }
  return instance.get();
}

bool Transport::ShouldDrop(const Subscription& sub, const lcm_recv_buf_t& rbuf) {
  if (options_.drop_rate <= 0.0) return false;
  // Keyed on the message, not on the order of arrival: the step and the
  // number of copies of it seen, never the episode id (a new one each run)
  // nor utime. Too short for a step (not a pidlab message): all such
  // messages of the channel share one key and are told apart by the count.
  int64_t episode_id = 0, step = 0;
  PeekEpisodeAndStep(rbuf.data, rbuf.data_size, &episode_id, &step);
  if (drop_attempts_.size() >= kMaxDropKeys) drop_attempts_.clear();
  const uint64_t attempt = drop_attempts_[DropKey{&sub, episode_id, step}]++;
  return DropDecision(options_.drop_seed, options_.drop_rate, sub.name_hash, step, attempt);
}

const Transport::CachedName& Transport::CachedChannel(const char* name) {
  // A handful of short names: a linear strcmp is cheaper than building the
  // prefixed name (a heap allocation) for every message.
  for (const auto& entry : channel_cache_)
    if (std::strcmp(entry.name.c_str(), name) == 0) return entry;
  if (channel_cache_.size() >= 64) channel_cache_.clear();  // bounded, whatever the callers pass
  channel_cache_.push_back(CachedName{name, Channel(name), LaneOf(name)});
  return channel_cache_.back();
}

void Transport::Subscription::HandleC(const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) {
  auto* sub = static_cast<Subscription*>(self);
  TransportCounters& c = sub->owner->counters_;
  ++c.received;
  if (sub->owner->ShouldDrop(*sub, *rbuf)) {
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
  const double wait = timeout_s > 0.0 ? timeout_s : 0.0;
  // One poll and one handle per ready instance: no extra zero-timeout poll
  // to drain the queue (the caller's loop comes straight back here).
  pollfd pfd[3];
  lcm::LCM* instance[3];
  int n = 0;
  for (int lane = 0; lane < 3; ++lane) {
    if (lane > 0 && !(listening_[lane] && lanes_[lane])) continue;
    instance[n] = lane == 0 ? lcm_ : lanes_[lane].get();
    pfd[n] = pollfd{instance[n]->getFileno(), POLLIN, 0};
    ++n;
  }
  // ppoll: the resend timer is a few hundred microseconds (rtt.h), below
  // poll's millisecond resolution.
  const double whole = std::floor(wait);
  timespec ts{static_cast<time_t>(whole), static_cast<long>((wait - whole) * 1e9)};
  if (ts.tv_nsec > 999999999L) ts.tv_nsec = 999999999L;
  const int ready = ppoll(pfd, static_cast<nfds_t>(n), &ts, nullptr);
  if (ready < 0) return errno == EINTR ? 0 : -1;
  int handled = 0;
  for (int i = 0; i < n && ready > 0; ++i) {
    if (!(pfd[i].revents & POLLIN)) continue;
    if (lcm_handle(instance[i]->getUnderlyingLCM()) != 0) return -1;
    ++handled;
  }
  return handled;
}

}  // namespace pidlab::transport
