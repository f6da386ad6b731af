#include "pidlab/plant_sim/plants.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pidlab/plant_sim/stepper_nonlinear.h"

namespace pidlab {

bool StepperMotorParameters::IsValid(std::string* error) const {
  const std::pair<const char*, double> fields[] = {{"resistance_ohm", resistance_ohm},
                                                   {"self_inductance_h", self_inductance_h},
                                                   {"mutual_inductance_h", mutual_inductance_h},
                                                   {"inertia_kg_m2", inertia_kg_m2},
                                                   {"rotor_teeth", rotor_teeth},
                                                   {"viscous_friction", viscous_friction},
                                                   {"tooth_pitch_rad", tooth_pitch_rad},
                                                   {"stationary_current_a", stationary_current_a},
                                                   {"flux_linkage", flux_linkage}};
  for (const auto& [name, v] : fields) {
    if (!std::isfinite(v) || v < 0.0 || v > kMaxCoefficientMagnitude ||
        (v == 0.0 && std::string(name) != "mutual_inductance_h" && std::string(name) != "viscous_friction")) {
      if (error) {
        std::ostringstream os;
        os << "stepper motor " << name << " = " << v << " must be finite, positive and at most "
           << kMaxCoefficientMagnitude;
        *error = os.str();
      }
      return false;
    }
  }
  if (self_inductance_h <= mutual_inductance_h) {
    if (error) *error = "stepper motor self_inductance_h must exceed mutual_inductance_h (Lp = L - M > 0)";
    return false;
  }
  if (std::cos(rotor_teeth * tooth_pitch_rad / 2.0) <= 0.0) {
    if (error) *error = "stepper motor cos(rotor_teeth * tooth_pitch_rad / 2) must be positive";
    return false;
  }
  return true;
}

TransferFunction StepperMotorTransferFunction(const StepperMotorParameters& p) {
  std::string error;
  if (!p.IsValid(&error)) throw std::invalid_argument(error);
  const double lp = p.self_inductance_h - p.mutual_inductance_h;
  const double half_angle = p.rotor_teeth * p.tooth_pitch_rad / 2.0;
  const double wnp2 = 2.0 * p.rotor_teeth * p.rotor_teeth * p.flux_linkage * p.stationary_current_a *
                      std::cos(half_angle) / p.inertia_kg_m2;
  const double kp = p.flux_linkage * std::sin(half_angle) * std::sin(half_angle) /
                    (lp * p.stationary_current_a * std::cos(half_angle));
  const double r_lp = p.resistance_ohm / lp;
  const double d_j = p.viscous_friction / p.inertia_kg_m2;
  TransferFunction tf;
  tf.num = {p.resistance_ohm / p.self_inductance_h * wnp2};
  tf.den = {1.0, r_lp + d_j, r_lp * d_j + wnp2 * (1.0 + kp), r_lp * wnp2};
  return tf;
}

std::vector<std::string> BuiltinPlantNames() {
  return {"double_integrator", "linear",  "oscillator",       "nonlinear",
          "stepper_motor",     "stepper", "stepper_nonlinear"};
}

namespace {

// MakePlant() with the refusal's message in *error.
bool MakePlantOrExplain(const std::string& name, const StepperMotorParameters& stepper, Plant* plant,
                        std::string* error) {
  if (name == "double_integrator" || name == "linear") {
    *plant = {"double_integrator", {{1.0}, {1.0, 0.0, 0.0}}};
  } else if (name == "oscillator" || name == "nonlinear") {
    *plant = {"oscillator", {{1.0}, {1.0, 0.0, 1.0}}};
  } else if (name == "stepper_motor" || name == "stepper") {
    if (!stepper.IsValid(error)) return false;
    *plant = {"stepper_motor", StepperMotorTransferFunction(stepper)};
    std::string why;
    if (!plant->tf.IsValid(&why)) {
      if (error) *error = "these stepper motor parameters give G(s) = " + plant->tf.ToString() + ": " + why;
      return false;
    }
  } else if (name == "stepper_nonlinear") {
    NonlinearStepperOptions o;
    o.motor = stepper;
    const Status st = MakeNonlinearStepperPlant(o, plant);
    if (!st.ok() && error) *error = st.message();
    return st.ok();
  } else {
    if (error)
      *error = "unknown plant '" + name +
               "' (expected double_integrator|linear, oscillator|nonlinear, stepper_motor|stepper, "
               "stepper_nonlinear, or custom with --num/--den)";
    return false;
  }
  return true;
}

}  // namespace

Status MakePlant(const std::string& name, const StepperMotorParameters& stepper, Plant* plant) {
  std::string why;
  if (!MakePlantOrExplain(name, stepper, plant, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

namespace {

// MakeNonlinearStepperPlant() with the refusal's message in *error.
bool MakeNonlinearStepperPlantOrExplain(const NonlinearStepperOptions& options, Plant* plant,
                                        std::string* error) {
  if (!options.IsValid(error)) return false;
  // The linearisation is taken without load (and its detent must keep the
  // holding point an equilibrium): it is the stability gate and the reference.
  StepperLinearization lin;
  if (const Status st = LinearizeStepper(options, &lin); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  std::string why;
  if (!lin.tf.IsValid(&why)) {
    if (error) *error = "the linearised stepper G(s) = " + lin.tf.ToString() + " is out of range: " + why;
    return false;
  }
  *plant = {"stepper_nonlinear", lin.tf, std::make_shared<const NonlinearStepperOptions>(options)};
  return true;
}

}  // namespace

Status MakeNonlinearStepperPlant(const NonlinearStepperOptions& options, Plant* plant) {
  std::string why;
  if (!MakeNonlinearStepperPlantOrExplain(options, plant, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

namespace {

// MakeCustomPlant() with the refusal's message in *error.
bool MakeCustomPlantOrExplain(const std::vector<double>& num, const std::vector<double>& den, Plant* plant,
                              std::string* error) {
  TransferFunction tf{num, den};
  if (!tf.IsValid(error)) return false;
  if (tf.RelativeDegree() < 1) {
    if (error) *error = "plant " + tf.ToString() + " must be strictly proper (deg num < deg den)";
    return false;
  }
  *plant = {"custom", tf};
  return true;
}

}  // namespace

Status MakeCustomPlant(const std::vector<double>& num, const std::vector<double>& den, Plant* plant) {
  std::string why;
  if (!MakeCustomPlantOrExplain(num, den, plant, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab
