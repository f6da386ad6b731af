#pragma once
// The process models of MATLAB's idproc, named as it names them:
//   P1D   Kp e^(-Td s) / (1 + Tp1 s)
//   P2D   Kp e^(-Td s) / ((1 + Tp1 s)(1 + Tp2 s))
//   P2DU  Kp e^(-Td s) / (1 + 2 Zeta Tw s + (Tw s)^2)
//   P1DI  Kp e^(-Td s) / (s (1 + Tp1 s))
//   P2DZ  Kp (1 + Tz s) e^(-Td s) / ((1 + Tp1 s)(1 + Tp2 s))
// and, as MATLAB's tfest(data, np, nz, 'IODelay', NaN), a general transfer
// function of n poles and m < n zeros:
//   TF    (b_m s^m + ... + b_0) e^(-Td s) / (s^n + a_(n-1) s^(n-1) + ... + a_0)
// Times in seconds; Kp in output units per input unit (per second for P1DI).
// `pidlab identify` fits them (tuner/identify/); a fitted model, with the
// covariance of its parameters, is a plant (ProcessModelUncertainty, carried
// by Plant::model) whose Monte Carlo draws come from that covariance
// (docs/identify.md, "The identified model as a plant").

#include <string>
#include <vector>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::plant_sim {

enum class ProcessModelKind { kP1D, kP2D, kP2DU, kP1DI, kP2DZ, kTf };

/// "p1d", "p2d", "p2du", "p1di", "p2dz", "tf".
const char* ToString(ProcessModelKind kind);
/// The inverse of ToString; false (and *kind untouched) for any other text.
bool Parse(const std::string& text, ProcessModelKind* kind);
/// "p1d|p2d|p2du|p1di|p2dz|tf", for help texts and error messages.
std::string ProcessModelKindNames();

/// The most poles of a tf model.
inline constexpr int kMaxTfPoles = 6;

struct ProcessModel {
  ProcessModelKind kind = ProcessModelKind::kP1D;
  double kp = 1.0;     // static gain (P1DI: gain of the integrator)
  double tp1_s = 1.0;  // P1D, P2D, P1DI
  double tp2_s = 0.0;  // P2D
  double tw_s = 1.0;   // P2DU: 1 / natural frequency
  double zeta = 0.5;   // P2DU: damping, in (0, 1)
  double tz_s = 0.0;   // P2DZ: the zero's time constant, any sign (negative: a right-half-plane zero)
  double td_s = 0.0;   // input delay, >= 0
  // TF only: n poles in 1..kMaxTfPoles, m zeros in 0..n-1, and the
  // coefficients in ascending powers of s: b = b_0..b_m, a = a_0..a_(n-1)
  // (the denominator monic, its s^n coefficient 1 implied).
  int poles = 0, zeros = 0;
  std::vector<double> b, a;

  /// Kp (1 + Tz s) / den(s), descending powers of s, without the delay
  /// (delay_s()); the numerator is Kp alone where Tz = 0. TF: b and a in
  /// descending powers, the denominator led by 1.
  TransferFunction ToTransferFunction() const;
  double delay_s() const { return td_s; }
};

/// The names of the model's parameters in a fixed order: P1D Kp Tp1 Td; P2D
/// Kp Tp1 Tp2 Td; P2DU Kp Tw Zeta Td; P1DI Kp Tp1 Td; P2DZ Kp Tp1 Tp2 Tz Td;
/// TF b0 .. b<zeros> a0 .. a<poles - 1> Td (Td always last). `poles` and
/// `zeros` are read for TF only (TF with poles < 1 or zeros outside
/// 0..poles-1: an empty list).
std::vector<std::string> ParameterNames(ProcessModelKind kind, int poles = 0, int zeros = 0);
/// The values of `model`'s parameters in the order of ParameterNames.
std::vector<double> ParameterValues(const ProcessModel& model);
/// The model of `kind` whose parameters, in the order of ParameterNames, are
/// `values` (as many, for TF: poles + zeros + 2).
ProcessModel ModelFromValues(ProcessModelKind kind, const std::vector<double>& values, int poles = 0,
                             int zeros = 0);

/// True when every root of s^n + a_(n-1) s^(n-1) + ... + a_0 (a = a_0 ..
/// a_(n-1), n >= 1) has a negative real part (the Routh-Hurwitz test).
bool IsHurwitz(const std::vector<double>& a);

/// True when `values` (in the order of ParameterNames(kind, poles, zeros), as
/// many) are a model's: every number finite, every time constant (Tp1, Tp2,
/// Tw) > 0, Zeta in (0, 1) and Td >= 0; TF: poles in 1..kMaxTfPoles, zeros
/// in 0..poles-1, a stable denominator (IsHurwitz) and a numerator not zero.
/// Otherwise false with *error naming the parameter, its value and the rule.
bool ParametersAreValid(ProcessModelKind kind, const std::vector<double>& values, std::string* error,
                        int poles = 0, int zeros = 0);

/// A fitted model and the uncertainty the data left in it: the parameter
/// values and their covariance (`pidlab identify --out`'s "covariance").
struct ProcessModelUncertainty {
  ProcessModelKind kind = ProcessModelKind::kP1D;
  int poles = 0, zeros = 0;  // TF only (ProcessModel::poles, zeros)
  /// In the order of ParameterNames(kind).
  std::vector<double> values;
  /// p x p, row-major in the order of `values`; empty when the fit gave none
  /// (its covariance was not ok): the draws then perturb the coefficients.
  std::vector<double> covariance;
  /// Why there is no covariance (the model file's covariance.message).
  std::string covariance_message;

  bool HasCovariance() const { return !covariance.empty(); }
};

}  // namespace pidlab::plant_sim
