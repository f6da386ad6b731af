// log_mutator: damaged and hostile LCM logs against `pidlab replay`, for
// tests/hostile/log_mutants_test.sh and bench/log_mutants_bench.sh.
//
// It reads one or more clean seed logs (lcm-logger's format: per event a
// big-endian sync word 0xEDA1DA01, int64 eventnum, int64 timestamp, int32
// channel length, int32 data length, the channel, the data) and writes
// --count mutants, seeded (std::mt19937_64, one generator per mutant, so
// `--only I` reproduces mutant I), each mutation class used in turn:
//   bitflip          1..16 bit flips (a quarter of them in event headers)
//   truncate         the file cut at a random offset (0, mid-header, mid-event)
//   data-length      an event's data length set to 0x7fffffff, negative, -1,
//                    64 MiB + 1, a little too long, random
//   channel-length   an event's channel length set to 0x7fffffff, -1, 0, 257,
//                    random
//   eventnum         eventnums set to INT64_MAX, INT64_MIN, -1, random, or a
//                    run counting up through INT64_MAX
//   reorder          swapped, reversed, shuffled or rotated events; the
//                    configurations moved to the end
//   dup-drop         duplicated and dropped events, dropped configurations
//   insert-bytes     random bytes, and fake event headers, inserted
//   channel-names    non-UTF-8 and control bytes in channel names (kept or
//                    breaking the pidlab suffix), empty and 256-byte names
//   payload-words    big-endian int64 words after the 8-byte fingerprint
//                    (utime, episode id, step, ...) set to 5e7, 2^40,
//                    INT64_MAX, INT64_MIN, -1, random; orphans of an unknown
//                    episode at a huge step; int32 array/string lengths
//   splice           the first part of one log and the last part of another
//   combination      2..4 of the above, event-level changes first
// and runs `PIDLAB replay MUTANT` on each (every second one with --json),
// fork/exec, stdout and stderr to files, a per-run timeout (a kill, counted
// as a hang), an RSS watchdog, wait4() for each child's peak RSS. A run
// passes if it was not killed by a signal, exited 0 or 1, wrote at most one
// line to stderr (exactly one non-empty line of at most --max-line chars on
// exit 1), no sanitizer report, with --json and exit 0 a single line that is
// a JSON object, and stayed under --max-rss-mb. One summary line, one line
// per failure (the mutant is kept); exit 1 on any failure, 2 on bad flags.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using Bytes = std::vector<uint8_t>;
using Clock = std::chrono::steady_clock;

constexpr uint32_t kSyncWord = 0xEDA1DA01u;
constexpr std::size_t kHeaderBytes = 28;
constexpr int64_t kI64Max = std::numeric_limits<int64_t>::max();
constexpr int64_t kI64Min = std::numeric_limits<int64_t>::min();

// ---- The log format

struct Event {
  int64_t eventnum = 0, timestamp = 0;
  std::string channel;
  Bytes data;
};

uint64_t GetBE(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

void PutBE(uint8_t* p, uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
}

void AppendBE(Bytes* b, uint64_t v, int n) {
  b->resize(b->size() + static_cast<std::size_t>(n));
  PutBE(b->data() + b->size() - static_cast<std::size_t>(n), v, n);
}

// The events of a clean log; false (with *error) at the first damage.
bool ParseLog(const Bytes& file, std::vector<Event>* events, std::string* error) {
  std::size_t at = 0;
  while (at < file.size()) {
    if (file.size() - at < kHeaderBytes || GetBE(&file[at], 4) != kSyncWord) {
      *error = "no event header at byte " + std::to_string(at);
      return false;
    }
    Event e;
    e.eventnum = static_cast<int64_t>(GetBE(&file[at + 4], 8));
    e.timestamp = static_cast<int64_t>(GetBE(&file[at + 12], 8));
    const uint64_t channel = GetBE(&file[at + 20], 4), data = GetBE(&file[at + 24], 4);
    if (channel + data > file.size() - at - kHeaderBytes) {
      *error = "the event at byte " + std::to_string(at) + " runs past the end of the file";
      return false;
    }
    const auto* p = file.data() + at + kHeaderBytes;
    e.channel.assign(reinterpret_cast<const char*>(p), channel);
    e.data.assign(p + channel, p + channel + data);
    events->push_back(std::move(e));
    at += kHeaderBytes + channel + data;
  }
  return true;
}

// The file of `events`, and where each event starts.
Bytes Serialize(const std::vector<Event>& events, std::vector<std::size_t>* offsets) {
  Bytes b;
  offsets->clear();
  for (const Event& e : events) {
    offsets->push_back(b.size());
    AppendBE(&b, kSyncWord, 4);
    AppendBE(&b, static_cast<uint64_t>(e.eventnum), 8);
    AppendBE(&b, static_cast<uint64_t>(e.timestamp), 8);
    AppendBE(&b, e.channel.size(), 4);
    AppendBE(&b, e.data.size(), 4);
    b.insert(b.end(), e.channel.begin(), e.channel.end());
    b.insert(b.end(), e.data.begin(), e.data.end());
  }
  return b;
}

struct Seed {
  std::string path;
  Bytes bytes;
  std::vector<Event> events;
  std::vector<std::size_t> offsets;
};

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string Hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%" PRIx64, v);
  return buf;
}

// ---- Mutation classes

enum Class {
  kBitflip,
  kTruncate,
  kDataLength,
  kChannelLength,
  kEventnum,
  kReorder,
  kDupDrop,
  kInsertBytes,
  kChannelNames,
  kPayloadWords,
  kSplice,
  kCombination,
  kClassCount
};
const char* const kClassNames[kClassCount] = {
    "bitflip",  "truncate",     "data-length",   "channel-length", "eventnum", "reorder",
    "dup-drop", "insert-bytes", "channel-names", "payload-words",  "splice",   "combination"};

// When a class applies inside a combination: event-level changes, then
// header fields (offsets still valid), then byte-level damage.
int Stage(int c) {
  switch (c) {
    case kEventnum:
    case kReorder:
    case kDupDrop:
    case kChannelNames:
    case kPayloadWords:
      return 0;
    case kDataLength:
    case kChannelLength:
      return 1;
    case kBitflip:
      return 2;
    case kInsertBytes:
      return 3;
    default:  // truncate, splice
      return 4;
  }
}

// One mutant in the making: its events until the first byte-level change,
// then its bytes (with the event offsets of the last serialization).
struct Work {
  std::vector<Event> events;
  Bytes bytes;
  std::vector<std::size_t> offsets;
  bool serialized = false;
  std::vector<std::string> what;
};

class Mutator {
 public:
  Mutator(const std::vector<Seed>* seeds, uint64_t seed, long index) : seeds_(seeds) {
    const auto i = static_cast<uint64_t>(index);  // seed_seq keeps 32 bits a value
    std::seed_seq seq{seed & 0xffffffffu, seed >> 32, i & 0xffffffffu, i >> 32, uint64_t{0x6c6f67}};
    rng_.seed(seq);
  }

  // The mutant of class c and what was done to it.
  Bytes Make(int c, std::string* what) {
    const Seed& s = Pick(*seeds_);
    Work w;
    w.events = s.events;
    if (c == kCombination) {
      std::vector<int> classes;
      const int n = static_cast<int>(Uniform(2, 4));
      while (static_cast<int>(classes.size()) < n) {
        const int k = static_cast<int>(Uniform(0, kCombination - 1));
        if (std::find(classes.begin(), classes.end(), k) == classes.end()) classes.push_back(k);
      }
      std::stable_sort(classes.begin(), classes.end(), [](int a, int b) { return Stage(a) < Stage(b); });
      for (int k : classes) Apply(k, &w);
    } else {
      Apply(c, &w);
    }
    Bytes out = Bytes(Ensure(&w));
    std::string text;
    for (const std::string& step : w.what) text += (text.empty() ? "" : "; ") + step;
    if (s.path.size() && seeds_->size() > 1) text = s.path.substr(s.path.find_last_of('/') + 1) + ": " + text;
    *what = text.size() > 240 ? text.substr(0, 237) + "..." : text;
    return out;
  }

 private:
  uint64_t Uniform(uint64_t lo, uint64_t hi) { return std::uniform_int_distribution<uint64_t>(lo, hi)(rng_); }
  bool Chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  template <typename T>
  const T& Pick(const std::vector<T>& v) {
    return v[Uniform(0, v.size() - 1)];
  }
  std::size_t Index(std::size_t n) { return static_cast<std::size_t>(Uniform(0, n - 1)); }

  Bytes& Ensure(Work* w) {
    if (!w->serialized) {
      w->bytes = Serialize(w->events, &w->offsets);
      w->serialized = true;
    }
    return w->bytes;
  }

  // Event-level classes need the events: once bytes are damaged they apply
  // to what can still be parsed (a combination orders them first anyway).
  void Apply(int c, Work* w) {
    if (Stage(c) == 0 && w->serialized) {
      std::vector<Event> events;
      std::string ignored;
      if (!ParseLog(w->bytes, &events, &ignored)) return;
      w->events = std::move(events);
      w->serialized = false;
    }
    if (Stage(c) == 0 && w->events.empty()) return;
    switch (c) {
      case kBitflip:
        return Bitflip(w);
      case kTruncate:
        return Truncate(w);
      case kDataLength:
        return LengthField(w, 24, "data");
      case kChannelLength:
        return LengthField(w, 20, "channel");
      case kEventnum:
        return Eventnum(w);
      case kReorder:
        return Reorder(w);
      case kDupDrop:
        return DupDrop(w);
      case kInsertBytes:
        return InsertBytes(w);
      case kChannelNames:
        return ChannelNames(w);
      case kPayloadWords:
        return PayloadWords(w);
      case kSplice:
        return Splice(w);
      default:
        return;
    }
  }

  void Bitflip(Work* w) {
    Bytes& b = Ensure(w);
    if (b.empty()) return;
    const int flips = static_cast<int>(Uniform(1, 16));
    // A quarter of the mutants flip bits of one episode configuration only:
    // the message that sizes an episode and steers its evaluation.
    std::vector<std::size_t> configs;
    if (w->offsets.size() == w->events.size())
      for (std::size_t i : Configs(w->events)) configs.push_back(i);
    if (!configs.empty() && Chance(0.25)) {
      const std::size_t e = Pick(configs);
      const std::size_t data = w->offsets[e] + kHeaderBytes + w->events[e].channel.size();
      for (int i = 0; i < flips; ++i)
        b[std::min(b.size() - 1, data + Index(w->events[e].data.size()))] ^=
            static_cast<uint8_t>(1u << Uniform(0, 7));
      w->what.push_back(std::to_string(flips) + " bit flips in the configuration of event " +
                        std::to_string(e));
      return;
    }
    int in_headers = 0;
    for (int i = 0; i < flips; ++i) {
      std::size_t at = Index(b.size());
      if (Chance(0.25) && !w->offsets.empty()) {
        at = std::min(b.size() - 1, Pick(w->offsets) + Index(kHeaderBytes));
        ++in_headers;
      }
      b[at] ^= static_cast<uint8_t>(1u << Uniform(0, 7));
    }
    w->what.push_back(std::to_string(flips) + " bit flips (" + std::to_string(in_headers) + " in headers)");
  }

  void Truncate(Work* w) {
    Bytes& b = Ensure(w);
    std::size_t cut = 0;
    const int how = static_cast<int>(Uniform(0, 3));
    if (how == 0 || w->offsets.empty()) {
      cut = b.empty() ? 0 : Index(b.size());
    } else if (how == 1) {
      cut = Pick(w->offsets) + Index(kHeaderBytes);  // mid-header
    } else if (how == 2) {
      cut = Pick(w->offsets) + kHeaderBytes + Uniform(0, 64);  // mid-channel or early data
    } else {
      // An empty file, no whole event at all, or at an event boundary.
      cut = Chance(0.3) ? 0 : Chance(0.5) ? Uniform(1, kHeaderBytes + 40) : Pick(w->offsets);
    }
    cut = std::min(cut, b.size());
    w->what.push_back("cut at byte " + std::to_string(cut) + " of " + std::to_string(b.size()));
    b.resize(cut);
  }

  uint32_t LengthValue(bool data, uint32_t old) {
    const uint32_t data_values[] = {0x7fffffffu, 0x80000000u, 0xffffffffu, 0x04000001u,
                                    0x04000000u, 0xfffffff0u, 0x00100000u};
    const uint32_t channel_values[] = {0x7fffffffu, 0x80000000u, 0xffffffffu, 0u, 257u, 256u, 65536u, 1u};
    switch (Uniform(0, 3)) {
      case 0:
        return static_cast<uint32_t>(rng_());
      case 1:
        return old + static_cast<uint32_t>(Uniform(1, 64));  // a little too long
      case 2:
        return old - static_cast<uint32_t>(Uniform(1, std::max<uint32_t>(1, std::min<uint32_t>(old, 64))));
      default:
        return data ? data_values[Uniform(0, std::size(data_values) - 1)]
                    : channel_values[Uniform(0, std::size(channel_values) - 1)];
    }
  }

  // The int32 length field at `field` (20: channel, 24: data) of 1..3 events.
  void LengthField(Work* w, std::size_t field, const char* what) {
    Bytes& b = Ensure(w);
    if (w->offsets.empty()) return;
    const int n = Chance(0.7) ? 1 : static_cast<int>(Uniform(2, 3));
    for (int i = 0; i < n; ++i) {
      const std::size_t e = Index(w->offsets.size());
      const std::size_t at = w->offsets[e] + field;
      if (at + 4 > b.size()) continue;
      const auto old = static_cast<uint32_t>(GetBE(&b[at], 4));
      const uint32_t v = (i == 0 && Chance(0.3)) ? 0x7fffffffu : LengthValue(field == 24, old);
      PutBE(&b[at], v, 4);
      w->what.push_back(std::string(what) + " length of event " + std::to_string(e) + " " +
                        std::to_string(old) + " -> " + Hex(v));
    }
  }

  int64_t HugeInt64() {
    const int64_t values[] = {
        kI64Max,          kI64Min,          -1,          0,           50000000,           50000001,
        int64_t{1} << 40, int64_t{1} << 31, kI64Max - 1, kI64Min + 1, int64_t{0x7fffffff}};
    return Chance(0.25) ? static_cast<int64_t>(rng_()) : values[Uniform(0, std::size(values) - 1)];
  }

  void Eventnum(Work* w) {
    auto& ev = w->events;
    if (Chance(0.3)) {  // counting up through INT64_MAX from a random event on
      const std::size_t from = Index(ev.size());
      int64_t v = kI64Max - static_cast<int64_t>(Uniform(0, 3));
      for (std::size_t i = from; i < ev.size(); ++i) {
        ev[i].eventnum = v;
        v = static_cast<int64_t>(static_cast<uint64_t>(v) + 1u);
      }
      w->what.push_back("eventnums counting through INT64_MAX from event " + std::to_string(from));
      return;
    }
    const int n = static_cast<int>(Uniform(1, 8));
    for (int i = 0; i < n; ++i) {
      const std::size_t e = Index(ev.size());
      ev[e].eventnum = HugeInt64();
      w->what.push_back("eventnum of event " + std::to_string(e) + " = " + std::to_string(ev[e].eventnum));
    }
  }

  std::vector<std::size_t> Configs(const std::vector<Event>& ev) const {
    std::vector<std::size_t> c;
    for (std::size_t i = 0; i < ev.size(); ++i)
      if (EndsWith(ev[i].channel, "EPISODE_CONFIG")) c.push_back(i);
    return c;
  }

  void Reorder(Work* w) {
    auto& ev = w->events;
    const std::size_t n = ev.size();
    switch (Uniform(0, 5)) {
      case 0: {
        const int swaps = static_cast<int>(Uniform(1, 10));
        for (int i = 0; i < swaps; ++i) std::swap(ev[Index(n)], ev[Index(n)]);
        w->what.push_back(std::to_string(swaps) + " pairs of events swapped");
        return;
      }
      case 1: {
        const std::size_t a = Index(n), len = std::min<std::size_t>(n - a, Uniform(2, 200));
        std::reverse(ev.begin() + static_cast<long>(a), ev.begin() + static_cast<long>(a + len));
        w->what.push_back("events " + std::to_string(a) + ".." + std::to_string(a + len) + " reversed");
        return;
      }
      case 2: {
        const std::size_t a = Index(n), len = std::min<std::size_t>(n - a, Uniform(2, 50));
        std::shuffle(ev.begin() + static_cast<long>(a), ev.begin() + static_cast<long>(a + len), rng_);
        w->what.push_back("events " + std::to_string(a) + ".." + std::to_string(a + len) + " shuffled");
        return;
      }
      case 3: {
        const std::size_t mid = Index(n);
        std::rotate(ev.begin(), ev.begin() + static_cast<long>(mid), ev.end());
        w->what.push_back("events rotated: " + std::to_string(mid) + " first");
        return;
      }
      case 4: {
        std::vector<Event> configs, rest;
        for (auto& e : ev) (EndsWith(e.channel, "EPISODE_CONFIG") ? configs : rest).push_back(std::move(e));
        rest.insert(rest.end(), configs.begin(), configs.end());
        ev = std::move(rest);
        w->what.push_back(std::to_string(configs.size()) + " configurations moved to the end");
        return;
      }
      default:
        std::shuffle(ev.begin(), ev.end(), rng_);
        w->what.push_back("all events shuffled");
        return;
    }
  }

  void DupDrop(Work* w) {
    auto& ev = w->events;
    switch (Uniform(0, 4)) {
      case 0: {
        const int n = static_cast<int>(Uniform(1, 20));
        for (int i = 0; i < n && !ev.empty(); ++i) {
          const Event copy = ev[Index(ev.size())];
          ev.insert(ev.begin() + static_cast<long>(Uniform(0, ev.size())), copy);
        }
        w->what.push_back(std::to_string(n) + " events duplicated at random places");
        return;
      }
      case 1: {
        const int n = static_cast<int>(Uniform(1, 20));
        for (int i = 0; i < n && !ev.empty(); ++i) ev.erase(ev.begin() + static_cast<long>(Index(ev.size())));
        w->what.push_back(std::to_string(n) + " events dropped");
        return;
      }
      case 2: {
        const std::size_t a = Index(ev.size()), len = std::min<std::size_t>(ev.size() - a, Uniform(1, 500));
        ev.erase(ev.begin() + static_cast<long>(a), ev.begin() + static_cast<long>(a + len));
        w->what.push_back("events " + std::to_string(a) + ".." + std::to_string(a + len) + " dropped");
        return;
      }
      case 3: {
        const auto configs = Configs(ev);
        for (auto it = configs.rbegin(); it != configs.rend(); ++it)
          ev.erase(ev.begin() + static_cast<long>(*it));
        w->what.push_back(std::to_string(configs.size()) + " configurations dropped (orphans)");
        return;
      }
      default: {
        const std::size_t a = Index(ev.size()), len = std::min<std::size_t>(ev.size() - a, Uniform(1, 300));
        const int times = static_cast<int>(Uniform(2, 5));
        std::vector<Event> block(ev.begin() + static_cast<long>(a), ev.begin() + static_cast<long>(a + len));
        for (int i = 1; i < times; ++i)
          ev.insert(ev.begin() + static_cast<long>(a + len), block.begin(), block.end());
        w->what.push_back("events " + std::to_string(a) + ".." + std::to_string(a + len) + " repeated " +
                          std::to_string(times) + " times");
        return;
      }
    }
  }

  Bytes RandomBytes(std::size_t n) {
    Bytes b(n);
    for (auto& x : b) x = static_cast<uint8_t>(rng_());
    return b;
  }

  void InsertBytes(Work* w) {
    Bytes& b = Ensure(w);
    const int n = static_cast<int>(Uniform(1, 8));
    int fake = 0;
    for (int i = 0; i < n; ++i) {
      Bytes ins;
      if (Chance(0.4)) {  // a fake event header, with lengths of any kind
        ++fake;
        AppendBE(&ins, kSyncWord, 4);
        AppendBE(&ins, static_cast<uint64_t>(HugeInt64()), 8);
        AppendBE(&ins, rng_(), 8);
        AppendBE(&ins, Chance(0.5) ? Uniform(1, 40) : rng_(), 4);
        AppendBE(&ins, Chance(0.3) ? 0x7fffffffu : Chance(0.5) ? Uniform(0, 200) : rng_(), 4);
        const Bytes tail = RandomBytes(Uniform(0, 64));
        ins.insert(ins.end(), tail.begin(), tail.end());
      } else {
        ins = RandomBytes(Uniform(1, 256));
      }
      std::size_t at = Uniform(0, b.size());
      if (Chance(0.5) && !w->offsets.empty()) at = std::min(b.size(), Pick(w->offsets));
      b.insert(b.begin() + static_cast<long>(at), ins.begin(), ins.end());
    }
    w->what.push_back(std::to_string(n) + " insertions of random bytes (" + std::to_string(fake) +
                      " fake headers)");
  }

  std::string BadBytes() {
    static const char* const kBad[] = {
        "\xff",         "\xfe",         "\xc3", "\xc3\x28",     "\xe2\x82",    "\xf0\x28\x8c\xbc",
        "\xc0\xaf",     "\xed\xa0\x80", "\x80", "\xf8\x88\x80", "\x1b[31m",    "\x1b]0;x\x07",
        "\r",           "\n",           "\t",   "\x7f",         "\x01",        "",
        "\xe2\x80\xae", "\"",           "\\",   "%s%n",         "\xef\xbb\xbf"};
    std::string s = kBad[Uniform(0, std::size(kBad) - 1)];
    if (s.empty()) s.assign(1, '\0');  // "": a NUL byte
    return s;
  }

  void ChannelNames(Work* w) {
    auto& ev = w->events;
    const int n = static_cast<int>(Uniform(1, 6));
    for (int i = 0; i < n; ++i) {
      const std::size_t e = Index(ev.size());
      std::string& ch = ev[e].channel;
      switch (Uniform(0, 5)) {
        case 0:
        case 1: {  // the prefix mangled, the pidlab suffix kept: still decoded as pidlab
          const std::size_t us = ch.find('_');
          const std::size_t at = us == std::string::npos ? 0 : Uniform(0, us + 1);
          ch.insert(at, BadBytes());
          break;
        }
        case 2:  // bytes of the name replaced by high or control bytes
          for (int k = static_cast<int>(Uniform(1, 4)); k > 0 && !ch.empty(); --k)
            ch[Index(ch.size())] = static_cast<char>(Chance(0.6) ? Uniform(0x80, 0xff) : Uniform(0, 0x1f));
          break;
        case 3:  // a name of nothing but invalid bytes
          ch.clear();
          for (int k = static_cast<int>(Uniform(1, 8)); k > 0; --k) ch += BadBytes();
          break;
        case 4:  // empty, or as long as the reader allows, or longer
          ch = Chance(0.3) ? std::string() : std::string(Chance(0.5) ? 256 : 257, static_cast<char>(0xa9));
          break;
        default:
          ch += BadBytes();
          break;
      }
      w->what.push_back("channel of event " + std::to_string(e) + " mangled (" + std::to_string(ch.size()) +
                        " bytes)");
    }
  }

  void PayloadWords(Work* w) {
    auto& ev = w->events;
    std::vector<std::size_t> eligible;
    for (std::size_t i = 0; i < ev.size(); ++i)
      if (ev[i].data.size() >= 16) eligible.push_back(i);
    if (eligible.empty()) return;
    if (Chance(0.25)) {  // orphans of an unknown episode at a huge step
      const int64_t id = static_cast<int64_t>(rng_());
      const int64_t step = Chance(0.5) ? 50000000 : Chance(0.5) ? int64_t{1} << 40 : HugeInt64();
      const int n = static_cast<int>(Uniform(1, 50));
      int done = 0;
      for (int i = 0; i < n; ++i) {
        Bytes& d = ev[Pick(eligible)].data;
        if (d.size() < 32) continue;
        PutBE(&d[16], static_cast<uint64_t>(id), 8);
        PutBE(&d[24], static_cast<uint64_t>(step) + static_cast<uint64_t>(Chance(0.5) ? i : 0), 8);
        ++done;
      }
      w->what.push_back(std::to_string(done) + " events moved to episode " + std::to_string(id) +
                        " at step " + std::to_string(step));
      return;
    }
    const auto configs = Configs(ev);
    const bool in_configs = !configs.empty() && Chance(0.25);  // the messages that size episodes
    const int n = static_cast<int>(Uniform(1, 8));
    for (int i = 0; i < n; ++i) {
      const std::size_t e = in_configs ? Pick(configs) : Pick(eligible);
      Bytes& d = ev[e].data;
      if (d.size() < 16) continue;
      if (Chance(0.2)) {  // an int32 (array or string length) at any 4-byte position
        const std::size_t at = 8 + 4 * Index((d.size() - 8) / 4);
        const uint32_t values[] = {0x7fffffffu, 0xffffffffu, 0x10000000u, 0x80000000u, 65u, 2001u, 4097u};
        const uint32_t v =
            Chance(0.3) ? static_cast<uint32_t>(rng_()) : values[Uniform(0, std::size(values) - 1)];
        PutBE(&d[at], v, 4);
        w->what.push_back("int32 at byte " + std::to_string(at) + " of event " + std::to_string(e) + " = " +
                          Hex(v));
        continue;
      }
      const std::size_t words = (d.size() - 8) / 8;
      const std::size_t j = Chance(0.7) ? Index(std::min<std::size_t>(words, 3)) : Index(words);
      const int64_t v = HugeInt64();
      PutBE(&d[8 + 8 * j], static_cast<uint64_t>(v), 8);
      w->what.push_back("payload word " + std::to_string(j) + " of event " + std::to_string(e) + " (" +
                        ev[e].channel.substr(0, 40) + ") = " + std::to_string(v));
    }
  }

  void Splice(Work* w) {
    const Bytes& a = Ensure(w);
    const Seed& other = Pick(*seeds_);
    const Bytes& b = other.bytes;
    std::size_t cut_a = a.empty() ? 0 : Index(a.size() + 1);
    std::size_t cut_b = b.empty() ? 0 : Index(b.size() + 1);
    const bool boundaries = Chance(0.5);
    if (boundaries) {  // at event boundaries: whole events of both
      if (!w->offsets.empty()) cut_a = std::min(a.size(), Pick(w->offsets));
      if (!other.offsets.empty()) cut_b = Pick(other.offsets);
    }
    Bytes out(a.begin(), a.begin() + static_cast<long>(cut_a));
    out.insert(out.end(), b.begin() + static_cast<long>(cut_b), b.end());
    w->bytes = std::move(out);
    w->offsets.clear();
    w->what.push_back(std::string("spliced ") + (boundaries ? "at events: " : "mid-event: ") + "bytes 0.." +
                      std::to_string(cut_a) + " + " + other.path.substr(other.path.find_last_of('/') + 1) +
                      " from byte " + std::to_string(cut_b));
  }

  const std::vector<Seed>* seeds_;
  std::mt19937_64 rng_;
};

// ---- Running pidlab replay

struct Options {
  std::string pidlab;
  std::vector<std::string> seed_logs;
  long count = 1000;
  uint64_t seed = 1;
  std::string work_dir;
  double timeout_s = 10.0;
  double max_rss_mb = 200.0;
  std::size_t max_line = 300;
  int jobs = 1;
  long only = -1;
  bool keep_all = false;
};

// One mutant's run: what the main process knows of it.
struct Run {
  long index = -1;
  int cls = 0;
  bool json = false;
  std::string what, mutant, out, err;
};

// What a runner reports of one child (raw bytes over a pipe).
struct Result {
  int status = 0;
  int timed_out = 0, rss_killed = 0;
  long max_rss_kb = 0;   // wait4's ru_maxrss
  long rss_seen_kb = 0;  // the watchdog's highest sample
  double seconds = 0;
};

struct Tally {
  long runs = 0, exit0 = 0, exit1 = 0, hangs = 0, crashes = 0, sanitizer = 0, rss = 0, other = 0;
  long by_class[kClassCount][2] = {};
  double max_rss_mb = 0, slowest_s = 0;
  std::vector<std::string> failures;
};

std::string Slurp(const std::string& path, std::size_t limit = 64u << 20) {
  std::ifstream f(path, std::ios::binary);
  std::string s;
  char buf[65536];
  while (f && s.size() < limit) {
    f.read(buf, sizeof buf);
    s.append(buf, static_cast<std::size_t>(f.gcount()));
  }
  return s;
}

bool WriteFile(const std::string& path, const Bytes& b) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  return static_cast<bool>(f);
}

long ResidentKb(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/statm");
  long size = 0, resident = 0;
  if (!(f >> size >> resident)) return 0;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

std::string Fixed(double v, int digits) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(digits);
  os << v;
  return os.str();
}

// Printable and short: failure lines quote what the child wrote.
std::string Printable(const std::string& s, std::size_t max = 200) {
  std::string out;
  for (unsigned char c : s.substr(0, max)) {
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return s.size() > max ? out + "..." : out;
}

// fork/exec `pidlab replay MUTANT [--json]`, stdout and stderr to files;
// kills it (SIGKILL) past the timeout or over the RSS limit; wait4 for its
// peak RSS.
Result RunChild(const Options& o, const Run& r) {
  std::vector<std::string> args = {o.pidlab, "replay", r.mutant};
  if (r.json) args.push_back("--json");
  Result res;
  const auto start = Clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    res.status = 126 << 8;  // reported as exit 126
    return res;
  }
  if (pid == 0) {
    // The child: stdin empty, stdout and stderr to files, no key from the caller.
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(r.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = open(r.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0) _exit(126);
    dup2(in, 0), dup2(out, 1), dup2(err, 2);
    unsetenv("PIDLAB_AUTH_KEY_FILE");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  const long rss_limit_kb = static_cast<long>(o.max_rss_mb * 1024.0);
  for (int sleep_us = 50;;) {
    rusage ru{};
    if (wait4(pid, &res.status, WNOHANG, &ru) == pid) {
      res.max_rss_kb = ru.ru_maxrss;
      break;
    }
    const double age = std::chrono::duration<double>(Clock::now() - start).count();
    res.rss_seen_kb = std::max(res.rss_seen_kb, ResidentKb(pid));
    if (!res.timed_out && !res.rss_killed && (age > o.timeout_s || res.rss_seen_kb > rss_limit_kb)) {
      (age > o.timeout_s ? res.timed_out : res.rss_killed) = 1;
      kill(pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(sleep_us));
    sleep_us = std::min(sleep_us * 2, 2000);
  }
  res.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return res;
}

// A runner: a small process forked before the seeds are loaded that runs
// the children of one job slot. A forked child's ru_maxrss starts at its
// parent's RSS, so children forked by the (larger) main process would report
// at least its size; a runner's is a few MB, below any pidlab run.
struct Runner {
  pid_t pid = -1;
  int requests = -1, results = -1;
};

bool WriteAll(int fd, const void* data, std::size_t n) {
  const auto* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w, n -= static_cast<std::size_t>(w);
  }
  return true;
}

bool ReadAll(int fd, void* data, std::size_t n) {
  auto* p = static_cast<char*>(data);
  while (n > 0) {
    const ssize_t got = read(fd, p, n);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    p += got, n -= static_cast<std::size_t>(got);
  }
  return true;
}

// Requests are lines "J\tMUTANT\tOUT\tERR" (J: 0 or 1 for --json; the
// paths are the work directory's); the answer is a Result.
void RunnerLoop(const Options& o, int requests, int results) {
  FILE* in = fdopen(requests, "r");
  char* line = nullptr;
  std::size_t capacity = 0;
  while (in && getline(&line, &capacity, in) > 0) {
    std::istringstream fields(line);
    Run r;
    std::string json;
    if (!std::getline(fields, json, '\t') || !std::getline(fields, r.mutant, '\t') ||
        !std::getline(fields, r.out, '\t') || !std::getline(fields, r.err, '\n'))
      break;
    r.json = json == "1";
    const Result res = RunChild(o, r);
    if (!WriteAll(results, &res, sizeof res)) break;
  }
  std::free(line);
}

bool StartRunner(const Options& o, const std::vector<Runner>& others, Runner* runner) {
  int req[2], res[2];
  if (pipe2(req, O_CLOEXEC) != 0) return false;
  if (pipe2(res, O_CLOEXEC) != 0) return false;
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives the main process
    for (const Runner& x : others) close(x.requests), close(x.results);
    close(req[1]), close(res[0]);
    RunnerLoop(o, req[0], res[1]);
    _exit(0);
  }
  close(req[0]), close(res[1]);
  *runner = Runner{pid, req[1], res[0]};
  return true;
}

bool IsSanitizerReport(const std::string& err) {
  return err.find("AddressSanitizer") != std::string::npos ||
         err.find("runtime error") != std::string::npos || err.find("LeakSanitizer") != std::string::npos ||
         err.find("UndefinedBehaviorSanitizer") != std::string::npos;
}

// Where the first whole LCM event of `file` starts, or -1: a sync word
// followed by a channel of 1..256 bytes and data of 0..64 MiB that end inside
// the file. Every sync word is tried, as the reader does after bad bytes, so
// the reader finds no event exactly when this finds none.
long long FirstWholeEvent(const std::string& file) {
  const auto word = [&file](std::size_t at) {
    uint32_t w = 0;
    for (std::size_t i = 0; i < 4; ++i) w = (w << 8) | static_cast<uint8_t>(file[at + i]);
    return w;
  };
  for (std::size_t at = 0; at + kHeaderBytes <= file.size(); ++at) {
    if (word(at) != 0xEDA1DA01u) continue;
    const auto channel = static_cast<int32_t>(word(at + 20)), data = static_cast<int32_t>(word(at + 24));
    if (channel >= 1 && channel <= 256 && data >= 0 && data <= (64 << 20) &&
        static_cast<long long>(channel) + data <= static_cast<long long>(file.size() - at - kHeaderBytes))
      return static_cast<long long>(at);
  }
  return -1;
}

// What is wrong with a run that exited with `code`, empty if nothing. A
// mutant without a whole event must exit 1 saying "no LCM event", and only
// such a mutant may.
std::string CheckOutput(const Options& o, const Run& r, int code) {
  const std::string err = Slurp(r.err);
  if (IsSanitizerReport(err)) return "sanitizer report: " + Printable(err);
  if (code != 0 && code != 1) return "exit " + std::to_string(code) + ": " + Printable(err);
  std::size_t lines = static_cast<std::size_t>(std::count(err.begin(), err.end(), '\n'));
  if (!err.empty() && err.back() != '\n') ++lines;
  if (lines > 1)
    return "exit " + std::to_string(code) + " with " + std::to_string(lines) +
           " lines on stderr: " + Printable(err);
  if (code == 1) {
    const std::string line = err.substr(0, err.find('\n'));
    if (line.find_first_not_of(" \t\r") == std::string::npos) return "exit 1 without a message on stderr";
    if (line.size() > o.max_line)
      return "exit 1 with a " + std::to_string(line.size()) + "-char line: " + Printable(line);
    const long long event = FirstWholeEvent(Slurp(r.mutant));
    if (line.find("no LCM event") != std::string::npos && event >= 0)
      return "exit 1 with 'no LCM event', but a whole event starts at byte " + std::to_string(event) + ": " +
             Printable(line);
    if (line.find("no LCM event") == std::string::npos && event < 0)
      return "exit 1 on a mutant without a whole event, not saying 'no LCM event': " + Printable(line);
    return "";
  }
  if (FirstWholeEvent(Slurp(r.mutant)) < 0) return "exit 0 on a mutant without a whole LCM event";
  const std::string out = Slurp(r.out);
  if (!r.json) {
    if (out.compare(0, 4, "log ") != 0) return "exit 0 without the table: " + Printable(out);
    // Text from the log (channel names, strings of a message) must not
    // reach a terminal raw: no escape sequences, no fake table lines.
    const auto raw = std::find_if(out.begin(), out.end(), [](char ch) {
      const auto c = static_cast<unsigned char>(ch);
      return (c < 0x20 && c != '\n') || c == 0x7f;
    });
    if (raw != out.end()) {
      const auto at = static_cast<std::size_t>(raw - out.begin());
      const std::size_t line = out.rfind('\n', at) == std::string::npos ? 0 : out.rfind('\n', at) + 1;
      const std::size_t from = std::max(line, at > 100 ? at - 100 : 0);
      return "exit 0 with a raw control byte in the table at byte " + std::to_string(at) + ": " +
             Printable(out.substr(from, 160));
    }
    return "";
  }
  if (out.empty() || out.back() != '\n' || out.find('\n') != out.size() - 1)
    return "--json: stdout is not a single line";
  const std::string line = out.substr(0, out.size() - 1);
  if (line.front() != '{' || line.back() != '}')
    return "--json: stdout is not a JSON object: " + Printable(line);
  try {
    const auto j = nlohmann::json::parse(line);  // strict: valid UTF-8 too
    if (!j.is_object() || !j.contains("episodes") || !j["episodes"].is_array())
      return "--json: no episodes array in the object";
  } catch (const std::exception& e) {
    return std::string("--json: stdout does not parse: ") + Printable(e.what());
  }
  return "";
}

// Accounts a finished run (a failure gets a line and its mutant is kept).
void Finish(const Options& o, const Run* r, const Result& res, Tally* t) {
  const double rss_mb = static_cast<double>(std::max(res.max_rss_kb, res.rss_seen_kb)) / 1024.0;
  const int status = res.status;
  t->max_rss_mb = std::max(t->max_rss_mb, rss_mb);
  t->slowest_s = std::max(t->slowest_s, res.seconds);
  ++t->runs;
  std::string why;
  if (res.timed_out) {
    ++t->hangs;
    why = "hang: killed after " + Fixed(o.timeout_s, 1) + " s";
  } else if (res.rss_killed) {
    ++t->rss;
    why = "RSS watchdog: killed at " + std::to_string(res.rss_seen_kb / 1024) + " MB";
  } else if (WIFSIGNALED(status)) {
    const std::string err = Slurp(r->err);
    ++(IsSanitizerReport(err) ? t->sanitizer : t->crashes);
    why = "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) +
          "): " + Printable(err);
  } else {
    const int code = WEXITSTATUS(status);
    why = CheckOutput(o, *r, code);
    if (why.empty() && rss_mb > o.max_rss_mb) {
      ++t->rss;
      why = "peak RSS " + Fixed(rss_mb, 1) + " MB over " + Fixed(o.max_rss_mb, 1) + " MB";
    } else if (why.compare(0, 17, "sanitizer report:") == 0) {
      ++t->sanitizer;
    } else if (!why.empty()) {
      ++t->other;
    } else {
      ++(code == 0 ? t->exit0 : t->exit1);
      ++t->by_class[r->cls][code];
    }
  }
  if (why.empty()) {
    if (!o.keep_all) {
      unlink(r->mutant.c_str());
      unlink(r->out.c_str());
      unlink(r->err.c_str());
    }
    return;
  }
  std::ostringstream line;
  line << "FAIL mutant " << r->index << " [" << kClassNames[r->cls] << ": " << r->what << "] replay"
       << (r->json ? " --json" : "") << ": " << why << "; kept " << r->mutant;
  t->failures.push_back(line.str());
}

int RunAll(const Options& o, const std::vector<Runner>& runners, const std::vector<Seed>& seeds) {
  Tally t;
  std::vector<Run> slot(runners.size());
  std::vector<bool> busy(runners.size(), false);
  const long first = o.only >= 0 ? o.only : 0, last = o.only >= 0 ? o.only + 1 : o.count;
  long next = first, running = 0;
  const auto t0 = Clock::now();
  while (next < last || running > 0) {
    for (std::size_t k = 0; k < runners.size() && next < last; ++k) {
      if (busy[k]) continue;
      Run& r = slot[k];
      r = Run();
      r.index = next++;
      r.cls = static_cast<int>(r.index % kClassCount);
      r.json = r.index % 2 == 1;
      char name[64];
      std::snprintf(name, sizeof name, "/mutant-%06ld", r.index);
      r.mutant = o.work_dir + name + ".lcm";
      r.out = o.work_dir + name + ".out";
      r.err = o.work_dir + name + ".err";
      Mutator m(&seeds, o.seed, r.index);
      if (!WriteFile(r.mutant, m.Make(r.cls, &r.what))) {
        std::cerr << "log_mutator: error: cannot write " << r.mutant << "\n";
        return 2;
      }
      const std::string request =
          std::string(r.json ? "1" : "0") + "\t" + r.mutant + "\t" + r.out + "\t" + r.err + "\n";
      if (!WriteAll(runners[k].requests, request.data(), request.size())) {
        std::cerr << "log_mutator: error: runner " << k << " is gone\n";
        return 2;
      }
      busy[k] = true;
      ++running;
    }
    std::vector<pollfd> fds;
    std::vector<std::size_t> which;
    for (std::size_t k = 0; k < runners.size(); ++k)
      if (busy[k]) fds.push_back({runners[k].results, POLLIN, 0}), which.push_back(k);
    if (poll(fds.data(), fds.size(), -1) < 0 && errno != EINTR) {
      std::cerr << "log_mutator: error: poll: " << std::strerror(errno) << "\n";
      return 2;
    }
    for (std::size_t f = 0; f < fds.size(); ++f) {
      if (!fds[f].revents) continue;
      const std::size_t k = which[f];
      Result res;
      if (!ReadAll(runners[k].results, &res, sizeof res)) {
        std::cerr << "log_mutator: error: runner " << k << " died\n";
        return 2;
      }
      Finish(o, &slot[k], res, &t);
      busy[k] = false;
      --running;
      if (t.runs % 100 == 0)
        std::cerr << "log_mutator: " << t.runs << "/" << (last - first) << " mutants, " << t.failures.size()
                  << " failures, " << Fixed(std::chrono::duration<double>(Clock::now() - t0).count(), 1)
                  << " s\n";
    }
  }
  const double total_s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::cerr << "log_mutator: by class (exit 0/exit 1):";
  for (int c = 0; c < kClassCount; ++c)
    std::cerr << " " << kClassNames[c] << " " << t.by_class[c][0] << "/" << t.by_class[c][1];
  std::cerr << "\n";
  std::cout << "log_mutator: " << t.runs << " mutants (" << kClassCount << " classes): exit 0: " << t.exit0
            << ", exit 1: " << t.exit1 << ", hangs " << t.hangs << ", crashes " << t.crashes
            << ", sanitizer reports " << t.sanitizer << ", over the RSS limit " << t.rss << ", bad output "
            << t.other << "; peak RSS " << Fixed(t.max_rss_mb, 1) << " MB (max), slowest "
            << Fixed(t.slowest_s, 2) << " s, total " << Fixed(total_s, 1) << " s\n";
  for (const std::string& f : t.failures) std::cout << f << "\n";
  return t.failures.empty() ? 0 : 1;
}

bool LoadSeed(const std::string& path, Seed* s, std::string* error) {
  s->path = path;
  const std::string text = Slurp(path, std::size_t{1} << 30);
  if (text.empty()) {
    *error = "seed log '" + path + "' cannot be read or is empty";
    return false;
  }
  s->bytes.assign(text.begin(), text.end());
  if (!ParseLog(s->bytes, &s->events, error)) {
    *error = "seed log '" + path + "' is not a clean LCM log: " + *error;
    return false;
  }
  Serialize(s->events, &s->offsets);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "log_mutator: write seeded mutants of clean LCM logs (bit flips, truncation, absurd lengths and "
      "eventnums, reordering, duplication, inserted bytes, non-UTF-8 channel names, huge payload words, "
      "splices, combinations) and check that `pidlab replay` reads each with exit 0 or 1, one clear line, "
      "no crash, hang or sanitizer report, and bounded peak RSS."};
  app.add_option("--pidlab", o.pidlab, "the pidlab executable")->required();
  app.add_option("--seed-log", o.seed_logs, "a clean LCM log to mutate (repeatable; splices use two)")
      ->required()
      ->take_all();
  app.add_option("--count", o.count, "mutants to run")
      ->check(CLI::Range(1L, 100000000L))
      ->capture_default_str();
  app.add_option("--seed", o.seed, "seed of the mutations")->capture_default_str();
  app.add_option("--work-dir", o.work_dir, "directory for mutants (failing ones are kept there)")->required();
  app.add_option("--timeout", o.timeout_s, "seconds per run before it is killed and counted as a hang")
      ->check(CLI::Range(0.01, 3600.0))
      ->capture_default_str();
  app.add_option("--max-rss-mb", o.max_rss_mb, "peak RSS allowed per run, MB")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  app.add_option("--max-line", o.max_line, "longest stderr line allowed on exit 1, characters")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--jobs", o.jobs, "runs at a time")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--only", o.only, "run only mutant INDEX (reproduces a failure)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--keep-all", o.keep_all, "keep every mutant and its output, not only failing ones");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "log_mutator: error: " << e.what() << "\n";
    return 2;
  }
  if (access(o.pidlab.c_str(), X_OK) != 0) {
    std::cerr << "log_mutator: error: '" << o.pidlab << "' is not an executable\n";
    return 2;
  }
  struct stat st {};
  if (stat(o.work_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || access(o.work_dir.c_str(), W_OK) != 0) {
    std::cerr << "log_mutator: error: --work-dir '" << o.work_dir << "' is not a writable directory\n";
    return 2;
  }
  // The runners first, while this process is small (see Runner).
  std::vector<Runner> runners;
  for (int k = 0; k < o.jobs; ++k) {
    Runner runner;
    if (!StartRunner(o, runners, &runner)) {
      std::cerr << "log_mutator: error: cannot start a runner: " << std::strerror(errno) << "\n";
      return 2;
    }
    runners.push_back(runner);
  }
  std::vector<Seed> seeds(o.seed_logs.size());
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    std::string error;
    if (!LoadSeed(o.seed_logs[i], &seeds[i], &error)) {
      std::cerr << "log_mutator: error: " << error << "\n";
      return 2;
    }
  }
  const int status = RunAll(o, runners, seeds);
  for (const Runner& runner : runners) {
    close(runner.requests);  // EOF: the runner ends
    close(runner.results);
    waitpid(runner.pid, nullptr, 0);
  }
  return status;
}
