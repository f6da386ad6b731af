// Unit tests of the launcher library (launcher/): the Supervisor on short
// shell commands, the missing-step ranges of a log, and the Launcher and its
// LogCapture end to end on real processes (pidlab-plant, pidlab-controller,
// pidlab-disturbance and lcm-logger).
//
// Every test that uses LCM first puts this process in a private network
// namespace of its own (EnterIsolatedNetworkOnce below; root is needed, and
// a test fails if it cannot: it is never skipped), so nothing it sends leaves
// the namespace. Listing the tests (gtest_discover_tests) does not enter it.

#include "pidlab/launcher/launcher.h"

#include <gtest/gtest.h>
#include <lcm/eventlog.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <pidlab/lcmt_plant_output.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/launcher/log_capture.h"
#include "pidlab/launcher/supervisor.h"
#include "pidlab/replay/log_reader.h"
#include "test_status.h"

using pidlab::episode_client::EpisodeClient;
using pidlab::episode_client::EpisodeClientOptions;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;

// Not in pidlab::launcher: the fixtures are called Launcher and LogCapture
// (test names read Launcher.StartReaches...), the library's classes are
// ln::Launcher and ln::LogCapture here.
namespace pidlab::launcher_test {
namespace {

namespace ln = pidlab::launcher;
using ln::Child;
using ln::CountSteps;
using ln::DescribeStatus;
using ln::ExitCodeOf;
using ln::LaunchOptions;
using ln::LaunchStatus;
using ln::LogCaptureOptions;
using ln::MissingSteps;
using ln::RangesText;
using ln::RepairStatus;
using ln::RepairSummary;
using ln::RunAndWait;
using ln::SelfDirectory;
using ln::Supervisor;
using Ranges = std::vector<std::pair<long, long>>;

/// A private directory for one test, removed with it.
class TempDir {
 public:
  TempDir() {
    std::string pattern = ::testing::TempDir() + "launcher_test.XXXXXX";
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string File(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Running or stopped (a zombie, or no process at all, is not alive).
bool Alive(pid_t pid) {
  if (pid <= 0) return false;
  const std::string stat = ReadFile("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t paren = stat.rfind(')');
  if (paren == std::string::npos || paren + 2 >= stat.size()) return false;
  const char state = stat[paren + 2];
  return state != 'Z' && state != 'X';
}

/// Polls until the predicate holds or timeout_s passed; returns it.
template <typename Pred>
bool Eventually(Pred pred, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!pred()) {
    if (std::chrono::steady_clock::now() > end) return pred();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

/// The children the supervisor reaps within timeout_s (at least one).
std::vector<Child> ReapSome(Supervisor* s, double timeout_s = 5.0) {
  std::vector<Child> ended;
  Eventually(
      [&] {
        ended = s->Reap();
        return !ended.empty();
      },
      timeout_s);
  return ended;
}

off_t FileSize(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? st.st_size : -1;
}

bool Contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// ---- Supervisor

TEST(Supervisor, ReapsAChildThatExitedAndDescribesItsStatus) {
  Supervisor s;
  const pid_t pid = s.Start("three", {"sh", "-c", "exit 3"});
  ASSERT_GT(pid, 0);
  const std::vector<Child> ended = ReapSome(&s);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].pid, pid);
  EXPECT_EQ(ended[0].name, "three");
  EXPECT_FALSE(ended[0].alive);
  EXPECT_EQ(ExitCodeOf(ended[0].status), 3);
  EXPECT_EQ(DescribeStatus(ended[0].status), "exited with status 3");
  ASSERT_NE(s.Find(pid), nullptr);
  EXPECT_FALSE(s.Find(pid)->alive);
  EXPECT_TRUE(s.Reap().empty());  // reported once
  EXPECT_EQ(s.Find(pid + 100000), nullptr);
}

TEST(Supervisor, DescribesAChildKilledByASignalTheShellsWay) {
  Supervisor s;
  const pid_t pid = s.Start("suicide", {"sh", "-c", "kill -KILL $$"});
  const std::vector<Child> ended = ReapSome(&s);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].pid, pid);
  EXPECT_EQ(ExitCodeOf(ended[0].status), 128 + SIGKILL);
  EXPECT_EQ(DescribeStatus(ended[0].status), std::string("killed by signal ") + strsignal(SIGKILL));
}

TEST(Supervisor, StartsAChildWithItsEnvironmentAndNiceValue) {
  Supervisor s;
  // Exits with its own nice value (field 19 of /proc/self/stat, inherited by cut).
  s.Start("nice",
          {"sh", "-c",
           "test \"$PIDLAB_TEST_VALUE\" = forty-two || exit 99; "
           "exit $(cut -d' ' -f19 /proc/self/stat)"},
          {{"PIDLAB_TEST_VALUE", "forty-two"}}, 5);
  const std::vector<Child> ended = ReapSome(&s);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ExitCodeOf(ended[0].status), 5) << DescribeStatus(ended[0].status);
  EXPECT_EQ(std::getenv("PIDLAB_TEST_VALUE"), nullptr);  // set in the child only
}

TEST(Supervisor, ReportsACommandItCannotRunAsExitStatus127) {
  Supervisor s;
  s.Start("missing", {"/nonexistent/pidlab-no-such-program"});
  const std::vector<Child> ended = ReapSome(&s);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ExitCodeOf(ended[0].status), 127);
}

TEST(Supervisor, StopChildEndsASleepWithTheSignalItSent) {
  Supervisor s;
  const pid_t pid = s.Start("sleep", {"sleep", "30"});
  ASSERT_TRUE(Alive(pid));
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(s.StopChild(pid, SIGTERM, 5.0));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  EXPECT_FALSE(Alive(pid));
  ASSERT_NE(s.Find(pid), nullptr);
  EXPECT_FALSE(s.Find(pid)->alive);
  EXPECT_EQ(ExitCodeOf(s.Find(pid)->status), 128 + SIGTERM);
  EXPECT_TRUE(s.Reap().empty());                     // StopChild reaped it
  EXPECT_TRUE(s.StopChild(pid, SIGTERM, 0.1));       // no longer running
  EXPECT_TRUE(s.StopChild(getpid(), SIGTERM, 0.1));  // not a child: nothing is sent
}

TEST(Supervisor, StopChildGivesUpOnAChildThatIgnoresTheSignal) {
  TempDir dir;
  const std::string trapped = dir.File("trapped");
  Supervisor s;
  const pid_t pid = s.Start("stubborn", {"sh", "-c", "trap '' TERM; touch " + trapped + "; sleep 30"});
  ASSERT_TRUE(Eventually([&] { return FileSize(trapped) >= 0; }, 5.0));  // the trap is set
  EXPECT_FALSE(s.StopChild(pid, SIGTERM, 0.3));
  EXPECT_TRUE(Alive(pid));
  EXPECT_TRUE(s.Find(pid)->alive);
  EXPECT_TRUE(s.StopChild(pid, SIGKILL, 2.0));
  EXPECT_FALSE(Alive(pid));
}

TEST(Supervisor, KillAllLeavesNoChildOrGrandchildAlive) {
  TempDir dir;
  const std::string grandchild_file = dir.File("grandchild.pid");
  Supervisor s;
  // A child that starts a grandchild (same process group) and waits for it,
  // one that ignores SIGTERM (so KillAll must escalate) and a plain one.
  const pid_t parent = s.Start("parent", {"sh", "-c", "sleep 30 & echo $! > " + grandchild_file + "; wait"});
  const std::string trapped = dir.File("trapped");
  const pid_t stubborn = s.Start("stubborn", {"sh", "-c", "trap '' TERM; touch " + trapped + "; sleep 30"});
  const pid_t plain = s.Start("plain", {"sleep", "30"});
  ASSERT_TRUE(Eventually([&] { return Contains(ReadFile(grandchild_file), "\n"); }, 5.0));
  const pid_t grandchild = std::atoi(ReadFile(grandchild_file).c_str());
  ASSERT_GT(grandchild, 0);
  ASSERT_TRUE(Alive(grandchild));
  ASSERT_TRUE(Eventually([&] { return FileSize(trapped) >= 0; }, 5.0));  // the trap is set
  // One process group, led by the first child, not ours.
  EXPECT_EQ(getpgid(parent), parent);
  EXPECT_EQ(getpgid(stubborn), parent);
  EXPECT_EQ(getpgid(plain), parent);
  EXPECT_EQ(getpgid(grandchild), parent);
  EXPECT_NE(getpgid(0), parent);

  s.KillAll();
  for (const pid_t pid : {parent, stubborn, plain}) {
    EXPECT_FALSE(Alive(pid)) << pid;
    EXPECT_FALSE(s.Find(pid)->alive) << pid;
  }
  // The grandchild is not ours to reap: it is killed, then reaped by init.
  EXPECT_TRUE(Eventually([&] { return !Alive(grandchild); }, 2.0));
  EXPECT_EQ(ExitCodeOf(s.Find(stubborn)->status), 128 + SIGKILL);
}

TEST(Supervisor, KillAllKillsAGrandchildStartedAfterTheFirstChildEnded) {
  TempDir dir;
  const std::string grandchild_file = dir.File("grandchild.pid");
  Supervisor s;
  s.Start("first", {"true"});  // leads the process group, then is gone
  ASSERT_EQ(ReapSome(&s).size(), 1u);
  const pid_t parent = s.Start("parent", {"sh", "-c", "sleep 30 & echo $! > " + grandchild_file + "; wait"});
  ASSERT_TRUE(Eventually([&] { return Contains(ReadFile(grandchild_file), "\n"); }, 5.0));
  const pid_t grandchild = std::atoi(ReadFile(grandchild_file).c_str());
  ASSERT_TRUE(Alive(grandchild));
  EXPECT_NE(getpgid(parent), getpgid(0));  // not in our group
  s.KillAll();
  EXPECT_FALSE(Alive(parent));
  EXPECT_TRUE(Eventually([&] { return !Alive(grandchild); }, 2.0));
  if (Alive(grandchild)) kill(grandchild, SIGKILL);
}

TEST(Supervisor, TheDestructorStopsEveryChild) {
  pid_t pid = -1;
  {
    Supervisor s;
    pid = s.Start("sleep", {"sleep", "30"});
    ASSERT_TRUE(Alive(pid));
  }
  EXPECT_FALSE(Alive(pid));
}

TEST(Supervisor, RedirectStderrAppendsTheChildsStderrToAFile) {
  TempDir dir;
  const std::string path = dir.File("children.err");
  std::ofstream(path) << "before\n";
  Supervisor s;
  s.RedirectStderr(path);
  s.Start("talker", {"sh", "-c", "echo one to stderr >&2; echo not to stderr"});
  ASSERT_EQ(ReapSome(&s).size(), 1u);
  s.Start("talker", {"sh", "-c", "echo two to stderr >&2"});
  ASSERT_EQ(ReapSome(&s).size(), 1u);
  EXPECT_EQ(ReadFile(path), "before\none to stderr\ntwo to stderr\n");
}

TEST(Supervisor, StartWithAStderrFileGivesThatChildItsOwnFile) {
  TempDir dir;
  Supervisor s;
  s.RedirectStderr(dir.File("shared.err"));
  s.Start("own", {"sh", "-c", "echo own >&2"}, {}, 0, dir.File("own.err"));
  s.Start("shared", {"sh", "-c", "echo shared >&2"});
  std::size_t ended = 0;
  ASSERT_TRUE(Eventually([&] { return (ended += s.Reap().size()) == 2; }, 5.0));
  EXPECT_EQ(ReadFile(dir.File("own.err")), "own\n");
  EXPECT_EQ(ReadFile(dir.File("shared.err")), "shared\n");
}

TEST(Supervisor, ReportsAStoppedChildOnceAndKeepsItAlive) {
  Supervisor s;
  const pid_t pid = s.Start("sleeper", {"sleep", "30"});
  ASSERT_EQ(kill(pid, SIGSTOP), 0);
  std::vector<Child> stopped;
  ASSERT_TRUE(Eventually(
      [&] {
        EXPECT_TRUE(s.Reap().empty());
        stopped = s.TakeStopped();
        return !stopped.empty();
      },
      5.0));
  ASSERT_EQ(stopped.size(), 1u);
  EXPECT_EQ(stopped[0].pid, pid);
  EXPECT_EQ(DescribeStatus(stopped[0].status), std::string("stopped by signal ") + strsignal(SIGSTOP));
  EXPECT_TRUE(s.Find(pid)->alive);
  EXPECT_TRUE(s.TakeStopped().empty());  // said once
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  const std::vector<Child> ended = ReapSome(&s);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ExitCodeOf(ended[0].status), 128 + SIGKILL);
}

TEST(LastWords, IsTheCauseAfterTheLastColonOfTheLastNonEmptyLine) {
  TempDir dir;
  const std::string file = dir.File("logger.err");
  std::ofstream(file) << "lcm_eventlog_write_event: No space left on device\n"
                      << "lcm_eventlog_write_event: Input/output error\n\n";
  EXPECT_EQ(ln::LastWords(file), "Input/output error");
  std::ofstream(file) << "killed\n";
  EXPECT_EQ(ln::LastWords(file), "killed");
  std::ofstream(file) << "";
  EXPECT_EQ(ln::LastWords(file), "");
  EXPECT_EQ(ln::LastWords(dir.File("missing")), "");
}

TEST(FreeBytesBeside, IsKnownForAWritableDirectoryAndUnknownForAMissingOne) {
  TempDir dir;
  EXPECT_GT(ln::FreeBytesBeside(dir.File("run.lcmlog")), 0);
  EXPECT_EQ(ln::FreeBytesBeside(dir.File("no/such/dir/run.lcmlog")), -1);
}

TEST(RunAndWait, SucceedsOnExitZeroAndQuotesTheCommandOtherwise) {
  std::string error = "untouched";
  EXPECT_TRUE(IsOk(RunAndWait({"sh", "-c", "exit 0"})));
  EXPECT_EQ(error, "untouched");
  EXPECT_FALSE(OkInto(RunAndWait({"sh", "-c", "exit 4"}), &error));
  EXPECT_EQ(error, "'sh -c exit 4' exited with status 4");
  EXPECT_FALSE(OkInto(RunAndWait({"/nonexistent/pidlab-no-such-program", "--flag"}), &error));
  EXPECT_EQ(error, "'/nonexistent/pidlab-no-such-program --flag' exited with status 127");
  EXPECT_FALSE(OkInto(RunAndWait({"sh", "-c", "kill -TERM $$"}), nullptr));  // no error wanted
}

// ---- Missing steps of a logged episode

TEST(MissingSteps, MergesTheThreeStreamsIntoSortedDisjointRanges) {
  replay::Episode e;
  e.outputs.missing = {{20, 20}, {5, 9}};
  e.commands.missing = {{8, 12}, {40, 41}};
  e.disturbances.missing = {{21, 22}, {10, 10}};
  const Ranges merged = MissingSteps(e);
  EXPECT_EQ(merged, (Ranges{{5, 12}, {20, 22}, {40, 41}}));  // 20 and 21-22 touch: one range
  EXPECT_EQ(CountSteps(merged), 8 + 3 + 2);
  EXPECT_EQ(RangesText(merged), "5-12,20-22,40-41");
}

TEST(MissingSteps, IsEmptyForACompleteEpisodeAndKeepsSingleSteps) {
  replay::Episode e;
  EXPECT_TRUE(MissingSteps(e).empty());
  EXPECT_EQ(CountSteps({}), 0);
  EXPECT_EQ(RangesText({}), "");
  e.commands.missing = {{0, 0}};
  e.disturbances.missing = {{0, 0}, {7, 7}};
  EXPECT_EQ(MissingSteps(e), (Ranges{{0, 0}, {7, 7}}));
  EXPECT_EQ(RangesText(MissingSteps(e)), "0,7");
  EXPECT_EQ(CountSteps(MissingSteps(e)), 2);
}

TEST(MissingSteps, RangesTextStopsAfterMaxRangesWithACount) {
  const Ranges ranges = {{1, 1}, {3, 5}, {9, 9}, {11, 20}};
  EXPECT_EQ(RangesText(ranges, 2), "1,3-5,... (4 ranges)");
  EXPECT_EQ(RangesText(ranges, 4), "1,3-5,9,11-20");
  EXPECT_EQ(CountSteps(ranges), 1 + 3 + 1 + 10);
}

// ---- RebuildLaneOutputs and MergeEventLogs (files only, no processes)

/// A complete episode of `steps` steps, dt 1 ms, y_k = 0.5 + k.
replay::LogContents OneCompleteEpisode(int64_t id, long steps) {
  replay::LogContents log;
  replay::Episode e;
  e.episode_id = id;
  e.has_config = true;
  e.total_steps = steps;
  e.spec.dt_s = 1e-3;
  for (long k = 0; k <= steps; ++k) e.y.push_back(0.5 + static_cast<double>(k));
  log.episodes.push_back(e);
  return log;
}

/// Writes (timestamp, channel, payload) events as lcm-logger would.
void WriteLog(const std::string& path,
              const std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>>& events) {
  lcm_eventlog_t* l = lcm_eventlog_create(path.c_str(), "w");
  ASSERT_NE(l, nullptr);
  for (const auto& [ts, channel, data] : events) {
    lcm_eventlog_event_t ev{};
    ev.timestamp = ts;
    std::string c = channel;
    std::vector<uint8_t> d = data;
    ev.channellen = static_cast<int32_t>(c.size());
    ev.channel = c.data();
    ev.datalen = static_cast<int32_t>(d.size());
    ev.data = d.data();
    ASSERT_EQ(lcm_eventlog_write_event(l, &ev), 0);
  }
  lcm_eventlog_destroy(l);
}

std::vector<uint8_t> Output(int64_t id, int64_t step, double y) {
  pidlab::lcmt_plant_output m{};
  m.episode_id = id;
  m.step = step;
  m.y = y;
  std::vector<uint8_t> data(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

pidlab::lcmt_plant_output Decoded(const std::vector<uint8_t>& data) {
  pidlab::lcmt_plant_output m{};
  EXPECT_EQ(m.decode(data.data(), 0, static_cast<int>(data.size())), static_cast<int>(data.size()));
  return m;
}

/// (timestamp, channel, step or -1) of every event of a log file.
std::vector<std::tuple<int64_t, std::string, int64_t>> ReadEvents(const std::string& path) {
  std::vector<std::tuple<int64_t, std::string, int64_t>> out;
  lcm_eventlog_t* l = lcm_eventlog_create(path.c_str(), "r");
  if (!l) return out;
  while (lcm_eventlog_event_t* ev = lcm_eventlog_read_next_event(l)) {
    pidlab::lcmt_plant_output m{};
    const bool output = m.decode(ev->data, 0, static_cast<int>(ev->datalen)) == ev->datalen;
    out.emplace_back(ev->timestamp, ev->channel, output ? m.step : -1);
    lcm_eventlog_free_event(ev);
  }
  lcm_eventlog_destroy(l);
  return out;
}

TEST(RebuildLaneOutputs, FillsAGapBetweenItsLoggedNeighboursWithTheEpisodesY) {
  TempDir dir;
  const std::string lane = dir.File("run.lcmlog.lane1");
  // Steps 0-2 and 5-10 logged 100 us apart; 3 and 4 lost.
  std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>> events;
  for (int64_t k : {0, 1, 2, 5, 6, 7, 8, 9, 10})
    events.emplace_back(1000 + 100 * k, "PIDLAB_PLANT_OUTPUT", Output(7, k, 0.5 + k));
  WriteLog(lane, events);
  const auto rebuilt = ln::RebuildLaneOutputs(OneCompleteEpisode(7, 10), lane, "PIDLAB_");
  ASSERT_EQ(rebuilt.size(), 2u);
  EXPECT_EQ(rebuilt[0].first, 1300);  // evenly between step 2 (1200) and step 5 (1500)
  EXPECT_EQ(rebuilt[1].first, 1400);
  const auto m3 = Decoded(rebuilt[0].second), m4 = Decoded(rebuilt[1].second);
  EXPECT_EQ(m3.episode_id, 7);
  EXPECT_EQ(m3.step, 3);
  EXPECT_EQ(m3.y, 3.5);
  EXPECT_EQ(m3.t_s, 3e-3);
  EXPECT_EQ(m3.utime, 1300);
  EXPECT_EQ(m4.step, 4);
  EXPECT_EQ(m4.y, 4.5);
}

TEST(RebuildLaneOutputs, PacesALostTailAndHeadOneDtApartAndNeverOutOfOrder) {
  TempDir dir;
  const std::string lane = dir.File("lane");
  // Only steps 2 and 3 logged, 1 us apart: 0-1 (head) and 4-5 (tail) lost;
  // y_6 = y_N, which no controller answers, is not rebuilt.
  WriteLog(lane, {{50000, "PIDLAB_PLANT_OUTPUT", Output(9, 2, 2.5)},
                  {50001, "PIDLAB_PLANT_OUTPUT", Output(9, 3, 3.5)}});
  const auto rebuilt = ln::RebuildLaneOutputs(OneCompleteEpisode(9, 6), lane, "PIDLAB_");
  ASSERT_EQ(rebuilt.size(), 4u);
  std::vector<int64_t> steps, times;
  for (const auto& r : rebuilt) {
    steps.push_back(Decoded(r.second).step);
    times.push_back(r.first);
  }
  EXPECT_EQ(steps, (std::vector<int64_t>{0, 1, 4, 5}));
  EXPECT_EQ(times, (std::vector<int64_t>{48000, 49000, 51001, 52001}));  // dt = 1 ms
}

TEST(RebuildLaneOutputs, LeavesAnEpisodeTheLaneNeverHeardAndAnIncompleteOneAlone) {
  TempDir dir;
  const std::string lane = dir.File("lane");
  WriteLog(lane,
           {{10, "PIDLAB_PLANT_OUTPUT", Output(1, 0, 0.5)}, {20, "OTHER_PLANT_OUTPUT", Output(2, 0, 0.5)}});
  replay::LogContents log = OneCompleteEpisode(2, 3);  // its outputs are on another prefix: unheard
  EXPECT_TRUE(ln::RebuildLaneOutputs(log, lane, "PIDLAB_").empty());
  log = OneCompleteEpisode(1, 3);
  log.episodes[0].commands.missing = {{1, 1}};  // not complete: its y cannot be trusted to be all there
  EXPECT_TRUE(ln::RebuildLaneOutputs(log, lane, "PIDLAB_").empty());
  EXPECT_TRUE(ln::RebuildLaneOutputs(OneCompleteEpisode(1, 3), dir.File("absent"), "PIDLAB_").empty());
}

TEST(MergeEventLogs, InterleavesTheInputsAndTheRebuiltEventsByTimestamp) {
  TempDir dir;
  WriteLog(
      dir.File("base"),
      {{10, "PIDLAB_EPISODE_CONFIG", {1, 2}}, {40, "PIDLAB_TRAJECTORY", {3}}, {70, "PIDLAB_SUMMARY", {4}}});
  WriteLog(dir.File("lane1"),
           {{20, "PIDLAB_PLANT_OUTPUT", Output(1, 0, 0.5)}, {40, "PIDLAB_PLANT_OUTPUT", Output(1, 2, 2.5)}});
  WriteLog(dir.File("lane2"), {{25, "PIDLAB_CONTROL", {5}}, {45, "PIDLAB_CONTROL", {6}}});
  const std::vector<ln::TimedPayload> rebuilt = {{30, Output(1, 1, 1.5)}, {60, Output(1, 3, 3.5)}};
  std::string error;
  ASSERT_TRUE(
      OkInto(ln::MergeEventLogs({dir.File("base"), dir.File("lane1"), dir.File("absent"), dir.File("lane2")},
                                rebuilt, "PIDLAB_PLANT_OUTPUT", dir.File("merged")),
             &error))
      << error;
  using E = std::tuple<int64_t, std::string, int64_t>;
  const auto events = ReadEvents(dir.File("merged"));
  const std::vector<E> want = {
      {10, "PIDLAB_EPISODE_CONFIG", -1}, {20, "PIDLAB_PLANT_OUTPUT", 0}, {25, "PIDLAB_CONTROL", -1},
      {30, "PIDLAB_PLANT_OUTPUT", 1},    {40, "PIDLAB_TRAJECTORY", -1},  {40, "PIDLAB_PLANT_OUTPUT", 2},
      {45, "PIDLAB_CONTROL", -1},        {60, "PIDLAB_PLANT_OUTPUT", 3}, {70, "PIDLAB_SUMMARY", -1}};
  EXPECT_EQ(events, want);  // on a tie (40) the base log's event first
}

TEST(MergeEventLogs, FailsNamingAnUnreadableBaseLogAndWritesNothing) {
  TempDir dir;
  std::string error;
  EXPECT_FALSE(OkInto(ln::MergeEventLogs({dir.File("absent")}, {}, "PIDLAB_PLANT_OUTPUT", dir.File("merged")),
                      &error));
  EXPECT_NE(error.find(dir.File("absent")), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir.File("merged")));
}

// ---- LaunchOptions::roles (no network: validation only)

TEST(LaunchOptions, RolesAreANonEmptySetOfPlantControllerDisturbance) {
  LaunchOptions o;
  EXPECT_EQ(o.roles, (std::vector<std::string>{"plant", "controller", "disturbance"}));
  EXPECT_EQ(o.roles, ln::AllRoles());
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  for (const std::vector<std::string>& subset :
       std::vector<std::vector<std::string>>{{"plant"},
                                             {"controller"},
                                             {"disturbance"},
                                             {"controller", "plant"},
                                             {"disturbance", "plant", "controller"}}) {
    o.roles = subset;
    EXPECT_TRUE(o.IsValid(&error)) << error;
  }
  // Each invalid set: one line naming the value.
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{}, "--roles names no role"},
      {{"plant", "foo"}, "--roles: 'foo' is not a role (plant, controller, disturbance)"},
      {{"Plant"}, "--roles: 'Plant' is not a role"},
      {{""}, "--roles: '' is not a role"},
      {{"plant", "logger"}, "'logger' is not a role"},
      {{"plant", "controller", "plant"}, "--roles: 'plant' is named twice"},
      {{"disturbance", "disturbance"}, "'disturbance' is named twice"},
  };
  for (const auto& [roles, message] : bad) {
    o.roles = roles;
    error.clear();
    EXPECT_FALSE(o.IsValid(&error)) << message;
    EXPECT_TRUE(Contains(error, message)) << error;
    EXPECT_FALSE(Contains(error, "\n")) << error;
  }
  o.roles = {std::string(1000, 'x')};  // a long value is cut
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_LT(error.size(), 200u) << error;
}

// ---- The launcher and its log capture on real processes

/// Enters a private network namespace once per process; every test that
/// uses LCM calls it first (ASSERT_NO_FATAL_FAILURE), so none sends outside.
void EnterIsolatedNetworkOnce() {
  static std::string error;
  static const bool entered = OkInto(ln::EnterIsolatedNetwork(), &error);
  ASSERT_TRUE(entered) << "launcher_test needs a private network namespace (root): " << error;
}

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
const char* const kRoles[] = {"plant", "controller", "disturbance"};

/// SIGALRM sets it: how a serving launch is ended (a signal handler).
volatile std::sig_atomic_t g_stop = 0;
void OnAlarm(int) { g_stop = SIGINT; }
void StopAfter(double seconds) {
  g_stop = 0;
  struct sigaction sa {};
  sa.sa_handler = OnAlarm;
  sigaction(SIGALRM, &sa, nullptr);
  itimerval t{};
  t.it_value.tv_sec = static_cast<time_t>(seconds);
  t.it_value.tv_usec = static_cast<suseconds_t>((seconds - static_cast<double>(t.it_value.tv_sec)) * 1e6);
  setitimer(ITIMER_REAL, &t, nullptr);
}

class Launcher : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_NO_FATAL_FAILURE(EnterIsolatedNetworkOnce()); }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "notes:\n";
      for (const std::string& n : notes_) std::cerr << "  " << n << "\n";
      std::cerr << "stderr of the processes:\n" << ReadFile(dir_.File("trio.err"));
    }
  }

  /// Options of a trio on its own channel prefix, stderr in a file.
  LaunchOptions Options() const {
    LaunchOptions o;
    o.lcm_url = kUrl;
    // Short (LCM channel names have at most 63 characters) and new for every
    // trio this process starts.
    static int trios = 0;
    o.channel_prefix = "LT" + std::to_string(++trios) + "_";
    o.bin_dir = SelfDirectory();  // every executable lands in bin/
    o.stderr_path = dir_.File("trio.err");
    return o;
  }
  ln::Launcher::NoteFn Notes() {
    return [this](const std::string& line) { notes_.push_back(line); };
  }
  bool NoteContains(const std::string& text) const {
    for (const std::string& n : notes_)
      if (Contains(n, text)) return true;
    return false;
  }
  /// One episode of the tuner's client over the running trio.
  bool RunEpisode(const ln::Launcher& launcher, const std::string& prefix, double horizon_s,
                  std::vector<double>* y, std::string* error) {
    EpisodeClientOptions co;
    co.lcm_url = launcher.lcm_url();
    co.transport.channel_prefix = prefix;
    co.max_attempts = 1;
    EpisodeClient client(co);
    Plant plant;
    if (!OkInto(MakePlant("double_integrator", StepperMotorParameters{}, &plant), error)) return false;
    LoopOptions options;
    options.loop = LoopKind::kSampled;
    options.dt_s = 1e-3;
    options.horizon_s = horizon_s;
    options.disturbance.kind = DisturbanceKind::kSquare;
    options.disturbance.amplitude = 0.3;
    const Status ran = client.Run(plant, PidGains{2.0, 1.0, 1.5}, options, options.disturbance, y, nullptr);
    if (error) *error = ran.message();
    return ran.ok();
  }
  /// The episodes of `prefix` in the log, which must be readable.
  std::vector<replay::Episode> ReadEpisodes(const std::string& path, const std::string& prefix) {
    replay::ReadOptions ro;
    ro.channel_prefix = prefix;
    replay::LogContents log;
    std::string error;
    EXPECT_TRUE(IsOk(replay::ReadLog(path, ro, &log)));
    return log.episodes;
  }

  TempDir dir_;
  std::vector<std::string> notes_;
};

/// The same, for the tests of the launcher's log capture.
class LogCapture : public Launcher {};

TEST_F(Launcher, StartReachesReadyWithEveryRoleAlive) {
  ln::Launcher l(Options(), Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  for (const char* role : kRoles) {
    EXPECT_GT(l.pid_of(role), 0) << role;
    EXPECT_TRUE(Alive(l.pid_of(role))) << role;
  }
  EXPECT_EQ(l.pid_of("nonsense"), -1);
  EXPECT_EQ(l.lcm_url(), kUrl);
  const pid_t controller = l.pid_of("controller");
  l.Stop();
  for (const char* role : kRoles) EXPECT_FALSE(Alive(l.pid_of(role))) << role;
  EXPECT_FALSE(Alive(controller));
}

/// The names (/proc/PID/comm, at most 15 characters) of this process's
/// living children.
std::multiset<std::string> ChildNames() {
  std::multiset<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = ReadFile(entry.path().string() + "/stat");
    const std::size_t paren = stat.rfind(')');
    if (paren == std::string::npos) continue;
    char state = 0;
    int ppid = 0;
    if (std::sscanf(stat.c_str() + paren + 1, " %c %d", &state, &ppid) != 2) continue;
    if (ppid != getpid() || state == 'Z' || state == 'X') continue;
    std::string comm = ReadFile(entry.path().string() + "/comm");
    if (!comm.empty() && comm.back() == '\n') comm.pop_back();
    names.insert(comm);
  }
  return names;
}

TEST_F(Launcher, StartsOnlyTheRolesNamedAndExportsOnlyTheirPids) {
  LaunchOptions o = Options();
  o.roles = {"controller", "plant"};  // any order
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  EXPECT_TRUE(Alive(l.pid_of("plant")));
  EXPECT_TRUE(Alive(l.pid_of("controller")));
  EXPECT_EQ(l.pid_of("disturbance"), -1);
  // Exactly those two processes (comm is cut at 15 characters).
  EXPECT_EQ(ChildNames(), (std::multiset<std::string>{"pidlab-plant", "pidlab-controll"}));
  std::map<std::string, std::string> env = l.CommandEnvironment();
  EXPECT_EQ(env["PIDLAB_PLANT_PID"], std::to_string(l.pid_of("plant")));
  EXPECT_EQ(env["PIDLAB_CONTROLLER_PID"], std::to_string(l.pid_of("controller")));
  EXPECT_EQ(env.count("PIDLAB_DISTURBANCE_PID"), 0u);
  EXPECT_EQ(env["PIDLAB_LCM_URL"], kUrl);
  EXPECT_EQ(
      l.Run({"sh", "-c", "test -z \"${PIDLAB_DISTURBANCE_PID+set}\" && test \"$PIDLAB_PLANT_PID\" -gt 0"},
            nullptr),
      0);
  l.Stop();
  EXPECT_FALSE(Alive(l.pid_of("plant")));
  EXPECT_FALSE(Alive(l.pid_of("controller")));
  EXPECT_TRUE(ChildNames().empty());
}

TEST_F(Launcher, TwoLaunchersWithDisjointRolesMakeOneTrioThatMatchesAWholeOne) {
  // The plant and the controller from one launcher, the disturbance from
  // another (as on two hosts), on one prefix; a whole trio on another.
  LaunchOptions split = Options();
  split.roles = {"plant", "controller"};
  LaunchOptions other = split;
  other.roles = {"disturbance"};
  const LaunchOptions whole = Options();
  ln::Launcher first(split, Notes());
  ln::Launcher second(other, Notes());
  ln::Launcher third(whole, Notes());
  std::string error;
  ASSERT_EQ(first.Start(nullptr, &error), LaunchStatus::kReady) << error;
  ASSERT_EQ(second.Start(nullptr, &error), LaunchStatus::kReady) << error;
  ASSERT_EQ(third.Start(nullptr, &error), LaunchStatus::kReady) << error;
  EXPECT_EQ(second.pid_of("plant"), -1);
  EXPECT_GT(second.pid_of("disturbance"), 0);
  std::vector<double> y_split, y_whole;
  ASSERT_TRUE(RunEpisode(first, split.channel_prefix, 1.0, &y_split, &error)) << error;
  ASSERT_TRUE(RunEpisode(third, whole.channel_prefix, 1.0, &y_whole, &error)) << error;
  EXPECT_EQ(y_split.size(), 1001u);  // y_0 to y_1000
  EXPECT_EQ(y_split, y_whole);       // bit for bit
}

TEST_F(Launcher, ARoleThatNeverAnswersIsNamedWhenNotReady) {
  // Only the controller, from a directory whose pidlab-controller never
  // answers a PING: the error names it and nothing else.
  TempDir bin;
  const std::string fake = bin.File("pidlab-controller");
  std::ofstream(fake) << "#!/bin/sh\nexec sleep 30\n";
  ASSERT_EQ(chmod(fake.c_str(), 0755), 0);
  LaunchOptions o = Options();
  o.roles = {"controller"};
  o.bin_dir = bin.File("");
  o.ready_timeout_s = 0.5;
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kNotReady) << error;
  EXPECT_TRUE(Contains(error, "not ready within 0.5 s: pidlab-controller (")) << error;
  EXPECT_FALSE(Contains(error, "pidlab-plant")) << error;
  EXPECT_FALSE(Contains(error, "pidlab-disturbance")) << error;
}

TEST_F(Launcher, AnLcmThatCannotStartIsAStartStatusNotAnException) {
  LaunchOptions o = Options();
  o.lcm_url = "udpm://239.255.76.67:99999";  // no such port: LCM does not start
  std::unique_ptr<ln::Launcher> l;
  EXPECT_NO_THROW(l = std::make_unique<ln::Launcher>(o, Notes()));
  std::string error;
  EXPECT_EQ(l->Start(nullptr, &error), LaunchStatus::kLcmFailed);
  EXPECT_TRUE(Contains(error, "cannot start LCM on 'udpm://239.255.76.67:99999")) << error;
}

TEST_F(Launcher, CommandEnvironmentNamesTheUrlPrefixPidsAndPath) {
  const LaunchOptions o = Options();
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  std::map<std::string, std::string> env = l.CommandEnvironment();
  EXPECT_EQ(env["PIDLAB_LCM_URL"], kUrl);
  EXPECT_EQ(env["PIDLAB_CHANNEL_PREFIX"], o.channel_prefix);
  EXPECT_EQ(env["PIDLAB_PLANT_PID"], std::to_string(l.pid_of("plant")));
  EXPECT_EQ(env["PIDLAB_CONTROLLER_PID"], std::to_string(l.pid_of("controller")));
  EXPECT_EQ(env["PIDLAB_DISTURBANCE_PID"], std::to_string(l.pid_of("disturbance")));
  EXPECT_EQ(env["PATH"].rfind(SelfDirectory() + ":", 0), 0u) << env["PATH"];
  EXPECT_EQ(env.count("PIDLAB_LOGGER_PID"), 0u);     // no log asked for
  EXPECT_EQ(env.count("PIDLAB_AUTH_KEY_FILE"), 0u);  // no key
}

TEST_F(Launcher, RunReturnsTheCommandsExitCodeAndGivesItTheEnvironment) {
  ln::Launcher l(Options(), Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  EXPECT_EQ(l.Run({"sh", "-c",
                   "test -n \"$PIDLAB_LCM_URL\" || exit 9; "
                   "test \"$PIDLAB_PLANT_PID\" -gt 0 || exit 8; "
                   "command -v pidlab-controller >/dev/null || exit 6; exit 7"},
                  nullptr),
            7);
  for (const char* role : kRoles) EXPECT_TRUE(Alive(l.pid_of(role))) << role;  // the trio outlives COMMAND
  EXPECT_EQ(l.Run({"sh", "-c", "kill -TERM $$"}, nullptr), 128 + SIGTERM);
  EXPECT_TRUE(l.FinishLog(false));  // no log: nothing to finish
}

TEST_F(Launcher, RunForwardsStopToTheCommandAsSigint) {
  ln::Launcher l(Options(), Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  StopAfter(0.3);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(l.Run({"sleep", "30"}, &g_stop), 128 + SIGINT);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

TEST_F(Launcher, ServingReturnsOneWhenARoleIsKilled) {
  ln::Launcher l(Options(), Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  const pid_t controller = l.pid_of("controller");
  ASSERT_EQ(kill(controller, SIGKILL), 0);
  StopAfter(10.0);  // a bound, in case the death went unnoticed
  EXPECT_EQ(l.Run({}, &g_stop), 1);
  StopAfter(0.0);  // disarm
  EXPECT_TRUE(NoteContains("pidlab-controller (pid " + std::to_string(controller) + ") killed by signal"));
}

TEST_F(Launcher, ATrioSetReapsAndNotesADeathInItsSecondTrioAtOnce) {
  LaunchOptions o = Options();
  ln::TrioSet trios(o, 2, Notes());
  std::string error;
  ASSERT_EQ(trios.Start(nullptr, &error), LaunchStatus::kReady) << error;
  const std::map<std::string, std::string> env = trios.CommandEnvironment();
  const pid_t plant = std::atoi(env.at("PIDLAB_TRIO2_PLANT_PID").c_str());
  ASSERT_GT(plant, 0);
  // COMMAND kills trio 2's plant, then waits (1 s at most) until the launcher
  // reaped it: a zombie keeps its /proc entry.
  const std::string command =
      "kill -9 $PIDLAB_TRIO2_PLANT_PID; i=0; while [ -e /proc/$PIDLAB_TRIO2_PLANT_PID ]; do "
      "i=$((i + 1)); [ $i -gt 100 ] && exit 3; sleep 0.01; done; exit 0";
  StopAfter(10.0);  // a bound, in case the death went unnoticed
  EXPECT_EQ(trios.Run({"sh", "-c", command}, &g_stop), 0);
  StopAfter(0.0);  // disarm
  EXPECT_TRUE(NoteContains("trio 2: pidlab-plant (pid " + std::to_string(plant) + ") killed by signal"));
  EXPECT_TRUE(trios.failure().empty()) << trios.failure();
  trios.Stop();
}

TEST_F(LogCapture, ALoggerThatDiesStopsTheRunNamingItsFileAndKeepsTheLaneFiles) {
  LaunchOptions o = Options();
  o.log_file = dir_.File("run.lcmlog");
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  const std::string logger = l.CommandEnvironment().at("PIDLAB_LOGGER_PID");
  const auto t0 = std::chrono::steady_clock::now();
  StopAfter(10.0);  // a bound, in case the death went unnoticed
  // COMMAND kills the logger and would then run for 30 s.
  EXPECT_EQ(l.Run({"sh", "-c", "kill -9 $PIDLAB_LOGGER_PID; exec sleep 30"}, &g_stop), 1);
  StopAfter(0.0);  // disarm
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  EXPECT_TRUE(Contains(l.failure(), "lcm-logger writing " + o.log_file + " (pid " + logger +
                                        ") killed by signal Killed; run stopped; kept " + o.log_file +
                                        " and its .lane1, .lane2"))
      << l.failure();
  EXPECT_FALSE(l.FinishLog(false));
  l.Stop();
  // No episode ran: Stop() read the log and says that none misses a step,
  // between the cause and the files kept.
  EXPECT_TRUE(Contains(l.failure(), "run stopped; no episode in " + o.log_file + " misses a step; kept " +
                                        o.log_file + " and its .lane1, .lane2"))
      << l.failure();
  EXPECT_GE(FileSize(o.log_file + ".lane1"), 0);
  EXPECT_GE(FileSize(o.log_file + ".lane2"), 0);
}

TEST_F(Launcher, ServingReturnsZeroWhenStopIsSet) {
  ln::Launcher l(Options(), Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  StopAfter(0.5);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(l.Run({}, &g_stop), 0);
  EXPECT_GE(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.4);
  for (const char* role : kRoles) EXPECT_TRUE(Alive(l.pid_of(role))) << role;  // Stop() ends them
  EXPECT_TRUE(notes_.empty());
}

TEST_F(Launcher, ABadBinDirFailsNamingTheProcess) {
  LaunchOptions o = Options();
  o.bin_dir = "/nonexistent/pidlab-bin";
  o.ready_timeout_s = 2.0;
  ln::Launcher l(o, Notes());
  std::string error;
  const LaunchStatus status = l.Start(nullptr, &error);
  EXPECT_TRUE(status == LaunchStatus::kChildDied || status == LaunchStatus::kNotReady)
      << static_cast<int>(status);
  EXPECT_TRUE(Contains(error, "pidlab-plant") || Contains(error, "pidlab-controller") ||
              Contains(error, "pidlab-disturbance"))
      << error;
  if (status == LaunchStatus::kChildDied) {
    EXPECT_TRUE(Contains(error, "exited with status 127 before it was ready")) << error;
  }
  EXPECT_TRUE(Contains(ReadFile(dir_.File("trio.err")), "cannot run /nonexistent/pidlab-bin/pidlab-"));
  for (const char* role : kRoles) EXPECT_FALSE(Alive(l.pid_of(role))) << role;
}

TEST_F(Launcher, InvalidOptionsThrowNamingTheValue) {
  auto what = [this](const LaunchOptions& o) -> std::string {
    try {
      ln::Launcher l(o, Notes());
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  LaunchOptions o = Options();
  o.drop_rate = 1.5;
  EXPECT_TRUE(Contains(what(o), "--drop-rate 1.5")) << what(o);
  o = Options();
  o.ready_timeout_s = -2;
  EXPECT_TRUE(Contains(what(o), "--ready-timeout -2")) << what(o);
  o = Options();
  o.channel_prefix = "TWO WORDS_";
  EXPECT_TRUE(Contains(what(o), "'TWO WORDS_'")) << what(o);
  o = Options();
  o.auth_key_file = dir_.File("no-such-key");
  EXPECT_TRUE(Contains(what(o), "no-such-key")) << what(o);
  o = Options();
  o.roles = {"plant", "foo"};
  EXPECT_TRUE(Contains(what(o), "--roles: 'foo'")) << what(o);
  o.roles = {};
  EXPECT_TRUE(Contains(what(o), "--roles")) << what(o);
  std::string error;
  EXPECT_TRUE(Options().IsValid(&error)) << error;
}

TEST_F(LogCapture, RecordsAnEpisodeThatReplaysComplete) {
  LaunchOptions o = Options();
  o.log_file = dir_.File("run.lcmlog");
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  const std::map<std::string, std::string> env = l.CommandEnvironment();
  ASSERT_EQ(env.count("PIDLAB_LOGGER_PID"), 1u);
  const pid_t logger = std::atoi(env.at("PIDLAB_LOGGER_PID").c_str());
  EXPECT_TRUE(Alive(logger));
  std::vector<double> y;
  ASSERT_TRUE(RunEpisode(l, o.channel_prefix, 1.0, &y, &error)) << error;
  EXPECT_TRUE(l.FinishLog(false));
  l.Stop();
  EXPECT_FALSE(Alive(logger));
  EXPECT_FALSE(NoteContains("repaired"));  // nothing was lost

  const std::vector<replay::Episode> episodes = ReadEpisodes(o.log_file, o.channel_prefix);
  ASSERT_EQ(episodes.size(), 1u);
  const replay::Episode& e = episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(e.total_steps, 1000);
  EXPECT_EQ(e.y, y);  // the log holds what the client saw
}

TEST_F(LogCapture, RepairsALogWhoseLoggerWasStoppedMidEpisode) {
  LaunchOptions o = Options();
  o.log_file = dir_.File("run.lcmlog");
  ln::Launcher l(o, Notes());
  std::string error;
  ASSERT_EQ(l.Start(nullptr, &error), LaunchStatus::kReady) << error;
  const pid_t logger = std::atoi(l.CommandEnvironment().at("PIDLAB_LOGGER_PID").c_str());
  ASSERT_GT(logger, 0);
  // 20000 steps (about 10k steps/s). Once the episode is under way (the log
  // grew: its configuration is on disk) the logger is stopped for 1 s, and
  // on a machine so slow that the episode outlasts that, until it ended: its
  // socket (4 MB) overflows and it loses messages.
  const off_t start_size = FileSize(o.log_file);
  std::atomic<bool> client_done{false};
  std::thread stopper([&] {
    if (!Eventually([&] { return FileSize(o.log_file) > start_size + 200000 || client_done; }, 10.0) ||
        client_done)
      return;
    kill(logger, SIGSTOP);
    const auto stopped = std::chrono::steady_clock::now();
    Eventually(
        [&] {
          const double held =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped).count();
          return held >= 1.0 && client_done;
        },
        20.0);
    kill(logger, SIGCONT);
  });
  std::vector<double> y;
  const bool ran = RunEpisode(l, o.channel_prefix, 20.0, &y, &error);
  client_done = true;
  stopper.join();
  ASSERT_TRUE(ran) << error;
  EXPECT_TRUE(l.FinishLog(false));
  EXPECT_TRUE(NoteContains("lcm-logger lost messages; repaired " + o.log_file +
                           " from the plant's trajectory chunks"));
  l.Stop();

  const std::vector<replay::Episode> episodes = ReadEpisodes(o.log_file, o.channel_prefix);
  ASSERT_EQ(episodes.size(), 1u);
  const replay::Episode& e = episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_GT(e.outputs.filled_from_chunks + e.commands.filled_from_chunks + e.disturbances.filled_from_chunks,
            0);
  EXPECT_EQ(e.y, y);
}

TEST_F(LogCapture, WaitsForItsMarkerAndFindsNothingToRepairInAnEmptyLog) {
  // LogCapture alone, on a supervisor and transport of the test's own.
  const std::string log_file = dir_.File("empty.lcmlog");
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  transport::TransportOptions topt;
  topt.channel_prefix = "LT_CAPTURE_";
  transport::Transport transport(&lcm, topt);
  Supervisor supervisor;
  supervisor.RedirectStderr(dir_.File("trio.err"));
  LogCaptureOptions lo;
  lo.log_file = log_file;
  lo.channel_prefix = topt.channel_prefix;
  lo.marker_timeout_s = 2.0;
  ln::LogCapture capture(lo, &transport, &supervisor);
  const pid_t logger = capture.StartLogger(kUrl);
  ASSERT_TRUE(Alive(logger));
  EXPECT_TRUE(capture.WaitForMarker("start"));
  const RepairSummary summary = capture.Repair();
  EXPECT_EQ(summary.status, RepairStatus::kComplete);
  EXPECT_EQ(summary.rounds, 0);
  EXPECT_TRUE(summary.lines.empty());
  EXPECT_TRUE(summary.republished.empty());

  kill(logger, SIGSTOP);  // a logger that writes nothing: no marker
  EXPECT_FALSE(capture.WaitForMarker("stopped"));
  kill(logger, SIGCONT);
  EXPECT_TRUE(supervisor.StopChild(logger, SIGINT, 3.0));
  EXPECT_EQ(ExitCodeOf(supervisor.Find(logger)->status), 0)
      << DescribeStatus(supervisor.Find(logger)->status);
}

TEST_F(LogCapture, CallsAnUnreadableLogUnreadable) {
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  transport::Transport transport(&lcm, {});
  Supervisor supervisor;
  LogCaptureOptions lo;
  lo.log_file = dir_.File("never-written.lcmlog");
  ln::LogCapture capture(lo, &transport, &supervisor);
  const RepairSummary summary = capture.Repair();
  EXPECT_EQ(summary.status, RepairStatus::kUnreadable);
  ASSERT_EQ(summary.lines.size(), 1u);
  EXPECT_TRUE(Contains(summary.lines[0], "cannot read " + lo.log_file)) << summary.lines[0];
}

}  // namespace
}  // namespace pidlab::launcher_test

int main(int argc, char** argv) {
  // No network namespace here: listing the tests (gtest_discover_tests) must
  // not need root. The tests that use LCM enter it first.
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
