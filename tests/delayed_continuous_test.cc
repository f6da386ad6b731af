// The continuous loop with dead time (delayed_loop.h): the Hermite store and
// the exact pieces against closed forms, the step's convergence order, the
// ideal derivative's kick through the delay, the neutral case refused.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/evaluation/delayed_loop.h"
#include "test_status.h"

using pidlab::evaluation::BuildDelayedClosedLoop;
using pidlab::evaluation::DelayedClosedLoop;
using pidlab::evaluation::DelayedLoopIsRetarded;
using pidlab::evaluation::DelayedStepSize;
using pidlab::evaluation::DelayedTrace;
using pidlab::evaluation::kDelayedStepFraction;
using pidlab::evaluation::SampleDelayedLoop;

namespace pidlab {
namespace {

DelayedClosedLoop Build(const TransferFunction& tf, const PidGains& g, double delay, const Disturbance& d,
                        double reference = 1.0) {
  DelayedClosedLoop loop;
  std::string error;
  EXPECT_TRUE(IsOk(BuildDelayedClosedLoop(tf, Realize(tf), g, d, delay, reference, &loop)));
  return loop;
}

std::vector<double> RunLoop(const DelayedClosedLoop& loop, const Disturbance& d, double ts, int n,
                            double force_step_s = 0.0) {
  std::vector<double> y;
  DelayedTrace trace;
  trace.force_step_s = force_step_s;
  std::string error;
  EXPECT_TRUE(IsOk(SampleDelayedLoop(loop, d, ts, n, &y, &trace)));
  return y;
}

TEST(DelayedContinuous, IntegratorUnderPControlMatchesTheMethodOfStepsPolynomials) {
  // y' = k (1 - y(t - L)): y = 0 before L, k (t - L) on [L, 2L], then
  // k (t - L) - k^2 (t - 2L)^2 / 2 on [2L, 3L], + k^3 (t - 3L)^3 / 6 on
  // [3L, 4L]: inputs of degree <= 3, which the Hermite store carries exactly.
  const double k = 0.7, L = 0.4;
  const Disturbance none(DisturbanceOptions{});
  const DelayedClosedLoop loop = Build(TransferFunction{{1.0}, {1.0, 0.0}}, {k, 0.0, 0.0}, L, none);
  const double ts = 0.01;
  const std::vector<double> y = RunLoop(loop, none, ts, 160);
  for (int i = 0; i < 160; ++i) {
    const double t = i * ts;
    double want = 0.0;
    if (t > L) want += k * (t - L);
    if (t > 2 * L) want -= k * k * std::pow(t - 2 * L, 2) / 2.0;
    if (t > 3 * L) want += k * k * k * std::pow(t - 3 * L, 3) / 6.0;
    EXPECT_NEAR(y[static_cast<std::size_t>(i)], want, 1e-13) << "t = " << t;
  }
}

TEST(DelayedContinuous, TheIdealDerivativesKickReachesThePlantAtTheDelay) {
  // 1/s^2, ideal PID: for t < L, e = 1 and u = kp + ki t (y = 0); the kick kd
  // delta(t) arrives at L, so on [L, 2L] y = kd (t - L) + kp (t - L)^2 / 2 +
  // ki (t - L)^3 / 6.
  const double kp = 2.0, ki = 0.5, kd = 0.8, L = 0.5;
  const Disturbance none(DisturbanceOptions{});
  const DelayedClosedLoop loop = Build(TransferFunction{{1.0}, {1.0, 0.0, 0.0}}, {kp, ki, kd}, L, none);
  const double ts = 0.025;
  const std::vector<double> y = RunLoop(loop, none, ts, 41);
  for (int i = 0; i <= 40; ++i) {
    const double t = i * ts, s = t - L;
    const double want = s > 0 ? kd * s + kp * s * s / 2.0 + ki * s * s * s / 6.0 : 0.0;
    EXPECT_NEAR(y[static_cast<std::size_t>(i)], want, 1e-12) << "t = " << t;
  }
}

TEST(DelayedContinuous, TheErrorFallsAsTheFourthPowerOfTheStep) {
  // FOPDT under PI with a square disturbance: the Hermite store is the only
  // error, O(h^4); halving h divides it by about 16.
  DisturbanceOptions sq;
  sq.kind = DisturbanceKind::kSquare;
  sq.amplitude = 0.5;
  const Disturbance d(sq);
  const DelayedClosedLoop loop = Build(TransferFunction{{1.0}, {1.0, 1.0}}, {0.6, 0.6, 0.0}, 0.5, d);
  const std::vector<double> fine = RunLoop(loop, d, 0.05, 101, 0.5 / 256);
  double err[2];
  for (int j = 0; j < 2; ++j) {
    const std::vector<double> y = RunLoop(loop, d, 0.05, 101, 0.5 / (8 << j));
    err[j] = 0.0;
    for (std::size_t i = 0; i < y.size(); ++i) err[j] = std::max(err[j], std::abs(y[i] - fine[i]));
  }
  EXPECT_GT(err[0] / err[1], 12.0) << err[0] << " " << err[1];
  EXPECT_LT(err[0] / err[1], 20.0) << err[0] << " " << err[1];
}

TEST(DelayedContinuous, TheStepDividesTheDelayAndFollowsTheFastestRate) {
  const Disturbance none(DisturbanceOptions{});
  const DelayedClosedLoop loop = Build(TransferFunction{{1.0}, {1.0, 1.0}}, {1.0, 1.0, 0.0}, 0.3, none);
  const double h = DelayedStepSize(loop);
  const double m = 0.3 / h;
  EXPECT_NEAR(m, std::round(m), 1e-9);
  // The fastest rate of 1/(s+1) under PI (1, 1) is the closed loop's |p| = 1.
  EXPECT_LE(h, kDelayedStepFraction * 1.0 + 1e-15);
  EXPECT_GT(h, 0.5 * kDelayedStepFraction);
}

TEST(DelayedContinuous, AnIdealDerivativeOnRelativeDegreeOneIsRefusedAsNeutral) {
  std::string error;
  const TransferFunction fo{{1.0}, {1.0, 1.0}};
  EXPECT_FALSE(OkInto(DelayedLoopIsRetarded(fo, {1.0, 1.0, 0.1}), &error));
  EXPECT_NE(error.find("neutral"), std::string::npos) << error;
  EXPECT_NE(error.find("--derivative-filter"), std::string::npos) << error;
  EXPECT_TRUE(OkInto(DelayedLoopIsRetarded(fo, {1.0, 1.0, 0.1, 0.01}), &error)) << "a filtered derivative";
  EXPECT_TRUE(IsOk(DelayedLoopIsRetarded(TransferFunction{{1.0}, {1.0, 2.0, 1.0}}, {1.0, 1.0, 0.1})));
  DelayedClosedLoop loop;
  EXPECT_FALSE(OkInto(BuildDelayedClosedLoop(fo, Realize(fo), {1.0, 1.0, 0.1},
                                             Disturbance(DisturbanceOptions{}), 0.3, 1.0, &loop),
                      &error));
}

}  // namespace
}  // namespace pidlab
