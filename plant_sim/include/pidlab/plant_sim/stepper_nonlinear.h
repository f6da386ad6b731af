#pragma once
// The two-phase permanent-magnet stepper motor as it is (Bodson, Chiasson,
// Novotnak and Rekowski, IEEE TCST 1993), with Table I's parameters, and its
// linearisation at the holding point of eq. (3). docs/stepper.md derives it.
//
// State x = [i_a, i_b, theta, omega] (A, A, rad, rad/s); theta is measured
// from phase a's detent, so the holding point with both phases at I_o is
// theta_0 = lambda / 2. With K_m = N_r n Phi_M (torque constant, N m / A):
//   psi_a = L i_a + M i_b + n Phi_M cos(N_r theta)
//   psi_b = L i_b + M i_a + n Phi_M cos(N_r (theta - lambda))
//   [L M; M L] [i_a'; i_b'] = [v_a; v_b] - r [i_a; i_b] - [e_a; e_b]
//   e_a = -K_m omega sin(N_r theta),  e_b = -K_m omega sin(N_r (theta - lambda))
//   J omega' = T_e - D omega - T_detent - T_load,  theta' = omega
//   T_e = -K_m (i_a sin(N_r theta) + i_b sin(N_r (theta - lambda)))
//   T_detent = T_d sin(4 N_r theta)
// For N_r lambda = pi/2 (Table I) phase b is Bodson's sin -> -cos.
//
// The control input u (rad) is the commanded rotor angle relative to the
// holding point, phi = theta_0 + g u. Two voltage-mode drives map it to the
// phase voltages, each clamped to +/- the phase-voltage limit:
//  * linear (default): the microstep table linearised at the holding point,
//      v_a = r (I_o - c g u),  v_b = r (I_o + c g u),  c = N_r I_o cot(N_r lambda / 2):
//    the common mode holds I_o, the differential voltage v_b - v_a is
//    proportional to u (what eq. (3) assumes for every u);
//  * microstep (sine table): the steady-state currents that hold the rotor at phi,
//      v_a = r k sin(N_r (lambda - phi)),  v_b = r k sin(N_r phi),  k = I_o / sin(N_r lambda / 2),
//    which wraps every electrical period 2 pi / N_r of phi.
// Both have the same linearisation. g = input_scale: 1 is the physical angle
// command (DC gain 1); eq. (3)'s numerator (r/L) w_np^2 needs g = (L - M)/L
// (docs/stepper.md), the default, so that the linearisation is eq. (3)
// exactly. The output y = theta - theta_0 (rad).

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/plant_sim/plants.h"
#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab {

struct NonlinearStepperOptions {
  StepperMotorParameters motor;
  /// Detent torque amplitude T_d, N m (>= 0; 0 keeps eq. (3)'s linearisation).
  double detent_torque_nm = 0.0;
  /// Constant load torque, N m (opposes positive theta), from t = 0.
  double load_torque_nm = 0.0;
  /// A further load torque step of this size at load_step_time_s, N m.
  double load_step_nm = 0.0;
  double load_step_time_s = 0.0;
  /// Phase-voltage limit of the drive, V (> 0; +inf: none).
  double voltage_limit_v = HUGE_VAL;
  /// g: phi = theta_0 + g u. 0 means the default (L - M)/L, which makes the
  /// linearisation eq. (3); 1 is the physical angle command (DC gain 1).
  double input_scale = 0.0;
  /// The sine-table drive instead of the linear one (see above).
  bool microstep_table = false;
  /// Integrator tolerances (absolute and relative, per state).
  double abs_tolerance = 1e-12;
  double rel_tolerance = 1e-12;

  /// Valid motor, finite non-negative torques and step time, positive
  /// voltage limit, finite input scale >= 0, tolerances in (0, 1e-3].
  bool IsValid(std::string* error) const;
  /// g actually used.
  double InputScale() const;
};

/// The model's right-hand side, templated on the scalar (double, long
/// double, Eigen::AutoDiffScalar, ceres::Jet). `t` only selects the load step.
template <typename T>
void StepperDerivative(const NonlinearStepperOptions& o, const T* x, const T& u, double t, T* dx) {
  using std::cos;
  using std::sin;
  const StepperMotorParameters& p = o.motor;
  const double nr = p.rotor_teeth, lambda = p.tooth_pitch_rad;
  const double km = nr * p.flux_linkage;
  const double k = p.stationary_current_a / std::sin(nr * lambda / 2.0);
  const T phi = T(lambda / 2.0) + T(o.InputScale()) * u;
  T va, vb;
  if (o.microstep_table) {
    va = T(p.resistance_ohm * k) * sin(T(nr) * (T(lambda) - phi));
    vb = T(p.resistance_ohm * k) * sin(T(nr) * phi);
  } else {
    const double io = p.stationary_current_a;
    const T cu = T(nr * io / std::tan(nr * lambda / 2.0) * o.InputScale()) * u;
    va = T(p.resistance_ohm) * (T(io) - cu);
    vb = T(p.resistance_ohm) * (T(io) + cu);
  }
  if (std::isfinite(o.voltage_limit_v)) {
    const T lim(o.voltage_limit_v);
    if (va > lim) va = lim;
    if (va < -lim) va = -lim;
    if (vb > lim) vb = lim;
    if (vb < -lim) vb = -lim;
  }
  const T& ia = x[0];
  const T& ib = x[1];
  const T& theta = x[2];
  const T& omega = x[3];
  const T sa = sin(T(nr) * theta);
  const T sb = sin(T(nr) * (theta - T(lambda)));
  // e_x = -K_m omega sin(.): the voltage left for L di/dt is v - r i - e.
  const T ra = va - T(p.resistance_ohm) * ia + T(km) * omega * sa;
  const T rb = vb - T(p.resistance_ohm) * ib + T(km) * omega * sb;
  const double l = p.self_inductance_h, m = p.mutual_inductance_h, det = l * l - m * m;
  dx[0] = (T(l) * ra - T(m) * rb) / T(det);
  dx[1] = (T(l) * rb - T(m) * ra) / T(det);
  dx[2] = omega;
  const double load = o.load_torque_nm + (t >= o.load_step_time_s ? o.load_step_nm : 0.0);
  const T torque = T(-km) * (ia * sa + ib * sb) - T(o.detent_torque_nm) * sin(T(4.0 * nr) * theta) -
                   T(p.viscous_friction) * omega - T(load);
  dx[3] = torque / T(p.inertia_kg_m2);
}

/// The state at the holding point: both phases at I_o, theta_0 = lambda/2, at rest.
std::vector<double> StepperHoldingState(const NonlinearStepperOptions& o);

/// Linearisation at the holding point (u = 0, no load) by automatic
/// differentiation of StepperDerivative: the Jacobian, moved to the common
/// mode (i_a + i_b)/2, the differential mode i_b - i_a, theta and omega, where
/// the common mode is neither driven nor seen, and the transfer function
/// u -> theta of the remaining third-order part (monic denominator).
/// Returns false with *error if the options are invalid, the holding point is
/// not an equilibrium (a load torque, or detent off a mid-step) or the common
/// mode does not decouple.
struct StepperLinearization {
  Eigen::Matrix4d a;  // d f / d x at the holding point
  Eigen::Vector4d b;  // d f / d u
  TransferFunction tf;
};
Status LinearizeStepper(const NonlinearStepperOptions& o, StepperLinearization* out);

/// Peak quantities seen while integrating.
struct StepperPeaks {
  double phase_voltage_v = 0.0;  // max |v_a|, |v_b| applied (after the limit)
  double phase_current_a = 0.0;  // max |i_a|, |i_b|
  double load_angle_rad = 0.0;   // max |N_r (phi - theta)| at step ends (electrical)
};

/// The nonlinear motor under a zero-order hold: u (plus the disturbance,
/// already added by the caller) held constant over each step of dt_s,
/// integrated by Boost.Odeint's controlled Dormand-Prince 5(4) stepper
/// (dense steps, fixed tolerances), deterministic for given inputs.
class NonlinearStepperPlant {
 public:
  /// Throws std::invalid_argument for invalid options or dt.
  NonlinearStepperPlant(const NonlinearStepperOptions& o, double dt_s);
  /// y_k = theta_k - theta_0.
  double Output() const { return state_[2] - theta0_; }
  /// Integrates one step of dt with input u held.
  void Step(double input);
  void Reset();
  const std::vector<double>& state() const { return state_; }
  const StepperPeaks& peaks() const { return peaks_; }
  /// Phase voltages the drive applies for input u.
  void PhaseVoltages(double input, double* va, double* vb) const;
  double time_s() const { return static_cast<double>(steps_) * dt_s_; }
  const NonlinearStepperOptions& options() const { return options_; }

 private:
  NonlinearStepperOptions options_;
  double dt_s_;
  double theta0_;
  long steps_ = 0;
  std::vector<double> state_;
  StepperPeaks peaks_;
};

}  // namespace pidlab
