// See rejections.h.
#include "rejections.h"

#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"

namespace pidlab::tune {

bool IdealDerivativeMakesLoopNeutral(const Plant& plant, const TuneOptions& options) {
  const bool ideal =
      !(options.loop.pid.derivative_filter_s > 0.0) && !(options.loop.derivative_filter_ratio > 0.0);
  return options.loop.loop == evaluation::LoopKind::kContinuous && ideal && plant.delay_s > 0.0 &&
         plant.tf.RelativeDegree() == 1;
}

namespace {

// A rule of the search and the flag that relaxes it.
struct Rule {
  const char* prefix;  // how LoopBoundsViolations's line starts
  const char* what;
  const char* helps;
};

constexpr std::array<Rule, 6> kBoundRules = {{
    {"Ms ", "above --max-ms", "raise --max-ms, or let migo design under an Ms bound: --method migo"},
    {"Mt ", "above --max-mt", "raise --max-mt"},
    {"noise gain", "above --max-noise-gain",
     "raise --max-noise-gain or filter the derivative: --derivative-filter-ratio 10"},
    {"phase margin", "below --min-phase-margin", "lower --min-phase-margin"},
    {"gain margin", "below --min-gain-margin", "lower --min-gain-margin"},
    {"time constant", "slower than --max-time-constant", "raise --max-time-constant or --horizon"},
}};

// Why an unstable loop: the ideal derivative's neutral loop on relative
// degree 1 with dead time, or the box.
std::pair<std::string, std::string> Unstable(const Plant& plant, const TuneOptions& options) {
  if (IdealDerivativeMakesLoopNeutral(plant, options) && options.upper > 0.0)
    return {
        "not strictly stable (an ideal derivative on a plant of relative degree 1 with dead time makes the "
        "loop neutral)",
        "filter the derivative: --derivative-filter-ratio 10, or --method migo"};
  return {"not strictly stable",
          "--method migo designs a stable loop; or give a box that holds one: --bounds LO,HI"};
}

// The first rule `g` breaks, as (what, helps); ("", "") if none.
std::pair<std::string, std::string> FirstBroken(const Plant& plant, const TuneOptions& options,
                                                const evaluation::ObjectiveEvaluator& evaluator,
                                                const PidGains& typed) {
  if (!std::isfinite(evaluator(typed))) return Unstable(plant, options);
  const PidGains g = evaluation::LoopGains(typed, options.loop);
  analysis::LoopAnalysisOptions coarse;
  coarse.points_per_decade = 20.0;
  analysis::LoopAnalysis a;
  if (!analysis::AnalyzeLoop(plant, g, options.loop, coarse, &a).ok() || !a.stable)
    return Unstable(plant, options);
  for (const std::string& v : analysis::LoopBoundsViolations(a, options.bounds))
    for (const Rule& r : kBoundRules)
      if (v.rfind(r.prefix, 0) == 0) return {r.what, r.helps};
  if (!std::isfinite(options.max_overshoot_pct) && !std::isfinite(options.max_settling_time_s)) return {};
  evaluation::LoopOptions undisturbed = options.loop;
  undisturbed.disturbance = DisturbanceOptions{};
  evaluation::Evaluation ev;
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  if (!evaluation::Evaluate(plant, typed, undisturbed, what, &ev).ok() || !ev.step.valid)
    return {"without a step response to measure", "--horizon longer"};
  if (ev.step.overshoot_pct > options.max_overshoot_pct)
    return {"above --max-overshoot", "raise --max-overshoot, or --two-dof"};
  if (ev.step.settling_time_s > options.max_settling_time_s)
    return {"slower than --max-settling", "raise --max-settling"};
  return {};
}

}  // namespace

std::string ExplainRejections(const Plant& plant, const TuneOptions& options,
                              const evaluation::ObjectiveEvaluator& evaluator) {
  if (plant.nonlinear) return "";
  std::map<std::pair<std::string, std::string>, int> count;
  int probes = 0;
  const double fractions[] = {0.01, 0.1, 1.0};
  for (double fp : fractions)
    for (double fi : fractions)
      for (double fd : fractions) {
        const auto at = [&options](double f) { return options.lower + f * (options.upper - options.lower); };
        ++probes;
        const auto broken = FirstBroken(plant, options, evaluator, PidGains{at(fp), at(fi), at(fd)});
        if (broken.first.empty()) return "";
        ++count[broken];
      }
  auto most = count.begin();
  for (auto it = count.begin(); it != count.end(); ++it)
    if (it->second > most->second) most = it;
  return "; " + std::to_string(most->second) + " of " + std::to_string(probes) +
         " probe points of the box are " + most->first.first + "; what helps: " + most->first.second;
}

}  // namespace pidlab::tune
