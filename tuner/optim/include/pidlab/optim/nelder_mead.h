#pragma once
// Nelder-Mead simplex minimisation in a box: pidlab's default optimiser.
//
// The textbook method (Nelder & Mead 1965, in the form of Lagarias et al.
// 1998) on a proper simplex of n + 1 vertices in n dimensions. Each iteration
// sorts the vertices, f(x_1) <= ... <= f(x_{n+1}), takes the centroid c of the
// best n and tries, along the line from the worst vertex through c,
//   reflection        x_r  = c + rho (c - x_{n+1})           accept if f_1 <= f_r < f_n
//   expansion         x_e  = c + rho chi (c - x_{n+1})       if f_r < f_1: better of x_e, x_r
//   outside contr.    x_oc = c + rho gamma (c - x_{n+1})     if f_n <= f_r < f_{n+1}: accept if f_oc <= f_r
//   inside contr.     x_ic = c - gamma (c - x_{n+1})         if f_r >= f_{n+1}: accept if f_ic < f_{n+1}
//   shrink            x_i  = x_1 + sigma (x_i - x_1), i > 1  otherwise (n evaluations)
// with (rho, chi, gamma, sigma) = (1, 2, 1/2, 1/2), or with `adaptive` the
// dimension-dependent values of Gao & Han (2012): (1, 1 + 2/n, 3/4 - 1/(2n),
// 1 - 1/n), which keep the method effective for larger n. For n = 1 the
// adaptive shrink would be 0, so the standard values are used.
//
// Bounds: every candidate is projected onto the box (coordinate-wise clamp)
// before it is evaluated. Projection keeps the method simple and never wastes
// an evaluation outside the box; its known cost is that vertices clamped onto
// the same face make the simplex degenerate (flat in that coordinate), which is
// harmless when the minimum lies on that face and otherwise left to the
// restart on convergence, which rebuilds a full-dimensional simplex.
//
// Rejected points (+inf or NaN) are worse than every finite value, so the
// simplex moves away from them by the rules above (a rejected reflection leads
// to an inside contraction, then a shrink towards the best vertex). Unlike a
// box face, a wall of rejected points is not projected onto: when the
// minimum lies on such a wall the simplex cannot slide along it and may stop
// short of the constrained minimum (in the unit test, by 3e-4 of the box width).
//
// Initial simplex: a base point p (x0, or uniform in the box), then
// p + h_j e_j with h_j = initial_step_fraction * (upper_j - lower_j), the
// sign flipped where +h_j would leave the box. A rejected base point (x0
// included) is replaced by uniform draws in the box; a rejected edge vertex is
// retried at -h_j, +h_j/2, -h_j/2, +h_j/4, ... (clamped to the box). Each
// vertex gets at most 1 + max_initial_redraws evaluations; a vertex still
// rejected after them stays in the simplex with f = +inf. A start whose every
// vertex is rejected is abandoned; if every start is abandoned the result is
// kNoFeasiblePoint.
//
// Convergence (checked before each iteration): the simplex diameter
// max_i max_j |x_ij - x_1j| / (upper_j - lower_j) <= x_tolerance, and the
// value spread f_{n+1} - f_1 <= f_tolerance * (1 + |f_1|) (or, when some vertex
// is rejected, the diameter test alone: the simplex straddles the edge of the
// feasible region more finely than x_tolerance). On convergence the simplex is
// rebuilt around the best vertex with the initial step, up to
// restarts_on_convergence times, which guards against premature collapse.
//
// Multi-start: `starts` independent runs; the first uses x0 when given. Start
// s draws from a random stream of its own (seeded from seed and s; start 0
// from seed itself) and gets a fixed share of max_evaluations: floor(max /
// starts), plus one for the first max % starts starts (a start whose share
// is 0 is not run). A start that converges early leaves its share unused.
// So the starts are independent: `parallel_for` may run them at the same
// time (one per LCM trio) and the result is bit for bit the same however
// they run. They are merged in start order: the result is the best feasible
// point over all starts (ties: the earlier start), evaluations and
// iterations are summed, the trace is start 1's iterations, then start 2's,
// and so on, and progress is reported as the starts are merged. There is no
// speculation inside a start (no reflection, expansion and contraction
// evaluated together): it would cost up to 3 evaluations per iteration for
// about 1.5 used, for a speed-up only while trios are idle.
//
// Termination: that of the start that produced the best point: kConverged if
// it converged, kMaxIterations if it ran out of iterations, kMaxEvaluations
// if its share of the evaluation budget stopped it (its best point is still
// returned); kNoFeasiblePoint if no evaluated point was feasible.

#include <cstdint>
#include <string>

#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {

struct NelderMeadOptions {
  /// Initial point of the first start; empty = uniform random in the bounds.
  /// Must be finite, of the bounds' size and inside them.
  Eigen::VectorXd x0;
  /// Initial simplex edge as a fraction of each bound width, in (0, 1].
  double initial_step_fraction = 0.1;
  /// Iteration budget of each start (restarts included), >= 1.
  int max_iterations = 1000;
  /// Hard cap on objective calls over all starts, >= 1, shared out between
  /// the starts in fixed parts (see above).
  int max_evaluations = 5000;
  /// Converged when the simplex diameter, relative to the bound widths, is at
  /// most this; finite, >= 0.
  double x_tolerance = 1e-8;
  /// ... and the spread of f over the simplex is at most f_tolerance * (1 + |f_best|); finite, >= 0.
  double f_tolerance = 1e-10;
  /// Gao & Han (2012) dimension-dependent coefficients instead of (1, 2, 1/2, 1/2).
  bool adaptive = false;
  /// Independent starts, >= 1; the first uses x0 if given, the others are random.
  int starts = 1;
  /// Simplex rebuilds around the best vertex after convergence, per start, >= 0.
  int restarts_on_convergence = 1;
  /// Extra tries for a rejected initial vertex, >= 0.
  int max_initial_redraws = 10;
  /// Seed of the random streams (initial points).
  std::uint64_t seed = 1;
  /// Runs the starts (empty: one after the other). Never changes the result.
  ParallelFor parallel_for;

  /// Checks every field; on failure names the field, its value and the rule.
  /// x0 is checked against the bounds by NelderMead itself.
  bool IsValid(std::string* error) const;
};

/// Minimises f over `bounds`. Never throws (exceptions from f propagate).
void NelderMead(const ObjectiveFunction& f, const Bounds& bounds, const NelderMeadOptions& options,
                OptimizerSummary* summary, const ProgressCallback& progress = nullptr);

}  // namespace pidlab::optim
