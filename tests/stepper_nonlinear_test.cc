// The nonlinear PM stepper: its linearisation (by automatic differentiation)
// is eq. (3), its integrator meets a long-double reference, it is
// deterministic, and the nonlinear loop matches eq. (3) for small moves.

#include "pidlab/plant_sim/stepper_nonlinear.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/evaluation/fast_objective.h"
#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::FastContinuousObjective;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;

namespace pidlab {
namespace {

std::vector<std::complex<double>> Roots(const std::vector<double>& monic) {
  const int n = static_cast<int>(monic.size()) - 1;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) companion(0, j) = -monic[static_cast<std::size_t>(j) + 1];
  for (int i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  Eigen::EigenSolver<Eigen::MatrixXd> es(companion);
  std::vector<std::complex<double>> r;
  for (int i = 0; i < n; ++i) r.push_back(es.eigenvalues()(i));
  std::sort(r.begin(), r.end(),
            [](auto a, auto b) { return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag(); });
  return r;
}

void ExpectSameTransferFunction(const TransferFunction& dut, const TransferFunction& eq3) {
  ASSERT_EQ(dut.den.size(), 4u) << dut.ToString();
  ASSERT_EQ(dut.num.size(), 1u) << dut.ToString();
  EXPECT_EQ(dut.den[0], 1.0);
  const auto p = Roots(dut.den), q = Roots(eq3.den);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_LT(std::abs(p[i] - q[i]), 1e-6 * std::abs(q[i])) << "pole " << i << ": " << p[i] << " vs " << q[i];
  const double dc = dut.num.back() / dut.den.back(), dc3 = eq3.num.back() / eq3.den.back();
  EXPECT_NEAR(dc, dc3, 1e-6 * std::abs(dc3));
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(dut.den[i], eq3.den[i], 1e-9 * std::abs(eq3.den[i])) << i;
  EXPECT_NEAR(dut.num[0], eq3.num[0], 1e-9 * eq3.num[0]);
}

TEST(StepperLinearization, JacobianByAutodiffIsEquationThreeForTableOne) {
  NonlinearStepperOptions o;
  StepperLinearization dut;
  std::string error;
  ASSERT_TRUE(IsOk(LinearizeStepper(o, &dut)));
  ExpectSameTransferFunction(dut.tf, StepperMotorTransferFunction(o.motor));
}

TEST(StepperLinearization, JacobianIsEquationThreeForOtherParameters) {
  NonlinearStepperOptions o;
  o.motor.resistance_ohm = 12.0;
  o.motor.mutual_inductance_h = 1.1e-3;
  o.motor.inertia_kg_m2 = 4e-5;
  o.motor.stationary_current_a = 0.4;
  o.motor.tooth_pitch_rad = 0.2;  // N_r lambda = 1.2, not pi/2
  StepperLinearization dut;
  std::string error;
  ASSERT_TRUE(IsOk(LinearizeStepper(o, &dut)));
  ExpectSameTransferFunction(dut.tf, StepperMotorTransferFunction(o.motor));
}

TEST(StepperLinearization, PhysicalAngleCommandHasDcGainOne) {
  NonlinearStepperOptions o;
  o.input_scale = 1.0;
  StepperLinearization dut;
  std::string error;
  ASSERT_TRUE(IsOk(LinearizeStepper(o, &dut)));
  EXPECT_NEAR(dut.tf.num.back() / dut.tf.den.back(), 1.0, 1e-12);
  // Eq. (3)'s DC gain is (r/L) / (r/Lp) = Lp/L: the default input scale.
  const TransferFunction eq3 = StepperMotorTransferFunction(o.motor);
  EXPECT_NEAR(eq3.num.back() / eq3.den.back(), (5.4e-3 - 0.4e-3) / 5.4e-3, 1e-12);
}

TEST(StepperLinearization, RefusesAPointThatIsNotAnEquilibrium) {
  NonlinearStepperOptions o;
  o.motor.tooth_pitch_rad = 0.2;
  o.detent_torque_nm = 1e-3;  // sin(4 N_r lambda/2) != 0: the detent moves the rest point
  StepperLinearization dut;
  std::string error;
  EXPECT_FALSE(OkInto(LinearizeStepper(o, &dut), &error));
  EXPECT_NE(error.find("equilibrium"), std::string::npos) << error;
}

// Classic RK4 in long double with a tiny fixed step: the reference.
std::array<long double, 4> ReferenceStep(const NonlinearStepperOptions& o, std::array<long double, 4> x,
                                         double u, double t0, double dt, int substeps) {
  const long double h = static_cast<long double>(dt) / substeps;
  auto f = [&](const std::array<long double, 4>& s, std::array<long double, 4>* d) {
    StepperDerivative<long double>(o, s.data(), static_cast<long double>(u), t0, d->data());
  };
  std::array<long double, 4> k1, k2, k3, k4, tmp;
  for (int n = 0; n < substeps; ++n) {
    f(x, &k1);
    for (int i = 0; i < 4; ++i) tmp[i] = x[i] + h / 2 * k1[i];
    f(tmp, &k2);
    for (int i = 0; i < 4; ++i) tmp[i] = x[i] + h / 2 * k2[i];
    f(tmp, &k3);
    for (int i = 0; i < 4; ++i) tmp[i] = x[i] + h * k3[i];
    f(tmp, &k4);
    for (int i = 0; i < 4; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  }
  return x;
}

TEST(NonlinearStepperPlant, MatchesALongDoubleRk4ReferenceToBetterThan1e8Rad) {
  // A large move (0.5 rad, beyond a step) under a 12 V limit and detent:
  // the currents swing hard, the rotor slews; inputs change every step.
  NonlinearStepperOptions o;
  o.voltage_limit_v = 12.0;
  o.detent_torque_nm = 2e-4;
  const double dt = 1e-4;
  NonlinearStepperPlant dut(o, dt);
  const std::vector<double> x0 = StepperHoldingState(o);
  std::array<long double, 4> ref{x0[0], x0[1], x0[2], x0[3]};
  double worst = 0.0, moved = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double u = 0.3 + 0.2 * std::sin(0.005 * k);
    ref = ReferenceStep(o, ref, u, k * dt, dt, 100);
    dut.Step(u);
    worst = std::max(worst, std::abs(static_cast<double>(ref[2]) - dut.state()[2]));
    moved = std::max(moved, std::abs(dut.Output()));
  }
  EXPECT_LT(worst, 1e-8) << "worst |theta - theta_ref| = " << worst;
  EXPECT_GT(moved, 0.2) << "the test trajectory should move the rotor by more than a step";
  std::printf("worst |theta - theta_ref| = %.3g rad over 0.2 s, largest move %.3g rad\n", worst, moved);
}

TEST(NonlinearStepperPlant, IsBitIdenticalRunToRun) {
  NonlinearStepperOptions o;
  o.voltage_limit_v = 12.0;
  o.load_step_nm = 1e-3;
  o.load_step_time_s = 0.01234;
  NonlinearStepperPlant a(o, 1e-4), b(o, 1e-4);
  for (int k = 0; k < 500; ++k) {
    a.Step(0.2);
    b.Step(0.2);
    ASSERT_EQ(a.state(), b.state()) << "step " << k;
  }
  a.Reset();
  NonlinearStepperPlant c(o, 1e-4);
  for (int k = 0; k < 500; ++k) {
    a.Step(0.2);
    c.Step(0.2);
  }
  EXPECT_EQ(a.state(), c.state());
}

TEST(NonlinearStepperPlant, HoldsItsPositionWithZeroInput) {
  NonlinearStepperPlant dut(NonlinearStepperOptions{}, 1e-4);
  for (int k = 0; k < 1000; ++k) dut.Step(0.0);
  EXPECT_LT(std::abs(dut.Output()), 1e-12);
  EXPECT_NEAR(dut.state()[0], 0.15, 1e-12);
}

TEST(NonlinearStepperPlant, RejectsInvalidOptions) {
  NonlinearStepperOptions o;
  o.voltage_limit_v = 0.0;
  EXPECT_THROW(NonlinearStepperPlant(o, 1e-4), std::invalid_argument);
  EXPECT_THROW(NonlinearStepperPlant(NonlinearStepperOptions{}, 0.0), std::invalid_argument);
}

TEST(StepperLinearization, MicrostepTableHasTheSameLinearisation) {
  NonlinearStepperOptions o;
  o.microstep_table = true;
  StepperLinearization dut;
  std::string error;
  ASSERT_TRUE(IsOk(LinearizeStepper(o, &dut)));
  ExpectSameTransferFunction(dut.tf, StepperMotorTransferFunction(o.motor));
}

// Done-when: for a 0.001 rad step the paper's Nelder-Mead gains give the same
// IAE per unit of step on the nonlinear motor as on eq. (3), within 1 %.
TEST(NonlinearStepperLoop, PapersGainsAgreeWithEquationThreeWithinOnePercentForAMilliradianStep) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  o.reference = 0.001;
  const PidGains nm{20.8836, 26.607, 12.4866};
  Plant linear, motor;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("stepper_motor", StepperMotorParameters{}, &linear)));
  ASSERT_TRUE(IsOk(MakePlant("stepper_nonlinear", StepperMotorParameters{}, &motor)));
  Evaluation lin, dut;
  ASSERT_TRUE(IsOk(Evaluate(linear, nm, o, EvaluateOptions{}, &lin)));
  ASSERT_TRUE(IsOk(Evaluate(motor, nm, o, EvaluateOptions{}, &dut)));
  ASSERT_TRUE(dut.stability.stable);
  EXPECT_NEAR(dut.iae_per_unit, lin.iae_per_unit, 0.01 * lin.iae_per_unit)
      << "nonlinear " << dut.iae_per_unit << " vs eq. (3) " << lin.iae_per_unit;
  EXPECT_TRUE(dut.has_motor);
  EXPECT_FALSE(dut.lost_steps) << dut.motor_note;
  EXPECT_GT(dut.motor.phase_voltage_v, 0.0);
}

TEST(NonlinearStepperLoop, ContinuousLoopIsRefusedForTheNonlinearMotor) {
  Plant motor;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("stepper_nonlinear", StepperMotorParameters{}, &motor)));
  Evaluation ev;
  EXPECT_FALSE(OkInto(Evaluate(motor, {1.0, 1.0, 0.1}, LoopOptions{}, EvaluateOptions{}, &ev), &error));
  EXPECT_NE(error.find("--loop sampled"), std::string::npos) << error;
}

TEST(NonlinearStepperLoop, FastContinuousObjectiveNeverClaimsTheNonlinearMotor) {
  Plant motor;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("stepper_nonlinear", StepperMotorParameters{}, &motor)));
  // Its tf (the linearisation, eq. (3)) alone would be covered; the plant is not.
  EXPECT_TRUE(FastContinuousObjective::Covers(motor.tf, LoopOptions{}, ObjectiveKind::kIae));
  for (const ObjectiveKind kind : {ObjectiveKind::kIae, ObjectiveKind::kIse, ObjectiveKind::kItae})
    EXPECT_FALSE(FastContinuousObjective::CoversPlant(motor, LoopOptions{}, kind));
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  EXPECT_FALSE(FastContinuousObjective::CoversPlant(motor, sampled, ObjectiveKind::kIae));
  Plant linear;
  ASSERT_TRUE(IsOk(MakePlant("stepper_motor", StepperMotorParameters{}, &linear)));
  EXPECT_TRUE(FastContinuousObjective::CoversPlant(linear, LoopOptions{}, ObjectiveKind::kIae));
}

TEST(NonlinearStepperLoop, ObjectiveEvaluatorRunsTheNonlinearMotor) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = 1e-4;
  o.horizon_s = 1.0;
  o.reference = 0.3;
  o.stability_margin = 0.0;
  Plant motor;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("stepper_nonlinear", StepperMotorParameters{}, &motor)));
  const ObjectiveEvaluator dut(motor, o, ObjectiveKind::kIae);
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(motor, {20.8836, 26.607, 12.4866}, o, EvaluateOptions{}, &ev)));
  EXPECT_EQ(dut({20.8836, 26.607, 12.4866}), ev.iae);
}

}  // namespace
}  // namespace pidlab
