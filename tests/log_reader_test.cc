// Reading pidlab episodes back from LCM logs that the tests write themselves
// with lcm::LogFile: honest logs, retransmissions, cut-off and corrupt tails,
// foreign and garbage events, several prefixes, an altered command.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <random>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/replay/replay.h"
#include "pidlab/transport/episode_spec.h"
#include "test_status.h"

using pidlab::episode_client::MakeEpisodeSpec;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::RunSampledLoopInProcess;
using pidlab::evaluation::SampledStep;

namespace pidlab::replay {
namespace {

namespace fs = std::filesystem;

// A short sampled episode on the double integrator: 1 s at dt = 10 ms.
struct Reference {
  Plant plant;
  PidGains gains{2.0, 0.5, 1.5};
  LoopOptions options;
  std::vector<double> y_all;
  std::vector<SampledStep> trajectory;
  Evaluation evaluation;  // in process, the code of `pidlab evaluate`

  explicit Reference(DisturbanceKind kind = DisturbanceKind::kSquare) {
    std::string error;
    EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &plant)));
    options.loop = LoopKind::kSampled;
    options.dt_s = 0.01;
    options.pid.dt_s = 0.01;
    options.sample_time_s = 0.05;
    options.horizon_s = 1.0;
    options.disturbance.kind = kind;
    options.disturbance.amplitude = kind == DisturbanceKind::kNone ? 0.0 : 0.2;
    options.disturbance.period_s = 0.4;
    EXPECT_TRUE(
        IsOk(RunSampledLoopInProcess(plant, gains, options, options.disturbance, &y_all, &trajectory)));
    EvaluateOptions what;
    EXPECT_TRUE(IsOk(Evaluate(plant, gains, options, what, &evaluation)));
  }
  long total_steps() const { return options.TotalSteps(); }
};

template <typename Msg>
void WriteMsg(lcm::LogFile* log, const std::string& channel, const Msg& msg, int64_t* eventnum) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent ev;
  ev.eventnum = (*eventnum)++;
  ev.timestamp = 1700000000000000 + ev.eventnum;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  ASSERT_EQ(log->writeEvent(&ev), 0);
}

void WriteRaw(lcm::LogFile* log, const std::string& channel, std::vector<uint8_t> bytes, int64_t* eventnum) {
  lcm::LogEvent ev;
  ev.eventnum = (*eventnum)++;
  ev.timestamp = 1700000000000000 + ev.eventnum;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(bytes.size());
  ev.data = bytes.data();
  ASSERT_EQ(log->writeEvent(&ev), 0);
}

struct EpisodeWriter {
  const Reference& ref;
  int64_t episode_id = 42;
  std::string prefix = "PIDLAB_";
  long alter_command_step = -1;  // add one ulp to this command
  long duplicate_step = -1;      // resend this step's three messages
  long swap_step = -1;           // write step k+1 before step k
  bool with_config = true;
  // Disturbance as the trio sends it now: lcmt_disturbance_block of at most
  // 128 samples, requested ahead by the plant (false: one
  // lcmt_disturbance_sample per step, as in older logs).
  bool blocks = false;
  long lose_block = -1;  // with blocks: this block (index) is not in the log

  void WriteStep(lcm::LogFile* log, long k, int64_t* num) const {
    const int64_t utime = 1700000000000000 + k;
    pidlab::lcmt_plant_output y{};
    y.utime = utime;
    y.episode_id = episode_id;
    y.step = k;
    y.t_s = static_cast<double>(k) * ref.options.dt_s;
    y.y = ref.y_all[static_cast<std::size_t>(k)];
    WriteMsg(log, prefix + "PLANT_OUTPUT", y, num);
    if (k == ref.total_steps()) return;
    const SampledStep& s = ref.trajectory[static_cast<std::size_t>(k)];
    pidlab::lcmt_control_command u{};
    u.utime = utime;
    u.episode_id = episode_id;
    u.step = k;
    u.t_s = s.t;
    u.r = s.r;
    u.y = s.y;
    u.u = k == alter_command_step ? std::nextafter(s.u, HUGE_VAL) : s.u;
    u.status = 0;
    WriteMsg(log, prefix + "CONTROL", u, num);
    if (blocks) return;
    pidlab::lcmt_disturbance_sample n{};
    n.utime = utime;
    n.episode_id = episode_id;
    n.step = k;
    n.t_s = s.t;
    n.n = s.n;
    WriteMsg(log, prefix + "DISTURBANCE", n, num);
  }

  void Write(lcm::LogFile* log, int64_t* num) const {
    if (with_config) {
      const auto config = transport::MakeEpisodeConfig(MakeEpisodeSpec(episode_id, ref.plant, ref.gains,
                                                                       ref.options, ref.options.disturbance,
                                                                       transport::RecoveryOptions{}));
      WriteMsg(log, prefix + "EPISODE_CONFIG", config, num);
      WriteMsg(log, prefix + "EPISODE_CONFIG", config, num);  // republished until acknowledged
    }
    if (blocks) {
      const long total = ref.total_steps();
      pidlab::lcmt_disturbance_request r{};
      r.episode_id = episode_id;
      r.step = 0;
      r.samples = static_cast<int32_t>(total);
      WriteMsg(log, prefix + "DISTURBANCE_REQUEST", r, num);
      for (long first = 0, index = 0; first < total; first += 32, ++index) {
        pidlab::lcmt_disturbance_block b{};
        b.episode_id = episode_id;
        b.step = first;
        b.dt_s = ref.options.dt_s;
        b.count = static_cast<int32_t>(std::min<long>(32, total - first));
        for (long k = first; k < first + b.count; ++k)
          b.n.push_back(ref.trajectory[static_cast<std::size_t>(k)].n);
        if (index != lose_block) WriteMsg(log, prefix + "DISTURBANCE_BLOCK", b, num);
      }
    }
    for (long k = 0; k <= ref.total_steps(); ++k) {
      if (k == swap_step) {
        WriteStep(log, k + 1, num);
        WriteStep(log, k, num);
        ++k;
        continue;
      }
      WriteStep(log, k, num);
      if (k == duplicate_step) WriteStep(log, k, num);
    }
  }
};

class LogReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pidlab_log_reader_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "run.lcmlog").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  LogContents Read(const ReadOptions& options = ReadOptions{}) {
    LogContents contents;
    std::string error;
    EXPECT_TRUE(IsOk(ReadLog(path_, options, &contents)));
    return contents;
  }
  static std::string Notes(const LogContents& c) {
    std::string s;
    for (const auto& n : c.notes) s += n + "\n";
    return s;
  }

  fs::path dir_;
  std::string path_;
};

TEST_F(LogReaderTest, HonestLogGivesTheLiveIaeExactlyAndIsComplete) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter{ref}.Write(&log, &num);
  }
  const LogContents dut = Read();
  EXPECT_TRUE(dut.clean_end);
  ASSERT_EQ(dut.episodes.size(), 1u);
  const Episode& e = dut.episodes[0];
  EXPECT_EQ(e.episode_id, 42);
  EXPECT_EQ(e.prefix, "PIDLAB_");
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(e.total_steps, 100);
  Evaluation ev;
  std::string error;
  ASSERT_TRUE(IsOk(EvaluateEpisode(e, &ev)));
  EXPECT_EQ(ev.iae, ref.evaluation.iae);  // bit for bit, no tolerance
  EXPECT_EQ(ev.ise, ref.evaluation.ise);
  EXPECT_EQ(ev.iae_undisturbed, ref.evaluation.iae_undisturbed);
  ASSERT_EQ(ev.trajectory.size(), ref.trajectory.size());
  for (std::size_t k = 0; k < ev.trajectory.size(); ++k) {
    EXPECT_EQ(ev.trajectory[k].u, ref.trajectory[k].u) << "step " << k;
    EXPECT_EQ(ev.trajectory[k].n, ref.trajectory[k].n) << "step " << k;
  }
  const RedriveResult r = Redrive(e);
  EXPECT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.steps_checked, 100);
}

TEST_F(LogReaderTest, RetransmissionsAndOutOfOrderStepsAreCountedNotHidden) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.duplicate_step = 10;
    w.swap_step = 20;
    w.Write(&log, &num);
  }
  const LogContents dut = Read();
  ASSERT_EQ(dut.episodes.size(), 1u);
  const Episode& e = dut.episodes[0];
  EXPECT_TRUE(e.Complete());
  EXPECT_EQ(e.outputs.duplicates, 1);
  EXPECT_EQ(e.commands.duplicates, 1);
  EXPECT_EQ(e.outputs.out_of_order, 1);
  EXPECT_EQ(e.commands.out_of_order, 1);
  Evaluation ev;
  std::string error;
  ASSERT_TRUE(IsOk(EvaluateEpisode(e, &ev)));
  EXPECT_EQ(ev.iae, ref.evaluation.iae);
}

TEST_F(LogReaderTest, TruncatedTailIsReportedAndEverythingBeforeIsRead) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter{ref}.Write(&log, &num);
  }
  const auto size = fs::file_size(path_);
  fs::resize_file(path_, size - 7);  // cut inside the last event (the final plant output)
  const LogContents dut = Read();
  EXPECT_FALSE(dut.clean_end);
  EXPECT_NE(Notes(dut).find("cut off"), std::string::npos) << Notes(dut);
  ASSERT_EQ(dut.episodes.size(), 1u);
  const Episode& e = dut.episodes[0];
  EXPECT_FALSE(e.Complete());
  ASSERT_EQ(e.outputs.missing.size(), 1u);
  EXPECT_EQ(e.outputs.missing[0], std::make_pair(100L, 100L));
  EXPECT_TRUE(e.commands.missing.empty());
  EXPECT_NE(e.CompletenessNote().find("steps 100"), std::string::npos) << e.CompletenessNote();
  Evaluation ev;
  std::string error;
  EXPECT_FALSE(OkInto(EvaluateEpisode(e, &ev), &error));
  EXPECT_NE(error.find("incomplete"), std::string::npos) << error;
  // Every command that is there is still checked.
  const RedriveResult r = Redrive(e);
  EXPECT_TRUE(r.ok) << r.message;
}

TEST_F(LogReaderTest, GarbageForeignAndSelfTestEventsAreCountedAndSkipped) {
  const Reference ref;
  std::mt19937 rng(7);
  auto random_bytes = [&rng](std::size_t n) {
    std::vector<uint8_t> b(n);
    for (auto& x : b) x = static_cast<uint8_t>(rng());
    return b;
  };
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    WriteRaw(&log, "LCM_SELF_TEST", {'l', 'c', 'm'}, &num);
    WriteRaw(&log, "ROBOT_POSE", random_bytes(64), &num);      // a foreign channel
    WriteRaw(&log, "PIDLAB_CONTROL", random_bytes(61), &num);  // unknown fingerprint on a pidlab channel
    // Right fingerprint, payload cut short: must not decode.
    pidlab::lcmt_plant_output y{};
    std::vector<uint8_t> short_output(static_cast<std::size_t>(y.getEncodedSize()));
    y.encode(short_output.data(), 0, static_cast<int>(short_output.size()));
    short_output.resize(20);
    WriteRaw(&log, "PIDLAB_PLANT_OUTPUT", short_output, &num);
    // A configuration whose num_size claims two billion doubles.
    auto config = transport::MakeEpisodeConfig(MakeEpisodeSpec(
        99, ref.plant, ref.gains, ref.options, ref.options.disturbance, transport::RecoveryOptions{}));
    std::vector<uint8_t> hostile(static_cast<std::size_t>(config.getEncodedSize()));
    config.encode(hostile.data(), 0, static_cast<int>(hostile.size()));
    const std::size_t num_size_at = 8 + 24 + 4 + config.plant_name.size() + 1;
    hostile[num_size_at] = 0x7f;
    WriteRaw(&log, "PIDLAB_EPISODE_CONFIG", hostile, &num);
    EpisodeWriter{ref}.Write(&log, &num);
    WriteRaw(&log, "ROBOT_POSE", random_bytes(10), &num);
  }
  // Raw garbage between two events in the middle of the file.
  {
    std::ifstream in(path_, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    // Splice right before the 200th event marker.
    const unsigned char marker[4] = {0xED, 0xA1, 0xDA, 0x01};
    std::size_t at = 0;
    for (int found = 0, i = 0; i + 4 <= static_cast<int>(bytes.size()); ++i) {
      if (std::memcmp(&bytes[static_cast<std::size_t>(i)], marker, 4) == 0 && ++found == 200) {
        at = static_cast<std::size_t>(i);
        break;
      }
    }
    ASSERT_GT(at, 0u);
    std::vector<char> junk(37, '\x5a');
    bytes.insert(bytes.begin() + static_cast<long>(at), junk.begin(), junk.end());
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const LogContents dut = Read();
  EXPECT_EQ(dut.self_test, 1);
  EXPECT_EQ(dut.foreign, 2);
  EXPECT_EQ(dut.unknown_type, 1);
  EXPECT_EQ(dut.decode_failures, 2);
  const std::string notes = Notes(dut);
  EXPECT_NE(notes.find("ROBOT_POSE"), std::string::npos) << notes;
  EXPECT_NE(notes.find("PIDLAB_CONTROL (fingerprint"), std::string::npos) << notes;
  EXPECT_NE(notes.find("garbage"), std::string::npos) << notes;
  ASSERT_EQ(dut.episodes.size(), 1u) << notes;
  const Episode& e = dut.episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  Evaluation ev;
  std::string error;
  ASSERT_TRUE(IsOk(EvaluateEpisode(e, &ev)));
  EXPECT_EQ(ev.iae, ref.evaluation.iae);
}

TEST_F(LogReaderTest, EpisodesOfSeveralPrefixesAreKeptApartAndCanBeFiltered) {
  const Reference disturbed;
  const Reference clean(DisturbanceKind::kNone);
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter a{disturbed};
    a.prefix = "LAB_A_";
    EpisodeWriter b{clean};
    b.prefix = "LAB_B_";  // same episode id, another trio
    a.Write(&log, &num);
    b.Write(&log, &num);
  }
  const LogContents all = Read();
  ASSERT_EQ(all.episodes.size(), 2u);
  EXPECT_EQ(all.episodes[0].prefix, "LAB_A_");
  EXPECT_EQ(all.episodes[1].prefix, "LAB_B_");
  Evaluation ev;
  std::string error;
  ASSERT_TRUE(IsOk(EvaluateEpisode(all.episodes[1], &ev)));
  EXPECT_EQ(ev.iae, clean.evaluation.iae);
  ReadOptions only_a;
  only_a.channel_prefix = "LAB_A_";
  const LogContents a = Read(only_a);
  ASSERT_EQ(a.episodes.size(), 1u);
  EXPECT_EQ(a.episodes[0].prefix, "LAB_A_");
  EXPECT_GT(a.other_prefix, 0);
}

TEST_F(LogReaderTest, RedriveNamesTheFirstAlteredCommandWithBothValues) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.alter_command_step = 37;
    w.Write(&log, &num);
  }
  const LogContents dut = Read();
  ASSERT_EQ(dut.episodes.size(), 1u);
  const RedriveResult r = Redrive(dut.episodes[0]);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.first_mismatch, 37);
  EXPECT_EQ(r.recomputed_u, ref.trajectory[37].u);
  EXPECT_EQ(r.logged_u, std::nextafter(ref.trajectory[37].u, HUGE_VAL));
  EXPECT_NE(r.message.find("step 37"), std::string::npos) << r.message;
}

TEST_F(LogReaderTest, DataWithoutConfigurationIsListedButNotEvaluated) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.with_config = false;
    w.Write(&log, &num);
  }
  const LogContents dut = Read();
  ASSERT_EQ(dut.episodes.size(), 1u);
  EXPECT_FALSE(dut.episodes[0].has_config);
  EXPECT_EQ(dut.orphan_messages, 1);
  Evaluation ev;
  std::string error;
  EXPECT_FALSE(OkInto(EvaluateEpisode(dut.episodes[0], &ev), &error));
  EXPECT_NE(error.find("configuration"), std::string::npos) << error;
}

TEST_F(LogReaderTest, ASuppliedConfigurationCompletesAnEpisodeWhoseLogLacksIt) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.with_config = false;
    w.Write(&log, &num);
  }
  ReadOptions options;
  options.channel_prefix = "PIDLAB_";
  options.supplied_configs.push_back(transport::MakeEpisodeConfig(MakeEpisodeSpec(
      42, ref.plant, ref.gains, ref.options, ref.options.disturbance, transport::RecoveryOptions{})));
  const LogContents dut = Read(options);
  ASSERT_EQ(dut.episodes.size(), 1u);
  const Episode& e = dut.episodes[0];
  EXPECT_TRUE(e.has_config);
  EXPECT_TRUE(e.config_supplied);
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(dut.orphan_messages, 0);
  Evaluation ev;
  ASSERT_TRUE(IsOk(EvaluateEpisode(e, &ev)));
  EXPECT_EQ(ev.iae, ref.evaluation.iae);
}

TEST_F(LogReaderTest, ASuppliedConfigurationYieldsToALoggedOneAndListsAnEpisodeTheLogLacks) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter{ref}.Write(&log, &num);
  }
  auto config = transport::MakeEpisodeConfig(MakeEpisodeSpec(
      42, ref.plant, ref.gains, ref.options, ref.options.disturbance, transport::RecoveryOptions{}));
  ReadOptions options;
  options.channel_prefix = "PIDLAB_";
  config.kp += 1.0;  // not what the log holds: the log's own wins, without a note
  options.supplied_configs.push_back(config);
  config.episode_id = 43;  // nothing of it in the log
  options.supplied_configs.push_back(config);
  const LogContents dut = Read(options);
  ASSERT_EQ(dut.episodes.size(), 2u) << Notes(dut);
  EXPECT_FALSE(dut.episodes[0].config_supplied);
  EXPECT_EQ(dut.episodes[0].config.kp, ref.gains.kp);
  EXPECT_TRUE(dut.episodes[0].Complete()) << dut.episodes[0].CompletenessNote();
  EXPECT_EQ(Notes(dut).find("more than once"), std::string::npos) << Notes(dut);
  const Episode& lacking = dut.episodes[1];
  EXPECT_EQ(lacking.episode_id, 43);
  EXPECT_TRUE(lacking.config_supplied);
  ASSERT_EQ(lacking.outputs.missing.size(), 1u);
  EXPECT_EQ(lacking.outputs.missing[0], std::make_pair(0L, ref.total_steps()));
}

TEST_F(LogReaderTest, AFileThatIsNotALogIsRefused) {
  {
    std::ofstream f(path_);
    f << "this is not an LCM log\n";
  }
  LogContents contents;
  std::string error;
  EXPECT_FALSE(OkInto(ReadLog(path_, ReadOptions{}, &contents), &error));
  EXPECT_NE(error.find("not an LCM log"), std::string::npos) << error;
  EXPECT_TRUE(contents.opened);
  EXPECT_FALSE(OkInto(ReadLog((dir_ / "missing.lcmlog").string(), ReadOptions{}, &contents), &error));
  EXPECT_NE(error.find("cannot be read"), std::string::npos) << error;
  EXPECT_FALSE(contents.opened);
}

TEST_F(LogReaderTest, AnEmptyFileHoldsNoLcmEventAndIsRefused) {
  std::ofstream(path_).close();
  LogContents contents;
  std::string error;
  EXPECT_FALSE(OkInto(ReadLog(path_, ReadOptions{}, &contents), &error));
  EXPECT_TRUE(contents.opened);
  EXPECT_EQ(contents.file_bytes, 0);
  EXPECT_EQ(contents.events, 0);
  EXPECT_NE(error.find("no LCM event"), std::string::npos) << error;
  EXPECT_NE(error.find(path_), std::string::npos) << error;
}

TEST_F(LogReaderTest, ALogWhoseOnlyEventIsForeignIsStillALog) {
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    WriteRaw(&log, "SOMEONE_ELSE", {'h', 'e', 'l', 'l', 'o'}, &num);
  }
  const LogContents dut = Read();
  EXPECT_EQ(dut.events, 1);
  EXPECT_EQ(dut.foreign, 1);
  EXPECT_TRUE(dut.episodes.empty());
}

}  // namespace
}  // namespace pidlab::replay

namespace pidlab::replay {
namespace {

TEST_F(LogReaderTest, DisturbanceBlocksRebuildEveryStepAndALostBlockIsNamed) {
  const Reference ref;
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.blocks = true;
    w.Write(&log, &num);
  }
  {
    const LogContents dut = Read();
    ASSERT_EQ(dut.episodes.size(), 1u);
    const Episode& e = dut.episodes[0];
    EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
    EXPECT_EQ(e.disturbances.received, 100);
    Evaluation ev;
    std::string error;
    ASSERT_TRUE(IsOk(EvaluateEpisode(e, &ev)));
    EXPECT_EQ(ev.iae, ref.evaluation.iae);
    ASSERT_EQ(ev.trajectory.size(), ref.trajectory.size());
    for (std::size_t k = 0; k < ev.trajectory.size(); ++k)
      EXPECT_EQ(ev.trajectory[k].n, ref.trajectory[k].n) << k;
  }
  {
    lcm::LogFile log(path_, "w");
    int64_t num = 0;
    EpisodeWriter w{ref};
    w.blocks = true;
    w.lose_block = 1;  // steps 32..63
    w.Write(&log, &num);
  }
  const LogContents dut = Read();
  ASSERT_EQ(dut.episodes.size(), 1u);
  const Episode& e = dut.episodes[0];
  EXPECT_FALSE(e.Complete());
  ASSERT_EQ(e.disturbances.missing.size(), 1u);
  EXPECT_EQ(e.disturbances.missing[0], std::make_pair(32L, 63L));
}

}  // namespace
}  // namespace pidlab::replay
