// launch's own record of the trio's episodes (launcher/episode_witness.h) on
// memq://, and the log of its configuration copies that it merges into a log
// whose logger lost them.

#include "pidlab/launcher/episode_witness.h"

#include <gtest/gtest.h>
#include <lcm/eventlog.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <string>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/transport/auth.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/transport.h"
#include "test_status.h"

namespace pidlab::launcher {
namespace {

using transport::Transport;
using transport::TransportOptions;

/// A valid configuration of a 100-step episode on the double integrator.
pidlab::lcmt_episode_config Config(int64_t episode_id, double kp = 2.0) {
  Plant plant;
  EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &plant)));
  evaluation::LoopOptions options;
  options.loop = evaluation::LoopKind::kSampled;
  options.dt_s = options.pid.dt_s = 0.01;
  options.sample_time_s = 0.05;
  options.horizon_s = 1.0;
  return transport::MakeEpisodeConfig(episode_client::MakeEpisodeSpec(
      episode_id, plant, PidGains{kp, 1.0, 0.0}, options, options.disturbance, transport::RecoveryOptions{}));
}

pidlab::lcmt_episode_summary Summary(int64_t episode_id) {
  pidlab::lcmt_episode_summary s{};
  s.episode_id = episode_id;
  return s;
}

/// Handles everything `transport` has queued.
void Drain(Transport* transport) {
  while (transport->WaitAndHandle(0.0) > 0) {
  }
}

TEST(EpisodeWitness, KeepsTheFirstCopyOfEachConfigurationAndEveryEpisodeThePlantEnded) {
  lcm::LCM lcm("memq://");
  TransportOptions options;
  Transport sender(&lcm, options), listener(&lcm, options);
  EpisodeWitness dut(&listener);
  auto first = Config(5, 2.0), again = Config(5, 3.0);
  sender.Publish(transport::kEpisodeConfigChannel, &first);
  sender.Publish(transport::kEpisodeConfigChannel, &again);
  for (int64_t id : {5, 5, 6}) {
    auto s = Summary(id);
    sender.Publish(transport::kSummaryChannel, &s);
  }
  Drain(&listener);
  ASSERT_NE(dut.Config(5), nullptr);
  EXPECT_EQ(dut.Config(5)->kp, 2.0);
  EXPECT_EQ(dut.Config(5)->utime, first.utime);
  EXPECT_EQ(dut.Config(6), nullptr);
  EXPECT_EQ(dut.ended(), (std::deque<int64_t>{5, 6}));
  EXPECT_TRUE(dut.Ended(6));
  EXPECT_FALSE(dut.Ended(7));
}

TEST(EpisodeWitness, ForgetsTheOldestEpisodesBeyondItsBound) {
  lcm::LCM lcm("memq://");
  Transport sender(&lcm, {}), listener(&lcm, {});
  EpisodeWitness dut(&listener, 2);
  for (int64_t id : {1, 2, 3}) {
    auto c = Config(id);
    auto s = Summary(id);
    sender.Publish(transport::kEpisodeConfigChannel, &c);
    sender.Publish(transport::kSummaryChannel, &s);
  }
  Drain(&listener);
  EXPECT_EQ(dut.Config(1), nullptr);
  EXPECT_NE(dut.Config(2), nullptr);
  EXPECT_NE(dut.Config(3), nullptr);
  EXPECT_EQ(dut.ended(), (std::deque<int64_t>{2, 3}));
}

TEST(EpisodeWitness, WithAKeyHearsOnlyAuthenticatedMessages) {
  lcm::LCM lcm("memq://");
  TransportOptions keyed;
  keyed.auth_key = transport::AuthKey{};
  keyed.auth_key->bytes.fill(7);
  Transport stranger(&lcm, {}), trio(&lcm, keyed), listener(&lcm, keyed);
  EpisodeWitness dut(&listener);
  auto forged = Config(8), real = Config(9);
  auto forged_end = Summary(8);
  stranger.Publish(transport::kEpisodeConfigChannel, &forged);
  stranger.Publish(transport::kSummaryChannel, &forged_end);
  trio.Publish(transport::kEpisodeConfigChannel, &real);
  Drain(&listener);
  EXPECT_EQ(dut.Config(8), nullptr);
  EXPECT_FALSE(dut.Ended(8));
  EXPECT_NE(dut.Config(9), nullptr);
}

class WriteConfigLogTest : public ::testing::Test {
 protected:
  void TearDown() override { std::remove(file_.c_str()); }
  std::string file_ = ::testing::TempDir() + "episode_witness_test." + std::to_string(getpid()) + ".lcmlog";
};

TEST_F(WriteConfigLogTest, WritesEachConfigurationAtItsUtimeInTimeOrder) {
  auto late = Config(2), early = Config(1);
  late.utime = 2000;
  early.utime = 1000;
  ASSERT_TRUE(IsOk(WriteConfigLog({late, early}, "PIDLAB_EPISODE_CONFIG", std::nullopt, file_)));
  lcm_eventlog_t* log = lcm_eventlog_create(file_.c_str(), "r");
  ASSERT_NE(log, nullptr);
  std::vector<int64_t> timestamps, ids;
  while (lcm_eventlog_event_t* ev = lcm_eventlog_read_next_event(log)) {
    EXPECT_EQ(std::string(ev->channel), "PIDLAB_EPISODE_CONFIG");
    pidlab::lcmt_episode_config m;
    EXPECT_EQ(m.decode(ev->data, 0, ev->datalen), ev->datalen);
    timestamps.push_back(ev->timestamp);
    ids.push_back(m.episode_id);
    lcm_eventlog_free_event(ev);
  }
  lcm_eventlog_destroy(log);
  EXPECT_EQ(timestamps, (std::vector<int64_t>{1000, 2000}));
  EXPECT_EQ(ids, (std::vector<int64_t>{1, 2}));
}

TEST_F(WriteConfigLogTest, TagsEachConfigurationSoThatTheKeyedReaderUsesIt) {
  transport::AuthKey key;
  key.bytes.fill(3);
  ASSERT_TRUE(IsOk(WriteConfigLog({Config(4)}, "PIDLAB_EPISODE_CONFIG", key, file_)));
  replay::ReadOptions options;
  options.auth_key = key;
  replay::LogContents contents;
  ASSERT_TRUE(IsOk(replay::ReadLog(file_, options, &contents)));
  EXPECT_EQ(contents.unauthenticated, 0);
  ASSERT_EQ(contents.episodes.size(), 1u);
  EXPECT_TRUE(contents.episodes[0].has_config);
  key.bytes.fill(4);  // another key: the tag does not verify
  options.auth_key = key;
  ASSERT_TRUE(IsOk(replay::ReadLog(file_, options, &contents)));
  EXPECT_EQ(contents.unauthenticated, 1);
}

TEST_F(WriteConfigLogTest, FailsNamingAFileItCannotWrite) {
  const Status st =
      WriteConfigLog({Config(1)}, "PIDLAB_EPISODE_CONFIG", std::nullopt, "/nonexistent-dir/x.lcmlog");
  EXPECT_EQ(st.code(), StatusCode::kIoFailed);
  EXPECT_NE(st.message().find("/nonexistent-dir/x.lcmlog"), std::string::npos) << st.message();
}

TEST(EpisodeList, NamesUpToThreeEpisodesThenCountsTheRest) {
  EXPECT_EQ(EpisodeList({7}), "7");
  EXPECT_EQ(EpisodeList({7, 8}), "7 and 8");
  EXPECT_EQ(EpisodeList({7, 8, 9}), "7, 8 and 9");
  EXPECT_EQ(EpisodeList({7, 8, 9, 10, 11}), "7, 8, 9 and 2 more");
}

}  // namespace
}  // namespace pidlab::launcher
