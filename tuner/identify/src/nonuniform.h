#pragma once
// The exact zero-order-hold response on a non-uniform time grid: identify.cc,
// internal (docs/identify.md, "Non-uniform sampling").

#include <vector>

#include "pidlab/identify/process_model.h"

namespace pidlab::identify::internal {

/// yhat_k = C x(t_k) (without y0) of `model` from a zero state at t[0], its
/// input du[j] held on [t_j + Td, t_(j+1) + Td) and 0 before t[0] + Td. Each
/// interval [t_k, t_(k+1)) is integrated exactly piece by piece between the
/// delayed input's breakpoints that fall inside it, every piece by its own
/// e^([[A, B], [0, 0]] h) (cached by the exact double h). On a uniform grid it
/// is DiscretePlant's response up to rounding. t strictly increasing, of
/// du's length. Throws std::invalid_argument if the model is not a valid
/// strictly proper plant or Td is negative or not finite.
std::vector<double> SimulateNonUniform(const ProcessModel& model, const std::vector<double>& t,
                                       const std::vector<double>& du);

}  // namespace pidlab::identify::internal
