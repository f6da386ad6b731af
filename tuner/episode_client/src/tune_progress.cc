#include "pidlab/episode_client/tune_progress.h"

#include <cmath>
#include <limits>
#include <pidlab/lcmt_tune_progress.hpp>
#include <random>
#include <stdexcept>

#include "pidlab/transport/protocol.h"

namespace pidlab::episode_client {

TuneProgressPublisher::TuneProgressPublisher(const EpisodeClientOptions& trio, int trios, std::string method,
                                             std::string objective, double min_interval_s)
    : TuneProgressPublisher(nullptr, trio, trios, std::move(method), std::move(objective), min_interval_s) {}

TuneProgressPublisher::TuneProgressPublisher(lcm::LCM* lcm, const EpisodeClientOptions& trio, int trios,
                                             std::string method, std::string objective, double min_interval_s)
    : trios_(trios),
      method_(std::move(method)),
      objective_(std::move(objective)),
      min_interval_s_(min_interval_s) {
  if (!lcm) {
    own_lcm_ = std::make_unique<lcm::LCM>(trio.lcm_url);
    if (!own_lcm_->good()) throw std::runtime_error("LCM could not start on " + trio.lcm_url);
    lcm = own_lcm_.get();
  }
  transport::TransportOptions options = trio.transport;
  options.drop_rate = 0.0;  // fault injection is for receiving; this only sends
  transport_ = std::make_unique<transport::Transport>(lcm, options);
  std::random_device device;
  id_ = static_cast<int64_t>((static_cast<uint64_t>(device()) << 31) ^ device()) & 0x7fffffffffffffffLL;
}

TuneProgressPublisher::~TuneProgressPublisher() = default;

void TuneProgressPublisher::Running(const optim::TracePoint& point) {
  last_ = point;
  const double now = transport::NowSeconds();
  if (now - last_sent_s_ < min_interval_s_) return;
  last_sent_s_ = now;
  const bool any = point.best_x.size() >= 3;
  const double gains[3] = {any ? point.best_x(0) : NAN, any ? point.best_x(1) : NAN,
                           any ? point.best_x(2) : NAN};
  Send(pidlab::lcmt_tune_progress::RUNNING, point.best_f, gains);
}

void TuneProgressPublisher::Finished(bool ok, const PidGains& gains, double objective, long evaluations) {
  const double g[3] = {gains.kp, gains.ki, gains.kd};
  last_.evaluations = static_cast<int>(evaluations);
  Send(ok ? pidlab::lcmt_tune_progress::DONE : pidlab::lcmt_tune_progress::FAILED,
       ok ? objective : std::numeric_limits<double>::infinity(), g);
}

void TuneProgressPublisher::Send(int8_t status, double best_objective, const double* gains) {
  pidlab::lcmt_tune_progress m{};
  m.episode_id = id_;
  m.step = last_.iteration;
  m.status = status;
  m.evaluations = last_.evaluations;
  m.best_objective = best_objective;
  for (int i = 0; i < 3; ++i) m.best_gains[i] = gains[i];
  m.trios = trios_;
  m.method = method_;
  m.objective = objective_;
  transport_->Publish(transport::kTuneProgressChannel, &m);  // a lost one is only a watcher's gap
}

}  // namespace pidlab::episode_client
