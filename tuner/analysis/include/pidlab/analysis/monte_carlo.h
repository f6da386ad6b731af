#pragma once
// Parametric robustness: one gain set on N plants drawn around the nominal
// one (docs/robustness.md, "Monte Carlo").
//
// Draws, seeded and reproducible on every platform (mt19937_64 and a fixed
// map of its 64 bits to u in [-1, 1)):
//  * the stepper motor: each of the nine Table I parameters p becomes
//    p (1 + spread u), independently, and G(s) is rebuilt by eq. (3);
//  * any other plant (the built-in 1/s^2 and 1/(s^2+1), a custom one): the
//    transfer function is first divided by its leading denominator
//    coefficient, which stays 1; every other coefficient c becomes
//    c (1 + spread u). A zero coefficient stays zero (1/s^2 keeps its double
//    pole at 0 and only its gain moves). A dead time is kept as it is;
//  * an identified model with a covariance (Plant::model, HasCovariance):
//    its parameter vector is drawn from the multivariate normal N(values,
//    covariance) (a Cholesky factor times standard normals by Box-Muller),
//    redrawn while a time constant is <= 0, Zeta is outside (0, 1) or Td < 0
//    (a truncated normal, at most kMaxModelRedraws redraws per plant), and
//    made a plant through the process model, its delay Td included. `spread`
//    does not apply. A model without a covariance is drawn as any other
//    plant, its coefficients within `spread`, its delay kept.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/spec/status.h"

namespace pidlab::analysis {

/// How many times one draw of a model is redrawn before it counts as invalid.
inline constexpr int kMaxModelRedraws = 1000;

/// MonteCarloSummary::perturbed of draws from a model's covariance.
inline constexpr const char* kCovariancePerturbed = "identified model's parameter covariance";

/// True when `plant`'s draws come from its identified model's covariance.
inline bool DrawsFromCovariance(const Plant& plant) { return plant.model && plant.model->HasCovariance(); }

struct MonteCarloOptions {
  /// Number of plants drawn, 1 .. 100000.
  int samples = 100;
  /// Relative half-width of the uniform perturbation, [0, 1) (0.1 = 10 %).
  double spread = 0.1;
  std::uint64_t seed = 1;
  /// Compute the overshoot distribution (step metrics of every draw; a nearly
  /// marginal draw can cost seconds). False: overshoot_pct stays empty.
  bool overshoot = true;

  bool IsValid(std::string* error) const;
};

/// Order statistics over the stable draws where the value is finite:
/// min, median (mean of the two middle values for an even count), p95
/// (nearest rank: the ceil(0.95 n)-th smallest), max. NaN when count = 0.
struct Distribution {
  int count = 0;
  double min = 0, median = 0, p95 = 0, max = 0;
};
Distribution Summarize(std::vector<double> values);

struct MonteCarloSummary {
  int samples = 0;
  /// Draws whose loop is strictly stable (LoopOptions::stability_margin);
  /// a draw whose parameters give no valid plant counts as not stable.
  int stable = 0;
  double stable_fraction = 0.0;
  /// Draws whose parameters gave no valid plant (also not stable).
  int invalid = 0;
  /// The IAE of options (eq. 4, with its disturbance), the undisturbed step
  /// overshoot (where stepinfo is defined) and Ms of options.loop.
  Distribution iae, overshoot_pct, ms;
  /// Redraws of a model's parameter vectors that were not a model's (the
  /// truncated normal; 0 for other plants).
  int redrawn = 0;
  /// "Table I parameters", "transfer-function coefficients" or "identified
  /// model's parameter covariance" (PerturbedText).
  std::string perturbed;
};

/// The plants of the draw (samples of them). `stepper` is the stepper
/// motor's Table I parameters when `nominal` is that motor, else null.
/// A draw whose parameters are invalid is returned with an empty tf.
/// *redrawn (when given) counts a model's redraws.
std::vector<Plant> DrawPlants(const Plant& nominal, const StepperMotorParameters* stepper,
                              const MonteCarloOptions& options, int* redrawn = nullptr);

/// What the draws of `nominal` perturb, in words (MonteCarloSummary::perturbed).
std::string PerturbedText(const Plant& nominal, const StepperMotorParameters* stepper);

/// Evaluates `gains` on every plant of DrawPlants. kInvalidInput for invalid
/// input (the nominal evaluation's errors). `progress(done, total)`
/// is called after each draw when set.
Status RunMonteCarlo(const Plant& nominal, const StepperMotorParameters* stepper, const PidGains& gains,
                     const evaluation::LoopOptions& options, const MonteCarloOptions& mc,
                     MonteCarloSummary* summary, const std::function<void(int, int)>& progress = nullptr);

}  // namespace pidlab::analysis
