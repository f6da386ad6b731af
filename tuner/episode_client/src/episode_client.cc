#include "pidlab/episode_client/episode_client.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <sstream>
#include <stdexcept>

#include "pidlab/transport/episode_start.h"

namespace pidlab::episode_client {
namespace {
using transport::NowSeconds;
}  // namespace

transport::EpisodeSpec MakeEpisodeSpec(int64_t episode_id, const Plant& plant, const PidGains& gains,
                                       const evaluation::LoopOptions& options,
                                       const DisturbanceOptions& disturbance,
                                       const transport::RecoveryOptions& recovery) {
  transport::EpisodeSpec spec;
  spec.episode_id = episode_id;
  spec.plant = plant;
  // The loop's gains, whose tf travels as the wire's derivative_filter_s.
  spec.gains = evaluation::LoopGains(gains, options);
  static_cast<EpisodeShape&>(spec) = options;  // dt, ts, horizon, reference, PID, noise on y
  spec.pid = PidOptionsAt(spec.pid, options.dt_s);
  spec.pid.derivative_filter_s = spec.gains.tf;
  spec.disturbance = disturbance;
  spec.total_steps = options.TotalSteps();
  spec.recovery = recovery;
  std::string error;
  if (!spec.IsValid(&error)) throw std::invalid_argument("invalid episode: " + error);
  return spec;
}

evaluation::LoopOptions SampledLoopOptions(const transport::EpisodeSpec& spec) {
  evaluation::LoopOptions o;
  o.loop = evaluation::LoopKind::kSampled;
  static_cast<EpisodeShape&>(o) = spec;
  return o;
}

bool EpisodeClientOptions::IsValid(std::string* error) const {
  if (!transport.IsValid(error) || !recovery.IsValid(error)) return false;
  std::ostringstream os;
  if (!(start_timeout_s > 0.0) || !std::isfinite(start_timeout_s))
    os << "start timeout " << start_timeout_s << " s must be positive and finite";
  else if (!(episode_timeout_s > 0.0))
    os << "episode timeout " << episode_timeout_s << " s must be positive";
  else if (max_attempts < 1 || max_attempts > 100)
    os << "max attempts " << max_attempts << " must be in [1, 100]";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

/// What the client has heard of the current episode.
struct EpisodeClient::State {
  int64_t episode_id = 0;
  long total = 0;
  std::vector<double> y, u, n;
  std::vector<char> have_y, have_u, have_n;
  long max_step = -1;  // highest y step seen
  double last_progress_s = 0;
  bool summary = false;
  pidlab::lcmt_episode_summary last_summary;
  std::string conflict;  // set once two chunks disagree on a step

  void Reset(int64_t id, long total_steps) {
    *this = State();
    episode_id = id;
    total = total_steps;
    const auto size = static_cast<std::size_t>(total + 1);
    y.assign(size, 0.0);
    u.assign(size, 0.0);
    n.assign(size, 0.0);
    have_y.assign(size, 0);
    have_u.assign(size, 0);
    have_n.assign(size, 0);
  }
  bool Mine(int64_t id) const { return episode_id != 0 && id == episode_id; }
  void OnChunk(const pidlab::lcmt_trajectory_chunk& m) {
    if (!Mine(m.episode_id) || m.step < 0 || m.count < 0 || m.step > total + 1 - m.count) return;
    for (int32_t i = 0; i < m.count && conflict.empty(); ++i) {
      const auto k = static_cast<std::size_t>(m.step + i);
      Take(m.y[i], &y[k], &have_y[k], "y", k, true);
      if (static_cast<long>(k) < total) {
        Take(m.u[i], &u[k], &have_u[k], "u", k, std::isfinite(m.u[i]));
        Take(m.n[i], &n[k], &have_n[k], "n", k, std::isfinite(m.n[i]));
      }
    }
    const long last = static_cast<long>(m.step) + m.count - 1;
    if (m.count > 0 && last > max_step) {
      max_step = last;
      last_progress_s = NowSeconds();
    }
  }
  /// The first value of a step is kept; a different one later is a conflict
  /// (a forged or corrupted chunk), never silently ignored.
  void Take(double value, double* kept, char* have, const char* what, std::size_t k, bool usable) {
    if (!usable) return;
    if (!*have) {
      *kept = value;
      *have = 1;
    } else if (std::memcmp(kept, &value, sizeof value) != 0) {
      std::ostringstream os;
      os << std::setprecision(17) << "conflicting TRAJECTORY messages for step " << k << " of episode "
         << episode_id << ": " << what << " = " << *kept << " and " << what << " = " << value
         << " (a forged or corrupted message on the network; see docs/security.md)";
      conflict = os.str();
    }
  }
  /// First step with something missing, or -1.
  long FirstMissing() const {
    for (long k = 0; k <= total; ++k) {
      if (!have_y[k] || (k < total && (!have_u[k] || !have_n[k]))) return k;
    }
    return -1;
  }
  bool Failed() const { return summary && last_summary.status == pidlab::lcmt_episode_summary::FAILED; }
  bool AtEnd() const {
    return max_step == total || (summary && last_summary.status == pidlab::lcmt_episode_summary::OK);
  }
};

EpisodeClient::EpisodeClient(const EpisodeClientOptions& options) : options_(options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
  own_lcm_ = std::make_unique<lcm::LCM>(options.lcm_url);
  if (!own_lcm_->good()) {
    status_ = Status::RunnerFailed("cannot start LCM on '" + options.lcm_url +
                                   "' (see docs/trio.md: multicast route)");
    return;
  }
  Start(own_lcm_.get());
}

EpisodeClient::EpisodeClient(const EpisodeClientOptions& options, lcm::LCM* lcm) : options_(options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
  if (!lcm || !lcm->good()) {
    status_ = Status::RunnerFailed("the LCM instance given for " + options.lcm_url + " is not good");
    return;
  }
  Start(lcm);
}

void EpisodeClient::Start(lcm::LCM* lcm) {
  try {
    transport_ = std::make_unique<transport::Transport>(lcm, options_.transport);
  } catch (const std::runtime_error& e) {  // the step lanes' LCM
    status_ = Status::RunnerFailed(e.what());
    return;
  }
  Listen();
}

void EpisodeClient::Listen() {
  starter_ = std::make_unique<transport::EpisodeStarter>(transport_.get());
  state_ = std::make_unique<State>();
  State* s = state_.get();
  // The client does not follow the per-step traffic (PLANT_OUTPUT, CONTROL):
  // the plant streams its trajectory in TRAJECTORY chunks (every 1000 steps or
  // 0.1 s), which are also its liveness signal. Whatever chunk is lost is asked
  // for again at the end (TRAJECTORY_REQUEST).
  transport_->Subscribe<pidlab::lcmt_trajectory_chunk>(
      transport::kTrajectoryChannel, [s](const pidlab::lcmt_trajectory_chunk& m) { s->OnChunk(m); });
  transport_->Subscribe<pidlab::lcmt_episode_summary>(transport::kSummaryChannel,
                                                      [s](const pidlab::lcmt_episode_summary& m) {
                                                        if (!s->Mine(m.episode_id)) return;
                                                        s->summary = true;
                                                        s->last_summary = m;
                                                      });
}

EpisodeClient::~EpisodeClient() = default;

const transport::TransportCounters& EpisodeClient::counters() const {
  static const transport::TransportCounters kNone{};
  return transport_ ? transport_->counters() : kNone;
}

evaluation::SampledRunner EpisodeClient::AsRunner() {
  return [this](const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                std::vector<evaluation::SampledStep>* trajectory) {
    return Run(plant, gains, options, disturbance, y_all, trajectory);
  };
}

std::string EpisodeClient::Where() const {
  return " (LCM " + options_.lcm_url + ", prefix " + options_.transport.channel_prefix + ")";
}

bool EpisodeClient::StartEpisode(const pidlab::lcmt_episode_config& config, std::string* error) {
  std::string missing;
  switch (
      starter_->Start(config, {"plant", "controller", "disturbance"}, options_.start_timeout_s, &missing)) {
    case transport::StartStatus::kStarted:
      return true;
    case transport::StartStatus::kLcmError:
      *error = "LCM receive error" + Where();
      return false;
    case transport::StartStatus::kTimedOut:
      break;
  }
  std::ostringstream os;
  os << "no answer from " << missing << " within " << options_.start_timeout_s << " s" << Where()
     << ": is the trio running (pidlab launch)?";
  *error = os.str();
  return false;
}

bool EpisodeClient::FollowEpisode(double t0, double* done_s, long* requests, std::string* error) {
  State& s = *state_;
  const double plant_deadline = options_.recovery.silence_deadline_s + 0.5;
  double last_request = -1e9;
  long last_first = -1;
  for (;;) {
    const double now = NowSeconds();
    if (!s.conflict.empty()) {
      *error = "episode failed: " + s.conflict + Where();
      return false;
    }
    if (s.Failed()) {
      // Text off the wire: escaped and cut before anyone prints it. Without a
      // key the summary's sender cannot be known: say so, so a forged FAILED
      // summary is a loud failure, never mistaken for the plant's verdict.
      *error =
          std::string(options_.transport.auth_key ? "episode failed: "
                                                  : "episode failed (SUMMARY not authenticated, no key): ") +
          transport::EscapeWireText(s.last_summary.message) + Where();
      return false;
    }
    if (now - t0 > options_.episode_timeout_s) {
      std::ostringstream os;
      os << "episode timeout " << options_.episode_timeout_s << " s at step " << s.max_step << " of "
         << s.total;
      *error = os.str();
      return false;
    }
    const bool at_end = s.AtEnd();
    if (at_end && *done_s < 0) *done_s = now;
    if (!at_end && now - s.last_progress_s > plant_deadline) {
      // A client that was itself starved of CPU may have the plant's progress
      // queued unread: read everything waiting before blaming the plant.
      int handled = 0;
      while ((handled = transport_->WaitAndHandle(0.0)) > 0) {
      }
      if (handled < 0) {
        *error = "LCM receive error" + Where();
        return false;
      }
      if (NowSeconds() - s.last_progress_s <= plant_deadline) continue;
      std::ostringstream os;
      os << "no answer from pidlab-plant for " << plant_deadline << " s at step " << s.max_step + 1 << " of "
         << s.total << Where();
      *error = os.str();
      return false;
    }
    if (at_end) {
      const long first = s.FirstMissing();
      // Complete: also wait a little for the SUMMARY (it carries the pacing
      // statistics; the plant repeats it 5 times, 0.1 s apart).
      if (first < 0 && (s.summary || now - *done_s > 0.45)) return true;
      if (first >= 0 && now - *done_s > plant_deadline + 1.0) {
        std::ostringstream os;
        os << "pidlab-plant did not resend step " << first << " of episode " << s.episode_id << Where();
        *error = os.str();
        return false;
      }
      // Ask at once when the previous answer arrived (the first missing step
      // moved on), else again after 10 retransmit intervals.
      if (first >= 0 &&
          (first != last_first || now - last_request >= 10 * options_.recovery.retransmit_interval_s)) {
        pidlab::lcmt_trajectory_request r;
        r.episode_id = s.episode_id;
        r.step = first;
        r.count = static_cast<int32_t>(std::min<long>(transport::kMaxTrajectoryChunk, s.total + 1 - first));
        transport_->Publish(transport::kTrajectoryRequestChannel, &r);
        last_request = now;
        last_first = first;
        ++*requests;
      }
    }
    if (transport_->WaitAndHandle(at_end ? std::min(0.001, options_.recovery.retransmit_interval_s) : 0.05) <
        0) {
      *error = "LCM receive error" + Where();
      return false;
    }
  }
}

bool EpisodeClient::RunOnce(const transport::EpisodeSpec& spec, std::string* error, bool* retryable) {
  const pidlab::lcmt_episode_config config = transport::MakeEpisodeConfig(spec);
  State& s = *state_;
  s.Reset(spec.episode_id, spec.total_steps);
  double done_s = -1;
  long requests = 0;
  *retryable = true;
  // 1. Configuration until all three acknowledge; 2. follow the lockstep
  // until the last y, then fetch whatever was missed.
  const bool ok = StartEpisode(config, error) && [&] {
    const double t0 = NowSeconds();
    s.last_progress_s = t0;
    if (!FollowEpisode(t0, &done_s, &requests, error)) return false;
    ++stats_.episodes;
    stats_.episode_ids.push_back(spec.episode_id);
    stats_.steps += s.total;
    stats_.seconds += (done_s > 0 ? done_s : NowSeconds()) - t0;
    stats_.resend_requests += requests;
    if (s.summary)
      stats_.realtime =
          transport::CombineRealtime(stats_.realtime, transport::RealtimeFromSummary(s.last_summary));
    return true;
  }();
  // Only silence (a dead, stopped or starved process) is worth a re-run: a
  // conflict is tampering, and any other failure the plant reports (e.g. a
  // non-finite control) is deterministic.
  if (!ok && (!s.conflict.empty() || (s.Failed() && s.last_summary.message.rfind("no answer from", 0) != 0)))
    *retryable = false;
  s.episode_id = 0;
  return ok;
}

Status EpisodeClient::Run(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                          const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                          std::vector<evaluation::SampledStep>* trajectory) {
  if (!status_.ok()) return status_;
  std::string why;
  if (!RunOrExplain(plant, gains, options, disturbance, y_all, trajectory, &why))
    return Status::RunnerFailed(why);
  return Status::Ok();
}

Status EpisodeClient::RunRelay(const Plant& plant, const PidGains& previous,
                               const evaluation::LoopOptions& options, const DisturbanceOptions& disturbance,
                               const RelayTuneOptions& relay,
                               std::vector<evaluation::SampledStep>* trajectory) {
  if (!status_.ok()) return status_;
  std::string why;
  std::vector<double> y_all;
  if (!RunOrExplain(plant, previous, options, disturbance, &y_all, trajectory, &why, &relay))
    return Status::RunnerFailed(why);
  return Status::Ok();
}

bool EpisodeClient::RunOrExplain(const Plant& plant, const PidGains& gains,
                                 const evaluation::LoopOptions& options,
                                 const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                                 std::vector<evaluation::SampledStep>* trajectory, std::string* error,
                                 const RelayTuneOptions* relay) {
  transport::EpisodeSpec spec;
  try {
    spec = MakeEpisodeSpec(transport::NewEpisodeId(), plant, gains, options, disturbance, options_.recovery);
  } catch (const std::invalid_argument& e) {
    if (error) *error = e.what();
    return false;
  }
  if (relay) {
    spec.relay = true;
    spec.relay_tune = *relay;
    if (!spec.IsValid(error)) return false;
  }
  std::string why;
  for (int attempt = 1;; ++attempt) {
    bool retryable = true;
    if (RunOnce(spec, &why, &retryable)) break;
    if (!retryable || attempt >= options_.max_attempts) {
      last_failure_retryable_ = retryable;
      if (error) *error = attempt > 1 ? why + " (after " + std::to_string(attempt) + " attempts)" : why;
      return false;
    }
    ++stats_.reruns;
    if (options_.on_note)
      options_.on_note("episode " + std::to_string(spec.episode_id) + " failed (" + why +
                       "); running it again (attempt " + std::to_string(attempt + 1) + " of " +
                       std::to_string(options_.max_attempts) + ")");
    spec.episode_id = transport::NewEpisodeId();
  }
  const State& s = *state_;
  y_all->assign(s.y.begin(), s.y.end());
  if (trajectory) {
    trajectory->clear();
    trajectory->reserve(static_cast<std::size_t>(s.total));
    for (long k = 0; k < s.total; ++k) {
      const auto i = static_cast<std::size_t>(k);
      trajectory->push_back({k, static_cast<double>(k) * spec.dt_s, spec.reference, s.y[i], s.u[i], s.n[i]});
    }
  }
  return true;
}

}  // namespace pidlab::episode_client
