#include "pidlab/launcher/log_capture.h"

#include <lcm/eventlog.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "pidlab/transport/episode_start.h"

namespace pidlab::launcher {
namespace {

// lcm-logger's socket asks for this receive buffer (the kernel caps it at
// net.core.rmem_max): under load the kernel drops datagrams silently when the
// logger does not read in time.
constexpr const char* kRecvBuf = "recv_buf_size=4194304";

std::string FileTail(const std::string& path, std::size_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(in.tellg());
  const std::size_t from = size > max_bytes ? size - max_bytes : 0;
  in.seekg(static_cast<std::streamoff>(from));
  std::string s(size - from, '\0');
  in.read(s.data(), static_cast<std::streamsize>(s.size()));
  return s;
}

long FileSize(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? static_cast<long>(st.st_size) : -1;
}

}  // namespace

std::string RangesText(const std::vector<std::pair<long, long>>& ranges, std::size_t max_ranges) {
  std::string s;
  for (std::size_t i = 0; i < ranges.size() && i < max_ranges; ++i) {
    s += (i ? "," : "") + std::to_string(ranges[i].first);
    if (ranges[i].second != ranges[i].first) s += "-" + std::to_string(ranges[i].second);
  }
  if (ranges.size() > max_ranges) s += ",... (" + std::to_string(ranges.size()) + " ranges)";
  return s;
}

std::vector<std::pair<long, long>> MissingSteps(const replay::Episode& e) {
  std::vector<std::pair<long, long>> all;
  for (const replay::StreamStats* s : {&e.outputs, &e.commands, &e.disturbances})
    all.insert(all.end(), s->missing.begin(), s->missing.end());
  std::sort(all.begin(), all.end());
  std::vector<std::pair<long, long>> merged;
  for (const auto& r : all) {
    if (!merged.empty() && r.first <= merged.back().second + 1)
      merged.back().second = std::max(merged.back().second, r.second);
    else
      merged.push_back(r);
  }
  return merged;
}

long CountSteps(const std::vector<std::pair<long, long>>& ranges) {
  long n = 0;
  for (const auto& r : ranges) n += r.second - r.first + 1;
  return n;
}

LogCapture::LogCapture(const LogCaptureOptions& options, transport::Transport* transport,
                       Supervisor* supervisor)
    : options_(options), transport_(transport), supervisor_(supervisor), witness_(transport) {}

LogCapture::~LogCapture() {
  for (const auto& [pid, files] : loggers_) std::remove(files.stderr_file.c_str());
}

long long FreeBytesBeside(const std::string& file) {
  const std::size_t slash = file.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : file.substr(0, slash);
  struct statvfs fs {};
  if (statvfs(dir.c_str(), &fs) != 0) return -1;
  return static_cast<long long>(fs.f_bavail) * static_cast<long long>(fs.f_frsize);
}

std::string LastWords(const std::string& stderr_file) {
  std::ifstream in(stderr_file);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  const std::size_t colon = last.rfind(": ");
  return colon == std::string::npos ? last : last.substr(colon + 2);
}

pid_t LogCapture::StartOneLogger(const std::string& url, const std::string& file) {
  char stderr_file[] = "/tmp/pidlab-lcm-logger-XXXXXX";
  const int fd = mkstemp(stderr_file);
  if (fd >= 0) close(fd);
  const pid_t pid = supervisor_->Start(
      "lcm-logger", {"lcm-logger", "-q", "-f", "--flush-interval=20", "--lcm-url=" + url, file}, {},
      options_.logger_nice, fd >= 0 ? stderr_file : "");
  loggers_[pid] = {file, fd >= 0 ? stderr_file : ""};
  return pid;
}

bool LogCapture::IsLogger(pid_t pid) const { return loggers_.count(pid) > 0; }

std::string LogCapture::DescribeLoggerEnd(const Child& logger) const {
  const auto it = loggers_.find(logger.pid);
  if (it == loggers_.end())
    return logger.name + " (pid " + std::to_string(logger.pid) + ") " + DescribeStatus(logger.status);
  const std::string cause = it->second.stderr_file.empty() ? "" : LastWords(it->second.stderr_file);
  return "lcm-logger writing " + it->second.log + " (pid " + std::to_string(logger.pid) + ") " +
         DescribeStatus(logger.status) + (cause.empty() ? "" : ": " + cause.substr(0, 80));
}

std::vector<std::string> LogCapture::AbandonLanes() {
  for (const auto& [pid, file] : lane_loggers_)
    if (pid > 0 && !supervisor_->StopChild(pid, SIGINT, 1.0)) supervisor_->StopChild(pid, SIGKILL, 1.0);
  std::vector<std::string> kept;
  struct stat st {};
  if (stat(options_.log_file.c_str(), &st) == 0) kept.push_back(options_.log_file);
  for (const auto& lane : lane_loggers_)
    if (stat(lane.second.c_str(), &st) == 0) kept.push_back(lane.second);
  lane_loggers_.clear();
  return kept;
}

pid_t LogCapture::StartLogger(const std::string& lcm_url) {
  std::string logger_url = lcm_url;
  if (logger_url.find("recv_buf_size=") == std::string::npos)
    logger_url += std::string(logger_url.find('?') == std::string::npos ? "?" : "&") + kRecvBuf;
  return StartOneLogger(logger_url, options_.log_file);
}

void LogCapture::StartLaneLoggers(const std::string& lcm_url) {
  for (int lane : {transport::kPlantOutputLane, transport::kControlLane}) {
    std::string url = transport::StepLaneUrl(lcm_url, lane);
    if (url.empty()) continue;  // memq:// and the like: every channel is on the base URL
    if (url.find("recv_buf_size=") == std::string::npos)
      url += std::string(url.find('?') == std::string::npos ? "?" : "&") + kRecvBuf;
    const std::string file = options_.log_file + ".lane" + std::to_string(lane);
    lane_loggers_.emplace_back(StartOneLogger(url, file), file);
  }
}

replay::ReadOptions LogCapture::ReaderOptions() const {
  replay::ReadOptions read_options;
  read_options.channel_prefix = options_.channel_prefix;
  read_options.auth_key = options_.auth_key;
  for (const int64_t id : witness_.ended())
    if (const auto* config = witness_.Config(id)) read_options.supplied_configs.push_back(*config);
  for (const int64_t id : orphans_with_copy_)
    if (const auto* config = witness_.Config(id); config && !witness_.Ended(id))
      read_options.supplied_configs.push_back(*config);
  return read_options;
}

std::string LogCapture::DescribeMissing() const {
  replay::LogContents log;
  if (!replay::ReadLog(options_.log_file, ReaderOptions(), &log).ok())
    return options_.log_file + " cannot be read";
  const replay::Episode* first = nullptr;
  long more = 0;
  for (const replay::Episode& e : log.episodes) {
    // As the repair: an episode without a configuration cannot be sized, one
    // that failed live is left as it is.
    if (!e.has_config || e.Complete()) continue;
    if (e.has_summary && e.summary_status == pidlab::lcmt_episode_summary::FAILED) continue;
    if (first)
      ++more;
    else
      first = &e;
  }
  if (!first) return "no episode in " + options_.log_file + " misses a step";
  const std::vector<std::pair<long, long>> ranges = MissingSteps(*first);
  std::ostringstream os;
  os << options_.log_file << " misses " << CountSteps(ranges) << " steps of episode " << first->episode_id;
  if (more > 0) os << " (and of " << more << " more episode" << (more == 1 ? "" : "s") << ")";
  os << ": " << RangesText(ranges, 2);
  return os.str();
}

std::vector<TimedPayload> RebuildLaneOutputs(const replay::LogContents& log, const std::string& lane_file,
                                             const std::string& channel_prefix) {
  std::vector<TimedPayload> out;
  std::map<std::pair<int64_t, int64_t>, int64_t> seen;  // (episode, step) -> first timestamp
  const std::string channel = channel_prefix + transport::kPlantOutputChannel;
  lcm_eventlog_t* l = lcm_eventlog_create(lane_file.c_str(), "r");
  if (!l) return out;
  while (lcm_eventlog_event_t* ev = lcm_eventlog_read_next_event(l)) {
    pidlab::lcmt_plant_output m;
    if (channel == ev->channel && m.decode(ev->data, 0, static_cast<int>(ev->datalen)) >= 0)
      seen.emplace(std::make_pair(m.episode_id, m.step), ev->timestamp);
    lcm_eventlog_free_event(ev);
  }
  lcm_eventlog_destroy(l);
  for (const replay::Episode& e : log.episodes) {
    if (!e.Complete()) continue;
    int64_t previous = -1;  // the timestamp of step k - 1, logged or rebuilt
    for (long k = 0; k < e.total_steps; ++k) {
      if (const auto it = seen.find({e.episode_id, k}); it != seen.end()) {
        previous = it->second;
        continue;
      }
      const auto next = seen.lower_bound({e.episode_id, k});
      const bool has_next = next != seen.end() && next->first.first == e.episode_id;
      auto prev = next;
      const bool has_prev = prev != seen.begin() && (--prev)->first.first == e.episode_id;
      if (!has_prev && !has_next) break;  // the lane logger heard nothing of this episode
      int64_t ts;
      if (has_prev && has_next) {
        const double f = static_cast<double>(k - prev->first.second) /
                         static_cast<double>(next->first.second - prev->first.second);
        ts = prev->second + static_cast<int64_t>(f * static_cast<double>(next->second - prev->second));
      } else if (has_prev) {
        ts = prev->second + static_cast<int64_t>((k - prev->first.second) * e.spec.dt_s * 1e6);
      } else {
        ts = next->second - static_cast<int64_t>((next->first.second - k) * e.spec.dt_s * 1e6);
      }
      if (previous >= 0 && ts <= previous) ts = previous + 1;
      previous = ts;
      pidlab::lcmt_plant_output m;
      m.utime = ts;
      m.episode_id = e.episode_id;
      m.step = k;
      m.t_s = static_cast<double>(k) * e.spec.dt_s;
      m.y = e.y[static_cast<std::size_t>(k)];
      std::vector<uint8_t> data(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(data.data(), 0, static_cast<int>(data.size()));
      out.emplace_back(ts, std::move(data));
    }
  }
  return out;
}

namespace {

// MergeEventLogs() with the refusal's message in *error.
bool MergeEventLogsOrExplain(const std::vector<std::string>& inputs, const std::vector<TimedPayload>& extra,
                             const std::string& extra_channel, const std::string& out_file,
                             std::string* error) {
  std::vector<lcm_eventlog_t*> logs;
  bool ok = true;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    lcm_eventlog_t* l = lcm_eventlog_create(inputs[i].c_str(), "r");
    if (!l) {
      if (i == 0) {
        ok = false;
        if (error) *error = "cannot open " + inputs[i] + " to merge into it";
      }
      continue;  // e.g. a lane logger that wrote nothing: nothing to merge
    }
    logs.push_back(l);
  }
  lcm_eventlog_t* out = ok ? lcm_eventlog_create(out_file.c_str(), "w") : nullptr;
  if (ok && !out) {
    ok = false;
    if (error) *error = "cannot write " + out_file;
  }
  if (ok) {
    // A k-way merge by timestamp; each input is in time order already.
    std::vector<lcm_eventlog_event_t*> head(logs.size(), nullptr);
    for (std::size_t i = 0; i < logs.size(); ++i) head[i] = lcm_eventlog_read_next_event(logs[i]);
    std::string channel = extra_channel;
    std::size_t next_extra = 0;
    auto write = [&](lcm_eventlog_event_t* ev) {
      if (ok && lcm_eventlog_write_event(out, ev) != 0) {
        ok = false;
        if (error) *error = "cannot write " + out_file;
      }
    };
    for (;;) {
      std::size_t best = logs.size();
      for (std::size_t i = 0; i < logs.size(); ++i)
        if (head[i] && (best == logs.size() || head[i]->timestamp < head[best]->timestamp)) best = i;
      if (next_extra < extra.size() &&
          (best == logs.size() || extra[next_extra].first < head[best]->timestamp)) {
        const TimedPayload& r = extra[next_extra++];
        lcm_eventlog_event_t ev{};
        ev.timestamp = r.first;
        ev.channellen = static_cast<int32_t>(channel.size());
        ev.datalen = static_cast<int32_t>(r.second.size());
        ev.channel = channel.data();
        ev.data = const_cast<uint8_t*>(r.second.data());
        write(&ev);
        continue;
      }
      if (best == logs.size()) break;
      write(head[best]);
      lcm_eventlog_free_event(head[best]);
      head[best] = lcm_eventlog_read_next_event(logs[best]);
    }
    for (lcm_eventlog_event_t* h : head)
      if (h) lcm_eventlog_free_event(h);
    lcm_eventlog_destroy(out);
  }
  for (lcm_eventlog_t* l : logs) lcm_eventlog_destroy(l);
  if (!ok) std::remove(out_file.c_str());
  return ok;
}

}  // namespace

Status MergeEventLogs(const std::vector<std::string>& inputs, const std::vector<TimedPayload>& extra,
                      const std::string& extra_channel, const std::string& out_file) {
  std::string why;
  if (!MergeEventLogsOrExplain(inputs, extra, extra_channel, out_file, &why)) return Status::IoFailed(why);
  return Status::Ok();
}

std::vector<TimedPayload> LogCapture::MissingLaneOutputs(const std::string& lane_file) const {
  // A controller driven from the log by lcm-logplayer waits for y_k forever
  // if y_k is missing. Authenticated runs are left as they are (the rebuilt
  // messages would carry no tag).
  if (options_.auth_key) return {};
  replay::LogContents log;
  if (!replay::ReadLog(options_.log_file, ReaderOptions(), &log).ok()) return {};
  return RebuildLaneOutputs(log, lane_file, options_.channel_prefix);
}

Status LogCapture::MergeLanes() {
  rebuilt_outputs_ = 0;
  if (lane_loggers_.empty() && restored_.empty()) return Status::Ok();
  for (const auto& [pid, file] : lane_loggers_)
    if (pid > 0 && !supervisor_->StopChild(pid, SIGINT, 3.0)) supervisor_->StopChild(pid, SIGKILL, 1.0);
  std::vector<std::string> inputs{options_.log_file}, beside;
  for (const auto& lane : lane_loggers_) beside.push_back(lane.second);
  std::vector<TimedPayload> rebuilt;
  for (const auto& lane : lane_loggers_)
    if (lane.second == options_.log_file + ".lane" + std::to_string(transport::kPlantOutputLane))
      rebuilt = MissingLaneOutputs(lane.second);
  std::stable_sort(rebuilt.begin(), rebuilt.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  rebuilt_outputs_ = static_cast<long>(rebuilt.size());
  std::string error;
  bool ok = true;
  if (!restored_.empty()) {
    // launch's copies are one more input, as a lane logger's file is.
    const std::string configs = options_.log_file + ".configs";
    const Status written = WriteConfigLog(
        restored_, options_.channel_prefix + transport::kEpisodeConfigChannel, options_.auth_key, configs);
    ok = written.ok();
    if (ok) beside.push_back(configs);
    error = written.message();
  }
  inputs.insert(inputs.end(), beside.begin(), beside.end());
  const std::string merged = options_.log_file + ".merging";
  ok = ok && MergeEventLogsOrExplain(
                 inputs, rebuilt, options_.channel_prefix + transport::kPlantOutputChannel, merged, &error);
  if (ok && std::rename(merged.c_str(), options_.log_file.c_str()) != 0) {
    ok = false;
    error = "cannot rename " + merged + " to " + options_.log_file;
    std::remove(merged.c_str());
  }
  if (ok) {
    for (const std::string& file : beside) std::remove(file.c_str());
  } else if (!beside.empty()) {
    // What the lanes hold exists nowhere else: keep it and say where.
    std::string kept;
    for (const std::string& file : beside) kept += (kept.empty() ? "" : ", ") + file;
    error += "; kept " + kept;
  }
  lane_loggers_.clear();
  restored_.clear();
  return ok ? Status::Ok() : Status::IoFailed(error);
}

bool LogCapture::WaitForMarker(const std::string& what) {
  std::random_device rd;
  const std::string nonce =
      "pidlab-launch-" + what + "-" + std::to_string(getpid()) + "-" + std::to_string(rd());
  pidlab::lcmt_ready m = transport::MakeReady(pidlab::lcmt_ready::MARKER, "launch", 0, nonce);
  const double start = transport::NowSeconds();
  double last = -1;
  while (transport::NowSeconds() - start < options_.marker_timeout_s) {
    if (FileTail(options_.log_file, 1 << 16).find(nonce) != std::string::npos) {
      long size = FileSize(options_.log_file);
      for (int i = 0; i < 100; ++i) {  // stable for 50 ms
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        const long now = FileSize(options_.log_file);
        if (now == size) return true;
        size = now;
      }
      return true;
    }
    if (transport::NowSeconds() - last > 0.2) {
      transport_->Publish(transport::kReadyChannel, &m);
      last = transport::NowSeconds();
    }
    transport_->WaitAndHandle(0.01);
  }
  return false;
}

bool LogCapture::FindGaps(std::vector<Gap>* gaps, std::vector<int64_t>* lost_configs,
                          RepairSummary* summary) {
  replay::LogContents log;
  for (;;) {
    if (const Status st = replay::ReadLog(options_.log_file, ReaderOptions(), &log); !st.ok()) {
      summary->status = RepairStatus::kUnreadable;
      summary->lines.push_back("cannot read " + options_.log_file + " to check it: " + st.message());
      return false;
    }
    // Data in the log of an episode whose configuration is not there, and
    // launch heard it: read again with launch's copy (once per episode).
    bool more = false;
    for (const replay::Episode& e : log.episodes)
      if (!e.has_config && e.config_error.empty() && witness_.Config(e.episode_id))
        more = orphans_with_copy_.insert(e.episode_id).second || more;
    if (!more) break;
  }
  gaps->clear();
  lost_configs->clear();
  restored_.clear();
  std::set<int64_t> listed;
  long orphans = 0;
  for (const replay::Episode& e : log.episodes) {
    listed.insert(e.episode_id);
    if (e.config_supplied) restored_.push_back(e.config);
    if (!e.has_config) {
      // The plant ended it: ours, and nothing holds its configuration.
      // Otherwise steps without a configuration: a stranger's messages,
      // which must not be able to make the log fail: noted, not repaired.
      if (witness_.Ended(e.episode_id))
        lost_configs->push_back(e.episode_id);
      else
        ++orphans;
      continue;
    }
    if (e.Complete()) continue;
    if (e.has_summary && e.summary_status == pidlab::lcmt_episode_summary::FAILED) continue;
    gaps->push_back({e.episode_id, MissingSteps(e)});
  }
  for (const int64_t id : witness_.ended())
    if (!listed.count(id)) lost_configs->push_back(id);  // nothing of it in the log, no copy here
  if (orphans > 0 && !noted_orphans_) {
    noted_orphans_ = true;
    summary->notes.push_back(std::to_string(orphans) + " episode id(s) in " + options_.log_file +
                             " have no configuration there and were not run by this trio (a stranger's "
                             "messages); left as they are (pidlab replay lists them)");
  }
  return true;
}

void LogCapture::AskForGaps(const std::vector<Gap>& gaps, RepairSummary* summary) {
  // Every missing range, paced so that the answers (up to 48 kB each) do not
  // overflow the logger's socket in one burst.
  asked_.clear();
  for (const Gap& g : gaps) {
    summary->republished[g.id] += CountSteps(g.ranges);
    for (const auto& r : g.ranges) {
      for (long first = r.first; first <= r.second; first += transport::kMaxTrajectoryChunk) {
        pidlab::lcmt_trajectory_request req;
        req.episode_id = g.id;
        req.step = first;
        req.count = static_cast<int32_t>(std::min(transport::kMaxTrajectoryChunk, r.second - first + 1));
        answers_.erase({g.id, first});
        asked_.emplace_back(g.id, first);
        transport_->Publish(transport::kTrajectoryRequestChannel, &req);
        transport_->WaitAndHandle(0.005);
      }
    }
  }
  // Wait (bounded) until this process heard every answer; the caller's
  // marker then makes sure whatever the logger received is on disk.
  const double t0 = transport::NowSeconds();
  for (;;) {
    bool all = true;
    for (const auto& key : asked_) all = all && answers_.count(key);
    if (all || transport::NowSeconds() - t0 > 1.0) break;
    transport_->WaitAndHandle(0.01);
  }
}

void LogCapture::DescribeUnrepaired(const std::vector<Gap>& gaps, RepairSummary* summary) const {
  for (const Gap& g : gaps) {
    bool answered = true;
    for (const auto& r : g.ranges)
      for (long first = r.first; first <= r.second; first += transport::kMaxTrajectoryChunk)
        answered = answered && answers_.count({g.id, first});
    std::ostringstream os;
    // The cause before the ranges: a long list is what a 300-character line cuts.
    os << options_.log_file << " is incomplete: episode " << g.id << " misses " << CountSteps(g.ranges)
       << " steps after " << options_.repair_rounds << " repair rounds, "
       << (answered ? "lcm-logger lost the plant's trajectory chunks every time"
                    : "pidlab-plant did not resend them (gone from its history, or dead)")
       << ": " << RangesText(g.ranges, 4);
    summary->lines.push_back(os.str());
  }
}

void LogCapture::Conclude(const std::vector<Gap>& gaps, const std::vector<int64_t>& lost_configs,
                          RepairSummary* summary) const {
  for (const auto& config : restored_) summary->restored.push_back(config.episode_id);
  summary->lost_configs = lost_configs;
  if (!lost_configs.empty()) {
    summary->status = RepairStatus::kIncomplete;
    summary->lines.push_back(options_.log_file + " is incomplete: the configuration of episode" +
                             (lost_configs.size() == 1 ? " " : "s ") + EpisodeList(lost_configs) +
                             ", which pidlab-plant ran, is not in it: lcm-logger lost every copy and "
                             "launch heard none");
  }
  if (!gaps.empty()) {
    summary->status = RepairStatus::kIncomplete;
    DescribeUnrepaired(gaps, summary);
  }
  if (summary->status == RepairStatus::kIncomplete) return;
  if (!restored_.empty()) {
    summary->status = RepairStatus::kRepaired;
    summary->lines.push_back(
        "lcm-logger lost the configuration of episode" + std::string(restored_.size() == 1 ? " " : "s ") +
        EpisodeList(summary->restored) + "; " + options_.log_file + " gets launch's own copy");
  }
  if (summary->republished.empty()) return;
  summary->status = RepairStatus::kRepaired;
  std::ostringstream os;
  os << "lcm-logger lost messages; repaired " << options_.log_file << " from the plant's trajectory chunks:";
  for (const auto& [id, n] : summary->republished) os << " episode " << id << " (" << n << " steps)";
  os << " in " << summary->rounds << " round" << (summary->rounds == 1 ? "" : "s");
  summary->lines.push_back(os.str());
}

RepairSummary LogCapture::Repair() {
  if (!listening_) {
    transport_->Subscribe<pidlab::lcmt_trajectory_chunk>(transport::kTrajectoryChannel,
                                                         [this](const pidlab::lcmt_trajectory_chunk& c) {
                                                           answers_[{c.episode_id, c.step}] = c.count;
                                                         });
    listening_ = true;
  }
  RepairSummary summary;
  for (int round = 0;; ++round) {
    summary.rounds = round;
    std::vector<Gap> gaps;
    std::vector<int64_t> lost_configs;
    if (!FindGaps(&gaps, &lost_configs, &summary)) return summary;
    if (gaps.empty() || round == options_.repair_rounds) {
      Conclude(gaps, lost_configs, &summary);
      return summary;
    }
    AskForGaps(gaps, &summary);
    if (!WaitForMarker("repair" + std::to_string(round))) {
      summary.status = RepairStatus::kUnreadable;
      summary.lines.push_back("lcm-logger stopped writing " + options_.log_file + " during its repair");
      return summary;
    }
  }
}

}  // namespace pidlab::launcher
