#pragma once
// The thin layer between LCM and the trio's protocol logic: channel names
// with a prefix, typed publish, decoding with undecodable messages counted
// (never a crash), seeded fault injection on receipt (the same messages of an
// episode lost on every run), and bounded waits.
// Works on any LCM URL, including memq:// for single-process tests.

#include <algorithm>
#include <cstdint>
#include <deque>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "pidlab/transport/auth.h"
#include "pidlab/transport/protocol.h"
#include "pidlab/transport/wire.h"

namespace pidlab::transport {

/// Microseconds since the epoch (the informative `utime` of every message).
int64_t NowUtime();
/// Monotonic seconds, for deadlines.
double NowSeconds();

struct TransportOptions {
  /// Prepended to every channel name; lets several trios share one network.
  std::string channel_prefix = kDefaultChannelPrefix;
  /// Fault injection: fraction in [0, 1) of received messages thrown away
  /// before decoding, as if the network had lost them.
  double drop_rate = 0.0;
  /// Seed of the drop decisions. Each decision is a hash of (seed, channel
  /// name without prefix, the message's step, how many times this
  /// subscription has received a message of that episode and step on that
  /// channel before): not a draw from one stream, whose order would follow
  /// the timing. The same episode run again with the same seed (whatever its
  /// id, its timing or the episodes before it) loses the same messages: the
  /// first y_k, its first resend, ... (DropDecision).
  uint64_t drop_seed = 1;
  /// With a key, every message sent carries an HMAC-SHA256 tag and every
  /// message received must carry a valid, fresh one (auth.h).
  std::optional<AuthKey> auth_key;
  /// The trio's LCM URL, for its step lanes: with a udpm:// URL the per-step
  /// channels travel on ports of their own in the same group (StepLaneUrl),
  /// so that a y_k wakes only the controller and a u_k only the plant, not
  /// every process of the trio. Empty, or not udpm://: every channel on the
  /// LCM instance given to the transport (memq:// tests).
  std::string step_lane_base_url;
  /// Messages LCM may hold for each subscription between its receive thread
  /// and WaitAndHandle. LCM 1.3.1's default is 30 and it drops the rest
  /// silently (no kernel counter moves): a burst, e.g. lcm-logplayer catching
  /// up after the machine stalled it, then loses a y_k, and a controller that
  /// answers y_k only after y_(k-1) waits for ever. The bound keeps a flood
  /// from growing LCM's ring buffer without limit (at most this many
  /// datagrams per subscription, each at most LCM's 64 kB packet).
  int queue_capacity = kDefaultQueueCapacity;

  static constexpr int kDefaultQueueCapacity = 4096;

  bool IsValid(std::string* error) const;
};

/// The step lanes: PLANT_OUTPUT on the base port + 1, CONTROL on the base
/// port + 2 (kPlantOutputLane, kControlLane), same group and options. Every
/// other channel stays on the base URL, where lcm-logger and lcm-spy listen;
/// the plant's TRAJECTORY chunks carry every y_k, u_k and n_k there.
inline constexpr int kPlantOutputLane = 1;
inline constexpr int kControlLane = 2;
/// The lane of a channel name (without prefix): 0 for the base URL.
int LaneOf(const char* name);
/// `base_url` with its port moved up by `lane` (udpm://GROUP[:PORT][?OPTS],
/// LCM's default port 7667); empty if base_url is not udpm:// or the port
/// would pass 65535.
std::string StepLaneUrl(const std::string& base_url, int lane);

struct TransportCounters {
  long received = 0;         // messages that reached a subscription
  long dropped = 0;          // thrown away by fault injection
  long undecodable = 0;      // failed to decode (garbage, wrong type): ignored
  long unauthenticated = 0;  // with a key: no tag, or a tag that does not verify (forged)
  long replayed = 0;         // with a key: dated outside the replay window, or a repeat
};

/// The fault injection's decision for one received message (TransportOptions::
/// drop_seed): true to throw it away. `name_hash` is ChannelNameHash of the
/// channel name without prefix, `attempt` counts the copies of the same
/// (episode, step) that reached the subscription before (0 for the first).
bool DropDecision(uint64_t seed, double drop_rate, uint64_t name_hash, int64_t step, uint64_t attempt);
/// FNV-1a of a channel name (without prefix).
uint64_t ChannelNameHash(const std::string& name);
/// The episode id and step of an encoded pidlab message: every lcmt type
/// starts with int64 utime, episode_id, step after LCM's 8-byte fingerprint.
/// False (and 0, 0) if `size` is too short to hold them.
bool PeekEpisodeAndStep(const void* data, std::size_t size, int64_t* episode_id, int64_t* step);

class Transport {
 public:
  /// `lcm` must outlive the transport and be good(). Options must be valid.
  Transport(lcm::LCM* lcm, const TransportOptions& options);
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  std::string Channel(const std::string& name) const { return options_.channel_prefix + name; }

  /// Stamps utime and publishes on <prefix><name>. Returns false on a send error.
  /// No allocation per message in the steady state: the channel name is
  /// cached and the message is encoded into a buffer that is reused.
  template <typename Msg>
  bool Publish(const char* name, Msg* msg) {
    msg->utime = NowUtime();
    const int size = msg->getEncodedSize();
    if (size < 0) return false;
    const std::size_t total = static_cast<std::size_t>(size) + (options_.auth_key ? kAuthTagBytes : 0);
    if (encode_buffer_.size() < total) encode_buffer_.resize(total);
    if (msg->encode(encode_buffer_.data(), 0, size) != size) return false;
    const CachedName& cached = CachedChannel(name);
    const std::string& channel = cached.prefixed;
    if (options_.auth_key) {
      const auto tag =
          AuthTag(*options_.auth_key, channel, encode_buffer_.data(), static_cast<std::size_t>(size));
      std::copy(tag.begin(), tag.end(), encode_buffer_.begin() + size);
    }
    return LcmFor(cached.lane)->publish(channel, encode_buffer_.data(), static_cast<unsigned int>(total)) ==
           0;
  }
  template <typename Msg>
  bool Publish(const std::string& name, Msg* msg) {
    return Publish(name.c_str(), msg);
  }

  /// Calls on_message for every message on <prefix><name> that survives fault
  /// injection and decodes as Msg.
  template <typename Msg>
  void Subscribe(const std::string& name, std::function<void(const Msg&)> on_message) {
    auto sub = std::make_unique<Subscription>();
    sub->owner = this;
    sub->decode_and_call = [on_message](const void* data, int size) {
      if (!WireLayoutOk(Msg::getHash(), data, size)) return false;  // before the decoder allocates
      Msg msg;
      try {
        if (msg.decode(data, 0, size) != size) return false;
      } catch (const std::exception&) {
        return false;  // e.g. a negative or absurd array length
      }
      on_message(msg);
      return true;
    };
    // The C API directly: lcm-cpp's trampoline builds a std::string of the
    // channel name for every message received.
    sub->channel = Channel(name);
    sub->name_hash = ChannelNameHash(name);
    const int lane = LaneOf(name.c_str());
    lcm_subscription_t* handle =
        lcm_subscribe(LcmFor(lane)->getUnderlyingLCM(), sub->channel.c_str(), &Subscription::HandleC, sub.get());
    if (handle) lcm_subscription_set_queue_capacity(handle, options_.queue_capacity);
    listening_[static_cast<std::size_t>(lane)] = true;
    subscriptions_.push_back(std::move(sub));
  }

  /// Waits at most timeout_s for traffic and handles one message of each
  /// LCM instance (base URL and step lanes) that has one (callers loop).
  /// Returns the number of messages handled (0 on timeout), -1 on an LCM
  /// error.
  int WaitAndHandle(double timeout_s);

  const TransportCounters& counters() const { return counters_; }
  const TransportOptions& options() const { return options_; }
  lcm::LCM* lcm() { return lcm_; }

 private:
  struct Subscription {
    Transport* owner = nullptr;
    std::string channel;     // prefixed
    uint64_t name_hash = 0;  // ChannelNameHash of the name without prefix
    std::function<bool(const void*, int)> decode_and_call;
    static void HandleC(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  };
  struct CachedName {
    std::string name, prefixed;
    int lane = 0;
  };
  bool ShouldDrop(const Subscription& sub, const lcm_recv_buf_t& rbuf);
  const CachedName& CachedChannel(const char* name);
  /// The LCM instance of a lane (0: the one given), created on first use: a
  /// lane only published on never opens a receive socket (LCM 1.3.1 sets
  /// that up on the first subscribe).
  lcm::LCM* LcmFor(int lane);

  std::deque<CachedName> channel_cache_;  // stable references
  std::vector<uint8_t> encode_buffer_;

  lcm::LCM* lcm_;
  TransportOptions options_;
  TransportCounters counters_;
  /// Copies received so far per (subscription, episode, step), for the drop
  /// decisions' attempt number; cleared when it holds kMaxDropKeys keys
  /// (copies of one step arrive close together, long before that).
  struct DropKey {
    const Subscription* sub;
    int64_t episode_id, step;
    bool operator==(const DropKey& o) const {
      return sub == o.sub && episode_id == o.episode_id && step == o.step;
    }
  };
  struct DropKeyHash {
    std::size_t operator()(const DropKey& k) const;
  };
  static constexpr std::size_t kMaxDropKeys = 1 << 15;
  std::unordered_map<DropKey, uint64_t, DropKeyHash> drop_attempts_;
  ReplayGuard replay_guard_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  std::unique_ptr<lcm::LCM> lanes_[3];  // [0] unused: lane 0 is lcm_
  bool listening_[3] = {false, false, false};
};

}  // namespace pidlab::transport
