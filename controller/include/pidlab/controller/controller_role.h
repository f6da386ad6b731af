#pragma once
// pidlab-controller's protocol logic: answers every plant output y_k with
// u_k = PID(r, y_k) (DiscretePid). A repeated y_k (the plant did not hear the
// answer) gets the u_k already computed: the PID is never stepped twice.

#include <memory>
#include <pidlab/lcmt_plant_output.hpp>
#include <string>

#include "pidlab/controller/pid.h"
#include "pidlab/spec/status.h"
#include "pidlab/transport/role.h"

namespace pidlab::controller {

/// The PID's arithmetic outside this process: processor in the loop
/// (controller/pil/, docs/pil.md), where a firmware computes every u.
class ExternalPid {
 public:
  virtual ~ExternalPid() = default;
  /// A new PID episode. A refusal that leaves the firmware usable (its range
  /// analysis refuses the gains) sets *fatal false: that episode goes
  /// unanswered. Anything else stops the role.
  virtual Status Configure(const transport::EpisodeSpec& spec, bool* fatal) = 0;
  /// One step. A failure stops the role.
  virtual Status Step(double r, double y, double* u, PidStatus* status) = 0;
};

class ControllerRole : public transport::Role {
 public:
  /// With `external`, PID episodes are computed by it; relay episodes are
  /// refused (its firmware has no relay), each with one line.
  ControllerRole(transport::Transport* transport, transport::LogFn log = {}, bool verbose = false,
                 std::shared_ptr<ExternalPid> external = nullptr);
  ~ControllerRole() override;
  /// The external PID failed: the one line said why, and the role stops.
  bool Halted() const override { return halted_; }

 protected:
  void StartEpisode(const transport::EpisodeSpec& spec) override;

 private:
  void OnOutput(const pidlab::lcmt_plant_output& msg);
  struct Episode;
  std::unique_ptr<Episode> ep_;
  std::shared_ptr<ExternalPid> external_;
  bool halted_ = false;
};

}  // namespace pidlab::controller
