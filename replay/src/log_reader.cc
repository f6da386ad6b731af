#include "pidlab/replay/log_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <set>
#include <sstream>

namespace pidlab::replay {
namespace {

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Walks the wire layout of a message before the generated decoder sees it:
// the generated code trusts string lengths and array sizes (a negative or huge
// one from a corrupt or hostile payload would read out of bounds or allocate
// gigabytes), so every variable-length field is bounded here first.
class LayoutCheck {
 public:
  LayoutCheck(const uint8_t* data, int size) : data_(data), size_(size) {}
  LayoutCheck& Fixed(int bytes) {
    if (ok_ && size_ - pos_ >= bytes)
      pos_ += bytes;
    else
      ok_ = false;
    return *this;
  }
  LayoutCheck& String() {
    int32_t len = 0;
    if (!ReadInt32(&len) || len < 1 || len > size_ - pos_ || data_[pos_ + len - 1] != 0)
      ok_ = false;
    else
      pos_ += len;
    return *this;
  }
  /// An int32 element count followed by count * element_bytes (several arrays
  /// of the same count: element_bytes is their sum).
  LayoutCheck& Array(int element_bytes) {
    int32_t count = 0;
    if (!ReadInt32(&count) || count < 0 || static_cast<long long>(count) * element_bytes > size_ - pos_)
      ok_ = false;
    else
      pos_ += count * element_bytes;
    return *this;
  }
  bool ok() const { return ok_; }

 private:
  bool ReadInt32(int32_t* v) {
    if (!ok_ || size_ - pos_ < 4) return false;
    const uint8_t* p = data_ + pos_;
    *v = static_cast<int32_t>((uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]);
    pos_ += 4;
    return true;
  }
  const uint8_t* data_;
  int size_;
  int pos_ = 8;  // after the fingerprint
  bool ok_ = true;
};

constexpr int kHeader = 24;  // utime, episode_id, step

bool LayoutOk(const std::string& type, const uint8_t* d, int n) {
  LayoutCheck c(d, n);
  c.Fixed(kHeader);
  if (type == "lcmt_episode_config") {
    c.String()
        .Array(8)
        .Array(8)
        .Fixed(7 * 8)
        .String()
        .Fixed(8)
        .String()
        .String()
        .Fixed(4 * 8)
        .String()
        .Fixed(6 * 8)
        .Fixed(2 * 8);
  } else if (type == "lcmt_ready") {
    c.Fixed(1).String().Fixed(4).String();
  } else if (type == "lcmt_episode_summary") {
    c.Fixed(1).Fixed(8).Fixed(8).String().String();
  } else if (type == "lcmt_trajectory_chunk") {
    c.Array(3 * 8);
  } else if (type == "lcmt_disturbance_block") {
    c.Fixed(8).Array(8);
  }
  return c.ok();
}

struct KnownType {
  const char* name;
  const char* suffix;  // channel name without the prefix
  int64_t hash;
};

std::vector<KnownType> KnownTypes() {
  return {
      {"lcmt_episode_config", "EPISODE_CONFIG", pidlab::lcmt_episode_config::getHash()},
      {"lcmt_ready", "READY", pidlab::lcmt_ready::getHash()},
      {"lcmt_plant_output", "PLANT_OUTPUT", pidlab::lcmt_plant_output::getHash()},
      {"lcmt_control_command", "CONTROL", pidlab::lcmt_control_command::getHash()},
      {"lcmt_disturbance_sample", "DISTURBANCE", pidlab::lcmt_disturbance_sample::getHash()},  // older logs
      {"lcmt_disturbance_block", "DISTURBANCE_BLOCK", pidlab::lcmt_disturbance_block::getHash()},
      {"lcmt_disturbance_request", "DISTURBANCE_REQUEST", pidlab::lcmt_disturbance_request::getHash()},
      {"lcmt_episode_summary", "SUMMARY", pidlab::lcmt_episode_summary::getHash()},
      {"lcmt_trajectory_request", "TRAJECTORY_REQUEST", pidlab::lcmt_trajectory_request::getHash()},
      {"lcmt_trajectory_chunk", "TRAJECTORY", pidlab::lcmt_trajectory_chunk::getHash()},
  };
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Per-step values of one stream, as first received, plus what happened.
struct StepRecord {
  double a = 0, b = 0, c = 0;
  int status = -1;
};
struct Stream {
  std::map<long, StepRecord> steps;
  long duplicates = 0, conflicts = 0, out_of_order = 0, max_seen = -1;
  void Add(long k, const StepRecord& r) {
    auto it = steps.find(k);
    if (it == steps.end()) {
      if (k < max_seen) ++out_of_order;
      max_seen = std::max(max_seen, k);
      steps.emplace(k, r);
    } else if (SameBits(it->second.a, r.a) && SameBits(it->second.b, r.b) && SameBits(it->second.c, r.c) &&
               it->second.status == r.status) {
      ++duplicates;
    } else {
      ++conflicts;
    }
  }
};

struct Building {
  Episode episode;
  bool config_conflict = false;
  pidlab::lcmt_episode_config config;
  Stream outputs, commands, disturbances;
  std::map<long, StepRecord> chunks;  // y, u, n from the plant's trajectory chunks
};

// A bounded list of examples for the notes.
struct Tally {
  long count = 0;
  std::set<std::string> examples;
  void Add(const std::string& example) {
    ++count;
    if (examples.size() < 4) examples.insert(example);
  }
  std::string Examples() const {
    std::string s;
    for (const auto& e : examples) s += (s.empty() ? "" : ", ") + e;
    return s;
  }
};

StreamStats Finish(const Stream& s, long expected_first, long expected_last, long filled) {
  StreamStats st;
  st.expected = expected_last - expected_first + 1;
  st.duplicates = s.duplicates;
  st.conflicts = s.conflicts;
  st.out_of_order = s.out_of_order;
  st.filled_from_chunks = filled;
  for (const auto& [k, r] : s.steps) {
    (void)r;
    if (k < expected_first || k > expected_last)
      ++st.beyond_end;
    else
      ++st.received;
  }
  return st;
}

void MissingRanges(const std::vector<char>& have, long first, long last, StreamStats* st) {
  for (long k = first; k <= last; ++k) {
    if (have[static_cast<std::size_t>(k)]) continue;
    if (!st->missing.empty() && st->missing.back().second == k - 1)
      st->missing.back().second = k;
    else
      st->missing.push_back({k, k});
  }
}

std::string Ranges(const std::vector<std::pair<long, long>>& r) {
  std::ostringstream os;
  for (std::size_t i = 0; i < r.size() && i < 5; ++i) {
    if (i) os << ",";
    os << r[i].first;
    if (r[i].second != r[i].first) os << "-" << r[i].second;
  }
  if (r.size() > 5) os << ",...";
  return os.str();
}

// Offset of the next event marker (0xEDA1DA01) at or after `from`, -1 if none.
long NextMarker(FILE* f, long from) {
  if (std::fseek(f, from, SEEK_SET) != 0) return -1;
  uint32_t window = 0;
  long pos = from;
  for (int c; (c = std::fgetc(f)) != EOF; ++pos) {
    window = (window << 8) | static_cast<uint32_t>(c);
    if (pos - from >= 3 && window == 0xEDA1DA01u) return pos - 3;
  }
  std::clearerr(f);
  return -1;
}

// One event read without LCM, for the events LCM's reader refuses.
struct RawEvent {
  int64_t eventnum = 0;
  std::string channel;
  std::vector<uint8_t> data;
  long bytes = 0;  // whole event on disk
};

// Reads the event whose marker is at `at` if it lies wholly inside the file
// and its lengths are sane (LCM's limits: channel 1..999 bytes).
bool ReadRawEvent(FILE* f, long at, long file_bytes, RawEvent* ev) {
  uint8_t h[28];
  if (std::fseek(f, at, SEEK_SET) != 0 || std::fread(h, 1, sizeof h, f) != sizeof h) return false;
  auto be = [&h](int from, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | h[from + i];
    return v;
  };
  if (be(0, 4) != 0xEDA1DA01u) return false;
  const auto channel_len = static_cast<int32_t>(be(20, 4));
  const auto data_len = static_cast<int32_t>(be(24, 4));
  if (channel_len <= 0 || channel_len >= 1000 || data_len < 0) return false;
  if (static_cast<long long>(at) + 28 + channel_len + data_len > file_bytes) return false;
  ev->eventnum = static_cast<int64_t>(be(4, 8));
  ev->channel.resize(static_cast<std::size_t>(channel_len));
  ev->data.resize(static_cast<std::size_t>(data_len));
  if (std::fread(&ev->channel[0], 1, ev->channel.size(), f) != ev->channel.size()) return false;
  if (data_len > 0 && std::fread(ev->data.data(), 1, ev->data.size(), f) != ev->data.size()) return false;
  ev->bytes = 28 + channel_len + data_len;
  return true;
}

}  // namespace

long StreamStats::MissingCount() const {
  long n = 0;
  for (const auto& [a, b] : missing) n += b - a + 1;
  return n;
}

bool Episode::Complete() const {
  return has_config && outputs.missing.empty() && commands.missing.empty() && disturbances.missing.empty();
}

std::string Episode::CompletenessNote() const {
  if (!has_config)
    return config_error.empty() ? "no episode configuration in the log"
                                : "invalid configuration: " + config_error;
  std::ostringstream os;
  auto stream = [&os](const char* what, const StreamStats& s) {
    if (s.missing.empty()) return;
    if (os.tellp() > 0) os << "; ";
    os << s.MissingCount() << " of " << s.expected << " " << what << " missing (steps " << Ranges(s.missing)
       << ")";
  };
  stream("plant outputs", outputs);
  stream("commands", commands);
  stream("disturbance samples", disturbances);
  return os.str();
}

bool ReadLog(const std::string& path, const ReadOptions& options, LogContents* out, std::string* error) {
  *out = LogContents();
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) {
    if (error) *error = "log '" + path + "' cannot be opened: " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    if (error) *error = "log '" + path + "' is not a regular file";
    return false;
  }
  out->file_bytes = st.st_size;
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    if (error) *error = "log '" + path + "' cannot be opened as an LCM log";
    return false;
  }
  const std::vector<KnownType> known = KnownTypes();
  std::map<std::pair<std::string, int64_t>, std::size_t> index;
  std::vector<Building> building;
  Tally foreign, unknown_type, decode_failed, other_prefix, orphans, unreadable;
  std::set<std::string> foreign_channels;
  int64_t last_eventnum = -1;
  FILE* f = log.getFilePtr();

  auto episode_of = [&](const std::string& prefix, int64_t id) -> Building& {
    const auto key = std::make_pair(prefix, id);
    auto it = index.find(key);
    if (it != index.end()) return building[it->second];
    index.emplace(key, building.size());
    building.emplace_back();
    building.back().episode.prefix = prefix;
    building.back().episode.episode_id = id;
    return building.back();
  };

  auto handle = [&](int64_t eventnum, const std::string& channel, const uint8_t* data, int size) {
    ++out->events;
    if (last_eventnum >= 0 && eventnum != last_eventnum + 1) ++out->eventnum_gaps;
    last_eventnum = eventnum;
    if (channel == "LCM_SELF_TEST") {
      ++out->self_test;
      return;
    }
    int64_t hash = 0;
    if (size >= 8) {
      uint64_t h = 0;
      for (int i = 0; i < 8; ++i) h = (h << 8) | data[i];
      hash = static_cast<int64_t>(h);
    }
    const KnownType* type = nullptr;
    for (const auto& t : known)
      if (size >= 8 && t.hash == hash) type = &t;
    if (!type) {
      bool pidlab_like = false;
      for (const auto& t : known) pidlab_like = pidlab_like || EndsWith(channel, t.suffix);
      if (pidlab_like && size < 8) {
        decode_failed.Add(channel + " (" + std::to_string(size) + " bytes: too short for a fingerprint)");
      } else if (pidlab_like) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(hash));
        unknown_type.Add(channel + " (fingerprint " + std::string(buf) + ")");
      } else {
        foreign.Add(channel);
      }
      return;
    }
    std::string prefix = EndsWith(channel, type->suffix)
                             ? channel.substr(0, channel.size() - std::strlen(type->suffix))
                             : channel + "/";
    // A pidlab type on the TRAJECTORY_REQUEST channel must not be taken for
    // a chunk on "<prefix>_REQUEST"-like names: the fingerprint decides the
    // type, the suffix only the prefix.
    if (!options.channel_prefix.empty() && prefix != options.channel_prefix) {
      other_prefix.Add(prefix.empty() ? "(none)" : prefix);
      return;
    }
    auto decode = [&](auto* msg) {
      if (!LayoutOk(type->name, data, size)) return false;
      try {
        return msg->decode(data, 0, size) == size;
      } catch (const std::exception&) {
        return false;
      }
    };
    const std::string name = type->name;
    bool ok = true;
    if (name == "lcmt_episode_config") {
      pidlab::lcmt_episode_config m{};
      if ((ok = decode(&m))) {
        Building& b = episode_of(prefix, m.episode_id);
        if (!b.episode.has_config && b.episode.config_error.empty()) {
          b.config = m;
          std::string err;
          if (transport::ParseEpisodeConfig(m, &b.episode.spec, &err))
            b.episode.has_config = true;
          else
            b.episode.config_error = err;
        } else {
          std::vector<uint8_t> x(static_cast<std::size_t>(m.getEncodedSize())), y(x.size());
          pidlab::lcmt_episode_config a = m, c = b.config;
          a.utime = c.utime = 0;
          if (a.getEncodedSize() != c.getEncodedSize())
            b.config_conflict = true;
          else {
            a.encode(x.data(), 0, static_cast<int>(x.size()));
            c.encode(y.data(), 0, static_cast<int>(y.size()));
            if (x != y) b.config_conflict = true;
          }
        }
      }
    } else if (name == "lcmt_plant_output") {
      pidlab::lcmt_plant_output m{};
      if ((ok = decode(&m))) episode_of(prefix, m.episode_id).outputs.Add(m.step, {m.y, m.t_s, 0, -1});
    } else if (name == "lcmt_control_command") {
      pidlab::lcmt_control_command m{};
      if ((ok = decode(&m))) episode_of(prefix, m.episode_id).commands.Add(m.step, {m.u, m.y, m.r, m.status});
    } else if (name == "lcmt_disturbance_sample") {
      pidlab::lcmt_disturbance_sample m{};
      if ((ok = decode(&m))) episode_of(prefix, m.episode_id).disturbances.Add(m.step, {m.n, m.t_s, 0, -1});
    } else if (name == "lcmt_disturbance_block") {
      // n_k for k in [step, step + count): each sample counts as the step's
      // disturbance sample (a resent block gives duplicates, as resent samples did).
      pidlab::lcmt_disturbance_block m{};
      if ((ok = decode(&m))) {
        Stream& d = episode_of(prefix, m.episode_id).disturbances;
        for (int32_t i = 0; i < m.count; ++i) {
          const long k = static_cast<long>(m.step) + i;
          d.Add(k, {m.n[static_cast<std::size_t>(i)], static_cast<double>(k) * m.dt_s, 0, -1});
        }
      }
    } else if (name == "lcmt_episode_summary") {
      pidlab::lcmt_episode_summary m{};
      if ((ok = decode(&m))) {
        Episode& e = episode_of(prefix, m.episode_id).episode;
        e.has_summary = true;
        e.summary_status = m.status;
        e.summary_step = static_cast<long>(m.step);
        e.summary_message = m.message;
      }
    } else if (name == "lcmt_trajectory_chunk") {
      pidlab::lcmt_trajectory_chunk m{};
      if ((ok = decode(&m))) {
        Building& b = episode_of(prefix, m.episode_id);
        for (int32_t i = 0; i < m.count; ++i)
          b.chunks.emplace(static_cast<long>(m.step) + i, StepRecord{m.y[i], m.u[i], m.n[i], -1});
      }
    } else if (name == "lcmt_ready") {
      pidlab::lcmt_ready m{};
      ok = decode(&m);
    } else if (name == "lcmt_trajectory_request") {
      pidlab::lcmt_trajectory_request m{};
      ok = decode(&m);
    } else if (name == "lcmt_disturbance_request") {
      pidlab::lcmt_disturbance_request m{};
      ok = decode(&m);
    }
    if (!ok) {
      decode_failed.Add(channel + " (" + name + ", " + std::to_string(size) + " bytes)");
      return;
    }
    ++out->pidlab_messages;
  };

  auto garbage = [&](long from, long to) {
    out->clean_end = false;
    std::ostringstream os;
    os << "bytes " << from << ".." << to - 1 << " between events are garbage; skipped";
    unreadable.Add(os.str());
  };
  for (;;) {
    const long start = std::ftell(f);
    const lcm::LogEvent* ev = start >= 0 && start < out->file_bytes ? log.readNextEvent() : nullptr;
    if (ev) {
      const long end = std::ftell(f);
      const long event_bytes = 4 + 8 + 8 + 4 + 4 + static_cast<long>(ev->channel.size()) + ev->datalen;
      if (end - start > event_bytes) garbage(start, end - event_bytes);
      out->bytes_read = end;
      handle(ev->eventnum, ev->channel, static_cast<const uint8_t*>(ev->data), ev->datalen);
      continue;
    }
    if (start < 0 || start >= out->file_bytes) break;
    // LCM refuses an event that is not followed by another event marker (or
    // the end of the file), and an event cut off or with a bad header. Read
    // the event ourselves if it is whole, then resume at the next marker.
    out->clean_end = false;
    std::clearerr(f);
    const long at = NextMarker(f, start);
    RawEvent raw;
    if (at >= 0 && ReadRawEvent(f, at, out->file_bytes, &raw)) {
      if (at > start) garbage(start, at);
      const long end = at + raw.bytes;
      out->bytes_read = end;
      handle(raw.eventnum, raw.channel, raw.data.data(), static_cast<int>(raw.data.size()));
      const long next = NextMarker(f, end);
      if (next > end) garbage(end, next);
      if (next < 0 && end < out->file_bytes) garbage(end, out->file_bytes);
      if (next < 0 || std::fseek(f, next, SEEK_SET) != 0) break;
      continue;
    }
    const long next = NextMarker(f, (at >= 0 ? at : start) + 1);
    std::ostringstream os;
    if (next < 0) {
      os << "the log ends with " << (out->file_bytes - start)
         << " bytes that are not a complete event (from byte " << start
         << "): it was cut off mid-write or its tail is corrupt; everything before was read";
      out->notes.push_back(os.str());
      out->bytes_read = start;
      break;
    }
    os << "bytes " << start << ".." << next - 1 << " are not a readable event (corrupt); skipped";
    unreadable.Add(os.str());
    if (std::fseek(f, next, SEEK_SET) != 0) break;
  }

  // Assemble the episodes.
  for (Building& b : building) {
    Episode& e = b.episode;
    const bool has_data =
        !b.outputs.steps.empty() || !b.commands.steps.empty() || !b.disturbances.steps.empty();
    if (!e.has_config && e.config_error.empty() && !has_data) continue;  // acks, summaries, chunks only
    long total = 0;
    if (e.has_config) {
      total = e.spec.total_steps;
    } else {
      for (const Stream* s : {&b.outputs, &b.commands, &b.disturbances})
        if (!s->steps.empty()) total = std::max(total, s->steps.rbegin()->first);
      orphans.Add(e.prefix + " episode " + std::to_string(e.episode_id));
    }
    const auto size = static_cast<std::size_t>(total + 1);
    e.total_steps = total;
    e.y.assign(size, std::nan(""));
    e.u.assign(size, std::nan(""));
    e.n.assign(size, std::nan(""));
    e.u_input_y.assign(size, std::nan(""));
    e.status.assign(size, -1);
    e.has_y.assign(size, 0);
    e.has_u.assign(size, 0);
    e.has_n.assign(size, 0);
    auto in = [total](long k) { return k >= 0 && k <= total; };
    for (const auto& [k, r] : b.outputs.steps)
      if (in(k)) e.y[k] = r.a, e.has_y[k] = 1;
    for (const auto& [k, r] : b.commands.steps)
      if (in(k) && k < total) e.u[k] = r.a, e.u_input_y[k] = r.b, e.status[k] = r.status, e.has_u[k] = 1;
    for (const auto& [k, r] : b.disturbances.steps)
      if (in(k) && k < total) e.n[k] = r.a, e.has_n[k] = 1;
    long fill_y = 0, fill_u = 0, fill_n = 0;
    for (const auto& [k, r] : b.chunks) {
      if (!in(k)) continue;
      if (!e.has_y[k] && std::isfinite(r.a)) e.y[k] = r.a, e.has_y[k] = 1, ++fill_y;
      if (k < total && !e.has_u[k] && std::isfinite(r.b)) e.u[k] = r.b, e.has_u[k] = 1, ++fill_u;
      if (k < total && !e.has_n[k] && std::isfinite(r.c)) e.n[k] = r.c, e.has_n[k] = 1, ++fill_n;
    }
    e.outputs = Finish(b.outputs, 0, total, fill_y);
    e.commands = Finish(b.commands, 0, total - 1, fill_u);
    e.disturbances = Finish(b.disturbances, 0, total - 1, fill_n);
    MissingRanges(e.has_y, 0, total, &e.outputs);
    MissingRanges(e.has_u, 0, total - 1, &e.commands);
    MissingRanges(e.has_n, 0, total - 1, &e.disturbances);
    if (b.config_conflict)
      out->notes.push_back(
          e.prefix + " episode " + std::to_string(e.episode_id) +
          ": the configuration was logged more than once with different content; the first is used");
    out->episodes.push_back(std::move(e));
  }

  out->foreign = foreign.count;
  out->unknown_type = unknown_type.count;
  out->decode_failures = decode_failed.count;
  out->other_prefix = other_prefix.count;
  out->orphan_messages = orphans.count;
  auto note = [out](const Tally& t, const std::string& what) {
    if (t.count) out->notes.push_back(std::to_string(t.count) + " " + what + ": " + t.Examples());
  };
  note(foreign, "events on non-pidlab channels ignored");
  note(unknown_type,
       "events on pidlab-named channels with an unknown fingerprint (a changed or foreign type) ignored");
  note(decode_failed, "pidlab events that do not decode (corrupt payload) ignored");
  note(other_prefix, "pidlab events of other channel prefixes skipped");
  note(orphans, "episodes whose configuration is not in the log (listed, not evaluated)");
  note(unreadable, "unreadable stretches skipped, reading resumed at the next event marker");
  if (out->self_test) out->notes.push_back(std::to_string(out->self_test) + " LCM self-test events ignored");
  if (out->events == 0 && out->file_bytes > 0) {
    if (error) *error = "'" + path + "' holds no LCM log event (not an LCM log?)";
    return false;
  }
  return true;
}

}  // namespace pidlab::replay
