// Loop analysis against closed forms: first- and second-order loops, a third-
// order lag's margins, a resonance with damping 1e-3 whose peak is 0.002 rad/s
// wide, the ideal derivative's unbounded noise gain, a near cancellation.

#include "pidlab/analysis/loop_analysis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <utility>

#include "test_status.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::ContinuousLoopMeetsBounds;
using pidlab::analysis::HinfNormBruinsmaSteinbuch;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::analysis::LoopBounds;
using pidlab::analysis::LoopBoundsViolation;
using pidlab::analysis::LoopFrequencyPoint;
using pidlab::analysis::LoopFrequencyResponse;
using pidlab::analysis::Polynomial;
using pidlab::evaluation::BuildContinuousClosedLoop;
using pidlab::evaluation::ContinuousClosedLoop;
using pidlab::evaluation::ContinuousStability;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;

namespace pidlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

LoopAnalysis AnalyzeOrFail(const TransferFunction& tf, const PidGains& g,
                           const LoopOptions& o = LoopOptions{},
                           const LoopAnalysisOptions& ao = LoopAnalysisOptions{}) {
  LoopAnalysis a;
  std::string error;
  EXPECT_TRUE(IsOk(AnalyzeLoop(Plant{"custom", tf}, g, o, ao, &a)));
  return a;
}

// |S| of L = wn^2 / (s (s + 2 zeta wn)) peaks at w^2 = wn^2 (1 + sqrt(1 + 8 zeta^2)) / 2.
double SecondOrderMs(double zeta) {
  const double x = 0.5 * (1.0 + std::sqrt(1.0 + 8.0 * zeta * zeta)), c = 4.0 * zeta * zeta;
  return std::sqrt(x * (x + c) / ((1.0 - x) * (1.0 - x) + c * x));
}

TEST(LoopAnalysis, IntegratorLoopHasNinetyDegreesAndNoGainMargin) {
  // L = k/s: S = s/(s+k), T = k/(s+k), C S = k s/(s+k).
  const double k = 3.0;
  const LoopAnalysis dut = AnalyzeOrFail({{1.0}, {1.0, 0.0}}, {k, 0.0, 0.0});
  ASSERT_TRUE(dut.stable);
  EXPECT_NEAR(dut.phase_margin_deg, 90.0, 1e-9);
  EXPECT_NEAR(dut.gain_crossover_rad_s, k, 1e-9 * k);
  EXPECT_NEAR(dut.delay_margin_s, kPi / 2.0 / k, 1e-9);
  EXPECT_TRUE(std::isinf(dut.gain_margin));
  EXPECT_NE(dut.gain_margin_note.find("infinite gain margin"), std::string::npos);
  EXPECT_NEAR(dut.ms, 1.0, 1e-9);
  EXPECT_NEAR(dut.mt, 1.0, 1e-9);
  EXPECT_NEAR(dut.noise_gain, k, 1e-9);
  EXPECT_NEAR(dut.slowest_time_constant_s, 1.0 / k, 1e-12);
}

TEST(LoopAnalysis, SecondOrderLoopMatchesTheClosedFormsOfMsAndMt) {
  for (const double zeta : {0.2, 0.35, 0.5, 0.7}) {
    const double wn = 2.7;
    const LoopAnalysis dut = AnalyzeOrFail({{wn * wn}, {1.0, 2.0 * zeta * wn, 0.0}}, {1.0, 0.0, 0.0});
    ASSERT_TRUE(dut.stable);
    EXPECT_NEAR(dut.mt, 1.0 / (2.0 * zeta * std::sqrt(1.0 - zeta * zeta)), 1e-9) << "zeta " << zeta;
    EXPECT_NEAR(dut.ms, SecondOrderMs(zeta), 1e-9) << "zeta " << zeta;
    // Gain crossover: w^4 + 4 zeta^2 wn^2 w^2 - wn^4 = 0; PM = atan(2 zeta wn / wc).
    const double wc = wn * std::sqrt(std::sqrt(1.0 + 4.0 * std::pow(zeta, 4)) - 2.0 * zeta * zeta);
    EXPECT_NEAR(dut.gain_crossover_rad_s, wc, 1e-9 * wc);
    EXPECT_NEAR(dut.phase_margin_deg, std::atan2(2.0 * zeta * wn, wc) * 180.0 / kPi, 1e-8);
    EXPECT_TRUE(std::isinf(dut.gain_margin)) << "the phase never reaches -180 deg";
  }
}

TEST(LoopAnalysis, ResonanceWithDampingOneThousandthIsFoundToItsPeak) {
  // Mt = 1 / (2 zeta sqrt(1 - zeta^2)) ~ 500 in a band 0.002 wn wide.
  const double zeta = 1e-3, wn = 7.3;
  const TransferFunction tf{{wn * wn}, {1.0, 2.0 * zeta * wn, 0.0}};
  const LoopAnalysis dut = AnalyzeOrFail(tf, {1.0, 0.0, 0.0});
  ASSERT_TRUE(dut.stable) << "damping 1e-3 is above the default 1e-9 margin";
  const double mt = 1.0 / (2.0 * zeta * std::sqrt(1.0 - zeta * zeta));
  EXPECT_NEAR(dut.mt, mt, 1e-7 * mt);
  EXPECT_NEAR(dut.ms, SecondOrderMs(zeta), 1e-7 * SecondOrderMs(zeta));
  EXPECT_NEAR(dut.mt_rad_s, wn * std::sqrt(1.0 - 2.0 * zeta * zeta), 1e-6 * wn);
  // Without the pole frequencies in the grid, a grid of 5 points a decade
  // sees at most |T| ~ 1 / |1 - (w/wn)^2| ~ 2 there; the Hamiltonian
  // iteration from a lower bound of 1 finds the peak alone.
  double w_peak = 0.0;
  Polynomial t_num{wn * wn}, t_den{1.0, 2.0 * zeta * wn, wn * wn};
  EXPECT_NEAR(HinfNormBruinsmaSteinbuch(t_num, t_den, 1.0, 1.0, 1e-9, &w_peak), mt, 1e-6 * mt);
  EXPECT_NEAR(w_peak, wn * std::sqrt(1.0 - 2.0 * zeta * zeta), 1e-4 * wn);
}

TEST(LoopAnalysis, HamiltonianIterationMatchesTheSecondOrderClosedForm) {
  for (const double zeta : {0.05, 0.3, 0.6}) {
    double w = 0.0;
    const double mt = 1.0 / (2.0 * zeta * std::sqrt(1.0 - zeta * zeta));
    EXPECT_NEAR(HinfNormBruinsmaSteinbuch({4.0}, {1.0, 4.0 * zeta, 4.0}, 0.5, 0.1, 1e-10, &w), mt, 1e-7 * mt)
        << "zeta " << zeta << " w " << w;
  }
}

TEST(LoopAnalysis, ThirdOrderLagHasTheClosedFormGainAndPhaseMargins) {
  // L = k/(s+1)^3: -180 deg at w = sqrt(3) where |L| = k/8; |L| = 1 at
  // w = sqrt(k^(2/3) - 1) with phase -3 atan(w).
  const double k = 2.0;
  const LoopAnalysis dut = AnalyzeOrFail({{1.0}, {1.0, 3.0, 3.0, 1.0}}, {k, 0.0, 0.0});
  ASSERT_TRUE(dut.stable);
  EXPECT_NEAR(dut.gain_margin, 8.0 / k, 1e-9);
  EXPECT_NEAR(dut.phase_crossover_rad_s, std::sqrt(3.0), 1e-9);
  const double wc = std::sqrt(std::pow(k, 2.0 / 3.0) - 1.0);
  const double pm = 180.0 - 3.0 * std::atan(wc) * 180.0 / kPi;
  EXPECT_NEAR(dut.gain_crossover_rad_s, wc, 1e-9);
  EXPECT_NEAR(dut.phase_margin_deg, pm, 1e-7);
  EXPECT_NEAR(dut.delay_margin_s, pm * kPi / 180.0 / wc, 1e-8);
}

TEST(LoopAnalysis, ConditionallyStableDoubleIntegratorHasAGainReductionMargin) {
  // L = (kd s^2 + kp s + ki)/s^3: phase -180 at w = sqrt(ki/kd), GM = ki/(kp kd) < 1.
  const PidGains g{29.6558, 0.4977, 28.3216};
  const LoopAnalysis dut = AnalyzeOrFail({{1.0}, {1.0, 0.0, 0.0}}, g);
  ASSERT_TRUE(dut.stable);
  EXPECT_NEAR(dut.gain_margin, g.ki / (g.kp * g.kd), 1e-9);
  EXPECT_NEAR(dut.phase_crossover_rad_s, std::sqrt(g.ki / g.kd), 1e-9);
}

TEST(LoopAnalysis, IdealDerivativeHasAnUnboundedNoiseGainAndTheFilterBoundsIt) {
  const TransferFunction di{{1.0}, {1.0, 0.0, 0.0}};
  PidGains g{29.6558, 0.4977, 28.3216};
  const LoopAnalysis ideal = AnalyzeOrFail(di, g);
  EXPECT_TRUE(std::isinf(ideal.noise_gain));
  EXPECT_EQ(ideal.noise_gain_note, "ideal derivative: unbounded");
  g.tf = 0.01;
  const LoopAnalysis filtered = AnalyzeOrFail(di, g);
  ASSERT_TRUE(filtered.stable);
  // C S -> kp + kd/tf at high frequency, where S -> 1.
  EXPECT_TRUE(std::isfinite(filtered.noise_gain));
  EXPECT_GE(filtered.noise_gain, (g.kp + g.kd / g.tf) * (1.0 - 1e-9));
  EXPECT_LT(filtered.noise_gain, 1.2 * (g.kp + g.kd / g.tf));
}

TEST(LoopAnalysis, ReportsTheNearCancellationOfTheSlowPole) {
  // The default tune of 1/s^2: kp 0.2999, ki 0, kd 30 on 1/s^2 leaves a pole near -0.01 on the PID zero
  // -kp/kd.
  const LoopAnalysis dut = AnalyzeOrFail({{1.0}, {1.0, 0.0, 0.0}}, {0.2999, 0.0, 30.0});
  ASSERT_TRUE(dut.stable);
  ASSERT_EQ(dut.cancellations.size(), 1u);
  EXPECT_NEAR(dut.cancellations[0].zero.real(), -0.2999 / 30.0, 1e-12);
  EXPECT_LT(dut.cancellations[0].relative_distance, 1e-3);
  EXPECT_NEAR(dut.slowest_time_constant_s, 100.0, 1.0);
}

TEST(LoopAnalysis, SampledLoopTendsToTheContinuousLoopAsDtShrinks) {
  const TransferFunction di{{1.0}, {1.0, 0.0, 0.0}};
  PidGains g{29.6558, 0.4977, 28.3216};
  g.tf = 0.02;
  const LoopAnalysis c = AnalyzeOrFail(di, g);
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-5;
  const LoopAnalysis s = AnalyzeOrFail(di, g, o);
  ASSERT_TRUE(s.stable);
  EXPECT_NEAR(s.ms, c.ms, 2e-3 * c.ms);
  EXPECT_NEAR(s.mt, c.mt, 2e-3 * c.mt);
  EXPECT_NEAR(s.noise_gain, c.noise_gain, 2e-3 * c.noise_gain);
  EXPECT_NEAR(s.phase_margin_deg, c.phase_margin_deg, 0.1);
  EXPECT_NEAR(s.gain_margin, c.gain_margin, 2e-3 * c.gain_margin);
  EXPECT_NEAR(s.slowest_time_constant_s, c.slowest_time_constant_s, 1e-3 * c.slowest_time_constant_s);
}

TEST(LoopAnalysis, UnstableLoopHasNoMargins) {
  const LoopAnalysis dut = AnalyzeOrFail({{1.0}, {1.0, 0.0, 0.0}}, {1.0, 5.0, 0.1});
  EXPECT_FALSE(dut.stable);
  EXPECT_TRUE(std::isnan(dut.ms));
}

TEST(LoopBounds, TheTunersCheapCheckAgreesWithTheFullAnalysis) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> gain(0.0, 30.0);
  const TransferFunction plants[] = {
      {{1.0}, {1.0, 0.0, 0.0}}, {{1.0}, {1.0, 0.0, 1.0}}, {{1.0}, {1.0, 3.0, 3.0, 1.0}}};
  LoopBounds b;
  b.max_ms = 1.6;
  b.max_mt = 1.5;
  b.min_phase_margin_deg = 40.0;
  b.max_noise_gain = 200.0;
  int met = 0, checked = 0;
  for (const auto& tf : plants) {
    for (int i = 0; i < 100; ++i) {
      PidGains g{gain(rng), gain(rng), gain(rng)};
      g.tf = 0.05;
      const LoopAnalysis a = AnalyzeOrFail(tf, g);
      if (!a.stable) continue;
      StateSpace ss = Realize(tf);
      ContinuousClosedLoop<double> loop;
      ASSERT_TRUE(OkInto(BuildContinuousClosedLoop<double>(ss, g, Disturbance(DisturbanceOptions{}), &loop),
                         nullptr));
      const bool full = LoopBoundsViolation(a, b).empty();
      EXPECT_EQ(ContinuousLoopMeetsBounds(tf, g, ContinuousStability(loop, 1e-9), b), full)
          << "kp " << g.kp << " ki " << g.ki << " kd " << g.kd << ": " << LoopBoundsViolation(a, b);
      met += full;
      ++checked;
    }
  }
  EXPECT_GT(met, 0) << "some loops meet the bounds";
  EXPECT_LT(met, checked) << "and some do not";
}

TEST(LoopBounds, NamesTheFirstBoundBroken) {
  LoopAnalysis a;
  a.stable = true;
  a.ms = 2.0;
  a.mt = 1.0;
  a.noise_gain = 10.0;
  a.phase_margin_deg = 50.0;
  a.slowest_time_constant_s = 1.0;
  LoopBounds b;
  EXPECT_EQ(LoopBoundsViolation(a, b), "");
  b.max_ms = 1.6;
  EXPECT_EQ(LoopBoundsViolation(a, b), "Ms 2 > 1.6");
  std::string error;
  b.max_ms = 0.5;
  EXPECT_FALSE(b.IsValid(&error));
  EXPECT_NE(error.find("max Ms 0.5"), std::string::npos);
}

}  // namespace
}  // namespace pidlab

namespace pidlab {
namespace {

// 1/s under P control: L = kp/(jw), S = jw/(jw + kp), T = kp/(jw + kp).
TEST(LoopFrequencyResponse, IntegratorUnderPControlMatchesTheClosedForm) {
  const double kp = 2.5;
  const std::vector<double> w = {1e-3, 0.1, 1.0, 2.5, 10.0, 1e3};
  std::vector<LoopFrequencyPoint> r;
  std::string error;
  ASSERT_TRUE(OkInto(LoopFrequencyResponse(Plant{"custom", TransferFunction{{1.0}, {1.0, 0.0}}},
                                           PidGains{kp, 0.0, 0.0}, LoopOptions{}, w, &r),
                     &error))
      << error;
  ASSERT_EQ(r.size(), w.size());
  for (std::size_t i = 0; i < w.size(); ++i) {
    const std::complex<double> jw(0.0, w[i]);
    EXPECT_EQ(r[i].w_rad_s, w[i]);
    EXPECT_LT(std::abs(r[i].l - kp / jw), 1e-12 * std::abs(kp / jw)) << w[i];
    EXPECT_LT(std::abs(r[i].s - jw / (jw + kp)), 1e-12) << w[i];
    EXPECT_LT(std::abs(r[i].t - kp / (jw + kp)), 1e-12) << w[i];
  }
  // |S| = 1/sqrt(2) at the bandwidth w = kp.
  EXPECT_NEAR(std::abs(r[3].s), 1.0 / std::sqrt(2.0), 1e-12);
}

// The filtered PID of the loop's derivative filter ratio on 1/(s^2+1),
// against C(jw) G(jw) written out directly; S + T = 1 everywhere.
TEST(LoopFrequencyResponse, FilteredPidOnTheOscillatorMatchesTheDirectProduct) {
  LoopOptions o;
  o.derivative_filter_ratio = 10.0;
  const PidGains g{3.0, 2.0, 1.5};
  const double tf = g.kd / (10.0 * g.kp);
  std::vector<LoopFrequencyPoint> r;
  std::string error;
  const std::vector<double> w = {0.01, 0.5, 0.999, 1.001, 7.0, 300.0};
  ASSERT_TRUE(OkInto(
      LoopFrequencyResponse(Plant{"custom", TransferFunction{{1.0}, {1.0, 0.0, 1.0}}}, g, o, w, &r), &error))
      << error;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const std::complex<double> s(0.0, w[i]);
    const std::complex<double> l = (g.kp + g.ki / s + g.kd * s / (tf * s + 1.0)) / (s * s + 1.0);
    EXPECT_LT(std::abs(r[i].l - l), 1e-10 * std::abs(l)) << w[i];
    EXPECT_LT(std::abs(r[i].s - 1.0 / (1.0 + l)), 1e-10) << w[i];
    EXPECT_LT(std::abs(r[i].s + r[i].t - 1.0), 1e-12) << w[i];
  }
  // On the plant's pole (w = 1) L is infinite: S = 0, T = 1, no NaN.
  ASSERT_TRUE(IsOk(
      LoopFrequencyResponse(Plant{"custom", TransferFunction{{1.0}, {1.0, 0.0, 1.0}}}, g, o, {1.0}, &r)));
  EXPECT_TRUE(std::isinf(std::abs(r[0].l)));
  EXPECT_EQ(std::abs(r[0].s), 0.0);
  EXPECT_EQ(r[0].t, std::complex<double>(1.0, 0.0));
}

TEST(LoopFrequencyResponse, RejectsFrequenciesOutsideTheLoopsRange) {
  std::vector<LoopFrequencyPoint> r;
  std::string error;
  const Plant p{"custom", TransferFunction{{1.0}, {1.0, 0.0}}};
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  EXPECT_FALSE(OkInto(
      LoopFrequencyResponse(p, PidGains{1.0, 0.0, 0.0}, sampled, {1.1 * M_PI / sampled.dt_s}, &r), &error));
  EXPECT_NE(error.find("pi/dt"), std::string::npos) << error;
  EXPECT_FALSE(OkInto(LoopFrequencyResponse(p, PidGains{1.0, 0.0, 0.0}, LoopOptions{}, {0.0}, &r), &error));
  EXPECT_NE(error.find("frequency"), std::string::npos) << error;
}

TEST(LoopFrequencyResponse, SampledLoopPeaksAtTheAnalysisMsMtAndNoiseGain) {
  const Plant p{"custom", TransferFunction{{1.0}, {1.0, 0.0, 1.0}}};
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  sampled.dt_s = 0.05;
  const PidGains g{2.0, 1.0, 1.5, 0.1};
  pidlab::analysis::LoopAnalysis a;
  std::string error;
  ASSERT_TRUE(IsOk(pidlab::analysis::AnalyzeLoop(p, g, sampled, {}, &a)));
  std::vector<LoopFrequencyPoint> r;
  ASSERT_TRUE(
      OkInto(LoopFrequencyResponse(p, g, sampled, {a.ms_rad_s, a.mt_rad_s, a.noise_gain_rad_s}, &r), &error))
      << error;
  EXPECT_NEAR(std::abs(r[0].s), a.ms, 1e-9 * a.ms);
  EXPECT_NEAR(std::abs(r[1].t), a.mt, 1e-9 * a.mt);
  EXPECT_NEAR(std::abs(r[2].cs), a.noise_gain, 1e-9 * a.noise_gain);
  EXPECT_NEAR(std::abs(r[0].s + r[0].t), 1.0, 1e-12);
}

}  // namespace
}  // namespace pidlab

namespace pidlab {
namespace {

// AnalyzeLoop keeps its last answers per thread (a served evaluation asks
// for the same loop three times at other horizons): a kept answer equals a
// new analysis bit for bit, and an input the analysis reads is never mixed up.
LoopAnalysis FreshAnalysis(const Plant& plant, const PidGains& g, const LoopOptions& o) {
  LoopAnalysis a;
  std::thread([&] { EXPECT_TRUE(IsOk(AnalyzeLoop(plant, g, o, LoopAnalysisOptions{}, &a))); }).join();
  return a;
}

void ExpectSameBits(const LoopAnalysis& a, const LoopAnalysis& b) {
  for (const auto& [x, y] : {std::pair{a.ms, b.ms},
                             {a.mt, b.mt},
                             {a.phase_margin_deg, b.phase_margin_deg},
                             {a.gain_margin, b.gain_margin},
                             {a.noise_gain, b.noise_gain},
                             {a.slowest_time_constant_s, b.slowest_time_constant_s},
                             {a.gain_crossover_rad_s, b.gain_crossover_rad_s}})
    EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << x << " vs " << y;
  EXPECT_EQ(a.stable, b.stable);
}

TEST(AnalyzeLoop, KeepsItsAnswerAcrossHorizonsBitForBitAndNeverForAnotherLoop) {
  Plant plant;
  plant.name = "custom";
  plant.tf.num = {2.0};
  plant.tf.den = {60.0, 1.0};
  plant.delay_s = 8.0;
  const PidGains g{1.98, 0.128, 8.5, 0.43};
  LoopOptions o;
  LoopAnalysis first, again;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, o, LoopAnalysisOptions{}, &first)));
  o.horizon_s = 500.0;
  o.sample_time_s = 1.0;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, g, o, LoopAnalysisOptions{}, &again)));
  ExpectSameBits(again, first);
  ExpectSameBits(again, FreshAnalysis(plant, g, o));
  // Another gain, filter, delay or plant name is another analysis.
  PidGains other = g;
  other.kp *= 1.0 + 1e-15;
  LoopAnalysis a;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, other, o, LoopAnalysisOptions{}, &a)));
  ExpectSameBits(a, FreshAnalysis(plant, other, o));
  Plant slower = plant;
  slower.delay_s = 9.0;
  ASSERT_TRUE(IsOk(AnalyzeLoop(slower, g, o, LoopAnalysisOptions{}, &a)));
  EXPECT_GT(a.ms, first.ms);
  ExpectSameBits(a, FreshAnalysis(slower, g, o));
  LoopOptions filtered = o;
  PidGains unfiltered = g;
  unfiltered.tf = 0.0;
  filtered.derivative_filter_ratio = 5.0;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, unfiltered, filtered, LoopAnalysisOptions{}, &a)));
  ExpectSameBits(a, FreshAnalysis(plant, unfiltered, filtered));
  filtered.derivative_filter_ratio = 20.0;
  LoopAnalysis b;
  ASSERT_TRUE(IsOk(AnalyzeLoop(plant, unfiltered, filtered, LoopAnalysisOptions{}, &b)));
  EXPECT_NE(a.noise_gain, b.noise_gain);
  ExpectSameBits(b, FreshAnalysis(plant, unfiltered, filtered));
}

}  // namespace
}  // namespace pidlab
