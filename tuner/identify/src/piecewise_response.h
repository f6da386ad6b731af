#pragma once
// The exact response of a model to a recorded input on any time grid, with
// a zero- or first-order hold and a given initial state: identify.cc,
// internal (docs/identify.md, "Non-uniform sampling", "Intersample behaviour
// and the initial condition").

#include <vector>

#include "pidlab/identify/identify.h"
#include "pidlab/identify/process_model.h"

namespace pidlab::identify::internal {

/// How the record's input continues before t[0] and from where the state starts.
struct PiecewiseStart {
  /// The input before t[0] (what the delay shows over [t[0], t[0] + Td)).
  double input_before = 0.0;
  /// x(t[0]) in the coordinates of plant_sim::Realize(model's transfer
  /// function); empty: zero.
  std::vector<double> state;
};

/// yhat_k = C x(t_k) (without y0) of `model`, its input the record's du
/// delayed by Td: with Intersample::kZoh du[j] is held on [t_j + Td,
/// t_(j+1) + Td); with kFoh it goes linearly from du[j] to du[j+1] over that
/// interval (and is held after the last sample); before t[0] + Td it is
/// start.input_before. Each interval [t_k, t_(k+1)) is integrated exactly
/// piece by piece between the delayed input's breakpoints inside it, every
/// piece by its own e^(M h), M = [[A, B], [0, 0]] (ZOH) or [[A, B, 0], [0, 0,
/// 1], [0, 0, 0]] (FOH), cached by the exact double h. On a uniform grid the
/// ZOH response is DiscretePlant's up to rounding. t strictly increasing, of
/// du's length. Throws std::invalid_argument if the model is not a valid
/// strictly proper plant, Td is negative or not finite, or start.state is
/// not of the model's order.
std::vector<double> SimulatePiecewise(const ProcessModel& model, const std::vector<double>& t,
                                      const std::vector<double>& du, Intersample hold,
                                      const PiecewiseStart& start = {});

/// The order of `model`'s realisation (the length of PiecewiseStart::state).
int ModelOrder(const ProcessModel& model);

/// The steady state x = -A^-1 B v of `model` for a constant input v; false
/// if A is singular (an integrator) and v != 0.
bool SteadyState(const ProcessModel& model, double v, std::vector<double>* state);

/// With InitialCondition::kEstimate: the state x(t[0]) whose free response
/// best fits target - yhat (least squares over the model's n free responses,
/// column-pivoting QR: variable projection, so the state is not a parameter
/// Ceres sees); adds that free response to *yhat and returns the state.
std::vector<double> FitInitialState(const ProcessModel& model, const std::vector<double>& t, Intersample hold,
                                    const std::vector<double>& target, std::vector<double>* yhat);

}  // namespace pidlab::identify::internal
