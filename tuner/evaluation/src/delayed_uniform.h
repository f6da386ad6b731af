#pragma once
// The method of steps on the uniform grid (delayed_loop.h, docs/deadtime.md):
// when the step h divides the dead time (L = m h, as DelayedStepSize chooses
// it) and no disturbance breakpoint lies inside the horizon, every node is
// t_j = j h and every piece's delayed input is one stored piece whole, the
// piece j - m. The step over a piece is then one map for the whole run,
//
//   w_{j+1} = phi w_j + gamma_d d_{j-m},
//
// d = (q, q', q, q') the stored piece's Hermite data at its ends, and the
// stored pieces fit a ring of m: one matrix exponential per run (and one per
// distinct offset of a sample inside a piece), no allocation per piece. The
// same pieces, the same cubic Hermite store and the same exact steps as the
// node-by-node integrator: the samples agree to rounding.

#include <vector>

#include "pidlab/evaluation/delayed_loop.h"

namespace pidlab::evaluation::internal {

/// True when the uniform grid applies: h divides the dead time to within
/// 1e-9 h, and a piecewise-constant disturbance has no breakpoint in
/// (0, t_end].
bool UniformGridApplies(const DelayedClosedLoop& loop, const Disturbance& disturbance, double h,
                        double t_end_s);

/// SampleDelayedLoop's samples (and trace) on the uniform grid of step h
/// (UniformGridApplies; at most kMaxDelayedPieces pieces, checked by the
/// caller).
void SampleUniformDelayedLoop(const DelayedClosedLoop& loop, double h, double ts, int num_samples,
                              std::vector<double>* y, DelayedTrace* trace);

}  // namespace pidlab::evaluation::internal
