#pragma once
// The gain box a search runs in, derived from the plant's scale, and which
// bounds an optimum lies on (docs/tuning.md, "The search box").
//
// The paper's box [0, 30]^3 suits its three plants, whose gains are of order
// one to thirty. A plant of time constant 1000 s or gain 0.01 needs gains of
// a different order, so a tuning with no `bounds` given takes its box from
// the plant: AMIGO's PID (tuning_rules.h) on the plant's FOPDT or IPDT model
// (Skogestad's half rule), and the box [0, 10 max(kp, ki, kd)] around it. A
// plant the rule refuses (1/s^2, 1/(s^2 + 1), the stepper motor: the paper's
// plants) keeps [0, 30]. `bounds` given by the user (or by a spec file, the
// echo of a --json result) always wins.

#include <set>
#include <string>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

/// The box's upper end over AMIGO's largest gain on the plant's model.
inline constexpr double kPlantBoxFactor = 10.0;

/// A gain box [lower, upper]^3 and where it came from.
struct SearchBox {
  double lower = 0.0;
  double upper = 30.0;
  /// "given" (the user's bounds), "plant" (derived) or "default" (the paper's [0, 30]).
  std::string source = "default";
  /// One line: the rule and model the plant's box came from, or why the
  /// default stands.
  std::string message;
};

/// The box from the plant's scale: [0, kPlantBoxFactor max(kp, ki, kd)] of
/// AMIGO's PID on the plant's half-rule model. kInvalidInput (with the rule's
/// reason) where AMIGO does not apply; `box` then keeps the default.
Status PlantSearchBox(const Plant& plant, SearchBox* box);

/// Resolves the spec's box: with no `bounds` among the `given` keys and a
/// search method (not ziegler-nichols, simc or amigo, which use no box), sets
/// s->tune.bounds to PlantSearchBox's box when the plant has one. The spec
/// then says the box that ran, so its echo runs again to the same numbers.
/// Returns the box and its source. A plant that does not build leaves the
/// spec as it is (BuildPlant reports it afterwards).
SearchBox ResolveSearchBox(spec::TuningSpec* s, const std::set<std::string>& given);

/// The bounds `g` lies on, in the order kp_lo, kp_hi, ki_lo, ki_hi, kd_lo,
/// kd_hi: a gain within 1e-6 (upper - lower) of an end (so kd_lo for a PI
/// optimum, ki_lo for a PD one).
std::vector<std::string> GainsAtBounds(const PidGains& g, double lower, double upper);

}  // namespace pidlab::tune
