// K trios serving one tune (tuner/episode_pool.h) on memq://: every client
// of a pool holds its own memq:// instance, where no role answers, so these
// tests cover what a pool does without a live trio: the URL list, the worker
// threads, and trios left out one by one until none is left. A pool over
// live trios is tested end to end by integration.trio.trios and
// integration.trio.trio_killed (tests/integration/trio_test.sh).

#include "pidlab/episode_client/episode_pool.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "test_status.h"

using pidlab::episode_client::EpisodeClientOptions;
using pidlab::episode_client::EpisodePool;
using pidlab::episode_client::SplitUrlList;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledRunner;
using pidlab::optim::ParallelFor;

namespace pidlab {
namespace {

EpisodeClientOptions SilentTrio(std::vector<std::string>* notes = nullptr) {
  EpisodeClientOptions o;
  o.lcm_url = "memq://";
  o.start_timeout_s = 0.1;
  o.max_attempts = 1;
  if (notes) o.on_note = [notes](const std::string& note) { notes->push_back(note); };
  return o;
}

struct Loop {
  Plant plant;
  PidGains gains{2.0, 1.0, 1.5};
  LoopOptions options;
};

Loop ShortLoop() {
  Loop l;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &l.plant)));
  l.options.loop = LoopKind::kSampled;
  l.options.horizon_s = 0.5;
  return l;
}

TEST(SplitUrlList, SplitsOnWhiteSpaceAndCommasAndSkipsEmptyItems) {
  EXPECT_EQ(SplitUrlList("udpm://a:1?ttl=0 udpm://b:2,udpm://c:3\tudpm://d:4\n"),
            (std::vector<std::string>{"udpm://a:1?ttl=0", "udpm://b:2", "udpm://c:3", "udpm://d:4"}));
  EXPECT_EQ(SplitUrlList(" ,, memq:// ,"), (std::vector<std::string>{"memq://"}));
  EXPECT_TRUE(SplitUrlList("").empty());
  EXPECT_TRUE(SplitUrlList(" , \n").empty());
}

TEST(EpisodePool, ThrowsWithoutATrio) {
  EXPECT_THROW(EpisodePool(std::vector<EpisodeClientOptions>{}), std::invalid_argument);
}

TEST(EpisodePool, HasOneClientPerTrioAndStartsWithNoneLost) {
  const EpisodePool dut({SilentTrio(), SilentTrio(), SilentTrio()});
  EXPECT_EQ(dut.size(), 3);
  EXPECT_TRUE(dut.lost().empty());
  EXPECT_EQ(dut.stats().episodes, 0);
  EXPECT_EQ(dut.stats().steps, 0);
}

TEST(EpisodePool, ParallelForRunsEveryIndexOnceOnAtMostOneThreadPerTrio) {
  EpisodePool dut({SilentTrio(), SilentTrio(), SilentTrio()});
  const ParallelFor parallel_for = dut.AsParallelFor();
  std::mutex mutex;
  std::vector<int> seen;
  std::set<std::thread::id> threads;
  parallel_for(40, [&](int i) {
    std::lock_guard<std::mutex> lock(mutex);
    seen.push_back(i);
    threads.insert(std::this_thread::get_id());
  });
  std::sort(seen.begin(), seen.end());
  std::vector<int> expected(40);
  for (int i = 0; i < 40; ++i) expected[static_cast<std::size_t>(i)] = i;
  EXPECT_EQ(seen, expected);
  EXPECT_GE(threads.size(), 1u);
  EXPECT_LE(threads.size(), 3u);
  EXPECT_EQ(threads.count(std::this_thread::get_id()), 0u);  // workers, not the caller

  int calls = 0;
  parallel_for(0, [&](int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(EpisodePool, ParallelForRethrowsWhatABodyThrewAfterEveryIndexRan) {
  EpisodePool dut({SilentTrio(), SilentTrio()});
  std::mutex mutex;
  int ran = 0;
  EXPECT_THROW(dut.AsParallelFor()(10,
                                   [&](int i) {
                                     {
                                       std::lock_guard<std::mutex> lock(mutex);
                                       ++ran;
                                     }
                                     if (i == 3) throw std::runtime_error("body 3");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ran, 10);
}

TEST(EpisodePool, LeavesOutEachSilentTrioNamingItAndFailsWhenNoneIsLeft) {
  std::vector<std::string> notes;
  EpisodePool dut({SilentTrio(&notes), SilentTrio()});
  const SampledRunner runner = dut.AsRunner();
  const Loop l = ShortLoop();
  std::vector<double> y;
  std::string error;
  EXPECT_FALSE(OkInto(runner(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  EXPECT_NE(error.find("every trio failed; the last: "), std::string::npos) << error;
  EXPECT_NE(error.find("no answer from"), std::string::npos) << error;
  const std::vector<std::string> lost = dut.lost();
  ASSERT_EQ(lost.size(), 2u);
  EXPECT_EQ(lost[0].rfind("trio 1 (memq://) left out: ", 0), 0u) << lost[0];
  EXPECT_EQ(lost[1].rfind("trio 2 (memq://) left out: ", 0), 0u) << lost[1];
  // The first trio's on_note is the pool's: one line per trio left out.
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_NE(notes[0].find("its episode runs on another trio"), std::string::npos) << notes[0];

  // Nothing is left to try: the next episode fails at once.
  error.clear();
  EXPECT_FALSE(OkInto(runner(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  EXPECT_NE(error.find("every trio failed"), std::string::npos) << error;
  EXPECT_EQ(dut.lost().size(), 2u);
}

TEST(EpisodePool, AnEpisodeThatFailsByItselfLeavesNoTrioOut) {
  EpisodePool dut({SilentTrio(), SilentTrio()});
  Loop l = ShortLoop();
  l.options.horizon_s = 1.01;  // not a multiple of the sample time: invalid anywhere
  std::vector<double> y;
  std::string error;
  EXPECT_FALSE(
      OkInto(dut.AsRunner()(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  EXPECT_NE(error.find("horizon 1.01"), std::string::npos) << error;
  EXPECT_TRUE(dut.lost().empty());
}

}  // namespace
}  // namespace pidlab
