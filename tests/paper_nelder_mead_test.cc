#include "pidlab/optim/paper_nelder_mead.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "pidlab/optim/nelder_mead.h"

using pidlab::optim::Bounds;
using pidlab::optim::NelderMead;
using pidlab::optim::NelderMeadOptions;
using pidlab::optim::ObjectiveFunction;
using pidlab::optim::OptimizerSummary;
using pidlab::optim::PaperNelderMead;
using pidlab::optim::PaperNelderMeadOptions;
using pidlab::optim::TerminationType;
using pidlab::optim::TracePoint;

namespace pidlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Bounds Cube(int n, double lo, double hi) {
  return Bounds{Eigen::VectorXd::Constant(n, lo), Eigen::VectorXd::Constant(n, hi)};
}

double Rosenbrock(const Eigen::VectorXd& x) {
  return (1.0 - x[0]) * (1.0 - x[0]) + 100.0 * (x[1] - x[0] * x[0]) * (x[1] - x[0] * x[0]);
}

struct Evaluation {
  Eigen::VectorXd x;
  double f;
};

// Runs the optimiser with an objective that records every call, and the
// evaluation count at the end of every iteration.
struct RecordedRun {
  std::vector<Evaluation> evaluations;
  std::vector<int> iteration_ends;
  OptimizerSummary summary;

  RecordedRun(const ObjectiveFunction& f, const Bounds& bounds, const PaperNelderMeadOptions& options) {
    auto recording = [&](const Eigen::VectorXd& x) {
      evaluations.push_back({x, f(x)});
      return evaluations.back().f;
    };
    PaperNelderMead(recording, bounds, options, &summary,
                    [this](const TracePoint& point) { iteration_ends.push_back(point.evaluations); });
  }
};

bool OnTheBox(const Eigen::VectorXd& x, const Bounds& b) {
  return (x.array() == b.lower.array()).any() || (x.array() == b.upper.array()).any();
}

// Smallest over largest spread of a 3-D point cloud: ~0 when the points are coplanar.
double ThirdOverFirstSingularValue(const std::vector<Evaluation>& points, std::size_t from) {
  Eigen::MatrixXd cloud(static_cast<Eigen::Index>(points.size() - from), 3);
  for (std::size_t i = from; i < points.size(); ++i) {
    cloud.row(static_cast<Eigen::Index>(i - from)) = points[i].x.transpose();
  }
  const Eigen::MatrixXd centred = cloud.rowwise() - cloud.colwise().mean();
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  return s[2] / s[0];
}

TEST(PaperNelderMead, FindsTheMinimumOfATwoDimensionalQuadraticWithinTheHundredIterations) {
  // In 2-D the triangle is a proper simplex.
  auto f = [](const Eigen::VectorXd& x) {
    const double a = x[0] - 1.0, b = x[1] + 0.5;
    return a * a + 2.0 * b * b + 0.5 * a * b;
  };
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    PaperNelderMeadOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    PaperNelderMead(f, Cube(2, -5.0, 5.0), options, &summary);

    ASSERT_EQ(summary.termination, TerminationType::kMaxIterations) << summary.BriefReport();
    EXPECT_EQ(summary.iterations, 100);
    EXPECT_NEAR(summary.x[0], 1.0, 1e-6) << "seed " << seed;
    EXPECT_NEAR(summary.x[1], -0.5, 1e-6) << "seed " << seed;
  }
}

TEST(PaperNelderMead, StaysInOnePlaneOfTheThreeDimensionalSpaceOnceTheBoxNoLongerDeflectsIt) {
  // Every new point is an affine combination of B, G and W, so the triangle only
  // leaves its plane when E is projected onto the box. After the last
  // projection, every point evaluated in later iterations lies in one plane,
  // and the minimum, which is off that plane, is never reached.
  const Eigen::Vector3d minimum(1.0, 2.0, 3.0);
  auto f = [&minimum](const Eigen::VectorXd& x) { return (x - minimum).squaredNorm(); };
  const Bounds bounds = Cube(3, -5.0, 5.0);
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    PaperNelderMeadOptions options;
    options.seed = seed;
    const RecordedRun run(f, bounds, options);
    EXPECT_GT(run.summary.f, 1e-6) << "seed " << seed << " reached the off-plane minimum";

    int last_projected = -1;
    for (std::size_t i = 0; i < run.evaluations.size(); ++i) {
      if (OnTheBox(run.evaluations[i].x, bounds)) last_projected = static_cast<int>(i);
    }
    // Start after the iteration of the last projection: its later points may
    // still mix the projected E in.
    const auto end_of_that_iteration =
        std::upper_bound(run.iteration_ends.begin(), run.iteration_ends.end(), last_projected);
    if (end_of_that_iteration == run.iteration_ends.end()) continue;
    const std::size_t from = static_cast<std::size_t>(*end_of_that_iteration);
    if (run.evaluations.size() - from < 100) continue;  // Too few points to mean much.
    ++checked;
    EXPECT_LT(ThirdOverFirstSingularValue(run.evaluations, from), 1e-9) << "seed " << seed;
  }
  EXPECT_GE(checked, 15);
}

TEST(PaperNelderMead, MissesAnOffPlaneMinimumThatTextbookNelderMeadFinds) {
  const Eigen::Vector3d minimum(10.0, 20.0, 5.0);
  auto f = [&minimum](const Eigen::VectorXd& x) { return (x - minimum).squaredNorm(); };
  const Bounds bounds = Cube(3, 0.0, 30.0);  // The paper's gain box.
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    PaperNelderMeadOptions paper_options;
    paper_options.seed = seed;
    OptimizerSummary paper;
    PaperNelderMead(f, bounds, paper_options, &paper);
    NelderMeadOptions options;
    options.seed = seed;
    OptimizerSummary textbook;
    NelderMead(f, bounds, options, &textbook);

    EXPECT_GT(paper.f, 1e-3) << "seed " << seed;
    EXPECT_LT(textbook.f, 1e-10) << "seed " << seed;
  }
}

// Replays the recorded evaluations against a literal transcription of Figure 6:
// every evaluated point must be the one the pseudo-code computes next, and
// every iteration must use the evaluations it implies.
std::map<int, int> ReplayFigure6(const RecordedRun& run, const Bounds& bounds) {
  const std::vector<Evaluation>& evals = run.evaluations;
  std::size_t next = 0;
  auto take = [&](const Eigen::VectorXd& expected, const char* name) {
    EXPECT_LT(next, evals.size()) << name;
    if (next >= evals.size()) return Evaluation{expected, kInf};
    const Evaluation& e = evals[next++];
    EXPECT_LE((e.x - expected).norm(), 1e-12 * (1.0 + expected.norm())) << name << " at evaluation " << next;
    return e;
  };
  auto sort = [](std::array<Evaluation, 3>* t) {
    std::stable_sort(t->begin(), t->end(),
                     [](const Evaluation& a, const Evaluation& b) { return a.f < b.f; });
  };

  std::array<Evaluation, 3> t = {evals.at(0), evals.at(1), evals.at(2)};
  next = 3;
  sort(&t);
  std::map<int, int> histogram;  // evaluations per iteration -> iterations
  for (int end : run.iteration_ends) {
    const std::size_t begin = next;
    Evaluation& b = t[0];
    Evaluation& g = t[1];
    Evaluation& w = t[2];
    const Eigen::VectorXd m = (b.x + g.x) / 2.0;
    const Evaluation e = take((3.0 * m - 2.0 * w.x).cwiseMax(bounds.lower).cwiseMin(bounds.upper), "E");
    if (e.f < g.f) {
      w = e;
    } else {
      const Evaluation r = take((m + e.x) / 2.0, "R");
      if (r.f < w.f) w = r;
      if (r.f >= g.f) {
        const Eigen::VectorXd c1_x = (w.x + m) / 2.0;
        const Eigen::VectorXd c2_x = (r.x + m) / 2.0;
        Evaluation c = take(c1_x, "C1");
        if (c1_x != c2_x) {
          const Evaluation c2 = take(c2_x, "C2");
          if (c2.f < c.f) c = c2;
        }
        if (c.f < w.f) {
          w = c;
        } else {
          const Eigen::VectorXd s_x = (b.x + w.x) / 2.0;
          g = take(m, "M");
          w = take(s_x, "S");
        }
      }
    }
    EXPECT_EQ(static_cast<int>(next), end);
    ++histogram[static_cast<int>(next - begin)];
    sort(&t);
  }
  EXPECT_EQ(static_cast<int>(next), run.summary.evaluations);
  EXPECT_EQ(evals.size(), next);
  return histogram;
}

TEST(PaperNelderMead, EvaluatesExactlyThePointsOfTheFigure6PseudoCode) {
  std::map<int, int> histogram;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    PaperNelderMeadOptions options;
    options.seed = seed;
    const Bounds bounds = Cube(2, -2.0, 2.0);
    const RecordedRun run(Rosenbrock, bounds, options);
    for (const auto& [count, iterations] : ReplayFigure6(run, bounds)) histogram[count] += iterations;
  }
  // Every branch of the pseudo-code was exercised: 1 (E accepted), 2 (R), 3 or 4
  // (contraction), 5 or 6 (shrink), and nothing else.
  for (const auto& [count, iterations] : histogram) {
    EXPECT_TRUE(count >= 1 && count <= 6) << count;
  }
  EXPECT_GT(histogram[1], 0);
  EXPECT_GT(histogram[2], 0);
  EXPECT_GT(histogram[3] + histogram[4], 0);
  EXPECT_GT(histogram[5] + histogram[6], 0);
}

TEST(PaperNelderMead, EvaluatesExactlyThePointsOfTheFigure6PseudoCodeInThreeDimensionsWithProjection) {
  const Eigen::Vector3d minimum(20.9, 26.6, 12.5);
  auto f = [&minimum](const Eigen::VectorXd& x) { return (x - minimum).cwiseAbs().sum(); };
  const Bounds bounds = Cube(3, 0.0, 30.0);
  PaperNelderMeadOptions options;
  options.seed = 4;
  options.starts = 1;
  const RecordedRun run(f, bounds, options);
  ReplayFigure6(run, bounds);
  int projected = 0;
  for (const Evaluation& e : run.evaluations) projected += OnTheBox(e.x, bounds) ? 1 : 0;
  EXPECT_GT(projected, 0);  // The replay did cover the projection of E.
}

TEST(PaperNelderMead, ShrinksEveryIterationOfAConstantFunctionForSixEvaluations) {
  // f(E) = f(G), f(R) = f(W), f(C) = f(W): no strict improvement ever, so every
  // iteration evaluates E, R, C1, C2, M and S.
  auto f = [](const Eigen::VectorXd&) { return 1.0; };
  PaperNelderMeadOptions options;
  options.max_iterations = 20;
  OptimizerSummary summary;
  PaperNelderMead(f, Cube(3, 0.0, 30.0), options, &summary);

  EXPECT_EQ(summary.evaluations, 3 + 6 * 20);
  EXPECT_EQ(summary.iterations, 20);
}

TEST(PaperNelderMead, GivesBitIdenticalResultsForTheSameSeed) {
  PaperNelderMeadOptions options;
  options.seed = 77;
  options.starts = 3;
  OptimizerSummary a, b;
  PaperNelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &a);
  PaperNelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.f, b.f);
  EXPECT_EQ(a.evaluations, b.evaluations);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  for (std::size_t i = 0; i < a.trace.size(); ++i) EXPECT_EQ(a.trace[i].best_x, b.trace[i].best_x);

  options.seed = 78;
  const RecordedRun one(Rosenbrock, Cube(2, -2.0, 2.0), options);
  options.seed = 79;
  const RecordedRun two(Rosenbrock, Cube(2, -2.0, 2.0), options);
  EXPECT_NE(one.evaluations.front().x, two.evaluations.front().x);
}

TEST(PaperNelderMead, RunsTheIterationsOfEveryStartAndKeepsTheBest) {
  std::vector<TracePoint> trace;
  PaperNelderMeadOptions options;
  options.starts = 4;
  options.max_iterations = 30;
  OptimizerSummary summary;
  PaperNelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary,
                  [&trace](const TracePoint& p) { trace.push_back(p); });
  EXPECT_EQ(summary.starts, 4);
  EXPECT_EQ(summary.iterations, 120);
  ASSERT_EQ(trace.size(), 120u);
  EXPECT_EQ(trace.back().best_f, summary.f);
  for (std::size_t i = 1; i < trace.size(); ++i) EXPECT_LE(trace[i].best_f, trace[i - 1].best_f);
}

TEST(PaperNelderMead, NeverReturnsARejectedPoint) {
  // Rejected (an "unstable loop") wherever x0 + x1 > 1; the minimum (1, 1) is in the rejected region.
  auto f = [](const Eigen::VectorXd& x) { return x[0] + x[1] > 1.0 ? kInf : Rosenbrock(x); };
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    PaperNelderMeadOptions options;
    options.seed = seed;
    OptimizerSummary summary;
    PaperNelderMead(f, Cube(2, -2.0, 2.0), options, &summary);
    if (!summary.IsUsable()) {
      EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
      continue;
    }
    EXPECT_LE(summary.x[0] + summary.x[1], 1.0);
    EXPECT_TRUE(std::isfinite(summary.f));
    EXPECT_EQ(summary.f, f(summary.x));
  }
}

TEST(PaperNelderMead, EndsWithNoFeasiblePointWhenEveryPointIsRejected) {
  auto f = [](const Eigen::VectorXd&) { return std::numeric_limits<double>::quiet_NaN(); };
  PaperNelderMeadOptions options;
  options.max_iterations = 10;
  OptimizerSummary summary;
  PaperNelderMead(f, Cube(3, 0.0, 30.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kNoFeasiblePoint);
  EXPECT_FALSE(summary.IsUsable());
  EXPECT_EQ(summary.rejected_evaluations, summary.evaluations);
  EXPECT_EQ(summary.evaluations, 3 + 6 * 10);
}

TEST(PaperNelderMead, StopsExactlyAtTheEvaluationBudget) {
  PaperNelderMeadOptions options;
  options.max_evaluations = 40;
  OptimizerSummary summary;
  PaperNelderMead(Rosenbrock, Cube(2, -2.0, 2.0), options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kMaxEvaluations);
  EXPECT_EQ(summary.evaluations, 40);
  EXPECT_TRUE(summary.IsUsable());
}

void ExpectInvalid(const PaperNelderMeadOptions& options, const Bounds& bounds, const std::string& field) {
  int calls = 0;
  auto f = [&calls](const Eigen::VectorXd& x) {
    ++calls;
    return x.squaredNorm();
  };
  OptimizerSummary summary;
  PaperNelderMead(f, bounds, options, &summary);
  EXPECT_EQ(summary.termination, TerminationType::kInvalidOptions);
  EXPECT_NE(summary.message.find(field), std::string::npos) << summary.message;
  EXPECT_EQ(calls, 0);
}

TEST(PaperNelderMead, RejectsZeroIterations) {
  PaperNelderMeadOptions options;
  options.max_iterations = 0;
  ExpectInvalid(options, Cube(3, 0.0, 30.0), "PaperNelderMeadOptions.max_iterations = 0");
}

TEST(PaperNelderMead, RejectsANegativeEvaluationBudget) {
  PaperNelderMeadOptions options;
  options.max_evaluations = -3;
  ExpectInvalid(options, Cube(3, 0.0, 30.0), "PaperNelderMeadOptions.max_evaluations = -3");
}

TEST(PaperNelderMead, RejectsZeroStarts) {
  PaperNelderMeadOptions options;
  options.starts = 0;
  ExpectInvalid(options, Cube(3, 0.0, 30.0), "PaperNelderMeadOptions.starts = 0");
}

TEST(PaperNelderMead, RejectsBoundsWhoseLowerIsNotBelowUpper) {
  ExpectInvalid(PaperNelderMeadOptions(), Cube(3, 30.0, 0.0),
                "Bounds.lower[0] = 30 must be < Bounds.upper[0]");
}

}  // namespace
}  // namespace pidlab
