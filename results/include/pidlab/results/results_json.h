#pragma once
// The JSON objects of `pidlab evaluate --json` and `pidlab tune --json`,
// built in one place so that the command line and the Python module
// (tools/python/) give the same keys and the same numbers.

#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/tune/tune.h"

namespace pidlab::results {

/// v, or null for NaN and +-inf (JSON has no such numbers).
nlohmann::json JsonNumber(double v);
/// {"kp", "ki", "kd", "tf"} (tf = 0: the ideal PID).
nlohmann::json ToJson(const PidGains& g);
/// The object of `pidlab evaluate --json` without "backend" (README.md,
/// docs/tuning.md list the keys).
nlohmann::json ToJson(const evaluation::Evaluation& ev);
/// The `robustness` object of evaluate and tune: ms, mt, gain_margin,
/// phase_margin_deg, delay_margin_s, noise_gain, slowest_time_constant_s
/// (null where infinite or undefined, with a note in `notes`), crossover and
/// peak frequencies, cancellations, and the `violations` of `bounds`.
/// A time scale: horizon_s, sample_time_s, source ("given", "eq. (4)",
/// "plant") and reason.
nlohmann::json TimeScaleJson(const tune::TimeScale& t);

nlohmann::json RobustnessJson(const analysis::LoopAnalysis& a, const analysis::LoopBounds& bounds);
/// The object of `pidlab tune --json`: plant `p`, options `o`, summary `s`,
/// and `ev`, the evaluation of s.gains on o.loop (unused unless s.stable);
/// `backend` is "local" or "lcm".
/// `tune --two-dof`'s second stage: the weights found, the setpoint and
/// load responses before and after them (docs/two_dof.md).
nlohmann::json TwoDofJson(const tune::TwoDofSummary& s);
nlohmann::json TuneJson(const Plant& p, const tune::TuneOptions& o, const tune::TuneSummary& s,
                        const evaluation::Evaluation& ev, const std::string& backend);

/// The object of `pidlab linearize --json`: plant, num, den (the
/// linearisation), eq3 {num, den} and input_scale.
nlohmann::json LinearizeJson(const TransferFunction& linearisation, const TransferFunction& eq3,
                             double input_scale);
/// {count, min, median, p95, max} of one Monte Carlo distribution.
nlohmann::json DistributionJson(const analysis::Distribution& d);
/// The `monte_carlo` object of `pidlab evaluate --monte-carlo N --json`.
nlohmann::json MonteCarloJson(const analysis::MonteCarloOptions& mc, const analysis::MonteCarloSummary& s);

}  // namespace pidlab::results
