#include "pidlab/plant_sim/discrete_plant.h"

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
  state_ = Eigen::VectorXd::Zero(ss.order());
  next_ = state_;
}

double DiscretePlant::Output() const {
  double y = 0.0;
  for (Eigen::Index i = 0; i < state_.size(); ++i) y += c_(i) * state_(i);
  return y;
}

void DiscretePlant::Step(double input) {
  const Eigen::Index n = state_.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    double acc = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) acc += phi_(i, j) * state_(j);
    next_(i) = acc + gamma_(i) * input;
  }
  state_.swap(next_);
}

void DiscretePlant::Reset() { state_.setZero(); }

}  // namespace pidlab
