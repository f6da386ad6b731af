// The relay experiment over episodes (tuner/autotune/experiment.h) on an
// in-process runner that steps the relay as the controller does: a relay
// that sits on one side of its band while y settles there is stopped after
// that episode, naming why (a reverse-acting process, or a relay too small
// for the process's gain, with the amplitude that would cross the band),
// instead of doubling its window up to --max-time; a slow process still
// moving gets its longer window (issue 60, "Guards that explain").

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <regex>
#include <string>
#include <vector>

#include "pidlab/autotune/experiment.h"
#include "test_status.h"

namespace pidlab::autotune {
namespace {

// K e^(-sL)/(Ts + 1) from rest, exact for an input held over each step.
struct Process {
  double k = 1.0, t = 1.0, l = 0.5;
  double y_start = 0.0;  ///< y at t = 0, decaying with T (a process not yet at rest)
};

RelayEpisodeRunner Runner(const Process& p, const ExperimentOptions& x) {
  return [p, x](const RelayTuneOptions& relay, double horizon_s, std::vector<RelaySample>* samples) {
    const double h = x.pid.dt_s, a = std::exp(-h / p.t);
    std::vector<double> pipe(static_cast<std::size_t>(std::lround(p.l / h)) + 1, 0.0);
    std::size_t head = 0;
    double y = p.y_start;
    RelayTuner tuner(relay, x.previous, x.pid);
    samples->clear();
    for (long i = 0; static_cast<double>(i) * h <= horizon_s; ++i) {
      const double t = static_cast<double>(i) * h;
      const double u = tuner.Step(t, 0.0, y);
      samples->push_back({t, 0.0, y, u});
      pipe[head] = u;
      head = (head + 1) % pipe.size();
      y = a * y + (1.0 - a) * p.k * pipe[head];
    }
    return Status::Ok();
  };
}

ExperimentOptions Options(double hysteresis) {
  ExperimentOptions x;
  x.relay.hold_s = 1.0;
  x.relay.amplitude = 1.0;
  x.relay.bias = 1.0 / 3.0;
  x.relay.hysteresis = hysteresis;
  x.pid.dt_s = 1e-2;
  x.first_window_s = 30.0;
  x.max_window_s = 480.0;
  return x;
}

TEST(RelayEpisodes, OnAReverseActingProcessItStopsAfterTheFirstEpisodeSayingSo) {
  const ExperimentOptions x = Options(0.0);
  ExperimentSummary s;
  ASSERT_TRUE(IsOk(RunExperiment(x, Runner({-1.0, 1.0, 0.5}, x), &s)));
  EXPECT_EQ(s.end, RelayPhase::kAborted);
  EXPECT_EQ(s.episodes, 1);
  EXPECT_NE(s.why.find("the process acts in reverse"), std::string::npos) << s.why;
  EXPECT_NE(s.why.find("y moved from 0 to 0.66667 and settled there"), std::string::npos) << s.why;
  EXPECT_EQ(s.hold_note, "") << "a hold at rest";
}

TEST(RelayEpisodes, ARelayTooSmallForItsBandIsStoppedNamingAnAmplitudeThatThenConverges) {
  ExperimentOptions x = Options(0.1);
  const Process small_gain{0.01, 1.0, 0.5};
  ExperimentSummary s;
  ASSERT_TRUE(IsOk(RunExperiment(x, Runner(small_gain, x), &s)));
  EXPECT_EQ(s.end, RelayPhase::kAborted);
  EXPECT_EQ(s.episodes, 1);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(s.why, m, std::regex("a relay amplitude of about ([0-9.e+-]+) \\(now 1\\)")))
      << s.why;
  const double needed = std::strtod(m[1].str().c_str(), nullptr);
  // y settles at -0.01 d_low = -0.0066667: crossing -0.1 takes 15 d; twice that.
  EXPECT_NEAR(needed, 30.0, 0.1) << s.why;
  x.relay.amplitude = needed;
  x.relay.bias = needed / 3.0;
  ExperimentSummary again;
  ASSERT_TRUE(IsOk(RunExperiment(x, Runner(small_gain, x), &again)));
  EXPECT_EQ(again.end, RelayPhase::kDone) << again.why;
}

TEST(RelayEpisodes, ASlowProcessStillMovingGetsALongerWindowNotAStop) {
  const ExperimentOptions x = Options(0.0);
  ExperimentSummary s;
  ASSERT_TRUE(IsOk(RunExperiment(x, Runner({1.0, 100.0, 5.0}, x), &s)));
  EXPECT_GE(s.episodes, 2);
  EXPECT_EQ(s.why.find("settled there"), std::string::npos) << s.why;
}

}  // namespace
}  // namespace pidlab::autotune

namespace pidlab::autotune {
namespace {

// A dead time of 20 s, the first window 10 s: doubling, the relay sees its
// first switch in the third episode (40 s) and its first full cycle in the
// fourth (80 s), then runs the window its period sets: 5 episodes. Sized by
// the first switch (a period is at least twice the time to it), the fourth
// episode's window is long enough to converge in: 4.
TEST(RelayEpisodes, AfterAFirstSwitchTheNextWindowIsSizedByItNotDoubled) {
  ExperimentOptions x = Options(0.0);
  x.first_window_s = 10.0;
  x.max_window_s = 4000.0;
  std::string windows;
  ExperimentSummary s;
  ASSERT_TRUE(IsOk(RunExperiment(x, Runner({1.0, 1.0, 20.0}, x), &s, [&](const std::string& line) {
    if (line.rfind("relay episode", 0) == 0) windows += line.substr(line.find("up to")) + "; ";
  })));
  EXPECT_EQ(s.end, RelayPhase::kDone) << s.why;
  EXPECT_EQ(s.episodes, 4) << windows;
  // The fourth: 20 periods of twice the 20.01 s to the first switch.
  EXPECT_NE(windows.find("up to 800.42 s"), std::string::npos) << windows;
}

}  // namespace
}  // namespace pidlab::autotune

namespace pidlab::autotune {
namespace {

// A process still settling from y = 2 (T = 2 s) when each episode starts:
// over the 1 s hold's second half y falls from 2 e^-0.25 to 2 e^-0.5, by
// 0.34, far more than the noise, the band and 5 % of the oscillation. The
// drift is named, and the next episode holds twice as long, until a hold no
// longer drifts (or reaches 16 times the one given); the estimate is made on
// that last episode (issue 60, "the hold lasts until drift converges").
TEST(RelayEpisodes, AHoldThatDriftsIsNamedAndDoubledUntilItRests) {
  const ExperimentOptions x = Options(0.0);
  ExperimentSummary s;
  Process settling{1.0, 2.0, 0.5};
  settling.y_start = 2.0;
  std::vector<std::string> lines;
  ASSERT_TRUE(IsOk(
      RunExperiment(x, Runner(settling, x), &s, [&](const std::string& line) { lines.push_back(line); })));
  const auto first = std::find_if(lines.begin(), lines.end(), [](const std::string& l) {
    return l.rfind("  the hold drifts or was disturbed: y moved -0.3", 0) == 0;
  });
  ASSERT_NE(first, lines.end());
  EXPECT_NE(first->find("a longer --hold"), std::string::npos) << *first;
  ASSERT_NE(std::next(first), lines.end());
  EXPECT_EQ(*std::next(first), "  the hold drifts: the next episode holds 2 s");
  EXPECT_GT(s.hold_s, 1.0);
  EXPECT_LE(s.hold_s, 16.0);
  EXPECT_GE(s.episodes, 2);
  // The last hold rests, or it is the longest allowed and says it drifts.
  EXPECT_TRUE(s.hold_note.empty() || s.hold_s == 16.0) << s.hold_s << ": " << s.hold_note;
  EXPECT_EQ(s.end, RelayPhase::kDone) << s.why;
}

}  // namespace
}  // namespace pidlab::autotune
