#pragma once
// The method of steps without a stored interpolant (delayed_loop.h,
// docs/deadtime.md, "The exact steps"). On a grid t_j = j h with L = m h, the
// history of the state itself carries the delayed input: on [t_j, t_j + h]
// the stack [w(t); w(t - L); w(t - 2L); ...] obeys a constant block
// bidiagonal system (m on the diagonal, C = e kq below it; the oldest
// component, before L, has no input), so
//
//   w(t_j + tau) = sum_{i >= 0} Psi_i(tau) w(t_j - i L),
//
// Psi_i the first block column of that system's exponential, the same
// blocks for every j (a block Toeplitz exponential). Exact up to rounding and
// the blocks dropped once below 1e-17 of the sum (they fall as (|C| h)^i / i!,
// so h is chosen with |C| h of order 1), where the Hermite store's h follows
// the loop's fastest rate: tens of nodes per delay instead of thousands.
// Samples fall on the nodes (h divides ts and L), so it applies when L / ts is
// a ratio of small integers and no disturbance breakpoint lies inside the
// horizon.

#include <vector>

#include "pidlab/evaluation/delayed_loop.h"

namespace pidlab::evaluation::internal {

/// The samples y of SampleDelayedLoop by the exact steps, and in *trace the
/// pieces and h (nothing recorded); false where they do not apply: then the
/// Hermite store runs.
bool SampleExactDelayedLoop(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts,
                            int num_samples, std::vector<double>* y, DelayedTrace* trace);

}  // namespace pidlab::evaluation::internal
