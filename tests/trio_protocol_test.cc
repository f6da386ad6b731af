// Unit tests of the trio protocol: all three roles and the episode logic in
// one memq:// LCM instance, single-threaded (no network).

#include <gtest/gtest.h>
#include <sched.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <random>
#include <set>
#include <thread>

#include "pidlab/controller/controller_role.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/disturbance_role.h"
#include "pidlab/plant_sim/plant_role.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/pacing.h"
#include "pidlab/transport/rtt.h"
#include "pidlab/transport/transport.h"
#include "test_status.h"

using pidlab::controller::ControllerRole;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::RunSampledLoopInProcess;
using pidlab::plant_sim::DisturbanceRole;
using pidlab::plant_sim::PlantRole;

namespace pidlab::transport {
namespace {

struct Episode {
  Plant plant;
  PidGains gains{2.0, 1.0, 1.5};
  LoopOptions options;
};

Episode DoubleIntegrator(double horizon_s = 2.0) {
  Episode e;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &e.plant)));
  e.options.loop = LoopKind::kSampled;
  e.options.horizon_s = horizon_s;
  e.options.disturbance.kind = DisturbanceKind::kSquare;
  e.options.disturbance.amplitude = 0.3;
  return e;
}

/// Records the plant's outputs and the summary from the memq traffic.
struct Recorder {
  std::vector<double> y;
  std::vector<char> have;
  bool summary = false;
  pidlab::lcmt_episode_summary last;
};

/// Runs one episode through the three roles on memq:// and returns y_0..y_N.
bool RunOnMemq(const Episode& e, double drop_rate, Recorder* rec, RoleCounters* controller_counters = nullptr,
               bool with_controller = true, bool with_disturbance = true) {
  lcm::LCM lcm("memq://");
  EXPECT_TRUE(lcm.good());
  TransportOptions topt;
  topt.drop_rate = drop_rate;
  Transport plant_t(&lcm, topt), controller_t(&lcm, topt), disturbance_t(&lcm, topt), client_t(&lcm, {});
  topt.drop_seed = 2;
  Transport controller_t2(&lcm, topt);
  PlantRole plant(&plant_t);
  std::unique_ptr<ControllerRole> controller;
  if (with_controller)
    controller = std::make_unique<ControllerRole>(drop_rate > 0 ? &controller_t2 : &controller_t);
  std::unique_ptr<DisturbanceRole> disturbance;
  if (with_disturbance) disturbance = std::make_unique<DisturbanceRole>(&disturbance_t);
  const long total = e.options.TotalSteps();
  rec->y.assign(static_cast<std::size_t>(total + 1), 0.0);
  rec->have.assign(static_cast<std::size_t>(total + 1), 0);
  int64_t id = 42;
  client_t.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel, [&](const pidlab::lcmt_plant_output& m) {
    if (m.episode_id == id && m.step >= 0 && m.step <= total) {
      rec->y[static_cast<std::size_t>(m.step)] = m.y;
      rec->have[static_cast<std::size_t>(m.step)] = 1;
    }
  });
  client_t.Subscribe<pidlab::lcmt_episode_summary>(kSummaryChannel,
                                                   [&](const pidlab::lcmt_episode_summary& m) {
                                                     rec->summary = true;
                                                     rec->last = m;
                                                   });
  RecoveryOptions recovery;
  recovery.retransmit_interval_s = 0.001;
  // Short where a role is missing on purpose (the plant must name it); long
  // otherwise: the roles share this one thread, and a machine that stalls the
  // process for 0.2 s must not look like a silent role.
  recovery.silence_deadline_s = with_controller && with_disturbance ? 5.0 : 0.2;
  auto config = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      id, e.plant, e.gains, e.options, e.options.disturbance, recovery));
  client_t.Publish(kEpisodeConfigChannel, &config);
  const double start = NowSeconds();
  double config_sent = start;
  while (!rec->summary && NowSeconds() - start < 20.0) {
    client_t.WaitAndHandle(0.001);
    const double now = NowSeconds();
    if (drop_rate > 0 &&
        now - config_sent > 0.01) {  // as the episode client does: a role may have dropped it
      client_t.Publish(kEpisodeConfigChannel, &config);
      config_sent = now;
    }
    plant.Tick(now);
    if (controller) controller->Tick(now);
    if (disturbance) disturbance->Tick(now);
  }
  if (controller_counters && controller) *controller_counters = controller->counters();
  return rec->summary && rec->last.status == pidlab::lcmt_episode_summary::OK;
}

std::vector<double> Reference(const Episode& e) {
  std::vector<double> y;
  std::string error;
  EXPECT_TRUE(OkInto(RunSampledLoopInProcess(e.plant, e.gains, e.options, e.options.disturbance, &y, nullptr),
                     &error));
  return y;
}

TEST(EpisodeConfig, RoundTripsEveryField) {
  Episode e = DoubleIntegrator();
  e.options.pid.derivative_filter_s = 0.01;
  e.options.pid.output_min = -5;
  e.options.pid.anti_windup = AntiWindup::kBackCalculation;
  e.options.pid.integral = IntegralMethod::kTrapezoidal;
  e.options.disturbance.seed = 99;
  const auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EpisodeSpec dut;
  std::string error;
  ASSERT_TRUE(IsOk(ParseEpisodeConfig(msg, &dut)));
  EXPECT_EQ(dut.episode_id, 7);
  EXPECT_EQ(dut.plant.tf.den, e.plant.tf.den);
  EXPECT_EQ(dut.gains.kd, 1.5);
  EXPECT_EQ(dut.pid.derivative_filter_s, 0.01);
  EXPECT_EQ(dut.pid.output_min, -5);
  EXPECT_EQ(dut.pid.anti_windup, AntiWindup::kBackCalculation);
  EXPECT_EQ(dut.pid.integral, IntegralMethod::kTrapezoidal);
  EXPECT_EQ(dut.disturbance.seed, 99u);
  EXPECT_EQ(dut.total_steps, e.options.TotalSteps());
}

TEST(EpisodeConfig, RejectsMalformedFieldsByName) {
  Episode e = DoubleIntegrator();
  auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EpisodeSpec dut;
  std::string error;
  auto bad = msg;
  bad.kp = -1;
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("kp"), std::string::npos) << error;
  bad = msg;
  bad.total_steps += 1;
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("total steps"), std::string::npos) << error;
  bad = msg;
  bad.anti_windup = "sometimes";
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("sometimes"), std::string::npos) << error;
  bad = msg;
  bad.episode_id = 0;
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
}

Episode Motor(double reference, double voltage_limit_v = HUGE_VAL, bool microstep = true) {
  Episode e;
  NonlinearStepperOptions o;
  o.voltage_limit_v = voltage_limit_v;
  o.detent_torque_nm = 0.0002;
  o.microstep_table = microstep;
  std::string error;
  EXPECT_TRUE(IsOk(MakeNonlinearStepperPlant(o, &e.plant)));
  e.gains = {20.8836, 26.607, 12.4866};
  e.options.loop = LoopKind::kSampled;
  e.options.dt_s = 1e-4;
  e.options.pid.dt_s = 1e-4;
  e.options.horizon_s = 0.1;
  e.options.reference = reference;
  return e;
}

TEST(EpisodeConfig, CarriesTheNonlinearMotorWithItsOptions) {
  const Episode e = Motor(0.2, 24.0);
  const auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EXPECT_EQ(msg.plant_name, "stepper_nonlinear");
  EXPECT_EQ(msg.motor_drive, "microstep");
  EpisodeSpec dut;
  std::string error;
  ASSERT_TRUE(IsOk(ParseEpisodeConfig(msg, &dut)));
  ASSERT_TRUE(dut.plant.nonlinear);
  EXPECT_EQ(dut.plant.tf.den, e.plant.tf.den);
  EXPECT_EQ(dut.plant.nonlinear->voltage_limit_v, 24.0);
  EXPECT_EQ(dut.plant.nonlinear->detent_torque_nm, 0.0002);
  EXPECT_TRUE(dut.plant.nonlinear->microstep_table);
  EXPECT_EQ(dut.plant.nonlinear->motor.resistance_ohm, 33.0);
  // A linear plant's message carries no motor.
  const Episode linear = DoubleIntegrator();
  const auto plain = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      8, linear.plant, linear.gains, linear.options, linear.options.disturbance, RecoveryOptions{}));
  EXPECT_EQ(plain.motor_drive, "");
  EXPECT_EQ(plain.motor_resistance_ohm, 0.0);
  ASSERT_TRUE(IsOk(ParseEpisodeConfig(plain, &dut)));
  EXPECT_FALSE(dut.plant.nonlinear);
}

TEST(EpisodeConfig, RejectsABadMotorByName) {
  const Episode e = Motor(0.2);
  const auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EpisodeSpec dut;
  std::string error;
  auto bad = msg;
  bad.motor_drive = "fullstep";
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("fullstep"), std::string::npos) << error;
  bad = msg;
  bad.motor_resistance_ohm = -1.0;
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("motor"), std::string::npos) << error;
  bad = msg;
  bad.motor_inertia_kg_m2 = std::nan("");
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  bad = msg;
  bad.den[1] *= 1.001;  // num/den that are not the motor's linearisation
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
  EXPECT_NE(error.find("linearisation"), std::string::npos) << error;
  bad = msg;
  bad.plant_name = "double_integrator";  // motor fields on a linear plant
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
}

TEST(TrioProtocol, TheNonlinearMotorIsBitIdenticalToTheInProcessLoop) {
  for (const double limit : {HUGE_VAL, 24.0}) {
    const Episode e = Motor(0.01, limit, /*microstep=*/false);
    Recorder rec;
    ASSERT_TRUE(RunOnMemq(e, 0.0, &rec)) << rec.last.message;
    const std::vector<double> want = Reference(e);
    ASSERT_EQ(rec.y.size(), want.size());
    for (std::size_t k = 0; k < want.size(); ++k)
      ASSERT_EQ(std::memcmp(&rec.y[k], &want[k], sizeof(double)), 0) << "step " << k << " limit " << limit;
    EXPECT_GT(want.back(), 0.001);  // the rotor moved toward the reference (slowly under 24 V)
  }
}

TEST(Transport, CountsUndecodableMessagesAndIgnoresThem) {
  lcm::LCM lcm("memq://");
  Transport dut(&lcm, {});
  int calls = 0;
  dut.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                           [&](const pidlab::lcmt_plant_output&) { ++calls; });
  std::mt19937 rng(3);
  for (int i = 0; i < 50; ++i) {
    std::vector<unsigned char> junk(1 + rng() % 100);
    for (auto& b : junk) b = static_cast<unsigned char>(rng());
    lcm.publish(dut.Channel(kPlantOutputChannel), junk.data(), static_cast<unsigned>(junk.size()));
  }
  pidlab::lcmt_control_command wrong_type{};
  lcm.publish(dut.Channel(kPlantOutputChannel), &wrong_type);
  pidlab::lcmt_plant_output good{};
  dut.Publish(kPlantOutputChannel, &good);
  while (dut.WaitAndHandle(0.01) > 0) {
  }
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(dut.counters().undecodable, 51);
  EXPECT_EQ(dut.counters().received, 52);
}

TEST(Transport, DropsTheConfiguredFractionReproducibly) {
  auto run = [](uint64_t seed) {
    lcm::LCM lcm("memq://");
    TransportOptions o;
    o.drop_rate = 0.2;
    o.drop_seed = seed;
    Transport dut(&lcm, o);
    std::vector<int64_t> got;
    dut.Subscribe<pidlab::lcmt_plant_output>(
        kPlantOutputChannel, [&](const pidlab::lcmt_plant_output& m) { got.push_back(m.step); });
    for (int k = 0; k < 2000; ++k) {
      pidlab::lcmt_plant_output m{};
      m.step = k;
      dut.Publish(kPlantOutputChannel, &m);
      dut.WaitAndHandle(0.0);
    }
    while (dut.WaitAndHandle(0.0) > 0) {
    }
    return got;
  };
  const auto a = run(5), b = run(5), c = run(6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NEAR(static_cast<double>(a.size()) / 2000.0, 0.8, 0.03);
}

/// Moves this test process into a network namespace of its own (root) with
/// multicast over its loopback, so that udpm:// traffic stays inside it.
bool EnterPrivateNetwork(std::string* error) {
  if (unshare(CLONE_NEWNET) != 0) {
    *error = std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno) + " (run as root)";
    return false;
  }
  if (std::system("ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo") !=
      0) {
    *error = "cannot set up multicast on the private namespace's loopback";
    return false;
  }
  return true;
}

/// Publishes `burst` outputs on the PLANT_OUTPUT lane of a udpm:// trio URL
/// while the receiving transport does not handle, lets LCM's receive thread
/// take them all, then handles: the steps that reached the subscription.
long OutputsSurvivingABurst(int queue_capacity, int burst) {
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  lcm::LCM base_in(url), base_out(url);
  TransportOptions in_options, out_options;
  in_options.step_lane_base_url = out_options.step_lane_base_url = url;
  in_options.queue_capacity = queue_capacity;
  Transport in(&base_in, in_options), out(&base_out, out_options);
  std::set<int64_t> steps;
  in.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel,
                                          [&](const pidlab::lcmt_plant_output& m) { steps.insert(m.step); });
  lcm::LCM probe(StepLaneUrl(url, kPlantOutputLane));
  long heard = 0;
  lcm::Subscription* heard_all = probe.subscribeFunction(
      ".*", +[](const lcm::ReceiveBuffer*, const std::string&, long* n) { ++*n; }, &heard);
  heard_all->setQueueCapacity(burst);
  for (int k = 0; k < burst; ++k) {
    pidlab::lcmt_plant_output m{};
    m.step = k;
    out.Publish(kPlantOutputChannel, &m);
  }
  // Readiness: a second receiver on the same lane has heard the whole burst
  // (every receiver's socket gets each datagram as it is sent), so `in`'s
  // receive thread has had it to queue.
  const double deadline = NowSeconds() + 5.0;
  while (heard < burst && NowSeconds() < deadline) probe.handleTimeout(50);
  while (in.WaitAndHandle(0.05) > 0) {
  }
  return static_cast<long>(steps.size());
}

TEST(Transport, KeepsEveryMessageOfABurstThatArrivesWhileItIsNotHandling) {
  std::string error;
  ASSERT_TRUE(EnterPrivateNetwork(&error)) << error;
  EXPECT_EQ(OutputsSurvivingABurst(TransportOptions::kDefaultQueueCapacity, 1000), 1000);
  // LCM's own default of 30 loses most of it, silently: what stalled a lone
  // controller fed by lcm-logplayer on a loaded machine.
  EXPECT_LT(OutputsSurvivingABurst(30, 1000), 100);
}

TEST(Transport, RejectsAQueueCapacityBelowOne) {
  TransportOptions o;
  std::string error;
  o.queue_capacity = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("queue capacity 0"), std::string::npos);
}

TEST(Transport, RejectsADropRateOutsideUnitInterval) {
  TransportOptions o;
  std::string error;
  o.drop_rate = 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("drop rate"), std::string::npos);
}

TEST(Trio, MatchesTheInProcessSampledLoopBitForBit) {
  const Episode e = DoubleIntegrator();
  Recorder rec;
  ASSERT_TRUE(RunOnMemq(e, 0.0, &rec)) << rec.last.message;
  const std::vector<double> expected = Reference(e);
  ASSERT_EQ(rec.y.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    ASSERT_TRUE(rec.have[k]) << "step " << k;
    ASSERT_EQ(rec.y[k], expected[k]) << "step " << k;  // bit for bit, no tolerance
  }
}

// 1/(s+1) e^(-sL) with a split delay (L not a multiple of dt) and a
// disturbance, which the plant also delays.
Episode Fopdt(double delay_s) {
  Episode e;
  std::string error;
  EXPECT_TRUE(IsOk(MakeCustomPlant({1.0}, {1.0, 1.0}, &e.plant)));
  e.plant.delay_s = delay_s;
  e.gains = PidGains{1.0, 1.0, 0.0};
  e.options.loop = LoopKind::kSampled;
  e.options.horizon_s = 2.0;
  e.options.disturbance.kind = DisturbanceKind::kSquare;
  e.options.disturbance.amplitude = 0.3;
  return e;
}

TEST(Trio, ThePlantsDeadTimeIsBitIdenticalToTheInProcessLoop) {
  for (const double delay : {0.3, 0.0123}) {
    SCOPED_TRACE(delay);
    const Episode e = Fopdt(delay);
    Recorder rec;
    ASSERT_TRUE(RunOnMemq(e, 0.05, &rec)) << rec.last.message;
    const std::vector<double> expected = Reference(e);
    ASSERT_EQ(rec.y.size(), expected.size());
    EXPECT_EQ(expected[1], 0.0) << "the input reaches the plant only after the dead time";
    for (std::size_t k = 0; k < expected.size(); ++k) {
      ASSERT_TRUE(rec.have[k]) << "step " << k;
      ASSERT_EQ(rec.y[k], expected[k]) << "step " << k;
    }
  }
}

TEST(EpisodeConfig, CarriesThePlantsDeadTimeAndRejectsABadOneByName) {
  const Episode e = Fopdt(0.3);
  const auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EXPECT_EQ(msg.delay_s, 0.3);
  EpisodeSpec dut;
  std::string error;
  ASSERT_TRUE(IsOk(ParseEpisodeConfig(msg, &dut)));
  EXPECT_EQ(dut.plant.delay_s, 0.3);
  for (const double bad_delay : {-1.0, std::nan(""), HUGE_VAL, 1e9, 2e4}) {
    SCOPED_TRACE(bad_delay);
    auto bad = msg;
    bad.delay_s = bad_delay;  // 2e4 s at dt 1e-3 is 2e7 stored inputs, more than 1e7
    EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error));
    EXPECT_EQ(error.rfind("delay_s", 0), 0u) << error;
  }
  auto motor = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, Motor(1.0).plant, e.gains, Motor(1.0).options, DisturbanceOptions{}, RecoveryOptions{}));
  motor.delay_s = 0.01;
  EXPECT_FALSE(OkInto(ParseEpisodeConfig(motor, &dut), &error));
  EXPECT_NE(error.find("delay_s"), std::string::npos) << error;
}

// An identification experiment on 1/(s^2 + 2 s + 1): a chirp at the plant
// input, open loop (gains 0) or closed, with noise on the measured y.
Episode Experiment(bool closed, double sigma) {
  Episode e;
  std::string error;
  EXPECT_TRUE(IsOk(MakeCustomPlant({1.0}, {1.0, 2.0, 1.0}, &e.plant)));
  e.gains = closed ? PidGains{2.0, 1.0, 0.5} : PidGains{0.0, 0.0, 0.0};
  e.options.loop = LoopKind::kSampled;
  e.options.horizon_s = 2.0;
  e.options.disturbance.kind = DisturbanceKind::kChirp;
  e.options.disturbance.amplitude = 0.5;
  e.options.disturbance.chirp_f0_hz = 0.2;
  e.options.disturbance.chirp_f1_hz = 20.0;
  e.options.disturbance.chirp_duration_s = 1.5;
  e.options.measurement_noise = MeasurementNoise{sigma, 4};
  return e;
}

TEST(Trio, AChirpWithMeasurementNoiseIsBitIdenticalToTheInProcessLoop) {
  for (const bool closed : {false, true}) {
    for (const double sigma : {0.0, 0.01}) {
      SCOPED_TRACE(std::string(closed ? "closed" : "open") + " loop, sigma " + std::to_string(sigma));
      const Episode e = Experiment(closed, sigma);
      Recorder rec;
      ASSERT_TRUE(RunOnMemq(e, 0.05, &rec)) << rec.last.message;
      const std::vector<double> expected = Reference(e);
      ASSERT_EQ(rec.y.size(), expected.size());
      if (sigma > 0.0) {
        EXPECT_NE(expected[0], 0.0) << "y_0 is measured with noise";
      }
      for (std::size_t k = 0; k < expected.size(); ++k) {
        ASSERT_TRUE(rec.have[k]) << "step " << k;
        ASSERT_EQ(rec.y[k], expected[k]) << "step " << k;
      }
    }
  }
}

TEST(EpisodeConfig, CarriesTheChirpAndTheMeasurementNoiseAndRejectsBadOnesByName) {
  const Episode e = Experiment(true, 0.01);
  const auto msg = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      7, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  EXPECT_EQ(msg.disturbance_kind, "chirp");
  EXPECT_EQ(msg.chirp_f1_hz, 20.0);
  EXPECT_EQ(msg.measurement_noise, 0.01);
  EpisodeSpec dut;
  std::string error;
  ASSERT_TRUE(IsOk(ParseEpisodeConfig(msg, &dut)));
  EXPECT_EQ(dut.disturbance.chirp_f0_hz, 0.2);
  EXPECT_EQ(dut.disturbance.chirp_duration_s, 1.5);
  EXPECT_EQ(dut.measurement_noise.sigma, 0.01);
  EXPECT_EQ(dut.measurement_noise.seed, 4u);
  const auto refuse = [&](pidlab::lcmt_episode_config bad, const std::string& name) {
    EXPECT_FALSE(OkInto(ParseEpisodeConfig(bad, &dut), &error)) << name;
    EXPECT_NE(error.find(name), std::string::npos) << error;
  };
  for (const double sigma : {-1.0, std::nan(""), HUGE_VAL}) {
    auto bad = msg;
    bad.measurement_noise = sigma;
    refuse(bad, "measurement noise");
  }
  for (const double f1 : {0.1, std::nan(""), 500.0}) {  // below f0, NaN, at Nyquist (dt 1e-3)
    auto bad = msg;
    bad.chirp_f1_hz = f1;
    refuse(bad, "chirp");
  }
  auto bad = msg;
  bad.chirp_duration_s = 0.0;
  refuse(bad, "chirp duration");
}

TEST(Trio, RecoversFromDroppedMessagesWithIdenticalResults) {
  const Episode e = DoubleIntegrator();
  Recorder rec;
  RoleCounters controller;
  ASSERT_TRUE(RunOnMemq(e, 0.05, &rec, &controller)) << rec.last.message;
  EXPECT_GT(controller.duplicates, 0);  // losses happened and were recovered
  const std::vector<double> expected = Reference(e);
  for (std::size_t k = 0; k < expected.size(); ++k) ASSERT_EQ(rec.y[k], expected[k]) << "step " << k;
}

TEST(Trio, NamesTheSilentControllerAfterTheDeadline) {
  const Episode e = DoubleIntegrator();
  Recorder rec;
  EXPECT_FALSE(RunOnMemq(e, 0.0, &rec, nullptr, /*with_controller=*/false));
  ASSERT_TRUE(rec.summary);
  EXPECT_EQ(rec.last.status, pidlab::lcmt_episode_summary::FAILED);
  EXPECT_EQ(rec.last.silent_role, "controller");
  EXPECT_NE(rec.last.message.find("pidlab-controller"), std::string::npos) << rec.last.message;
  EXPECT_EQ(rec.last.step, 0);
}

TEST(Trio, NamesTheSilentDisturbanceAfterTheDeadline) {
  // n comes in blocks requested ahead; without any, the plant cannot take
  // step 0 and must name the disturbance, not the controller.
  const Episode e = DoubleIntegrator();
  Recorder rec;
  EXPECT_FALSE(RunOnMemq(e, 0.0, &rec, nullptr, /*with_controller=*/true, /*with_disturbance=*/false));
  ASSERT_TRUE(rec.summary);
  EXPECT_EQ(rec.last.status, pidlab::lcmt_episode_summary::FAILED);
  EXPECT_EQ(rec.last.silent_role, "disturbance");
  EXPECT_NE(rec.last.message.find("pidlab-disturbance"), std::string::npos) << rec.last.message;
  EXPECT_EQ(rec.last.step, 0);
}

TEST(Trio, RecoversFromTwentyPercentDropsInEveryProcessWithIdenticalResults) {
  const Episode e = DoubleIntegrator();
  Recorder rec;
  RoleCounters controller;
  ASSERT_TRUE(RunOnMemq(e, 0.2, &rec, &controller)) << rec.last.message;
  EXPECT_GT(controller.duplicates, 0);  // the plant resent y_k, the controller re-answered with its u_k
  const std::vector<double> expected = Reference(e);
  for (std::size_t k = 0; k < expected.size(); ++k) ASSERT_EQ(rec.y[k], expected[k]) << "step " << k;
}

/// The number after `key` ("resent ", "re-answered ") in a role's
/// "episode <id>: done" line, or -1.
long CountIn(const std::string& line, const std::string& key) {
  const std::size_t at = line.find(key);
  return at == std::string::npos ? -1 : std::stol(line.substr(at + key.size()));
}

/// The per-episode counts the roles' "episode <id>: done" lines report.
struct EpisodeCounts {
  long resent = -1, plant_dropped = -1, reanswered = -1, controller_dropped = -1, disturbance_dropped = -1;
};

TEST(Trio, ThreeIdenticalEpisodesWithASeededDropRateEachReportTheSameResendsAndReAnswers) {
  // Why the counts repeat exactly: every process drops with a decision keyed
  // on (seed, channel, step, copy number), so each episode loses the same
  // messages, whatever its id and timing. And every resend here is caused by
  // a loss, never by a slow answer: the three roles share one memq:// LCM in
  // this one thread, and the loop delivers every queued message (drains)
  // before it lets the plant look at its resend timer. Whatever was sent and
  // not dropped has then arrived, so the timer can only fire for a lost
  // message, however long the machine stalled this thread.
  const Episode e = DoubleIntegrator(0.5);
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  auto lossy = [](uint64_t seed) {
    TransportOptions o;
    o.drop_rate = 0.1;
    o.drop_seed = seed;
    return o;
  };
  // The plant's and the controller's seeds as pidlab launch gives them (1, 2);
  // the disturbance's 5, not 3: with 3 it loses none of its few requests
  // (one per 128 steps) and its count could not tell an episode's own from
  // the lifetime's.
  Transport plant_t(&lcm, lossy(1)), controller_t(&lcm, lossy(2)), disturbance_t(&lcm, lossy(5)),
      client_t(&lcm, {});
  std::vector<std::string> plant_lines, controller_lines, disturbance_lines;
  PlantRole plant(&plant_t, [&](const std::string& line) { plant_lines.push_back(line); });
  ControllerRole controller(&controller_t,
                            [&](const std::string& line) { controller_lines.push_back(line); });
  DisturbanceRole disturbance(&disturbance_t,
                              [&](const std::string& line) { disturbance_lines.push_back(line); });
  int64_t id = 0;
  bool summary = false;
  client_t.Subscribe<pidlab::lcmt_episode_summary>(
      kSummaryChannel, [&](const pidlab::lcmt_episode_summary& m) {
        summary = summary || (m.episode_id == id && m.status == pidlab::lcmt_episode_summary::OK);
      });
  auto drain = [&] {
    while (client_t.WaitAndHandle(0.0) > 0) {
    }
  };
  RecoveryOptions recovery;
  recovery.retransmit_interval_s = 0.001;
  recovery.silence_deadline_s = 5.0;  // never reached: no stall of this thread fails an episode
  std::vector<EpisodeCounts> counts;
  for (id = 101; id <= 103; ++id) {  // ids of their own: the drops must not depend on them
    summary = false;
    const std::size_t plant_seen = plant_lines.size(), controller_seen = controller_lines.size(),
                      disturbance_seen = disturbance_lines.size();
    auto config = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
        id, e.plant, e.gains, e.options, e.options.disturbance, recovery));
    // Three copies at once, as a client resends an unacknowledged one: a role
    // that drops a copy takes the next, before any y_0 (memq:// is FIFO).
    for (int copy = 0; copy < 3; ++copy) client_t.Publish(kEpisodeConfigChannel, &config);
    const double start = NowSeconds();
    while (!summary && NowSeconds() - start < 20.0) {
      client_t.WaitAndHandle(0.001);
      drain();
      plant.Tick(NowSeconds());
    }
    ASSERT_TRUE(summary) << "episode " << id;
    drain();  // late copies of this episode: not into the next one's queue
    EpisodeCounts c;
    for (std::size_t i = plant_seen; i < plant_lines.size(); ++i)
      if (plant_lines[i].find(": done") != std::string::npos) {
        c.resent = CountIn(plant_lines[i], "(resent ");
        c.plant_dropped = CountIn(plant_lines[i], ", dropped ");
      }
    for (std::size_t i = controller_seen; i < controller_lines.size(); ++i)
      if (controller_lines[i].find(": done") != std::string::npos) {
        c.reanswered = CountIn(controller_lines[i], "(re-answered ");
        c.controller_dropped = CountIn(controller_lines[i], ", dropped ");
      }
    for (std::size_t i = disturbance_seen; i < disturbance_lines.size(); ++i)
      if (disturbance_lines[i].find(": done") != std::string::npos)
        c.disturbance_dropped = CountIn(disturbance_lines[i], "(dropped ");
    std::printf(
        "episode %lld: plant resent %ld, dropped %ld; controller re-answered %ld, dropped %ld; "
        "disturbance dropped %ld\n",
        static_cast<long long>(id), c.resent, c.plant_dropped, c.reanswered, c.controller_dropped,
        c.disturbance_dropped);
    counts.push_back(c);
  }
  ASSERT_EQ(counts.size(), 3u);
  EXPECT_GT(counts[0].resent, 0);
  EXPECT_GT(counts[0].reanswered, 0);
  EXPECT_GT(counts[0].plant_dropped, 0);
  EXPECT_GT(counts[0].controller_dropped, 0);
  EXPECT_GT(counts[0].disturbance_dropped, 0);
  for (std::size_t i = 1; i < counts.size(); ++i) {
    // Equal, so each line counts its own episode: lifetime totals would grow
    // (c, 2c, 3c).
    EXPECT_EQ(counts[i].resent, counts[0].resent) << "episode " << i + 1;
    EXPECT_EQ(counts[i].plant_dropped, counts[0].plant_dropped) << "episode " << i + 1;
    EXPECT_EQ(counts[i].reanswered, counts[0].reanswered) << "episode " << i + 1;
    EXPECT_EQ(counts[i].controller_dropped, counts[0].controller_dropped) << "episode " << i + 1;
    EXPECT_EQ(counts[i].disturbance_dropped, counts[0].disturbance_dropped) << "episode " << i + 1;
  }
  // The lifetime totals hold all three (and whatever came after a "done"
  // line, e.g. a re-answer of the last step).
  EXPECT_GE(plant.counters().retransmits, 3 * counts[0].resent);
  EXPECT_GE(controller.counters().duplicates, 3 * counts[0].reanswered);
}

TEST(RttEstimator, UsesTheInitialTimeoutUntilTheFirstSample) {
  RttOptions o;
  o.initial_s = 0.002;
  RttEstimator rtt(o);
  EXPECT_FALSE(rtt.has_sample());
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 0.002);
}

TEST(RttEstimator, FollowsRfc6298ForTheFirstAndLaterSamples) {
  RttOptions o;
  o.floor_s = 1e-6;
  RttEstimator rtt(o);
  rtt.Sample(100e-6);  // SRTT = R, RTTVAR = R / 2, RTO = SRTT + 4 RTTVAR
  EXPECT_DOUBLE_EQ(rtt.srtt_s(), 100e-6);
  EXPECT_DOUBLE_EQ(rtt.rttvar_s(), 50e-6);
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 300e-6);
  rtt.Sample(200e-6);  // RTTVAR = 3/4 50 + 1/4 |100 - 200|, then SRTT = 7/8 100 + 1/8 200
  EXPECT_DOUBLE_EQ(rtt.rttvar_s(), 0.75 * 50e-6 + 0.25 * 100e-6);
  EXPECT_DOUBLE_EQ(rtt.srtt_s(), 0.875 * 100e-6 + 0.125 * 200e-6);
  EXPECT_DOUBLE_EQ(rtt.Timeout(), rtt.srtt_s() + 4 * rtt.rttvar_s());
}

TEST(RttEstimator, KeepsTheTimeoutBetweenFloorAndCeiling) {
  RttOptions o;
  o.floor_s = 150e-6;
  o.ceiling_s = 0.1;
  RttEstimator rtt(o);
  for (int i = 0; i < 100; ++i) rtt.Sample(10e-6);  // RTTVAR collapses: the floor holds
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 150e-6);
  rtt.Sample(1.0);
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 0.1);
  rtt.Sample(-1.0);  // ignored
  rtt.Sample(std::nan(""));
  EXPECT_EQ(rtt.samples(), 101);
}

TEST(RttEstimator, DoublesPerBackoffUpToTheCeilingAndResetsOnASampleOrProgress) {
  RttOptions o;
  o.floor_s = 200e-6;
  o.ceiling_s = 1e-3;
  RttEstimator rtt(o);
  for (int i = 0; i < 50; ++i) rtt.Sample(20e-6);
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 200e-6);
  rtt.Backoff();
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 400e-6);
  rtt.Backoff();
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 800e-6);
  rtt.Backoff();
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 1e-3);
  for (int i = 0; i < 40; ++i) rtt.Backoff();
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 1e-3);
  rtt.EndBackoff();
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 200e-6);
  rtt.Backoff();
  rtt.Sample(20e-6);
  EXPECT_DOUBLE_EQ(rtt.Timeout(), 200e-6);
}

TEST(RttEstimator, RejectsAFloorAboveTheCeiling) {
  RttOptions o;
  o.floor_s = 0.2;
  o.ceiling_s = 0.1;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("ceiling"), std::string::npos) << error;
}

TEST(Trio, PlantLearnsTheRoundTripWithoutSamplesFromResentExchanges) {
  // Karn's rule: an estimate exists after a clean episode, and the timeout
  // it gives is between the floor and the ceiling.
  const Episode e = DoubleIntegrator(0.5);
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Transport plant_t(&lcm, {}), controller_t(&lcm, {}), disturbance_t(&lcm, {}), client_t(&lcm, {});
  PlantRole plant(&plant_t);
  ControllerRole controller(&controller_t);
  DisturbanceRole disturbance(&disturbance_t);
  bool done = false;
  client_t.Subscribe<pidlab::lcmt_episode_summary>(kSummaryChannel,
                                                   [&](const pidlab::lcmt_episode_summary&) { done = true; });
  auto config = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      5, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  client_t.Publish(kEpisodeConfigChannel, &config);
  const double start = NowSeconds();
  while (!done && NowSeconds() - start < 20.0) {
    client_t.WaitAndHandle(0.001);
    plant.Tick(NowSeconds());
  }
  ASSERT_TRUE(done);
  EXPECT_GE(plant.rtt().samples(), 1);
  EXPECT_LE(plant.rtt().samples(), e.options.TotalSteps());
  EXPECT_GE(plant.rtt().Timeout(), plant.rtt().options().floor_s);
  EXPECT_LE(plant.rtt().Timeout(), plant.rtt().options().ceiling_s);
}

TEST(Trio, PacedEpisodeIsBitIdenticalAndReportsBoundedStatistics) {
  // 0.2 s at dt = 1 ms, FACTOR 1: the same y as unpaced, every step 1..N
  // counted, 0 <= p50 <= p99 <= max, and never faster than the schedule.
  const Episode e = DoubleIntegrator(0.2);
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Transport plant_t(&lcm, {}), controller_t(&lcm, {}), disturbance_t(&lcm, {}), client_t(&lcm, {});
  PlantRole plant(&plant_t, {}, false, /*realtime_factor=*/1.0);
  ControllerRole controller(&controller_t);
  DisturbanceRole disturbance(&disturbance_t);
  const long total = e.options.TotalSteps();
  std::vector<double> y(static_cast<std::size_t>(total + 1), 0.0);
  bool done = false;
  pidlab::lcmt_episode_summary summary;
  client_t.Subscribe<pidlab::lcmt_plant_output>(kPlantOutputChannel, [&](const pidlab::lcmt_plant_output& m) {
    if (m.step >= 0 && m.step <= total) y[static_cast<std::size_t>(m.step)] = m.y;
  });
  client_t.Subscribe<pidlab::lcmt_episode_summary>(kSummaryChannel,
                                                   [&](const pidlab::lcmt_episode_summary& m) {
                                                     done = true;
                                                     summary = m;
                                                   });
  auto config = transport::MakeEpisodeConfig(pidlab::episode_client::MakeEpisodeSpec(
      6, e.plant, e.gains, e.options, e.options.disturbance, RecoveryOptions{}));
  client_t.Publish(kEpisodeConfigChannel, &config);
  const double start = NowSeconds();
  while (!done && NowSeconds() - start < 20.0) {
    client_t.WaitAndHandle(0.001);
    plant.Tick(NowSeconds());
  }
  ASSERT_TRUE(done);
  ASSERT_EQ(summary.status, pidlab::lcmt_episode_summary::OK) << summary.message;
  EXPECT_GE(NowSeconds() - start, 0.2);  // step N starts no earlier than t0 + N dt
  EXPECT_EQ(y, Reference(e));
  const RealtimeStats rt = RealtimeFromSummary(summary);
  ASSERT_TRUE(rt.paced());
  EXPECT_EQ(rt.factor, 1.0);
  EXPECT_GE(rt.missed_deadlines, 0);
  EXPECT_LE(rt.missed_deadlines, total);
  EXPECT_GE(rt.lateness_p50_s, 0.0);
  EXPECT_LE(rt.lateness_p50_s, rt.lateness_p99_s);
  EXPECT_LE(rt.lateness_p99_s, rt.lateness_max_s);
  EXPECT_GT(rt.rate_hz, 0.0);
  EXPECT_LE(rt.rate_hz, 1000.0 * (1 + 1e-9));
}

TEST(Realtime, CombinesEpisodesSummingMissesAndKeepingTheWorstFigures) {
  RealtimeStats a, b;
  a.factor = b.factor = 1.0;
  a.missed_deadlines = 2;
  b.missed_deadlines = 3;
  a.lateness_p99_s = 1e-4;
  b.lateness_p99_s = 2e-4;
  a.rate_hz = 999.0;
  b.rate_hz = 998.0;
  const RealtimeStats c = CombineRealtime(a, b);
  EXPECT_EQ(c.missed_deadlines, 5);
  EXPECT_EQ(c.lateness_p99_s, 2e-4);
  EXPECT_EQ(c.rate_hz, 998.0);
  EXPECT_EQ(CombineRealtime(RealtimeStats{}, a).missed_deadlines, 2);
  EXPECT_FALSE(RealtimeFromSummary(pidlab::lcmt_episode_summary{}).paced());
  std::string error;
  EXPECT_FALSE(RealtimeFactorIsValid(0.0, &error));
  EXPECT_NE(error.find("--realtime 0"), std::string::npos) << error;
  EXPECT_FALSE(RealtimeFactorIsValid(std::nan(""), &error));
  EXPECT_TRUE(RealtimeFactorIsValid(2.5, &error));
}

}  // namespace
}  // namespace pidlab::transport
