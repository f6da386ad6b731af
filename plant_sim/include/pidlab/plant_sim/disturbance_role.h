#pragma once
// pidlab-disturbance's protocol logic: answers each DISTURBANCE_REQUEST
// (steps first..first+samples) with DISTURBANCE_BLOCKs of n_k = n(k dt). It
// never sees y: n does not depend on the loop, so it is stateless and a
// repeated request gets the same answer.

#include <memory>
#include <pidlab/lcmt_disturbance_request.hpp>

#include "pidlab/transport/role.h"

namespace pidlab::plant_sim {

class DisturbanceRole : public transport::Role {
 public:
  DisturbanceRole(transport::Transport* transport, transport::LogFn log = {}, bool verbose = false);
  ~DisturbanceRole() override;

 protected:
  void StartEpisode(const transport::EpisodeSpec& spec) override;

 private:
  void OnRequest(const pidlab::lcmt_disturbance_request& msg);
  struct Episode;
  std::unique_ptr<Episode> ep_;
};

}  // namespace pidlab::plant_sim
