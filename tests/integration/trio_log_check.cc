// trio_log_check LOG [PREFIX]: checks that an lcm-logger file holds every step
// of every episode in it (y for 0..N, u and n for 0..N-1), read with the
// project's log reader (pidlab_logreader, the code of `pidlab replay`): steps
// the plant republished as trajectory chunks count, and are shown as such.
// Prints one line per episode; exit 0 if there is at least one episode and
// all are complete, 1 otherwise, 2 if the file cannot be read.

#include <cstdio>
#include <string>

#include "pidlab/replay/log_reader.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: trio_log_check LOG [PREFIX]\n");
    return 2;
  }
  pidlab::replay::ReadOptions options;
  options.channel_prefix = argc > 2 ? argv[2] : "PIDLAB_";
  pidlab::replay::LogContents log;
  if (const pidlab::Status st = pidlab::replay::ReadLog(argv[1], options, &log); !st.ok()) {
    std::fprintf(stderr, "cannot read %s: %s\n", argv[1], st.message().c_str());
    return 2;
  }
  if (log.episodes.empty()) {
    std::printf("no episode in %s\n", argv[1]);
    return 1;
  }
  bool ok = true;
  for (const auto& e : log.episodes) {
    const bool complete = e.Complete();
    ok = ok && complete;
    auto stream = [](const pidlab::replay::StreamStats& s) {
      return std::to_string(s.expected - s.MissingCount()) + "/" + std::to_string(s.expected) + " (" +
             std::to_string(s.filled_from_chunks) + " from chunks)";
    };
    std::printf("episode %lld: %ld steps, y %s, u %s, n %s: %s\n", static_cast<long long>(e.episode_id),
                e.total_steps, stream(e.outputs).c_str(), stream(e.commands).c_str(),
                stream(e.disturbances).c_str(),
                complete ? "complete" : ("INCOMPLETE: " + e.CompletenessNote()).c_str());
  }
  return ok ? 0 : 1;
}
