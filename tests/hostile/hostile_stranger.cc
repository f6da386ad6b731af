// hostile_stranger: a stranger on the trio's multicast group, for the hostile
// traffic tests (tests/hostile/hostile_test.sh) and bench/hostile_bench.sh.
// It watches the live traffic (tagged or not) and attacks the episode it
// sees with one class of messages, seeded, until it has sent --messages
// messages or --seconds have passed:
//   fuzz          random bytes, and bit-flipped copies of real datagrams
//   huge-arrays   array lengths of 2^28 and 2^31-1 on every array channel
//   absurd-steps  blocks, requests, commands and chunks at INT64_MAX, INT64_MIN, -1
//   forge-control     CONTROL for the step just published, u = 0, right y
//   forge-disturbance DISTURBANCE_BLOCKs answering every request with n = 0.5
//   forge-output      PLANT_OUTPUT for the next step, y = 5
//   forge-chunk       TRAJECTORY chunks with y = 5
//   forge-summary     SUMMARY FAILED with terminal escapes in its message
//   replay            exact copies of earlier datagrams
//   all           every class in turn
// It never sends anywhere but the URL it is given (the tests give it a
// group inside a private network namespace).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "pidlab/transport/transport.h"
#include "pidlab/transport/wire.h"

namespace {

constexpr int kTag = 32;  // an HMAC tag after the payload, when the trio has a key
const char* const kClasses[] = {"fuzz",          "huge-arrays",       "absurd-steps",
                                "forge-control", "forge-disturbance", "forge-output",
                                "forge-chunk",   "forge-summary",     "replay"};
const char* const kChannels[] = {
    "EPISODE_CONFIG",     "READY",      "PLANT_OUTPUT",        "CONTROL",          "DISTURBANCE", "SUMMARY",
    "TRAJECTORY_REQUEST", "TRAJECTORY", "DISTURBANCE_REQUEST", "DISTURBANCE_BLOCK"};

/// Decodes a message whether or not a tag follows it (the layout checked
/// first: the stranger hears its own huge arrays too).
template <typename Msg>
bool DecodeEither(const lcm::ReceiveBuffer* rbuf, Msg* m) {
  const int size = static_cast<int>(rbuf->data_size);
  for (int n : {size, size - kTag})
    if (n > 0 && pidlab::transport::WireLayoutOk(Msg::getHash(), rbuf->data, n) &&
        m->decode(rbuf->data, 0, n) == n)
      return true;
  return false;
}

struct Stranger {
  lcm::LCM* lcm = nullptr;
  lcm::LCM* lanes[3] = {nullptr, nullptr, nullptr};  // the trio's step lanes (transport.h), [0] = lcm
  std::string prefix;
  std::string attack;
  long budget = 0;
  long sent = 0;
  std::mt19937_64 rng;
  int64_t episode = 0;                                            // the live episode seen last
  pidlab::lcmt_plant_output last_output{};                        // the plant output seen last
  std::deque<std::pair<std::string, std::vector<uint8_t>>> seen;  // recent real datagrams

  bool Spent() const { return sent >= budget; }

  template <typename Msg>
  void Send(const std::string& channel, Msg* m) {
    if (Spent()) return;
    For(channel)->publish(prefix + channel, m);
    ++sent;
  }
  void SendRaw(const std::string& channel, const std::vector<uint8_t>& bytes) {
    if (Spent()) return;
    For(channel)->publish(prefix + channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    ++sent;
  }
  /// Where the trio listens for a channel: the per-step channels on their lanes.
  lcm::LCM* For(const std::string& channel) const {
    lcm::LCM* lane = lanes[pidlab::transport::LaneOf(channel.c_str())];
    return lane ? lane : lcm;
  }
  bool Is(const char* cls) const { return attack == cls; }

  void Remember(const std::string& channel, const lcm::ReceiveBuffer* rbuf) {
    const auto* d = static_cast<const uint8_t*>(rbuf->data);
    seen.emplace_back(channel, std::vector<uint8_t>(d, d + rbuf->data_size));
    if (seen.size() > 256) seen.pop_front();
  }

  void OnOutput(const pidlab::lcmt_plant_output& y) {
    episode = y.episode_id;
    if (y.y != 5.0) last_output = y;  // not our own forgery
    if (Is("forge-control")) {
      pidlab::lcmt_control_command c{};
      c.episode_id = y.episode_id;
      c.step = y.step;
      c.y = y.y;
      Send("CONTROL", &c);
    } else if (Is("forge-output") && y.y != 5.0) {
      pidlab::lcmt_plant_output f = y;
      f.step = y.step + 1;
      f.y = 5.0;
      Send("PLANT_OUTPUT", &f);
    } else if (Is("forge-summary")) {
      pidlab::lcmt_episode_summary s{};
      s.episode_id = y.episode_id;
      s.status = pidlab::lcmt_episode_summary::FAILED;
      s.silent_role = "controller";
      s.message = "\x1b[31mEVIL\x1b[0m " + std::string(5000, 'x');
      Send("SUMMARY", &s);
    }
  }
  void OnRequest(const pidlab::lcmt_disturbance_request& r) {
    episode = r.episode_id;
    if (!Is("forge-disturbance")) return;
    pidlab::lcmt_disturbance_block b{};
    b.episode_id = r.episode_id;
    b.step = r.step;
    b.count = static_cast<int32_t>(std::clamp<int64_t>(r.samples, 0, 128));
    b.n.assign(static_cast<std::size_t>(b.count), 0.5);
    Send("DISTURBANCE_BLOCK", &b);
  }
  void OnChunk(const pidlab::lcmt_trajectory_chunk& c) {
    episode = c.episode_id;
    if (!Is("forge-chunk")) return;
    pidlab::lcmt_trajectory_chunk f = c;
    for (double& y : f.y) y = 5.0;
    Send("TRAJECTORY", &f);
  }

  /// Unsolicited messages of the current class (not answers to traffic).
  void Unsolicited() {
    if (Is("fuzz")) {
      std::vector<uint8_t> junk(1 + rng() % 300);
      for (auto& b : junk) b = static_cast<uint8_t>(rng());
      if (rng() % 2 == 0) std::memcpy(junk.data(), "\x00\x00\x00\x00", std::min<std::size_t>(4, junk.size()));
      SendRaw(kChannels[rng() % 10], junk);
      if (!seen.empty()) {  // a real datagram with a few bits flipped
        auto [channel, bytes] = seen[rng() % seen.size()];
        for (int i = 0; i < 3; ++i) bytes[rng() % bytes.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
        SendRaw(channel.substr(prefix.size()), bytes);
      }
    } else if (Is("huge-arrays")) {
      for (uint32_t count : {0x10000000u, 0x7fffffffu, 0x80000000u}) {
        std::vector<uint8_t> d = Header(pidlab::lcmt_trajectory_chunk::getHash());
        Put32(&d, count);
        d.resize(d.size() + 64);
        SendRaw("TRAJECTORY", d);
        d = Header(pidlab::lcmt_disturbance_block::getHash());
        d.resize(d.size() + 8);
        Put32(&d, count);
        SendRaw("DISTURBANCE_BLOCK", d);
        d = Header(pidlab::lcmt_episode_config::getHash());
        Put32(&d, 2);
        d.push_back('x');
        d.push_back(0);
        Put32(&d, count);
        SendRaw("EPISODE_CONFIG", d);
      }
    } else if (Is("absurd-steps")) {
      for (int64_t step : {std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max() - 1,
                           std::numeric_limits<int64_t>::min(), int64_t{-1}}) {
        pidlab::lcmt_disturbance_block b{};
        b.episode_id = episode;
        b.step = step;
        b.count = 1;
        b.n = {0.5};
        Send("DISTURBANCE_BLOCK", &b);
        pidlab::lcmt_trajectory_request r{};
        r.episode_id = episode;
        r.step = step;
        r.count = 2000;
        Send("TRAJECTORY_REQUEST", &r);
        pidlab::lcmt_disturbance_request q{};
        q.episode_id = episode;
        q.step = step;
        q.samples = 1 << 30;
        Send("DISTURBANCE_REQUEST", &q);
        pidlab::lcmt_trajectory_chunk c{};
        c.episode_id = episode;
        c.step = step;
        c.count = 1;
        c.y = c.u = c.n = {5.0};
        Send("TRAJECTORY", &c);
        pidlab::lcmt_control_command u{};
        u.episode_id = episode;
        u.step = step;
        Send("CONTROL", &u);
      }
    } else if (attack.rfind("forge-", 0) == 0 && episode != 0) {
      // Besides answering traffic, keep forging for the steps around the
      // live one (most land as foreign or duplicate, some as conflicts).
      pidlab::lcmt_plant_output y = last_output;
      y.step += static_cast<int64_t>(rng() % 3);
      OnOutput(y);
      pidlab::lcmt_disturbance_request r{};
      r.episode_id = episode;
      r.step = y.step + 128;
      r.samples = 128;
      OnRequest(r);
      pidlab::lcmt_trajectory_chunk c{};
      c.episode_id = episode;
      c.step = std::max<int64_t>(0, y.step - 10);
      c.count = 1;
      c.y = c.u = c.n = {0.25};
      OnChunk(c);
    } else if (Is("replay") && !seen.empty()) {
      const auto& [channel, bytes] = seen[rng() % seen.size()];
      SendRaw(channel.substr(prefix.size()), bytes);
    }
  }

  std::vector<uint8_t> Header(int64_t hash) const {
    std::vector<uint8_t> d;
    for (int i = 0; i < 8; ++i)
      d.push_back(static_cast<uint8_t>(static_cast<uint64_t>(hash) >> (56 - 8 * i)));
    for (int i = 0; i < 8; ++i) d.push_back(0);  // utime
    for (int i = 0; i < 8; ++i)
      d.push_back(static_cast<uint8_t>(static_cast<uint64_t>(episode) >> (56 - 8 * i)));
    for (int i = 0; i < 8; ++i) d.push_back(0);  // step
    return d;
  }
  static void Put32(std::vector<uint8_t>* d, uint32_t v) {
    for (int i = 0; i < 4; ++i) d->push_back(static_cast<uint8_t>(v >> (24 - 8 * i)));
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "hostile_stranger: attacks a live pidlab trio with one class of hostile messages (tests only)"};
  std::string url, prefix = "PIDLAB_", attack = "all";
  long messages = 20000;
  double seconds = 30.0;
  uint64_t seed = 1;
  app.add_option("--lcm-url", url, "LCM URL of the trio")->required();
  app.add_option("--prefix", prefix, "channel prefix")->capture_default_str();
  app.add_option("--attack", attack, "fuzz | huge-arrays | absurd-steps | forge-* | replay | all")
      ->capture_default_str();
  app.add_option("--messages", messages, "messages to send in all")->capture_default_str();
  app.add_option("--seconds", seconds, "stop after this long in any case")->capture_default_str();
  app.add_option("--seed", seed, "seed")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::vector<std::string> classes;
  if (attack == "all")
    classes.assign(std::begin(kClasses), std::end(kClasses));
  else if (std::find(std::begin(kClasses), std::end(kClasses), attack) != std::end(kClasses))
    classes = {attack};
  else {
    std::fprintf(stderr, "hostile_stranger: error: unknown --attack '%s'\n", attack.c_str());
    return 2;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "hostile_stranger: cannot start LCM on %s\n", url.c_str());
    return 1;
  }
  // The per-step channels travel on the trio's step lanes (transport.h).
  std::unique_ptr<lcm::LCM> lane_instances[3];
  for (int lane : {pidlab::transport::kPlantOutputLane, pidlab::transport::kControlLane}) {
    const std::string lane_url = pidlab::transport::StepLaneUrl(url, lane);
    if (!lane_url.empty()) lane_instances[lane] = std::make_unique<lcm::LCM>(lane_url);
  }
  Stranger s;
  s.lcm = &lcm;
  for (int lane = 0; lane < 3; ++lane)
    s.lanes[lane] = lane_instances[lane] ? lane_instances[lane].get() : &lcm;
  s.prefix = prefix;
  s.attack = classes[0];
  s.budget = messages;
  s.rng.seed(seed);
  s.For("PLANT_OUTPUT")
      ->subscribeFunction(
          prefix + "PLANT_OUTPUT",
          +[](const lcm::ReceiveBuffer* rbuf, const std::string& ch, Stranger* st) {
            st->Remember(ch, rbuf);
            pidlab::lcmt_plant_output m{};
            if (DecodeEither(rbuf, &m)) st->OnOutput(m);
          },
          &s);
  lcm.subscribeFunction(
      prefix + "DISTURBANCE_REQUEST",
      +[](const lcm::ReceiveBuffer* rbuf, const std::string& ch, Stranger* st) {
        st->Remember(ch, rbuf);
        pidlab::lcmt_disturbance_request m{};
        if (DecodeEither(rbuf, &m)) st->OnRequest(m);
      },
      &s);
  lcm.subscribeFunction(
      prefix + "TRAJECTORY",
      +[](const lcm::ReceiveBuffer* rbuf, const std::string& ch, Stranger* st) {
        st->Remember(ch, rbuf);
        pidlab::lcmt_trajectory_chunk m{};
        if (DecodeEither(rbuf, &m)) st->OnChunk(m);
      },
      &s);
  for (const char* ch : {"CONTROL", "DISTURBANCE_BLOCK", "EPISODE_CONFIG", "READY", "SUMMARY"})
    s.For(ch)->subscribeFunction(
        prefix + ch,
        +[](const lcm::ReceiveBuffer* rbuf, const std::string& c, Stranger* st) { st->Remember(c, rbuf); },
        &s);
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  const long per_class = messages / static_cast<long>(classes.size());
  for (std::size_t i = 0; i < classes.size(); ++i) {
    s.attack = classes[i];
    s.budget = i + 1 == classes.size() ? messages : per_class * static_cast<long>(i + 1);
    while (!s.Spent() && std::chrono::steady_clock::now() < end) {
      for (int lane = 0; lane < 3; ++lane) {  // what arrived meanwhile, on the base URL and the lanes
        if (lane > 0 && s.lanes[lane] == &lcm) continue;
        for (int n = 0; n < 256 && s.lanes[lane]->handleTimeout(0) > 0;) ++n;
      }
      s.Unsolicited();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
  std::printf("hostile_stranger: %ld messages sent (%s)\n", s.sent, attack.c_str());
  return 0;
}
