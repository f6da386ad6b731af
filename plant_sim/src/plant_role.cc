#include "pidlab/plant_sim/plant_role.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_pacing_progress.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <sstream>

#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"

namespace pidlab::plant_sim {
using transport::DescribeRealtime;
using transport::EpisodeSpec;
using transport::kControlChannel;
using transport::kDisturbanceBlockChannel;
using transport::kDisturbanceRequestChannel;
using transport::kMaxNoiseRequest;
using transport::kMaxTrajectoryChunk;
using transport::kNoiseBlock;
using transport::kNoiseLookahead;
using transport::kPlantOutputChannel;
using transport::kSummaryChannel;
using transport::kTrajectoryChannel;
using transport::kTrajectoryRequestChannel;
using transport::LogFn;
using transport::NowSeconds;
using transport::Pacer;
using transport::RealtimeStats;
using transport::Role;
using transport::RttEstimator;
using transport::RttOptions;
using transport::SetRealtime;
using transport::Transport;

namespace {
constexpr int kStreamChunk = 1000;      // the plant streams its trajectory in chunks of this many steps...
constexpr double kStreamPeriod = 0.1;   // ...or of whatever is new after this many seconds (liveness)
constexpr int kResendCopies = 2;        // datagrams per resend of y_k (Tick)
constexpr int kSummaryRepeats = 5;      // a summary is repeated this often...
constexpr double kSummaryPeriod = 0.1;  // ...this many seconds apart
constexpr long kNoiseCheckSteps = 32;   // every this many steps the plant re-requests n it lacks (below)
const double kNaN = std::numeric_limits<double>::quiet_NaN();

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::string Bits(double v) {
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}
}  // namespace

struct PlantRole::Episode {
  EpisodeSpec spec;
  std::unique_ptr<DiscretePlant> plant;          // a linear plant: exact ZOH
  std::unique_ptr<NonlinearStepperPlant> motor;  // stepper_nonlinear: the motor, integrated
  double Output() const { return motor ? motor->Output() : plant->Output(); }
  void Step(double input) { motor ? motor->Step(input) : plant->Step(input); }
  long k = 0;
  bool have_u = false;
  double u = 0;
  std::vector<double> y_hist, u_hist, n_hist;  // n_hist[k]: n_k once its block arrived
  std::vector<char> have_n;                    // per step
  long n_requested_end = 0;                    // n requested for steps [0, n_requested_end)
  long n_check_end = 0;                        // n_requested_end at the last gap check
  long streamed = 0;                           // trajectory streamed for steps [0, streamed)
  double stream_last_s = 0;
  double step_start_s = 0, last_send_s = 0, start_s = 0;
  double y_sent_s = 0;    // first transmission of y_k
  bool y_resent = false;  // y_k (or a request at step k) was resent: no round-trip sample (Karn)
  int resends = 0;        // resends at step k
  bool finished = false;
  std::unique_ptr<Pacer> pacer;  // with --realtime
  pidlab::lcmt_episode_summary summary;
  int summary_sent = 0;
  double summary_last_s = 0;
  // The process's lifetime counters when this episode started: the episode's
  // own counts are the differences.
  long retransmits_at_start = 0;
  long dropped_at_start = 0;
};

PlantRole::PlantRole(Transport* transport, LogFn log, bool verbose, double realtime_factor)
    : Role(transport, "plant", std::move(log), verbose), realtime_factor_(realtime_factor) {
  transport_->Subscribe<pidlab::lcmt_control_command>(
      kControlChannel, [this](const pidlab::lcmt_control_command& m) { OnControl(m); });
  transport_->Subscribe<pidlab::lcmt_disturbance_block>(
      kDisturbanceBlockChannel, [this](const pidlab::lcmt_disturbance_block& m) { OnDisturbanceBlock(m); });
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
  if (spec.plant.nonlinear) {
    ep->motor = std::make_unique<NonlinearStepperPlant>(*spec.plant.nonlinear, spec.dt_s);
    ep->motor->Reset();
  } else {
    // With its dead time: the applied input (control plus disturbance) acts
    // delay_s later, as in the in-process loop (DelayedPlantStep).
    ep->plant = std::make_unique<DiscretePlant>(spec.plant.tf, spec.dt_s, spec.plant.delay_s);
    ep->plant->Reset();
  }
  const auto n = static_cast<std::size_t>(spec.total_steps);
  ep->y_hist.assign(n + 1, kNaN);
  ep->u_hist.assign(n + 1, kNaN);
  ep->n_hist.assign(n + 1, kNaN);
  ep->have_n.assign(n + 1, 0);
  // y as the plant reports it: with measurement noise y_k + v_k, the same
  // function as the in-process loop (MeasurementNoise::Measured).
  ep->y_hist[0] = spec.measurement_noise.Measured(ep->Output(), 0);
  ep->start_s = ep->step_start_s = ep->stream_last_s = NowSeconds();
  ep->retransmits_at_start = counters_.retransmits;
  ep->dropped_at_start = transport_->counters().dropped;
  ep_ = std::move(ep);
  running_ = true;
  if (!rtt_.has_sample()) {
    // The estimate carries over from episode to episode (it measures the
    // network, not the episode); before the first round trip the episode's
    // retransmit interval is the timeout.
    RttOptions o;
    o.initial_s = spec.recovery.retransmit_interval_s;
    o.ceiling_s = std::max(o.ceiling_s, o.initial_s);
    rtt_ = RttEstimator(o);
  }
  ep_->n_requested_end = std::min<long>(kNoiseLookahead, spec.total_steps);
  RequestNoise(0, ep_->n_requested_end);
  if (realtime_factor_ > 0.0) {
    ep_->pacer = std::make_unique<Pacer>(realtime_factor_, spec.dt_s, spec.total_steps);
    ep_->pacer->Start();  // step 0 starts now: t0
  }
  PublishOutput();
  ep_->y_sent_s = ep_->last_send_s;
}

void PlantRole::RequestNoise(long first, long samples) {
  if (samples <= 0) return;
  pidlab::lcmt_disturbance_request r;
  r.episode_id = ep_->spec.episode_id;
  r.step = first;
  r.samples = static_cast<int32_t>(samples);
  transport_->Publish(kDisturbanceRequestChannel, &r);
}

void PlantRole::PublishChunk(const Episode& ep, long first, long last) {
  pidlab::lcmt_trajectory_chunk c;
  c.episode_id = ep.spec.episode_id;
  c.step = first;
  c.count = static_cast<int32_t>(last - first);
  c.y.assign(ep.y_hist.begin() + first, ep.y_hist.begin() + last);
  c.u.assign(ep.u_hist.begin() + first, ep.u_hist.begin() + last);
  c.n.assign(ep.n_hist.begin() + first, ep.n_hist.begin() + last);
  transport_->Publish(kTrajectoryChannel, &c);
}

void PlantRole::StreamTrajectory(long upto) {
  Episode& e = *ep_;
  while (e.streamed < upto) {
    const long last = std::min<long>(upto, e.streamed + kMaxTrajectoryChunk);
    PublishChunk(e, e.streamed, last);
    e.streamed = last;
  }
  e.stream_last_s = NowSeconds();
  if (e.pacer) {  // the live pacing figures, for watchers (pidlab serve --lcm-url)
    pidlab::lcmt_pacing_progress p;
    p.episode_id = e.spec.episode_id;
    transport::SetPacingProgress(e.pacer->Progress(), &p);
    transport_->Publish(transport::kPacingChannel, &p);
  }
}

void PlantRole::PublishOutput() {
  pidlab::lcmt_plant_output m;
  m.episode_id = ep_->spec.episode_id;
  m.step = ep_->k;
  m.t_s = static_cast<double>(ep_->k) * ep_->spec.dt_s;
  m.y = ep_->y_hist[static_cast<std::size_t>(ep_->k)];
  transport_->Publish(kPlantOutputChannel, &m);
  ep_->last_send_s = NowSeconds();
}

void PlantRole::OnControl(const pidlab::lcmt_control_command& m) {
  if (!running_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  if (m.step < 0 || m.step > e.k) {  // no controller answers a y the plant has not published
    ++counters_.foreign;
    return;
  }
  const auto k = static_cast<std::size_t>(m.step);
  // The command says which y it was computed from: anything but the y this
  // plant published means a second PLANT_OUTPUT for that step reached the
  // controller (a forged or corrupted one).
  if (!SameBits(m.y, e.y_hist[k])) {
    Conflict(kPlantOutputChannel, m.step,
             "the controller answered y = " + Bits(m.y) + ", the plant published y = " + Bits(e.y_hist[k]));
    return;
  }
  const bool used = m.step < e.k || e.have_u;
  if (used) {
    const double kept = m.step < e.k ? e.u_hist[k] : e.u;
    if (!SameBits(m.u, kept)) {
      Conflict(kControlChannel, m.step, "u = " + Bits(kept) + " and u = " + Bits(m.u));
      return;
    }
    ++counters_.duplicates;
    return;
  }
  if (m.status == pidlab::lcmt_control_command::INVALID_INPUT || !std::isfinite(m.u)) {
    Finish(false, "controller",
           "pidlab-controller could not compute u at step " + std::to_string(m.step) +
               " (invalid input or non-finite output)");
    return;
  }
  e.u = m.u;
  e.have_u = true;
  if (!e.y_resent) rtt_.Sample(NowSeconds() - e.y_sent_s);  // Karn: only exchanges sent once
  TryAdvance();
}

void PlantRole::Conflict(const char* channel, int64_t step, const std::string& detail) {
  ++counters_.conflicts;
  Finish(false, "",
         "conflicting " + std::string(channel) + " messages for step " + std::to_string(step) +
             " of episode " + std::to_string(ep_->spec.episode_id) + ": " + detail +
             " (a forged or corrupted message on the network; see docs/security.md)");
}

void PlantRole::OnDisturbanceBlock(const pidlab::lcmt_disturbance_block& m) {
  if (!running_ || m.episode_id != ep_->spec.episode_id) {
    ++counters_.foreign;
    return;
  }
  Episode& e = *ep_;
  if (m.step < 0 || m.count < 0 || m.step > e.spec.total_steps - m.count ||
      m.n.size() != static_cast<std::size_t>(m.count)) {
    ++counters_.foreign;  // not an answer of this episode's disturbance
    return;
  }
  bool fresh = false;
  for (int32_t i = 0; i < m.count; ++i) {
    const auto k = static_cast<std::size_t>(m.step + i);
    const double n = m.n[static_cast<std::size_t>(i)];
    if (e.have_n[k]) {
      if (!SameBits(n, e.n_hist[k])) {
        Conflict(kDisturbanceBlockChannel, m.step + i, "n = " + Bits(e.n_hist[k]) + " and n = " + Bits(n));
        return;
      }
      continue;
    }
    e.n_hist[k] = n;
    e.have_n[k] = 1;
    fresh = true;
  }
  if (!fresh) {
    ++counters_.duplicates;
    return;
  }
  TryAdvance();
}

void PlantRole::TryAdvance() {
  Episode& e = *ep_;
  const auto k = static_cast<std::size_t>(e.k);
  if (!e.have_u || !e.have_n[k]) return;
  e.u_hist[k] = e.u;
  // Same operation and order as RunSampledLoop (RunNonlinearSampledLoop for
  // the motor): input = u + n, then ZOH.
  e.Step(e.u + e.n_hist[k]);
  ++e.k;
  e.have_u = false;
  e.y_hist[k + 1] = e.spec.measurement_noise.Measured(e.Output(), static_cast<std::int64_t>(k + 1));
  if (e.pacer) e.pacer->WaitForStep(e.k);  // step k starts no earlier than t0 + k dt / factor
  e.step_start_s = NowSeconds();
  e.y_resent = false;
  e.resends = 0;
  rtt_.EndBackoff();  // progress: the path works again
  if (e.k == e.spec.total_steps) {
    PublishOutput();
    StreamTrajectory(e.k + 1);  // the rest, y_N too (u and n NaN there)
    Finish(true, "", "");
    return;
  }
  PublishOutput();
  e.y_sent_s = e.last_send_s;
  // Keep n requested ahead: one request and one block per kNoiseBlock steps.
  if (e.n_requested_end < e.spec.total_steps && e.n_requested_end - e.k <= kNoiseLookahead - kNoiseBlock) {
    const long samples = std::min<long>(kNoiseBlock, e.spec.total_steps - e.n_requested_end);
    RequestNoise(e.n_requested_end, samples);
    e.n_requested_end += samples;
  }
  // A block lost on the way would stall the step that needs it by a resend
  // timeout: every kNoiseCheckSteps steps, ask again for n still missing
  // among the steps requested at the previous check (long enough ago for
  // any answer to have arrived), before the lockstep reaches them.
  if (e.k % kNoiseCheckSteps == 0) {
    const long end = std::min<long>(e.n_check_end, e.spec.total_steps);
    for (long s = e.k; s < end; ++s) {
      if (e.have_n[static_cast<std::size_t>(s)]) continue;
      ++counters_.retransmits;
      Verbose("asking again for n from step " + std::to_string(s) + " at step " + std::to_string(e.k));
      RequestNoise(s, std::min<long>(end - s, kMaxNoiseRequest));
      break;
    }
    e.n_check_end = e.n_requested_end;
  }
  if (e.k - e.streamed >= kStreamChunk) StreamTrajectory(e.k);
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
  const RealtimeStats realtime = e.pacer ? e.pacer->Stats() : RealtimeStats{};
  SetRealtime(realtime, &s);
  transport_->Publish(kSummaryChannel, &s);
  e.summary_sent = 1;
  e.summary_last_s = NowSeconds();
  std::ostringstream os;
  const double wall = NowSeconds() - e.start_s;
  os << "episode " << e.spec.episode_id << ": " << (ok ? "done" : "FAILED") << ", plant " << e.spec.plant.name
     << ", " << e.k << "/" << e.spec.total_steps << " steps in " << wall << " s";
  if (ok) os << ", y_final " << s.final_y;
  if (!ok) os << ": " << message;
  os << " (resent " << counters_.retransmits - e.retransmits_at_start << ", dropped "
     << transport_->counters().dropped - e.dropped_at_start << ", round trip "
     << std::lround(rtt_.srtt_s() * 1e6) << " us, resend timeout " << std::lround(rtt_.BaseTimeout() * 1e6)
     << " us)";
  if (realtime.paced()) os << "; " << DescribeRealtime(realtime);
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
  if (m.step < 0 || m.step > ep->k || m.count <= 0) {
    ++counters_.foreign;
    return;
  }
  const long first = static_cast<long>(m.step);
  const long last = std::min<long>(first + std::min<long>(m.count, kMaxTrajectoryChunk), ep->k + 1);
  if (last <= first) return;
  PublishChunk(*ep, first, last);
}

double PlantRole::MaxWait() const {
  if (!running_) return 0.05;
  const Episode& e = *ep_;
  const double next = std::min({e.last_send_s + rtt_.Timeout(), e.stream_last_s + kStreamPeriod,
                                e.step_start_s + e.spec.recovery.silence_deadline_s});
  return std::clamp(next - NowSeconds(), 0.0, 0.05);
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
  const bool have_n = e.have_n[static_cast<std::size_t>(e.k)] != 0;
  if (now_s - e.step_start_s >= e.spec.recovery.silence_deadline_s) {
    std::string silent;
    if (!e.have_u) silent = "controller";
    if (!have_n) silent += silent.empty() ? "disturbance" : ",disturbance";
    std::ostringstream os;
    os << "no answer from pidlab-"
       << (silent == "controller,disturbance" ? "controller and pidlab-disturbance" : silent) << " for "
       << e.spec.recovery.silence_deadline_s << " s at step " << e.k << " of " << e.spec.total_steps;
    Finish(false, silent, os.str());
    return;
  }
  if (now_s - e.last_send_s >= rtt_.Timeout()) {
    // Ask again only for what is missing: y_k makes the controller repeat u_k,
    // a request makes the disturbance resend the blocks from n_k on. From the
    // second resend of the same step on, the timeout doubles (up to the
    // ceiling) until the step completes: a lost message is chance here, not
    // congestion, so a single loss waits one timeout, a double loss two, and a
    // dead peer is asked at most about 10 times a second.
    ++counters_.retransmits;
    e.y_resent = true;
    if (e.resends++ >= 1) rtt_.Backoff();
    Verbose(std::string("resending") + (e.have_u ? "" : " y") + (have_n ? "" : " n request") + " at step " +
            std::to_string(e.k) + " after " + std::to_string(std::lround(rtt_.Timeout() * 1e6)) + " us");
    if (!have_n) {
      const long samples = std::min<long>(kNoiseLookahead, e.spec.total_steps - e.k);
      RequestNoise(e.k, samples);
      e.n_requested_end = std::max(e.n_requested_end, e.k + samples);
    }
    // A resend goes out as kResendCopies datagrams: the controller answers
    // each from its cache, and the exchange is lost again only if every copy
    // or every answer is. At 20 % loss in each process one exchange fails
    // with p = 0.36 and two copies with 0.13, which cuts the waits behind a
    // loss by about a quarter (docs/trio.md, "Loss recovery").
    if (!e.have_u)
      for (int copy = 0; copy < kResendCopies; ++copy) PublishOutput();
    else
      e.last_send_s = now_s;
  }
  if (now_s - e.stream_last_s >= kStreamPeriod) StreamTrajectory(e.k);  // also the client's liveness signal
}

}  // namespace pidlab::plant_sim
