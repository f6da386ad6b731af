#pragma once
// The standard figure of a closed-loop run (part of pidlab_plot): panels
// stacked top to bottom
//   y(t) with the reference r(t) | e(t) = r - y | u(t) (if any run has it) | n(t)
// with several runs overlaid (one colour per run, the reference once).

#include <string>
#include <vector>

#include "pidlab/plot/plot.h"

namespace pidlab::plot {

/// One run of the loop on its own time grid. Every non-empty vector has the
/// size of t; u may be empty (a run that recorded no command).
struct LoopTrace {
  std::string name;  // legend entry, e.g. "kp=1 ki=0.5 kd=2" or "episode 3"
  std::vector<double> t, r, y, e, u, n;
  /// u is held over each step (the sampled loop's); false: u is the
  /// continuous loop's at the sample times, drawn as a line.
  bool u_held = true;
};

/// Units used in the axis labels.
struct LoopUnits {
  std::string time = "s";
  std::string output = "-";   // y, r, e
  std::string command = "-";  // u, n (n is added to the plant input)
};

/// Units of a built-in plant (double_integrator, oscillator, stepper_motor,
/// custom): the stepper's output and command are angles in rad; the others
/// are dimensionless.
LoopUnits UnitsOfPlant(const std::string& plant_name);

/// Builds the figure (width x height px, written to output_path). A failed
/// Status (kInvalidInput) if a trace's vectors disagree in length or no trace
/// has points.
Status MakeLoopFigure(const std::vector<LoopTrace>& traces, const LoopUnits& units, const std::string& title,
                      Figure* figure);

}  // namespace pidlab::plot
