#include "pidlab/plant_sim/discrete_plant.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pidlab/plant_sim/matrix_exp.h"

namespace pidlab {

DiscretePlant::DiscretePlant(const TransferFunction& tf, double dt_s) : dt_s_(dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    throw std::invalid_argument("dt " + std::to_string(dt_s) + " s must be positive and finite");
  if (tf.RelativeDegree() < 1)
    throw std::invalid_argument("plant " + tf.ToString() + " must be strictly proper for a sampled loop");
  const StateSpace ss = Realize(tf);
  Eigen::MatrixXd gamma;
  ZeroOrderHold<double>(ss.a, Eigen::MatrixXd(ss.b), dt_s, &phi_, &gamma);
  gamma_ = gamma.col(0);
  c_ = ss.c;
  state_.assign(static_cast<std::size_t>(ss.order()), 0.0);
  next_ = state_;
}

double DiscretePlant::Output() const { return OutputOf(c_, state_); }

void DiscretePlant::Step(double input) {
  ZohStep(phi_, gamma_, state_, input, &next_);
  state_.swap(next_);
}

void DiscretePlant::Reset() { std::fill(state_.begin(), state_.end(), 0.0); }

}  // namespace pidlab
