// Unit tests of the live scope's state (monitor/live_scope.h): the trios'
// views merged, and a LiveScope on a quiet memq:// trio streaming to an
// outlet of the test's own.

#include "pidlab/monitor/live_scope.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pidlab::monitor {
namespace {

EpisodeInfo Episode(int64_t id, double first_heard_s) {
  EpisodeInfo e;
  e.episode_id = id;
  e.first_heard_s = first_heard_s;
  return e;
}

TEST(MergeTrios, OrdersEveryTriosEpisodesByWhenHeardAndNamesEachOnesTrio) {
  MonitorSnapshot first, second;
  first.episodes = {Episode(11, 1.0), Episode(12, 3.0)};
  second.episodes = {Episode(21, 2.0)};
  const LiveView dut = MergeTrios({first, second}, {"udpm://a", "udpm://b"}, 7);
  ASSERT_EQ(dut.episodes.size(), 3u);
  EXPECT_EQ(dut.episodes[0].episode_id, 11);
  EXPECT_EQ(dut.episodes[1].episode_id, 21);
  EXPECT_EQ(dut.episodes[2].episode_id, 12);
  EXPECT_EQ(dut.trio_of, (std::vector<int>{1, 2, 1}));
  EXPECT_EQ(dut.trios.size(), 2u);
  EXPECT_EQ(dut.trio_urls, (std::vector<std::string>{"udpm://a", "udpm://b"}));
  EXPECT_EQ(dut.version, 7);
}

TEST(MergeTrios, ShowsAtMostMaxShownEpisodesKeepingTheNewest) {
  MonitorSnapshot s;
  for (int i = 0; i < static_cast<int>(kMaxShownEpisodes) + 5; ++i) s.episodes.push_back(Episode(i, i));
  const LiveView dut = MergeTrios({s}, {"memq://"}, 0);
  ASSERT_EQ(dut.episodes.size(), kMaxShownEpisodes);
  EXPECT_EQ(dut.episodes.front().episode_id, 5);
  EXPECT_EQ(dut.episodes.back().episode_id, static_cast<int64_t>(kMaxShownEpisodes) + 4);
}

// Records what the scope posts; the test waits on it with a deadline.
class RecordingOutlet : public LiveOutlet {
 public:
  bool open() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return open_;
  }
  long dropped() const override { return 0; }
  void PostStatus(const LiveView& view, const int64_t* selected_episode_id) override {
    std::lock_guard<std::mutex> lock(mutex_);
    ++statuses_;
    last_had_selection_ = selected_episode_id != nullptr;
    last_trios_ = view.trios.size();
    changed_.notify_all();
  }
  void PostView(std::string) override {}
  void PostData(std::string) override {}

  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    open_ = false;
  }
  // Waits at most 5 s for `done` (under the lock); its value then.
  bool WaitFor(const std::function<bool()>& done) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(5), done);
  }
  int statuses() const { return statuses_; }
  bool last_had_selection() const { return last_had_selection_; }
  std::size_t last_trios() const { return last_trios_; }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool open_ = true;
  int statuses_ = 0;
  bool last_had_selection_ = true;
  std::size_t last_trios_ = 0;
};

std::vector<LiveMonitorOptions> QuietTrios(int count) {
  std::vector<LiveMonitorOptions> trios(static_cast<std::size_t>(count));
  for (LiveMonitorOptions& o : trios) o.lcm_url = "memq://";
  return trios;
}

TEST(LiveScope, ANewSubscriberGetsTheStatusAtOnceWithoutASelectionOnAQuietTrio) {
  LiveScope dut(QuietTrios(2));
  auto outlet = std::make_shared<RecordingOutlet>();
  dut.Subscribe(outlet.get(), outlet, LiveScope::kDefaultColumns);
  ASSERT_TRUE(outlet->WaitFor([&] { return outlet->statuses() >= 1; }));
  EXPECT_FALSE(outlet->last_had_selection());
  EXPECT_EQ(outlet->last_trios(), 2u);
}

TEST(LiveScope, AnEpisodeNotKeptCannotBeSelectedNorFetched) {
  LiveScope dut(QuietTrios(1));
  auto outlet = std::make_shared<RecordingOutlet>();
  EXPECT_EQ(dut.Select(outlet.get(), 42), LiveScope::SelectStatus::kNotKept);
  dut.Subscribe(outlet.get(), outlet, LiveScope::kDefaultColumns);
  EXPECT_EQ(dut.Select(outlet.get(), 42), LiveScope::SelectStatus::kNotKept);
  EXPECT_TRUE(dut.DataFrame(42, 0).empty());
}

TEST(LiveScope, AClosedOutletIsLetGo) {
  LiveScope dut(QuietTrios(1));
  auto outlet = std::make_shared<RecordingOutlet>();
  const std::weak_ptr<RecordingOutlet> watched = outlet;
  dut.Subscribe(outlet.get(), outlet, LiveScope::kDefaultColumns);
  ASSERT_TRUE(outlet->WaitFor([&] { return outlet->statuses() >= 1; }));
  outlet->Close();
  outlet.reset();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!watched.expired() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(watched.expired());
}

TEST(LiveScope, AnUnsubscribedOutletIsReleasedAtOnce) {
  LiveScope dut(QuietTrios(1));
  auto outlet = std::make_shared<RecordingOutlet>();
  const std::weak_ptr<RecordingOutlet> watched = outlet;
  dut.Subscribe(outlet.get(), outlet, LiveScope::kDefaultColumns);
  const void* key = outlet.get();
  outlet.reset();
  dut.Unsubscribe(key);
  EXPECT_TRUE(watched.expired());
}

}  // namespace
}  // namespace pidlab::monitor
