#pragma once
// PID controllers.
//
// Continuous (eq. 2 of the paper), ideal parallel form:
//   u(t) = kp e(t) + ki \int_0^t e dt + kd de/dt,   e = r - y,
// or with a first-order derivative filter of time constant tf > 0:
//   C(s) = kp + ki / s + kd s / (tf s + 1)           (tf = 0: the ideal PID).
// Two degrees of freedom (docs/two_dof.md): setpoint weights b, c in [0, 1]
// (PidOptions::setpoint_weight_b, setpoint_weight_c) weight r in the
// proportional and derivative terms,
//   u = kp (b r - y) + ki/s (r - y) + kd s / (tf s + 1) (c r - y);
// b = c = 1 is the 1-DOF PID above, c = 0 the derivative on measurement.
// A first-order setpoint filter of time constant tr > 0
// (PidOptions::setpoint_filter_s) takes r to r_f = r / (tr s + 1) before all
// three terms, where the weights alone cannot shape the response (0 = none):
//   u = kp (b r_f - y) + ki/s (r_f - y) + kd s / (tf s + 1) (c r_f - y).
//
// Discrete, period dt, one call per sample k (t_k = k dt), u_k held over
// [t_k, t_{k+1}):
//   r_k stands for the filtered f_k where tr > 0 (0: r_k itself):
//       f_k = f_{k-1} + dt/(tr+dt) (r_k - f_{k-1}), f_{-1} = 0 (at rest),
//       the backward-Euler image of 1/(tr s + 1), as the derivative's filter
//   e_k = r_k - y_k
//   P_k = kp (b r_k - y_k)
//   I_k = I_{k-1} + ki dt e_k                    (backward Euler, default)
//       | I_{k-1} + ki dt e_{k-1}                 (forward Euler)
//       | I_{k-1} + ki dt (e_k + e_{k-1}) / 2     (trapezoidal)
//   D_k = tf/(tf+dt) D_{k-1} + kd/(tf+dt) (s_k - s_{k-1}),
//         s_k = c r_k - y_k (c = 1: on error; c = 0: on measurement),
//         the backward-Euler image of kd s / (tf s + 1) with the same tf as
//         the continuous loop (EffectiveDerivativeFilter)
//   u_k = sat(P_k + I_k + D_k)
// The loop is at rest before k = 0 (r = y = e = 0), so with the defaults
// (tf = 0, b = c = 1, no limits) a unit step in r gives the
// derivative kick kd/dt over the first step: area kd, the discrete image of
// the ideal PID's impulse, and the loop converges to the continuous one as
// dt -> 0.
//
// Templated on the scalar so the same code runs on double and ceres::Jet.
// The per-sample Step() never throws: it returns a status (ruckig style).

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace pidlab {

template <typename T>
struct PidGainsT {
  T kp = T(0.0);
  T ki = T(0.0);
  T kd = T(0.0);
  /// Time constant of the derivative filter kd s / (tf s + 1), s; 0 = the
  /// paper's ideal derivative. The same tf drives the continuous loop and the
  /// discrete PID.
  T tf = T(0.0);
};
using PidGains = PidGainsT<double>;

/// The largest gain GainsAreValid accepts (README.md, "Exit status and
/// limits"): larger gains only overflow the closed loop's matrices.
inline constexpr double kMaxGain = 1e12;

/// Gains (and the filter time constant tf, s) must be finite and at most
/// kMaxGain in size (the paper's search box is [0, 30]^3); tf >= 0. kp, ki
/// and kd share one sign: all >= 0 (direct acting), or all <= 0, the PID of
/// a reverse-acting plant (a negative gain: u = -|kp| e - ...).
inline bool GainsAreValid(const PidGains& g, std::string* error) {
  const std::pair<const char*, double> f[] = {{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}, {"tf", g.tf}};
  for (const auto& [name, v] : f) {
    const bool tf = name[0] == 't';
    if (!std::isfinite(v) || std::fabs(v) > kMaxGain || (tf && v < 0.0)) {
      if (error) {
        std::ostringstream os;
        if (tf)
          os << "derivative filter " << v << " s (tf) must be finite, >= 0 and at most " << kMaxGain;
        else
          os << "gain " << name << " = " << v << " must be finite and at most " << kMaxGain << " in size";
        *error = os.str();
      }
      return false;
    }
  }
  const bool positive = g.kp > 0.0 || g.ki > 0.0 || g.kd > 0.0;
  const bool negative = g.kp < 0.0 || g.ki < 0.0 || g.kd < 0.0;
  if (positive && negative) {
    if (error) {
      std::ostringstream os;
      os << "gains kp = " << g.kp << ", ki = " << g.ki << ", kd = " << g.kd
         << " differ in sign: all must be >= 0 (direct acting) or all <= 0 (reverse acting)";
      *error = os.str();
    }
    return false;
  }
  return true;
}

/// True where the gains are those of a reverse-acting loop (all <= 0, one < 0).
inline bool GainsAreReverse(const PidGains& g) { return g.kp < 0.0 || g.ki < 0.0 || g.kd < 0.0; }

/// The spec's derivative_on (kept for the flag and for logs): kError is
/// setpoint weight c = 1, kMeasurement c = 0 (SetpointWeightC).
enum class DerivativeOn { kError, kMeasurement };
enum class IntegralMethod { kBackwardEuler, kForwardEuler, kTrapezoidal };
enum class AntiWindup { kNone, kClamping, kBackCalculation };

struct PidOptions {
  /// Sample period in s, > 0.
  double dt_s = 1e-3;
  /// Time constant of the first-order derivative filter in s; 0 = unfiltered.
  /// Used where the gains carry none (PidGains::tf = 0): the field the wire
  /// (lcmt_episode_config) carries. See EffectiveDerivativeFilter.
  double derivative_filter_s = 0.0;
  /// Output limits; lower < upper. Infinite = unlimited.
  double output_min = -std::numeric_limits<double>::infinity();
  double output_max = std::numeric_limits<double>::infinity();
  /// Integrator protection when the output saturates. Clamping stops
  /// integrating while saturated and the error pushes further into the limit;
  /// back-calculation feeds (u_sat - u) * back_calculation_gain into I.
  AntiWindup anti_windup = AntiWindup::kClamping;
  double back_calculation_gain = 1.0;  // 1/s, > 0
  IntegralMethod integral = IntegralMethod::kBackwardEuler;
  /// Setpoint weights of the 2-DOF PID, each finite and in [0, 1]: b weights
  /// r in the proportional term, c in the derivative term (c = 0: derivative
  /// on measurement). The weights live here, not in the gains: they do not
  /// change the feedback loop (Ms, margins, load rejection), only how r
  /// enters. 1, 1: the 1-DOF PID, bit for bit.
  double setpoint_weight_b = 1.0;  // b
  double setpoint_weight_c = 1.0;  // c
  /// Time constant tr of the first-order setpoint filter r / (tr s + 1), s,
  /// finite and >= 0; 0 = none (r enters as it is). Like the weights, it
  /// changes only how r enters, never the feedback loop.
  double setpoint_filter_s = 0.0;  // tr

  bool IsValid(std::string* error) const {
    std::ostringstream os;
    if (!(dt_s > 0.0) || !std::isfinite(dt_s))
      os << "dt " << dt_s << " s must be positive and finite";
    else if (!(derivative_filter_s >= 0.0) || !std::isfinite(derivative_filter_s))
      os << "derivative filter " << derivative_filter_s << " s must be >= 0 and finite";
    else if (std::isnan(output_min) || std::isnan(output_max) || !(output_min < output_max))
      os << "output limits [" << output_min << ", " << output_max << "] must satisfy min < max";
    else if (!SetpointWeightIsValid(setpoint_weight_b))
      os << "setpoint weight b = " << setpoint_weight_b << " must be finite and in [0, 1]";
    else if (!SetpointWeightIsValid(setpoint_weight_c))
      os << "setpoint weight c = " << setpoint_weight_c << " must be finite and in [0, 1]";
    else if (!(setpoint_filter_s >= 0.0) || !std::isfinite(setpoint_filter_s))
      os << "setpoint filter " << setpoint_filter_s << " s must be >= 0 and finite";
    else if (anti_windup == AntiWindup::kBackCalculation &&
             (!(back_calculation_gain > 0.0) || !std::isfinite(back_calculation_gain)))
      os << "back-calculation gain " << back_calculation_gain << " must be positive";
    else
      return true;
    if (error) *error = os.str();
    return false;
  }

  static bool SetpointWeightIsValid(double w) { return std::isfinite(w) && w >= 0.0 && w <= 1.0; }
};

/// The derivative's setpoint weight c that derivative_on stands for: 1 on
/// the error, 0 on the measurement.
inline double SetpointWeightC(DerivativeOn v) { return v == DerivativeOn::kError ? 1.0 : 0.0; }

/// The PID's options for a loop of period `loop_dt_s`: `options` with its
/// sample time set to the loop's. The one place the PID's dt is derived from
/// a loop (the loop, the episode, replay and the Ceres cross-check call it).
PidOptions PidOptionsAt(PidOptions options, double loop_dt_s);

/// The derivative filter time constant a PID runs with: gains.tf where it is
/// set (> 0), else options.derivative_filter_s.
template <typename T>
T EffectiveDerivativeFilter(const PidGainsT<T>& gains, const PidOptions& options) {
  if (gains.tf > T(0.0)) return gains.tf;
  return T(options.derivative_filter_s);
}

bool ParseDerivativeOn(const std::string& s, DerivativeOn* v);
bool ParseIntegralMethod(const std::string& s, IntegralMethod* v);
bool ParseAntiWindup(const std::string& s, AntiWindup* v);
std::string ToString(DerivativeOn v);
std::string ToString(IntegralMethod v);
std::string ToString(AntiWindup v);

enum class PidStatus {
  kOk,            // u computed, not saturated
  kSaturated,     // u computed and clipped to the output limits
  kInvalidInput,  // r or y not finite: u is left unchanged, state untouched
};

template <typename T>
class DiscretePid {
 public:
  /// Options must be valid (checked by the caller with IsValid).
  DiscretePid(const PidGainsT<T>& gains, const PidOptions& options) : gains_(gains), options_(options) {}

  PidStatus Step(const T& r_in, const T& y, T* u) {
    using std::isfinite;
    if (!IsFinite(r_in) || !IsFinite(y)) return PidStatus::kInvalidInput;
    const double dt = options_.dt_s;
    // The setpoint filter's f_k (tr > 0), or r_k itself.
    if (options_.setpoint_filter_s > 0.0)
      filtered_r_ += T(dt) / (T(options_.setpoint_filter_s) + T(dt)) * (r_in - filtered_r_);
    const T r = options_.setpoint_filter_s > 0.0 ? filtered_r_ : r_in;
    const T e = r - y;
    // The operation order is the exported C's (pidlab export): keep it.
    const T p = gains_.kp * (T(options_.setpoint_weight_b) * r - y);
    T integral = integral_;
    switch (options_.integral) {
      case IntegralMethod::kBackwardEuler:
        integral += gains_.ki * T(dt) * e;
        break;
      case IntegralMethod::kForwardEuler:
        integral += gains_.ki * T(dt) * prev_error_;
        break;
      case IntegralMethod::kTrapezoidal:
        integral += gains_.ki * T(dt * 0.5) * (e + prev_error_);
        break;
    }
    const T signal = T(options_.setpoint_weight_c) * r - y;
    const T tf = EffectiveDerivativeFilter(gains_, options_);
    const T d =
        tf / (tf + T(dt)) * derivative_ + gains_.kd * (signal - prev_signal_) * (T(1.0) / (tf + T(dt)));
    const T unsaturated = p + integral + d;
    T out = unsaturated;
    bool saturated = false;
    if (ToValue(out) > options_.output_max) {
      out = T(options_.output_max);
      saturated = true;
    }
    if (ToValue(out) < options_.output_min) {
      out = T(options_.output_min);
      saturated = true;
    }
    if (saturated) {
      if (options_.anti_windup == AntiWindup::kClamping) {
        // Integrate only if the error pulls the output back inside the limits.
        // (The integral moves u the way ki e does: against e where reverse acting.)
        const double pull = ToValue(gains_.ki) < 0.0 ? -ToValue(e) : ToValue(e);
        const bool pushes_further = (ToValue(unsaturated) > options_.output_max && pull > 0.0) ||
                                    (ToValue(unsaturated) < options_.output_min && pull < 0.0);
        if (pushes_further) integral = integral_;
      } else if (options_.anti_windup == AntiWindup::kBackCalculation) {
        integral += T(options_.back_calculation_gain * dt) * (out - unsaturated);
      }
    }
    integral_ = integral;
    derivative_ = d;
    prev_error_ = e;
    prev_signal_ = signal;
    *u = out;
    return saturated ? PidStatus::kSaturated : PidStatus::kOk;
  }

  /// Back to rest: r = y = e = 0 before the next sample.
  void Reset() {
    integral_ = T(0.0);
    derivative_ = T(0.0);
    prev_error_ = T(0.0);
    prev_signal_ = T(0.0);
    filtered_r_ = T(0.0);
  }

  const PidGainsT<T>& gains() const { return gains_; }
  const PidOptions& options() const { return options_; }

 private:
  static double ToValue(double x) { return x; }
  template <typename U>
  static double ToValue(const U& x) {
    return ToValue(x.a);
  }
  static bool IsFinite(const T& x) { return std::isfinite(ToValue(x)); }

  PidGainsT<T> gains_;
  PidOptions options_;
  T integral_ = T(0.0);
  T derivative_ = T(0.0);
  T prev_error_ = T(0.0);
  T prev_signal_ = T(0.0);
  T filtered_r_ = T(0.0);  // the setpoint filter's state f_k (tr > 0)
};

}  // namespace pidlab
