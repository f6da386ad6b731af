// logplayer_check ORIGINAL PLAYBACK [PREFIX]: compares the CONTROL commands
// of two lcm-logger files, read with the project's event reader: ORIGINAL is
// the log of a live episode (`pidlab launch --log`), PLAYBACK what a lone
// pidlab-controller answered when lcm-logplayer played ORIGINAL to it. Every
// (episode, step) commanded in ORIGINAL must be in PLAYBACK, and every copy of
// it in either file (resends, re-answered duplicates) must carry the same u,
// bit for bit. Prints the counts; exit 0 if all agree, 1 if not, 2 if a file
// cannot be read.

#include <cstdio>
#include <cstring>
#include <map>
#include <pidlab/lcmt_control_command.hpp>
#include <string>
#include <utility>

#include "pidlab/replay/event_reader.h"

namespace {
struct Commands {
  std::map<std::pair<int64_t, int64_t>, uint64_t> u;  // (episode, step) -> bits of u
  long events = 0, copies = 0, disagreeing = 0;
};

bool Read(const char* path, const std::string& channel, Commands* out) {
  pidlab::replay::EventReader reader;
  std::string error;
  if (!reader.Open(path, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
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
  if (argc < 3) {
    std::fprintf(stderr, "usage: logplayer_check ORIGINAL PLAYBACK [PREFIX]\n");
    return 2;
  }
  const std::string channel = std::string(argc > 3 ? argv[3] : "PIDLAB_") + "CONTROL";
  Commands original, playback;
  if (!Read(argv[1], channel, &original) || !Read(argv[2], channel, &playback)) return 2;
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
      "original: %zu steps commanded (%ld CONTROL events, %ld repeats, %ld disagreeing); playback: %zu steps "
      "(%ld events, %ld repeats, %ld disagreeing); missing %ld, different u %ld, not in the original %ld\n",
      original.u.size(), original.events, original.copies, original.disagreeing, playback.u.size(),
      playback.events, playback.copies, playback.disagreeing, missing, different, extra);
  const bool ok = !original.u.empty() && missing == 0 && different == 0 && extra == 0 &&
                  original.disagreeing == 0 && playback.disagreeing == 0;
  return ok ? 0 : 1;
}
