#pragma once
// Multi-start from a space-filling design: a search whose result does not
// depend on the luck of a few random starts.
//
//  1. Design: `design_points` points of a Sobol' sequence (sobol.h) in the
//     unit cube, digitally shifted by the seed when `scramble`, mapped to the
//     box coordinate by coordinate through the warp
//        x_j = lower_j + width_j (e^(w u_j) - 1) / (e^w - 1)     (w = warp; w = 0: x = lower + width u)
//     A positive warp spreads the points evenly in log-scale over the lower
//     part of the box: with w = ln(10^4) as many points lie in the first
//     1/10^4 of each width as in the last half. All of them are evaluated
//     (through `parallel_for`: they are independent).
//  2. Selection: the design points in increasing f (ties: design order); a
//     point is kept unless it lies within `min_separation` (in u, max norm) of
//     one kept already; at most `starts` are kept. So the starts lie in
//     different parts of the box, not all in the one basin that the best few
//     points share.
//  3. Polish: from each kept point, NelderMead (options `polish`) in the
//     warped coordinates u in [0, 1]^n, one start each, with a fixed share of
//     what the design left of max_evaluations (as NelderMead's own starts:
//     floor(rest / starts), one more for the first rest % starts). The
//     starts are independent and may run at the same time; the result is the
//     same bits however they run.
//
// The result is the best feasible point over the design and every polish
// (ties: the earlier one: design, then start 1, 2, ...). The polished points,
// best first, are returned in *minima for a second-stage refinement (the
// tuner runs Ceres from the best few).
//
// Trace: one point for the design (iteration 1), then each start's
// iterations in start order, best-so-far over everything before.
// Termination: kNoFeasiblePoint if no point was feasible; otherwise that of
// the start that gave the best point (kConverged, kMaxIterations,
// kMaxEvaluations), or kMaxIterations when the design itself gave it (no
// polish improved on it).

#include <cstdint>
#include <string>
#include <vector>

#include "pidlab/optim/nelder_mead.h"
#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {

struct MultiStartOptions {
  /// Points of the design, >= 1 and <= 2^20; a power of two keeps the
  /// Sobol' net property (every dyadic box of the right volume holds one).
  int design_points = 1024;
  /// w of the warp above: 0 (linear) to 40; the same for every coordinate.
  double warp = 0.0;
  /// Polished starts, >= 1 (fewer when the design has fewer feasible,
  /// separated points).
  int starts = 8;
  /// Smallest distance between two starts in the warped unit cube (max norm), [0, 1).
  double min_separation = 0.05;
  /// Options of each polish in the unit cube. Its x0, starts, seed,
  /// max_evaluations and parallel_for are set by MultiStart.
  NelderMeadOptions polish = DefaultPolish();
  /// Hard cap on objective calls: the design, then the polishes; > design_points.
  int max_evaluations = 20000;
  /// Digital shift of the Sobol' points from `seed`; false: the seed-free sequence.
  bool scramble = true;
  std::uint64_t seed = 1;
  /// Runs the design evaluations, then the starts. Never changes the result.
  ParallelFor parallel_for;

  static NelderMeadOptions DefaultPolish() {
    NelderMeadOptions o;
    o.initial_step_fraction = 0.05;
    o.restarts_on_convergence = 1;
    return o;
  }
  /// Checks every field (and polish); names the field, its value and the rule.
  bool IsValid(std::string* error) const;
};

/// One polished start.
struct LocalMinimum {
  Eigen::VectorXd start;  // the design point it started from (box coordinates)
  Eigen::VectorXd x;      // its best point (box coordinates); empty if none was feasible
  double f = std::numeric_limits<double>::infinity();
  int evaluations = 0;
  TerminationType termination = TerminationType::kNoFeasiblePoint;
};

/// Minimises f over `bounds`. Never throws (exceptions from f propagate).
/// `minima` (optional): the polished starts, by increasing f (ties: start order).
void MultiStart(const ObjectiveFunction& f, const Bounds& bounds, const MultiStartOptions& options,
                OptimizerSummary* summary, const ProgressCallback& progress = nullptr,
                std::vector<LocalMinimum>* minima = nullptr);

}  // namespace pidlab::optim
