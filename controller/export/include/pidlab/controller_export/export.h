#pragma once
// The discrete PID as a dependency-free C99 module (`pidlab export`): the
// controller DiscretePid runs (pidlab/controller/pid.h), written out as
// pidlab_pid.h and pidlab_pid.c for a firmware project (docs/export.md).
//
// The generated step is DiscretePid::Step in the same operation order, with
// the 2-DOF setpoint weights b (proportional) and c (derivative):
//   e = r - y,  p = kp (b r - y),  I as DiscretePid (on e),
//   s = c r - y,  D = tf/(tf+dt) D + kd (s - s_prev) (1/(tf+dt)),
//   u = sat(p + I + D) with DiscretePid's clamping or back-calculation.
// b = c = 1 is DiscretePid with derivative on error; c = 0 on measurement.
// With Scalar::kDouble the outputs equal DiscretePid<double>'s bit for bit
// (tests/export_test.cc); kFloat runs the same code in float; kQ31 and kQ15
// run it in saturating fixed point, scaled from the gains and the declared
// input range, with the range analysis in the generated comment.
//
// On top of DiscretePid the module has what firmware needs and a simulation
// does not: a manual mode whose output follows a given u while the
// integrator tracks it (bumpless transfer back to automatic), and run-time
// changes of gains, setpoint weights and sample time without a bump.

#include <string>

#include "pidlab/controller/pid.h"

namespace pidlab::controller_export {

/// The number type of the generated controller.
enum class Scalar { kDouble, kFloat, kQ31, kQ15 };
bool ParseScalar(const std::string& s, Scalar* v);
std::string ToString(Scalar v);

/// The controller to export: what DiscretePid runs, plus the setpoint weights.
struct Controller {
  /// kp, ki, kd and tf (s); tf = 0 takes pid.derivative_filter_s
  /// (EffectiveDerivativeFilter), as DiscretePid does.
  PidGains gains;
  /// Sample time, limits, anti-windup, integration rule. The derivative's
  /// signal is setpoint_weight_c's (c = 0: on measurement), whatever else
  /// the options say.
  PidOptions pid;
  /// Setpoint weight of the proportional term, in [0, 1].
  double setpoint_weight_b = 1.0;
  /// Setpoint weight of the derivative term, in [0, 1]; 0 = derivative on
  /// measurement.
  double setpoint_weight_c = 1.0;
};

struct Options {
  Scalar scalar = Scalar::kDouble;
  /// Fixed point (kQ31, kQ15): the declared range of r and y, in the loop's
  /// units; lo < hi, both finite. Inside it no intermediate overflows;
  /// outside it the inputs saturate to it. Unused by kDouble and kFloat.
  double input_min = -1.0;
  double input_max = 1.0;
  /// The plant the controller was tuned on, one line for the header comment
  /// (e.g. "oscillator = 1/(s^2+1)").
  std::string plant;
  /// The spec it came from, as JSON text, for the header comment.
  std::string spec_json;
  /// The pidlab version that generated it.
  std::string pidlab_version;
  /// Where the period dt came from (e.g. "given: --dt"), for the header comment.
  std::string dt_source;
  /// What pidlab found of the plant's sampled loop at dt, for the header comment.
  std::string loop_check;
  /// Also the relay autotune (`--autotune`, docs/autotune.md): pidlab_relay.h
  /// and pidlab_relay.c, controller/relay.h's RelayTuner over this PID.
  /// Double, q31 and q15 (RelayTuneOptions::q_bits); not float.
  bool autotune = false;

  /// False with *error naming the field, its value and the rule broken.
  bool IsValid(std::string* error) const;
};

/// The two files' text.
struct GeneratedCode {
  std::string header;  // pidlab_pid.h
  std::string source;  // pidlab_pid.c
  std::string relay_header;  // pidlab_relay.h (Options::autotune), else empty
  std::string relay_source;  // pidlab_relay.c
};

/// The controller as C99. Throws std::invalid_argument naming the value for
/// invalid options or an invalid controller (gains, PID options, weights, or
/// fixed point that cannot represent them).
GeneratedCode Generate(const Options& options, const Controller& controller);

/// Fixed point's grids (q31, q15): y = q input_full_scale 2^-bits, u = q
/// output_full_scale 2^-bits, as Generate scales them. Throws
/// std::invalid_argument as Generate does for a controller fixed point
/// cannot hold.
struct FixedScale {
  int bits = 31;
  double input_full_scale = 1.0;
  double output_full_scale = 1.0;
};
FixedScale FixedPointScale(const Options& options, const Controller& controller);

/// Checks the controller as Generate does; false with *error.
bool ControllerIsValid(const Controller& controller, std::string* error);

}  // namespace pidlab::controller_export
