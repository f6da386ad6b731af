#pragma once
// Types shared by the derivative-free, plant-independent optimisers
// (NelderMead, PaperNelderMead, GeneticAlgorithm, PsoGsa).
//
// Every optimiser minimises an ObjectiveFunction over a box (Bounds) and
// follows the same contract:
//   * Only points inside the box are ever evaluated, so the result lies inside
//     the box too.
//   * A non-finite objective value (+inf, -inf or NaN) marks a rejected point,
//     e.g. an unstable closed loop. It counts as an evaluation and as a
//     rejected evaluation, compares worse than every finite value, and is never
//     the best point nor the returned result.
//   * The best point is the best feasible point ever evaluated, over all
//     starts; ties keep the earlier point.
//   * Options are validated first: invalid options (or bounds, or an empty
//     objective) give TerminationType::kInvalidOptions and a message naming the
//     field, its value and the rule broken. Nothing throws, except exceptions
//     thrown by the objective itself, which propagate unchanged.
//   * Randomness comes from a std::mt19937_64 seeded from the options and
//     mapped to [0, 1) without std::*_distribution, so a seed gives the same
//     bits with every standard library.
//   * max_evaluations is a hard cap on calls to the objective, over all starts.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace pidlab::optim {

/// The function to minimise. Returns +inf (or NaN) to reject a point.
using ObjectiveFunction = std::function<double(const Eigen::VectorXd& x)>;

/// The search box lower <= x <= upper (inclusive).
struct Bounds {
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;

  /// Same non-zero size, all values finite, lower[i] < upper[i] for every i.
  bool IsValid(std::string* error) const;
};

enum class TerminationType {
  kConverged,        // The algorithm's own convergence test passed.
  kMaxIterations,    // The iteration (generation) budget ran out.
  kMaxEvaluations,   // The evaluation budget ran out.
  kNoFeasiblePoint,  // Every evaluated point was rejected: the result is unusable.
  kInvalidOptions,   // Nothing was evaluated; see the message.
};

/// "CONVERGED", "MAX_ITERATIONS", "MAX_EVALUATIONS", "NO_FEASIBLE_POINT", "INVALID_OPTIONS".
std::string ToString(TerminationType type);

/// The state after one iteration (generation) of an optimiser.
struct TracePoint {
  int iteration = 0;                                        // 1-based, counted over all starts.
  int evaluations = 0;                                      // Objective calls so far, over all starts.
  double best_f = std::numeric_limits<double>::infinity();  // Best feasible value so far; +inf if none.
  Eigen::VectorXd best_x;                                   // Its point; empty if none.
};

/// Optional observer, called once per completed iteration with the new trace point.
using ProgressCallback = std::function<void(const TracePoint&)>;

/// Runs body(0), ..., body(count - 1), in any order and possibly at the same
/// time (e.g. one thread per LCM trio), and returns when all are done. An
/// exception thrown by a body is rethrown (the one of the lowest index).
/// Empty: one after the other on the calling thread. The optimisers make
/// their results independent of it: the same bits whatever runs the bodies.
using ParallelFor = std::function<void(int count, const std::function<void(int index)>& body)>;

/// Runs a ParallelFor, or the loop when it is empty.
void RunParallel(const ParallelFor& parallel_for, int count, const std::function<void(int index)>& body);

struct OptimizerSummary {
  Eigen::VectorXd x;  // Best feasible point (inside the bounds); empty if none was found.
  double f = std::numeric_limits<double>::infinity();  // Objective at x; +inf if none.
  int iterations = 0;                                  // Completed iterations, over all starts.
  int evaluations = 0;                                 // Objective calls, over all starts.
  int rejected_evaluations = 0;                        // Calls that returned a non-finite value.
  int starts = 1;                                      // Starts begun.
  TerminationType termination = TerminationType::kInvalidOptions;
  std::string message;
  std::vector<TracePoint> trace;  // Best-so-far after every completed iteration.

  /// A feasible point was found (x is set and f is finite).
  bool IsUsable() const;
  /// One line: termination, f, x, iterations, evaluations, starts and message.
  std::string BriefReport() const;
};

}  // namespace pidlab::optim
