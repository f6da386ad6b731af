// Transfer functions, their realisation, the built-in plants, the matrix
// exponential and the exact ZOH discretisation, against closed forms.

#include "pidlab/plant_sim/transfer_function.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/plant_sim/matrix_exp.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/plant_sim/polynomial.h"
#include "test_status.h"

namespace pidlab {
namespace {

using Complex = std::complex<double>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// p(s) by Horner, descending powers.
Complex Poly(const std::vector<double>& p, Complex s) {
  Complex v = 0.0;
  for (double c : p) v = v * s + c;
  return v;
}

Complex TfAt(const TransferFunction& tf, Complex s) { return Poly(tf.num, s) / Poly(tf.den, s); }

// C (sI - A)^-1 B + D.
Complex StateSpaceAt(const StateSpace& ss, Complex s) {
  const int n = ss.order();
  if (n == 0) return ss.d;
  const Eigen::MatrixXcd m = s * Eigen::MatrixXcd::Identity(n, n) - ss.a.cast<Complex>();
  const Eigen::VectorXcd x = m.fullPivLu().solve(ss.b.cast<Complex>());
  return (ss.c.cast<Complex>() * x)(0) + ss.d;
}

void ExpectRealizationMatches(const TransferFunction& tf, const std::vector<Complex>& points) {
  const StateSpace dut = Realize(tf);
  for (const Complex& s : points) {
    const Complex expected = TfAt(tf, s);
    const Complex actual = StateSpaceAt(dut, s);
    EXPECT_LE(std::abs(actual - expected), 1e-10 * std::abs(expected))
        << tf.ToString() << " at s = " << s << ": " << actual << " vs " << expected;
  }
}

const std::vector<Complex> kPoints = {{0.3, 1.0}, {-2.0, 5.0}, {0.0, 10.0}, {1000.0, 100.0}, {-0.5, -0.7}};

TEST(Realize, GivesTheSameTransferFunctionForTheDoubleIntegrator) {
  ExpectRealizationMatches({{1.0}, {1.0, 0.0, 0.0}}, kPoints);
}

TEST(Realize, GivesTheSameTransferFunctionForTheOscillator) {
  ExpectRealizationMatches({{1.0}, {1.0, 0.0, 1.0}}, kPoints);
}

TEST(Realize, GivesTheSameTransferFunctionForAThirdOrderPlantWithZeros) {
  ExpectRealizationMatches({{2.0, -3.0, 5.0}, {4.0, 4.0, 5.0, 6.0}}, kPoints);
}

TEST(Realize, GivesTheSameTransferFunctionForABiproperPlantWithFeedthrough) {
  const TransferFunction tf{{2.0, 1.0}, {1.0, 3.0}};
  ExpectRealizationMatches(tf, kPoints);
  EXPECT_DOUBLE_EQ(Realize(tf).d, 2.0);
}

TEST(Realize, IgnoresLeadingZeroCoefficients) {
  ExpectRealizationMatches({{0.0, 0.0, 1.0}, {0.0, 2.0, 3.0, 1.0}}, kPoints);
  EXPECT_EQ(Realize({{0.0, 0.0, 1.0}, {0.0, 2.0, 3.0, 1.0}}).order(), 2);
}

TEST(Realize, GivesTheSameTransferFunctionForTheBadlyScaledStepperMotor) {
  const TransferFunction tf = StepperMotorTransferFunction(StepperMotorParameters{});
  // Points around both the slow mechanical poles and the electrical pole near -6600 rad/s.
  ExpectRealizationMatches(tf, {{1.0, 1.0},
                                {0.0, 25.0},
                                {-10.0, 30.0},
                                {0.0, 300.0},
                                {-6000.0, 500.0},
                                {0.0, 6600.0},
                                {1e5, 1e4},
                                {-0.01, 0.0}});
}

TEST(Realize, ThrowsForAnInvalidTransferFunction) {
  EXPECT_THROW(Realize({{1.0}, {}}), std::invalid_argument);
  EXPECT_THROW(Realize({{1.0}, {1.0, kNaN}}), std::invalid_argument);
}

TEST(TransferFunction, AcceptsAProperTransferFunction) {
  const TransferFunction dut{{1.0, 2.0}, {1.0, 3.0, 2.0}};
  std::string error;
  EXPECT_TRUE(dut.IsValid(&error)) << error;
  EXPECT_EQ(dut.RelativeDegree(), 1);
  EXPECT_DOUBLE_EQ(dut.DcGain(), 1.0);
}

TEST(TransferFunction, RejectsAnEmptyDenominator) {
  const TransferFunction dut{{1.0}, {}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("denominator"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsAnEmptyNumerator) {
  const TransferFunction dut{{}, {1.0, 1.0}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("numerator"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsANanNumeratorCoefficientNamingIt) {
  const TransferFunction dut{{1.0, kNaN}, {1.0, 1.0, 1.0}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("nan"), std::string::npos) << error;
  EXPECT_NE(error.find("numerator"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsAnInfiniteDenominatorCoefficientNamingIt) {
  const TransferFunction dut{{1.0}, {1.0, kInf}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("inf"), std::string::npos) << error;
  EXPECT_NE(error.find("denominator"), std::string::npos) << error;
}

TEST(TransferFunction, AcceptsAtMostSixtyFourCoefficients) {
  std::string error;
  const std::vector<double> ones(kMaxTransferFunctionCoefficients, 1.0);
  EXPECT_TRUE((TransferFunction{{1.0}, ones}.IsValid(&error))) << error;
  std::vector<double> too_many = ones;
  too_many.push_back(1.0);
  EXPECT_FALSE((TransferFunction{{1.0}, too_many}.IsValid(&error)));
  EXPECT_NE(error.find("denominator has 65 coefficients, more than 64"), std::string::npos) << error;
  EXPECT_FALSE((TransferFunction{too_many, too_many}.IsValid(&error)));
  EXPECT_NE(error.find("numerator has 65"), std::string::npos) << error;
  EXPECT_FALSE((TransferFunction{{1.0}, std::vector<double>(20000, 1.0)}.IsValid(&error)));
  EXPECT_NE(error.find("20000"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsCoefficientsBeyondTheMagnitudeLimitsNamingThem) {
  std::string error;
  EXPECT_TRUE((TransferFunction{{1e12}, {1e-12, 0.0, -1e12}}.IsValid(&error))) << error;
  EXPECT_FALSE((TransferFunction{{1.0}, {1.0, 1e13, 1.0}}.IsValid(&error)));
  EXPECT_NE(error.find("denominator coefficient 1e+13"), std::string::npos) << error;
  EXPECT_FALSE((TransferFunction{{-1e308}, {1.0, 1.0}}.IsValid(&error)));
  EXPECT_NE(error.find("numerator coefficient -1e+308"), std::string::npos) << error;
  // A tiny leading coefficient would overflow the realisation (1e12 / 1e-300).
  EXPECT_FALSE((TransferFunction{{1.0}, {1e-300, 1e12, 1.0}}.IsValid(&error)));
  EXPECT_NE(error.find("1e-300"), std::string::npos) << error;
}

TEST(BalanceInPlace, TerminatesOnAMatrixWithInfiniteEntries) {
  // Row 1 has an infinite column norm against a finite row norm: halving inf
  // never balanced it, and this call spun forever.
  Eigen::MatrixXd a(2, 2);
  a << 0.0, kInf, 1.0, 0.0;
  BalanceInPlace(&a);
  Eigen::MatrixXd b = Eigen::MatrixXd::Constant(3, 3, kNaN);
  BalanceInPlace(&b);
  Eigen::MatrixXd c(3, 3);
  c << 1e308, 1e308, 1e308, 1e-308, 0.0, kInf, 1.0, -kInf, 1.0;
  const Eigen::VectorXd d = BalanceInPlace(&c);
  EXPECT_EQ(d.size(), 3);
}

TEST(MatrixExp, ReturnsOnAnInfiniteMatrix) {
  Eigen::MatrixXd a(2, 2);
  a << 0.0, kInf, 1.0, 0.0;
  const Eigen::MatrixXd e = MatrixExp<double>(a);
  EXPECT_FALSE(e.allFinite());
}

TEST(MakePlant, RejectsStepperParametersWhoseCoefficientsAreOutOfRange) {
  StepperMotorParameters p;
  p.inertia_kg_m2 = 1e-300;
  Plant plant;
  std::string error;
  EXPECT_FALSE(OkInto(MakePlant("stepper", p, &plant), &error));
  EXPECT_NE(error.find("stepper motor parameters"), std::string::npos) << error;
  p = StepperMotorParameters{};
  p.rotor_teeth = 1e13;
  EXPECT_FALSE(OkInto(MakePlant("stepper", p, &plant), &error));
  EXPECT_NE(error.find("rotor_teeth"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsAnImproperTransferFunctionNamingTheDegrees) {
  const TransferFunction dut{{1.0, 0.0, 0.0, 1.0}, {1.0, 2.0, 1.0}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("improper"), std::string::npos) << error;
  EXPECT_NE(error.find("3"), std::string::npos) << error;
  EXPECT_NE(error.find("2"), std::string::npos) << error;
}

TEST(TransferFunction, RejectsAZeroDenominator) {
  const TransferFunction dut{{1.0}, {0.0, 0.0}};
  std::string error;
  EXPECT_FALSE(dut.IsValid(&error));
  EXPECT_NE(error.find("zero"), std::string::npos) << error;
}

TEST(PolynomialRoots, FindsTheRootsOfAFactoredCubic) {
  // (s + 1)(s + 2)(s + 3) = s^3 + 6 s^2 + 11 s + 6.
  auto dut = PolynomialRoots({1.0, 6.0, 11.0, 6.0});
  ASSERT_EQ(dut.size(), 3u);
  std::vector<double> re;
  for (const auto& r : dut) {
    EXPECT_NEAR(r.imag(), 0.0, 1e-12);
    re.push_back(r.real());
  }
  std::sort(re.begin(), re.end());
  EXPECT_NEAR(re[0], -3.0, 1e-12);
  EXPECT_NEAR(re[1], -2.0, 1e-12);
  EXPECT_NEAR(re[2], -1.0, 1e-12);
}

TEST(StepperMotor, CoefficientsFollowEquationThreeFromTableOne) {
  // Table I by hand.
  const double r = 33.0, l = 5.4e-3, m = 0.4e-3, j = 0.16e-4, nr = 6.0, d = 1.35e-5, lambda = M_PI / 12.0,
               io = 0.15, flux = 1.2e-3;
  const double lp = l - m;                // 5.0e-3
  const double half = nr * lambda / 2.0;  // pi / 4
  const double wnp2 = 2.0 * nr * nr * flux * io * std::cos(half) / j;
  const double kp = flux * std::sin(half) * std::sin(half) / (lp * io * std::cos(half));
  // Spot check of the hand computation: wnp2 = 810 cos(pi/4), kp = 0.8 sqrt(2).
  EXPECT_NEAR(wnp2, 810.0 * std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(kp, 0.8 * std::sqrt(2.0), 1e-12);
  const std::vector<double> num = {r / l * wnp2};
  const std::vector<double> den = {1.0, r / lp + d / j, r * d / (lp * j) + wnp2 * (1.0 + kp), r / lp * wnp2};

  const TransferFunction dut = StepperMotorTransferFunction(StepperMotorParameters{});
  ASSERT_EQ(dut.num.size(), num.size());
  ASSERT_EQ(dut.den.size(), den.size());
  for (std::size_t i = 0; i < num.size(); ++i) EXPECT_NEAR(dut.num[i], num[i], 1e-12 * std::abs(num[i]));
  for (std::size_t i = 0; i < den.size(); ++i) EXPECT_NEAR(dut.den[i], den[i], 1e-12 * std::abs(den[i]));
}

TEST(StepperMotor, HasAnElectricalPoleNearMinus6600) {
  const TransferFunction tf = StepperMotorTransferFunction(StepperMotorParameters{});
  double fastest = 0.0;
  for (const auto& p : PolynomialRoots(tf.den)) fastest = std::min(fastest, p.real());
  EXPECT_NEAR(fastest, -6600.0, 100.0);
}

TEST(StepperMotor, OverriddenParameterChangesTheModel) {
  StepperMotorParameters p;
  p.resistance_ohm = 66.0;
  const TransferFunction base = StepperMotorTransferFunction(StepperMotorParameters{});
  const TransferFunction dut = StepperMotorTransferFunction(p);
  EXPECT_NEAR(dut.num[0], 2.0 * base.num[0], 1e-12 * base.num[0]);
  EXPECT_NEAR(dut.den[3], 2.0 * base.den[3], 1e-12 * base.den[3]);
}

TEST(StepperMotor, RejectsAnInductanceBelowTheMutualInductance) {
  StepperMotorParameters p;
  p.self_inductance_h = 0.3e-3;
  std::string error;
  EXPECT_FALSE(p.IsValid(&error));
  EXPECT_NE(error.find("self_inductance_h"), std::string::npos) << error;
  EXPECT_THROW(StepperMotorTransferFunction(p), std::invalid_argument);
}

TEST(StepperMotor, RejectsANegativeResistanceNamingIt) {
  StepperMotorParameters p;
  p.resistance_ohm = -1.0;
  std::string error;
  EXPECT_FALSE(p.IsValid(&error));
  EXPECT_NE(error.find("resistance_ohm"), std::string::npos) << error;
  EXPECT_NE(error.find("-1"), std::string::npos) << error;
}

void ExpectSameTf(const TransferFunction& a, const TransferFunction& b) {
  EXPECT_EQ(a.num, b.num);
  EXPECT_EQ(a.den, b.den);
}

TEST(MakePlant, LinearIsTheDoubleIntegrator) {
  Plant dut, alias;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &dut)));
  ASSERT_TRUE(IsOk(MakePlant("linear", StepperMotorParameters{}, &alias)));
  EXPECT_EQ(dut.name, "double_integrator");
  EXPECT_EQ(alias.name, "double_integrator");
  ExpectSameTf(dut.tf, {{1.0}, {1.0, 0.0, 0.0}});
  ExpectSameTf(alias.tf, dut.tf);
}

TEST(MakePlant, NonlinearIsTheOscillator) {
  Plant dut, alias;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("oscillator", StepperMotorParameters{}, &dut)));
  ASSERT_TRUE(IsOk(MakePlant("nonlinear", StepperMotorParameters{}, &alias)));
  EXPECT_EQ(dut.name, "oscillator");
  EXPECT_EQ(alias.name, "oscillator");
  ExpectSameTf(dut.tf, {{1.0}, {1.0, 0.0, 1.0}});
  ExpectSameTf(alias.tf, dut.tf);
}

TEST(MakePlant, StepperIsTheStepperMotor) {
  Plant dut, alias;
  std::string error;
  ASSERT_TRUE(IsOk(MakePlant("stepper_motor", StepperMotorParameters{}, &dut)));
  ASSERT_TRUE(IsOk(MakePlant("stepper", StepperMotorParameters{}, &alias)));
  EXPECT_EQ(dut.name, "stepper_motor");
  EXPECT_EQ(alias.name, "stepper_motor");
  ExpectSameTf(dut.tf, StepperMotorTransferFunction(StepperMotorParameters{}));
  ExpectSameTf(alias.tf, dut.tf);
}

TEST(MakePlant, RejectsAnUnknownNameNamingIt) {
  Plant dut;
  std::string error;
  EXPECT_FALSE(OkInto(MakePlant("triple_integrator", StepperMotorParameters{}, &dut), &error));
  EXPECT_NE(error.find("triple_integrator"), std::string::npos) << error;
}

TEST(MakeCustomPlant, AcceptsAStrictlyProperPlant) {
  Plant dut;
  std::string error;
  ASSERT_TRUE(IsOk(MakeCustomPlant({1.0, 2.0}, {1.0, 3.0, 2.0}, &dut)));
  EXPECT_EQ(dut.name, "custom");
  ExpectSameTf(dut.tf, {{1.0, 2.0}, {1.0, 3.0, 2.0}});
}

TEST(MakeCustomPlant, RejectsABiproperPlant) {
  Plant dut;
  std::string error;
  EXPECT_FALSE(OkInto(MakeCustomPlant({1.0, 2.0}, {1.0, 3.0}, &dut), &error));
  EXPECT_NE(error.find("strictly proper"), std::string::npos) << error;
}

TEST(MakeCustomPlant, RejectsANanCoefficient) {
  Plant dut;
  std::string error;
  EXPECT_FALSE(OkInto(MakeCustomPlant({kNaN}, {1.0, 3.0}, &dut), &error));
  EXPECT_NE(error.find("nan"), std::string::npos) << error;
}

// ---- Matrix exponential and ZOH ----

TEST(MatrixExp, OfADiagonalMatrixIsTheExponentialOfTheDiagonal) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3, 3);
  a.diagonal() << -3.0, 2.5, -50.0;
  const Eigen::MatrixXd dut = MatrixExp<double>(a);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double expected = i == j ? std::exp(a(i, i)) : 0.0;
      EXPECT_NEAR(dut(i, j), expected, 1e-13 * std::max(1.0, std::abs(expected))) << i << "," << j;
    }
}

TEST(MatrixExp, OfARotationGeneratorIsARotation) {
  for (double w : {0.1, 1.0, 7.0, 40.0}) {
    Eigen::MatrixXd a(2, 2);
    a << 0.0, w, -w, 0.0;
    const Eigen::MatrixXd dut = MatrixExp<double>(a);
    EXPECT_NEAR(dut(0, 0), std::cos(w), 1e-12) << w;
    EXPECT_NEAR(dut(0, 1), std::sin(w), 1e-12) << w;
    EXPECT_NEAR(dut(1, 0), -std::sin(w), 1e-12) << w;
    EXPECT_NEAR(dut(1, 1), std::cos(w), 1e-12) << w;
  }
}

TEST(MatrixExp, OfANilpotentMatrixIsAFinitePolynomial) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3, 3);
  a(0, 1) = 2.0;
  a(1, 2) = 3.0;
  // a^2 has the single entry (0, 2) = 6; exp(a) = I + a + a^2 / 2.
  Eigen::MatrixXd expected = Eigen::MatrixXd::Identity(3, 3);
  expected(0, 1) = 2.0;
  expected(1, 2) = 3.0;
  expected(0, 2) = 3.0;
  const Eigen::MatrixXd dut = MatrixExp<double>(a);
  EXPECT_LE((dut - expected).cwiseAbs().maxCoeff(), 1e-14) << dut;
}

TEST(MatrixExp, OfZeroIsTheIdentity) {
  const Eigen::MatrixXd dut = MatrixExp<double>(Eigen::MatrixXd::Zero(4, 4));
  EXPECT_EQ(dut, Eigen::MatrixXd::Identity(4, 4));
}

TEST(ZeroOrderHold, OfAChainOfIntegratorsMatchesTheClosedForm) {
  // x1' = u, x2' = x1: phi = [[1, 0], [h, 1]], gamma = [h, h^2 / 2].
  const double h = 0.25;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2, 2);
  a(1, 0) = 1.0;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(2, 1);
  b(0, 0) = 1.0;
  Eigen::MatrixXd phi, gamma;
  ZeroOrderHold<double>(a, b, h, &phi, &gamma);
  EXPECT_NEAR(phi(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(phi(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(phi(1, 0), h, 1e-15);
  EXPECT_NEAR(phi(1, 1), 1.0, 1e-15);
  EXPECT_NEAR(gamma(0, 0), h, 1e-15);
  EXPECT_NEAR(gamma(1, 0), h * h / 2.0, 1e-15);
}

TEST(DiscretePlant, DoubleIntegratorStepResponseIsTheSampledParabola) {
  const double h = 0.1;
  DiscretePlant dut({{1.0}, {1.0, 0.0, 0.0}}, h);
  for (int k = 0; k <= 100; ++k) {
    const double t = k * h;
    EXPECT_NEAR(dut.Output(), t * t / 2.0, 1e-12 * std::max(1.0, t * t)) << "k = " << k;
    dut.Step(1.0);
  }
}

TEST(DiscretePlant, FirstOrderLagFollowsTheExactRecursion) {
  const double a = 3.0, h = 0.02;
  DiscretePlant dut({{1.0}, {1.0, a}}, h);
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> input(-2.0, 2.0);
  double y = 0.0;
  for (int k = 0; k < 500; ++k) {
    EXPECT_NEAR(dut.Output(), y, 1e-12) << "k = " << k;
    const double u = input(rng);
    dut.Step(u);
    y = std::exp(-a * h) * y + (1.0 - std::exp(-a * h)) / a * u;
  }
}

TEST(DiscretePlant, ResetReturnsToRest) {
  DiscretePlant dut({{1.0}, {1.0, 1.0}}, 0.1);
  dut.Step(1.0);
  ASSERT_NE(dut.Output(), 0.0);
  dut.Reset();
  EXPECT_EQ(dut.Output(), 0.0);
}

TEST(DiscretePlant, RejectsABiproperPlant) {
  EXPECT_THROW(DiscretePlant({{1.0, 0.0}, {1.0, 1.0}}, 0.1), std::invalid_argument);
}

TEST(DiscretePlant, RejectsAZeroStep) {
  EXPECT_THROW(DiscretePlant({{1.0}, {1.0, 1.0}}, 0.0), std::invalid_argument);
}

TEST(DiscretePlant, RejectsANegativeStep) {
  EXPECT_THROW(DiscretePlant({{1.0}, {1.0, 1.0}}, -0.1), std::invalid_argument);
}

TEST(DiscretePlant, RejectsAnInvalidTransferFunction) {
  EXPECT_THROW(DiscretePlant({{1.0}, {1.0, kNaN}}, 0.1), std::invalid_argument);
}

}  // namespace
TEST(Polynomial, ProductOfLagsExpandsTheFactors) {
  // (2s + 1)(s + 1)(0.5s + 1) = s^3 + 3.5 s^2 + 3.5 s + 1.
  EXPECT_EQ(LagProduct({2.0, 1.0, 0.5}), (std::vector<double>{1.0, 3.5, 3.5, 1.0}));
  EXPECT_EQ(LagProduct({}), (std::vector<double>{1.0}));
  EXPECT_EQ(PolynomialProduct({1.0, -2.0}, {1.0, 2.0}), (std::vector<double>{1.0, 0.0, -4.0}));
  EXPECT_TRUE(PolynomialProduct({}, {1.0}).empty());
}

}  // namespace pidlab
