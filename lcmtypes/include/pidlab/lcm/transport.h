#pragma once
// The thin layer between LCM and the trio's protocol logic: channel names
// with a prefix, typed publish, decoding with undecodable messages counted
// (never a crash), seeded fault injection on receipt, and bounded waits.
// Works on any LCM URL, including memq:// for single-process tests.

#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace pidlab::lcm_trio {

/// Default LCM URL of a trio (multicast, never leaves the host: ttl=0).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
inline constexpr const char* kDefaultChannelPrefix = "PIDLAB_";

/// Channel names (without the prefix). See lcmtypes/README.md.
inline constexpr const char* kEpisodeConfigChannel = "EPISODE_CONFIG";
inline constexpr const char* kReadyChannel = "READY";
inline constexpr const char* kPlantOutputChannel = "PLANT_OUTPUT";
inline constexpr const char* kControlChannel = "CONTROL";
inline constexpr const char* kDisturbanceChannel = "DISTURBANCE";
inline constexpr const char* kSummaryChannel = "SUMMARY";
inline constexpr const char* kTrajectoryRequestChannel = "TRAJECTORY_REQUEST";
inline constexpr const char* kTrajectoryChannel = "TRAJECTORY";

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
  /// Seed of the drop decisions (std::mt19937_64).
  uint64_t drop_seed = 1;

  bool IsValid(std::string* error) const;
};

struct TransportCounters {
  long received = 0;     // messages that reached a subscription
  long dropped = 0;      // thrown away by fault injection
  long undecodable = 0;  // failed to decode (garbage, wrong type): ignored
};

class Transport {
 public:
  /// `lcm` must outlive the transport and be good(). Options must be valid.
  Transport(lcm::LCM* lcm, const TransportOptions& options);
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  std::string Channel(const std::string& name) const { return options_.channel_prefix + name; }

  /// Stamps utime and publishes on <prefix><name>. Returns false on a send error.
  template <typename Msg>
  bool Publish(const std::string& name, Msg* msg) {
    msg->utime = NowUtime();
    return lcm_->publish(Channel(name), msg) == 0;
  }

  /// Calls on_message for every message on <prefix><name> that survives fault
  /// injection and decodes as Msg.
  template <typename Msg>
  void Subscribe(const std::string& name, std::function<void(const Msg&)> on_message) {
    auto sub = std::make_unique<Subscription>();
    sub->owner = this;
    sub->decode_and_call = [on_message](const void* data, int size) {
      Msg msg;
      try {
        if (msg.decode(data, 0, size) != size) return false;
      } catch (const std::exception&) {
        return false;  // e.g. a negative or absurd array length
      }
      on_message(msg);
      return true;
    };
    lcm_->subscribe(Channel(name), &Subscription::Handle, sub.get());
    subscriptions_.push_back(std::move(sub));
  }

  /// Waits at most timeout_s for traffic and handles every message already
  /// queued. Returns the number of messages handled (0 on timeout), -1 on an
  /// LCM error.
  int WaitAndHandle(double timeout_s);

  const TransportCounters& counters() const { return counters_; }
  const TransportOptions& options() const { return options_; }
  lcm::LCM* lcm() { return lcm_; }

 private:
  struct Subscription {
    Transport* owner = nullptr;
    std::function<bool(const void*, int)> decode_and_call;
    void Handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  };
  bool ShouldDrop();

  lcm::LCM* lcm_;
  TransportOptions options_;
  TransportCounters counters_;
  std::mt19937_64 drop_rng_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
};

}  // namespace pidlab::lcm_trio
