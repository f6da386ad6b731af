#pragma once
// PID tuning: a search method on the paper's objective (or ISE/ITAE/
// continuous IAE), over the gain box, followed by a Ceres least-squares
// cross-check of the result.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/tuner/evaluation.h"
#include "pidlab/tuner/optimizer.h"
#include "pidlab/tuner/ziegler_nichols.h"

namespace pidlab {

enum class TuneMethod { kNelderMead, kPaperNelderMead, kZieglerNichols, kGeneticAlgorithm, kPsoGsa };
/// nelder-mead | paper-nm | ziegler-nichols | ga | pso-gsa
bool ParseTuneMethod(const std::string& s, TuneMethod* method);
std::string ToString(TuneMethod method);

struct TuneOptions {
  TuneMethod method = TuneMethod::kNelderMead;
  ObjectiveKind objective = ObjectiveKind::kIae;
  /// The loop the objective is evaluated on (default: the paper's continuous
  /// loop, ts = 0.05 s, n = 25 s, no disturbance). Its stability_margin is the
  /// acceptance margin of candidates; TuneOptions() raises it to 0.01, because
  /// with a margin near zero the search parks poles a hair left of the
  /// imaginary axis where the sampled objective cannot see them.
  LoopOptions loop = DefaultTuneLoop();
  static LoopOptions DefaultTuneLoop() {
    LoopOptions o;
    o.stability_margin = 0.01;
    return o;
  }
  /// Search box, the same for kp, ki and kd (paper: 0 to 30).
  double lower = 0.0;
  double upper = 30.0;
  /// Iteration budget; 0 = the method's default (100 for paper-nm, as the paper).
  int max_iterations = 0;
  /// Evaluation budget over all starts; 0 = the method's default.
  int max_evaluations = 0;
  /// Independent seeded starts (nelder-mead, paper-nm).
  int starts = 4;
  /// nelder-mead: Gao & Han's dimension-dependent coefficients instead of
  /// (1, 2, 1/2, 1/2).
  bool adaptive = false;
  std::uint64_t seed = 1;
  /// Constraints on the undisturbed step response (+inf = none): a candidate
  /// violating them is rejected like an unstable loop.
  double max_overshoot_pct = std::numeric_limits<double>::infinity();
  double max_settling_time_s = std::numeric_limits<double>::infinity();
  /// Run the Ceres cross-check after the search.
  bool refine = true;
  /// Verdict "agree" when |f_ceres - f_search| <= agree_tolerance * f_search.
  double agree_tolerance = 1e-3;
  /// Ziegler-Nichols rule (ziegler-nichols only).
  ZieglerNicholsRule zn_rule = ZieglerNicholsRule::kClassic;

  bool IsValid(std::string* error) const;
};

/// The Ceres cross-check: starting from the search result, a bound-constrained
/// least-squares problem whose minimum is the same objective, with derivatives
/// by automatic differentiation through the templated loop.
struct RefineSummary {
  bool ran = false;
  PidGains gains;
  double objective = std::numeric_limits<double>::infinity();  // re-evaluated exactly
  std::string termination;                                     // Ceres's termination type
  int iterations = 0;
  /// "agree", "nelder-mead stopped short" (Ceres found better; its gains are
  /// returned), or "not run".
  std::string verdict = "not run";
  /// (f_search - f_ceres) / f_search.
  double relative_improvement = 0.0;
  std::string message;
};

struct TuneSummary {
  TuneMethod method = TuneMethod::kNelderMead;
  /// Best gains found (the Ceres gains if it found better), and their objective.
  PidGains gains;
  double objective = std::numeric_limits<double>::infinity();
  /// The search method's own result before the cross-check.
  PidGains search_gains;
  double search_objective = std::numeric_limits<double>::infinity();
  bool stable = false;
  int evaluations = 0;
  int iterations = 0;
  double wall_time_s = 0.0;
  OptimizerSummary optimizer;            // empty for ziegler-nichols
  ZieglerNicholsResult ziegler_nichols;  // ziegler-nichols only
  RefineSummary refine;
  std::string message;
  std::string BriefReport() const;
};

/// Tunes the PID for `plant`. Returns false with *error for invalid input or
/// when the method does not apply (e.g. Ziegler-Nichols on 1/s^2).
/// `runner` evaluates the sampled loop (in-process, or episodes over the LCM trio).
bool Tune(const Plant& plant, const TuneOptions& options, TuneSummary* summary, std::string* error,
          const ProgressCallback& progress = nullptr, const SampledRunner& runner = RunSampledLoopInProcess);

/// The Ceres cross-check alone, from `start` (used by Tune).
RefineSummary RefineWithCeres(const Plant& plant, const TuneOptions& options, const PidGains& start,
                              double start_objective);

}  // namespace pidlab
