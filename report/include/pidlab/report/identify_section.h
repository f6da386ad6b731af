#pragma once
// The report's section "Identifying the motor": the nonlinear stepper
// (stepper_nonlinear) treated as a motor nobody wrote down. An open-loop PRBS
// experiment on the sampled loop with noise on the measured angle (in
// process: the trio gives the same bits, integration.trio.excite), a P2DU
// with delay identified from it (pidlab::identify), its DC gain and pole pair
// against eq. (3)'s, and `tune --robust` on the identified model (its robust
// set drawn from the covariance) against the same on eq. (3), both gain sets
// run on eq. (3) and on the motor. docs/identify.md, "End to end".

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/tune.h"

namespace pidlab::report {

/// One gain set of the section on eq. (3) and on the motor.
struct IdentifyGainSet {
  std::string name;
  tune::TuneSummary tune;
  bool tuned = false;
  double eq3_ms = 0, motor_ms = 0;  // Ms of the sampled loop (the motor's: its linearisation)
  double eq3_iae_per_unit = 0, motor_iae_per_unit = 0;
  bool eq3_stable = false, motor_stable = false;
};

struct IdentifySection {
  // The experiment.
  double dt_s = 1e-4, horizon_s = 3.0, amplitude_rad = 5e-4, clock_s = 2e-3, noise_rad = 2e-5;
  std::uint64_t seed = 5;
  identify::IdentifyData data;
  identify::IdentifyResult fit;
  std::vector<identify::PoleEstimate> poles;
  // Eq. (3).
  double eq3_dc_gain = 0, eq3_pair_re = 0, eq3_pair_im = 0, eq3_fast_pole = 0;
  bool dc_within = false, pair_within = false;  // within the fit's 95 % intervals
  // The tunings (sampled loop at tune_dt_s over tune_horizon_s) and their runs.
  double tune_dt_s = 1e-3, tune_horizon_s = 3.0, move_rad = 0.01;
  int robust_samples = 16;
  IdentifyGainSet on_model, on_eq3;
};

/// Runs the experiment, the fit, the tunings and the runs. A failed Status (kRunnerFailed)
/// if a step cannot run (a fit or tune that fails is reported, not an error).
Status ComputeIdentifySection(bool quick, std::uint64_t seed, IdentifySection* section);

/// The Markdown of the section (heading "## Identifying the motor").
void RenderIdentifySection(std::ostream& os, const IdentifySection& section);

/// Draws out_dir/file (measured and simulated angle, residuals and their
/// autocorrelation) and sets *caption. A failed Status (kIoFailed) if drawing fails.
Status DrawIdentifyFigure(const IdentifySection& section, const std::string& out_dir, const std::string& file,
                          std::string* caption);

}  // namespace pidlab::report
