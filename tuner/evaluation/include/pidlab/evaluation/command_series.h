#pragma once
// The command u and the load response of a loop at its evaluation's sample
// times: what the workbench draws (results::PlotSeries), `evaluate
// --samples-csv` writes beside y and `pidlab plot` draws.

#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"

namespace pidlab::evaluation {

/// The command and the load response at the evaluation's sample times.
struct CommandSeries {
  /// The sampled loop's recorded u; the continuous loop's u of the
  /// undisturbed step response (with dead time by the delayed loop's samplers,
  /// the ideal derivative's impulse left out).
  std::vector<double> u;
  /// The load response: r = 0, a unit step at the plant input (the load
  /// IAE's run), and its command u. Empty for the nonlinear motor.
  std::vector<double> load_y, load_u;
  /// What is missing or approximated, and why.
  std::vector<std::string> notes;
};

/// The CommandSeries of the loop `evaluation` ran: Evaluate of `plant`,
/// `typed_gains` and `options` (a sampled loop with record_trajectory).
void CommandAndLoadSeries(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                          const Evaluation& evaluation, CommandSeries* out);

}  // namespace pidlab::evaluation
