#include "pidlab/plant_sim/disturbance_role.h"

#include <algorithm>
#include <pidlab/lcmt_disturbance_block.hpp>

#include "pidlab/plant_sim/disturbance.h"

namespace pidlab::plant_sim {
using transport::EpisodeSpec;
using transport::LogFn;
using transport::Role;
using transport::Transport;
using transport::kDisturbanceBlockChannel;
using transport::kDisturbanceRequestChannel;
using transport::kMaxNoiseRequest;
using transport::kNoiseBlock;


struct DisturbanceRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<Disturbance> disturbance;
  pidlab::lcmt_disturbance_block block;
  bool logged = false;
  long dropped_at_start = 0;  // the transport's lifetime count when the episode started
};

DisturbanceRole::DisturbanceRole(Transport* transport, LogFn log, bool verbose)
    : Role(transport, "disturbance", std::move(log), verbose) {
  transport_->Subscribe<pidlab::lcmt_disturbance_request>(
      kDisturbanceRequestChannel, [this](const pidlab::lcmt_disturbance_request& m) { OnRequest(m); });
}
DisturbanceRole::~DisturbanceRole() = default;

void DisturbanceRole::StartEpisode(const EpisodeSpec& spec) {
  auto ep = std::make_unique<Episode>();
  ep->spec = spec;
  ep->disturbance = std::make_unique<Disturbance>(spec.disturbance);
  ep->dropped_at_start = transport_->counters().dropped;
  ep_ = std::move(ep);
}

void DisturbanceRole::OnRequest(const pidlab::lcmt_disturbance_request& m) {
  if (!ep_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  const long total = e.spec.total_steps;
  if (m.step < 0 || m.step >= total || m.samples <= 0) {
    ++counters_.foreign;
    return;
  }
  const long first = static_cast<long>(m.step);
  const long end = std::min<long>(total, first + std::min<long>(m.samples, kMaxNoiseRequest));
  if (end <= first) {
    ++counters_.duplicates;
    return;
  }
  // Stateless: n_k depends on k only, so a repeated request gets the same answer.
  pidlab::lcmt_disturbance_block& b = e.block;
  b.episode_id = e.spec.episode_id;
  b.dt_s = e.spec.dt_s;
  for (long s = first; s < end; s += kNoiseBlock) {
    const long count = std::min<long>(kNoiseBlock, end - s);
    b.step = s;
    b.count = static_cast<int32_t>(count);
    b.n.resize(static_cast<std::size_t>(count));
    for (long i = 0; i < count; ++i)
      b.n[static_cast<std::size_t>(i)] =
          e.disturbance->Value(static_cast<double>(s + i) * e.spec.dt_s);
    transport_->Publish(kDisturbanceBlockChannel, &b);
  }
  if (end == total && !e.logged) {
    e.logged = true;
    Log("episode " + std::to_string(e.spec.episode_id) + ": done, " + std::to_string(total) +
        " samples (dropped " + std::to_string(transport_->counters().dropped - e.dropped_at_start) + ")");
  }
}

}  // namespace pidlab::plant_sim
