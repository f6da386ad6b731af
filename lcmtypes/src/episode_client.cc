#include "pidlab/lcm/episode_client.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

namespace pidlab::lcm_trio {
namespace {
constexpr double kConfigResendPeriod = 0.05;  // s
constexpr int kRequestChunk = 2000;           // steps per resend request

int64_t NewEpisodeId() {
  // An identifier, not an input of the computation: any unique value will do.
  std::random_device rd;
  const uint64_t a = (static_cast<uint64_t>(rd()) << 32) ^ rd();
  const auto t = static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  const int64_t id =
      static_cast<int64_t>((a ^ (t * 0x9E3779B97F4A7C15ull) ^ static_cast<uint64_t>(getpid())) >> 1);
  return id == 0 ? 1 : id;
}
}  // namespace

bool EpisodeClientOptions::IsValid(std::string* error) const {
  if (!transport.IsValid(error) || !recovery.IsValid(error)) return false;
  std::ostringstream os;
  if (!(start_timeout_s > 0.0) || !std::isfinite(start_timeout_s))
    os << "start timeout " << start_timeout_s << " s must be positive and finite";
  else if (!(episode_timeout_s > 0.0))
    os << "episode timeout " << episode_timeout_s << " s must be positive";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

struct EpisodeClient::State {
  int64_t episode_id = 0;
  long total = 0;
  std::set<std::string> acked;
  std::vector<double> y, u, n;
  std::vector<char> have_y, have_u, have_n;
  long max_step = -1;  // highest y step seen
  double last_progress_s = 0;
  bool summary = false;
  pidlab::lcmt_episode_summary last_summary;

  bool Complete() const {
    for (long k = 0; k <= total; ++k) {
      if (!have_y[k]) return false;
      if (k < total && (!have_u[k] || !have_n[k])) return false;
    }
    return true;
  }
  /// First step with something missing, or -1.
  long FirstMissing() const {
    for (long k = 0; k <= total; ++k) {
      if (!have_y[k] || (k < total && (!have_u[k] || !have_n[k]))) return k;
    }
    return -1;
  }
};

EpisodeClient::EpisodeClient(const EpisodeClientOptions& options) : options_(options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
  lcm_ = std::make_unique<lcm::LCM>(options.lcm_url);
  if (!lcm_->good())
    throw std::runtime_error("cannot start LCM on '" + options.lcm_url +
                             "' (see docs/trio.md: multicast route)");
  transport_ = std::make_unique<Transport>(lcm_.get(), options.transport);
  state_ = std::make_unique<State>();
  State* s = state_.get();
  auto mine = [s](int64_t id) { return s->episode_id != 0 && id == s->episode_id; };
  transport_->Subscribe<pidlab::lcmt_ready>(kReadyChannel, [s, mine](const pidlab::lcmt_ready& m) {
    if (m.state == pidlab::lcmt_ready::CONFIG_ACK && mine(m.episode_id)) s->acked.insert(m.role);
  });
  // The client does not follow the per-step traffic (PLANT_OUTPUT, CONTROL):
  // the plant streams its trajectory in TRAJECTORY chunks (every 1000 steps or
  // 0.1 s), which are also its liveness signal. Whatever chunk is lost is asked
  // for again at the end (TRAJECTORY_REQUEST).
  transport_->Subscribe<pidlab::lcmt_trajectory_chunk>(
      kTrajectoryChannel, [s, mine](const pidlab::lcmt_trajectory_chunk& m) {
        if (!mine(m.episode_id) || m.step < 0 || m.count < 0 || m.step + m.count > s->total + 1) return;
        for (int32_t i = 0; i < m.count; ++i) {
          const auto k = static_cast<std::size_t>(m.step + i);
          if (!s->have_y[k]) s->y[k] = m.y[i], s->have_y[k] = 1;
          if (static_cast<long>(k) < s->total) {
            if (!s->have_u[k] && std::isfinite(m.u[i])) s->u[k] = m.u[i], s->have_u[k] = 1;
            if (!s->have_n[k] && std::isfinite(m.n[i])) s->n[k] = m.n[i], s->have_n[k] = 1;
          }
        }
        const long last = static_cast<long>(m.step) + m.count - 1;
        if (m.count > 0 && last > s->max_step) {
          s->max_step = last;
          s->last_progress_s = NowSeconds();
        }
      });
  transport_->Subscribe<pidlab::lcmt_episode_summary>(kSummaryChannel,
                                                      [s, mine](const pidlab::lcmt_episode_summary& m) {
                                                        if (!mine(m.episode_id)) return;
                                                        s->summary = true;
                                                        s->last_summary = m;
                                                      });
}

EpisodeClient::~EpisodeClient() = default;

const TransportCounters& EpisodeClient::counters() const { return transport_->counters(); }

SampledRunner EpisodeClient::AsRunner() {
  return [this](const Plant& plant, const PidGains& gains, const LoopOptions& options,
                const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                std::vector<SampledStep>* trajectory, std::string* error) {
    return Run(plant, gains, options, disturbance, y_all, trajectory, error);
  };
}

bool EpisodeClient::Run(const Plant& plant, const PidGains& gains, const LoopOptions& options,
                        const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                        std::vector<SampledStep>* trajectory, std::string* error) {
  auto fail = [error](const std::string& what) {
    if (error) *error = what;
    return false;
  };
  State& s = *state_;
  pidlab::lcmt_episode_config config =
      MakeEpisodeConfig(NewEpisodeId(), plant, gains, options, disturbance, options_.recovery);
  {
    EpisodeSpec check;
    std::string why;
    if (!ParseEpisodeConfig(config, &check, &why)) return fail("invalid episode: " + why);
  }
  const long total = static_cast<long>(config.total_steps);
  s = State();
  s.total = total;
  const auto size = static_cast<std::size_t>(total + 1);
  s.y.assign(size, 0.0);
  s.u.assign(size, 0.0);
  s.n.assign(size, 0.0);
  s.have_y.assign(size, 0);
  s.have_u.assign(size, 0);
  s.have_n.assign(size, 0);
  s.episode_id = config.episode_id;

  const char* roles[] = {"plant", "controller", "disturbance"};
  const double start = NowSeconds();
  double last_config = -1e9;
  std::ostringstream where;
  where << " (LCM " << options_.lcm_url << ", prefix " << options_.transport.channel_prefix << ")";
  // 1. Configuration until all three acknowledge.
  while (s.acked.size() < 3 ||
         !(s.acked.count("plant") && s.acked.count("controller") && s.acked.count("disturbance"))) {
    const double now = NowSeconds();
    if (now - start > options_.start_timeout_s) {
      std::string missing;
      for (const char* r : roles)
        if (!s.acked.count(r)) missing += (missing.empty() ? "pidlab-" : ", pidlab-") + std::string(r);
      std::ostringstream os;
      os << "no answer from " << missing << " within " << options_.start_timeout_s << " s" << where.str()
         << ": is the trio running (pidlab launch)?";
      s.episode_id = 0;
      return fail(os.str());
    }
    if (now - last_config >= kConfigResendPeriod) {
      transport_->Publish(kEpisodeConfigChannel, &config);
      last_config = now;
    }
    if (transport_->WaitAndHandle(0.01) < 0) return fail("LCM receive error" + where.str());
  }
  const double t0 = NowSeconds();
  s.last_progress_s = t0;
  // 2. Follow the lockstep until the last y, then fetch whatever was missed.
  const double plant_deadline = options_.recovery.silence_deadline_s + 0.5;
  double last_request = -1e9;
  long requests = 0;
  double done_s = -1;
  for (;;) {
    const double now = NowSeconds();
    if (s.summary && s.last_summary.status == pidlab::lcmt_episode_summary::FAILED) {
      s.episode_id = 0;
      return fail("episode failed: " + s.last_summary.message + where.str());
    }
    if (now - t0 > options_.episode_timeout_s) {
      std::ostringstream os;
      os << "episode timeout " << options_.episode_timeout_s << " s at step " << s.max_step << " of "
         << total;
      s.episode_id = 0;
      return fail(os.str());
    }
    const bool at_end =
        s.max_step == total || (s.summary && s.last_summary.status == pidlab::lcmt_episode_summary::OK);
    if (at_end && done_s < 0) done_s = now;
    if (!at_end && now - s.last_progress_s > plant_deadline) {
      // A client that was itself starved of CPU may have the plant's progress
      // queued unread: read everything waiting before blaming the plant.
      int handled = 0;
      while ((handled = transport_->WaitAndHandle(0.0)) > 0) {
      }
      if (handled < 0) return fail("LCM receive error" + where.str());
      if (NowSeconds() - s.last_progress_s <= plant_deadline) continue;
      std::ostringstream os;
      os << "no answer from pidlab-plant for " << plant_deadline << " s at step " << s.max_step + 1 << " of "
         << total << where.str();
      s.episode_id = 0;
      return fail(os.str());
    }
    if (at_end) {
      const long first = s.FirstMissing();
      if (first < 0) break;
      if (now - done_s > plant_deadline + 1.0) {
        std::ostringstream os;
        os << "pidlab-plant did not resend step " << first << " of episode " << s.episode_id << where.str();
        s.episode_id = 0;
        return fail(os.str());
      }
      if (now - last_request >= 10 * options_.recovery.retransmit_interval_s) {
        pidlab::lcmt_trajectory_request r;
        r.episode_id = s.episode_id;
        r.step = first;
        r.count = static_cast<int32_t>(std::min<long>(kRequestChunk, total + 1 - first));
        transport_->Publish(kTrajectoryRequestChannel, &r);
        last_request = now;
        ++requests;
      }
    }
    if (transport_->WaitAndHandle(at_end ? options_.recovery.retransmit_interval_s : 0.05) < 0)
      return fail("LCM receive error" + where.str());
  }
  const double t1 = done_s > 0 ? done_s : NowSeconds();
  ++stats_.episodes;
  stats_.steps += total;
  stats_.seconds += t1 - t0;
  stats_.resent_steps += requests;
  const double dt = options.dt_s;
  y_all->assign(s.y.begin(), s.y.end());
  if (trajectory) {
    trajectory->clear();
    trajectory->reserve(static_cast<std::size_t>(total));
    for (long k = 0; k < total; ++k) {
      const auto i = static_cast<std::size_t>(k);
      trajectory->push_back({k, static_cast<double>(k) * dt, config.reference, s.y[i], s.u[i], s.n[i]});
    }
  }
  s.episode_id = 0;
  return true;
}

}  // namespace pidlab::lcm_trio
