#include "pidlab/optim/pso_gsa.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

using pidlab::optim::Bounds;
using pidlab::optim::OptimizerSummary;
using pidlab::optim::PsoGsa;
using pidlab::optim::PsoGsaInertia;
using pidlab::optim::PsoGsaOptions;
using pidlab::optim::TerminationType;
using pidlab::optim::TracePoint;

namespace pidlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kPi = std::acos(-1.0);

Bounds Cube(int n, double lo, double hi) {
  return Bounds{Eigen::VectorXd::Constant(n, lo), Eigen::VectorXd::Constant(n, hi)};
}

double ShiftedSphere(const Eigen::VectorXd& x) { return (x.array() - 0.3).square().sum(); }

double Rosenbrock(const Eigen::VectorXd& x) {
  return (1.0 - x[0]) * (1.0 - x[0]) + 100.0 * (x[1] - x[0] * x[0]) * (x[1] - x[0] * x[0]);
}

double Rastrigin(const Eigen::VectorXd& x) {
  double f = 10.0 * static_cast<double>(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) f += x[i] * x[i] - 10.0 * std::cos(2.0 * kPi * x[i]);
  return f;
}

bool Inside(const Eigen::VectorXd& x, const Bounds& b) {
  return (x.array() >= b.lower.array()).all() && (x.array() <= b.upper.array()).all();
}

TEST(PsoGsa, FindsTheMinimumOfAShiftedSphereInThreeDimensions) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    PsoGsaOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    PsoGsa(ShiftedSphere, Cube(3, -5.0, 5.0), options, &summary);

    EXPECT_EQ(summary.termination, TerminationType::kMaxIterations) << summary.BriefReport();
    EXPECT_LT(summary.f, 1e-10) << "seed " << seed;
    EXPECT_LT((summary.x.array() - 0.3).abs().maxCoeff(), 1e-5) << "seed " << seed;
  }
}

TEST(PsoGsa, FindsTheRosenbrockMinimumInTwoDimensions) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    PsoGsaOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    PsoGsa(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);

    EXPECT_LT(summary.f, 1e-3) << "seed " << seed;
    EXPECT_LT((summary.x.array() - 1.0).abs().maxCoeff(), 0.05) << "seed " << seed;
  }
}

TEST(PsoGsa, FindsTheGlobalMinimumOfRastriginWithLinearlyDecreasingInertia) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    PsoGsaOptions options;
    options.seed = seed;
    options.inertia = PsoGsaInertia::kLinearDecreasing;
    OptimizerSummary summary;
    PsoGsa(Rastrigin, Cube(2, -5.12, 5.12), options, &summary);
    EXPECT_LT(summary.f, 1e-8) << "seed " << seed;
  }
}

TEST(PsoGsa, FindsTheGlobalMinimumOfRastriginFromMostSeedsWithRandomInertia) {
  // With the original random inertia and only a gBest term the swarm sometimes collapses
  // prematurely; then it sits in a neighbouring local minimum (f = 0.995).
  int global = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    PsoGsaOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    PsoGsa(Rastrigin, Cube(2, -5.12, 5.12), options, &summary);
    global += summary.f < 1e-8 ? 1 : 0;
    EXPECT_LT(summary.f, 1.0) << "seed " << seed;
  }
  EXPECT_GE(global, 5);
}

TEST(PsoGsa, EvaluatesTheSwarmOnceAtTheStartAndOncePerIteration) {
  PsoGsaOptions options;
  options.population_size = 12;
  options.max_iterations = 17;
  std::vector<int> evaluations;
  OptimizerSummary summary;
  PsoGsa(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary,
         [&evaluations](const TracePoint& point) { evaluations.push_back(point.evaluations); });
  EXPECT_EQ(summary.evaluations, 12 * (17 + 1));
  EXPECT_EQ(summary.iterations, 17);
  ASSERT_EQ(evaluations.size(), 17u);
  EXPECT_EQ(evaluations.front(), 24);
}

TEST(PsoGsa, EvaluatesOnlyPointsInsideTheBounds) {
  // The minimum (0.3, 0.3, 0.3) lies outside [-1, 0]^3, at its upper corner.
  const Bounds bounds = Cube(3, -1.0, 0.0);
  int outside = 0;
  auto f = [&](const Eigen::VectorXd& x) {
    outside += Inside(x, bounds) ? 0 : 1;
    return ShiftedSphere(x);
  };
  OptimizerSummary summary;
  PsoGsa(f, bounds, PsoGsaOptions(), &summary);
  EXPECT_EQ(outside, 0);
  EXPECT_TRUE(Inside(summary.x, bounds));
  EXPECT_LT(summary.x.cwiseAbs().maxCoeff(), 1e-6);
}

TEST(PsoGsa, NeverReturnsARejectedAgent) {
  // Rejected wherever x0 > 0: the unconstrained minimum (0.3, 0.3) is rejected, the answer is (0, 0.3).
  auto f = [](const Eigen::VectorXd& x) { return x[0] > 0.0 ? kInf : ShiftedSphere(x); };
  OptimizerSummary summary;
  PsoGsa(f, Cube(2, -1.0, 1.0), PsoGsaOptions(), &summary);

  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  EXPECT_GT(summary.rejected_evaluations, 0);
  EXPECT_LE(summary.x[0], 0.0);
  EXPECT_NEAR(summary.x[0], 0.0, 1e-3);
  EXPECT_NEAR(summary.x[1], 0.3, 1e-3);
}

TEST(PsoGsa, SearchesRandomlyUntilItFindsASmallFeasibleRegion) {
  // 0.25% of the box is feasible, so the initial swarm of 30 most likely has no feasible agent.
  int calls_before_first_feasible = -1, calls = 0;
  auto f = [&](const Eigen::VectorXd& x) {
    ++calls;
    if (!(x.array() >= 0.95).all()) return kInf;
    if (calls_before_first_feasible < 0) calls_before_first_feasible = calls - 1;
    return (x.array() - 0.97).square().sum();
  };
  OptimizerSummary summary;
  PsoGsa(f, Cube(2, 0.0, 1.0), PsoGsaOptions(), &summary);
  ASSERT_GT(calls_before_first_feasible, 30);  // Precondition: the initial swarm had none.
  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  EXPECT_LT((summary.x.array() - 0.97).abs().maxCoeff(), 1e-6);
}

TEST(PsoGsa, EndsWithNoFeasiblePointWhenEveryPointIsRejected) {
  auto f = [](const Eigen::VectorXd&) { return std::numeric_limits<double>::quiet_NaN(); };
  PsoGsaOptions options;
  options.max_iterations = 5;
  OptimizerSummary summary;
  PsoGsa(f, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
  EXPECT_FALSE(summary.IsUsable());
  EXPECT_EQ(summary.evaluations, 30 * 6);
  EXPECT_EQ(summary.rejected_evaluations, summary.evaluations);
}

TEST(PsoGsa, GivesBitIdenticalResultsForTheSameSeed) {
  PsoGsaOptions options;
  options.seed = 99;
  OptimizerSummary a, b, c;
  PsoGsa(Rastrigin, Cube(2, -5.12, 5.12), options, &a);
  PsoGsa(Rastrigin, Cube(2, -5.12, 5.12), options, &b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.f, b.f);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  for (std::size_t i = 0; i < a.trace.size(); ++i) EXPECT_EQ(a.trace[i].best_x, b.trace[i].best_x);

  options.seed = 100;
  PsoGsa(Rastrigin, Cube(2, -5.12, 5.12), options, &c);
  EXPECT_NE(a.trace.front().best_x, c.trace.front().best_x);
}

TEST(PsoGsa, StopsExactlyAtTheEvaluationBudget) {
  PsoGsaOptions options;
  options.max_evaluations = 75;
  OptimizerSummary summary;
  PsoGsa(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kMaxEvaluations);
  EXPECT_EQ(summary.evaluations, 75);
  EXPECT_EQ(summary.iterations, 1);  // 30 + 30 fit, the next 30 do not.
  EXPECT_TRUE(summary.IsUsable());
}

void ExpectInvalid(const PsoGsaOptions& options, const std::string& field) {
  int calls = 0;
  auto f = [&calls](const Eigen::VectorXd& x) {
    ++calls;
    return x.squaredNorm();
  };
  OptimizerSummary summary;
  PsoGsa(f, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find(field), std::string::npos) << summary.message;
  EXPECT_EQ(calls, 0);
}

TEST(PsoGsa, RejectsASwarmOfOne) {
  PsoGsaOptions options;
  options.population_size = 1;
  ExpectInvalid(options, "PsoGsaOptions.population_size = 1");
}

TEST(PsoGsa, RejectsZeroIterations) {
  PsoGsaOptions options;
  options.max_iterations = 0;
  ExpectInvalid(options, "max_iterations = 0");
}

TEST(PsoGsa, RejectsANegativeEvaluationBudget) {
  PsoGsaOptions options;
  options.max_evaluations = -10;
  ExpectInvalid(options, "max_evaluations = -10");
}

TEST(PsoGsa, RejectsAZeroGravitationalConstant) {
  PsoGsaOptions options;
  options.g0 = 0.0;
  ExpectInvalid(options, "g0 = 0");
}

TEST(PsoGsa, RejectsANanDecayRate) {
  PsoGsaOptions options;
  options.alpha = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(options, "alpha");
}

TEST(PsoGsa, RejectsANegativeGravityWeight) {
  PsoGsaOptions options;
  options.c1 = -0.5;
  ExpectInvalid(options, "c1 = -0.5");
}

TEST(PsoGsa, RejectsAnInfiniteSocialWeight) {
  PsoGsaOptions options;
  options.c2 = kInf;
  ExpectInvalid(options, "c2 = inf");
}

TEST(PsoGsa, RejectsAnInertiaAboveOne) {
  PsoGsaOptions options;
  options.inertia_start = 1.2;
  ExpectInvalid(options, "inertia_start = 1.2");
}

TEST(PsoGsa, RejectsANegativeFinalInertia) {
  PsoGsaOptions options;
  options.inertia_end = -0.1;
  ExpectInvalid(options, "inertia_end = -0.1");
}

TEST(PsoGsa, RejectsAZeroVelocityLimit) {
  PsoGsaOptions options;
  options.max_velocity_fraction = 0.0;
  ExpectInvalid(options, "max_velocity_fraction = 0");
}

TEST(PsoGsa, RejectsAZeroEpsilon) {
  PsoGsaOptions options;
  options.epsilon = 0.0;
  ExpectInvalid(options, "epsilon = 0");
}

TEST(PsoGsa, RejectsNonFiniteBounds) {
  OptimizerSummary summary;
  PsoGsa(ShiftedSphere, Bounds{Eigen::Vector2d(0.0, -kInf), Eigen::Vector2d(1.0, 1.0)}, PsoGsaOptions(),
         &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find("Bounds.lower[1] = -inf must be finite"), std::string::npos)
      << summary.message;
}

}  // namespace
}  // namespace pidlab
