#include "pidlab/optim/genetic_algorithm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

using pidlab::optim::Bounds;
using pidlab::optim::GaCrossover;
using pidlab::optim::GeneticAlgorithm;
using pidlab::optim::GeneticAlgorithmOptions;
using pidlab::optim::OptimizerSummary;
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

TEST(GeneticAlgorithm, FindsTheMinimumOfAShiftedSphereInThreeDimensions) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    GeneticAlgorithmOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    GeneticAlgorithm(ShiftedSphere, Cube(3, -5.0, 5.0), options, &summary);

    EXPECT_EQ(summary.termination, TerminationType::kMaxIterations) << summary.BriefReport();
    EXPECT_LT(summary.f, 1e-4) << "seed " << seed;
    EXPECT_LT((summary.x.array() - 0.3).abs().maxCoeff(), 1e-2) << "seed " << seed;
  }
}

TEST(GeneticAlgorithm, FindsTheRosenbrockMinimumInTwoDimensions) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    GeneticAlgorithmOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    GeneticAlgorithm(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);

    EXPECT_LT(summary.f, 1e-3) << "seed " << seed;
    EXPECT_LT((summary.x.array() - 1.0).abs().maxCoeff(), 0.1) << "seed " << seed;
  }
}

TEST(GeneticAlgorithm, FindsTheGlobalMinimumOfRastriginInTwoDimensions) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    GeneticAlgorithmOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    GeneticAlgorithm(Rastrigin, Cube(2, -5.12, 5.12), options, &summary);

    EXPECT_LT(summary.f, 1e-3) << "seed " << seed;
    EXPECT_LT(summary.x.cwiseAbs().maxCoeff(), 1e-2) << "seed " << seed;
  }
}

TEST(GeneticAlgorithm, FindsTheSphereMinimumWithBlxAlphaCrossover) {
  GeneticAlgorithmOptions options;
  options.crossover = GaCrossover::kBlxAlpha;
  OptimizerSummary summary;
  GeneticAlgorithm(ShiftedSphere, Cube(3, -5.0, 5.0), options, &summary);
  EXPECT_LT(summary.f, 1e-4) << summary.BriefReport();
}

TEST(GeneticAlgorithm, EvaluatesEachChildOnceAndNeverReevaluatesTheElites) {
  GeneticAlgorithmOptions options;
  OptimizerSummary summary;
  GeneticAlgorithm(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary);
  EXPECT_EQ(summary.evaluations, 40 + 100 * (40 - 2));
  EXPECT_EQ(summary.iterations, 100);

  // An odd number of places per generation drops the last pair's second child unevaluated.
  options.population_size = 41;
  GeneticAlgorithm(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary);
  EXPECT_EQ(summary.evaluations, 41 + 100 * (41 - 2));
}

TEST(GeneticAlgorithm, EvaluatesOnlyPointsInsideTheBounds) {
  // The minimum (0.3, 0.3, 0.3) lies outside [-1, 0]^3, on its upper corner.
  const Bounds bounds = Cube(3, -1.0, 0.0);
  int outside = 0;
  auto f = [&](const Eigen::VectorXd& x) {
    outside += Inside(x, bounds) ? 0 : 1;
    return ShiftedSphere(x);
  };
  GeneticAlgorithmOptions options;
  options.crossover = GaCrossover::kBlxAlpha;  // Its children overshoot the parents most.
  OptimizerSummary summary;
  GeneticAlgorithm(f, bounds, options, &summary);
  EXPECT_EQ(outside, 0);
  EXPECT_TRUE(Inside(summary.x, bounds));
  EXPECT_LT(summary.x.cwiseAbs().maxCoeff(), 1e-3);
}

TEST(GeneticAlgorithm, NeverReturnsARejectedIndividual) {
  // Rejected wherever x0 > 0: the unconstrained minimum (0.3, 0.3) is rejected, the answer is (0, 0.3).
  auto f = [](const Eigen::VectorXd& x) { return x[0] > 0.0 ? kInf : ShiftedSphere(x); };
  GeneticAlgorithmOptions options;
  OptimizerSummary summary;
  GeneticAlgorithm(f, Cube(2, -1.0, 1.0), options, &summary);

  ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
  EXPECT_GT(summary.rejected_evaluations, 0);
  EXPECT_LE(summary.x[0], 0.0);
  EXPECT_NEAR(summary.x[0], 0.0, 1e-2);
  EXPECT_NEAR(summary.x[1], 0.3, 1e-2);
  for (const TracePoint& point : summary.trace) EXPECT_TRUE(std::isfinite(point.best_f));
}

TEST(GeneticAlgorithm, ConcentratesInASmallFeasibleRegionBecauseRejectedIndividualsLoseTournaments) {
  // Only 4% of the box is feasible. Were rejected individuals to win tournaments, about as
  // many children would be rejected late in the run as at the start.
  int rejected = 0;
  auto f = [&rejected](const Eigen::VectorXd& x) {
    if ((x.array() >= 0.8).all()) return (x.array() - 0.9).square().sum();
    ++rejected;
    return kInf;
  };
  int evaluations_at_50 = 0, rejected_at_50 = 0;
  GeneticAlgorithmOptions options;
  OptimizerSummary summary;
  GeneticAlgorithm(f, Cube(2, 0.0, 1.0), options, &summary, [&](const TracePoint& point) {
    if (point.iteration == 50) {
      evaluations_at_50 = point.evaluations;
      rejected_at_50 = rejected;
    }
  });
  ASSERT_TRUE(summary.IsUsable());
  EXPECT_LT((summary.x.array() - 0.9).abs().maxCoeff(), 1e-2);
  const double late_rejected_fraction =
      static_cast<double>(rejected - rejected_at_50) / (summary.evaluations - evaluations_at_50);
  EXPECT_LT(late_rejected_fraction, 0.2);
}

TEST(GeneticAlgorithm, EndsWithNoFeasiblePointWhenEveryPointIsRejected) {
  auto f = [](const Eigen::VectorXd&) { return kInf; };
  GeneticAlgorithmOptions options;
  options.max_generations = 3;
  OptimizerSummary summary;
  GeneticAlgorithm(f, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
  EXPECT_FALSE(summary.IsUsable());
  EXPECT_EQ(summary.evaluations, 40 + 3 * 38);
}

TEST(GeneticAlgorithm, GivesBitIdenticalResultsForTheSameSeed) {
  GeneticAlgorithmOptions options;
  options.seed = 123;
  OptimizerSummary a, b, c;
  GeneticAlgorithm(Rastrigin, Cube(2, -5.12, 5.12), options, &a);
  GeneticAlgorithm(Rastrigin, Cube(2, -5.12, 5.12), options, &b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.f, b.f);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  for (std::size_t i = 0; i < a.trace.size(); ++i) EXPECT_EQ(a.trace[i].best_f, b.trace[i].best_f);

  options.seed = 124;
  GeneticAlgorithm(Rastrigin, Cube(2, -5.12, 5.12), options, &c);
  EXPECT_NE(a.trace.front().best_x, c.trace.front().best_x);
}

TEST(GeneticAlgorithm, ReportsEveryGenerationToTheProgressCallback) {
  std::vector<TracePoint> seen;
  GeneticAlgorithmOptions options;
  options.max_generations = 25;
  OptimizerSummary summary;
  GeneticAlgorithm(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary,
                   [&seen](const TracePoint& point) { seen.push_back(point); });
  ASSERT_EQ(seen.size(), 25u);
  EXPECT_EQ(seen.front().evaluations, 40 + 38);
  EXPECT_EQ(seen.back().iteration, 25);
  EXPECT_EQ(seen.back().best_f, summary.f);
}

TEST(GeneticAlgorithm, StopsExactlyAtTheEvaluationBudget) {
  GeneticAlgorithmOptions options;
  options.max_evaluations = 100;
  OptimizerSummary summary;
  GeneticAlgorithm(ShiftedSphere, Cube(2, -1.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kMaxEvaluations);
  EXPECT_EQ(summary.evaluations, 100);
  EXPECT_EQ(summary.iterations, 1);  // 40 + 38 = 78 fit, the second generation does not.
  EXPECT_TRUE(summary.IsUsable());
}

void ExpectInvalid(const GeneticAlgorithmOptions& options, const std::string& field) {
  int calls = 0;
  auto f = [&calls](const Eigen::VectorXd& x) {
    ++calls;
    return x.squaredNorm();
  };
  OptimizerSummary summary;
  GeneticAlgorithm(f, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find(field), std::string::npos) << summary.message;
  EXPECT_EQ(calls, 0);
}

TEST(GeneticAlgorithm, RejectsAPopulationOfOne) {
  GeneticAlgorithmOptions options;
  options.population_size = 1;
  options.elite_count = 0;
  ExpectInvalid(options, "GeneticAlgorithmOptions.population_size = 1");
}

TEST(GeneticAlgorithm, RejectsZeroGenerations) {
  GeneticAlgorithmOptions options;
  options.max_generations = 0;
  ExpectInvalid(options, "max_generations = 0");
}

TEST(GeneticAlgorithm, RejectsANegativeEvaluationBudget) {
  GeneticAlgorithmOptions options;
  options.max_evaluations = -1;
  ExpectInvalid(options, "max_evaluations = -1");
}

TEST(GeneticAlgorithm, RejectsAnEmptyTournament) {
  GeneticAlgorithmOptions options;
  options.tournament_size = 0;
  ExpectInvalid(options, "tournament_size = 0");
}

TEST(GeneticAlgorithm, RejectsANanCrossoverProbability) {
  GeneticAlgorithmOptions options;
  options.crossover_probability = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(options, "crossover_probability");
}

TEST(GeneticAlgorithm, RejectsANegativeSbxIndex) {
  GeneticAlgorithmOptions options;
  options.sbx_eta = -1.0;
  ExpectInvalid(options, "sbx_eta = -1");
}

TEST(GeneticAlgorithm, RejectsAnInfiniteBlxAlpha) {
  GeneticAlgorithmOptions options;
  options.blx_alpha = kInf;
  ExpectInvalid(options, "blx_alpha = inf");
}

TEST(GeneticAlgorithm, RejectsAMutationProbabilityAboveOne) {
  GeneticAlgorithmOptions options;
  options.mutation_probability = 1.5;
  ExpectInvalid(options, "mutation_probability = 1.5");
}

TEST(GeneticAlgorithm, RejectsANanMutationIndex) {
  GeneticAlgorithmOptions options;
  options.mutation_eta = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(options, "mutation_eta");
}

TEST(GeneticAlgorithm, RejectsAsManyElitesAsIndividuals) {
  GeneticAlgorithmOptions options;
  options.elite_count = 40;
  ExpectInvalid(options, "elite_count = 40");
}

TEST(GeneticAlgorithm, RejectsBoundsOfMismatchedSizes) {
  OptimizerSummary summary;
  GeneticAlgorithm(ShiftedSphere, Bounds{Eigen::Vector2d(0, 0), Eigen::Vector3d(1, 1, 1)},
                   GeneticAlgorithmOptions(), &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find("Bounds.lower has size 2"), std::string::npos) << summary.message;
}

}  // namespace
}  // namespace pidlab
