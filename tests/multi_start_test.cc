#include "pidlab/optim/multi_start.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "pidlab/optim/sobol.h"

using pidlab::optim::Bounds;
using pidlab::optim::LocalMinimum;
using pidlab::optim::MultiStart;
using pidlab::optim::MultiStartOptions;
using pidlab::optim::ObjectiveFunction;
using pidlab::optim::OptimizerSummary;
using pidlab::optim::SobolSequence;
using pidlab::optim::TerminationType;

namespace pidlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SobolSequence, StartsWithTheJoeKuoPointsInThreeDimensions) {
  const SobolSequence dut(3);
  const double expected[8][3] = {{0, 0, 0},
                                 {0.5, 0.5, 0.5},
                                 {0.75, 0.25, 0.25},
                                 {0.25, 0.75, 0.75},
                                 {0.375, 0.375, 0.625},
                                 {0.875, 0.875, 0.125},
                                 {0.625, 0.125, 0.875},
                                 {0.125, 0.625, 0.375}};
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(dut.Point(static_cast<std::uint32_t>(i))[j], expected[i][j]) << i;
}

// The first 2^m points put exactly one point in every interval of width 2^-m
// of each coordinate, and (dimensions 1-2, t = 0) one in every dyadic box of
// area 2^-m; a digital shift keeps both.
void ExpectNet(const SobolSequence& dut, int m) {
  const std::uint32_t n = 1u << m;
  for (int j = 0; j < dut.dimensions(); ++j) {
    std::set<std::uint32_t> cells;
    for (std::uint32_t i = 0; i < n; ++i) cells.insert(static_cast<std::uint32_t>(dut.Point(i)[j] * n));
    EXPECT_EQ(cells.size(), n) << "coordinate " << j;
  }
  for (int a = 0; a <= m; ++a) {
    std::set<std::pair<std::uint32_t, std::uint32_t>> boxes;
    for (std::uint32_t i = 0; i < n; ++i) {
      const Eigen::VectorXd x = dut.Point(i);
      boxes.insert(
          {static_cast<std::uint32_t>(x[0] * (1u << a)), static_cast<std::uint32_t>(x[1] * (1u << (m - a)))});
    }
    EXPECT_EQ(boxes.size(), n) << "boxes 2^-" << a << " x 2^-" << m - a;
  }
}

TEST(SobolSequence, FirstPowerOfTwoPointsFormANetWithAndWithoutADigitalShift) {
  ExpectNet(SobolSequence(4), 10);
  ExpectNet(SobolSequence(4, 7), 10);
}

TEST(SobolSequence, DigitalShiftDependsOnTheSeedOnly) {
  const SobolSequence a(3, 1), b(3, 1), c(3, 2);
  EXPECT_EQ(a.Point(5), b.Point(5));
  EXPECT_NE(a.Point(5), c.Point(5));
  EXPECT_NE(a.Point(0), SobolSequence(3).Point(0));
}

TEST(SobolSequence, ThrowsForZeroOrMoreThanFourDimensions) {
  EXPECT_THROW(SobolSequence(0), std::invalid_argument);
  EXPECT_THROW(SobolSequence(5), std::invalid_argument);
}

Bounds Cube(int n, double lo, double hi) {
  return Bounds{Eigen::VectorXd::Constant(n, lo), Eigen::VectorXd::Constant(n, hi)};
}

// A broad bowl around (0.7, 0.7, 0.7) (f = 1 at best) and a narrow well
// near the lower corner, at (0.02, 0.05, 0.03) with a width of 0.02 (f = 0
// at its bottom), like the PID gains whose best values are small.
double BowlAndWell(const Eigen::VectorXd& x) {
  const Eigen::Vector3d well(0.02, 0.05, 0.03);
  const double bowl = 1.0 + (x.array() - 0.7).square().sum();
  return bowl * (1.0 - std::exp(-(x - well).squaredNorm() / (2.0 * 0.02 * 0.02)));
}

TEST(MultiStart, FindsANarrowWellNearTheLowerBoundForEverySeedWithAWarpedDesign) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    MultiStartOptions options;
    options.seed = seed;
    options.warp = 4.0;
    options.design_points = 1024;
    options.starts = 16;
    options.min_separation = 0.2;
    OptimizerSummary summary;
    MultiStart(BowlAndWell, Cube(3, 0.0, 1.0), options, &summary);
    ASSERT_TRUE(summary.IsUsable()) << summary.BriefReport();
    EXPECT_LT(summary.f, 1e-6) << "seed " << seed << ": " << summary.BriefReport();
  }
}

TEST(MultiStart, KeepsEveryPointInTheBoxAndTheEvaluationBudgetAsAHardCap) {
  const Bounds box{Eigen::Vector2d(-1.0, 2.0), Eigen::Vector2d(3.0, 2.5)};
  int calls = 0;
  const ObjectiveFunction f = [&](const Eigen::VectorXd& x) {
    ++calls;
    EXPECT_TRUE((x.array() >= box.lower.array()).all() && (x.array() <= box.upper.array()).all()) << x;
    return std::sin(5.0 * x[0]) + std::cos(7.0 * x[1]);
  };
  MultiStartOptions options;
  options.design_points = 64;
  options.max_evaluations = 200;
  options.warp = 3.0;
  options.polish.x_tolerance = 0.0;  // never converges: every start uses its share
  options.polish.f_tolerance = 0.0;
  OptimizerSummary summary;
  std::vector<LocalMinimum> minima;
  MultiStart(f, box, options, &summary, nullptr, &minima);
  EXPECT_EQ(calls, 200);
  EXPECT_EQ(summary.evaluations, 200);
  EXPECT_EQ(summary.termination, TerminationType::kMaxEvaluations) << summary.message;
  ASSERT_FALSE(minima.empty());
  for (std::size_t i = 1; i < minima.size(); ++i) EXPECT_LE(minima[i - 1].f, minima[i].f);
  EXPECT_EQ(minima.front().f, summary.f);
}

TEST(MultiStart, StartsLieAtLeastTheMinimumSeparationApart) {
  MultiStartOptions options;
  options.min_separation = 0.3;
  options.starts = 50;
  options.design_points = 256;
  options.max_evaluations = 2000;
  std::vector<LocalMinimum> minima;
  OptimizerSummary summary;
  MultiStart([](const Eigen::VectorXd& x) { return x.squaredNorm(); }, Cube(2, 0.0, 1.0), options, &summary,
             nullptr, &minima);
  ASSERT_GE(minima.size(), 2u);
  EXPECT_LE(minima.size(), 16u);  // at most 4 x 4 cells of side 0.3 fit in the square
  for (std::size_t i = 0; i < minima.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      EXPECT_GE((minima[i].start - minima[k].start).cwiseAbs().maxCoeff(), 0.3);
}

void ThreeThreads(int count, const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  std::vector<std::thread> workers;
  for (int w = 0; w < 3; ++w)
    workers.emplace_back([&] {
      for (int i; (i = next.fetch_add(1)) < count;) body(i);
    });
  for (auto& t : workers) t.join();
}

TEST(MultiStart, GivesTheSameBitsWhateverRunsTheEvaluations) {
  const ObjectiveFunction f = [](const Eigen::VectorXd& x) { return BowlAndWell(x); };
  MultiStartOptions options;
  options.design_points = 128;
  options.max_evaluations = 1500;
  OptimizerSummary one, parallel;
  MultiStart(f, Cube(3, 0.0, 1.0), options, &one);
  options.parallel_for = ThreeThreads;
  MultiStart(f, Cube(3, 0.0, 1.0), options, &parallel);
  EXPECT_EQ(parallel.f, one.f);
  EXPECT_EQ(parallel.x, one.x);
  EXPECT_EQ(parallel.evaluations, one.evaluations);
  ASSERT_EQ(parallel.trace.size(), one.trace.size());
  for (std::size_t i = 0; i < one.trace.size(); ++i) EXPECT_EQ(parallel.trace[i].best_f, one.trace[i].best_f);
}

TEST(MultiStart, ReportsNoFeasiblePointWhenEveryDesignPointIsRejected) {
  MultiStartOptions options;
  options.design_points = 32;
  options.max_evaluations = 100;
  OptimizerSummary summary;
  MultiStart([](const Eigen::VectorXd&) { return kInf; }, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
  EXPECT_EQ(summary.evaluations, 32);
  EXPECT_FALSE(summary.IsUsable());
}

TEST(MultiStart, NamesTheInvalidOption) {
  OptimizerSummary summary;
  MultiStartOptions options;
  options.max_evaluations = options.design_points;
  MultiStart([](const Eigen::VectorXd& x) { return x.sum(); }, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find("MultiStartOptions.max_evaluations"), std::string::npos) << summary.message;
  options = MultiStartOptions();
  options.warp = -1.0;
  MultiStart([](const Eigen::VectorXd& x) { return x.sum(); }, Cube(2, 0.0, 1.0), options, &summary);
  EXPECT_NE(summary.message.find("MultiStartOptions.warp = -1"), std::string::npos) << summary.message;
  MultiStart([](const Eigen::VectorXd& x) { return x.sum(); }, Cube(5, 0.0, 1.0), MultiStartOptions(),
             &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find("at most 4 dimensions"), std::string::npos) << summary.message;
}

}  // namespace
}  // namespace pidlab
