// The Ceres cross-check of a tuning result.
//
// The paper's objective sum_m |e_m| is not a sum of squares, so it is written
// as one: residual r_m = w_m (e_m^2 + eps^2)^(1/4), whose square
// w_m^2 sqrt(e_m^2 + eps^2) is a smooth |e_m| (w_m = 1 for IAE, sqrt(t_m) for
// ITAE; ISE uses r_m = e_m directly). The gains are bounded by the tuning box.
// Derivatives come from automatic differentiation through the same templated
// closed loop that the objective uses (matrix exponential and all), so there
// are no finite differences. The result is re-evaluated with the exact,
// unsmoothed objective before any verdict.

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "pidlab/tune/tune.h"

namespace pidlab::tune {
namespace {

// Smoothing of |e| in the least-squares form; small against the errors that
// matter (the paper's IAE has 501 samples of up to 1) but keeps the Jacobian
// finite where e crosses zero.
constexpr double kSmoothing = 1e-6;

struct ErrorResiduals {
  const StateSpace* realization;
  const Plant* plant;
  const evaluation::LoopOptions* loop;
  const DiscretePlant* discrete;  // sampled loop only
  evaluation::ObjectiveKind kind;

  template <typename T>
  bool operator()(const T* const gains, T* residuals) const {
    // The loop's derivative filter (a ratio makes tf a function of kp and kd,
    // differentiated with them).
    const PidGainsT<T> g = evaluation::LoopGains(PidGainsT<T>{gains[0], gains[1], gains[2]}, *loop);
    const PidGains gd =
        evaluation::LoopGains(PidGains{ToDouble(gains[0]), ToDouble(gains[1]), ToDouble(gains[2])}, *loop);
    if (!GainsAreValid(gd, nullptr)) return false;
    const Disturbance disturbance(loop->disturbance);
    std::vector<T> y;
    const double ts = loop->sample_time_s;
    if (loop->loop == evaluation::LoopKind::kContinuous) {
      evaluation::ContinuousClosedLoop<T> cl;
      if (!evaluation::BuildContinuousClosedLoop<T>(*realization, g, disturbance, &cl, loop->reference,
                                                    evaluation::SetpointWeightsOf(loop->pid))
               .ok())
        return false;
      evaluation::ContinuousClosedLoop<double> cld;
      if (!evaluation::BuildContinuousClosedLoop<double>(*realization, gd, disturbance, &cld, loop->reference)
               .ok())
        return false;
      if (!evaluation::ContinuousStability(cld, loop->stability_margin).stable) return false;
      evaluation::SampleContinuousLoop<T>(cl, disturbance, ts, loop->NumSamples(), &y);
    } else {
      PidOptions pid = loop->Pid();
      if (!evaluation::SampledLoopIsStable(*discrete, gd, pid, loop->stability_margin)) return false;
      if (evaluation::RunSampledLoop<T>(*discrete, g, pid, disturbance, loop->TotalSteps(),
                                        loop->StepsPerSample(), &y, nullptr,
                                        loop->reference) == PidStatus::kInvalidInput)
        return false;  // the loop diverged: no residuals at this point
    }
    for (std::size_t m = 0; m < y.size(); ++m) {
      const T e = T(loop->reference) - y[m];
      switch (kind) {
        case evaluation::ObjectiveKind::kIse:
          residuals[m] = e;
          break;
        case evaluation::ObjectiveKind::kIae:
          residuals[m] = sqrt(sqrt(e * e + T(kSmoothing * kSmoothing)));
          break;
        case evaluation::ObjectiveKind::kItae:
          residuals[m] =
              T(std::sqrt(static_cast<double>(m) * ts)) * sqrt(sqrt(e * e + T(kSmoothing * kSmoothing)));
          break;
        case evaluation::ObjectiveKind::kIaeContinuous:
        case evaluation::ObjectiveKind::kLoadIae:
        case evaluation::ObjectiveKind::kSetpointLoad:
          return false;
      }
    }
    return true;
  }
};

RefineTermination FromCeres(ceres::TerminationType type) {
  switch (type) {
    case ceres::CONVERGENCE:
      return RefineTermination::kConvergence;
    case ceres::NO_CONVERGENCE:
      return RefineTermination::kNoConvergence;
    case ceres::FAILURE:
      return RefineTermination::kFailure;
    case ceres::USER_SUCCESS:
      return RefineTermination::kUserSuccess;
    case ceres::USER_FAILURE:
      return RefineTermination::kUserFailure;
  }
  return RefineTermination::kFailure;
}

// Runs the bound-constrained least-squares problem from `start`; the solution
// is left in *refined, Ceres's termination and iteration count in *summary.
void SolveLeastSquares(const Plant& plant, const TuneOptions& options, const PidGains& start,
                       PidGains* refined, RefineSummary* summary) {
  const StateSpace realization = Realize(plant.tf);
  std::unique_ptr<DiscretePlant> discrete;
  if (options.loop.loop == evaluation::LoopKind::kSampled)
    discrete = std::make_unique<DiscretePlant>(evaluation::SampledPlant(plant, options.loop.dt_s));
  double x[3] = {start.kp, start.ki, start.kd};
  ceres::Problem problem;
  auto* cost = new ceres::AutoDiffCostFunction<ErrorResiduals, ceres::DYNAMIC, 3>(
      new ErrorResiduals{&realization, &plant, &options.loop, discrete.get(), options.objective},
      options.loop.NumSamples());
  problem.AddResidualBlock(cost, nullptr, x);
  for (int i = 0; i < 3; ++i) {
    problem.SetParameterLowerBound(x, i, options.lower);
    problem.SetParameterUpperBound(x, i, options.upper);
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 200;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver, &problem, &ceres_summary);
  summary->ran = true;
  summary->termination = FromCeres(ceres_summary.termination_type);
  summary->iterations = static_cast<int>(ceres_summary.iterations.size()) - 1;
  *refined = PidGains{x[0], x[1], x[2]};
}

// The verdict on Ceres's point, whose exact objective is f, against the
// search's start_objective; keeps Ceres's gains where they are better.
void Judge(const TuneOptions& options, const PidGains& refined, double f, double start_objective,
           RefineSummary* summary) {
  summary->relative_improvement = (start_objective - f) / start_objective;
  if (std::isfinite(f) && f < start_objective * (1.0 - options.agree_tolerance)) {
    summary->verdict = RefineVerdict::kSearchStoppedShort;
    summary->gains = refined;
    summary->objective = f;
    summary->message = "Ceres lowered the objective by " +
                       std::to_string(100.0 * summary->relative_improvement) + " %; its gains are returned";
  } else if (std::isfinite(f) && std::abs(f - start_objective) <= options.agree_tolerance * start_objective) {
    summary->verdict = RefineVerdict::kAgree;
    if (f < start_objective) {
      summary->gains = refined;
      summary->objective = f;
    }
    summary->message =
        "Ceres and the search agree within " + std::to_string(100.0 * options.agree_tolerance) + " %";
  } else {
    summary->verdict = RefineVerdict::kSearchBetter;
    summary->message = "Ceres's smooth least-squares optimum is worse on the exact objective (" +
                       std::to_string(f) + "); the search result stands";
  }
}

}  // namespace

namespace {

// Why the cross-check cannot run from `start_objective` ("" when it can).
std::string WhyNotRun(const Plant& plant, const TuneOptions& options, double start_objective) {
  if (options.loop.loop == evaluation::LoopKind::kContinuous && plant.delay_s > 0.0)
    return "not run: the continuous loop with dead time has no templated (differentiable) path; the "
           "search's result stands";
  if (options.objective == evaluation::ObjectiveKind::kIaeContinuous)
    return "not run: iae-continuous has no sample least-squares form";
  if (options.objective == evaluation::ObjectiveKind::kLoadIae ||
      options.objective == evaluation::ObjectiveKind::kSetpointLoad)
    return "not run: " + ToString(options.objective) + " has no least-squares form in pidlab yet";
  if (!std::isfinite(start_objective)) return "not run: the search found no stable loop";
  return "";
}

// Ceres from `start`: its point in *refined and that point's exact objective.
double SolveAndEvaluate(const Plant& plant, const TuneOptions& options, const PidGains& start,
                        PidGains* refined, RefineSummary* summary) {
  SolveLeastSquares(plant, options, start, refined, summary);
  const evaluation::ObjectiveEvaluator exact(plant, options.loop, options.objective, nullptr,
                                             options.load_weight);
  return exact(*refined);
}

}  // namespace

RefineSummary RefineWithCeres(const Plant& plant, const TuneOptions& options, const PidGains& start,
                              double start_objective) {
  RefineSummary summary;
  summary.gains = start;
  summary.objective = start_objective;
  summary.message = WhyNotRun(plant, options, start_objective);
  if (!summary.message.empty()) return summary;
  PidGains refined;
  const double f = SolveAndEvaluate(plant, options, start, &refined, &summary);
  summary.runs = 1;
  Judge(options, refined, f, start_objective, &summary);
  return summary;
}

RefineSummary RefineWithCeres(const Plant& plant, const TuneOptions& options,
                              const std::vector<PidGains>& starts,
                              const std::vector<double>& start_objectives) {
  RefineSummary summary;
  if (starts.empty() || starts.size() != start_objectives.size()) {
    summary.message = "not run: no start";
    return summary;
  }
  const double f_search = start_objectives[0];
  summary.gains = starts[0];
  summary.objective = f_search;
  summary.message = WhyNotRun(plant, options, f_search);
  if (!summary.message.empty()) return summary;
  // Every run from its start; the lowest finite exact objective wins (ties:
  // the earlier start), its termination and iterations are reported.
  PidGains best_point;
  double best_f = std::numeric_limits<double>::infinity();
  RefineSummary best_run;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    if (!std::isfinite(start_objectives[k])) continue;
    RefineSummary run;
    PidGains refined;
    const double f = SolveAndEvaluate(plant, options, starts[k], &refined, &run);
    ++summary.runs;
    if (k == 0 || (std::isfinite(f) && f < best_f)) {
      best_f = f;
      best_point = refined;
      best_run = run;
      summary.start_index = static_cast<int>(k);
    }
  }
  summary.ran = true;
  summary.termination = best_run.termination;
  summary.iterations = best_run.iterations;
  Judge(options, best_point, best_f, f_search, &summary);
  if (summary.start_index > 0)
    summary.message += " (Ceres from polished minimum " + std::to_string(summary.start_index + 1) + " of " +
                       std::to_string(starts.size()) + ")";
  return summary;
}

}  // namespace pidlab::tune
