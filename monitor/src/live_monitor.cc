#include "pidlab/monitor/live_monitor.h"

#include <algorithm>
#include <atomic>
#include <deque>
#include <limits>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_pacing_progress.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <pidlab/lcmt_tune_progress.hpp>
#include <stdexcept>

#include "pidlab/autotune/relay.h"
#include "pidlab/controller/relay.h"
#include "pidlab/transport/episode_spec.h"

namespace pidlab::monitor {

// A relay episode followed as its steps arrive (FollowRelay).
struct RelayFollower {
  RelayTuneOptions options;
  std::shared_ptr<RelayTuner> tuner;
  double dt_s = 0.0, r = 0.0;
};

bool LiveMonitorOptions::IsValid(std::string* error) const {
  std::string e;
  if (lcm_url.empty())
    e = "lcm_url is empty";
  else if (max_episodes < 1 || max_episodes > 1024)
    e = "max_episodes " + std::to_string(max_episodes) + " must be in 1..1024";
  else if (max_total_steps < 1 || max_total_steps > 100000000)
    e = "max_total_steps " + std::to_string(max_total_steps) + " must be in 1..1e8";
  else if (max_kept_steps < max_total_steps || max_kept_steps > 1000000000)
    e = "max_kept_steps " + std::to_string(max_kept_steps) + " must be in max_total_steps (" +
        std::to_string(max_total_steps) + ")..1e9";
  else if (transport.drop_rate != 0.0)
    e = "a monitor does not inject faults: drop_rate must be 0";
  else
    transport.IsValid(&e);
  if (error) *error = e;
  return e.empty();
}

const char* TuningStatusName(TuningStatus status) {
  switch (status) {
    case TuningStatus::kDone:
      return "done";
    case TuningStatus::kFailed:
      return "failed";
    case TuningStatus::kRunning:
      break;
  }
  return "running";
}

const char* StatusName(EpisodeStatus status) {
  switch (status) {
    case EpisodeStatus::kComplete:
      return "complete";
    case EpisodeStatus::kFailed:
      return "failed";
    case EpisodeStatus::kRunning:
      break;
  }
  return "running";
}

const char* RoleName(Role role) {
  static const char* const names[kRoleCount] = {"plant", "controller", "disturbance", "client"};
  return names[static_cast<int>(role)];
}

struct LiveMonitor::State {
  mutable std::mutex mutex;
  std::deque<EpisodeTrace> episodes;  // oldest first
  std::deque<TuningInfo> tunings;     // oldest first
  std::array<RoleHealth, kRoleCount> roles;
  transport::TransportCounters counters;
  long trajectory_requests = 0;
  long rejected = 0;
  std::atomic<long> version{0};
  int max_episodes = 32;
  long max_total_steps = 0;
  long max_kept_steps = 0;
  long kept_steps = 0;  // total_steps + 1 summed over the episodes kept

  EpisodeTrace* Find(int64_t id) {
    for (EpisodeTrace& e : episodes)
      if (e.info.episode_id == id) return &e;
    return nullptr;
  }
  void Heard(Role role, int pid = 0) {
    RoleHealth& h = roles[static_cast<std::size_t>(role)];
    h.last_heard_s = transport::NowSeconds();
    if (pid != 0) h.pid = pid;
  }
  void Changed() { ++version; }

  void OnConfig(const pidlab::lcmt_episode_config& m) {
    std::lock_guard<std::mutex> lock(mutex);
    Heard(Role::kClient);
    if (Find(m.episode_id)) return;  // a resend
    if (m.total_steps < 0 || m.total_steps > max_total_steps) {
      ++rejected;
      return;
    }
    EpisodeTrace e;
    e.info.episode_id = m.episode_id;
    e.info.first_heard_s = transport::NowSeconds();
    e.info.plant = m.plant_name;
    e.info.kp = m.kp, e.info.ki = m.ki, e.info.kd = m.kd;
    e.info.r = m.reference;
    e.info.dt_s = m.dt_s;
    e.info.total_steps = static_cast<long>(m.total_steps);
    if (m.controller_mode == "relay") {  // the relay, when the configuration is one a controller runs
      transport::EpisodeSpec spec;
      if (transport::ParseEpisodeConfig(m, &spec).ok() && spec.relay) {
        auto relay = std::make_shared<RelayFollower>();
        relay->options = spec.relay_tune;
        relay->tuner =
            std::make_shared<RelayTuner>(spec.relay_tune, spec.gains, PidOptionsAt(spec.pid, spec.dt_s));
        relay->dt_s = spec.dt_s;
        relay->r = spec.reference;
        e.relay = relay;
        e.info.relay.active = true;
        e.info.relay.phase = ToString(RelayPhase::kHold);
      }
    }
    const std::size_t size = static_cast<std::size_t>(m.total_steps) + 1;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    e.y.assign(size, nan), e.u.assign(size, nan), e.n.assign(size, nan);
    e.received.assign(size, false);
    const long steps = static_cast<long>(size);
    while (!episodes.empty() &&
           (static_cast<int>(episodes.size()) >= max_episodes || kept_steps + steps > max_kept_steps)) {
      kept_steps -= episodes.front().info.total_steps + 1;
      episodes.pop_front();
    }
    kept_steps += steps;
    episodes.push_back(std::move(e));
    Changed();
  }

  void OnChunk(const pidlab::lcmt_trajectory_chunk& m) {
    std::lock_guard<std::mutex> lock(mutex);
    Heard(Role::kPlant);
    EpisodeTrace* e = Find(m.episode_id);
    const long last = e ? e->info.total_steps : -1;
    if (!e || m.step < 0 || m.count < 0 || m.step > last || m.count > last + 1 - m.step) {
      ++rejected;  // an unknown episode, or steps outside it
      return;
    }
    for (int32_t i = 0; i < m.count; ++i) {
      const std::size_t k = static_cast<std::size_t>(m.step + i);
      e->y[k] = m.y[static_cast<std::size_t>(i)];
      e->u[k] = m.u[static_cast<std::size_t>(i)];
      e->n[k] = m.n[static_cast<std::size_t>(i)];
      if (!e->received[k]) {
        e->received[k] = true;
        ++e->info.steps_done;
      }
    }
    if (m.count > 0) e->info.highest_step = std::max<long>(e->info.highest_step, m.step + m.count - 1);
    if (e->relay) FollowRelay(e);
    Changed();
  }

  // Steps the episode's RelayTuner over the steps now received in order and
  // updates its view; the estimates on each new cycle.
  static void FollowRelay(EpisodeTrace* e) {
    RelayFollower& f = *e->relay;
    RelayView& v = e->info.relay;
    const std::size_t before = f.tuner->cycles().size();
    const RelayPhase phase_before = f.tuner->phase();
    long k = v.steps_followed;
    for (; k < e->info.total_steps && e->received[static_cast<std::size_t>(k)]; ++k) {
      const double y = e->y[static_cast<std::size_t>(k)];
      if (std::isfinite(y)) f.tuner->Step(static_cast<double>(k) * f.dt_s, f.r, y);
    }
    v.steps_followed = k;
    const RelayTuner& t = *f.tuner;
    v.phase = ToString(t.phase());
    v.why = t.why();
    v.u0 = t.u0(), v.y0 = t.y0(), v.noise_sigma = t.noise_sigma(), v.hysteresis = t.hysteresis();
    v.d_high = t.d_high(), v.d_low = t.d_low();
    v.cycles = static_cast<int>(t.cycles().size());
    v.restarts = t.restarts();
    if (!t.cycles().empty()) {
      v.last_period_s = t.cycles().back().period_s();
      v.last_amplitude = t.cycles().back().amplitude();
    }
    if ((t.cycles().size() == before && t.phase() == phase_before) || t.cycles().size() < 3) return;
    autotune::RelayOptions o;
    o.setpoint = t.y0(), o.u0 = t.u0(), o.d_high = t.d_high(), o.d_low = t.d_low(),
    o.hysteresis = t.hysteresis();
    o.settled_cycles = f.options.settled_cycles;
    o.tolerance = f.options.tolerance;
    if (!o.IsValid(nullptr)) return;
    const autotune::RelayEstimates r =
        autotune::EstimateFromCycles(o, t.cycles(), t.phase() == RelayPhase::kDone, t.noise_sigma());
    v.estimates = r.model_found;
    v.converged = r.converged;
    v.message = r.message;
    v.period_s = r.period_s, v.period_ci_s = r.period_ci_s;
    v.ku = r.ku, v.pu_s = r.pu_s, v.ku_describing_function = r.ku_describing_function;
    v.gain = r.model.gain, v.time_constant_s = r.model.time_constant_s, v.delay_s = r.model.delay_s;
    v.integrating = r.model.integrating;
    v.model_from = r.model_from;
  }

  void OnSummary(const pidlab::lcmt_episode_summary& m) {
    std::lock_guard<std::mutex> lock(mutex);
    Heard(Role::kPlant);
    EpisodeTrace* e = Find(m.episode_id);
    if (!e) return;
    e->info.status =
        m.status == pidlab::lcmt_episode_summary::OK ? EpisodeStatus::kComplete : EpisodeStatus::kFailed;
    e->info.message = m.message;
    e->info.realtime = transport::RealtimeFromSummary(m);
    Changed();
  }

  void OnPacing(const pidlab::lcmt_pacing_progress& m) {
    std::lock_guard<std::mutex> lock(mutex);
    Heard(Role::kPlant);
    EpisodeTrace* e = Find(m.episode_id);
    if (!e) return;
    e->info.pacing = transport::PacingProgressFromMessage(m);
    Changed();
  }

  void OnTuneProgress(const pidlab::lcmt_tune_progress& m) {
    std::lock_guard<std::mutex> lock(mutex);
    const double now = transport::NowSeconds();
    auto it = std::find_if(tunings.begin(), tunings.end(),
                           [&](const TuningInfo& t) { return t.tuning_id == m.episode_id; });
    if (it == tunings.end()) {
      if (tunings.size() >= LiveMonitor::kMaxTunings) tunings.pop_front();
      TuningInfo fresh;
      fresh.tuning_id = m.episode_id;
      fresh.first_heard_s = now;
      tunings.push_back(fresh);
      it = tunings.end() - 1;
    }
    TuningInfo& t = *it;
    t.last_heard_s = now;
    t.status = m.status == pidlab::lcmt_tune_progress::DONE     ? TuningStatus::kDone
               : m.status == pidlab::lcmt_tune_progress::FAILED ? TuningStatus::kFailed
                                                                : TuningStatus::kRunning;
    t.iterations = static_cast<long>(m.step);
    t.evaluations = m.evaluations;
    t.best_objective = m.best_objective;
    for (std::size_t i = 0; i < 3; ++i) t.best_gains[i] = m.best_gains[i];
    t.trios = m.trios;
    t.method = m.method;
    t.objective = m.objective;
    Changed();
  }

  void OnReady(const pidlab::lcmt_ready& m) {
    std::lock_guard<std::mutex> lock(mutex);
    for (int r = 0; r < kRoleCount; ++r)
      if (m.role == RoleName(static_cast<Role>(r))) Heard(static_cast<Role>(r), m.pid);
    Changed();
  }

  void OnHeard(Role role, bool trajectory_request) {
    std::lock_guard<std::mutex> lock(mutex);
    Heard(role);
    if (trajectory_request) ++trajectory_requests;
  }
};

LiveMonitor::LiveMonitor(const LiveMonitorOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("LiveMonitor: " + error);
  own_lcm_ = std::make_unique<lcm::LCM>(options_.lcm_url);
  if (!own_lcm_->good()) {
    status_ = Status::RunnerFailed("LCM cannot start on '" + options_.lcm_url + "'");
    return;
  }
  try {
    transport_ = std::make_unique<transport::Transport>(own_lcm_.get(), options_.transport);
  } catch (const std::runtime_error& e) {  // the step lanes' LCM
    status_ = Status::RunnerFailed(e.what());
    return;
  }
  Subscribe();
}

LiveMonitor::LiveMonitor(lcm::LCM* lcm, const LiveMonitorOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("LiveMonitor: " + error);
  transport_ = std::make_unique<transport::Transport>(lcm, options_.transport);
  Subscribe();
}

LiveMonitor::~LiveMonitor() = default;

void LiveMonitor::Subscribe() {
  state_ = std::make_unique<State>();
  state_->max_episodes = options_.max_episodes;
  state_->max_total_steps = options_.max_total_steps;
  state_->max_kept_steps = options_.max_kept_steps;
  State* s = state_.get();
  using transport::Transport;
  transport_->Subscribe<pidlab::lcmt_episode_config>(
      transport::kEpisodeConfigChannel, [s](const pidlab::lcmt_episode_config& m) { s->OnConfig(m); });
  transport_->Subscribe<pidlab::lcmt_ready>(transport::kReadyChannel,
                                            [s](const pidlab::lcmt_ready& m) { s->OnReady(m); });
  transport_->Subscribe<pidlab::lcmt_trajectory_chunk>(
      transport::kTrajectoryChannel, [s](const pidlab::lcmt_trajectory_chunk& m) { s->OnChunk(m); });
  transport_->Subscribe<pidlab::lcmt_episode_summary>(
      transport::kSummaryChannel, [s](const pidlab::lcmt_episode_summary& m) { s->OnSummary(m); });
  transport_->Subscribe<pidlab::lcmt_pacing_progress>(
      transport::kPacingChannel, [s](const pidlab::lcmt_pacing_progress& m) { s->OnPacing(m); });
  transport_->Subscribe<pidlab::lcmt_tune_progress>(
      transport::kTuneProgressChannel, [s](const pidlab::lcmt_tune_progress& m) { s->OnTuneProgress(m); });
  transport_->Subscribe<pidlab::lcmt_disturbance_request>(
      transport::kDisturbanceRequestChannel,
      [s](const pidlab::lcmt_disturbance_request&) { s->OnHeard(Role::kPlant, false); });
  transport_->Subscribe<pidlab::lcmt_disturbance_block>(
      transport::kDisturbanceBlockChannel,
      [s](const pidlab::lcmt_disturbance_block&) { s->OnHeard(Role::kDisturbance, false); });
  transport_->Subscribe<pidlab::lcmt_trajectory_request>(
      transport::kTrajectoryRequestChannel,
      [s](const pidlab::lcmt_trajectory_request&) { s->OnHeard(Role::kClient, true); });
}

int LiveMonitor::Poll(double timeout_s) {
  if (!transport_) return -1;
  const int handled = transport_->WaitAndHandle(timeout_s);
  std::lock_guard<std::mutex> lock(state_->mutex);
  const transport::TransportCounters& c = transport_->counters();
  if (c.received != state_->counters.received || c.undecodable != state_->counters.undecodable ||
      c.unauthenticated != state_->counters.unauthenticated || c.replayed != state_->counters.replayed) {
    state_->counters = c;
    state_->Changed();
  }
  return handled;
}

MonitorSnapshot LiveMonitor::Snapshot() const {
  MonitorSnapshot out;
  std::lock_guard<std::mutex> lock(state_->mutex);
  out.episodes.reserve(state_->episodes.size());
  for (const EpisodeTrace& e : state_->episodes) out.episodes.push_back(e.info);
  out.tunings.assign(state_->tunings.begin(), state_->tunings.end());
  out.roles = state_->roles;
  out.counters = state_->counters;
  out.trajectory_requests = state_->trajectory_requests;
  out.rejected = state_->rejected;
  out.now_s = transport::NowSeconds();
  return out;
}

bool LiveMonitor::WithEpisode(int64_t episode_id,
                              const std::function<void(const EpisodeTrace&)>& read) const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  const EpisodeTrace* e = state_->Find(episode_id);
  if (!e) return false;
  read(*e);
  return true;
}

long LiveMonitor::version() const { return state_->version.load(); }

}  // namespace pidlab::monitor
