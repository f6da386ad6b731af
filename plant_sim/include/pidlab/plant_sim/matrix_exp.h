#pragma once
// Matrix exponential and exact zero-order-hold discretisation, templated on
// the scalar so the same code runs on double and on ceres::Jet.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pidlab {

/// The value part of a scalar: the scalar itself for double, `.a` for a Jet.
inline double ToDouble(double x) { return x; }
template <typename T>
double ToDouble(const T& x) {
  return ToDouble(x.a);
}

template <typename T>
using MatrixX = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
template <typename T>
using VectorX = Eigen::Matrix<T, Eigen::Dynamic, 1>;

/// exp(a) by scaling and squaring of a truncated Taylor series. Only sums and
/// products are used, so automatic differentiation passes straight through.
/// The scaled matrix has infinity norm <= 1/2 and the series is cut when the
/// next term is below 1e-17 relative, i.e. at double precision.
template <typename T>
MatrixX<T> MatrixExp(const MatrixX<T>& a) {
  const Eigen::Index n = a.rows();
  double norm = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double row = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) row += std::abs(ToDouble(a(i, j)));
    norm = std::max(norm, row);
  }
  // At most 1100 squarings (2^1100 > any finite norm / 0.5): an infinite norm
  // gives a non-finite result rather than an out-of-range cast.
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::min(1100.0, std::ceil(std::log2(norm / 0.5))));
  const MatrixX<T> scaled = a * T(std::ldexp(1.0, -squarings));
  MatrixX<T> result = MatrixX<T>::Identity(n, n);
  MatrixX<T> term = MatrixX<T>::Identity(n, n);
  double term_bound = 1.0;
  const double scaled_norm = norm * std::ldexp(1.0, -squarings);
  for (int k = 1; k <= 30; ++k) {
    term = (term * scaled) * T(1.0 / k);
    result += term;
    term_bound *= scaled_norm / k;
    if (term_bound < 1e-17) break;
  }
  for (int s = 0; s < squarings; ++s) result = (result * result).eval();
  return result;
}

/// Exact zero-order-hold discretisation of x' = A x + B u over h:
/// x(t+h) = phi x(t) + gamma u(t), from exp([[A, B], [0, 0]] h).
template <typename T>
void ZeroOrderHold(const MatrixX<T>& a, const MatrixX<T>& b, double h, MatrixX<T>* phi, MatrixX<T>* gamma) {
  const Eigen::Index n = a.rows(), m = b.cols();
  MatrixX<T> aug = MatrixX<T>::Zero(n + m, n + m);
  aug.topLeftCorner(n, n) = a * T(h);
  aug.topRightCorner(n, m) = b * T(h);
  const MatrixX<T> e = MatrixExp<T>(aug);
  *phi = e.topLeftCorner(n, n);
  *gamma = e.topRightCorner(n, m);
}

}  // namespace pidlab
