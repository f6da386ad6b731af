// Closed-loop responses against closed forms and an independent RK4
// integration; stability; convergence of the sampled loop; LoopOptions.

#include "pidlab/evaluation/closed_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::evaluation::BuildContinuousClosedLoop;
using pidlab::evaluation::ContinuousClosedLoop;
using pidlab::evaluation::ContinuousStability;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::kMaxLoopSteps;
using pidlab::evaluation::kStepsPerBreakpoint;
using pidlab::evaluation::LoopGains;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::RunSampledLoop;
using pidlab::evaluation::SampleContinuousLoop;
using pidlab::evaluation::SampledStability;
using pidlab::evaluation::SampledStep;

namespace pidlab {
namespace {

Evaluation EvaluateOrFail(const TransferFunction& tf, const PidGains& gains, const LoopOptions& options) {
  Evaluation ev;
  std::string error;
  EXPECT_TRUE(IsOk(Evaluate(Plant{"custom", tf}, gains, options, EvaluateOptions{}, &ev)));
  return ev;
}

Plant Builtin(const std::string& name) {
  Plant p;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant(name, StepperMotorParameters{}, &p)));
  return p;
}

// ---- First order: 1/(s+1) under proportional control ----

TEST(ContinuousLoop, ProportionalControlOfAFirstOrderLagIsAFirstOrderLoop) {
  // y(t) = K/(1+K) (1 - e^{-(1+K) t}).
  const double k = 4.0, a = 1.0 + k, yf = k / (1.0 + k);
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {k, 0.0, 0.0}, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable) << "a P-only loop on 1/(s+1) has its single pole at -5";
  ASSERT_EQ(dut.y.size(), 501u);
  for (std::size_t m = 0; m < dut.y.size(); ++m) {
    const double t = 0.05 * m;
    EXPECT_NEAR(dut.y[m], yf * (1.0 - std::exp(-a * t)), 1e-12) << "t = " << t;
  }
  EXPECT_NEAR(dut.step.final_value, yf, 1e-12);
}

TEST(ContinuousLoop, ProportionalIntegralControlCancellingTheLagIsAFirstOrderLoop) {
  // kp + ki/s = kp (s + 1)/s cancels the plant pole: L = kp/s, y = 1 - e^{-kp t}.
  const double kp = 3.0;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {kp, kp, 0.0}, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable);
  ASSERT_EQ(dut.y.size(), 501u);
  for (std::size_t m = 0; m < dut.y.size(); ++m) {
    const double t = 0.05 * m;
    EXPECT_NEAR(dut.y[m], 1.0 - std::exp(-kp * t), 1e-12) << "t = " << t;
  }
}

// ---- Second order: wn^2 / (s (s + 2 zeta wn)) under unit proportional control ----

double SecondOrderStep(double zeta, double wn, double t) {
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  return 1.0 - std::exp(-zeta * wn * t) *
                   (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t));
}

TEST(ContinuousLoop, UnitFeedbackOfATypeOnePlantIsTheClassicSecondOrderResponse) {
  const double zeta = 0.3, wn = 2.0;
  const Evaluation dut =
      EvaluateOrFail({{wn * wn}, {1.0, 2.0 * zeta * wn, 0.0}}, {1.0, 0.0, 0.0}, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable) << "poles of s^2 + 1.2 s + 4 are in the left half plane";
  for (std::size_t m = 0; m < dut.y.size(); ++m)
    EXPECT_NEAR(dut.y[m], SecondOrderStep(zeta, wn, 0.05 * m), 1e-12) << "m = " << m;
}

TEST(ContinuousLoop, CancellingPiControlGivesTheClassicSecondOrderResponse) {
  // Plant wn^2 / ((s + 1)(s + 2 zeta wn)), kp = ki = 1: L = wn^2 / (s (s + 2 zeta wn)).
  const double zeta = 0.3, wn = 2.0;
  const Evaluation dut = EvaluateOrFail({{wn * wn}, {1.0, 1.0 + 2.0 * zeta * wn, 2.0 * zeta * wn}},
                                        {1.0, 1.0, 0.0}, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable);
  for (std::size_t m = 0; m < dut.y.size(); ++m)
    EXPECT_NEAR(dut.y[m], SecondOrderStep(zeta, wn, 0.05 * m), 1e-12) << "m = " << m;
}

// ---- Stability ----

TEST(ContinuousStability, DoubleIntegratorWithProportionalControlIsMarginalAndNotStable) {
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, {1.0, 0.0, 0.0}, LoopOptions{});
  EXPECT_FALSE(dut.stability.stable);
  EXPECT_TRUE(std::isinf(dut.iae) && dut.iae > 0);
  EXPECT_TRUE(std::isinf(dut.ise));
  EXPECT_TRUE(std::isinf(dut.itae));
  EXPECT_TRUE(std::isinf(dut.iae_continuous));
  EXPECT_FALSE(dut.step.valid);
  // s^2 + 1 = 0: poles at +-j.
  int on_axis = 0;
  for (const auto& p : dut.stability.poles)
    on_axis += std::abs(p.real()) < 1e-9 && std::abs(std::abs(p.imag()) - 1.0) < 1e-9;
  EXPECT_EQ(on_axis, 2);
}

TEST(ContinuousStability, OscillatorWithoutControlIsNotStable) {
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 1.0}}, {0.0, 0.0, 0.0}, LoopOptions{});
  EXPECT_FALSE(dut.stability.stable);
  EXPECT_TRUE(std::isinf(dut.iae));
}

TEST(ContinuousStability, DoubleIntegratorWithALargeIntegralGainIsUnstable) {
  // s^3 + kp s + ki: no s^2 term, a pole in the right half plane.
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, {1.0, 10.0, 0.0}, LoopOptions{});
  EXPECT_FALSE(dut.stability.stable);
  EXPECT_GT(dut.stability.abscissa, 0.1);
  EXPECT_TRUE(std::isinf(dut.iae));
  // All three poles are reported, not only those up to the first unstable one.
  ASSERT_EQ(dut.stability.poles.size(), 3u);
  for (const auto& p : dut.stability.poles) EXPECT_LT(std::abs(p * p * p + p + 10.0), 1e-9) << p;
}

TEST(ContinuousStability, CriticallyDampedPdLoopIsStableWithItsPoles) {
  // 1/s^2 with kp = 1, kd = 2, ki = 0.001: s^3 + 2 s^2 + s + 0.001.
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, {1.0, 0.001, 2.0}, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable);
  ASSERT_EQ(dut.stability.poles.size(), 3u);
  // Each pole is a root of s^3 + 2 s^2 + s + 0.001.
  for (const auto& p : dut.stability.poles)
    EXPECT_LT(std::abs(p * p * p + 2.0 * p * p + p + 0.001), 1e-9) << p;
  EXPECT_TRUE(std::isfinite(dut.iae));
}

TEST(ContinuousStability, ProportionalDerivativeLoopWithoutIntegralIsStable) {
  // 1/s^2 with kp = 1, kd = 2: (s + 1)^2. The unused integrator state does not
  // reach y and must not count as a pole at 0.
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, {1.0, 0.0, 2.0}, LoopOptions{});
  EXPECT_TRUE(dut.stability.stable) << "poles of (s + 1)^2 are at -1";
  EXPECT_TRUE(std::isfinite(dut.iae));
}

TEST(SampledStability, StepperMotorWithNelderMeadGainsIsUnstableAtOneMillisecond) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-3;
  Evaluation dut;
  std::string error;
  ASSERT_TRUE(OkInto(
      Evaluate(Builtin("stepper_motor"), {20.8836, 26.607, 12.4866}, o, EvaluateOptions{}, &dut), &error))
      << error;
  EXPECT_FALSE(dut.stability.stable);
  EXPECT_GT(dut.stability.abscissa, 1.0);
  EXPECT_TRUE(std::isinf(dut.iae));
}

TEST(SampledStability, StepperMotorWithNelderMeadGainsIsStableAtATenthOfAMillisecond) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  Evaluation dut;
  std::string error;
  ASSERT_TRUE(OkInto(
      Evaluate(Builtin("stepper_motor"), {20.8836, 26.607, 12.4866}, o, EvaluateOptions{}, &dut), &error))
      << error;
  EXPECT_TRUE(dut.stability.stable);
  EXPECT_LT(dut.stability.abscissa, 1.0);
  EXPECT_TRUE(std::isfinite(dut.iae));
}

TEST(SampledStability, ProportionalLoopWithoutIntegralIsStable) {
  // 1/(s+1) with kp = 4 at dt = 1e-3: y_{k+1} = (q - (1 - q) 4) y_k + ..., |.| < 1.
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, {4.0, 0.0, 0.0}, o);
  EXPECT_TRUE(dut.stability.stable) << "the unused integrator must not count as a pole at z = 1";
}

// ---- Disturbance: exact propagation across breakpoints not aligned with ts ----

// Independent RK4 of 1/s^2 under the ideal PID with the square wave at the
// plant input: y' = v, v' = kp (1 - y) + ki z - kd v + n(t), z' = 1 - y, and
// the derivative kick v(0+) = kd.
std::vector<double> Rk4DoubleIntegrator(const PidGains& g, double amplitude, double period, double phase,
                                        double ts, int samples) {
  auto square = [&](double t_mid) {
    const long piece = static_cast<long>(std::floor((t_mid + phase) / (period / 2.0)));
    return piece % 2 == 0 ? amplitude : -amplitude;
  };
  std::vector<double> events;
  for (int m = 1; m < samples; ++m) events.push_back(m * ts);
  const double t_end = (samples - 1) * ts;
  for (long j = 1; j * period / 2.0 - phase < t_end; ++j)
    if (j * period / 2.0 - phase > 0.0) events.push_back(j * period / 2.0 - phase);
  std::sort(events.begin(), events.end());
  using State = std::array<double, 3>;
  auto f = [&](const State& s, double n) {
    return State{s[1], g.kp * (1.0 - s[0]) + g.ki * s[2] - g.kd * s[1] + n, 1.0 - s[0]};
  };
  State s{0.0, g.kd, 0.0};
  std::vector<double> y = {0.0};
  double t = 0.0;
  for (double te : events) {
    if (te - t < 1e-13) continue;
    const double n = square(0.5 * (t + te));
    const int steps = static_cast<int>(std::ceil((te - t) / 1e-4));
    const double h = (te - t) / steps;
    for (int i = 0; i < steps; ++i) {
      const State k1 = f(s, n);
      State tmp;
      for (int j = 0; j < 3; ++j) tmp[j] = s[j] + 0.5 * h * k1[j];
      const State k2 = f(tmp, n);
      for (int j = 0; j < 3; ++j) tmp[j] = s[j] + 0.5 * h * k2[j];
      const State k3 = f(tmp, n);
      for (int j = 0; j < 3; ++j) tmp[j] = s[j] + h * k3[j];
      const State k4 = f(tmp, n);
      for (int j = 0; j < 3; ++j) s[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    t = te;
    const double m = te / ts;
    if (std::abs(m - std::round(m)) < 1e-9) y.push_back(s[0]);
  }
  return y;
}

TEST(ContinuousLoop, SquareDisturbanceNotAlignedWithTheSamplesMatchesAnIndependentRk4) {
  const PidGains g{2.0, 1.0, 3.0};
  LoopOptions o;
  o.horizon_s = 3.0;
  o.disturbance.kind = DisturbanceKind::kSquare;
  o.disturbance.amplitude = 0.5;
  o.disturbance.period_s = 0.13;
  o.disturbance.phase_s = 0.02;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, g, o);
  ASSERT_TRUE(dut.stability.stable);
  const std::vector<double> expected = Rk4DoubleIntegrator(g, 0.5, 0.13, 0.02, 0.05, 61);
  ASSERT_EQ(expected.size(), 61u);
  ASSERT_EQ(dut.y.size(), 61u);
  for (std::size_t m = 0; m < expected.size(); ++m) EXPECT_NEAR(dut.y[m], expected[m], 1e-6) << "m = " << m;
  // The disturbance really acted: the undisturbed IAE differs.
  EXPECT_GT(std::abs(dut.iae - dut.iae_undisturbed), 1e-3);
}

TEST(ContinuousLoop, WithoutDisturbanceMatchesTheIndependentRk4) {
  const PidGains g{2.0, 1.0, 3.0};
  LoopOptions o;
  o.horizon_s = 3.0;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, g, o);
  const std::vector<double> expected = Rk4DoubleIntegrator(g, 0.0, 0.13, 0.0, 0.05, 61);
  ASSERT_EQ(dut.y.size(), expected.size());
  for (std::size_t m = 0; m < expected.size(); ++m) EXPECT_NEAR(dut.y[m], expected[m], 1e-6) << "m = " << m;
  EXPECT_EQ(dut.iae, dut.iae_undisturbed);
}

// ---- Sampled loop converges to the continuous one ----

void ExpectSampledConvergesToContinuous(const std::string& plant_name, const PidGains& gains) {
  const Plant plant = Builtin(plant_name);
  Evaluation continuous;
  std::string error;
  ASSERT_TRUE(IsOk(Evaluate(plant, gains, LoopOptions{}, EvaluateOptions{}, &continuous)));
  ASSERT_TRUE(continuous.stability.stable);
  double previous = std::numeric_limits<double>::infinity();
  for (double dt : {1e-2, 1e-3, 1e-4}) {
    LoopOptions o;
    o.loop = LoopKind::kSampled;
    o.dt_s = dt;
    Evaluation dut;
    EvaluateOptions what;
    what.compute_step_info = false;
    ASSERT_TRUE(IsOk(Evaluate(plant, gains, o, what, &dut)));
    const double rel = std::abs(dut.iae - continuous.iae) / continuous.iae;
    EXPECT_LT(rel, previous) << "dt = " << dt;
    if (dt == 1e-3) {
      EXPECT_LT(rel, 0.01) << "dt = 1e-3: sampled " << dut.iae << " continuous " << continuous.iae;
    }
    previous = rel;
  }
  EXPECT_LT(previous, 0.002);
}

TEST(SampledLoop, ConvergesToTheContinuousIaeForTableTwoNelderMeadGains) {
  ExpectSampledConvergesToContinuous("double_integrator", {29.6558, 0.4977, 28.3216});
}

TEST(SampledLoop, ConvergesToTheContinuousIaeForTableThreeNelderMeadGains) {
  ExpectSampledConvergesToContinuous("oscillator", {0.0774, 14.7575, 14.9913});
}

TEST(SampledLoop, FirstSamplesFollowTheLockstepOrder) {
  // 1/s^2 with kd only at dt: u_0 = kd/dt held over [0, dt) gives
  // y_1 = kd/dt * dt^2/2 = kd dt / 2 and y' = kd afterwards.
  const double kd = 0.2, dt = 0.01;
  const DiscretePlant plant({{1.0}, {1.0, 0.0, 0.0}}, dt);
  PidOptions pid;
  pid.dt_s = dt;
  std::vector<double> y;
  RunSampledLoop<double>(plant, PidGains{0.0, 0.0, kd}, pid, Disturbance(DisturbanceOptions{}), 3, 1, &y);
  ASSERT_EQ(y.size(), 4u);
  EXPECT_EQ(y[0], 0.0);
  EXPECT_NEAR(y[1], kd * dt / 2.0, 1e-15);
  // Step 1: e = 1 - y_1, D = -kd (y_1 - 0)/dt = -kd^2/2; constant over [dt, 2dt).
  const double v1 = kd, u1 = -kd * (kd * dt / 2.0) / dt;
  EXPECT_NEAR(y[2], y[1] + v1 * dt + u1 * dt * dt / 2.0, 1e-14);
}

// 1/(s - 100) under kp = 200 with output limits +/-1: stable by the linear
// test (which ignores the limits), but the saturated loop runs away and y
// overflows about 7 s in.
struct RunawayLoop {
  static constexpr double kDt = 1e-3;
  static constexpr long kSteps = 10000;  // 10 s
  DiscretePlant plant{{{1.0}, {1.0, -100.0}}, kDt};
  PidOptions pid;
  RunawayLoop() {
    pid.dt_s = kDt;
    pid.output_min = -1.0;
    pid.output_max = 1.0;
  }
};

TEST(SampledLoop, ReportsInvalidInputOnceTheLoopDivergesAndStillRunsEveryStep) {
  const RunawayLoop loop;
  ASSERT_TRUE(SampledStability(loop.plant, PidGains{200.0, 0.0, 0.0}, loop.pid, 0.0).stable);
  std::vector<double> y;
  std::vector<SampledStep> trajectory;
  const PidStatus dut =
      RunSampledLoop<double>(loop.plant, PidGains{200.0, 0.0, 0.0}, loop.pid,
                             Disturbance(DisturbanceOptions{}), RunawayLoop::kSteps, 100, &y, &trajectory);
  EXPECT_EQ(dut, PidStatus::kInvalidInput);
  ASSERT_EQ(y.size(), static_cast<std::size_t>(RunawayLoop::kSteps / 100 + 1));
  ASSERT_EQ(trajectory.size(), static_cast<std::size_t>(RunawayLoop::kSteps));
  EXPECT_TRUE(std::isfinite(y[1]));
  EXPECT_FALSE(std::isfinite(y.back()));
  // Where y is not finite the PID answers u = 0, like pidlab-controller.
  const SampledStep& last = trajectory.back();
  EXPECT_FALSE(std::isfinite(last.y));
  EXPECT_EQ(last.u, 0.0);
  EXPECT_EQ(last.k, RunawayLoop::kSteps - 1);
}

TEST(SampledLoop, ReportsOkForASaturatedLoopThatStaysFinite) {
  const double dt = 1e-3;
  const DiscretePlant plant({{1.0}, {1.0, 1.0}}, dt);
  PidOptions pid;
  pid.dt_s = dt;
  pid.output_min = -0.5;
  pid.output_max = 0.5;  // kp = 10 asks for u = 10 at first: saturated
  std::vector<double> y;
  EXPECT_EQ(RunSampledLoop<double>(plant, PidGains{10.0, 1.0, 0.0}, pid, Disturbance(DisturbanceOptions{}),
                                   2000, 1, &y),
            PidStatus::kOk);
  EXPECT_EQ(y.size(), 2001u);
}

TEST(ObjectiveEvaluator, RejectsASampledLoopThatDiverges) {
  const RunawayLoop loop;
  LoopOptions options;
  options.loop = LoopKind::kSampled;
  options.dt_s = RunawayLoop::kDt;
  options.horizon_s = 10.0;
  options.stability_margin = 0.0;
  options.pid = loop.pid;
  for (ObjectiveKind kind : {ObjectiveKind::kIae, ObjectiveKind::kIaeContinuous}) {
    const ObjectiveEvaluator dut(Plant{"custom", {{1.0}, {1.0, -100.0}}}, options, kind);
    EXPECT_EQ(dut(PidGains{200.0, 0.0, 0.0}), std::numeric_limits<double>::infinity()) << ToString(kind);
  }
}

// ---- LoopOptions ----

TEST(LoopOptions, DefaultsAreValidAndGiveThePapersSampleCount) {
  LoopOptions dut;
  std::string error;
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  EXPECT_EQ(dut.NumSamples(), 501);
  dut.loop = LoopKind::kSampled;
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  EXPECT_EQ(dut.StepsPerSample(), 50);
  EXPECT_EQ(dut.TotalSteps(), 25000);
}

TEST(LoopOptions, RejectsASampleTimeNotAMultipleOfDt) {
  LoopOptions dut;
  dut.loop = LoopKind::kSampled;
  dut.sample_time_s = 0.05;
  dut.dt_s = 0.03;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("0.05"), std::string::npos) << error;
  EXPECT_NE(error.find("0.03"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsAZeroDtForTheSampledLoop) {
  LoopOptions dut;
  dut.loop = LoopKind::kSampled;
  dut.dt_s = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("dt 0"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsANegativeDtForTheSampledLoop) {
  LoopOptions dut;
  dut.loop = LoopKind::kSampled;
  dut.dt_s = -1e-3;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("dt -0.001"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsAZeroDtEvenForTheContinuousLoop) {
  LoopOptions dut;
  dut.dt_s = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error)) << "pidlab evaluate --dt 0 must be bad input";
  EXPECT_NE(error.find("dt 0"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsAHorizonNotAMultipleOfTheSampleTime) {
  LoopOptions dut;
  dut.horizon_s = 25.02;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("25.02"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsAZeroSampleTime) {
  LoopOptions dut;
  dut.sample_time_s = 0.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("sample time 0"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsAnInvalidDisturbance) {
  LoopOptions dut;
  dut.disturbance.kind = DisturbanceKind::kSquare;
  dut.disturbance.period_s = -2.0;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("-2"), std::string::npos) << error;
}

TEST(LoopOptions, RejectsMoreThanFiftyMillionSampledSteps) {
  LoopOptions dut;
  dut.loop = LoopKind::kSampled;
  dut.dt_s = 1e-7;  // 2.5e8 steps
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("more than 5e7"), std::string::npos) << error;
  dut.dt_s = 5e-7;  // 5e7 steps: the limit
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  EXPECT_EQ(dut.TotalSteps(), kMaxLoopSteps);
  dut.dt_s = 1e-300;  // a ratio far beyond a long
  EXPECT_FALSE(dut.IsValid(&error));
}

TEST(LoopOptions, RejectsMoreThanTenMillionSamples) {
  LoopOptions dut;
  dut.sample_time_s = 1e-7;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("more than 1e7"), std::string::npos) << error;
  dut.sample_time_s = 1e-300;
  EXPECT_FALSE(dut.IsValid(&error));
}

TEST(LoopOptions, RejectsMoreThanAMillionDisturbanceSwitchesOnTheContinuousLoop) {
  LoopOptions dut;
  dut.disturbance.kind = DisturbanceKind::kSquare;
  dut.disturbance.amplitude = 1.0;
  dut.disturbance.period_s = 1e-6;  // 5e7 switches in 25 s
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("more than 1e6"), std::string::npos) << error;
  dut.loop = LoopKind::kSampled;  // sampled: one value a step, no switches to follow
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  dut.loop = LoopKind::kContinuous;
  dut.disturbance.kind = DisturbanceKind::kNoise;
  dut.disturbance.noise_hold_s = 1e-9;
  EXPECT_FALSE(dut.IsValid(&error));
  dut.disturbance.noise_hold_s = 0.01;
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  EXPECT_DOUBLE_EQ(dut.DisturbanceBreakpoints(), 2501.0);
  EXPECT_DOUBLE_EQ(dut.StepsPerEvaluation(), 501.0 + kStepsPerBreakpoint * 2501.0);
}

TEST(LoopOptions, RejectsAHugeDisturbancePhase) {
  LoopOptions dut;
  dut.disturbance.kind = DisturbanceKind::kSquare;
  dut.disturbance.amplitude = 1.0;
  dut.disturbance.phase_s = 1e300;
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("phase 1e+300"), std::string::npos) << error;
}

TEST(SampleContinuousLoop, EndsOnABreakpointThatDoesNotAdvance) {
  // Unvalidated: with a phase of 1e300 every breakpoint rounds to t itself,
  // and the sub-step loop used to spin there.
  DisturbanceOptions d;
  d.kind = DisturbanceKind::kSquare;
  d.amplitude = 1.0;
  d.phase_s = 1e300;
  const Disturbance disturbance(d);
  ContinuousClosedLoop<double> loop;
  std::string error;
  ASSERT_TRUE(OkInto(BuildContinuousClosedLoop<double>(Realize({{1.0}, {1.0, 1.0}}), PidGains{1.0, 1.0, 0.0},
                                                       disturbance, &loop),
                     &error))
      << error;
  std::vector<double> y;
  SampleContinuousLoop<double>(loop, disturbance, 0.05, 11, &y);
  EXPECT_EQ(y.size(), 11u);
}

TEST(Evaluate, RejectsANegativeGainAsBadInput) {
  Evaluation ev;
  std::string error;
  EXPECT_FALSE(
      OkInto(Evaluate(Builtin("linear"), {1.0, -2.0, 0.0}, LoopOptions{}, EvaluateOptions{}, &ev), &error));
  EXPECT_NE(error.find("ki = -2"), std::string::npos) << error;
}

TEST(Evaluate, RejectsABiproperPlantAsBadInput) {
  Evaluation ev;
  std::string error;
  EXPECT_FALSE(OkInto(Evaluate(Plant{"custom", {{1.0, 0.0}, {1.0, 1.0}}}, {1.0, 0.0, 0.0}, LoopOptions{},
                               EvaluateOptions{}, &ev),
                      &error));
  EXPECT_NE(error.find("strictly proper"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab

// ---- The filtered PID kp + ki/s + kd s/(tf s + 1) in the continuous loop ----

namespace pidlab {
namespace {

// y(m ts) of the double integrator under the filtered PID by classic RK4 at
// h = 1e-4 s on x1' = x2, x2' = u, z' = e, v' = (e - v)/tf,
// u = kp e + ki z + (kd/tf)(e - v), e = 1 - x1: independent of the matrix form.
std::vector<double> FilteredDoubleIntegratorRk4(const PidGains& g, double ts, int samples) {
  std::array<double, 4> w{0.0, 0.0, 0.0, 0.0};  // x1, x2, z, v
  auto f = [&](const std::array<double, 4>& s) {
    const double e = 1.0 - s[0];
    const double u = g.kp * e + g.ki * s[2] + g.kd / g.tf * (e - s[3]);
    return std::array<double, 4>{s[1], u, e, (e - s[3]) / g.tf};
  };
  const double h = 1e-4;
  const int per = static_cast<int>(std::lround(ts / h));
  std::vector<double> y{w[0]};
  for (int m = 1; m < samples; ++m) {
    for (int k = 0; k < per; ++k) {
      auto add = [&](const std::array<double, 4>& a, const std::array<double, 4>& b, double c) {
        std::array<double, 4> r{};
        for (int i = 0; i < 4; ++i) r[i] = a[i] + c * b[i];
        return r;
      };
      const auto k1 = f(w), k2 = f(add(w, k1, h / 2)), k3 = f(add(w, k2, h / 2)), k4 = f(add(w, k3, h));
      for (int i = 0; i < 4; ++i) w[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
    y.push_back(w[0]);
  }
  return y;
}

TEST(FilteredPid, ContinuousLoopMatchesAnIndependentRk4) {
  PidGains g{29.6558, 0.4977, 28.3216};
  g.tf = 0.05;
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 0.0, 0.0}}, g, LoopOptions{});
  ASSERT_TRUE(dut.stability.stable);
  EXPECT_EQ(dut.stability.poles.size(), 4u) << "plant 2 + integral + filter";
  const std::vector<double> ref = FilteredDoubleIntegratorRk4(g, 0.05, 501);
  ASSERT_EQ(dut.y.size(), ref.size());
  for (std::size_t m = 0; m < ref.size(); ++m) EXPECT_NEAR(dut.y[m], ref[m], 1e-9) << "m = " << m;
  EXPECT_DOUBLE_EQ(dut.gains.tf, 0.05);
}

TEST(FilteredPid, TendsToTheIdealPidAsTheFilterVanishes) {
  const PidGains ideal{29.6558, 0.4977, 28.3216};
  PidGains g = ideal;
  g.tf = 1e-6;
  const TransferFunction di{{1.0}, {1.0, 0.0, 0.0}};
  EXPECT_NEAR(EvaluateOrFail(di, g, LoopOptions{}).iae, EvaluateOrFail(di, ideal, LoopOptions{}).iae, 1e-4);
}

TEST(FilteredPid, WithoutDerivativeGainTheFilterIsAHiddenModeAndChangesNothing) {
  PidGains g{2.0, 1.0, 0.0};
  const Evaluation ideal = EvaluateOrFail({{1.0}, {1.0, 1.0}}, g, LoopOptions{});
  g.tf = 7.0;  // a slow hidden filter pole at -1/7 must not show
  const Evaluation dut = EvaluateOrFail({{1.0}, {1.0, 1.0}}, g, LoopOptions{});
  EXPECT_EQ(dut.stability.poles.size(), ideal.stability.poles.size());
  EXPECT_NEAR(dut.iae, ideal.iae, 1e-12);
  EXPECT_NEAR(dut.step.final_value, 1.0, 1e-12);
}

TEST(FilteredPid, SampledLoopConvergesToTheFilteredContinuousLoop) {
  PidGains g{29.6558, 0.4977, 28.3216};
  g.tf = 0.05;
  const TransferFunction di{{1.0}, {1.0, 0.0, 0.0}};
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  sampled.dt_s = 1e-4;
  const double continuous = EvaluateOrFail(di, g, LoopOptions{}).iae;
  EXPECT_NEAR(EvaluateOrFail(di, g, sampled).iae, continuous, 2e-3 * continuous);
}

TEST(FilteredPid, OptionsFilterReachesBothLoopsAndTheGainsFilterWins) {
  const TransferFunction di{{1.0}, {1.0, 0.0, 0.0}};
  LoopOptions o;
  o.pid.derivative_filter_s = 0.05;
  PidGains g{29.6558, 0.4977, 28.3216};
  const Evaluation from_options = EvaluateOrFail(di, g, o);
  EXPECT_DOUBLE_EQ(from_options.gains.tf, 0.05);
  g.tf = 0.05;
  EXPECT_EQ(from_options.iae, EvaluateOrFail(di, g, LoopOptions{}).iae);
  o.pid.derivative_filter_s = 0.2;  // the gains' own tf is used
  EXPECT_EQ(EvaluateOrFail(di, g, o).gains.tf, 0.05);
}

TEST(FilteredPid, ARatiosFilterIsAtLeastItsFloorAndAGivenTfIsKept) {
  LoopOptions o;
  o.derivative_filter_ratio = 10.0;
  o.derivative_filter_min_s = 0.5;
  EXPECT_DOUBLE_EQ(LoopGains(PidGains{2.0, 1.0, 4.0}, o).tf, 0.5) << "Td / N = 0.2 < 0.5";
  EXPECT_DOUBLE_EQ(LoopGains(PidGains{2.0, 1.0, 40.0}, o).tf, 2.0) << "Td / N = 2 above the floor";
  EXPECT_EQ(LoopGains(PidGains{2.0, 1.0, 0.0}, o).tf, 0.0) << "no derivative: no filter";
  EXPECT_EQ(LoopGains(PidGains{2.0, 1.0, 4.0, 0.1}, o).tf, 0.1) << "the gains' own tf";
  std::string error;
  o.derivative_filter_min_s = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("floor -1"), std::string::npos) << error;
}

TEST(FilteredPid, RatioSetsTfToKdOverNKp) {
  LoopOptions o;
  o.derivative_filter_ratio = 10.0;
  EXPECT_DOUBLE_EQ(LoopGains(PidGains{2.0, 1.0, 4.0}, o).tf, 0.2);
  EXPECT_EQ(LoopGains(PidGains{2.0, 1.0, 0.0}, o).tf, 0.0) << "no derivative: no filter";
  EXPECT_TRUE(std::isinf(LoopGains(PidGains{0.0, 1.0, 4.0}, o).tf));
  Evaluation ev;
  std::string error;
  EXPECT_FALSE(OkInto(
      Evaluate(Plant{"custom", {{1.0}, {1.0, 0.0, 0.0}}}, PidGains{0.0, 1.0, 4.0}, o, EvaluateOptions{}, &ev),
      &error));
  EXPECT_NE(error.find("kp > 0"), std::string::npos) << error;
  o.pid.derivative_filter_s = 0.1;
  EXPECT_FALSE(o.IsValid(&error)) << "a time constant and a ratio at once";
  EXPECT_NE(error.find("not both"), std::string::npos) << error;
}

TEST(FilteredPid, DiscretePidUsesTheGainsFilter) {
  PidGains g{1.0, 0.0, 2.0};
  g.tf = 0.1;
  PidOptions with_gains, with_options;
  with_gains.dt_s = with_options.dt_s = 0.01;
  with_options.derivative_filter_s = 0.1;
  DiscretePid<double> a(g, with_gains), b(PidGains{1.0, 0.0, 2.0}, with_options);
  for (int k = 0; k < 20; ++k) {
    double ua = 0, ub = 0;
    a.Step(1.0, 0.01 * k, &ua);
    b.Step(1.0, 0.01 * k, &ub);
    EXPECT_EQ(ua, ub) << "k = " << k;
  }
}

// A dead time L = 0.3 s at dt = 1 ms stores 300 inputs, whose poles reach
// |Im p| = pi / dt with a decay that grows only like log |p| / L: counted at
// their full modulus, the tuner's margin 0.01 refused this well-damped PI
// loop. Counted up to pi / L they pass, and the loop's own modes still carry
// the full criterion (a margin of 0.3 refuses the lightly damped kp = ki = 3).
TEST(SampledLoop, CountsADeadTimesPolesUpToPiOverLInTheStabilityMargin) {
  const double dt = 1e-3;
  const DiscretePlant plant(TransferFunction{{1.0}, {1.0, 1.0}}, dt, 0.3);
  PidOptions pid;
  pid.dt_s = dt;
  const PidGains gains{0.5, 0.8, 0.0};
  const auto dut = SampledStability(plant, gains, pid, 0.01);
  EXPECT_TRUE(dut.stable);
  EXPECT_EQ(dut.poles.size(), 1u + 300u + 4u);
  // Some stored-input pole fails the uncapped criterion at 0.01.
  bool uncapped_fails = false;
  for (const auto& z : dut.poles) {
    if (std::abs(z) == 0.0) continue;
    const std::complex<double> p = std::log(z) / dt;
    if (!(p.real() < -0.01 * std::max(1.0, std::abs(p)))) uncapped_fails = true;
  }
  EXPECT_TRUE(uncapped_fails);
  EXPECT_TRUE(SampledStability(plant, gains, pid, 0.3).stable);
  EXPECT_FALSE(SampledStability(plant, PidGains{3.0, 3.0, 0.0}, pid, 0.3).stable);
  EXPECT_DOUBLE_EQ(evaluation::DelayedMarginModulus(0.3), 3.14159265358979323846 / 0.3);
  EXPECT_TRUE(std::isinf(evaluation::DelayedMarginModulus(0.0)));
}

// A prbs at the plant input is piecewise constant with a switch every clock:
// the exact continuous loop follows its switches, and the sampled loop at a
// fine dt (the clock a multiple of dt) converges to it.
TEST(Evaluate, APrbsDisturbanceGivesTheSameLoopContinuousAndFinelySampled) {
  LoopOptions o;
  o.horizon_s = 10.0;
  o.disturbance.kind = DisturbanceKind::kPrbs;
  o.disturbance.amplitude = 0.3;
  o.disturbance.noise_hold_s = 0.2;
  o.disturbance.seed = 11;
  const TransferFunction tf{{1.0}, {1.0, 2.0, 1.0}};
  const PidGains gains{2.0, 1.0, 0.5, 0.05};
  const Evaluation continuous = EvaluateOrFail(tf, gains, o);
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  const Evaluation sampled = EvaluateOrFail(tf, gains, o);
  ASSERT_TRUE(continuous.stability.stable);
  EXPECT_GT(continuous.iae, 1.2 * continuous.iae_undisturbed);  // the prbs moves the output
  EXPECT_NEAR(sampled.iae, continuous.iae, 2e-3 * continuous.iae);
  EXPECT_NEAR(sampled.iae_undisturbed, continuous.iae_undisturbed, 2e-3 * continuous.iae_undisturbed);
}

}  // namespace
}  // namespace pidlab
