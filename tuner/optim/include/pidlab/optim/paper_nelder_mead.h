#pragma once
// The "Nelder-Mead" variant of Assawinchaichote & Sinlapakun (Section IV and
// the pseudo-code of Figure 6), reproduced literally for comparison. Prefer
// NelderMead (nelder_mead.h) for real work.
//
// CAVEAT: the paper keeps a triangle of three points B, G, W whatever the
// dimension. For the PID gains (n = 3) three points span only a plane, and
// every new point is an affine combination of B, G and W, so the search can
// never leave the plane through its initial three random points: whatever
// lies off that plane is unreachable. The only way off the plane is the
// projection of E onto the box (below). For n = 2 the triangle is a proper
// simplex and the method behaves like a Nelder-Mead with an "expansion first"
// rule; for n = 1 it works on a segment.
//
// One run: K1, K2, K3 uniform in the box; sort so f(B) <= f(G) <= f(W); then
// max_iterations times (the paper's i_max = 100, no other stopping test):
//   M = (B + G) / 2;  E = 3M - 2W;  evaluate f(E)
//   if f(E) < f(G): W <- E
//   else:
//     R = (M + E) / 2;  evaluate f(R)
//     if f(R) < f(W): W <- R
//     if f(R) >= f(G):
//       C1 = (W + M) / 2, C2 = (R + M) / 2   (W as it is now, i.e. R if just replaced)
//       C = the one of C1, C2 with the smaller f (C1 on a tie)
//       if f(C) < f(W): W <- C
//       else: S = (B + W) / 2;  G <- M;  W <- S   (f(M) and f(S) evaluated)
//   re-sort B, G, W (stable: ties keep the order B, G, W)
// With E = 3M - 2W, R = (M + E)/2 = 2M - W is the classic reflection and E
// the classic expansion; unlike textbook Nelder-Mead, the expansion is tried
// first and accepted when merely better than G.
//
// Reading of the pseudo-code, where it is ambiguous:
//   * "if f(R) >= f(G)" is tested after, and independently of, "if f(R) <
//     f(W)"; C1 uses the current W, so when R has just replaced W, C1 = C2 =
//     (R + M)/2 and that point is evaluated once.
//   * The shrink needs f(M) and f(S) to re-sort, so it costs two evaluations.
// Evaluations: 3 for the initial triangle, then per iteration
//   1  E accepted;
//   2  R evaluated, f(R) < f(G) (W <- R, no contraction);
//   3  W <- R, contraction (C1 = C2) accepted;     5  ... rejected, shrink;
//   4  W kept, contraction (C1, C2) accepted;      6  ... rejected, shrink.
// So one start costs at most 3 + 6 * max_iterations evaluations.
//
// Bounds: only E can leave the box (every other point is a midpoint of two
// points in it); E is projected onto the box (coordinate-wise clamp) before
// it is evaluated, and R = (M + E)/2 uses the projected E.
//
// Rejected points (+inf or NaN) compare worse than every finite value; the
// initial points are not re-drawn (the paper does not), so a start whose three
// points are rejected relies on later moves to find a feasible point.
//
// Multi-start: `starts` independent runs from one seeded random stream; the
// result is the best feasible point over all of them. Termination is
// kMaxIterations when every start ran its max_iterations (the paper has no
// convergence test, so kConverged never occurs), kMaxEvaluations when the
// evaluation budget stopped the call, kNoFeasiblePoint if nothing feasible was
// evaluated.

#include <cstdint>
#include <string>

#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {

struct PaperNelderMeadOptions {
  /// Iterations of the Figure 6 loop per start (the paper's i_max), >= 1.
  int max_iterations = 100;
  /// Hard cap on objective calls over all starts, >= 1 (default never binds: 3 + 6 * 100 per start).
  int max_evaluations = 5000;
  /// Independent random starts, >= 1 (the paper uses one).
  int starts = 1;
  /// Seed of the random stream (initial triangles).
  std::uint64_t seed = 1;

  /// Checks every field; on failure names the field, its value and the rule.
  bool IsValid(std::string* error) const;
};

/// Minimises f over `bounds` with the paper's three-point method. Never throws
/// (exceptions from f propagate).
void PaperNelderMead(const ObjectiveFunction& f, const Bounds& bounds, const PaperNelderMeadOptions& options,
                     OptimizerSummary* summary, const ProgressCallback& progress = nullptr);

}  // namespace pidlab::optim
