#pragma once
// The report's section "The motor itself": gain sets designed on
// eq. (3) run on the nonlinear two-phase PM stepper (stepper_nonlinear,
// docs/stepper.md) for moves of 0.001 rad, 0.01 rad, one tooth pitch and the
// paper's 1 rad, each with and without a driver's phase-voltage limit, next
// to eq. (3) on the same sampled loop; a tune done on the motor itself; and
// the curves of the figure that overlays the motor's and eq. (3)'s responses.
// Computed by ComputeMotorSection (in process, no files), rendered by
// RenderMotorSection, drawn by DrawMotorFigure.

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"
#include "pidlab/tune/tune.h"

namespace pidlab::report {

/// One move of one gain set on the motor.
struct MotorRow {
  double move_rad = 0;   // reference step A
  bool limited = false;  // the drive's phase-voltage limit applied
  bool stable = false;   // the linearised loop (the gate of every sampled run)
  double iae = 0;        // eq. (4) on the motor, of e = A - y
  double iae_per_unit = 0;
  bool step_valid = false;  // step metrics exist (the response settled to a final value)
  double rise_time_s = 0, overshoot_pct = 0, settling_time_s = 0;
  double peak_phase_voltage_v = 0, peak_phase_current_a = 0;
  bool lost_steps = false;
  double final_error_rad = 0;
  /// IAE/A of the motor over IAE/A of eq. (3) on the same loop (1: eq. (3) holds).
  double ratio = 0;
};

/// A gain set and what it does on eq. (3) and on the motor.
struct MotorGainSet {
  std::string name;    // "paper Nelder-Mead (Table IV)", ...
  std::string origin;  // how the gains were obtained
  PidGains gains;
  /// Eq. (3) (the linear stepper_motor) on the same sampled loop, A = 1 (a
  /// linear loop: IAE/A and the step metrics are the same for every A).
  bool eq3_stable = false;
  double eq3_iae_per_unit = 0, eq3_rise_time_s = 0, eq3_overshoot_pct = 0, eq3_settling_time_s = 0;
  std::vector<MotorRow> rows;  // moves x {no limit, limit}
};

/// One curve of the figure: y(t)/A on the motor, or eq. (3)'s.
struct MotorCurve {
  std::string name;
  bool limited = false;  // drawn in the panel of the limited drive
  std::vector<double> t, y_per_unit;
};

struct MotorSection {
  double dt_s = 1e-4;           // the sampled loop's period
  double horizon_s = 3.0;       // n of eq. (4) for every row
  double sample_time_s = 0.05;  // ts of eq. (4)
  double voltage_limit_v = 24.0;
  double tooth_pitch_rad = 0;    // lambda of the model (Table I: pi/12)
  double holding_voltage_v = 0;  // r I_o: what the holding point alone needs
  std::vector<double> moves;     // 0.001, 0.01, lambda, 1
  std::vector<MotorGainSet> sets;
  /// The robust preset (`pidlab tune --robust` on eq. (3)), the third set:
  /// its tune found a stable loop.
  bool robust_available = false;
  std::string robust_note;
  /// The tune done on the motor itself (its gains are the last set).
  tune::TuneSummary motor_tune;
  double tune_move_rad = 0, tune_horizon_s = 0, tune_sample_time_s = 0;
  std::vector<MotorCurve> curves;
  double compute_time_s = 0;  // wall time (printed by nobody in report.md)
};

/// Runs every row, the eq. (3) references and the tune on the motor.
/// `paper_nm` are the paper's Table IV Nelder-Mead gains; `quick` shortens
/// the horizon and the tune's budget (smoke tests). A failed Status (kRunnerFailed) only if
/// an evaluation cannot run.
Status ComputeMotorSection(const PidGains& paper_nm, bool quick, std::uint64_t seed, MotorSection* section);

/// The Markdown of the section (heading "## The motor itself").
void RenderMotorSection(std::ostream& os, const MotorSection& section);

/// Draws out_dir/file (the motor's and eq. (3)'s responses overlaid, without
/// and with the limit) and sets *caption. A failed Status (kIoFailed) if drawing fails.
Status DrawMotorFigure(const MotorSection& section, const std::string& out_dir, const std::string& file,
                       std::string* caption);

}  // namespace pidlab::report
