#pragma once
// LiveScope: the state of the live scope (`pidlab serve --lcm-url`,
// docs/live.md). It watches one or several trios, each with a LiveMonitor
// on a thread of its own (the caller's thread never waits on LCM), and
// streams to every subscriber from one sender thread: the status at most 10
// times a second, binary view frames at most 30 times a second, latest
// wins, and an ended episode's whole data once.
//
// A subscriber is an outlet the caller implements (a page's WebSocket in
// `pidlab serve`): the scope knows no server and writes no JSON; the outlet
// turns the merged view into its status message.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pidlab/monitor/live_monitor.h"

namespace pidlab::monitor {

/// What the monitors of the trios watched hear, merged.
struct LiveView {
  /// Each trio's snapshot, in the order the trios were given, and its URL.
  std::vector<MonitorSnapshot> trios;
  std::vector<std::string> trio_urls;
  /// The episodes of every trio, oldest first (by when their configuration
  /// was heard), at most kMaxShownEpisodes; trio_of[i] is episodes[i]'s trio, 1..K.
  std::vector<EpisodeInfo> episodes;
  std::vector<int> trio_of;
  /// Moves when anything shown changes.
  long version = 0;
};
inline constexpr std::size_t kMaxShownEpisodes = 32;
/// Merges the trios' snapshots (taken in that order) into a LiveView.
LiveView MergeTrios(std::vector<MonitorSnapshot> trios, std::vector<std::string> urls, long version);

/// Where the scope posts one subscriber's stream. Called from the sender
/// thread (and from Subscribe's caller for nothing): keep each call short.
class LiveOutlet {
 public:
  virtual ~LiveOutlet() = default;
  /// False once the subscriber has gone: the scope lets it go.
  virtual bool open() const = 0;
  /// Frames dropped on the way to the subscriber so far (in every frame's header).
  virtual long dropped() const = 0;
  /// The view with the subscriber's selected episode (null: none yet).
  virtual void PostStatus(const LiveView& view, const int64_t* selected_episode_id) = 0;
  /// A kind-1 view frame (frames.h); a newer one may replace it unsent.
  virtual void PostView(std::string frame) = 0;
  /// A kind-2 frame of a whole episode; never dropped.
  virtual void PostData(std::string frame) = 0;
};

class LiveScope {
 public:
  /// View frames' columns unless a subscriber asks for others.
  static constexpr int kDefaultColumns = 1000;

  /// Watches each trio (at least one). If LCM cannot start on a URL,
  /// status() names it (LiveMonitor::status).
  explicit LiveScope(const std::vector<LiveMonitorOptions>& trios);
  /// Stops the monitor and sender threads and joins them.
  ~LiveScope();
  LiveScope(const LiveScope&) = delete;
  LiveScope& operator=(const LiveScope&) = delete;

  /// Streams to `outlet` from now on, under `key` (any address naming the
  /// subscriber, e.g. its connection), replacing a subscriber of that key;
  /// columns in kMinColumns..kMaxColumns (frames.h).
  void Subscribe(const void* key, std::shared_ptr<LiveOutlet> outlet, int columns);
  /// Stops streaming to the subscriber of `key`, if any.
  void Unsubscribe(const void* key);

  enum class SelectStatus { kSelected, kNotKept, kNotSubscribed };
  /// The subscriber of `key` follows episode `episode_id` from now on
  /// (without a selection: the newest); its status is posted at once.
  SelectStatus Select(const void* key, int64_t episode_id);

  /// A kind-2 frame of the whole episode, `dropped` in its header; empty if
  /// the episode is not kept.
  std::string DataFrame(int64_t episode_id, long dropped) const;

  /// Ok, or the first trio this scope cannot hear (LCM did not start).
  Status status() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace pidlab::monitor
