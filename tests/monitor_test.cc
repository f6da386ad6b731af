// Unit tests of the live monitor (monitor/): the min/max decimation and the
// frames byte for byte, and a LiveMonitor on one memq:// LCM instance fed by
// the three roles and the episode client in this process, or by messages
// published by hand (forged, hostile).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <string>
#include <vector>

#include "pidlab/controller/controller_role.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/monitor/frames.h"
#include "pidlab/monitor/live_monitor.h"
#include "pidlab/plant_sim/disturbance_role.h"
#include "pidlab/plant_sim/plant_role.h"
#include "test_status.h"

namespace pidlab::monitor {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof v);
}

std::string ExpectedHeader(uint32_t kind, const std::vector<double>& fields) {
  std::string out;
  Put(&out, kFrameMagic);
  Put(&out, kind);
  for (double f : fields) Put(&out, f);
  return out;
}

TEST(DecimateMinMax, FewerStepsThanColumnsGiveOneStepPerColumnWithMinEqualToMax) {
  const std::vector<double> v = {1.0, -2.0, 3.5};
  std::vector<float> lo, hi;
  DecimateMinMax(v.data(), 3, 100, &lo, &hi);
  ASSERT_EQ(lo.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(lo[i], static_cast<float>(v[i]));
    EXPECT_EQ(hi[i], static_cast<float>(v[i]));
  }
}

TEST(DecimateMinMax, ColumnsCoverFloorBoundariesAndKeepExtremesNeverAverages) {
  // 10 steps in 4 columns: [0,2) [2,5) [5,7) [7,10).
  const std::vector<double> v = {0, 9, 1, -7, 2, 5, 5, 3, 100, -1};
  std::vector<float> lo, hi;
  DecimateMinMax(v.data(), 10, 4, &lo, &hi);
  EXPECT_EQ(lo, (std::vector<float>{0, -7, 5, -1}));
  EXPECT_EQ(hi, (std::vector<float>{9, 2, 5, 100}));
}

TEST(DecimateMinMax, NaNIsSkippedAndAColumnWithoutValuesIsNaN) {
  const std::vector<double> v = {kNaN, 4, kNaN, kNaN, 1, 2};
  std::vector<float> lo, hi;
  DecimateMinMax(v.data(), 6, 3, &lo, &hi);
  EXPECT_EQ(lo[0], 4.0f);
  EXPECT_EQ(hi[0], 4.0f);
  EXPECT_TRUE(std::isnan(lo[1]) && std::isnan(hi[1]));
  EXPECT_EQ(lo[2], 1.0f);
  EXPECT_EQ(hi[2], 2.0f);
}

TEST(EncodeViewFrame, WritesTheHeaderThenSixFloat32ArraysByteForByte) {
  const std::vector<double> y = {1, 2, 3, 4}, u = {5, 6, 7, kNaN}, n = {0, 0, 0, kNaN};
  const FrameInfo info{42, 0.001, 3, 4, 7};
  const std::string frame = EncodeViewFrame(info, y.data(), u.data(), n.data(), 4, 16);
  std::string want = ExpectedHeader(kViewFrame, {42, 0, 4, 4, 0.001, 3, 4, 7});
  for (const std::vector<double>* s : {&y, &u, &n})
    for (int pass = 0; pass < 2; ++pass)  // min, then max: equal with one step per column
      for (double v : *s) Put(&want, static_cast<float>(v));
  ASSERT_EQ(frame.size(), kFrameHeaderBytes + 6 * 4 * sizeof(float));
  EXPECT_EQ(frame, want);
}

TEST(EncodeDataFrame, WritesTheHeaderThenThreeFloat64ArraysBitForBit) {
  const std::vector<double> y = {0.1, 0.2, 0.30000000000000004}, u = {1e-300, -0.0, kNaN}, n = {3, 2, kNaN};
  const FrameInfo info{9, 0.01, 2, 3, 0};
  const std::string frame = EncodeDataFrame(info, 0, y.data(), u.data(), n.data(), 3);
  std::string want = ExpectedHeader(kDataFrame, {9, 0, 3, 0, 0.01, 2, 3, 0});
  for (const std::vector<double>* s : {&y, &u, &n})
    for (double v : *s) Put(&want, v);
  EXPECT_EQ(frame, want);
}

TEST(LiveMonitorOptions, IsValidNamesTheFieldAndValue) {
  LiveMonitorOptions o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.max_episodes = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_episodes 0"), std::string::npos) << error;
  o = LiveMonitorOptions{};
  o.max_total_steps = -5;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_total_steps -5"), std::string::npos) << error;
  o = LiveMonitorOptions{};
  o.max_kept_steps = o.max_total_steps - 1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_kept_steps 9999999"), std::string::npos) << error;
}

TEST(LiveMonitor, AnLcmThatCannotStartIsAStatusAndPollsNothingNotAnException) {
  LiveMonitorOptions o;
  o.lcm_url = "udpm://239.255.76.67:99999";  // no such port: LCM does not start
  std::unique_ptr<LiveMonitor> dut;
  EXPECT_NO_THROW(dut = std::make_unique<LiveMonitor>(o));
  EXPECT_EQ(dut->status().code(), StatusCode::kRunnerFailed);
  EXPECT_NE(dut->status().message().find("99999"), std::string::npos) << dut->status().message();
  EXPECT_EQ(dut->Poll(0.0), -1);
}

// Handles everything waiting on a memq:// instance.
void Drain(LiveMonitor* dut) {
  while (dut->Poll(0.0) > 0) {
  }
}

LiveMonitorOptions MemqOptions() {
  LiveMonitorOptions o;
  o.lcm_url = "memq://";
  return o;
}

TEST(LiveMonitor, AssemblesAnEpisodeOfTheInProcessTrioBitForBitWithItsHealth) {
  lcm::LCM lcm{"memq://"};
  ASSERT_TRUE(lcm.good());
  transport::Transport plant_t{&lcm, {}}, controller_t{&lcm, {}}, disturbance_t{&lcm, {}};
  plant_sim::PlantRole plant{&plant_t};
  plant_sim::DisturbanceRole disturbance{&disturbance_t};
  controller::ControllerRole controller{&controller_t};
  LiveMonitor dut(&lcm, MemqOptions());
  episode_client::EpisodeClientOptions co;
  co.lcm_url = "memq://";
  co.start_timeout_s = 1.0;
  episode_client::EpisodeClient client(co, &lcm);

  Plant p;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &p)));
  evaluation::LoopOptions options;
  options.loop = evaluation::LoopKind::kSampled;
  options.horizon_s = 2.0;
  options.disturbance.kind = DisturbanceKind::kSquare;
  options.disturbance.amplitude = 0.3;
  std::vector<double> y;
  std::vector<evaluation::SampledStep> trajectory;
  ASSERT_TRUE(IsOk(client.Run(p, {2.0, 1.0, 1.5}, options, options.disturbance, &y, &trajectory)));
  Drain(&dut);

  const MonitorSnapshot s = dut.Snapshot();
  ASSERT_EQ(s.episodes.size(), 1u);
  const EpisodeInfo& e = s.episodes[0];
  EXPECT_EQ(e.status, EpisodeStatus::kComplete);
  EXPECT_EQ(e.plant, "double_integrator");
  EXPECT_EQ(e.kp, 2.0);
  EXPECT_EQ(e.steps_done, e.total_steps + 1);
  ASSERT_EQ(static_cast<long>(trajectory.size()), e.total_steps);
  ASSERT_TRUE(dut.WithEpisode(e.episode_id, [&](const EpisodeTrace& t) {
    for (const evaluation::SampledStep& step : trajectory) {
      const std::size_t k = static_cast<std::size_t>(step.k);
      ASSERT_EQ(std::memcmp(&t.y[k], &step.y, sizeof(double)), 0) << "y at step " << k;
      ASSERT_EQ(std::memcmp(&t.u[k], &step.u, sizeof(double)), 0) << "u at step " << k;
      ASSERT_EQ(std::memcmp(&t.n[k], &step.n, sizeof(double)), 0) << "n at step " << k;
    }
    EXPECT_TRUE(std::isnan(t.u.back()) && std::isnan(t.n.back()));
    EXPECT_EQ(t.y.back(), y.back());
  }));
  for (Role r : {Role::kPlant, Role::kController, Role::kDisturbance, Role::kClient})
    EXPECT_FALSE(std::isnan(s.roles[static_cast<std::size_t>(r)].last_heard_s)) << RoleName(r);
  EXPECT_GT(s.roles[static_cast<std::size_t>(Role::kPlant)].pid, 0);
  EXPECT_GT(s.counters.received, 0);
  EXPECT_EQ(s.rejected, 0);
}

pidlab::lcmt_episode_config Config(int64_t id, int64_t total_steps) {
  pidlab::lcmt_episode_config c{};
  c.episode_id = id;
  c.plant_name = "oscillator";
  c.total_steps = total_steps;
  c.dt_s = 0.01;
  return c;
}

pidlab::lcmt_trajectory_chunk Chunk(int64_t id, int64_t step, int32_t count) {
  pidlab::lcmt_trajectory_chunk c{};
  c.episode_id = id;
  c.step = step;
  c.count = count;
  for (int32_t i = 0; i < count; ++i) {
    c.y.push_back(static_cast<double>(step + i));
    c.u.push_back(1.0), c.n.push_back(2.0);
  }
  return c;
}

TEST(LiveMonitor, AForgedMessageIsNotShownAndIsCountedAsUnauthenticated) {
  lcm::LCM lcm{"memq://"};
  transport::TransportOptions good, forged;
  good.auth_key = transport::AuthKey{};
  good.auth_key->bytes.fill(7);
  forged.auth_key = transport::AuthKey{};
  forged.auth_key->bytes.fill(8);  // the wrong key: its MACs do not verify
  LiveMonitorOptions o = MemqOptions();
  o.transport.auth_key = good.auth_key;
  LiveMonitor dut(&lcm, o);
  transport::Transport honest{&lcm, good}, stranger{&lcm, forged};
  auto config = Config(5, 10);
  auto fake = Config(6, 10);
  ASSERT_TRUE(honest.Publish(transport::kEpisodeConfigChannel, &config));
  ASSERT_TRUE(stranger.Publish(transport::kEpisodeConfigChannel, &fake));
  auto chunk = Chunk(5, 0, 3);
  ASSERT_TRUE(stranger.Publish(transport::kTrajectoryChannel, &chunk));
  Drain(&dut);
  const MonitorSnapshot s = dut.Snapshot();
  ASSERT_EQ(s.episodes.size(), 1u);
  EXPECT_EQ(s.episodes[0].episode_id, 5);
  EXPECT_EQ(s.episodes[0].steps_done, 0);
  EXPECT_EQ(s.counters.unauthenticated, 2);
}

TEST(LiveMonitor, ChunksOutsideTheirEpisodeAndOverlongEpisodesAreCountedAndIgnored) {
  lcm::LCM lcm{"memq://"};
  LiveMonitorOptions o = MemqOptions();
  o.max_total_steps = 100;
  LiveMonitor dut(&lcm, o);
  transport::Transport t{&lcm, {}};
  auto config = Config(1, 10), huge = Config(2, 101);
  t.Publish(transport::kEpisodeConfigChannel, &config);
  t.Publish(transport::kEpisodeConfigChannel, &huge);
  for (auto [step, count] : {std::pair<int64_t, int32_t>{-1, 2}, {5, 7}, {11, 0}, {9, 3}}) {
    auto bad = Chunk(1, step, count);
    t.Publish(transport::kTrajectoryChannel, &bad);
  }
  auto unknown = Chunk(3, 0, 2), good = Chunk(1, 4, 7);  // steps 4..10: the last one
  t.Publish(transport::kTrajectoryChannel, &unknown);
  t.Publish(transport::kTrajectoryChannel, &good);
  Drain(&dut);
  const MonitorSnapshot s = dut.Snapshot();
  ASSERT_EQ(s.episodes.size(), 1u);
  EXPECT_EQ(s.rejected, 6);  // the long episode, four chunks outside, one of an unknown episode
  EXPECT_EQ(s.episodes[0].steps_done, 7);
  EXPECT_EQ(s.episodes[0].highest_step, 10);
  dut.WithEpisode(1, [](const EpisodeTrace& e) {
    EXPECT_TRUE(std::isnan(e.y[3]));
    EXPECT_EQ(e.y[10], 10.0);
  });
}

TEST(LiveMonitor, KeepsAtMostMaxKeptStepsOverAllEpisodesDroppingTheOldest) {
  lcm::LCM lcm{"memq://"};
  LiveMonitorOptions o = MemqOptions();
  o.max_total_steps = 100;
  o.max_kept_steps = 250;
  LiveMonitor dut(&lcm, o);
  transport::Transport t{&lcm, {}};
  for (int64_t id : {21, 22, 23}) {  // 101 steps each: the third pushes the first out
    auto c = Config(id, 100);
    t.Publish(transport::kEpisodeConfigChannel, &c);
  }
  Drain(&dut);
  const MonitorSnapshot s = dut.Snapshot();
  ASSERT_EQ(s.episodes.size(), 2u);
  EXPECT_EQ(s.episodes[0].episode_id, 22);
  EXPECT_EQ(s.episodes[1].episode_id, 23);
}

TEST(LiveMonitor, KeepsAtMostMaxEpisodesDroppingTheOldest) {
  lcm::LCM lcm{"memq://"};
  LiveMonitorOptions o = MemqOptions();
  o.max_episodes = 2;
  LiveMonitor dut(&lcm, o);
  transport::Transport t{&lcm, {}};
  for (int64_t id : {11, 12, 12, 13}) {  // 12 twice: a resend is not a new episode
    auto c = Config(id, 5);
    t.Publish(transport::kEpisodeConfigChannel, &c);
  }
  Drain(&dut);
  const MonitorSnapshot s = dut.Snapshot();
  ASSERT_EQ(s.episodes.size(), 2u);
  EXPECT_EQ(s.episodes[0].episode_id, 12);
  EXPECT_EQ(s.episodes[1].episode_id, 13);
}

}  // namespace
}  // namespace pidlab::monitor
