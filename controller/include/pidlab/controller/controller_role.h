#pragma once
// pidlab-controller's protocol logic: answers every plant output y_k with
// u_k = PID(r, y_k) (DiscretePid). A repeated y_k (the plant did not hear the
// answer) gets the u_k already computed: the PID is never stepped twice.

#include <memory>
#include <pidlab/lcmt_plant_output.hpp>

#include "pidlab/transport/role.h"

namespace pidlab::controller {

class ControllerRole : public transport::Role {
 public:
  ControllerRole(transport::Transport* transport, transport::LogFn log = {}, bool verbose = false);
  ~ControllerRole() override;

 protected:
  void StartEpisode(const transport::EpisodeSpec& spec) override;

 private:
  void OnOutput(const pidlab::lcmt_plant_output& msg);
  struct Episode;
  std::unique_ptr<Episode> ep_;
};

}  // namespace pidlab::controller
