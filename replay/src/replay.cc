#include "pidlab/replay/replay.h"

#include <cmath>
#include <cstring>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <sstream>
#include <stdexcept>

#include "pidlab/controller/relay.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/transport/episode_start.h"

using pidlab::episode_client::SampledLoopOptions;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::EvaluateSampledRun;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopGains;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::RunSampledLoopInProcess;
using pidlab::evaluation::SampledRun;
using pidlab::evaluation::SampledStep;

namespace pidlab::replay {
namespace {

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::string Full(double v) {
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}

}  // namespace

bool EpisodeTrajectory(const Episode& e, std::vector<SampledStep>* trajectory) {
  if (!e.Complete()) return false;
  trajectory->clear();
  trajectory->reserve(static_cast<std::size_t>(e.total_steps));
  const double dt = e.spec.dt_s;
  for (long k = 0; k < e.total_steps; ++k)
    trajectory->push_back({k, static_cast<double>(k) * dt, e.spec.reference, e.y[k], e.u[k], e.n[k]});
  return true;
}

Status EvaluateEpisode(const Episode& e, Evaluation* evaluation) {
  if (!e.has_config) return Status::InvalidInput(e.CompletenessNote());
  if (!e.Complete()) return Status::InvalidInput("incomplete: " + e.CompletenessNote());
  // The run as the log recorded it; the undisturbed response, which no
  // episode of the log holds, is the loop run in process without the
  // disturbance.
  const LoopOptions options = SampledLoopOptions(e.spec);
  SampledRun run;
  run.y = e.y;
  EpisodeTrajectory(e, &run.trajectory);
  if (options.disturbance.kind != DisturbanceKind::kNone)
    RunSampledLoopInProcess(e.spec.plant, LoopGains(e.spec.gains, options), options, DisturbanceOptions{},
                            &run.y_undisturbed, nullptr);
  EvaluateOptions what;
  what.record_trajectory = true;
  return EvaluateSampledRun(e.spec.plant, e.spec.gains, options, what, run, evaluation);
}

RedriveResult Redrive(const Episode& e) {
  RedriveResult r;
  if (!e.has_config) {
    r.message = e.CompletenessNote();
    return r;
  }
  PidOptions pid = e.spec.pid;
  pid = PidOptionsAt(pid, e.spec.dt_s);
  DiscretePid<double> dut(e.spec.gains, pid);
  // A relay episode (docs/autotune.md): the controller's RelayTuner, stepped
  // at the times the plant published, t_k = k dt.
  std::unique_ptr<RelayTuner> relay;
  if (e.spec.relay) relay = std::make_unique<RelayTuner>(e.spec.relay_tune, e.spec.gains, pid);
  for (long k = 0; k < e.total_steps; ++k) {
    if (!e.has_y[k] || !e.has_u[k]) {
      r.message = "cannot re-drive past step " + std::to_string(k) + ": the log has no " +
                  (e.has_y[k] ? "command" : "plant output") + " for it";
      return r;
    }
    double u = 0.0;
    if (relay)
      u = std::isfinite(e.y[k]) ? relay->Step(static_cast<double>(k) * e.spec.dt_s, e.spec.reference, e.y[k])
                                : 0.0;
    else
      dut.Step(e.spec.reference, e.y[k], &u);
    ++r.steps_checked;
    if (!SameBits(u, e.u[k])) {
      r.first_mismatch = k;
      r.logged_u = e.u[k];
      r.recomputed_u = u;
      std::ostringstream os;
      os << std::setprecision(17) << "first mismatch at step " << k
         << " (t = " << static_cast<double>(k) * pid.dt_s << " s): logged u = " << e.u[k]
         << ", recomputed u = " << u << " from y = " << e.y[k];
      r.message = os.str();
      return r;
    }
  }
  r.ok = true;
  r.message = "all " + std::to_string(r.steps_checked) + " commands reproduced bit for bit";
  return r;
}

namespace {

// Re-drives a live pidlab-controller (started alone, without plant and
// disturbance) with the logged plant outputs, one step at a time: publish y_k,
// wait for the command of step k (resending y_k on silence), compare bits.
// Throws std::invalid_argument (LCM) or std::runtime_error (the controller).
RedriveResult RedriveOverLcmThrowing(const Episode& e, const std::string& url, const std::string& prefix,
                                     double deadline_s) {
  RedriveResult r;
  if (!e.has_config) {
    r.message = e.CompletenessNote();
    return r;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) throw std::invalid_argument("--lcm-url '" + url + "': LCM cannot start");
  transport::TransportOptions topt;
  topt.channel_prefix = prefix;
  topt.step_lane_base_url = url;
  transport::Transport transport(&lcm, topt);
  const int64_t id = transport::NewEpisodeId();  // a fresh episode, never the logged one
  long answered_step = -1;
  double answered_u = 0.0;
  transport::EpisodeStarter starter(&transport);
  transport.Subscribe<pidlab::lcmt_control_command>(transport::kControlChannel,
                                                    [&](const pidlab::lcmt_control_command& m) {
                                                      if (m.episode_id == id && m.step == answered_step + 1)
                                                        answered_step = m.step, answered_u = m.u;
                                                    });
  transport::EpisodeSpec spec = e.spec;
  spec.episode_id = id;
  const double retransmit_s = 0.01;
  std::string missing;
  if (starter.Start(transport::MakeEpisodeConfig(spec), {"controller"}, deadline_s, &missing, retransmit_s) !=
      transport::StartStatus::kStarted)
    throw std::runtime_error("no pidlab-controller acknowledged the episode on " + url + " prefix " + prefix +
                             " (start one alone: pidlab-controller --lcm-url ...)");
  for (long k = 0; k < e.total_steps; ++k) {
    if (!e.has_y[k] || !e.has_u[k]) {
      r.message = "cannot re-drive past step " + std::to_string(k) + ": the log has no " +
                  (e.has_y[k] ? "command" : "plant output") + " for it";
      return r;
    }
    pidlab::lcmt_plant_output y{};
    y.episode_id = id;
    y.step = k;
    y.t_s = static_cast<double>(k) * e.spec.dt_s;
    y.y = e.y[k];
    for (double start = transport::NowSeconds(); answered_step < k;) {
      if (transport::NowSeconds() - start > deadline_s)
        throw std::runtime_error("pidlab-controller did not answer step " + std::to_string(k) + " within " +
                                 Full(deadline_s) + " s");
      transport.Publish(transport::kPlantOutputChannel, &y);
      for (double sent = transport::NowSeconds();
           answered_step < k && transport::NowSeconds() - sent < retransmit_s;)
        transport.WaitAndHandle(retransmit_s);
    }
    ++r.steps_checked;
    if (std::memcmp(&answered_u, &e.u[k], sizeof answered_u) != 0) {
      r.first_mismatch = k;
      r.logged_u = e.u[k];
      r.recomputed_u = answered_u;
      r.message = "first mismatch at step " + std::to_string(k) + " (t = " + Full(y.t_s) +
                  " s): logged u = " + Full(e.u[k]) + ", live controller u = " + Full(answered_u) +
                  " from y = " + Full(e.y[k]);
      return r;
    }
  }
  r.ok = true;
  r.message =
      "all " + std::to_string(r.steps_checked) + " commands reproduced bit for bit by the live controller";
  return r;
}

}  // namespace

Status RedriveOverLcm(const Episode& e, const std::string& url, const std::string& prefix, double deadline_s,
                      RedriveResult* result) {
  try {
    *result = RedriveOverLcmThrowing(e, url, prefix, deadline_s);
  } catch (const std::invalid_argument& bad_url) {
    return Status::InvalidInput(bad_url.what());
  } catch (const std::runtime_error& failed) {  // no acknowledgement, no answer, a step lane
    return Status::RunnerFailed(failed.what());
  }
  return Status::Ok();
}

}  // namespace pidlab::replay
