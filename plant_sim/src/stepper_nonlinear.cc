#include "pidlab/plant_sim/stepper_nonlinear.h"

#include <algorithm>
#include <array>
#include <boost/numeric/odeint.hpp>
#include <sstream>
#include <stdexcept>
#include <unsupported/Eigen/AutoDiff>

namespace pidlab {
namespace {

using State = std::array<double, 4>;

bool Fail(const std::string& what, std::string* error) {
  if (error) *error = what;
  return false;
}

// Characteristic polynomial of a 3x3 matrix, monic, descending powers.
std::vector<double> CharPoly3(const Eigen::Matrix3d& a) {
  const double tr = a.trace();
  const double m2 = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0) + a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0) +
                    a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
  return {1.0, -tr, m2, -a.determinant()};
}

}  // namespace

bool NonlinearStepperOptions::IsValid(std::string* error) const {
  if (!motor.IsValid(error)) return false;
  std::ostringstream os;
  if (!std::isfinite(detent_torque_nm) || detent_torque_nm < 0.0 ||
      detent_torque_nm > kMaxCoefficientMagnitude)
    os << "detent torque " << detent_torque_nm << " N m must be finite and >= 0";
  else if (!std::isfinite(load_torque_nm) || std::abs(load_torque_nm) > kMaxCoefficientMagnitude)
    os << "load torque " << load_torque_nm << " N m must be finite";
  else if (!std::isfinite(load_step_nm) || std::abs(load_step_nm) > kMaxCoefficientMagnitude)
    os << "load step " << load_step_nm << " N m must be finite";
  else if (!std::isfinite(load_step_time_s) || load_step_time_s < 0.0 ||
           load_step_time_s > kMaxCoefficientMagnitude)
    os << "load step time " << load_step_time_s << " s must be finite and >= 0";
  else if (!(voltage_limit_v > 0.0))
    os << "phase-voltage limit " << voltage_limit_v << " V must be positive (inf: none)";
  else if (!std::isfinite(input_scale) || input_scale < 0.0 || input_scale > kMaxCoefficientMagnitude)
    os << "input scale " << input_scale << " must be finite and >= 0 (0: (L - M)/L)";
  else if (!(abs_tolerance > 0.0 && abs_tolerance <= 1e-3) || !(rel_tolerance > 0.0 && rel_tolerance <= 1e-3))
    os << "integrator tolerances " << abs_tolerance << ", " << rel_tolerance << " must be in (0, 1e-3]";
  else if (std::sin(motor.rotor_teeth * motor.tooth_pitch_rad / 2.0) <= 0.0)
    os << "sin(rotor_teeth * tooth_pitch_rad / 2) must be positive";
  else
    return true;
  return Fail(os.str(), error);
}

double NonlinearStepperOptions::InputScale() const {
  if (input_scale > 0.0) return input_scale;
  return (motor.self_inductance_h - motor.mutual_inductance_h) / motor.self_inductance_h;
}

std::vector<double> StepperHoldingState(const NonlinearStepperOptions& o) {
  const double io = o.motor.stationary_current_a;
  return {io, io, o.motor.tooth_pitch_rad / 2.0, 0.0};
}

namespace {

// LinearizeStepper() with the refusal's message in *error.
bool LinearizeStepperOrExplain(const NonlinearStepperOptions& o, StepperLinearization* out,
                               std::string* error) {
  if (!o.IsValid(error)) return false;
  NonlinearStepperOptions unloaded = o;
  unloaded.load_torque_nm = 0.0;
  unloaded.load_step_nm = 0.0;
  using Ad = Eigen::AutoDiffScalar<Eigen::Matrix<double, 5, 1>>;
  const std::vector<double> x0 = StepperHoldingState(o);
  Ad x[4], dx[4];
  for (int i = 0; i < 4; ++i) x[i] = Ad(x0[static_cast<std::size_t>(i)], 5, i);
  const Ad u(0.0, 5, 4);
  StepperDerivative<Ad>(unloaded, x, u, -1.0, dx);
  double scale = 0.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) out->a(i, j) = dx[i].derivatives()(j);
    out->b(i) = dx[i].derivatives()(4);
    scale = std::max(scale, out->a.row(i).cwiseAbs().maxCoeff() * std::max(1.0, std::abs(x0[2])));
  }
  for (int i = 0; i < 4; ++i)
    if (std::abs(dx[i].value()) > 1e-9 * scale)
      return Fail(
          "the holding point (both phases at I_o, theta = lambda/2) is not an equilibrium of these options "
          "(detent off a mid-step?): nothing to linearise",
          error);
  // z = [c, d, theta, omega], c = (i_a + i_b)/2, d = i_b - i_a: x = Q z.
  Eigen::Matrix4d q;
  q << 1, -0.5, 0, 0, 1, 0.5, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix4d az = q.inverse() * out->a * q;
  const Eigen::Vector4d bz = q.inverse() * out->b;
  const double tol = 1e-9 * az.cwiseAbs().maxCoeff();
  if (std::abs(az(0, 1)) > tol || std::abs(az(0, 2)) > tol || std::abs(az(0, 3)) > tol ||
      std::abs(bz(0)) > 1e-9 * bz.cwiseAbs().maxCoeff())
    return Fail("the common mode of the phase currents does not decouple at the holding point", error);
  const Eigen::Matrix3d a3 = az.bottomRightCorner<3, 3>();
  const Eigen::Vector3d b3 = bz.tail<3>();
  const Eigen::RowVector3d c3(0.0, 1.0, 0.0);
  // SISO: C adj(sI - A) B = det(sI - A + B C) - det(sI - A).
  const std::vector<double> den = CharPoly3(a3);
  const std::vector<double> with = CharPoly3(a3 - b3 * c3);
  std::vector<double> num;
  for (std::size_t i = 1; i < 4; ++i) num.push_back(with[i] - den[i]);
  // Drop the leading zeros (exactly zero for this structure: relative degree 3).
  const double top = std::max({std::abs(num[0]), std::abs(num[1]), std::abs(num[2])});
  while (num.size() > 1 && std::abs(num.front()) <= 1e-12 * top) num.erase(num.begin());
  out->tf = {num, den};
  return true;
}

}  // namespace

Status LinearizeStepper(const NonlinearStepperOptions& o, StepperLinearization* out) {
  std::string why;
  if (!LinearizeStepperOrExplain(o, out, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

NonlinearStepperPlant::NonlinearStepperPlant(const NonlinearStepperOptions& o, double dt_s)
    : options_(o), dt_s_(dt_s), theta0_(o.motor.tooth_pitch_rad / 2.0) {
  std::string error;
  if (!o.IsValid(&error)) throw std::invalid_argument(error);
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    throw std::invalid_argument("dt " + std::to_string(dt_s) + " s must be positive and finite");
  Reset();
}

void NonlinearStepperPlant::Reset() {
  state_ = StepperHoldingState(options_);
  steps_ = 0;
  peaks_ = StepperPeaks{};
  peaks_.phase_current_a = options_.motor.stationary_current_a;
}

void NonlinearStepperPlant::PhaseVoltages(double input, double* va, double* vb) const {
  const StepperMotorParameters& p = options_.motor;
  const double k = p.stationary_current_a / std::sin(p.rotor_teeth * p.tooth_pitch_rad / 2.0);
  const double phi = p.tooth_pitch_rad / 2.0 + options_.InputScale() * input;
  if (options_.microstep_table) {
    *va = p.resistance_ohm * k * std::sin(p.rotor_teeth * (p.tooth_pitch_rad - phi));
    *vb = p.resistance_ohm * k * std::sin(p.rotor_teeth * phi);
  } else {
    const double io = p.stationary_current_a;
    const double cu = p.rotor_teeth * io / std::tan(p.rotor_teeth * p.tooth_pitch_rad / 2.0) *
                      options_.InputScale() * input;
    *va = p.resistance_ohm * (io - cu);
    *vb = p.resistance_ohm * (io + cu);
  }
  const double lim = options_.voltage_limit_v;
  *va = std::clamp(*va, -lim, lim);
  *vb = std::clamp(*vb, -lim, lim);
}

void NonlinearStepperPlant::Step(double input) {
  namespace odeint = boost::numeric::odeint;
  const double t0 = time_s(), t1 = static_cast<double>(steps_ + 1) * dt_s_;
  auto stepper = odeint::make_controlled(options_.abs_tolerance, options_.rel_tolerance,
                                         odeint::runge_kutta_dopri5<State>());
  State x{state_[0], state_[1], state_[2], state_[3]};
  const NonlinearStepperOptions& o = options_;
  if (std::isfinite(input)) {
    // Integrate [t0, t1] in pieces that do not straddle the load step, so
    // that the right-hand side is smooth on each.
    std::array<double, 3> cuts{t0, t1, t1};
    if (o.load_step_nm != 0.0 && o.load_step_time_s > t0 && o.load_step_time_s < t1)
      cuts = {t0, o.load_step_time_s, t1};
    for (int piece = 0; piece < 2; ++piece) {
      const double a = cuts[static_cast<std::size_t>(piece)], b = cuts[static_cast<std::size_t>(piece) + 1];
      if (!(b > a)) continue;
      // The load torque of the piece is the one at its start (t >= step time).
      const double t_piece = a;
      auto rhs = [&o, input, t_piece](const State& s, State& ds, double /*t*/) {
        StepperDerivative<double>(o, s.data(), input, t_piece, ds.data());
      };
      odeint::integrate_adaptive(stepper, rhs, x, a, b, (b - a) / 4.0);
    }
  } else {
    x.fill(std::numeric_limits<double>::quiet_NaN());
  }
  state_.assign(x.begin(), x.end());
  ++steps_;
  double va = 0.0, vb = 0.0;
  PhaseVoltages(input, &va, &vb);
  peaks_.phase_voltage_v = std::max({peaks_.phase_voltage_v, std::abs(va), std::abs(vb)});
  peaks_.phase_current_a = std::max({peaks_.phase_current_a, std::abs(state_[0]), std::abs(state_[1])});
  const double phi = theta0_ + options_.InputScale() * input;
  peaks_.load_angle_rad =
      std::max(peaks_.load_angle_rad, std::abs(options_.motor.rotor_teeth * (phi - state_[2])));
}

}  // namespace pidlab
