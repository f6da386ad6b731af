#pragma once
// What evaluate.cc and metrics.cc share inside the evaluation library.

#include "pidlab/evaluation/evaluation.h"

namespace pidlab::evaluation::internal {

/// sum_m |y_L(m ts)| of the load response of a strictly stable loop: the
/// continuous loop built with r = 0 (no reference state, no derivative kick)
/// and the step as its exosystem state, or the sampled loop run with r_k = 0.
/// `discrete` is the plant at dt (sampled loop only).
double LoadIaeOfStableLoop(const StateSpace& realization, const DiscretePlant* discrete,
                           const PidGains& gains, const LoopOptions& options, const Disturbance& step);

}  // namespace pidlab::evaluation::internal
