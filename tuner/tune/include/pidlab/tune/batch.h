#pragma once
// The AMIGO test batch (docs/deadtime.md, "The AMIGO test batch"): the
// families P1-P9 of Astrom and Hagglund's test batch for PID design
// ("Advanced PID Control", ISA 2006, sec. 7.2; J. Process Control 14 (2004)
// 635-650), and for every plant AMIGO's PID against pidlab's optimum of the
// load IAE under Ms <= 1.4, both with the same filtered derivative and scored
// on the same loop.
//
// Pure library: no printing; progress through a callback; the plants run on
// `jobs` threads and the results do not depend on how many.

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/tuning_rules.h"

namespace pidlab::tune {

/// One plant of the batch.
struct BatchPlant {
  std::string family;     // "P1" ... "P9"
  std::string parameter;  // "T", "n", "alpha", "L1"
  double value = 0.0;     // the parameter's value
  std::string label;      // e.g. "T = 2"; P7: "T = 2, L1 = 0.3"
  Plant plant;            // the transfer function and dead time
  /// The plant in factors, what the half rule reads for AMIGO's model (P9's
  /// lightly damped pair is replaced by a double real pole of the same
  /// sum of time constants; docs/deadtime.md).
  FactoredPlant factors;
};

/// The families of `set` ("amigo", the only one), in order P1 ... P9, each
/// over its published grid. False for an unknown set.
bool TestBatchPlants(const std::string& set, std::vector<BatchPlant>* plants);
/// The plants of the named families only ("P1", "P4"; each must exist):
/// kInvalidInput naming the first unknown one.
Status SelectFamilies(const std::vector<BatchPlant>& all, const std::vector<std::string>& families,
                      std::vector<BatchPlant>* selected);

struct BatchOptions {
  /// The loop both controllers are scored on. Sampled until the continuous
  /// loop with dead time exists; continuous takes only delay-free plants.
  evaluation::LoopKind loop = evaluation::LoopKind::kSampled;
  /// Sampled loop: dt = L / steps_per_delay, L the AMIGO model's dead time.
  double steps_per_delay = 20.0;
  /// The horizon: horizon_factor (L + Ti) of AMIGO's model and controller.
  double horizon_factor = 20.0;
  /// Strict stability margin of the loop (closed_loop.h).
  double stability_margin = 1e-3;
  /// N of the derivative filter Tf = Td / N, for AMIGO and pidlab alike.
  double filter_ratio = 10.0;
  /// The robustness bound of pidlab's optimum, and the tolerance of its
  /// check by the full analysis.
  double max_ms = 1.4;
  double ms_tolerance = 1e-3;
  /// Evaluation budgets: the multi-start over the plant's box, and the
  /// Nelder-Mead started from AMIGO's gains.
  int search_evaluations = 1200;
  int polish_evaluations = 600;
  std::uint64_t seed = 1;
  /// Threads over the plants; 0 = std::thread::hardware_concurrency().
  int jobs = 0;
  bool IsValid(std::string* error) const;
};

/// One plant's outcome.
struct BatchResult {
  BatchPlant plant;
  ProcessModel model;  // AMIGO's model (half rule)
  /// tau = L / (L + T) of the FOPDT model; 0 for an ipdt model (T infinite).
  double tau = 0.0;
  double dt_s = 0.0, horizon_s = 0.0;
  double box_upper = 0.0;  // the search box [0, box_upper]^3
  /// AMIGO: K, Ti, Td, the gains (with tf = Td / N), Ms, load IAE.
  double amigo_k = 0.0, amigo_ti_s = 0.0, amigo_td_s = 0.0;
  PidGains amigo_gains;
  double amigo_ms = 0.0, amigo_load_iae = 0.0;
  bool amigo_feasible = false;  // stable and Ms <= max_ms + ms_tolerance
  /// pidlab: the best of the multi-start, the Nelder-Mead from AMIGO's gains
  /// (scaled down by the largest factor c <= 1 that gives Ms <= max_ms when
  /// AMIGO's own loop breaks it), and AMIGO itself when feasible (else the
  /// scaled gains); `source` says which.
  PidGains gains;
  double ms = 0.0, load_iae = 0.0;
  bool feasible = false;  // stable and Ms <= max_ms + ms_tolerance by the full analysis
  std::string source;
  std::vector<std::string> at_bounds;
  /// pidlab's load IAE over AMIGO's (NaN when either is not finite).
  double ratio = 0.0;
  double wall_time_s = 0.0;
  std::string message;  // why a number is missing, or ""
};

/// AMIGO and pidlab on one plant. kInvalidInput for invalid options; a plant
/// where something fails is reported in the result (message), not as an
/// error.
Status RunBatchPlant(const BatchPlant& plant, const BatchOptions& options, BatchResult* result);

/// Every plant on options.jobs threads, results in the plants' order.
/// `progress(done, total)` is called after each plant (from the worker
/// threads, one call at a time).
Status RunBatch(const std::vector<BatchPlant>& plants, const BatchOptions& options,
                std::vector<BatchResult>* results,
                const std::function<void(int done, int total)>& progress = nullptr);

/// The batch in a few numbers. On the plants where both AMIGO and pidlab
/// meet the Ms bound, a win is pidlab's load IAE below AMIGO's by more than
/// 1e-9 relative, a loss above it, else a tie; the ratios' range over those
/// plants and pidlab's largest feasible Ms (NaN where there is none).
struct BatchTally {
  int plants = 0, amigo_feasible = 0, pidlab_feasible = 0, wins = 0, ties = 0, losses = 0;
  double best_ratio = std::numeric_limits<double>::quiet_NaN();
  double worst_ratio = std::numeric_limits<double>::quiet_NaN();
  double max_ms = std::numeric_limits<double>::quiet_NaN();
};

BatchTally TallyBatch(const std::vector<BatchResult>& results);

}  // namespace pidlab::tune
