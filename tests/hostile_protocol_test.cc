// The trio's roles under hostile traffic on memq:// (single process, no
// network): a datagram with absurd lengths or steps never crashes a role, and
// a forged message never silently changes a result: the episode either ends
// bit-identical or fails naming the conflicting channel and step.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <vector>

#include "pidlab/controller/controller_role.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/plant_sim/disturbance_role.h"
#include "pidlab/plant_sim/plant_role.h"
#include "pidlab/transport/transport.h"
#include "pidlab/transport/wire.h"
#include "test_status.h"

using pidlab::controller::ControllerRole;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::RunSampledLoopInProcess;
using pidlab::plant_sim::DisturbanceRole;
using pidlab::plant_sim::PlantRole;

namespace pidlab::transport {
namespace {

constexpr int64_t kId = 42;

TransportOptions WithKey(std::optional<AuthKey> key) {
  TransportOptions o;
  o.auth_key = key;
  return o;
}

AuthKey TestKey(uint8_t seed) {
  AuthKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<uint8_t>(seed + 7 * i);
  return k;
}

struct Arena;
/// On every y_k, answers first with u = 0 computed from the right y.
void ForgeControlCommands(Arena* a);
void ForgeCommandFor(Arena* a, const pidlab::lcmt_plant_output& m);

/// One episode of the double integrator with a square disturbance, run by
/// the three roles on memq://; `attack` is called with the attacker's
/// transport before the roles subscribe, so its handlers run first.
struct Arena {
  lcm::LCM lcm{"memq://"};
  TransportOptions trio_options;  // the trio's (and the observing client's): with or without a key
  Transport attacker_t;
  Transport plant_t, controller_t, disturbance_t, client_t;
  std::unique_ptr<PlantRole> plant;
  std::unique_ptr<ControllerRole> controller;
  std::unique_ptr<DisturbanceRole> disturbance;
  Plant model;
  LoopOptions options;
  std::vector<double> y;
  bool summary = false;
  pidlab::lcmt_episode_summary last;

  explicit Arena(const std::function<void(Arena*)>& attack = nullptr,
                 std::optional<AuthKey> key = std::nullopt)
      : trio_options(WithKey(key)),
        attacker_t(&lcm, {}),
        plant_t(&lcm, trio_options),
        controller_t(&lcm, trio_options),
        disturbance_t(&lcm, trio_options),
        client_t(&lcm, trio_options) {
    std::string error;
    EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &model)));
    options.loop = LoopKind::kSampled;
    options.horizon_s = 1.0;
    options.disturbance.kind = DisturbanceKind::kSquare;
    options.disturbance.amplitude = 0.3;
    if (attack) attack(this);
    plant = std::make_unique<PlantRole>(&plant_t);
    controller = std::make_unique<ControllerRole>(&controller_t);
    disturbance = std::make_unique<DisturbanceRole>(&disturbance_t);
    y.assign(static_cast<std::size_t>(options.TotalSteps() + 1), std::numeric_limits<double>::quiet_NaN());
    client_t.Subscribe<pidlab::lcmt_plant_output>(
        kPlantOutputChannel, [this](const pidlab::lcmt_plant_output& m) {
          if (m.episode_id == kId && m.step >= 0 && m.step < static_cast<int64_t>(y.size()) &&
              std::isnan(y[static_cast<std::size_t>(m.step)]))
            y[static_cast<std::size_t>(m.step)] = m.y;
        });
    client_t.Subscribe<pidlab::lcmt_episode_summary>(kSummaryChannel,
                                                     [this](const pidlab::lcmt_episode_summary& m) {
                                                       summary = true;
                                                       last = m;
                                                     });
  }

  /// Runs the episode; true if the plant summarised it OK.
  bool Run() {
    RecoveryOptions recovery;
    recovery.retransmit_interval_s = 0.001;
    recovery.silence_deadline_s = 0.3;
    auto config = MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
        kId, model, PidGains{2.0, 1.0, 1.5}, options, options.disturbance, recovery));
    client_t.Publish(kEpisodeConfigChannel, &config);
    const double start = NowSeconds();
    while (!summary && NowSeconds() - start < 20.0) {
      client_t.WaitAndHandle(0.001);
      const double now = NowSeconds();
      plant->Tick(now);
      controller->Tick(now);
      disturbance->Tick(now);
    }
    return summary && last.status == pidlab::lcmt_episode_summary::OK;
  }

  std::vector<double> Reference() const {
    std::vector<double> ref;
    std::string error;
    EXPECT_TRUE(OkInto(
        RunSampledLoopInProcess(model, PidGains{2.0, 1.0, 1.5}, options, options.disturbance, &ref, nullptr),
        &error));
    return ref;
  }
};

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(HostileTraffic, AnUnattackedEpisodeIsBitIdenticalToTheInProcessLoop) {
  Arena arena;
  ASSERT_TRUE(arena.Run()) << arena.last.message;
  EXPECT_TRUE(SameBits(arena.y, arena.Reference()));
}

void ForgeControlCommands(Arena* a) {
  // The attacker reads the wire itself: it sees every y_k, tagged or not
  // (a tag is 32 bytes after the payload), and answers with its own command.
  a->lcm.subscribeFunction(
      a->attacker_t.Channel(kPlantOutputChannel),
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Arena* arena) {
        pidlab::lcmt_plant_output m{};
        const int size = static_cast<int>(rbuf->data_size);
        if (m.decode(rbuf->data, 0, size) != size &&
            m.decode(rbuf->data, 0, size - static_cast<int>(kAuthTagBytes)) !=
                size - static_cast<int>(kAuthTagBytes))
          return;
        ForgeCommandFor(arena, m);
      },
      a);
}

void ForgeCommandFor(Arena* a, const pidlab::lcmt_plant_output& m) {
  {
    pidlab::lcmt_control_command c{};
    c.episode_id = m.episode_id;
    c.step = m.step;
    c.y = m.y;
    c.u = 0.0;
    a->attacker_t.Publish(kControlChannel, &c);
  }
}

TEST(Authentication, WithAKeyForgedCommandsAreCountedAndTheResultIsBitIdentical) {
  Arena arena(ForgeControlCommands, TestKey(1));
  ASSERT_TRUE(arena.Run()) << arena.last.message;
  EXPECT_TRUE(SameBits(arena.y, arena.Reference()));
  EXPECT_GT(arena.plant_t.counters().unauthenticated, 0);
  EXPECT_EQ(arena.plant->counters().conflicts, 0);
}

TEST(Authentication, AMessageTaggedWithAnotherKeyIsUnauthenticated) {
  lcm::LCM lcm("memq://");
  Transport sender(&lcm, WithKey(TestKey(2))), receiver(&lcm, WithKey(TestKey(3)));
  int heard = 0;
  receiver.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                                [&](const pidlab::lcmt_plant_output&) { ++heard; });
  pidlab::lcmt_plant_output m{};
  sender.Publish(kPlantOutputChannel, &m);
  while (receiver.WaitAndHandle(0.0) > 0) {
  }
  EXPECT_EQ(heard, 0);
  EXPECT_EQ(receiver.counters().unauthenticated, 1);
}

TEST(Authentication, AnExactRepeatOfAnAcceptedDatagramIsDroppedAsReplayed) {
  lcm::LCM lcm("memq://");
  Transport sender(&lcm, WithKey(TestKey(4))), receiver(&lcm, WithKey(TestKey(4)));
  int heard = 0;
  receiver.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                                [&](const pidlab::lcmt_plant_output&) { ++heard; });
  std::vector<uint8_t> captured;
  auto* raw = lcm.subscribeFunction(
      sender.Channel(kPlantOutputChannel),
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, std::vector<uint8_t>* out) {
        const auto* d = static_cast<const uint8_t*>(rbuf->data);
        out->assign(d, d + rbuf->data_size);
      },
      &captured);
  pidlab::lcmt_plant_output m{};
  m.episode_id = kId;
  sender.Publish(kPlantOutputChannel, &m);
  while (receiver.WaitAndHandle(0.0) > 0) {
  }
  lcm.unsubscribe(raw);
  ASSERT_EQ(heard, 1);
  lcm.publish(sender.Channel(kPlantOutputChannel), captured.data(), static_cast<unsigned>(captured.size()));
  while (receiver.WaitAndHandle(0.0) > 0) {
  }
  EXPECT_EQ(heard, 1);
  EXPECT_EQ(receiver.counters().replayed, 1);
}

TEST(Authentication, AKeyFileIsReadAndAShortOneIsRefusedNamingTheFile) {
  const std::string path = ::testing::TempDir() + "/pidlab_test_key";
  {
    std::ofstream f(path, std::ios::binary);
    f << "0123456789abcdef0123456789abcdef";
  }
  AuthKey a, b;
  std::string error;
  ASSERT_TRUE(IsOk(LoadAuthKey(path, &a)));
  ASSERT_TRUE(IsOk(LoadAuthKey(path, &b)));
  EXPECT_EQ(a.bytes, b.bytes);
  {
    std::ofstream f(path, std::ios::binary);
    f << "short";
  }
  EXPECT_FALSE(OkInto(LoadAuthKey(path, &a), &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_FALSE(OkInto(LoadAuthKey("/nonexistent/key", &a), &error));
}

TEST(HostileTraffic, AForgedControlCommandFailsTheEpisodeNamingControlAndTheStep) {
  Arena arena([](Arena* a) {
    // On every y_k, answer first with u = 0 computed from the right y.
    a->attacker_t.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                                       [a](const pidlab::lcmt_plant_output& m) {
                                                         if (m.step != 50) return;
                                                         pidlab::lcmt_control_command c{};
                                                         c.episode_id = m.episode_id;
                                                         c.step = m.step;
                                                         c.y = m.y;
                                                         c.u = 0.0;
                                                         a->attacker_t.Publish(kControlChannel, &c);
                                                       });
  });
  EXPECT_FALSE(arena.Run());
  ASSERT_TRUE(arena.summary);
  EXPECT_NE(arena.last.message.find("conflicting CONTROL messages for step 50"), std::string::npos)
      << arena.last.message;
  EXPECT_EQ(arena.last.silent_role, "");
  EXPECT_EQ(arena.plant->counters().conflicts, 1);
}

TEST(HostileTraffic, ForgedDisturbanceBlocksAheadFailTheEpisodeNamingTheBlockChannel) {
  Arena arena([](Arena* a) {
    a->attacker_t.Subscribe<pidlab::lcmt_disturbance_request>(
        kDisturbanceRequestChannel, [a](const pidlab::lcmt_disturbance_request& m) {
          pidlab::lcmt_disturbance_block b{};
          b.episode_id = m.episode_id;
          b.step = m.step;
          b.dt_s = 1e-3;
          b.count = static_cast<int32_t>(std::min<int64_t>(m.samples, kNoiseBlock));
          b.n.assign(static_cast<std::size_t>(b.count), 0.5);
          a->attacker_t.Publish(kDisturbanceBlockChannel, &b);
        });
  });
  EXPECT_FALSE(arena.Run());
  EXPECT_NE(arena.last.message.find("conflicting DISTURBANCE_BLOCK messages for step"), std::string::npos)
      << arena.last.message;
}

TEST(HostileTraffic, AForgedPlantOutputAheadNamesPlantOutputAndBlamesNoProcess) {
  Arena arena([](Arena* a) {
    // When y_k is out, claim y_{k+1} = 5 before the plant publishes it: the
    // controller answers it, then sees the plant's real y_{k+1}.
    a->attacker_t.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                                       [a](const pidlab::lcmt_plant_output& m) {
                                                         if (m.step != 30 || m.y == 5.0) return;
                                                         pidlab::lcmt_plant_output f = m;
                                                         f.step = m.step + 1;
                                                         f.y = 5.0;
                                                         a->attacker_t.Publish(kPlantOutputChannel, &f);
                                                       });
  });
  EXPECT_FALSE(arena.Run());
  EXPECT_NE(arena.last.message.find("conflicting PLANT_OUTPUT messages for step 31"), std::string::npos)
      << arena.last.message;
  EXPECT_EQ(arena.last.silent_role, "");
}

TEST(HostileTraffic, MessagesAtAbsurdStepsAreCountedAndChangeNothing) {
  const int64_t huge = std::numeric_limits<int64_t>::max();
  Arena arena([huge](Arena* a) {
    a->attacker_t.Subscribe<pidlab::lcmt_plant_output>(
        kPlantOutputChannel, [a, huge](const pidlab::lcmt_plant_output& m) {
          if (m.step % 100 != 0) return;
          for (int64_t step : {huge, huge - 1, std::numeric_limits<int64_t>::min(), int64_t{-1}}) {
            pidlab::lcmt_disturbance_block b{};
            b.episode_id = m.episode_id;
            b.step = step;
            b.count = 1;
            b.n = {0.5};
            a->attacker_t.Publish(kDisturbanceBlockChannel, &b);
            pidlab::lcmt_trajectory_request r{};
            r.episode_id = m.episode_id;
            r.step = step;
            r.count = 2000;
            a->attacker_t.Publish(kTrajectoryRequestChannel, &r);
            pidlab::lcmt_disturbance_request d{};
            d.episode_id = m.episode_id;
            d.step = step;
            d.samples = 1024;
            a->attacker_t.Publish(kDisturbanceRequestChannel, &d);
            pidlab::lcmt_control_command c{};
            c.episode_id = m.episode_id;
            c.step = step;
            a->attacker_t.Publish(kControlChannel, &c);
          }
        });
  });
  ASSERT_TRUE(arena.Run()) << arena.last.message;
  EXPECT_TRUE(SameBits(arena.y, arena.Reference()));
  EXPECT_GT(arena.plant->counters().foreign, 0);
}

/// A raw datagram: fingerprint, the 24-byte header, then `body`.
std::vector<uint8_t> Datagram(int64_t fingerprint, const std::vector<uint8_t>& body) {
  std::vector<uint8_t> d;
  d.reserve(8 + 24 + body.size());
  for (int i = 0; i < 8; ++i)
    d.push_back(static_cast<uint8_t>(static_cast<uint64_t>(fingerprint) >> (56 - 8 * i)));
  for (int i = 0; i < 24; ++i) d.push_back(i == 15 ? 42 : 0);  // utime 0, episode id 42, step 0
  for (uint8_t b : body) d.push_back(b);
  return d;
}

TEST(WireLayout, RejectsATrajectoryChunkDeclaringTwoToThe28Elements) {
  const auto d = Datagram(pidlab::lcmt_trajectory_chunk::getHash(), {0x10, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_FALSE(WireLayoutOk(pidlab::lcmt_trajectory_chunk::getHash(), d.data(), static_cast<int>(d.size())));
}

TEST(WireLayout, RejectsAConfigWhosePolynomialIsLongerThanTheProtocolAllows) {
  pidlab::lcmt_episode_config m{};
  m.plant_name = m.anti_windup = m.derivative_on = m.integral = m.disturbance_kind = "x";
  m.num.assign(kMaxPolynomialCoefficients + 1, 1.0);
  m.num_size = static_cast<int32_t>(m.num.size());
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_FALSE(WireLayoutOk(m.getHash(), buf.data(), static_cast<int>(buf.size())));
  m.num.assign(3, 1.0);
  m.num_size = 3;
  buf.assign(static_cast<std::size_t>(m.getEncodedSize()), 0);
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_TRUE(WireLayoutOk(m.getHash(), buf.data(), static_cast<int>(buf.size())));
}

TEST(WireLayout, HugeArrayLengthsOnEveryChannelAreCountedUndecodableWithoutCrashing) {
  Arena arena([](Arena* a) {
    a->attacker_t.Subscribe<pidlab::lcmt_plant_output>(
        kPlantOutputChannel, [a](const pidlab::lcmt_plant_output& m) {
          if (m.step != 10) return;
          const std::vector<uint8_t> huge = {0x7f, 0xff, 0xff, 0xff, 0, 0, 0, 0, 0, 0, 0, 0};
          for (const auto& [channel, hash] : std::vector<std::pair<const char*, int64_t>>{
                   {kTrajectoryChannel, pidlab::lcmt_trajectory_chunk::getHash()},
                   {kDisturbanceBlockChannel, pidlab::lcmt_disturbance_block::getHash()},
                   {kEpisodeConfigChannel, pidlab::lcmt_episode_config::getHash()}}) {
            std::vector<uint8_t> body = huge;
            if (hash == pidlab::lcmt_disturbance_block::getHash())
              body.insert(body.begin(), 8, 0);  // dt_s first
            if (hash == pidlab::lcmt_episode_config::getHash()) body = {0, 0, 0, 2, 'x', 0, 0x10, 0, 0, 0};
            const auto d = Datagram(hash, body);
            a->lcm.publish(a->attacker_t.Channel(channel), d.data(), static_cast<unsigned>(d.size()));
          }
        });
  });
  ASSERT_TRUE(arena.Run()) << arena.last.message;
  EXPECT_TRUE(SameBits(arena.y, arena.Reference()));
  EXPECT_GT(arena.plant_t.counters().undecodable, 0);
}

TEST(WireText, EscapesBytesOutsidePrintableAsciiAndCutsLongText) {
  EXPECT_EQ(EscapeWireText("ok"), "ok");
  EXPECT_EQ(EscapeWireText(std::string("a\nb\x01\xff", 5)), "a\\x0ab\\x01\\xff");
  EXPECT_EQ(EscapeWireText(std::string(300, 'x'), 10), std::string(10, 'x') + "...");
}

}  // namespace
}  // namespace pidlab::transport
