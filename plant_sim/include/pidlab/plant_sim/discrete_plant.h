#pragma once
// A plant discretised exactly (zero-order hold) at a fixed step: what the
// plant process and the in-process sampled loop both run, so their
// trajectories agree bit for bit.

#include <string>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab {

class DiscretePlant {
 public:
  /// Throws std::invalid_argument if `tf` is invalid or not strictly proper
  /// (a direct feedthrough would make the sampled loop algebraic), or if dt_s
  /// is not positive and finite.
  DiscretePlant(const TransferFunction& tf, double dt_s);

  /// y_k = C x_k, the output at the start of the current step.
  double Output() const;
  /// x_{k+1} = Phi x_k + Gamma u_k, with u_k the total plant input (control
  /// plus disturbance) held over the step. Fixed summation order.
  void Step(double input);
  void Reset();

  int order() const { return static_cast<int>(state_.size()); }
  double dt_s() const { return dt_s_; }
  const Eigen::MatrixXd& phi() const { return phi_; }
  const Eigen::VectorXd& gamma() const { return gamma_; }

 private:
  double dt_s_;
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma_;
  Eigen::RowVectorXd c_;
  Eigen::VectorXd state_;
  Eigen::VectorXd next_;
};

}  // namespace pidlab
