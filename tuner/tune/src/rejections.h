// Why a search found no usable point (issue 40, "Failures name their
// cause"): the rule that rejected most of a probe of the box, and the flag
// that helps.
#pragma once

#include <string>

#include "pidlab/plant_sim/plants.h"
#include "pidlab/tune/tune.h"

namespace pidlab::tune {

/// Checks a 3 x 3 x 3 grid of the box (each gain at 1 %, 10 % and 100 % of
/// the way from `lower` to `upper`) as the search checks a candidate: strict
/// stability (`evaluator` finite), then options.bounds, then the step's overshoot and settling
/// bounds. Returns "; K of 27 probe points of the box are <rule>; what
/// helps: <flags>" for the rule that rejects most of them, or "" when a probe point
/// passes every rule (the search then ran out of budget, not of loops).
/// True when every loop of `options` on `plant` is neutral, never strictly
/// stable: an ideal derivative (no filter) on the continuous loop of a plant
/// of relative degree 1 with dead time.
bool IdealDerivativeMakesLoopNeutral(const Plant& plant, const TuneOptions& options);

std::string ExplainRejections(const Plant& plant, const TuneOptions& options,
                              const evaluation::ObjectiveEvaluator& evaluator);

}  // namespace pidlab::tune
