#pragma once
// The workbench's plot data for one loop (docs/workbench.md, "The series"):
// what the page draws, computed by the code of the evaluation and of the
// loop analysis, never by the page.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/command_series.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/spec/status.h"

namespace pidlab::results {

struct PlotSeriesOptions {
  /// Points of the log frequency grid (plus the frequencies of Ms, Mt and the
  /// noise gain, so that the grid's peaks are the reported ones). 10..5000.
  int frequency_points = 300;
  /// The grid's points at most, after points are inserted where the dead
  /// time's phase turns by more than pi/2 between neighbours and where the
  /// phase of L steps by more than 120 degrees; the grid is cut below its top
  /// (with a note) rather than exceed it. frequency_points + 3..20000.
  int max_frequency_points = 2000;
  /// The grid spans this factor below and above the gain crossover (1 rad/s
  /// without one). > 1.
  double decades_around_crossover = 3.0;
};

/// The series of the loop `evaluation` ran (Evaluate of `plant`, `typed_gains`,
/// `options`; a sampled loop evaluated with record_trajectory) and `analysis`
/// found (AnalyzeLoop of the same loop), as the JSON object
///   t, y          the evaluation's sample times and y (== `--samples-csv`)
///   u             the command at those times (evaluation::CommandAndLoadSeries)
///   load_y, load_u  the load response (r = 0, unit step at the plant input,
///                 the load IAE's run; null for a nonlinear plant)
///   w, s, t_mag, cs |S|, |T|, |C S| on a log grid (rad/s) of the continuous
///                 loop (with its dead time; the sampled loop's C(s) G(s) too,
///                 "frequency_loop" says which), ms, mt, noise_gain (the analysis)
///   l_re, l_im    L(jw) on that grid (the Nyquist curve)
///   l_phase_deg   the phase of L, degrees, continuous along the grid
///                 (analysis::LoopPhaseDeg); the grid resolves the dead time:
///                 its phase turns by at most 90 degrees between neighbours,
///                 and the phase of L steps by at most 120 (within
///                 max_frequency_points)
///   gain_crossovers_rad_s  the analysis's gain crossovers
///   phase_crossover_rad_s  its phase crossover of the gain margin (NaN: null)
///   notes         what is missing and why.
/// kRunnerFailed with the message if the frequency response fails.
Status PlotSeries(const Plant& plant, const PidGains& typed_gains, const evaluation::LoopOptions& options,
                  const evaluation::Evaluation& evaluation, const analysis::LoopAnalysis& analysis,
                  const PlotSeriesOptions& series_options, nlohmann::json* series);

/// The Monte-Carlo band around the step response: the plants of
/// analysis::DrawPlants (the draws of `evaluate --monte-carlo`, same seed and
/// spread), each evaluated with `typed_gains` on `options`, and per sample
/// time the least and the largest y over the stable draws:
///   {draws, stable, invalid, y_min, y_max} (y_min, y_max null with no stable draw).
/// `stepper` as for DrawPlants. kRunnerFailed with the message if an
/// evaluation fails.
Status MonteCarloBand(const Plant& nominal, const StepperMotorParameters* stepper,
                      const PidGains& typed_gains, const evaluation::LoopOptions& options,
                      const analysis::MonteCarloOptions& mc, nlohmann::json* band);

}  // namespace pidlab::results
