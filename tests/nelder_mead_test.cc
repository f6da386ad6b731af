#include "pidlab/optim/nelder_mead.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

using pidlab::optim::Bounds;
using pidlab::optim::NelderMead;
using pidlab::optim::NelderMeadOptions;
using pidlab::optim::ObjectiveFunction;
using pidlab::optim::OptimizerSummary;
using pidlab::optim::TerminationType;
using pidlab::optim::TracePoint;

namespace pidlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kPi = std::acos(-1.0);

double Rosenbrock(const Eigen::VectorXd& x) {
  return (1.0 - x[0]) * (1.0 - x[0]) + 100.0 * (x[1] - x[0] * x[0]) * (x[1] - x[0] * x[0]);
}

double Rastrigin(const Eigen::VectorXd& x) {
  double f = 10.0 * static_cast<double>(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) f += x[i] * x[i] - 10.0 * std::cos(2.0 * kPi * x[i]);
  return f;
}

Bounds Box(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) { return Bounds{lower, upper}; }

Bounds Cube(int n, double lo, double hi) {
  return Box(Eigen::VectorXd::Constant(n, lo), Eigen::VectorXd::Constant(n, hi));
}

// Wraps an objective and records every point it is called with.
struct Recorder {
  ObjectiveFunction f;
  std::vector<Eigen::VectorXd> points;
  std::vector<double> values;

  ObjectiveFunction Wrapped() {
    return [this](const Eigen::VectorXd& x) {
      points.push_back(x);
      values.push_back(f(x));
      return values.back();
    };
  }
};

bool Inside(const Eigen::VectorXd& x, const Bounds& b) {
  return x.size() == b.lower.size() && (x.array() >= b.lower.array()).all() &&
         (x.array() <= b.upper.array()).all();
}

TEST(NelderMead, FindsTheRosenbrockMinimumInTwoDimensions) {
  NelderMeadOptions options;
  options.x0 = Eigen::Vector2d(-1.2, 1.0);
  OptimizerSummary summary;
  NelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);

  ASSERT_EQ(summary.termination, TerminationType::kConverged) << summary.BriefReport();
  EXPECT_TRUE(summary.IsUsable());
  EXPECT_NEAR(summary.x[0], 1.0, 1e-6);
  EXPECT_NEAR(summary.x[1], 1.0, 1e-6);
  EXPECT_LT(summary.f, 1e-12);
  EXPECT_LT(summary.evaluations, 1000);
}

TEST(NelderMead, FindsAMinimumThatLiesOnTheBoundsOfAThreeDimensionalBox) {
  // Unconstrained minimum (0.5, 2, -0.3); the box [0, 1]^3 moves it to (0.5, 1, 0).
  const Eigen::Vector3d centre(0.5, 2.0, -0.3);
  auto f = [&centre](const Eigen::VectorXd& x) { return (x - centre).squaredNorm(); };
  NelderMeadOptions options;
  options.seed = 3;
  OptimizerSummary summary;
  NelderMead(f, Cube(3, 0.0, 1.0), options, &summary);

  ASSERT_EQ(summary.termination, TerminationType::kConverged) << summary.BriefReport();
  EXPECT_NEAR(summary.x[0], 0.5, 1e-6);
  EXPECT_EQ(summary.x[1], 1.0);  // Projection puts the answer exactly on the bound.
  EXPECT_EQ(summary.x[2], 0.0);
  EXPECT_NEAR(summary.f, 1.0 + 0.09, 1e-10);
}

TEST(NelderMead, FindsTheInteriorMinimumOfAnIllConditionedThreeDimensionalQuadratic) {
  Eigen::Matrix3d a;
  a << 10.0, 2.0, 0.0,  //
      2.0, 1.0, 0.1,    //
      0.0, 0.1, 0.1;    // Positive definite, condition number ~250.
  const Eigen::Vector3d centre(0.2, -0.7, 1.5);
  auto f = [&](const Eigen::VectorXd& x) { return (x - centre).dot(a * (x - centre)); };
  NelderMeadOptions options;
  options.seed = 11;
  OptimizerSummary summary;
  NelderMead(f, Cube(3, -3.0, 3.0), options, &summary);

  ASSERT_EQ(summary.termination, TerminationType::kConverged) << summary.BriefReport();
  EXPECT_LT((summary.x - centre).norm(), 1e-4);
  EXPECT_LT(summary.f, 1e-9);
}

TEST(NelderMead, MinimisesAOneDimensionalFunction) {
  auto f = [](const Eigen::VectorXd& x) { return std::cos(x[0]); };
  NelderMeadOptions options;
  options.x0 = Eigen::VectorXd::Constant(1, 2.0);
  OptimizerSummary summary;
  NelderMead(f, Cube(1, 0.0, 5.0), options, &summary);

  ASSERT_EQ(summary.termination, TerminationType::kConverged) << summary.BriefReport();
  EXPECT_NEAR(summary.x[0], kPi, 1e-4);
}

TEST(NelderMead, AdaptiveCoefficientsMinimiseAnEightDimensionalEllipsoid) {
  auto f = [](const Eigen::VectorXd& x) {
    double s = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) s += static_cast<double>(i + 1) * (x[i] - 0.1) * (x[i] - 0.1);
    return s;
  };
  NelderMeadOptions options;
  options.adaptive = true;
  options.max_evaluations = 20000;
  options.max_iterations = 10000;
  OptimizerSummary summary;
  NelderMead(f, Cube(8, -1.0, 1.0), options, &summary);

  ASSERT_EQ(summary.termination, TerminationType::kConverged) << summary.BriefReport();
  EXPECT_LT((summary.x.array() - 0.1).abs().maxCoeff(), 1e-4);
}

TEST(NelderMead, EvaluatesOnlyPointsInsideTheBounds) {
  // The unconstrained minimum (1, 1) lies outside the box, so the simplex keeps pushing against it.
  Recorder recorder{Rosenbrock, {}, {}};
  const Bounds bounds = Box(Eigen::Vector2d(-2.0, -1.0), Eigen::Vector2d(0.5, 2.0));
  NelderMeadOptions options;
  options.starts = 4;
  OptimizerSummary summary;
  NelderMead(recorder.Wrapped(), bounds, options, &summary);

  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  ASSERT_EQ(static_cast<int>(recorder.points.size()), summary.evaluations);
  for (const Eigen::VectorXd& x : recorder.points) ASSERT_TRUE(Inside(x, bounds)) << x.transpose();
  EXPECT_TRUE(Inside(summary.x, bounds));
  EXPECT_EQ(summary.x[0], 0.5);
  EXPECT_NEAR(summary.x[1], 0.25, 1e-6);
}

TEST(NelderMead, NeverReturnsARejectedPointAndStaysOnTheFeasibleSide) {
  // Unconstrained minimum (0.7, 0.3) lies in the rejected region x0 > 0.5: the answer is (0.5, 0.3).
  Recorder recorder{[](const Eigen::VectorXd& x) {
                      if (x[0] > 0.5) return kInf;
                      return (x[0] - 0.7) * (x[0] - 0.7) + (x[1] - 0.3) * (x[1] - 0.3);
                    },
                    {},
                    {}};
  NelderMeadOptions options;
  options.x0 = Eigen::Vector2d(0.1, 0.9);
  OptimizerSummary summary;
  NelderMead(recorder.Wrapped(), Cube(2, 0.0, 1.0), options, &summary);

  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  EXPECT_GT(summary.rejected_evaluations, 0);  // The test did exercise rejection.
  EXPECT_LE(summary.x[0], 0.5);
  EXPECT_TRUE(std::isfinite(recorder.f(summary.x)));
  // Against a wall of rejected points the simplex cannot slide along the wall, so it stalls close to,
  // not at, the constrained minimum (documented in docs/optimisers.md).
  EXPECT_NEAR(summary.f, 0.04, 1e-6);
  EXPECT_NEAR(summary.x[0], 0.5, 1e-3);
  EXPECT_NEAR(summary.x[1], 0.3, 1e-3);
  for (const TracePoint& point : summary.trace) EXPECT_TRUE(std::isfinite(point.best_f));
  int rejected = 0;
  for (double v : recorder.values) rejected += std::isinf(v) ? 1 : 0;
  EXPECT_EQ(rejected, summary.rejected_evaluations);
}

TEST(NelderMead, TreatsNanAsARejectedPoint) {
  auto f = [](const Eigen::VectorXd& x) {
    return x[0] + x[1] < 0.0 ? std::numeric_limits<double>::quiet_NaN() : (x[0] + x[1]) + 0.1 * x[0] * x[0];
  };
  NelderMeadOptions options;
  options.seed = 5;
  OptimizerSummary summary;
  NelderMead(f, Cube(2, -1.0, 1.0), options, &summary);

  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  EXPECT_GT(summary.rejected_evaluations, 0);
  EXPECT_FALSE(std::isnan(summary.f));
  EXPECT_GE(summary.x[0] + summary.x[1], 0.0);
  EXPECT_NEAR(summary.f, 0.0, 1e-6);
}

TEST(NelderMead, EndsWithNoFeasiblePointWhenEveryPointIsRejected) {
  auto f = [](const Eigen::VectorXd&) { return kInf; };
  NelderMeadOptions options;
  options.starts = 3;
  options.max_initial_redraws = 2;
  OptimizerSummary summary;
  NelderMead(f, Cube(2, 0.0, 1.0), options, &summary);

  EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
  EXPECT_FALSE(summary.IsUsable());
  EXPECT_EQ(summary.x.size(), 0);
  EXPECT_EQ(summary.f, kInf);
  EXPECT_EQ(summary.iterations, 0);
  EXPECT_EQ(summary.starts, 3);
  // Per start: base point 1 + 2 redraws, each of the 2 edge vertices 1 + 2 tries.
  EXPECT_EQ(summary.evaluations, 3 * (3 + 2 * 3));
  EXPECT_EQ(summary.rejected_evaluations, summary.evaluations);
}

TEST(NelderMead, RedrawsARejectedInitialPoint) {
  // Feasible only for x0 > 0.7; seed 1 draws its first base point at x0 < 0.6, out of reach of its
  // edge vertices (step 0.1), so without redraws the start has no feasible vertex.
  Recorder recorder{
      [](const Eigen::VectorXd& x) { return x[0] > 0.7 ? (x - Eigen::Vector2d(0.8, 0.5)).norm() : kInf; },
      {},
      {}};
  NelderMeadOptions options;
  options.seed = 1;
  options.max_initial_redraws = 0;
  OptimizerSummary without;
  NelderMead(recorder.Wrapped(), Cube(2, 0.0, 1.0), options, &without);
  ASSERT_LT(recorder.points.front()[0], 0.6);  // Precondition of this test.
  EXPECT_EQ(without.termination, TerminationType::kNoFeasiblePoint);

  options.max_initial_redraws = 10;
  OptimizerSummary with;
  NelderMead(recorder.f, Cube(2, 0.0, 1.0), options, &with);
  ASSERT_TRUE(with.IsUsable()) << with.BriefReport();
  EXPECT_NEAR(with.x[0], 0.8, 1e-5);
  EXPECT_NEAR(with.x[1], 0.5, 1e-5);
}

TEST(NelderMead, GivesBitIdenticalResultsForTheSameSeed) {
  NelderMeadOptions options;
  options.starts = 3;
  options.seed = 42;
  OptimizerSummary a, b;
  NelderMead(Rastrigin, Cube(2, -5.12, 5.12), options, &a);
  NelderMead(Rastrigin, Cube(2, -5.12, 5.12), options, &b);

  ASSERT_TRUE(a.IsUsable());
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.f, b.f);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.iterations, b.iterations);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  for (std::size_t i = 0; i < a.trace.size(); ++i) EXPECT_EQ(a.trace[i].best_f, b.trace[i].best_f);
}

TEST(NelderMead, DrawsDifferentStartsForDifferentSeeds) {
  Recorder one{Rastrigin, {}, {}};
  Recorder two{Rastrigin, {}, {}};
  NelderMeadOptions options;
  options.seed = 1;
  OptimizerSummary summary;
  NelderMead(one.Wrapped(), Cube(2, -5.12, 5.12), options, &summary);
  options.seed = 2;
  NelderMead(two.Wrapped(), Cube(2, -5.12, 5.12), options, &summary);
  EXPECT_NE(one.points.front(), two.points.front());
}

TEST(NelderMead, MultiStartIsAtLeastAsGoodAsASingleStartOnRastrigin) {
  const Bounds bounds = Cube(2, -5.12, 5.12);
  // A small initial simplex (0.2 wide, the period of the ripple is 1) lets one start fall into a
  // local minimum, which is what multi-start is for.
  NelderMeadOptions options;
  options.seed = 10;
  options.initial_step_fraction = 0.02;
  options.max_evaluations = 100000;
  OptimizerSummary single;
  NelderMead(Rastrigin, bounds, options, &single);
  // Each start lands in the origin's cell with probability about 1/105:
  // 300 starts (333 evaluations each) miss it with probability about 6 %.
  options.starts = 300;
  OptimizerSummary multi;
  NelderMead(Rastrigin, bounds, options, &multi);

  ASSERT_TRUE(single.IsUsable());
  ASSERT_TRUE(multi.IsUsable());
  EXPECT_EQ(multi.starts, 300);
  EXPECT_LE(multi.f, single.f);
  EXPECT_GT(single.f, 0.5);  // One start is caught in a local minimum...
  EXPECT_LT(multi.f, 1e-8);  // ...many find the global one at the origin.
  EXPECT_LT(multi.x.norm(), 1e-4);
}

TEST(NelderMead, StopsExactlyAtTheEvaluationBudget) {
  Recorder recorder{Rosenbrock, {}, {}};
  NelderMeadOptions options;
  options.max_evaluations = 50;
  OptimizerSummary summary;
  NelderMead(recorder.Wrapped(), Cube(2, -2.0, 2.0), options, &summary);

  EXPECT_EQ(summary.termination, TerminationType::kMaxEvaluations);
  EXPECT_EQ(summary.evaluations, 50);
  EXPECT_EQ(recorder.points.size(), 50u);
  EXPECT_TRUE(summary.IsUsable());
  EXPECT_NE(summary.message.find("max_evaluations"), std::string::npos);
}

TEST(NelderMead, StopsAtTheIterationBudget) {
  NelderMeadOptions options;
  options.max_iterations = 7;
  OptimizerSummary summary;
  NelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);

  EXPECT_EQ(summary.termination, TerminationType::kMaxIterations);
  EXPECT_EQ(summary.iterations, 7);
}

TEST(NelderMead, ReportsEveryIterationToTheProgressCallbackAndTheTrace) {
  std::vector<TracePoint> seen;
  NelderMeadOptions options;
  options.starts = 2;
  OptimizerSummary summary;
  NelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary,
             [&seen](const TracePoint& point) { seen.push_back(point); });

  ASSERT_EQ(static_cast<int>(seen.size()), summary.iterations);
  ASSERT_EQ(summary.trace.size(), seen.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].iteration, static_cast<int>(i) + 1);
    EXPECT_EQ(seen[i].best_f, summary.trace[i].best_f);
    if (i > 0) {
      EXPECT_LE(seen[i].best_f, seen[i - 1].best_f);
      EXPECT_GT(seen[i].evaluations, seen[i - 1].evaluations);
    }
  }
  EXPECT_EQ(seen.back().best_f, summary.f);
  EXPECT_EQ(seen.back().best_x, summary.x);
}

TEST(NelderMead, RestartOnConvergenceNeverMakesTheResultWorse) {
  NelderMeadOptions options;
  options.seed = 9;
  options.restarts_on_convergence = 0;
  OptimizerSummary once;
  NelderMead(Rastrigin, Cube(2, -5.12, 5.12), options, &once);
  options.restarts_on_convergence = 3;
  OptimizerSummary restarted;
  NelderMead(Rastrigin, Cube(2, -5.12, 5.12), options, &restarted);

  EXPECT_LE(restarted.f, once.f);
  EXPECT_GT(restarted.evaluations, once.evaluations);
}

TEST(NelderMead, NeverReturnsAPointOutsideTheBoundsForRandomBoxes) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Vector3d lo(u(rng), u(rng), u(rng));
    const Eigen::Vector3d width(1.0 + std::abs(u(rng)), 1.0 + std::abs(u(rng)), 1.0 + std::abs(u(rng)));
    const Bounds bounds = Box(lo, lo + width);
    const Eigen::Vector3d target(u(rng), u(rng), u(rng));
    auto f = [&target](const Eigen::VectorXd& x) { return (x - target).squaredNorm(); };
    NelderMeadOptions options;
    options.seed = static_cast<std::uint64_t>(trial);
    OptimizerSummary summary;
    NelderMead(f, bounds, options, &summary);
    ASSERT_TRUE(summary.IsUsable());
    EXPECT_TRUE(Inside(summary.x, bounds)) << summary.x.transpose();
    // The answer is the projection of the target onto the box.
    EXPECT_LT((summary.x - target.cwiseMax(bounds.lower).cwiseMin(bounds.upper)).norm(), 1e-5);
  }
}

// One test per precondition: each gives kInvalidOptions, names the field, and calls nothing.
void ExpectInvalid(const NelderMeadOptions& options, const Bounds& bounds, const std::string& field) {
  int calls = 0;
  auto f = [&calls](const Eigen::VectorXd& x) {
    ++calls;
    return x.squaredNorm();
  };
  OptimizerSummary summary;
  NelderMead(f, bounds, options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find(field), std::string::npos) << summary.message;
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(summary.evaluations, 0);
  EXPECT_FALSE(summary.IsUsable());
}

TEST(NelderMead, RejectsANegativeEvaluationBudget) {
  NelderMeadOptions options;
  options.max_evaluations = -1;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "max_evaluations = -1");
}

TEST(NelderMead, RejectsAZeroIterationBudget) {
  NelderMeadOptions options;
  options.max_iterations = 0;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "max_iterations = 0");
}

TEST(NelderMead, RejectsANanXTolerance) {
  NelderMeadOptions options;
  options.x_tolerance = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "x_tolerance");
}

TEST(NelderMead, RejectsANanFTolerance) {
  NelderMeadOptions options;
  options.f_tolerance = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "f_tolerance");
}

TEST(NelderMead, RejectsAnInitialStepFractionOutsideZeroToOne) {
  NelderMeadOptions options;
  options.initial_step_fraction = 0.0;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "initial_step_fraction");
}

TEST(NelderMead, RejectsZeroStarts) {
  NelderMeadOptions options;
  options.starts = 0;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "starts = 0");
}

TEST(NelderMead, RejectsANegativeRestartCount) {
  NelderMeadOptions options;
  options.restarts_on_convergence = -1;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "restarts_on_convergence");
}

TEST(NelderMead, RejectsANegativeRedrawCount) {
  NelderMeadOptions options;
  options.max_initial_redraws = -1;
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "max_initial_redraws");
}

TEST(NelderMead, RejectsANonFiniteX0) {
  NelderMeadOptions options;
  options.x0 = Eigen::Vector2d(0.5, kInf);
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "x0[1]");
}

TEST(NelderMead, RejectsAnX0OfTheWrongSize) {
  NelderMeadOptions options;
  options.x0 = Eigen::Vector3d(0.5, 0.5, 0.5);
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "x0 has size 3");
}

TEST(NelderMead, RejectsAnX0OutsideTheBounds) {
  NelderMeadOptions options;
  options.x0 = Eigen::Vector2d(0.5, 1.5);
  ExpectInvalid(options, Cube(2, 0.0, 1.0), "x0[1] = 1.5");
}

TEST(NelderMead, RejectsBoundsWhoseLowerIsNotBelowUpper) {
  ExpectInvalid(NelderMeadOptions(), Box(Eigen::Vector2d(0.0, 1.0), Eigen::Vector2d(1.0, 1.0)),
                "Bounds.lower[1] = 1 must be < Bounds.upper[1]");
}

TEST(NelderMead, RejectsBoundsOfMismatchedSizes) {
  ExpectInvalid(NelderMeadOptions(), Box(Eigen::Vector2d(0.0, 0.0), Eigen::Vector3d(1.0, 1.0, 1.0)),
                "Bounds.lower has size 2 but Bounds.upper has size 3");
}

TEST(NelderMead, RejectsEmptyBounds) {
  ExpectInvalid(NelderMeadOptions(), Box(Eigen::VectorXd(), Eigen::VectorXd()), "at least one dimension");
}

TEST(NelderMead, RejectsInfiniteBounds) {
  ExpectInvalid(NelderMeadOptions(), Box(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, kInf)),
                "Bounds.upper[1] = inf must be finite");
}

TEST(NelderMead, RejectsAnEmptyObjective) {
  OptimizerSummary summary;
  NelderMead(ObjectiveFunction(), Cube(2, 0.0, 1.0), NelderMeadOptions(), &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find("objective"), std::string::npos);
}

TEST(OptimizerSummary, BriefReportNamesTheTerminationTheResultAndTheCounts) {
  NelderMeadOptions options;
  options.x0 = Eigen::Vector2d(-1.2, 1.0);
  OptimizerSummary summary;
  NelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);
  const std::string report = summary.BriefReport();
  EXPECT_EQ(report.rfind("CONVERGED: f = ", 0), 0u) << report;
  EXPECT_NE(report.find(std::to_string(summary.evaluations) + " evaluations"), std::string::npos) << report;
  EXPECT_NE(report.find("1 start"), std::string::npos) << report;
}

TEST(OptimizerSummary, ADefaultSummaryIsNotUsable) {
  EXPECT_FALSE(OptimizerSummary().IsUsable());
  EXPECT_EQ(ToString(TerminationType::kNoFeasiblePoint), "NO_FEASIBLE_POINT");
}

}  // namespace
}  // namespace pidlab
