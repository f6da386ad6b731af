#include "pidlab/controller/controller_role.h"

#include <cmath>
#include <cstring>
#include <pidlab/lcmt_control_command.hpp>

#include "pidlab/controller/pid.h"
#include "pidlab/controller/relay.h"

namespace pidlab::controller {
using transport::EpisodeSpec;
using transport::kControlChannel;
using transport::kPlantOutputChannel;
using transport::LogFn;
using transport::Role;
using transport::Transport;

namespace {
int8_t ToCommandStatus(PidStatus status) {
  switch (status) {
    case PidStatus::kOk:
      return pidlab::lcmt_control_command::OK;
    case PidStatus::kSaturated:
      return pidlab::lcmt_control_command::SATURATED;
    case PidStatus::kInvalidInput:
      break;
  }
  return pidlab::lcmt_control_command::INVALID_INPUT;
}
}  // namespace

struct ControllerRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<DiscretePid<double>> pid;
  std::unique_ptr<RelayTuner> relay;  // a relay episode (spec.relay)
  long expected = 0;
  pidlab::lcmt_control_command last;
  bool have_last = false;
  // The process's lifetime counters when this episode started: the episode's
  // own counts are the differences.
  long duplicates_at_start = 0;
  long dropped_at_start = 0;
  bool refused = false;  // the external PID refused it: unanswered
};

ControllerRole::ControllerRole(Transport* transport, LogFn log, bool verbose,
                               std::shared_ptr<ExternalPid> external)
    : Role(transport, "controller", std::move(log), verbose), external_(std::move(external)) {
  transport_->Subscribe<pidlab::lcmt_plant_output>(
      kPlantOutputChannel, [this](const pidlab::lcmt_plant_output& m) { OnOutput(m); });
}
ControllerRole::~ControllerRole() = default;

void ControllerRole::StartEpisode(const EpisodeSpec& spec) {
  auto ep = std::make_unique<Episode>();
  ep->spec = spec;
  ep->pid = std::make_unique<DiscretePid<double>>(spec.gains, PidOptionsAt(spec.pid, spec.dt_s));
  if (spec.relay)
    ep->relay = std::make_unique<RelayTuner>(spec.relay_tune, spec.gains, PidOptionsAt(spec.pid, spec.dt_s));
  ep->duplicates_at_start = counters_.duplicates;
  ep->dropped_at_start = transport_->counters().dropped;
  if (external_ && !halted_) {
    bool fatal = true;
    if (spec.relay) {
      ep->refused = true;
      fatal = false;
      Log("episode " + std::to_string(spec.episode_id) +
          ": a relay episode, and the firmware in the loop runs the PID only: not answered");
    } else if (const Status st = external_->Configure(spec, &fatal); !st.ok()) {
      ep->refused = true;
      Log("episode " + std::to_string(spec.episode_id) + ": " + st.message() +
          (fatal ? "" : ": not answered"));
      halted_ = fatal;
    }
  }
  ep_ = std::move(ep);
}

void ControllerRole::OnOutput(const pidlab::lcmt_plant_output& m) {
  if (!ep_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  if (e.refused || halted_) return;
  if (m.step == e.expected && m.step < e.spec.total_steps) {
    double u = 0.0;
    PidStatus status = PidStatus::kInvalidInput;
    if (external_) {
      if (const Status st = external_->Step(e.spec.reference, m.y, &u, &status); !st.ok()) {
        Log("episode " + std::to_string(e.spec.episode_id) + " step " + std::to_string(m.step) + ": " +
            st.message());
        halted_ = true;
        return;
      }
    } else if (!e.relay) {
      status = e.pid->Step(e.spec.reference, m.y, &u);
    } else if (std::isfinite(m.y)) {
      const RelayPhase before = e.relay->phase();
      u = e.relay->Step(m.t_s, e.spec.reference, m.y);
      status = PidStatus::kOk;
      if (e.relay->phase() != before && verbose_)
        Log("episode " + std::to_string(e.spec.episode_id) + ": relay " + ToString(e.relay->phase()) +
            " at t = " + std::to_string(m.t_s) + " s" +
            (e.relay->why().empty() ? std::string() : ": " + e.relay->why()));
    }
    pidlab::lcmt_control_command& c = e.last;
    c.episode_id = e.spec.episode_id;
    c.step = m.step;
    c.t_s = m.t_s;
    c.r = e.spec.reference;
    c.y = m.y;
    c.u = u;
    c.status = ToCommandStatus(status);
    e.have_last = true;
    ++e.expected;
    transport_->Publish(kControlChannel, &c);
    if (m.step + 1 == e.spec.total_steps) {
      Log("episode " + std::to_string(e.spec.episode_id) + ": done, " + std::to_string(e.expected) +
          " commands (re-answered " + std::to_string(counters_.duplicates - e.duplicates_at_start) +
          ", dropped " + std::to_string(transport_->counters().dropped - e.dropped_at_start) + ")");
    }
  } else if (e.have_last && m.step == e.last.step) {
    if (std::memcmp(&m.y, &e.last.y, sizeof m.y) != 0) {
      // A second, different y for a step already answered: not the plant's
      // resend. Never compute from it; repeat our answer, which carries the y
      // it was computed from, so the plant can tell which of the two it
      // published and fail the episode naming the conflict.
      ++counters_.conflicts;
      transport_->Publish(kControlChannel, &e.last);
      return;
    }
    // The plant did not get our answer: repeat it, never step the PID twice.
    ++counters_.duplicates;
    transport_->Publish(kControlChannel, &e.last);
  } else {
    ++counters_.duplicates;
  }
}

}  // namespace pidlab::controller
