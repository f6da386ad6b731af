// The fast continuous-loop objective (fast_objective.h) against the general
// path: Routh-Hurwitz against the eigenvalues, and the objective over many
// random gains, stable and unstable, on the paper's plants and custom ones.

#include "pidlab/evaluation/fast_objective.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
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
using pidlab::evaluation::FastContinuousObjective;
using pidlab::evaluation::GeneralContinuousObjective;
using pidlab::evaluation::IsHurwitz;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::PolynomialStability;
using pidlab::evaluation::PolynomialStabilityTest;
using pidlab::evaluation::RootRadiusBound;
using pidlab::evaluation::ShiftPolynomial;
using pidlab::evaluation::Stability;

namespace pidlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Plant Builtin(const std::string& name) {
  Plant p;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant(name, StepperMotorParameters{}, &p)));
  return p;
}

// Gains log-uniform over [1e-3, 1e3], with ki = 0 or kd = 0 now and then.
PidGains RandomGains(std::mt19937* rng) {
  std::uniform_real_distribution<double> exponent(-3.0, 3.0);
  std::uniform_int_distribution<int> zero(0, 9);
  PidGains g{std::pow(10.0, exponent(*rng)), std::pow(10.0, exponent(*rng)), std::pow(10.0, exponent(*rng))};
  if (zero(*rng) == 0) g.ki = 0.0;
  if (zero(*rng) == 0) g.kd = 0.0;
  return g;
}

using LongMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;

// exp(a) in long double (64-bit mantissa on x86-64): Taylor series to 40
// terms after scaling to norm <= 1/32.
LongMatrix LongExp(const LongMatrix& a) {
  long double norm = 0.0L;
  for (Eigen::Index i = 0; i < a.rows(); ++i) norm = std::max(norm, a.row(i).cwiseAbs().sum());
  const int squarings =
      norm > 0.5L ? static_cast<int>(std::ceil(std::log2(static_cast<double>(norm)))) + 5 : 5;
  const LongMatrix scaled = a * std::ldexp(1.0L, -squarings);
  LongMatrix result = LongMatrix::Identity(a.rows(), a.cols()), term = result;
  for (int k = 1; k <= 40; ++k) {
    term = (term * scaled) / static_cast<long double>(k);
    result += term;
  }
  for (int s = 0; s < squarings; ++s) result = (result * result).eval();
  return result;
}

// The objective of a stable loop in long double, from the same loop matrix:
// how far the general path itself is from its exact value.
double LongObjective(const TransferFunction& tf, const PidGains& g, const LoopOptions& options,
                     ObjectiveKind kind) {
  ContinuousClosedLoop<double> loop;
  EXPECT_TRUE(
      IsOk(BuildContinuousClosedLoop<double>(Realize(tf), g, Disturbance(DisturbanceOptions{}), &loop)));
  const LongMatrix phi =
      LongExp(loop.m.cast<long double>() * static_cast<long double>(options.sample_time_s));
  Eigen::Matrix<long double, Eigen::Dynamic, 1> w = loop.w0.cast<long double>();
  long double sum = 0.0L;
  for (int m = 0; m < options.NumSamples(); ++m) {
    if (m > 0) w = (phi * w).eval();
    long double y = 0.0L;
    for (int i = 0; i < loop.plant_order; ++i) y += static_cast<long double>(loop.c(i)) * w(i);
    const long double e = static_cast<long double>(options.reference) - y;
    sum += kind == ObjectiveKind::kIse    ? e * e
           : kind == ObjectiveKind::kItae ? static_cast<long double>(m * options.sample_time_s) * std::abs(e)
                                          : std::abs(e);
  }
  return static_cast<double>(sum);
}

// Both paths give +inf together, or the same objective to 5e-11 relative
// plus twice the general path's own rounding error (its distance from the
// long double value). The fast path advances the state in blocks of samples
// (fast_objective.cc), which rounds differently; for the paper's gains the
// two agree to 1e-13, over random gains the median difference is 1e-14 and
// the largest 1e-11 (iae) to 3e-9 (itae, where the general path itself is
// off by up to 6e-6), as accurate as the general path against long double.
void ExpectSameObjective(double fast, double general, double exact, const PidGains& g,
                         const std::string& what) {
  SCOPED_TRACE(what + " kp=" + std::to_string(g.kp) + " ki=" + std::to_string(g.ki) +
               " kd=" + std::to_string(g.kd));
  if (std::isinf(general)) {
    EXPECT_EQ(fast, kInf);
  } else {
    ASSERT_TRUE(std::isfinite(fast)) << "general path " << general;
    EXPECT_NEAR(fast, general, 5e-11 * std::abs(general) + 2.0 * std::abs(general - exact))
        << "exact " << exact;
  }
}

std::vector<double> Expand(const std::vector<std::complex<double>>& roots) {
  std::vector<std::complex<double>> p{1.0};
  for (const auto& r : roots) {
    std::vector<std::complex<double>> q(p.size() + 1, 0.0);
    for (std::size_t i = 0; i < p.size(); ++i) {
      q[i] += p[i];
      q[i + 1] -= r * p[i];
    }
    p = q;
  }
  std::vector<double> out;
  for (const auto& c : p) out.push_back(c.real());
  return out;
}

std::vector<double> Multiply(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> out(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

std::vector<double> Add(std::vector<double> a, std::vector<double> b) {
  if (a.size() < b.size()) a.insert(a.begin(), b.size() - a.size(), 0.0);
  if (b.size() < a.size()) b.insert(b.begin(), a.size() - b.size(), 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
  return a;
}

// 1 + D G = 0 with D = kp + ki / s + kd s: s den + (kd s^2 + kp s + ki) num,
// or den + (kd s + kp) num without the integrator's hidden pole at 0.
std::vector<double> LoopPolynomial(const TransferFunction& tf, const PidGains& g) {
  if (g.ki == 0.0) return Add(tf.den, Multiply({g.kd, g.kp}, tf.num));
  return Add(Multiply({1.0, 0.0}, tf.den), Multiply({g.kd, g.kp, g.ki}, tf.num));
}

TEST(IsHurwitz, AcceptsPolynomialsWithEveryRootInTheOpenLeftHalfPlane) {
  const double a[] = {1.0, 3.0, 2.0};  // (s + 1)(s + 2)
  EXPECT_TRUE(IsHurwitz(a, 2));
  const double b[] = {1.0, 3.0, 3.0, 1.0};  // (s + 1)^3
  EXPECT_TRUE(IsHurwitz(b, 3));
  const double c[] = {-2.0, -6.0, -4.0};  // a negative leading coefficient
  EXPECT_TRUE(IsHurwitz(c, 2));
  const std::vector<double> d = Expand({{-1.0, 5.0}, {-1.0, -5.0}, -0.1, -100.0, {-3.0, 1.0}, {-3.0, -1.0}});
  EXPECT_TRUE(IsHurwitz(d.data(), 6));
}

TEST(IsHurwitz, RejectsRootsOnTheAxisOrToTheRight) {
  const double oscillator[] = {1.0, 0.0, 1.0};  // s^2 + 1
  EXPECT_FALSE(IsHurwitz(oscillator, 2));
  const double axis_pair[] = {1.0, 1.0, 1.0, 1.0};  // (s + 1)(s^2 + 1)
  EXPECT_FALSE(IsHurwitz(axis_pair, 3));
  const double origin[] = {1.0, 1.0, 0.0};  // s (s + 1)
  EXPECT_FALSE(IsHurwitz(origin, 2));
  const double right[] = {1.0, -1.0, 1.0};  // roots at 1/2 +- j sqrt(3)/2
  EXPECT_FALSE(IsHurwitz(right, 2));
  const std::vector<double> one_right = Expand({-1.0, -2.0, -3.0, 0.01, -5.0});
  EXPECT_FALSE(IsHurwitz(one_right.data(), 5));
  const double nan[] = {1.0, std::nan(""), 1.0};
  EXPECT_FALSE(IsHurwitz(nan, 2));
  const double zero_lead[] = {0.0, 1.0, 1.0};
  EXPECT_FALSE(IsHurwitz(zero_lead, 2));
}

TEST(ShiftPolynomial, GivesThePolynomialAtAShiftedArgument) {
  std::vector<double> p{2.0, -1.0, 0.5, 3.0, -4.0};
  std::vector<double> q = p;
  const double h = -0.75;
  ShiftPolynomial(h, q.data(), 4);
  auto eval = [](const std::vector<double>& c, double s) {
    double v = 0.0;
    for (double x : c) v = v * s + x;
    return v;
  };
  for (double s : {-2.0, -0.3, 0.0, 1.0, 2.5}) EXPECT_NEAR(eval(q, s), eval(p, s + h), 1e-12);
}

TEST(RootRadiusBound, BoundsEveryRoot) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coefficient(-1e3, 1e3);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> p(6);
    for (double& v : p) v = coefficient(rng);
    const double bound = RootRadiusBound(p.data(), 5);
    for (const auto& r : PolynomialRoots(p)) EXPECT_LE(std::abs(r), bound * (1.0 + 1e-12));
  }
}

TEST(PolynomialStabilityTest, AgreesWithTheEigenvaluesWheneverItDecides) {
  std::mt19937 rng(11);
  int decided = 0, stable = 0;
  for (const char* name : {"double_integrator", "oscillator", "stepper_motor"}) {
    const Plant plant = Builtin(name);
    const StateSpace ss = Realize(plant.tf);
    for (int trial = 0; trial < 500; ++trial) {
      const PidGains g = RandomGains(&rng);
      ContinuousClosedLoop<double> loop;
      ASSERT_TRUE(OkInto(BuildContinuousClosedLoop<double>(ss, g, Disturbance(DisturbanceOptions{}), &loop),
                         nullptr));
      const Stability eig = ContinuousStability(loop, 1e-9);
      const std::vector<double> p = LoopPolynomial(plant.tf, g);
      const PolynomialStability verdict =
          PolynomialStabilityTest(p.data(), static_cast<int>(p.size()) - 1, 1e-9);
      if (verdict == PolynomialStability::kUndecided) continue;
      ++decided;
      stable += eig.stable;
      EXPECT_EQ(verdict == PolynomialStability::kStable, eig.stable)
          << name << " kp=" << g.kp << " ki=" << g.ki << " kd=" << g.kd;
    }
  }
  EXPECT_GT(decided, 1000);  // 1222: the rest have a pole within 1e-6 max(1, rho) of the axis
  EXPECT_GT(stable, 300);
  EXPECT_LT(stable, decided - 300);
}

TEST(PolynomialStabilityTest, LeavesRootsNearTheMarginToTheEigenvalues) {
  // A pair at -1e-8 +- 2j: stable with margin 0, not with 1e-6 or 1e-9 * 2.
  const std::vector<double> p = Expand({{-1e-8, 2.0}, {-1e-8, -2.0}, -3.0});
  EXPECT_EQ(PolynomialStabilityTest(p.data(), 3, 1e-9), PolynomialStability::kUndecided);
  const std::vector<double> q = Expand({{1e-3, 2.0}, {1e-3, -2.0}, -3.0});
  EXPECT_EQ(PolynomialStabilityTest(q.data(), 3, 1e-9), PolynomialStability::kUnstable);
  const std::vector<double> r = Expand({{-1e-3, 2.0}, {-1e-3, -2.0}, -3.0});
  EXPECT_EQ(PolynomialStabilityTest(r.data(), 3, 1e-9), PolynomialStability::kStable);
  // A margin of 0.1 asks Re s < -0.1 |s| = -0.2 for the pair at 2j.
  EXPECT_EQ(PolynomialStabilityTest(r.data(), 3, 0.1), PolynomialStability::kUndecided);
}

TEST(FastContinuousObjective, CoversTheContinuousUndisturbedLoopOfStrictlyProperPlantsUpToOrderSix) {
  const LoopOptions options;
  EXPECT_TRUE(FastContinuousObjective::Covers(Builtin("stepper_motor").tf, options, ObjectiveKind::kIae));
  EXPECT_TRUE(FastContinuousObjective::Covers({{1.0}, {1.0, 1.0}}, options, ObjectiveKind::kItae));
  EXPECT_TRUE(
      FastContinuousObjective::Covers({{1.0}, {1, 6, 15, 20, 15, 6, 1}}, options, ObjectiveKind::kIse));
  EXPECT_FALSE(
      FastContinuousObjective::Covers({{1.0}, {1, 7, 21, 35, 35, 21, 7, 1}}, options, ObjectiveKind::kIae));
  EXPECT_FALSE(FastContinuousObjective::Covers({{1.0, 2.0}, {1.0, 1.0}}, options, ObjectiveKind::kIae));
  EXPECT_FALSE(FastContinuousObjective::Covers({{1.0}, {1.0, 0.0}}, options, ObjectiveKind::kIaeContinuous));
  LoopOptions disturbed;
  disturbed.disturbance.kind = DisturbanceKind::kStep;
  disturbed.disturbance.amplitude = 0.1;
  EXPECT_FALSE(FastContinuousObjective::Covers({{1.0}, {1.0, 0.0}}, disturbed, ObjectiveKind::kIae));
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  EXPECT_FALSE(FastContinuousObjective::Covers({{1.0}, {1.0, 0.0}}, sampled, ObjectiveKind::kIae));
}

// Many random gains per plant and objective: the fast path equals the general
// one (to 1e-12 relative, +inf together), and ObjectiveEvaluator uses it.
void CompareOnRandomGains(const Plant& plant, const LoopOptions& options, int trials, unsigned seed,
                          int* finite_count, int* infinite_count) {
  std::mt19937 rng(seed);
  const StateSpace ss = Realize(plant.tf);
  const Disturbance none(DisturbanceOptions{});
  for (ObjectiveKind kind : {ObjectiveKind::kIae, ObjectiveKind::kIse, ObjectiveKind::kItae}) {
    const ObjectiveEvaluator dut(plant, options, kind);
    ASSERT_TRUE(dut.fast_path()) << plant.tf.ToString();
    for (int trial = 0; trial < trials; ++trial) {
      const PidGains g = RandomGains(&rng);
      const double general = GeneralContinuousObjective(ss, none, options, kind, g);
      const double exact = std::isfinite(general) ? LongObjective(plant.tf, g, options, kind) : general;
      ExpectSameObjective(dut(g), general, exact, g, plant.tf.ToString() + " " + ToString(kind));
      ++*(std::isfinite(general) ? finite_count : infinite_count);
    }
  }
}

TEST(FastContinuousObjective, EqualsTheGeneralPathOnThePapersPlantsOverRandomGains) {
  for (const char* name : {"double_integrator", "oscillator", "stepper_motor"}) {
    int finite = 0, infinite = 0;
    CompareOnRandomGains(Builtin(name), LoopOptions{}, 400, 3, &finite, &infinite);
    EXPECT_GT(finite, 100) << name;
    EXPECT_GT(infinite, 100) << name;
  }
}

TEST(FastContinuousObjective, EqualsTheGeneralPathOnCustomPlantsOfOrderOneToSix) {
  const std::vector<TransferFunction> plants = {
      {{2.0}, {1.0, 0.5}},
      {{1.0, 3.0}, {1.0, 2.0, 0.0}},
      {{1.0}, {1.0, 3.0, 3.0, 1.0}},
      {{0.5, 1.0}, {1.0, 1.0, 4.0, 0.0, 0.0}},
      {{1.0}, {1.0, 5.0, 10.0, 10.0, 5.0, 1.0}},
      {{1.0, 0.0, 2.0}, {1.0, 2.0, 3.0, 4.0, 3.0, 2.0, 1.0}},
      {{0.0, 1.0}, {2.0, 1.0, -1.0}},  // a leading zero and an unstable plant
  };
  int finite = 0, infinite = 0;
  unsigned seed = 5;
  for (const TransferFunction& tf : plants)
    CompareOnRandomGains(Plant{"custom", tf}, LoopOptions{}, 100, ++seed, &finite, &infinite);
  EXPECT_GT(finite, 300);
  EXPECT_GT(infinite, 300);
}

TEST(FastContinuousObjective, EqualsTheGeneralPathWithAMarginHorizonAndSampleTimeOfTheUsersChoice) {
  LoopOptions options;
  options.stability_margin = 0.05;
  options.sample_time_s = 0.01;
  options.horizon_s = 3.0;
  int finite = 0, infinite = 0;
  CompareOnRandomGains(Builtin("stepper_motor"), options, 200, 17, &finite, &infinite);
  CompareOnRandomGains(Builtin("oscillator"), options, 200, 19, &finite, &infinite);
  EXPECT_GT(finite, 100);
  EXPECT_GT(infinite, 100);
}

TEST(FastContinuousObjective, EqualsTheGeneralPathForAReferenceStepOfAnySize) {
  int finite = 0, infinite = 0;
  for (double reference : {0.37, -3.5, 1e3}) {
    LoopOptions options;
    options.reference = reference;
    CompareOnRandomGains(Builtin("stepper_motor"), options, 100, 23, &finite, &infinite);
    CompareOnRandomGains(Builtin("double_integrator"), options, 100, 29, &finite, &infinite);
  }
  EXPECT_GT(finite, 300);
  EXPECT_GT(infinite, 300);
}

// Gains on a ray kp = ki = kd = t cross the stability boundary at t*; just
// inside, just outside and on it, the verdict and the value are the general
// path's (the polynomial test leaves these to the eigenvalues).
TEST(FastContinuousObjective, EqualsTheGeneralPathAtTheStabilityBoundary) {
  const Plant plant{"custom",
                    {{1.0}, {1.0, 1.0, 1.0, 0.0}}};  // 1/(s (s^2 + s + 1)): unstable for large gains
  const StateSpace ss = Realize(plant.tf);
  const Disturbance none(DisturbanceOptions{});
  const LoopOptions options;
  const ObjectiveEvaluator dut(plant, options, ObjectiveKind::kIae);
  ASSERT_TRUE(dut.fast_path());
  auto general = [&](double t) {
    return GeneralContinuousObjective(ss, none, options, ObjectiveKind::kIae, PidGains{t, 0.2 * t, 0.0});
  };
  double lo = 1e-3, hi = 10.0;
  ASSERT_TRUE(std::isfinite(general(lo)));
  ASSERT_TRUE(std::isinf(general(hi)));
  for (int i = 0; i < 200 && hi - lo > 0.0; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (std::isfinite(general(mid)) ? lo : hi) = mid;
  }
  for (double t : {lo, hi, lo * (1 - 1e-12), hi * (1 + 1e-12), lo * (1 - 1e-8), hi * (1 + 1e-8),
                   lo * (1 - 1e-4), hi * (1 + 1e-4)}) {
    const PidGains g{t, 0.2 * t, 0.0};
    const double exact =
        std::isfinite(general(t)) ? LongObjective(plant.tf, g, options, ObjectiveKind::kIae) : kInf;
    ExpectSameObjective(dut(g), general(t), exact, g, "boundary");
  }
}

TEST(ObjectiveEvaluator, FallsBackToTheGeneralPathForWhatTheFastPathDoesNotCover) {
  const Plant plant = Builtin("double_integrator");
  const PidGains g{29.6558, 0.4977, 28.3216};
  LoopOptions disturbed;
  disturbed.disturbance.kind = DisturbanceKind::kStep;
  disturbed.disturbance.amplitude = 0.1;
  disturbed.disturbance.step_time_s = 5.0;
  const ObjectiveEvaluator with_disturbance(plant, disturbed, ObjectiveKind::kIae);
  EXPECT_FALSE(with_disturbance.fast_path());
  EXPECT_EQ(with_disturbance(g),
            GeneralContinuousObjective(Realize(plant.tf), Disturbance(disturbed.disturbance), disturbed,
                                       ObjectiveKind::kIae, g));
  const ObjectiveEvaluator continuous_integral(plant, LoopOptions{}, ObjectiveKind::kIaeContinuous);
  EXPECT_FALSE(continuous_integral.fast_path());
  LoopOptions sampled;
  sampled.loop = LoopKind::kSampled;
  EXPECT_FALSE(ObjectiveEvaluator(plant, sampled, ObjectiveKind::kIae).fast_path());
  const Plant seventh{"custom", {{1.0}, {1, 7, 21, 35, 35, 21, 7, 1}}};
  const ObjectiveEvaluator high_order(seventh, LoopOptions{}, ObjectiveKind::kIae);
  EXPECT_FALSE(high_order.fast_path());
  const PidGains h{1.0, 0.1, 0.5};
  EXPECT_EQ(high_order(h), GeneralContinuousObjective(Realize(seventh.tf), Disturbance(DisturbanceOptions{}),
                                                      LoopOptions{}, ObjectiveKind::kIae, h));
}

TEST(ObjectiveEvaluator, FastPathGivesThePapersObjectiveForItsNelderMeadGains) {
  struct Case {
    const char* plant;
    PidGains gains;
  };
  for (const Case& c :
       {Case{"double_integrator", {29.6558, 0.4977, 28.3216}}, Case{"oscillator", {0.0774, 14.7575, 14.9913}},
        Case{"stepper_motor", {20.8836, 26.607, 12.4866}}}) {
    const Plant plant = Builtin(c.plant);
    const ObjectiveEvaluator dut(plant, LoopOptions{}, ObjectiveKind::kIae);
    ASSERT_TRUE(dut.fast_path());
    Evaluation ev;
    std::string error;
    ASSERT_TRUE(IsOk(Evaluate(plant, c.gains, LoopOptions{}, EvaluateOptions{}, &ev)));
    EXPECT_NEAR(dut(c.gains), ev.iae, 1e-13 * ev.iae) << c.plant;
  }
}

}  // namespace
}  // namespace pidlab
