#pragma once
// A complete log of the trio's traffic: lcm-logger under supervision, an end
// marker that proves everything published before it is on disk, and repair of
// whatever the logger still lost: steps from the plant's trajectory chunks,
// configurations from launch's own copies (episode_witness.h).

#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/launcher/episode_witness.h"
#include "pidlab/launcher/supervisor.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/spec/status.h"
#include "pidlab/transport/transport.h"

namespace pidlab::launcher {

/// Union of the missing steps of the three streams of an episode, as sorted
/// disjoint inclusive ranges.
std::vector<std::pair<long, long>> MissingSteps(const replay::Episode& episode);
/// "3,5-9,..." (at most max_ranges ranges, then a count).
std::string RangesText(const std::vector<std::pair<long, long>>& ranges, std::size_t max_ranges = 8);
long CountSteps(const std::vector<std::pair<long, long>>& ranges);

/// One event to write into a log: (timestamp in us, payload).
using TimedPayload = std::pair<int64_t, std::vector<uint8_t>>;

/// The PLANT_OUTPUT events (<prefix>PLANT_OUTPUT, lcmt_plant_output) a step
/// lane's lcm-logger lost, rebuilt from `log`: one for every step k <
/// total_steps (those a controller answers) of every complete episode of
/// `log` that `lane_file` does not hold, with the y of the episode. Its timestamp lies between those of its
/// logged neighbours, spread evenly (a lost tail or head: dt apart), and always after the step before it
/// (logged or rebuilt), so a player paces it as the plant did and a controller, which answers y_k only after
/// y_(k-1), sees it in order. Nothing for an episode the lane logger heard nothing of, or if `lane_file`
/// cannot be read. In step order.
std::vector<TimedPayload> RebuildLaneOutputs(const replay::LogContents& log, const std::string& lane_file,
                                             const std::string& channel_prefix);

/// Writes `out_file`: every event of the files `inputs` (each in time order,
/// as lcm-logger writes them) and of `extra` (sorted by timestamp, on
/// `extra_channel`), merged by timestamp; on a tie an earlier input comes
/// first, and an extra event goes before any logged event with a later
/// timestamp. A truncated tail (a logger killed mid-write) ends that input;
/// an input other than inputs[0] that does not exist is skipped. A failed
/// Status (kIoFailed) if inputs[0] cannot be read or out_file cannot be
/// written.
Status MergeEventLogs(const std::vector<std::string>& inputs, const std::vector<TimedPayload>& extra,
                      const std::string& extra_channel, const std::string& out_file);

/// Bytes free for an unprivileged writer on the file system that holds
/// `file` (its directory), or -1 if that cannot be told.
long long FreeBytesBeside(const std::string& file);

/// The cause a program wrote as its last words into `stderr_file`: the text
/// after the last ": " of its last non-empty line ("lcm_eventlog_write_event:
/// No space left on device" -> "No space left on device"); empty if none.
std::string LastWords(const std::string& stderr_file);

enum class RepairStatus {
  kComplete,    // nothing was missing
  kRepaired,    // steps were missing and the plant's chunks filled them
  kIncomplete,  // still missing after every round (see the summary's lines)
  kUnreadable,  // the log could not be read or the logger stopped writing
};

struct RepairSummary {
  RepairStatus status = RepairStatus::kComplete;
  int rounds = 0;
  std::map<int64_t, long> republished;  // episode -> steps asked for (all rounds)
  /// Episodes whose configuration the log lacks and launch heard: MergeLanes
  /// writes launch's copy into the log.
  std::vector<int64_t> restored;
  /// Episodes the plant ended whose configuration neither the log nor launch has.
  std::vector<int64_t> lost_configs;
  /// One line per problem (kIncomplete, kUnreadable) or the repair (kRepaired).
  std::vector<std::string> lines;
  /// Informative lines whatever the status (e.g. episodes without a configuration).
  std::vector<std::string> notes;
};

struct LogCaptureOptions {
  std::string log_file;
  std::string channel_prefix;
  /// lcm-logger runs this much nicer than everyone else (negative: higher
  /// priority), so a loaded machine starves the trio before the logger.
  int logger_nice = -10;
  /// Rounds of (read log, ask the plant for the missing steps, wait for the
  /// answers to be in the log).
  int repair_rounds = 6;
  /// How long to wait for the logger to write a marker, s.
  double marker_timeout_s = 10.0;
  /// The trio's key, if it has one: the log is read with it.
  std::optional<transport::AuthKey> auth_key;
};

class LogCapture {
 public:
  /// `transport` and `supervisor` must outlive this object.
  LogCapture(const LogCaptureOptions& options, transport::Transport* transport, Supervisor* supervisor);
  /// Removes the files that held the loggers' stderr.
  ~LogCapture();
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;

  /// Starts lcm-logger on `lcm_url` (a large receive buffer is added unless
  /// the URL sets one). Returns its pid.
  pid_t StartLogger(const std::string& lcm_url);

  /// Starts one more lcm-logger per step lane of `lcm_url` (PLANT_OUTPUT on
  /// port + 1, CONTROL on port + 2; none for URLs without lanes), each into a
  /// file of its own beside the log (FILE.lane1, FILE.lane2).
  void StartLaneLoggers(const std::string& lcm_url);

  /// True if `pid` is one of the lcm-loggers started here.
  bool IsLogger(pid_t pid) const;
  /// One line on a logger that ended: the file it wrote, its pid, how it
  /// ended and the cause it gave ("lcm-logger writing run.lcmlog.lane1
  /// (pid 12) exited with status 1: No space left on device").
  std::string DescribeLoggerEnd(const Child& logger) const;
  /// After a logger died: stops the lane loggers without merging, so
  /// whatever the files hold stays as written. Returns the log files that
  /// exist (the log first, then the lane files).
  std::vector<std::string> AbandonLanes();

  /// After a logger died and the base logger stopped: what the log misses,
  /// as `pidlab replay` would report it, in one short clause: "FILE misses
  /// 24590 steps of episode ID: 411-25000" for the first episode with a
  /// configuration in FILE that misses steps (and did not fail live), with
  /// "(and of N more episodes)" before the ranges if others miss steps too;
  /// "no episode in FILE misses a step" or "FILE cannot be read" otherwise.
  /// Episodes whose configuration never reached FILE are not known to it.
  std::string DescribeMissing() const;

  /// Stops the lane loggers and merges their events into the log by
  /// timestamp (the base port's events first on a tie), so the log holds the
  /// per-step datagrams too and lcm-logplayer can drive a controller from it.
  /// Call after the base logger stopped. A failed Status (kIoFailed) if it
  /// failed (the log is then left as the base logger wrote it, and the lane
  /// files are kept and named in the message).
  /// Outputs the PLANT_OUTPUT lane's logger lost are rebuilt from the
  /// trajectory chunks (not for authenticated runs); rebuilt_outputs() counts them.
  /// The configurations Repair found the log lacking are merged in too, from
  /// launch's copies (via FILE.configs, removed after the merge), with their
  /// tags in authenticated runs.
  Status MergeLanes();
  long rebuilt_outputs() const { return rebuilt_outputs_; }

  /// Publishes a MARKER until lcm-logger has written it to the log (so
  /// everything published before it is on disk), then waits until the file
  /// stops growing. False if the marker never appeared.
  bool WaitForMarker(const std::string& what);

  /// Makes sure the log holds every step of every episode in it: reads it
  /// with the replay reader, asks the plant to republish each missing range
  /// as trajectory chunks, waits until the answers are in the log, and
  /// repeats up to repair_rounds times. Episodes the plant ended with a
  /// FAILED summary are left as they are. An episode the plant ended (its
  /// SUMMARY heard live) or with data in the log, whose configuration the
  /// log lacks, takes launch's own copy (MergeLanes writes it into the log)
  /// and is repaired like the others; without a copy it is incomplete.
  RepairSummary Repair();

 private:
  struct Gap {
    int64_t id;
    std::vector<std::pair<long, long>> ranges;
  };
  /// The replay reader's options for the log: launch's copies of the
  /// configurations of the episodes the plant ended or the log holds data of.
  replay::ReadOptions ReaderOptions() const;
  /// Reads the log: the gaps to fill and the episodes that ran without a
  /// configuration anywhere, or false with *summary filled.
  bool FindGaps(std::vector<Gap>* gaps, std::vector<int64_t>* lost_configs, RepairSummary* summary);
  /// The summary's status and lines once no round is left to run.
  void Conclude(const std::vector<Gap>& gaps, const std::vector<int64_t>& lost_configs,
                RepairSummary* summary) const;
  void AskForGaps(const std::vector<Gap>& gaps, RepairSummary* summary);
  /// (timestamp, encoded lcmt_plant_output) for every step of a complete
  /// episode whose PLANT_OUTPUT is not in `lane_file`.
  std::vector<TimedPayload> MissingLaneOutputs(const std::string& lane_file) const;
  void DescribeUnrepaired(const std::vector<Gap>& gaps, RepairSummary* summary) const;

  LogCaptureOptions options_;
  transport::Transport* transport_;
  Supervisor* supervisor_;
  EpisodeWitness witness_;
  std::set<int64_t> orphans_with_copy_;  // data in the log, no configuration there, a copy here
  /// launch's copies of the configurations the log lacks (the last Repair's).
  std::vector<pidlab::lcmt_episode_config> restored_;
  bool listening_ = false;
  mutable bool noted_orphans_ = false;
  /// The plant's chunks as this process hears them: (episode, first step) -> count.
  std::map<std::pair<int64_t, int64_t>, int> answers_;
  std::vector<std::pair<int64_t, int64_t>> asked_;
  std::vector<std::pair<pid_t, std::string>> lane_loggers_;  // pid, file
  struct LoggerFiles {
    std::string log;          // what it writes
    std::string stderr_file;  // where its complaints go (a temporary file)
  };
  std::map<pid_t, LoggerFiles> loggers_;
  /// Starts one lcm-logger into `file` with its stderr captured.
  pid_t StartOneLogger(const std::string& url, const std::string& file);
  long rebuilt_outputs_ = 0;
};

}  // namespace pidlab::launcher
