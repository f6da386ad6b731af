// Unit tests of the tuner's episode client (tuner/episode_client.h): the
// episode spec it builds, and whole episodes against the three roles run in
// this process on one memq:// LCM instance (no network). The roles share the
// client's LCM instance (every memq:// instance is a queue of its own), so the
// client's waits handle their messages: one thread, as in trio_protocol_test.

#include "pidlab/episode_client/episode_client.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <pidlab/lcmt_tune_progress.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/controller/controller_role.h"
#include "pidlab/episode_client/tune_progress.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/disturbance_role.h"
#include "pidlab/plant_sim/plant_role.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/transport.h"
#include "test_status.h"

using pidlab::episode_client::EpisodeClient;
using pidlab::episode_client::EpisodeClientOptions;
using pidlab::episode_client::EpisodeClientStats;
using pidlab::episode_client::MakeEpisodeSpec;
using pidlab::episode_client::SampledLoopOptions;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::RunSampledLoopInProcess;
using pidlab::evaluation::SampledStep;

namespace pidlab {
namespace {

struct Loop {
  Plant plant;
  PidGains gains{2.0, 1.0, 1.5};
  LoopOptions options;
};

Loop DoubleIntegrator(double horizon_s = 2.0) {
  Loop l;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &l.plant)));
  l.options.loop = LoopKind::kSampled;
  l.options.horizon_s = horizon_s;
  l.options.disturbance.kind = DisturbanceKind::kSquare;
  l.options.disturbance.amplitude = 0.3;
  return l;
}

/// The roles on one memq:// instance and a client on the same instance.
struct InProcessTrio {
  explicit InProcessTrio(bool with_controller = true, EpisodeClientOptions options = Defaults()) {
    EXPECT_TRUE(lcm.good());
    if (with_controller) controller = std::make_unique<controller::ControllerRole>(&controller_t);
    client = std::make_unique<EpisodeClient>(options, &lcm);
  }
  static EpisodeClientOptions Defaults() {
    EpisodeClientOptions o;
    o.lcm_url = "memq://";
    o.start_timeout_s = 1.0;
    return o;
  }

  lcm::LCM lcm{"memq://"};
  transport::Transport plant_t{&lcm, {}}, controller_t{&lcm, {}}, disturbance_t{&lcm, {}};
  plant_sim::PlantRole plant{&plant_t};
  plant_sim::DisturbanceRole disturbance{&disturbance_t};
  std::unique_ptr<controller::ControllerRole> controller;
  std::unique_ptr<EpisodeClient> client;
};

std::string InvalidSpecError(const Loop& l) {
  try {
    MakeEpisodeSpec(1, l.plant, l.gains, l.options, l.options.disturbance, transport::RecoveryOptions{});
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(EpisodeClient, MakeEpisodeSpecRejectsAnInvalidLoopNamingTheField) {
  Loop l = DoubleIntegrator();
  l.options.horizon_s = 1.01;  // not a multiple of the 0.05 s sample time
  EXPECT_NE(InvalidSpecError(l).find("horizon 1.01"), std::string::npos) << InvalidSpecError(l);
  l = DoubleIntegrator();
  l.options.dt_s = 0.003;  // 0.05 s is not a multiple of it
  EXPECT_NE(InvalidSpecError(l).find("sample time"), std::string::npos) << InvalidSpecError(l);
  l = DoubleIntegrator();
  l.options.pid.derivative_filter_s = -1.0;
  EXPECT_NE(InvalidSpecError(l).find("derivative filter -1"), std::string::npos) << InvalidSpecError(l);
  l = DoubleIntegrator();
  l.gains.kp = -1.0;
  EXPECT_NE(InvalidSpecError(l).find("kp"), std::string::npos) << InvalidSpecError(l);
}

TEST(EpisodeClient, SampledLoopOptionsRoundTripsDtHorizonPidAndDisturbance) {
  Loop l = DoubleIntegrator(3.0);
  l.options.dt_s = 5e-4;
  l.options.sample_time_s = 0.1;
  l.options.pid.derivative_filter_s = 0.01;
  l.options.pid.output_min = -4.0;
  l.options.pid.output_max = 6.0;
  l.options.pid.anti_windup = AntiWindup::kBackCalculation;
  l.options.pid.back_calculation_gain = 2.5;
  l.options.pid.setpoint_weight_b = 0.75;
  l.options.pid.setpoint_weight_c = 0.0;  // derivative on measurement
  l.options.pid.integral = IntegralMethod::kTrapezoidal;
  DisturbanceOptions d;  // differs from options.disturbance: the spec takes this one
  d.kind = DisturbanceKind::kSine;
  d.amplitude = 0.7;
  d.period_s = 1.5;
  d.phase_s = 0.25;
  d.seed = 77;
  transport::RecoveryOptions recovery;
  recovery.retransmit_interval_s = 0.004;
  recovery.silence_deadline_s = 2.0;
  const transport::EpisodeSpec spec = MakeEpisodeSpec(9, l.plant, l.gains, l.options, d, recovery);
  EXPECT_EQ(spec.episode_id, 9);
  EXPECT_EQ(spec.total_steps, 6000);
  EXPECT_EQ(spec.recovery.silence_deadline_s, 2.0);

  const LoopOptions back = SampledLoopOptions(spec);
  EXPECT_EQ(back.loop, LoopKind::kSampled);
  EXPECT_EQ(back.dt_s, 5e-4);
  EXPECT_EQ(back.sample_time_s, 0.1);
  EXPECT_EQ(back.horizon_s, 3.0);
  EXPECT_EQ(back.TotalSteps(), l.options.TotalSteps());
  EXPECT_EQ(back.pid.dt_s, 5e-4);  // the PID runs at the loop's period
  EXPECT_EQ(back.pid.derivative_filter_s, 0.01);
  EXPECT_EQ(back.pid.output_min, -4.0);
  EXPECT_EQ(back.pid.output_max, 6.0);
  EXPECT_EQ(back.pid.anti_windup, AntiWindup::kBackCalculation);
  EXPECT_EQ(back.pid.back_calculation_gain, 2.5);
  EXPECT_EQ(back.pid.setpoint_weight_b, 0.75);
  EXPECT_EQ(back.pid.setpoint_weight_c, 0.0);
  EXPECT_EQ(back.pid.integral, IntegralMethod::kTrapezoidal);
  EXPECT_EQ(back.disturbance.kind, DisturbanceKind::kSine);
  EXPECT_EQ(back.disturbance.amplitude, 0.7);
  EXPECT_EQ(back.disturbance.period_s, 1.5);
  EXPECT_EQ(back.disturbance.phase_s, 0.25);
  EXPECT_EQ(back.disturbance.seed, 77u);
  std::string error;
  EXPECT_TRUE(back.IsValid(&error)) << error;
}

TEST(EpisodeClient, AnLcmThatCannotStartIsAStatusOfEveryRunNotAnException) {
  EpisodeClientOptions options;
  options.lcm_url = "udpm://239.255.76.67:99999";  // no such port: LCM does not start
  std::unique_ptr<EpisodeClient> dut;
  EXPECT_NO_THROW(dut = std::make_unique<EpisodeClient>(options));
  EXPECT_EQ(dut->status().code(), pidlab::StatusCode::kRunnerFailed);
  EXPECT_NE(dut->status().message().find("99999"), std::string::npos) << dut->status().message();
  pidlab::Plant plant;
  std::string error;
  ASSERT_TRUE(IsOk(pidlab::MakePlant("double_integrator", pidlab::StepperMotorParameters{}, &plant)));
  LoopOptions loop;
  loop.loop = LoopKind::kSampled;
  std::vector<double> y;
  const pidlab::Status run = dut->Run(plant, pidlab::PidGains{1, 1, 1}, loop, loop.disturbance, &y, nullptr);
  EXPECT_EQ(run.code(), pidlab::StatusCode::kRunnerFailed);
  EXPECT_EQ(run.message(), dut->status().message());
}

TEST(EpisodeClient, RejectsInvalidOptionsNamingTheValue) {
  EpisodeClientOptions o = InProcessTrio::Defaults();
  o.start_timeout_s = 0.0;
  lcm::LCM lcm("memq://");
  try {
    EpisodeClient client(o, &lcm);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("start timeout 0"), std::string::npos) << e.what();
  }
  o = InProcessTrio::Defaults();
  o.max_attempts = 0;
  try {
    EpisodeClient client(o, &lcm);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max attempts 0"), std::string::npos) << e.what();
  }
}

TEST(EpisodeClient, RunEqualsTheInProcessSampledLoopBitForBit) {
  const Loop l = DoubleIntegrator();
  std::vector<double> expected_y;
  std::vector<SampledStep> expected;
  std::string error;
  ASSERT_TRUE(OkInto(
      RunSampledLoopInProcess(l.plant, l.gains, l.options, l.options.disturbance, &expected_y, &expected),
      &error))
      << error;

  InProcessTrio trio;
  std::vector<double> y;
  std::vector<SampledStep> trajectory;
  ASSERT_TRUE(
      OkInto(trio.client->Run(l.plant, l.gains, l.options, l.options.disturbance, &y, &trajectory), &error))
      << error;
  ASSERT_EQ(y.size(), static_cast<std::size_t>(l.options.TotalSteps() + 1));
  ASSERT_EQ(y.size(), expected_y.size());
  // Bit for bit: memcmp, so that even -0.0 and +0.0 would differ.
  for (std::size_t k = 0; k < y.size(); ++k)
    ASSERT_EQ(std::memcmp(&y[k], &expected_y[k], sizeof(double)), 0) << "y at step " << k;
  ASSERT_EQ(trajectory.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    ASSERT_EQ(trajectory[k].k, expected[k].k);
    ASSERT_EQ(std::memcmp(&trajectory[k].y, &expected[k].y, sizeof(double)), 0) << "y at step " << k;
    ASSERT_EQ(std::memcmp(&trajectory[k].u, &expected[k].u, sizeof(double)), 0) << "u at step " << k;
    ASSERT_EQ(std::memcmp(&trajectory[k].n, &expected[k].n, sizeof(double)), 0) << "n at step " << k;
  }
}

TEST(EpisodeClient, EvaluateThroughTheClientEqualsEvaluateInProcess) {
  const Loop l = DoubleIntegrator();
  Evaluation local, remote;
  std::string error;
  ASSERT_TRUE(IsOk(Evaluate(l.plant, l.gains, l.options, EvaluateOptions{}, &local)));
  InProcessTrio trio;
  ASSERT_TRUE(OkInto(
      Evaluate(l.plant, l.gains, l.options, EvaluateOptions{}, &remote, trio.client->AsRunner()), &error))
      << error;
  EXPECT_EQ(remote.iae, local.iae);
  EXPECT_EQ(remote.ise, local.ise);
  EXPECT_EQ(remote.itae, local.itae);
  EXPECT_EQ(remote.iae_undisturbed, local.iae_undisturbed);
  EXPECT_EQ(remote.y, local.y);
}

TEST(EpisodeClient, RunReturnsFalseNamingTheSilentControllerWithinTheStartTimeout) {
  EpisodeClientOptions o = InProcessTrio::Defaults();
  o.start_timeout_s = 0.3;
  o.max_attempts = 1;
  InProcessTrio trio(/*with_controller=*/false, o);
  const Loop l = DoubleIntegrator();
  std::vector<double> y;
  std::string error;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(
      OkInto(trio.client->Run(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(error.find("no answer from pidlab-controller within 0.3 s"), std::string::npos) << error;
  EXPECT_EQ(error.find("pidlab-plant"), std::string::npos) << error;  // the others answered
  EXPECT_EQ(error.find("pidlab-disturbance"), std::string::npos) << error;
  EXPECT_NE(error.find("memq://"), std::string::npos) << error;
  EXPECT_GE(seconds, 0.3);
  EXPECT_LT(seconds, 0.3 + 1.0);
  EXPECT_EQ(trio.client->stats().episodes, 0);
  EXPECT_EQ(trio.client->stats().reruns, 0);
}

TEST(EpisodeClient, RunsAnEpisodeThatFailedOnSilenceAgainAndNotesIt) {
  std::vector<std::string> notes;
  EpisodeClientOptions o = InProcessTrio::Defaults();
  o.start_timeout_s = 0.2;
  o.max_attempts = 2;
  o.on_note = [&notes](const std::string& note) { notes.push_back(note); };
  InProcessTrio trio(/*with_controller=*/false, o);
  const Loop l = DoubleIntegrator();
  std::vector<double> y;
  std::string error;
  EXPECT_FALSE(
      OkInto(trio.client->Run(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  EXPECT_NE(error.find("pidlab-controller"), std::string::npos) << error;
  EXPECT_NE(error.find("(after 2 attempts)"), std::string::npos) << error;
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("running it again (attempt 2 of 2)"), std::string::npos) << notes[0];
  EXPECT_EQ(trio.client->stats().reruns, 1);
}

TEST(EpisodeClient, StatsCountEpisodesAndSteps) {
  InProcessTrio trio;
  const Loop a = DoubleIntegrator(1.0), b = DoubleIntegrator(0.5);
  std::vector<double> y;
  std::string error;
  EXPECT_EQ(trio.client->stats().episodes, 0);
  ASSERT_TRUE(
      OkInto(trio.client->Run(a.plant, a.gains, a.options, a.options.disturbance, &y, nullptr), &error))
      << error;
  ASSERT_TRUE(
      OkInto(trio.client->Run(b.plant, b.gains, b.options, b.options.disturbance, &y, nullptr), &error))
      << error;
  const EpisodeClientStats& stats = trio.client->stats();
  EXPECT_EQ(stats.episodes, 2);
  EXPECT_EQ(stats.steps, a.options.TotalSteps() + b.options.TotalSteps());
  EXPECT_EQ(stats.steps, 1500);
  EXPECT_GT(stats.seconds, 0.0);
  EXPECT_GT(stats.StepsPerSecond(), 0.0);
  EXPECT_EQ(stats.reruns, 0);
  EXPECT_EQ(stats.resend_requests, 0);  // memq:// loses nothing
  EXPECT_EQ(trio.client->counters().dropped, 0);
  EXPECT_EQ(y.size(), 501u);  // the last episode's
}

TEST(EpisodeClient, RunOfAnInvalidLoopReturnsFalseWithoutStartingAnEpisode) {
  InProcessTrio trio;
  Loop l = DoubleIntegrator();
  l.options.horizon_s = 1.01;
  std::vector<double> y;
  std::string error;
  EXPECT_FALSE(
      OkInto(trio.client->Run(l.plant, l.gains, l.options, l.options.disturbance, &y, nullptr), &error));
  EXPECT_NE(error.find("invalid episode: horizon 1.01"), std::string::npos) << error;
  EXPECT_EQ(trio.plant.counters().episodes, 0);
  EXPECT_EQ(trio.client->stats().episodes, 0);
}

TEST(TuneProgressPublisher, SendsTheSearchAtMostOnceAnIntervalAndTheResultAtTheEnd) {
  lcm::LCM lcm("memq://");
  EpisodeClientOptions trio;
  trio.lcm_url = "memq://";
  transport::Transport listener(&lcm, trio.transport);
  std::vector<pidlab::lcmt_tune_progress> heard;
  listener.Subscribe<pidlab::lcmt_tune_progress>(
      transport::kTuneProgressChannel, [&](const pidlab::lcmt_tune_progress& m) { heard.push_back(m); });
  episode_client::TuneProgressPublisher dut(&lcm, trio, /*trios=*/3, "nelder-mead", "iae",
                                            /*min_interval_s=*/3600.0);
  optim::TracePoint none;  // before any feasible point
  none.iteration = 1;
  none.evaluations = 4;
  dut.Running(none);
  optim::TracePoint better = none;
  better.iteration = 2;
  better.evaluations = 8;
  better.best_f = 1.5;
  better.best_x = Eigen::Vector3d(1, 2, 3);
  dut.Running(better);  // within the interval: not sent
  dut.Finished(true, PidGains{1, 2, 3}, 1.25, 9);
  while (listener.WaitAndHandle(0.0) > 0) {
  }
  ASSERT_EQ(heard.size(), 2u);
  EXPECT_EQ(heard[0].status, pidlab::lcmt_tune_progress::RUNNING);
  EXPECT_EQ(heard[0].evaluations, 4);
  EXPECT_TRUE(std::isinf(heard[0].best_objective));
  EXPECT_TRUE(std::isnan(heard[0].best_gains[0]));
  EXPECT_EQ(heard[1].status, pidlab::lcmt_tune_progress::DONE);
  EXPECT_EQ(heard[1].step, 2);  // the last point seen, sent or not
  EXPECT_EQ(heard[1].evaluations, 9) << "the tuning's own count, not the last point's 8";
  EXPECT_EQ(heard[1].best_objective, 1.25);
  EXPECT_EQ(heard[1].best_gains[2], 3.0);
  EXPECT_EQ(heard[1].trios, 3);
  EXPECT_EQ(heard[1].method, "nelder-mead");
  EXPECT_EQ(heard[1].objective, "iae");
  EXPECT_EQ(heard[0].episode_id, dut.id());
  EXPECT_EQ(heard[1].episode_id, dut.id());
}

}  // namespace
}  // namespace pidlab
