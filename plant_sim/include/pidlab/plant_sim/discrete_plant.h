#pragma once
// A plant discretised exactly (zero-order hold) at a fixed step: what the
// plant process and the in-process sampled loop both run, so their
// trajectories agree bit for bit.

#include <string>
#include <vector>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab {

/// One exact ZOH step, next = phi x + gamma input, in a fixed summation order.
/// Shared by DiscretePlant and the templated sampled loop so that both give
/// the same bits for double.
template <typename T>
void ZohStep(const Eigen::MatrixXd& phi, const Eigen::VectorXd& gamma, const std::vector<T>& x,
             const T& input, std::vector<T>* next) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < n; ++i) {
    T acc = T(0.0);
    for (std::size_t j = 0; j < n; ++j)
      acc += phi(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
    (*next)[i] = acc + gamma(static_cast<Eigen::Index>(i)) * input;
  }
}

/// y = c x in a fixed summation order.
template <typename T>
T OutputOf(const Eigen::RowVectorXd& c, const std::vector<T>& x) {
  T y = T(0.0);
  for (std::size_t i = 0; i < x.size(); ++i) y += c(static_cast<Eigen::Index>(i)) * x[i];
  return y;
}

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
  const Eigen::RowVectorXd& c() const { return c_; }
  const std::vector<double>& state() const { return state_; }

 private:
  double dt_s_;
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma_;
  Eigen::RowVectorXd c_;
  std::vector<double> state_;
  std::vector<double> next_;
};

}  // namespace pidlab
