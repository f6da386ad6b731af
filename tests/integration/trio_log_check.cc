// trio_log_check LOG: checks that an lcm-logger file holds every step of every
// episode whose configuration it contains (y for 0..N, u and n for 0..N-1).
// Prints one line per episode; exit 0 if all are complete, 1 otherwise.

#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_plant_output.hpp>

#include <cstdio>
#include <map>
#include <set>
#include <string>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: trio_log_check LOG [PREFIX]\n");
    return 2;
  }
  const std::string prefix = argc > 2 ? argv[2] : "PIDLAB_";
  lcm::LogFile log(argv[1], "r");
  if (!log.good()) {
    std::fprintf(stderr, "cannot read %s\n", argv[1]);
    return 2;
  }
  std::map<int64_t, int64_t> total;  // episode -> N
  std::map<int64_t, std::set<int64_t>> y, u, n;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    const int size = static_cast<int>(e->datalen);
    if (e->channel == prefix + "EPISODE_CONFIG") {
      pidlab::lcmt_episode_config m;
      if (m.decode(e->data, 0, size) == size) total[m.episode_id] = m.total_steps;
    } else if (e->channel == prefix + "PLANT_OUTPUT") {
      pidlab::lcmt_plant_output m;
      if (m.decode(e->data, 0, size) == size) y[m.episode_id].insert(m.step);
    } else if (e->channel == prefix + "CONTROL") {
      pidlab::lcmt_control_command m;
      if (m.decode(e->data, 0, size) == size) u[m.episode_id].insert(m.step);
    } else if (e->channel == prefix + "DISTURBANCE") {
      pidlab::lcmt_disturbance_sample m;
      if (m.decode(e->data, 0, size) == size) n[m.episode_id].insert(m.step);
    }
  }
  if (total.empty()) {
    std::printf("no episode configuration in %s\n", argv[1]);
    return 1;
  }
  bool ok = true;
  for (const auto& [id, steps] : total) {
    auto count = [](const std::set<int64_t>& s, int64_t last) {
      long c = 0;
      for (int64_t k = 0; k <= last; ++k) c += s.count(k);
      return c;
    };
    const long cy = count(y[id], steps), cu = count(u[id], steps - 1), cn = count(n[id], steps - 1);
    const bool complete = cy == steps + 1 && cu == steps && cn == steps;
    ok = ok && complete;
    std::printf("episode %lld: %lld steps, y %ld/%lld, u %ld/%lld, n %ld/%lld: %s\n", static_cast<long long>(id),
                static_cast<long long>(steps), cy, static_cast<long long>(steps + 1), cu,
                static_cast<long long>(steps), cn, static_cast<long long>(steps), complete ? "complete" : "INCOMPLETE");
  }
  return ok ? 0 : 1;
}
