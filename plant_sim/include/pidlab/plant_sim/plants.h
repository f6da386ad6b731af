#pragma once
// The built-in plants of the paper and user transfer functions.

#include <memory>
#include <string>
#include <vector>

#include "pidlab/plant_sim/process_model.h"
#include "pidlab/plant_sim/transfer_function.h"
#include "pidlab/spec/status.h"

namespace pidlab {

/// Table I of the paper, SI units. J is read as 0.16e-4 kg m^2 (the table's
/// "g.m^2" unit label notwithstanding): with it eq. (3) reproduces every
/// published IAE of Tables IV-VI to four digits.
struct StepperMotorParameters {
  double resistance_ohm = 33.0;                            // r, stator resistance
  double self_inductance_h = 5.4e-3;                       // L
  double mutual_inductance_h = 0.4e-3;                     // M
  double inertia_kg_m2 = 0.16e-4;                          // J
  double rotor_teeth = 6.0;                                // N_r
  double viscous_friction = 1.35e-5;                       // D, N m s / rad
  double tooth_pitch_rad = 3.14159265358979323846 / 12.0;  // lambda
  double stationary_current_a = 0.15;                      // I_o
  double flux_linkage = 1.2e-3;                            // n Phi_M, T m^2

  /// All finite, positive (M and D may be 0) and at most
  /// kMaxCoefficientMagnitude, L > M, and cos(N_r lambda / 2) > 0.
  bool IsValid(std::string* error) const;
};

/// Eq. (3): G(s) = (r/L) w^2 / (s^3 + (r/Lp + D/J) s^2 + (r D/(Lp J) + w^2 (1 + kp)) s + (r/Lp) w^2).
/// Throws std::invalid_argument for invalid parameters.
TransferFunction StepperMotorTransferFunction(const StepperMotorParameters& p);

/// A named plant. `name` is the canonical name (double_integrator,
/// oscillator, stepper_motor or custom).
struct NonlinearStepperOptions;  // stepper_nonlinear.h

struct Plant {
  std::string name;
  /// The plant, or for a nonlinear plant its linearisation at the operating
  /// point (used for the closed-loop stability gate and as the reference).
  TransferFunction tf;
  /// Set for stepper_nonlinear: the sampled loop integrates this model.
  std::shared_ptr<const NonlinearStepperOptions> nonlinear = nullptr;
  /// Dead time L of the plant, G(s) e^(-sL), s: at least 0 and finite
  /// (docs/deadtime.md). 0 is the plant without delay.
  double delay_s = 0.0;
  /// Set for an identified model (plant model:FILE): its kind, parameters
  /// and their covariance, from which the Monte Carlo and robust-set draws
  /// come (tf and delay_s are the model's at its values).
  std::shared_ptr<const plant_sim::ProcessModelUncertainty> model = nullptr;
};

/// Canonical names and aliases accepted by MakePlant.
std::vector<std::string> BuiltinPlantNames();

/// Builds a built-in plant by name or alias: double_integrator (linear) = 1/s^2,
/// oscillator (nonlinear) = 1/(s^2+1), stepper_motor (stepper) = eq. (3) with
/// `stepper`, stepper_nonlinear = the nonlinear motor of stepper_nonlinear.h
/// with `stepper` and default options (MakeNonlinearStepperPlant for others). A failed Status (kInvalidInput)
/// naming the value for an unknown name, invalid stepper parameters, or parameters whose G(s) is not a valid
/// TransferFunction (a coefficient out of the limits).
Status MakePlant(const std::string& name, const StepperMotorParameters& stepper, Plant* plant);

/// The nonlinear stepper with its options; tf is its linearisation. A failed
/// Status (kInvalidInput) naming the option.
Status MakeNonlinearStepperPlant(const NonlinearStepperOptions& options, Plant* plant);

/// A user plant from coefficient lists; must be valid and strictly proper (a
/// failed Status, kInvalidInput, otherwise).
Status MakeCustomPlant(const std::vector<double>& num, const std::vector<double>& den, Plant* plant);

}  // namespace pidlab
