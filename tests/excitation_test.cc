// Excitation for identification experiments: the chirp disturbance and the
// seeded measurement noise on y (docs/identify.md), their checks, and the
// sampled loop that reports the measured y.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/plant_sim/disturbance.h"
#include "pidlab/spec/loop_spec.h"
#include "spec_build.h"  // internal to pidlab::tune: the steps tested one by one
#include "test_status.h"

namespace pidlab {
namespace {

using evaluation::LoopKind;
using evaluation::LoopOptions;
using evaluation::RunSampledLoop;

constexpr double kTwoPi = 6.283185307179586476925286766559;

DisturbanceOptions Chirp(double amplitude, double f0, double f1, double duration_s) {
  DisturbanceOptions o;
  o.kind = DisturbanceKind::kChirp;
  o.amplitude = amplitude;
  o.chirp_f0_hz = f0;
  o.chirp_f1_hz = f1;
  o.chirp_duration_s = duration_s;
  return o;
}

TEST(Chirp, SamplesEqualTheClosedFormAtEveryStepAndZeroAfterTheSweep) {
  const double a = 0.3, f0 = 0.2, f1 = 7.0, big_t = 5.0, dt = 1e-3;
  const Disturbance dut(Chirp(a, f0, f1, big_t));
  for (long k = 0; k <= 6000; ++k) {
    const double t = static_cast<double>(k) * dt;
    const double want =
        t <= big_t ? a * std::sin(kTwoPi * (f0 * t + (f1 - f0) * t * t / (2.0 * big_t))) : 0.0;
    ASSERT_NEAR(dut.Value(t), want, 1e-12) << "step " << k;
  }
  EXPECT_EQ(dut.Value(0.0), 0.0);
  EXPECT_EQ(dut.Value(big_t + 1e-9), 0.0);
  EXPECT_FALSE(dut.IsPiecewiseConstant());
}

TEST(Chirp, IsAPureFunctionOfTheStepSoEveryProcessGetsTheSameBits) {
  const Disturbance a(Chirp(1.0, 0.5, 20.0, 10.0)), b(Chirp(1.0, 0.5, 20.0, 10.0));
  const double dt = 1e-4;
  // Out of order and repeated: the value at k dt does not depend on history.
  for (long k : {99999L, 3L, 50000L, 3L, 0L, 77777L}) {
    const double t = static_cast<double>(k) * dt;
    EXPECT_EQ(a.Value(t), b.Value(t));
    EXPECT_EQ(a.Value(t), a.Value(t));
  }
}

// f(t) = |n'| / (2 pi sqrt(A^2 - n^2)) from a one-sided difference.
double InstantaneousFrequency(const Disturbance& d, double t, double h, double amplitude) {
  const double n = d.Value(t);
  const double slope = (d.Value(t + h) - d.Value(t)) / h;
  return std::abs(slope) / (kTwoPi * std::sqrt(amplitude * amplitude - n * n));
}

TEST(Chirp, InstantaneousFrequencyIsF0AtTheStartAndF1AtTheEnd) {
  const double a = 1.0, f0 = 0.5, f1 = 4.0, big_t = 8.0, h = 1e-7;
  const Disturbance dut(Chirp(a, f0, f1, big_t));
  EXPECT_NEAR(InstantaneousFrequency(dut, 0.0, h, a), f0, 1e-4 * f0);
  // At T from the left: n(T - h) to n(T - 2h) (the sweep is 0 after T).
  const double t_end = big_t - h;
  const double n = dut.Value(t_end);
  const double slope = (dut.Value(t_end) - dut.Value(t_end - h)) / h;
  EXPECT_NEAR(std::abs(slope) / (kTwoPi * std::sqrt(a * a - n * n)), f1, 1e-3 * f1);
  // Over the sweep the phase advances (f0 + f1) / 2 T cycles: two sign
  // changes per cycle.
  int crossings = 0;
  const double dt = 1e-4;
  for (long k = 1; k * dt <= big_t; ++k)
    if ((dut.Value((k - 1) * dt) < 0.0) != (dut.Value(k * dt) < 0.0)) ++crossings;
  EXPECT_NEAR(crossings, 2.0 * (f0 + f1) / 2.0 * big_t, 2.0);
}

TEST(DisturbanceOptions, RejectsABadChirpBandOrDurationNamingIt) {
  std::string error;
  EXPECT_TRUE(Chirp(1.0, 0.0, 5.0, 2.0).IsValid(&error)) << error;
  for (const auto& [f0, f1] : {std::pair{5.0, 5.0}, {6.0, 5.0}, {-1.0, 5.0}}) {
    EXPECT_FALSE(Chirp(1.0, f0, f1, 2.0).IsValid(&error));
    EXPECT_NE(error.find("chirp band"), std::string::npos) << error;
  }
  EXPECT_FALSE(Chirp(1.0, 0.0, std::nan(""), 2.0).IsValid(&error));
  EXPECT_NE(error.find("chirp band"), std::string::npos) << error;
  EXPECT_FALSE(Chirp(1.0, 0.0, 5.0, 0.0).IsValid(&error));
  EXPECT_NE(error.find("chirp duration 0"), std::string::npos) << error;
}

TEST(MeasurementNoise, HasZeroMeanAndTheGivenStandardDeviation) {
  const MeasurementNoise dut{0.05, 11};
  const long n = 200000;
  double sum = 0.0, sum2 = 0.0;
  for (long k = 0; k < n; ++k) {
    const double v = dut.Value(k);
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n, std_dev = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * 0.05 / std::sqrt(static_cast<double>(n)));
  EXPECT_NEAR(std_dev, 0.05, 0.05 * 0.01);
}

TEST(MeasurementNoise, IsAFunctionOfSeedAndStepAndAnotherStreamThanTheNoiseDisturbance) {
  const MeasurementNoise dut{1.0, 7}, again{1.0, 7}, other_seed{1.0, 8};
  DisturbanceOptions noise;
  noise.kind = DisturbanceKind::kNoise;
  noise.amplitude = 1.0;
  noise.seed = 7;
  noise.noise_hold_s = 1.0;
  const Disturbance disturbance(noise);
  int same_as_other_seed = 0, same_as_disturbance = 0;
  for (long k : {0L, 1L, 2L, 1000L, 5L, 1L, 49999999L}) {
    EXPECT_EQ(dut.Value(k), again.Value(k)) << "step " << k;
    EXPECT_EQ(dut.Value(k), dut.Value(k)) << "step " << k;
    same_as_other_seed += dut.Value(k) == other_seed.Value(k);
    same_as_disturbance += dut.Value(k) == disturbance.Value(static_cast<double>(k));
  }
  EXPECT_EQ(same_as_other_seed, 0);
  EXPECT_EQ(same_as_disturbance, 0);
  EXPECT_EQ(MeasurementNoise{}.Value(3), 0.0);
  const double minus_zero = -0.0;
  EXPECT_TRUE(std::signbit(MeasurementNoise{}.Measured(minus_zero, 3))) << "sigma 0 leaves y's bits";
}

TEST(MeasurementNoise, RejectsANegativeOrNonFiniteSigma) {
  std::string error;
  for (double bad : {-0.1, std::nan(""), HUGE_VAL, 1e13}) {
    EXPECT_FALSE((MeasurementNoise{bad, 1}.IsValid(&error))) << bad;
    EXPECT_EQ(error.rfind("measurement noise", 0), 0u) << error;
  }
}

TEST(SampledLoop, OpenLoopReportsTheTrueOutputPlusTheNoiseOfEachStep) {
  Plant plant;
  std::string error;
  ASSERT_TRUE(IsOk(MakeCustomPlant({1.0}, {1.0, 2.0, 1.0}, &plant)));
  const DiscretePlant discrete(plant.tf, 1e-3);
  PidOptions pid;
  pid.dt_s = 1e-3;
  const Disturbance chirp(Chirp(0.5, 0.1, 5.0, 2.0));
  const MeasurementNoise noise{0.01, 3};
  std::vector<double> clean, measured;
  RunSampledLoop<double>(discrete, PidGains{0.0, 0.0, 0.0}, pid, chirp, 2000, 1, &clean);
  RunSampledLoop<double>(discrete, PidGains{0.0, 0.0, 0.0}, pid, chirp, 2000, 1, &measured, nullptr, 1.0,
                         noise);
  ASSERT_EQ(clean.size(), measured.size());
  for (std::size_t k = 0; k < clean.size(); ++k)
    ASSERT_EQ(measured[k], clean[k] + noise.Value(static_cast<std::int64_t>(k))) << "step " << k;
}

LoopOptions Sampled() {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.horizon_s = 2.0;
  return o;
}

TEST(LoopOptions, RefusesAChirpOrMeasurementNoiseOnTheContinuousLoopAndABandAboveNyquist) {
  std::string error;
  LoopOptions o = Sampled();
  o.disturbance = Chirp(1.0, 0.0, 499.0, 2.0);
  o.measurement_noise = MeasurementNoise{0.01, 1};
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.disturbance.chirp_f1_hz = 500.0;  // 1 / (2 dt) at dt 1e-3
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("Nyquist"), std::string::npos) << error;
  o = Sampled();
  o.loop = LoopKind::kContinuous;
  o.disturbance = Chirp(1.0, 0.0, 5.0, 2.0);
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("chirp"), std::string::npos) << error;
  o.disturbance = DisturbanceOptions{};
  o.measurement_noise = MeasurementNoise{0.01, 1};
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("measurement noise 0.01"), std::string::npos) << error;
}

TEST(SpecBuild, NamesTheChirpBandAndTheMeasurementNoiseAsTheCallerSpellsThem) {
  spec::LoopSpec s;
  s.loop = "sampled";
  s.horizon_s = 2.0;
  s.disturbance = "chirp";
  s.disturbance_amplitude = 0.5;
  s.chirp_band = {1.0, 600.0};
  LoopOptions o;
  std::string error;
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error));
  EXPECT_EQ(error.rfind("--chirp-band 1,600 Hz: F1 must be below the Nyquist frequency", 0), 0u) << error;
  s.chirp_band = {2.0, 1.0};
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kKey, &o, &error));
  EXPECT_EQ(error.rfind("chirp_band 2,1 Hz must have 0 <= F0 < F1", 0), 0u) << error;
  s.chirp_band = {0.0, 5.0};
  ASSERT_TRUE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error)) << error;
  EXPECT_EQ(o.disturbance.chirp_duration_s, 2.0) << "the duration defaults to the horizon";
  s.loop = "continuous";
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error));
  EXPECT_NE(error.find("--loop sampled"), std::string::npos) << error;
  s = spec::LoopSpec();
  s.loop = "sampled";
  s.measurement_noise = -1.0;
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error));
  EXPECT_EQ(error, "--measurement-noise -1 must be >= 0");
  s.measurement_noise = 0.02;
  s.seed = 9;
  ASSERT_TRUE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error)) << error;
  EXPECT_EQ(o.measurement_noise.sigma, 0.02);
  EXPECT_EQ(o.measurement_noise.seed, 9u);
}

TEST(MeasurementNoise, AResolutionRoundsTheMeasuredYToItsNearestMultipleHalvesAwayFromZero) {
  MeasurementNoise q;
  q.resolution = 0.25;
  EXPECT_TRUE(q.enabled());
  EXPECT_EQ(q.Measured(0.1, 0), 0.0);
  EXPECT_EQ(q.Measured(0.125, 0), 0.25);
  EXPECT_EQ(q.Measured(-0.125, 0), -0.25);
  EXPECT_EQ(q.Measured(1.3, 0), 1.25);
  EXPECT_EQ(q.Measured(-7.0, 0), -7.0);
  // With noise: the noisy value is what is rounded.
  MeasurementNoise noisy{0.01, 3};
  noisy.resolution = 0.001;
  for (std::int64_t k : {0, 1, 17}) {
    const double expected = 0.001 * std::round((0.5 + noisy.Value(k)) / 0.001);
    EXPECT_EQ(noisy.Measured(0.5, k), expected) << "step " << k;
  }
  std::string error;
  for (double bad : {-0.1, std::nan(""), HUGE_VAL}) {
    q.resolution = bad;
    EXPECT_FALSE(q.IsValid(&error)) << bad;
    EXPECT_EQ(error.rfind("measurement resolution", 0), 0u) << error;
  }
}

TEST(SampledLoop, AQuantisedSensorReportsOnlyMultiplesOfItsResolutionToThePid) {
  Plant plant;
  std::string error;
  ASSERT_TRUE(IsOk(MakeCustomPlant({1.0}, {1.0, 2.0, 1.0}, &plant)));
  const DiscretePlant discrete(plant.tf, 1e-3);
  PidOptions pid;
  pid.dt_s = 1e-3;
  MeasurementNoise sensor;
  sensor.resolution = 0.05;
  std::vector<double> exact, measured;
  const Disturbance none(DisturbanceOptions{});
  RunSampledLoop<double>(discrete, PidGains{2.0, 1.0, 0.1}, pid, none, 3000, 1, &exact);
  RunSampledLoop<double>(discrete, PidGains{2.0, 1.0, 0.1}, pid, none, 3000, 1, &measured, nullptr, 1.0,
                         sensor);
  ASSERT_EQ(exact.size(), measured.size());
  int differ = 0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    ASSERT_EQ(measured[k], 0.05 * std::round(measured[k] / 0.05)) << "step " << k;
    ASSERT_NEAR(measured[k], exact[k], 0.1) << "step " << k;
    differ += measured[k] != exact[k];
  }
  EXPECT_GT(differ, 100) << "the PID saw the quantised y";
}

TEST(SpecBuild, NamesTheMeasurementResolutionAndKeepsItToTheSampledLoop) {
  spec::LoopSpec s;
  s.loop = "sampled";
  s.horizon_s = 2.0;
  s.measurement_resolution = 0.01;
  LoopOptions o;
  std::string error;
  ASSERT_TRUE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error)) << error;
  EXPECT_EQ(o.measurement_noise.resolution, 0.01);
  s.measurement_resolution = -1.0;
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kFlag, &o, &error));
  EXPECT_EQ(error, "--measurement-resolution -1 must be >= 0 and finite");
  s.measurement_resolution = 0.01;
  s.loop = "continuous";
  EXPECT_FALSE(tune::BuildLoopOptions(s, spec::NameStyle::kKey, &o, &error));
  EXPECT_EQ(error.rfind("measurement_resolution 0.01: a quantised measured y needs loop sampled", 0), 0u)
      << error;
  LoopOptions direct = Sampled();
  direct.loop = LoopKind::kContinuous;
  direct.measurement_noise.resolution = 0.01;
  EXPECT_FALSE(direct.IsValid(&error));
  EXPECT_NE(error.find("measurement resolution 0.01"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab
