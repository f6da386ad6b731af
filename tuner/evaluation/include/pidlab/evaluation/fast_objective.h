#pragma once
// The tuner's hot path on the continuous loop: the objective of eq. (4) for
// one gain vector without allocation, with the loop matrix, its exponential
// and the state in fixed-size Eigen matrices templated on the loop order, and
// strict stability decided from the characteristic polynomial (Routh-Hurwitz)
// instead of an eigen-decomposition. ObjectiveEvaluator uses it for every case
// it covers (FastContinuousObjective::Covers) and the general path
// (BuildContinuousClosedLoop, ContinuousStability, SampleContinuousLoop) for
// everything else; both give the same objective to rounding (tested to 1e-12
// relative) and the same stability verdict (borderline polynomials are
// decided by ContinuousStability itself).

#include <string>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::evaluation {

/// Routh's array on p(s) = p[0] s^d + p[1] s^(d-1) + ... + p[d], d <= 15:
/// true iff every first-column entry has the sign of p[0] (!= 0), i.e. every
/// root has Re s < 0. A zero entry (a root on the axis, or a pair symmetric
/// about it) or a non-finite one is false.
bool IsHurwitz(const double* p, int degree);

/// p(s) -> p(s + h), coefficients in descending powers, in place.
void ShiftPolynomial(double h, double* p, int degree);

/// Fujiwara's bound on the roots of p: every root has |s| <= the result
/// (infinity or NaN for a p[0] of 0 or non-finite coefficients).
double RootRadiusBound(const double* p, int degree);

enum class PolynomialStability { kStable, kUnstable, kUndecided };

/// ContinuousStability's rule (every root s has Re s < -margin max(1, |s|))
/// decided from the characteristic polynomial where it is clear: kStable when
/// p(s - sigma) is Hurwitz for sigma = (margin + kPolynomialTestBuffer)
/// max(1, rho), rho = RootRadiusBound (so every root satisfies the rule with
/// room to spare); kUnstable when p(s + kPolynomialTestBuffer max(1, rho)) is
/// not (a root lies clearly in the right half-plane); kUndecided in the band
/// between, or for non-finite coefficients: there the eigenvalue test decides.
PolynomialStability PolynomialStabilityTest(const double* p, int degree, double margin);

/// Width of the band left to the eigenvalue test, relative to max(1, rho):
/// far above the rounding of Routh's array and of the eigenvalues.
inline constexpr double kPolynomialTestBuffer = 1e-6;

/// The objective of ObjectiveEvaluator on the continuous loop, fast.
class FastContinuousObjective {
 public:
  /// Largest plant order with a fixed-size instantiation (loop order + 1 for
  /// the reference state).
  static constexpr int kMaxPlantOrder = 6;

  /// True for what the fast path computes: the continuous loop, no
  /// disturbance, any reference step A, the iae, ise or itae objective, a
  /// strictly proper plant of order 1..kMaxPlantOrder, the ideal PID (no
  /// derivative filter in the options; a gain with tf != 0 goes the general
  /// path too).
  static bool Covers(const TransferFunction& tf, const LoopOptions& options, ObjectiveKind kind);
  /// Covers for a plant: never a nonlinear one (stepper_nonlinear), whose tf
  /// is only its linearisation.
  static bool CoversPlant(const Plant& plant, const LoopOptions& options, ObjectiveKind kind);

  /// `realization` is Realize(tf). Throws std::invalid_argument if !Covers.
  FastContinuousObjective(const TransferFunction& tf, const StateSpace& realization,
                          const LoopOptions& options, ObjectiveKind kind);

  /// The objective of `gains` (valid: GainsAreValid), +inf when the loop is
  /// not strictly stable or ill-posed, exactly as the general path. Safe to
  /// call from several threads at once: it writes nothing but its stack.
  double operator()(const PidGains& gains) const;

 private:
  template <int N>
  double Run(const PidGains& gains) const;
  /// The characteristic polynomial of the loop's [x; z] block (degree n + 1,
  /// or n when the integrator is disconnected) into p; returns the degree.
  int CharacteristicPolynomial(const PidGains& gains, bool integrator_connected, double* p) const;

  StateSpace realization_;
  Eigen::VectorXd den_;  // monic, descending, n + 1 coefficients
  Eigen::VectorXd num_;  // over den's leading coefficient, powers n-1 .. 0
  Eigen::RowVectorXd ca_;
  double cb_ = 0.0;
  LoopOptions options_;
  ObjectiveKind kind_;
  Disturbance none_;  // for the general path of undecided polynomials
  int order_ = 0;
  int num_samples_ = 0;
};

}  // namespace pidlab::evaluation
