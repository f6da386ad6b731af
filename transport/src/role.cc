#include "pidlab/transport/role.h"

#include <unistd.h>

#include "pidlab/transport/episode_start.h"

namespace pidlab::transport {

Role::Role(Transport* transport, std::string role, LogFn log, bool verbose)
    : transport_(transport), role_(std::move(role)), log_(std::move(log)), verbose_(verbose) {
  transport_->Subscribe<pidlab::lcmt_episode_config>(
      kEpisodeConfigChannel, [this](const pidlab::lcmt_episode_config& m) { OnConfig(m); });
  transport_->Subscribe<pidlab::lcmt_ready>(kReadyChannel,
                                            [this](const pidlab::lcmt_ready& m) { OnReady(m); });
}

void Role::Log(const std::string& line) const {
  if (log_) log_(line);
}
void Role::Verbose(const std::string& line) const {
  if (verbose_ && log_) log_(line);
}

void Role::Ack(int64_t episode_id) {
  pidlab::lcmt_ready r = MakeReady(
      episode_id == 0 ? pidlab::lcmt_ready::ALIVE : pidlab::lcmt_ready::CONFIG_ACK, role_, episode_id);
  transport_->Publish(kReadyChannel, &r);
}

void Role::OnReady(const pidlab::lcmt_ready& m) {
  if (m.state == pidlab::lcmt_ready::PING) Ack(0);
}

void Role::OnConfig(const pidlab::lcmt_episode_config& m) {
  if (m.episode_id == episode_id_ && episode_id_ != 0) {
    ++counters_.duplicates;
    Ack(episode_id_);  // our first acknowledgement may have been lost
    return;
  }
  EpisodeSpec spec;
  if (const Status st = ParseEpisodeConfig(m, &spec); !st.ok()) {
    ++counters_.bad_configs;
    Log("ignoring configuration of episode " + std::to_string(m.episode_id) + ": " + st.message());
    return;
  }
  episode_id_ = spec.episode_id;
  ++counters_.episodes;
  StartEpisode(spec);
  Ack(episode_id_);
  Verbose("episode " + std::to_string(episode_id_) + ": started, plant " + spec.plant.name + ", " +
          std::to_string(spec.total_steps) + " steps");
}

int ServeRole(Transport* transport, Role* role, const volatile std::sig_atomic_t* stop) {
  while (!*stop) {
    if (transport->WaitAndHandle(role->MaxWait()) < 0) return 1;
    if (role->Halted()) return 2;
    role->Tick(NowSeconds());
  }
  return 0;
}

}  // namespace pidlab::transport
