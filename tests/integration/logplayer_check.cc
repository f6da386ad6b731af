// logplayer_check [--prefix P] ORIGINAL PLAYBACK...: compares the CONTROL
// commands of lcm-logger files: ORIGINAL is the log of a live run (`pidlab
// launch --log`), each PLAYBACK what a lone pidlab-controller answered when
// lcm-logplayer played ORIGINAL to it. The commands of ORIGINAL are every u of
// every complete episode as `pidlab replay` reads them (pidlab_logreader:
// CONTROL events and the plant's trajectory chunks); a PLAYBACK's are its
// CONTROL events (event reader). Several PLAYBACK files (playbacks of the same
// log into fresh controllers) are taken together: a recording lcm-logger can
// miss a few answers on a loaded machine, and a controller answers in step
// order, so a step answered in any of them was reached. Every step must be
// in some PLAYBACK, and every copy of it (re-answered duplicates, other
// playbacks) must carry the same u, bit for bit. Prints the counts; exit 0 if
// all agree, 1 if not, 2 if a file cannot be read or the usage is wrong.

#include <cstdio>
#include <cstring>
#include <map>
#include <pidlab/lcmt_control_command.hpp>
#include <string>
#include <utility>

#include "pidlab/replay/event_reader.h"
#include "pidlab/replay/log_reader.h"

namespace {
struct Commands {
  std::map<std::pair<int64_t, int64_t>, uint64_t> u;  // (episode, step) -> bits of u
  long events = 0, copies = 0, disagreeing = 0;
};

bool Read(const char* path, const std::string& channel, Commands* out) {
  pidlab::replay::EventReader reader;
  if (const pidlab::Status st = reader.Open(path); !st.ok()) {
    std::fprintf(stderr, "%s\n", st.message().c_str());
    return false;
  }
  pidlab::replay::LogEvent e;
  while (reader.Next(&e)) {
    if (e.channel != channel) continue;
    pidlab::lcmt_control_command c;
    if (c.decode(e.data.data(), 0, static_cast<int>(e.data.size())) < 0) continue;
    ++out->events;
    uint64_t bits;
    std::memcpy(&bits, &c.u, sizeof bits);
    auto [it, fresh] = out->u.emplace(std::make_pair(c.episode_id, c.step), bits);
    if (!fresh) {
      ++out->copies;
      if (it->second != bits) ++out->disagreeing;
    }
  }
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  std::string prefix = "PIDLAB_";
  int first = 1;
  if (argc > 2 && std::strcmp(argv[1], "--prefix") == 0) {
    prefix = argv[2];
    first = 3;
  }
  if (argc - first < 2) {
    std::fprintf(stderr, "usage: logplayer_check [--prefix P] ORIGINAL PLAYBACK...\n");
    return 2;
  }
  const std::string channel = prefix + "CONTROL";
  Commands original, playback;
  pidlab::replay::ReadOptions options;
  options.channel_prefix = prefix;
  pidlab::replay::LogContents log;
  if (const pidlab::Status st = pidlab::replay::ReadLog(argv[first], options, &log); !st.ok()) {
    std::fprintf(stderr, "cannot read %s: %s\n", argv[first], st.message().c_str());
    return 2;
  }
  long incomplete = 0;
  for (const auto& e : log.episodes) {
    if (!e.Complete()) {
      ++incomplete;
      continue;
    }
    for (long k = 0; k < e.total_steps; ++k) {
      uint64_t bits;
      std::memcpy(&bits, &e.u[static_cast<std::size_t>(k)], sizeof bits);
      original.u.emplace(std::make_pair(e.episode_id, k), bits);
    }
  }
  for (int i = first + 1; i < argc; ++i)
    if (!Read(argv[i], channel, &playback)) return 2;
  long missing = 0, different = 0, extra = 0;
  for (const auto& [key, bits] : original.u) {
    const auto it = playback.u.find(key);
    if (it == playback.u.end())
      ++missing;
    else if (it->second != bits)
      ++different;
  }
  for (const auto& entry : playback.u) extra += original.u.count(entry.first) ? 0 : 1;
  std::printf(
      "original: %zu steps commanded in %zu episodes (%ld incomplete); playback (%d recording%s): %zu steps "
      "(%ld CONTROL events, %ld repeats, %ld disagreeing); missing %ld, different u %ld, not in the original "
      "%ld\n",
      original.u.size(), log.episodes.size(), incomplete, argc - first - 1, argc - first - 1 == 1 ? "" : "s",
      playback.u.size(), playback.events, playback.copies,
      playback.disagreeing, missing, different, extra);
  const bool ok = !original.u.empty() && missing == 0 && different == 0 && extra == 0 && incomplete == 0 &&
                  playback.disagreeing == 0;
  return ok ? 0 : 1;
}
