#include "pidlab/lcm/roles.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <sstream>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/plant_sim/disturbance.h"

namespace pidlab::lcm_trio {
namespace {
constexpr int kMaxChunk = 2000;         // steps per lcmt_trajectory_chunk
constexpr int kSummaryRepeats = 5;      // a summary is repeated this often...
constexpr double kSummaryPeriod = 0.1;  // ...this many seconds apart
const double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

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
  pidlab::lcmt_ready r;
  r.episode_id = episode_id;
  r.step = -1;
  r.state = episode_id == 0 ? pidlab::lcmt_ready::ALIVE : pidlab::lcmt_ready::CONFIG_ACK;
  r.role = role_;
  r.pid = static_cast<int32_t>(getpid());
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
  std::string error;
  if (!ParseEpisodeConfig(m, &spec, &error)) {
    ++counters_.bad_configs;
    Log("ignoring configuration of episode " + std::to_string(m.episode_id) + ": " + error);
    return;
  }
  episode_id_ = spec.episode_id;
  ++counters_.episodes;
  StartEpisode(spec);
  Ack(episode_id_);
  Verbose("episode " + std::to_string(episode_id_) + ": started, plant " + spec.plant.name + ", " +
          std::to_string(spec.total_steps) + " steps");
}

// ---------------------------------------------------------------- plant

struct PlantRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<DiscretePlant> plant;
  long k = 0;
  bool have_u = false, have_n = false;
  double u = 0, n = 0;
  std::vector<double> y_hist, u_hist, n_hist;
  double step_start_s = 0, last_send_s = 0, start_s = 0;
  bool finished = false;
  pidlab::lcmt_episode_summary summary;
  int summary_sent = 0;
  double summary_last_s = 0;
};

PlantRole::PlantRole(Transport* transport, LogFn log, bool verbose)
    : Role(transport, "plant", std::move(log), verbose) {
  transport_->Subscribe<pidlab::lcmt_control_command>(
      kControlChannel, [this](const pidlab::lcmt_control_command& m) { OnControl(m); });
  transport_->Subscribe<pidlab::lcmt_disturbance_sample>(
      kDisturbanceChannel, [this](const pidlab::lcmt_disturbance_sample& m) { OnDisturbance(m); });
  transport_->Subscribe<pidlab::lcmt_trajectory_request>(
      kTrajectoryRequestChannel,
      [this](const pidlab::lcmt_trajectory_request& m) { OnTrajectoryRequest(m); });
}

PlantRole::~PlantRole() = default;

void PlantRole::StartEpisode(const EpisodeSpec& spec) {
  if (ep_) {  // keep the previous trajectory for late TRAJECTORY_REQUESTs (pidlab launch --log)
    auto bytes = [](const Episode& e) { return 3 * sizeof(double) * e.y_hist.size(); };
    ep_->plant.reset();
    history_bytes_ += bytes(*ep_);
    history_.push_back(std::move(ep_));
    while (history_.size() > 1 && history_bytes_ > kPlantHistoryBytes) {
      history_bytes_ -= bytes(*history_.front());
      history_.pop_front();
    }
  }
  auto ep = std::make_unique<Episode>();
  ep->spec = spec;
  ep->plant = std::make_unique<DiscretePlant>(spec.plant.tf, spec.options.dt_s);
  ep->plant->Reset();
  const auto n = static_cast<std::size_t>(spec.total_steps);
  ep->y_hist.assign(n + 1, kNaN);
  ep->u_hist.assign(n + 1, kNaN);
  ep->n_hist.assign(n + 1, kNaN);
  ep->y_hist[0] = ep->plant->Output();
  ep->start_s = ep->step_start_s = NowSeconds();
  ep_ = std::move(ep);
  running_ = true;
  PublishOutput();
}

void PlantRole::PublishOutput() {
  pidlab::lcmt_plant_output m;
  m.episode_id = ep_->spec.episode_id;
  m.step = ep_->k;
  m.t_s = static_cast<double>(ep_->k) * ep_->spec.options.dt_s;
  m.y = ep_->y_hist[static_cast<std::size_t>(ep_->k)];
  transport_->Publish(kPlantOutputChannel, &m);
  ep_->last_send_s = NowSeconds();
}

void PlantRole::OnControl(const pidlab::lcmt_control_command& m) {
  if (!running_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  if (m.step != ep_->k || ep_->have_u) {
    ++counters_.duplicates;
    return;
  }
  if (m.status == 2 || !std::isfinite(m.u)) {
    Finish(false, "controller",
           "pidlab-controller could not compute u at step " + std::to_string(m.step) +
               " (invalid input or non-finite output)");
    return;
  }
  ep_->u = m.u;
  ep_->have_u = true;
  TryAdvance();
}

void PlantRole::OnDisturbance(const pidlab::lcmt_disturbance_sample& m) {
  if (!running_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  if (m.step != ep_->k || ep_->have_n) {
    ++counters_.duplicates;
    return;
  }
  ep_->n = m.n;
  ep_->have_n = true;
  TryAdvance();
}

void PlantRole::TryAdvance() {
  Episode& e = *ep_;
  if (!e.have_u || !e.have_n) return;
  const auto k = static_cast<std::size_t>(e.k);
  e.u_hist[k] = e.u;
  e.n_hist[k] = e.n;
  // Same operation and order as RunSampledLoop: input = u + n, then ZOH.
  e.plant->Step(e.u + e.n);
  ++e.k;
  e.have_u = e.have_n = false;
  e.y_hist[k + 1] = e.plant->Output();
  e.step_start_s = NowSeconds();
  PublishOutput();
  if (e.k == e.spec.total_steps) Finish(true, "", "");
}

void PlantRole::Finish(bool ok, const std::string& silent_role, const std::string& message) {
  Episode& e = *ep_;
  running_ = false;
  e.finished = true;
  pidlab::lcmt_episode_summary& s = e.summary;
  s.episode_id = e.spec.episode_id;
  s.step = e.k;
  s.status = ok ? pidlab::lcmt_episode_summary::OK : pidlab::lcmt_episode_summary::FAILED;
  s.total_steps = e.spec.total_steps;
  s.final_y = ok ? e.y_hist.back() : kNaN;
  s.silent_role = silent_role;
  s.message = message;
  transport_->Publish(kSummaryChannel, &s);
  e.summary_sent = 1;
  e.summary_last_s = NowSeconds();
  std::ostringstream os;
  const double wall = NowSeconds() - e.start_s;
  os << "episode " << e.spec.episode_id << ": " << (ok ? "done" : "FAILED") << ", plant " << e.spec.plant.name
     << ", " << e.k << "/" << e.spec.total_steps << " steps in " << wall << " s";
  if (ok) os << ", y_final " << s.final_y;
  if (!ok) os << ": " << message;
  os << " (resent " << counters_.retransmits << ", dropped " << transport_->counters().dropped << ")";
  Log(os.str());
}

const PlantRole::Episode* PlantRole::FindEpisode(int64_t episode_id) const {
  if (ep_ && ep_->spec.episode_id == episode_id) return ep_.get();
  for (auto it = history_.rbegin(); it != history_.rend(); ++it)
    if ((*it)->spec.episode_id == episode_id) return it->get();
  return nullptr;
}

void PlantRole::OnTrajectoryRequest(const pidlab::lcmt_trajectory_request& m) {
  const Episode* ep = FindEpisode(m.episode_id);
  if (!ep) {
    ++counters_.foreign;
    return;
  }
  const long first = std::max<long>(0, static_cast<long>(m.step));
  const long last = std::min<long>({first + std::min<long>(m.count, kMaxChunk), ep->k + 1});
  if (last <= first) return;
  pidlab::lcmt_trajectory_chunk c;
  c.episode_id = m.episode_id;
  c.step = first;
  c.count = static_cast<int32_t>(last - first);
  c.y.assign(ep->y_hist.begin() + first, ep->y_hist.begin() + last);
  c.u.assign(ep->u_hist.begin() + first, ep->u_hist.begin() + last);
  c.n.assign(ep->n_hist.begin() + first, ep->n_hist.begin() + last);
  transport_->Publish(kTrajectoryChannel, &c);
}

double PlantRole::MaxWait() const {
  if (running_) return ep_->spec.recovery.retransmit_interval_s;
  return 0.05;
}

void PlantRole::Tick(double now_s) {
  if (!ep_) return;
  Episode& e = *ep_;
  if (e.finished) {
    if (e.summary_sent < kSummaryRepeats && now_s - e.summary_last_s >= kSummaryPeriod) {
      transport_->Publish(kSummaryChannel, &e.summary);
      ++e.summary_sent;
      e.summary_last_s = now_s;
    }
    return;
  }
  if (now_s - e.step_start_s >= e.spec.recovery.silence_deadline_s) {
    std::string silent;
    if (!e.have_u) silent = "controller";
    if (!e.have_n) silent += silent.empty() ? "disturbance" : ",disturbance";
    std::ostringstream os;
    os << "no answer from pidlab-"
       << (silent == "controller,disturbance" ? "controller and pidlab-disturbance" : silent) << " for "
       << e.spec.recovery.silence_deadline_s << " s at step " << e.k << " of " << e.spec.total_steps;
    Finish(false, silent, os.str());
    return;
  }
  if (now_s - e.last_send_s >= e.spec.recovery.retransmit_interval_s) {
    ++counters_.retransmits;
    Verbose("resending y at step " + std::to_string(e.k));
    PublishOutput();
  }
}

// ---------------------------------------------------------------- controller

struct ControllerRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<DiscretePid<double>> pid;
  long expected = 0;
  pidlab::lcmt_control_command last;
  bool have_last = false;
};

ControllerRole::ControllerRole(Transport* transport, LogFn log, bool verbose)
    : Role(transport, "controller", std::move(log), verbose) {
  transport_->Subscribe<pidlab::lcmt_plant_output>(
      kPlantOutputChannel, [this](const pidlab::lcmt_plant_output& m) { OnOutput(m); });
}
ControllerRole::~ControllerRole() = default;

void ControllerRole::StartEpisode(const EpisodeSpec& spec) {
  auto ep = std::make_unique<Episode>();
  ep->spec = spec;
  PidOptions options = spec.options.pid;
  options.dt_s = spec.options.dt_s;
  ep->pid = std::make_unique<DiscretePid<double>>(spec.gains, options);
  ep_ = std::move(ep);
}

void ControllerRole::OnOutput(const pidlab::lcmt_plant_output& m) {
  if (!ep_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  if (m.step == e.expected && m.step < e.spec.total_steps) {
    double u = 0.0;
    const PidStatus status = e.pid->Step(e.spec.reference, m.y, &u);
    pidlab::lcmt_control_command& c = e.last;
    c.episode_id = e.spec.episode_id;
    c.step = m.step;
    c.t_s = m.t_s;
    c.r = e.spec.reference;
    c.y = m.y;
    c.u = u;
    c.status = status == PidStatus::kOk ? 0 : status == PidStatus::kSaturated ? 1 : 2;
    e.have_last = true;
    ++e.expected;
    transport_->Publish(kControlChannel, &c);
    if (m.step + 1 == e.spec.total_steps) {
      Log("episode " + std::to_string(e.spec.episode_id) + ": done, " + std::to_string(e.expected) +
          " commands (re-answered " + std::to_string(counters_.duplicates) + ", dropped " +
          std::to_string(transport_->counters().dropped) + ")");
    }
  } else if (e.have_last && m.step == e.last.step) {
    // The plant did not get our answer: repeat it, never step the PID twice.
    ++counters_.duplicates;
    transport_->Publish(kControlChannel, &e.last);
  } else {
    ++counters_.duplicates;
  }
}

// ---------------------------------------------------------------- disturbance

struct DisturbanceRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<Disturbance> disturbance;
  bool logged = false;
};

DisturbanceRole::DisturbanceRole(Transport* transport, LogFn log, bool verbose)
    : Role(transport, "disturbance", std::move(log), verbose) {
  transport_->Subscribe<pidlab::lcmt_plant_output>(
      kPlantOutputChannel, [this](const pidlab::lcmt_plant_output& m) { OnOutput(m); });
}
DisturbanceRole::~DisturbanceRole() = default;

void DisturbanceRole::StartEpisode(const EpisodeSpec& spec) {
  auto ep = std::make_unique<Episode>();
  ep->spec = spec;
  ep->disturbance = std::make_unique<Disturbance>(spec.options.disturbance);
  ep_ = std::move(ep);
}

void DisturbanceRole::OnOutput(const pidlab::lcmt_plant_output& m) {
  if (!ep_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  if (m.step < 0 || m.step >= e.spec.total_steps) return;
  // Stateless: n_k depends on k only, so a repeated request gets the same answer.
  pidlab::lcmt_disturbance_sample d;
  d.episode_id = e.spec.episode_id;
  d.step = m.step;
  d.t_s = static_cast<double>(m.step) * e.spec.options.dt_s;
  d.n = e.disturbance->Value(static_cast<double>(m.step) * e.spec.options.dt_s);
  transport_->Publish(kDisturbanceChannel, &d);
  if (m.step + 1 == e.spec.total_steps && !e.logged) {
    e.logged = true;
    Log("episode " + std::to_string(e.spec.episode_id) + ": done, " + std::to_string(e.spec.total_steps) +
        " samples (dropped " + std::to_string(transport_->counters().dropped) + ")");
  }
}

int ServeRole(Transport* transport, Role* role, const volatile std::sig_atomic_t* stop) {
  while (!*stop) {
    if (transport->WaitAndHandle(role->MaxWait()) < 0) return 1;
    role->Tick(NowSeconds());
  }
  return 0;
}

}  // namespace pidlab::lcm_trio
