#pragma once
// Single-input single-output linear plants: transfer functions and their
// state-space realisations.

#include <Eigen/Dense>
#include <complex>
#include <string>
#include <vector>

namespace pidlab {

/// Input limits of a transfer function (README.md, "Exit status and limits"):
/// at most this many coefficients in the numerator and in the denominator (the
/// wire format's transport::kMaxPolynomialCoefficients, which agrees: checked
/// where both are visible, in tools/cli_common.cc) ...
inline constexpr int kMaxTransferFunctionCoefficients = 64;
/// ... and every coefficient 0 or of magnitude in [kMinCoefficientMagnitude,
/// kMaxCoefficientMagnitude], so that the realisation (coefficients divided by
/// the leading one, at most 1e24) and the closed loop stay finite.
inline constexpr double kMaxCoefficientMagnitude = 1e12;
inline constexpr double kMinCoefficientMagnitude = 1e-12;

/// G(s) = num(s) / den(s), coefficients in descending powers of s.
struct TransferFunction {
  std::vector<double> num;
  std::vector<double> den;

  /// At most kMaxTransferFunctionCoefficients coefficients each, every one 0
  /// or finite with magnitude in [kMinCoefficientMagnitude,
  /// kMaxCoefficientMagnitude], non-zero leading denominator coefficient, and
  /// deg num <= deg den. Names the offending value on failure.
  bool IsValid(std::string* error) const;
  /// deg den - deg num (leading zeros ignored).
  int RelativeDegree() const;
  /// G(0) (infinite for a pole at the origin).
  double DcGain() const;
  std::string ToString() const;
};

/// x' = A x + B u, y = C x + D u.
struct StateSpace {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
  int order() const { return static_cast<int>(a.rows()); }
};

/// Controllable canonical realisation, then diagonally balanced (powers of two,
/// so exact) to keep badly scaled plants such as the stepper motor, whose
/// coefficients span nine decades, well conditioned. Throws
/// std::invalid_argument if `tf` is not valid.
StateSpace Realize(const TransferFunction& tf);

/// Diagonal balancing with powers of two (as LAPACK's gebal), so that rows
/// and columns of A have comparable norms; eigenvalues are unchanged and
/// computed more accurately. Returns d with A <- D^-1 A D. Terminates for any
/// A: at most 100 sweeps, and a row whose off-diagonal norms are not finite
/// (an A with inf or NaN) is left as it is.
Eigen::VectorXd BalanceInPlace(Eigen::MatrixXd* a);

/// Roots of a polynomial in descending powers (companion-matrix eigenvalues).
std::vector<std::complex<double>> PolynomialRoots(const std::vector<double>& p);

}  // namespace pidlab
