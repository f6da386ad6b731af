#pragma once
// Tuning rules on a low-order process model (docs/tuning.md, "Tuning rules"):
// Skogestad's SIMC (J. Process Control 13, 2003) and Astrom and Hagglund's
// AMIGO ("Advanced PID Control", ISA 2006, chapter 7).
//
// The model is first order plus dead time (FOPDT, K e^(-Ls) / (T s + 1)),
// second order plus dead time (SOPDT, K e^(-Ls) / ((T1 s + 1)(T2 s + 1)),
// T1 >= T2) or integrating plus dead time (K' e^(-Ls) / (s (T2 s + 1)), T2 = 0
// for the pure IPDT). A plant of exactly the form a rule needs is used as it
// is; any other is reduced by Skogestad's half rule: the largest neglected time
// constant is split half to the dead time, half to the smallest retained one;
// every smaller time constant and every inverse-response (right half-plane
// zero) time constant goes to the dead time whole.
//
// A plant the rules do not take is refused (Status kInvalidInput, one line
// saying why): complex, unstable or repeated-integrator poles, a zero at the
// origin or in the left half-plane (a lead; Skogestad's lead rules depend on
// the closed-loop time constant and are not implemented), a negative gain, or
// a model whose dead time is 0 (both rules put the closed-loop speed at L).

#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

/// Which controller the rule gives: PI (kd = 0) or PID.
enum class RuleForm { kPi, kPid };
/// pi | pid
bool ParseRuleForm(const std::string& s, RuleForm* form);
std::string ToString(RuleForm form);

enum class TuningRule { kSimc, kAmigo };
std::string ToString(TuningRule rule);

enum class ProcessModelKind {
  kFopdt,        // "fopdt": K e^(-Ls) / (T s + 1)
  kSopdt,        // "sopdt": K e^(-Ls) / ((T1 s + 1)(T2 s + 1)), T1 >= T2
  kIntegrating,  // "ipdt": K' e^(-Ls) / (s (T2 s + 1)), T2 >= 0
};
/// fopdt | sopdt | ipdt
std::string ToString(ProcessModelKind kind);

/// The model a rule used.
struct ProcessModel {
  ProcessModelKind kind = ProcessModelKind::kFopdt;
  /// K (fopdt, sopdt; output / input), or K' (ipdt; output / (input s)).
  double gain = 0.0;
  /// fopdt: {T}; sopdt: {T1, T2}, T1 >= T2 (sorted after the half rule); ipdt: {} or {T2} (a lag after the
  /// integrator, kept for SIMC's PID). Seconds.
  std::vector<double> time_constants;
  /// L (theta in SIMC), s.
  double delay_s = 0.0;
  /// True if the half rule reduced the plant to this model; false if the plant
  /// is of this form exactly.
  bool half_rule = false;
};

/// The rule's controller in its own form and in pidlab's parallel gains.
struct TuningRuleResult {
  TuningRule rule = TuningRule::kSimc;
  RuleForm form = RuleForm::kPid;
  ProcessModel model;
  /// The rule's parameters: Kc (K in AMIGO), tau_I (Ti) and tau_D (Td), s.
  /// SIMC's are of the series form Kc (1 + 1/(tau_I s)) (tau_D s + 1);
  /// AMIGO's of the parallel (ideal) form K (1 + 1/(Ti s) + Td s).
  double kc = 0.0, ti_s = 0.0, td_s = 0.0;
  /// "series" (SIMC) or "parallel" (AMIGO).
  std::string controller_form;
  /// kp + ki/s + kd s, exactly the controller above (tf = 0).
  PidGains gains;
  /// One line: rule, model and gains.
  std::string message;
  /// The plant's own dead time, s (the model's delay also holds what the
  /// half rule moved into it). The sampled loop simulates it.
  double plant_delay_s = 0.0;
};

/// Series PID Kc (1 + 1/(ti s)) (td s + 1) as the parallel kp + ki/s + kd s,
/// exactly: kp = Kc (1 + td/ti), ki = Kc/ti, kd = Kc td.
PidGains SeriesToParallel(double kc, double ti_s, double td_s);

/// The model `rule` with `form` uses for `plant` (its tf and delay_s): AMIGO
/// and SIMC's PI take an FOPDT (or an IPDT), SIMC's PID an SOPDT (or an IPDT
/// with a lag). kInvalidInput with one line if the plant does not reduce.
Status ReduceModel(const Plant& plant, TuningRule rule, RuleForm form, ProcessModel* model);

/// A plant given by its factors: K s^-integrators prod(-T0 s + 1) /
/// prod(tau s + 1) e^(-delay s), the form the half rule reads.
struct FactoredPlant {
  double gain = 0.0;
  int integrators = 0;          // 0 or 1
  std::vector<double> lags;     // tau > 0, s (any order)
  std::vector<double> inverse;  // T0 > 0 of right half-plane zeros, s
  double delay_s = 0.0;
};
/// ReduceModel on a plant given by its factors (no root finding: a repeated
/// pole such as (s + 1)^8 stays exactly real).
Status ReduceFactored(const FactoredPlant& plant, TuningRule rule, RuleForm form, ProcessModel* model);

/// SIMC with tight tuning (tau_c = theta) on `model`.
Status SimcTune(const ProcessModel& model, RuleForm form, TuningRuleResult* result, double tau_c_s = 0.0);
/// AMIGO on `model` (an fopdt or an ipdt without a lag).
Status AmigoTune(const ProcessModel& model, RuleForm form, TuningRuleResult* result);

/// ReduceModel, then the rule.
/// `tau_c_s` > 0: SIMC's closed-loop time constant tau_c (`tune --tau-c`;
/// the model may then have no dead time); 0: tau_c = theta, the tight tuning.
Status ApplyTuningRule(const Plant& plant, TuningRule rule, RuleForm form, TuningRuleResult* result,
                       double tau_c_s = 0.0);

}  // namespace pidlab::tune
