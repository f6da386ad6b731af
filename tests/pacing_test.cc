// Real-time pacing (transport/pacing.h): the statistics' arithmetic, their
// round trip through a SUMMARY, and a Pacer on the machine's own clock (only
// bounds the schedule guarantees are asserted: a step never starts early,
// and a step started late is counted).

#include "pidlab/transport/pacing.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

namespace pidlab::transport {
namespace {

RealtimeStats Paced(double factor, long missed, double p50, double p99, double max, double rate) {
  RealtimeStats s;
  s.factor = factor;
  s.steps = 100;
  s.missed_deadlines = missed;
  s.lateness_p50_s = p50;
  s.lateness_p99_s = p99;
  s.lateness_max_s = max;
  s.rate_hz = rate;
  return s;
}

TEST(RealtimeFactor, PositiveFiniteFactorsAreValidOthersNamed) {
  std::string error;
  EXPECT_TRUE(RealtimeFactorIsValid(1.0, &error));
  EXPECT_TRUE(RealtimeFactorIsValid(0.25, &error));
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    error.clear();
    EXPECT_FALSE(RealtimeFactorIsValid(bad, &error)) << bad;
    EXPECT_NE(error.find("--realtime"), std::string::npos) << error;
  }
  EXPECT_FALSE(RealtimeFactorIsValid(-2.0, nullptr));
}

TEST(DescribeRealtime, IsEmptyWhenNotPacedAndNamesEveryFigureWhenPaced) {
  EXPECT_EQ(DescribeRealtime(RealtimeStats{}), "");
  EXPECT_EQ(DescribeRealtime(Paced(1.0, 2, 12e-6, 40e-6, 85e-6, 1000.0)),
            "paced 1x: 2 missed deadlines, lateness p50 12 us, p99 40 us, max 85 us, 1000.0 steps/s");
  EXPECT_NE(DescribeRealtime(Paced(2.0, 1, 0, 0, 0, 5.0)).find("1 missed deadline,"), std::string::npos);
}

TEST(CombineRealtime, SumsMissesTakesTheWorstLatenessAndTheLowestRate) {
  const RealtimeStats a = Paced(1.0, 2, 10e-6, 50e-6, 90e-6, 1000.0);
  const RealtimeStats b = Paced(1.0, 3, 20e-6, 30e-6, 200e-6, 900.0);
  const RealtimeStats dut = CombineRealtime(a, b);
  EXPECT_EQ(dut.steps, 200);
  EXPECT_EQ(dut.missed_deadlines, 5);
  EXPECT_EQ(dut.lateness_p50_s, 20e-6);
  EXPECT_EQ(dut.lateness_p99_s, 50e-6);
  EXPECT_EQ(dut.lateness_max_s, 200e-6);
  EXPECT_EQ(dut.rate_hz, 900.0);
}

TEST(CombineRealtime, SkipsAnUnpacedSide) {
  const RealtimeStats a = Paced(1.0, 2, 10e-6, 50e-6, 90e-6, 1000.0);
  EXPECT_EQ(CombineRealtime(a, RealtimeStats{}).missed_deadlines, 2);
  EXPECT_EQ(CombineRealtime(RealtimeStats{}, a).rate_hz, 1000.0);
  EXPECT_FALSE(CombineRealtime(RealtimeStats{}, RealtimeStats{}).paced());
}

TEST(RealtimeSummary, RoundTripsThroughASummaryAndAnUnpacedOneStaysUnpaced) {
  pidlab::lcmt_episode_summary m{};
  const RealtimeStats s = Paced(0.5, 7, 1e-5, 2e-4, 3e-3, 480.5);
  SetRealtime(s, &m);
  m.step = 100;
  const RealtimeStats back = RealtimeFromSummary(m);
  EXPECT_EQ(back.factor, 0.5);
  EXPECT_EQ(back.steps, 100);
  EXPECT_EQ(back.missed_deadlines, 7);
  EXPECT_EQ(back.lateness_p50_s, 1e-5);
  EXPECT_EQ(back.lateness_p99_s, 2e-4);
  EXPECT_EQ(back.lateness_max_s, 3e-3);
  EXPECT_EQ(back.rate_hz, 480.5);
  m.realtime_factor = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(RealtimeFromSummary(m).paced());
  m.realtime_factor = 0.0;
  EXPECT_FALSE(RealtimeFromSummary(m).paced());
}

TEST(Pacer, NeverStartsAStepBeforeItIsDue) {
  Pacer dut(/*factor=*/10.0, /*dt_s=*/0.01, /*total_steps=*/20);  // a 1 ms period
  EXPECT_DOUBLE_EQ(dut.period_s(), 1e-3);
  const auto t0 = std::chrono::steady_clock::now();
  dut.Start();
  for (long k = 1; k <= 20; ++k) dut.WaitForStep(k);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(elapsed, 20e-3);
  const RealtimeStats s = dut.Stats();
  EXPECT_EQ(s.factor, 10.0);
  EXPECT_EQ(s.steps, 20);
  EXPECT_GE(s.lateness_p50_s, 0.0);
  EXPECT_LE(s.lateness_p50_s, s.lateness_p99_s);
  EXPECT_LE(s.lateness_p99_s, s.lateness_max_s);
  EXPECT_GT(s.rate_hz, 0.0);
  EXPECT_LE(s.rate_hz, 1000.0 * (1 + 1e-9));  // 20 steps in no less than 20 periods
}

TEST(Pacer, CountsAStepThatStartedMoreThanAPeriodLateAsMissed) {
  Pacer dut(/*factor=*/1.0, /*dt_s=*/1e-3, /*total_steps=*/2);
  dut.Start();
  std::this_thread::sleep_for(std::chrono::milliseconds(5));  // step 1 was due after 1 ms
  dut.WaitForStep(1);
  const RealtimeStats s = dut.Stats();
  EXPECT_EQ(s.steps, 1);
  EXPECT_EQ(s.missed_deadlines, 1);
  EXPECT_GE(s.lateness_max_s, 4e-3);
}

TEST(Pacer, StatsBeforeAnyStepArePacedAndEmpty) {
  Pacer dut(2.0, 1e-3, 10);
  dut.Start();
  const RealtimeStats s = dut.Stats();
  EXPECT_TRUE(s.paced());
  EXPECT_EQ(s.steps, 0);
  EXPECT_EQ(s.missed_deadlines, 0);
  EXPECT_EQ(s.rate_hz, 0.0);
}

TEST(LatenessHistogram, BinsArePowersOfTwoMicrosecondsWithTheEndsOpen) {
  EXPECT_EQ(LatenessBin(0.0), 0);
  EXPECT_EQ(LatenessBin(-1e-9), 0);
  EXPECT_EQ(LatenessBin(0.999e-6), 0);
  EXPECT_EQ(LatenessBin(1e-6), 1);  // [1, 2) us
  EXPECT_EQ(LatenessBin(1.99e-6), 1);
  EXPECT_EQ(LatenessBin(2e-6), 2);    // [2, 4) us
  EXPECT_EQ(LatenessBin(100e-6), 7);  // [64, 128) us
  EXPECT_EQ(LatenessBin(std::ldexp(1e-6, 21) * 1.5), 22);
  EXPECT_EQ(LatenessBin(10.0), kLatenessBins - 1);
  EXPECT_EQ(LatenessBin(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_DOUBLE_EQ(LatenessBinUpperEdge(0), 1e-6);
  EXPECT_DOUBLE_EQ(LatenessBinUpperEdge(7), 128e-6);
  EXPECT_TRUE(std::isinf(LatenessBinUpperEdge(kLatenessBins - 1)));
}

TEST(PacingProgress, PercentilesAreTheUpperEdgesOfTheNearestRankBinsCappedByTheMaximum) {
  PacingProgress p;
  EXPECT_EQ(p.UpperPercentile(0.5), 0.0);  // no steps yet
  p.steps = 100;
  p.lateness_max_s = 300e-6;
  p.histogram[static_cast<std::size_t>(LatenessBin(10e-6))] = 50;  // ranks 1..50: [8, 16) us
  p.histogram[static_cast<std::size_t>(LatenessBin(40e-6))] = 49;  // ranks 51..99: [32, 64) us
  p.histogram[static_cast<std::size_t>(LatenessBin(300e-6))] = 1;  // rank 100: [256, 512) us
  EXPECT_DOUBLE_EQ(p.UpperPercentile(0.50), 16e-6);
  EXPECT_DOUBLE_EQ(p.UpperPercentile(0.99), 64e-6);
  EXPECT_DOUBLE_EQ(p.UpperPercentile(1.0), 300e-6);  // the bin's edge, 512 us, capped by the maximum
  pidlab::lcmt_pacing_progress m{};
  SetPacingProgress(p, &m);
  EXPECT_EQ(m.step, 100);
  EXPECT_EQ(m.lateness_histogram[LatenessBin(40e-6)], 49);
  EXPECT_DOUBLE_EQ(m.lateness_p50_upper_s, 16e-6);
  EXPECT_DOUBLE_EQ(m.lateness_p99_upper_s, 64e-6);
  // A watcher reads the same figures back, and the same bounds from them.
  const PacingProgress back = PacingProgressFromMessage(m);
  EXPECT_EQ(back.steps, p.steps);
  EXPECT_EQ(back.histogram, p.histogram);
  EXPECT_EQ(back.lateness_max_s, p.lateness_max_s);
  EXPECT_EQ(back.UpperPercentile(0.50), m.lateness_p50_upper_s);
  EXPECT_EQ(back.UpperPercentile(0.99), m.lateness_p99_upper_s);
}

TEST(Pacer, ProgressAgreesWithTheExactStatsAndBoundsTheirPercentiles) {
  Pacer dut(/*factor=*/10.0, /*dt_s=*/0.01, /*total_steps=*/30);
  dut.Start();
  for (long k = 1; k <= 30; ++k) dut.WaitForStep(k);
  const RealtimeStats exact = dut.Stats();
  const PacingProgress live = dut.Progress();
  EXPECT_EQ(live.steps, exact.steps);
  EXPECT_EQ(live.missed_deadlines, exact.missed_deadlines);
  EXPECT_EQ(live.lateness_max_s, exact.lateness_max_s);
  EXPECT_EQ(live.rate_hz, exact.rate_hz);
  long counted = 0;
  for (long c : live.histogram) counted += c;
  EXPECT_EQ(counted, 30);
  // An upper bound within one bin: at most twice the exact figure (or 1 us).
  EXPECT_GE(live.UpperPercentile(0.50), exact.lateness_p50_s);
  EXPECT_LE(live.UpperPercentile(0.50), std::max(2 * exact.lateness_p50_s, 1e-6));
  EXPECT_GE(live.UpperPercentile(0.99), exact.lateness_p99_s);
  EXPECT_LE(live.UpperPercentile(0.99), std::max(2 * exact.lateness_p99_s, 1e-6));
}

}  // namespace
}  // namespace pidlab::transport
