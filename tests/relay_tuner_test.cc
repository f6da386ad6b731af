// The relay autotune's state machine as the controller runs it
// (controller/relay.h, RelayTuner): the hold's operating point and noise, the
// heat-only relay, the guards (y limit, timeout from the period, load change),
// and the model from the half periods and integrals under noise
// (autotune::FopdtFromTimes).

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pidlab/autotune/relay.h"
#include "pidlab/controller/relay.h"
#include "test_status.h"

namespace pidlab {
namespace {

// K e^(-sL)/(Ts + 1), exact for an input held over each step h, from rest;
// measured with Gaussian noise of `sigma` (seeded); a load `load` added to the
// input from `load_time_s` on.
struct Fopdt {
  double k = 1.0, t = 1.0, l = 0.5, h = 1e-3;
  double sigma = 0.0, load = 0.0, load_time_s = 1e300;
  std::vector<double> pipe;
  std::size_t head = 0;
  double x = 0.0;
  std::mt19937_64 rng{7};
  std::normal_distribution<double> normal{0.0, 1.0};
  double Measure() { return x + (sigma > 0.0 ? sigma * normal(rng) : 0.0); }
  void Apply(double u, double t_s) {
    if (pipe.empty()) pipe.assign(static_cast<std::size_t>(std::lround(l / h)), 0.0);
    const double in = u + (t_s >= load_time_s ? load : 0.0);
    const double arriving = pipe[head];
    pipe[head] = in;
    head = (head + 1) % pipe.size();
    const double a = std::exp(-h / t);
    x = a * x + (1.0 - a) * k * arriving;
  }
};

// Steps `tuner` on `plant` with reference r until it ends or `t_end_s`.
void RunTuner(RelayTuner* tuner, Fopdt* plant, double r, double t_end_s) {
  for (long i = 0; i * plant->h <= t_end_s; ++i) {
    const double t = static_cast<double>(i) * plant->h;
    const double u = tuner->Step(t, r, plant->Measure());
    plant->Apply(u, t);
    if (tuner->phase() == RelayPhase::kDone || tuner->phase() == RelayPhase::kAborted) return;
  }
}

PidOptions Loop(double lo = -1e300, double hi = 1e300) {
  PidOptions o;
  o.dt_s = 1e-3;
  o.output_min = lo;
  o.output_max = hi;
  return o;
}

TEST(RelayTuner, FindsTheOperatingPointAndTheNoiseInTheHoldAndConvergesAroundIt) {
  Fopdt plant;
  plant.k = 2.0;
  plant.sigma = 0.01;
  RelayTuneOptions o;
  o.hold_s = 20.0;
  o.amplitude = 0.5;
  o.bias = 0.15;
  o.noise_multiple = 3.0;
  RelayTuner tuner(o, PidGains{0.3, 0.5, 0.0}, Loop());
  RunTuner(&tuner, &plant, 1.0, 200.0);
  ASSERT_EQ(tuner.phase(), RelayPhase::kDone) << tuner.why();
  EXPECT_NEAR(tuner.u0(), 0.5, 0.01);  // K u0 = r
  EXPECT_NEAR(tuner.y0(), 1.0, 0.01);
  EXPECT_NEAR(tuner.noise_sigma(), 0.01, 0.0015);
  EXPECT_DOUBLE_EQ(tuner.hysteresis(), 3.0 * tuner.noise_sigma());
  EXPECT_DOUBLE_EQ(tuner.d_high(), 0.65);
  EXPECT_DOUBLE_EQ(tuner.d_low(), 0.35);
  // Under noise at least kNoisySettledCycles after the approach.
  EXPECT_GE(static_cast<int>(tuner.cycles().size()), kNoisySettledCycles + 1);
}

// 1 e^(-0.5s)/(s+1) measured with noise sigma 0.05 (seeded), the hysteresis
// 3 sigma, from rest.
RelayTuner RunNoisyRelay(int seed, double d, double bias, double t_end_s) {
  Fopdt plant;
  plant.sigma = 0.05;
  plant.rng.seed(static_cast<unsigned>(seed));
  RelayTuneOptions o;
  o.amplitude = d;
  o.bias = bias;
  o.noise_multiple = 3.0;
  RelayTuner tuner(o, PidGains{}, Loop());
  RunTuner(&tuner, &plant, 0.0, t_end_s);
  return tuner;
}

TEST(RelayTuner, StopsARelayTooSmallForTheNoiseWithinThreeOfItsPeriodsNamingTheAmplitudeThatWould) {
  // A relay of 0.05 moves y by at most 0.05, under the hysteresis 0.15, so
  // only the noise switches it. Against the period of a relay that beats the
  // noise (0.35), over 40 seeds: the noise switches at random, so most stop
  // within 3 periods and every one within 4.
  const RelayTuner working = RunNoisyRelay(1, 0.35, 0.0, 200.0);
  ASSERT_EQ(working.phase(), RelayPhase::kDone) << working.why();
  const double period = working.cycles().back().period_s();
  int within_3 = 0;
  for (int seed = 1; seed <= 40; ++seed) {
    const RelayTuner tuner = RunNoisyRelay(seed, 0.05, 0.0, 120.0);
    ASSERT_EQ(tuner.phase(), RelayPhase::kAborted) << "seed " << seed;
    EXPECT_NE(tuner.why().find("cannot beat the noise"), std::string::npos) << tuner.why();
    EXPECT_NE(tuner.why().find("(now 0.05)"), std::string::npos) << tuner.why();
    const double ran = tuner.end_s() - tuner.relay_start_s();
    EXPECT_LT(ran, 4.0 * period) << "seed " << seed << ": " << tuner.why();
    within_3 += ran < 3.0 * period;
  }
  EXPECT_GE(within_3, 35) << "of 40 within 3 periods of " << period << " s";
}

TEST(RelayTuner, NeverStopsARelayThatBeatsTheNoiseOnTheNoiseGuard) {
  // The same process and noise, relays with K d over 3 hysteresis, over 40
  // seeds: none is taken for the noise, and none times out, though noise cuts
  // cycles short (the timeout counts the longest cycle's periods).
  int done = 0;
  for (int seed = 1; seed <= 40; ++seed) {
    for (double d : {0.5, 1.0}) {
      const RelayTuner tuner = RunNoisyRelay(seed, d, 0.2 * d, 200.0);
      EXPECT_NE(tuner.phase(), RelayPhase::kRelay) << "seed " << seed << ", d " << d;
      EXPECT_EQ(tuner.why().find("noise"), std::string::npos)
          << "seed " << seed << ", d " << d << ": " << tuner.why();
      EXPECT_EQ(tuner.why().find("did not converge"), std::string::npos)
          << "seed " << seed << ", d " << d << ": " << tuner.why();
      done += tuner.phase() == RelayPhase::kDone;
    }
  }
  // The rest end on a noise-cut cycle read as a load change (no PID to hold).
  EXPECT_GE(done, 74) << "of 80";
}

TEST(RelayTuner, CutsTheRelayToTheOutputRangeForAHeatOnlyActuator) {
  Fopdt plant;
  RelayTuneOptions o;
  o.amplitude = 0.4;
  o.bias = 0.1;
  RelayTuner tuner(o, PidGains{0.5, 0.5, 0.0}, Loop(0.0, 2.0));
  RunTuner(&tuner, &plant, 0.2, 100.0);  // u0 = 0.2: the low side would be -0.1
  ASSERT_EQ(tuner.phase(), RelayPhase::kDone) << tuner.why();
  EXPECT_NEAR(tuner.u0(), 0.2, 1e-3);
  EXPECT_DOUBLE_EQ(tuner.d_low(), tuner.u0());  // down to u = 0
  EXPECT_DOUBLE_EQ(tuner.d_high(), 0.5);
}

TEST(RelayTuner, RefusesARelayWithNoRoomAroundTheOperatingPoint) {
  Fopdt plant;
  RelayTuner tuner(RelayTuneOptions{}, PidGains{}, Loop(0.0, 2.0));  // open loop at u0 = 0: no room below
  RunTuner(&tuner, &plant, 1.0, 20.0);
  ASSERT_EQ(tuner.phase(), RelayPhase::kAborted);
  EXPECT_NE(tuner.why().find("no room for a relay around u0 = 0"), std::string::npos) << tuner.why();
}

TEST(RelayTuner, StopsWhenYLeavesTheLimitAndResumesThePreviousPid) {
  Fopdt plant;
  RelayTuneOptions o;
  o.y_limit = 0.1;  // the relay's amplitude is about 0.4
  RelayTuner tuner(o, PidGains{0.5, 0.5, 0.0}, Loop());
  RunTuner(&tuner, &plant, 1.0, 50.0);
  ASSERT_EQ(tuner.phase(), RelayPhase::kAborted);
  EXPECT_NE(tuner.why().find("beyond the limit 0.1"), std::string::npos) << tuner.why();
  // After: the previous PI again, which brings y back to r.
  RunTuner(&tuner, &plant, 1.0, 0.0);
  for (int i = 0; i < 40000; ++i) {
    const double t = 50.0 + i * plant.h;
    plant.Apply(tuner.Step(t, 1.0, plant.Measure()), t);
  }
  EXPECT_NEAR(plant.x, 1.0, 1e-3);
}

TEST(RelayTuner, GivesUpAfterTimeoutPeriodsOfAnOscillationThatDoesNotSettle) {
  // y is a sine whose period shrinks by 5 % a cycle, whatever the input.
  RelayTuneOptions o;
  o.hold_s = 1.0;
  o.timeout_periods = 8.0;
  RelayTuner tuner(o, PidGains{}, Loop());
  double phase = 0.0, period = 4.0;
  for (long i = 0; i < 1000000 && tuner.phase() != RelayPhase::kAborted; ++i) {
    const double t = i * 1e-3;
    const double y = t < 1.0 ? 0.0 : std::sin(2.0 * 3.14159265358979323846 * phase);
    tuner.Step(t, 0.0, y);
    if (t >= 1.0) {
      phase += 1e-3 / period;
      if (phase > 1.0) phase -= 1.0, period *= 0.95;
    }
  }
  ASSERT_EQ(tuner.phase(), RelayPhase::kAborted);
  EXPECT_NE(tuner.why().find("did not converge within 8 periods"), std::string::npos) << tuner.why();
}

TEST(RelayTuner, RestartsFromTheHoldWhenALoadChangesTheSettledOscillation) {
  Fopdt plant;
  plant.load = 0.3;
  plant.load_time_s = 14.3;  // the third cycle (they start at 10.5, 12.2, 13.8 s)
  RelayTuner tuner(RelayTuneOptions{}, PidGains{1.0, 1.0, 0.0}, Loop());
  RunTuner(&tuner, &plant, 1.0, 200.0);
  ASSERT_EQ(tuner.phase(), RelayPhase::kDone) << tuner.why();
  ASSERT_EQ(tuner.load_changes_s().size(), 1u);
  EXPECT_GT(tuner.load_changes_s()[0], 13.0);
  EXPECT_EQ(tuner.restarts(), 1);
  EXPECT_NEAR(tuner.u0(), 0.7, 1e-3);  // the new operating point takes the load
}

TEST(FopdtFromTimes, RecoversTheModelFromHalfPeriodsAndIntegralsUnderNoise) {
  for (const double sigma : {0.0, 0.05}) {
    Fopdt plant;
    plant.sigma = sigma;
    RelayTuneOptions o;
    o.amplitude = 1.0;
    o.bias = 1.0 / 3.0;
    o.noise_multiple = 3.0;
    RelayTuner tuner(o, PidGains{}, Loop());
    RunTuner(&tuner, &plant, 1.0, 300.0);
    ASSERT_EQ(tuner.phase(), RelayPhase::kDone) << tuner.why();
    autotune::RelayOptions relay;
    relay.setpoint = tuner.y0();
    relay.u0 = tuner.u0();
    relay.d_high = tuner.d_high();
    relay.d_low = tuner.d_low();
    relay.hysteresis = tuner.hysteresis();
    relay.settled_cycles = static_cast<int>(tuner.cycles().size()) - 1;
    const autotune::RelayEstimates e =
        autotune::EstimateFromCycles(relay, tuner.cycles(), true, 1.0);  // the half periods, noise or not
    ASSERT_TRUE(e.model_found) << e.message;
    EXPECT_EQ(e.model_from, "switching times and integrals");
    EXPECT_NEAR(e.model.gain, 1.0, sigma > 0.0 ? 0.05 : 0.002) << sigma;
    EXPECT_NEAR(e.model.time_constant_s, 1.0, sigma > 0.0 ? 0.08 : 0.005) << sigma;
    EXPECT_NEAR(e.model.delay_s, 0.5, sigma > 0.0 ? 0.04 : 0.003) << sigma;
  }
}

}  // namespace
}  // namespace pidlab
