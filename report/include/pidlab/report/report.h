#pragma once
// The paper report (`pidlab report`): Tables II-VI of Assawinchaichote &
// Sinlapakun regenerated from their published gains, pidlab's own tunings of
// the same plants, the stepper motor on the sampled loop (in process, and as
// one episode over the LCM trio when ReportOptions::trio_runner is set; see
// trio_episode.h), and PNG figures equivalent to Figs 9-21.
//
// Three steps, so that tests can check the numbers without parsing Markdown:
//   ReadPaperTables  -> the published rows (paper_tables.csv)
//   ComputeReport    -> every evaluation and tuning, and the trio episode
//                       beside them (no files written)
//   WriteReport      -> DIR/report.md and the figures beside it
// Deterministic for a given seed: report.md holds no wall-clock times.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pidlab/report/identify_section.h"
#include "pidlab/report/motor_section.h"
#include "pidlab/report/robust_section.h"
#include "pidlab/report/two_dof_section.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/tune.h"

namespace pidlab::report {

/// One row of paper_tables.csv: the paper's published gains and figures, and
/// the reference values (ref_*) recomputed independently with standard
/// definitions.
struct PaperRow {
  std::string table;   // II .. VI
  std::string plant;   // double_integrator | oscillator | stepper_motor
  std::string method;  // ziegler_nichols | nelder_mead | pso_gsa | genetic_algorithm
  /// Square-wave amplitude the gains were tuned under (0: none stated).
  double disturbance_amplitude = 0.0;
  PidGains gains;
  double paper_rise_time_s = 0, paper_overshoot_pct = 0, paper_settling_time_s = 0, paper_iae = 0;
  double ref_rise_time_s = 0, ref_overshoot_pct = 0, ref_settling_time_s = 0, ref_iae = 0;
};

/// Reads the CSV (header line with the columns above, in any order). A failed Status
/// (kInvalidInput) naming the path, line or column on failure.
Status ReadPaperTables(const std::string& path, std::vector<PaperRow>* rows);
/// The same from the CSV text; `path` names it in errors.
Status ParsePaperTables(const std::string& csv, const std::string& path, std::vector<PaperRow>* rows);
/// data/paper_tables.csv as it was when pidlab was built (the default of
/// `pidlab report`, so the command works anywhere).
const std::string& BuiltinPaperTablesCsv();

/// Step metrics and objectives of one gain set on the paper's loop.
struct Metrics {
  bool stable = false;
  double iae = 0;            // of y1, the undisturbed response (what the tables report)
  double iae_disturbed = 0;  // of y = y1 + y2 under the row's disturbance (= iae without one)
  double rise_time_s = 0, overshoot_pct = 0, settling_time_s = 0;
  /// Closed-loop pole with the largest real part (the slowest mode).
  double slowest_pole_re = 0, slowest_pole_im = 0;
  std::string step_note;  // why the step metrics are n/a, if they are
  /// The slowest pole's time constant exceeds the 25 s horizon: the loop is
  /// stable on paper but its step metrics are meaningless over the horizon.
  bool NearlyMarginal() const { return stable && slowest_pole_re > -1.0 / 25.0; }
};

/// A published row and pidlab's re-evaluation of its gains.
struct RowResult {
  PaperRow paper;
  Metrics pidlab;
  /// One line per published figure that pidlab does not reproduce (empty:
  /// all agree within tolerance), each saying which and why.
  std::vector<std::string> differences;
};

/// How one of pidlab's own tunings ended.
enum class TuningStatus {
  kTuned,          // gains found: summary.gains and metrics are set
  kNotApplicable,  // Tune refused: the method does not apply (Ziegler-Nichols on 1/s^2 or 1/(s^2+1))
  kNoStableLoop,   // the search found no strictly stable loop in the box
};

/// One of pidlab's own tunings.
struct Tuning {
  std::string plant;
  tune::TuneMethod method = tune::TuneMethod::kNelderMead;
  double disturbance_amplitude = 0.0;  // square wave during tuning (0: none)
  TuningStatus status = TuningStatus::kNotApplicable;
  std::string message;  // kTuned: the search's summary; otherwise why not
  tune::TuneSummary summary;
  Metrics metrics;  // of summary.gains (kTuned only)
  bool Tuned() const { return status == TuningStatus::kTuned; }
};

/// The sampled loop (the LCM trio's lockstep loop) against the continuous one
/// for the paper's stepper-motor Nelder-Mead gains.
struct SampledSection {
  double dt_s = 1e-4;
  PidGains gains;
  Metrics continuous;
  Metrics sampled_in_process;
  /// The same loop at a finer period, to show convergence to the continuous loop.
  double fine_dt_s = 1e-5;
  Metrics sampled_fine;
  double fastest_plant_pole_re = 0;  // most negative real part of the plant's poles
  /// The paper's horizon n and the trio episode's horizon, s (the paper's: at
  /// about 14,000 lockstep steps/s the 250,000 steps take under 20 s). The
  /// episode is compared with the in-process sampled loop on the same horizon.
  double horizon_s = 25.0;
  double trio_horizon_s = 25.0;
  Metrics sampled_trio_horizon;
  bool trio_ran = false;
  Metrics trio;
  std::string trio_note;  // why the trio did not run, or how it ran
};

struct Figure {
  std::string file;     // relative to the output folder
  std::string caption;  // what it shows and which paper figure it mirrors
};

struct ReportOptions {
  std::string paper_tables;  // path of the CSV given with --paper-tables (informative)
  std::string out_dir;       // folder for report.md and the figures
  std::uint64_t seed = 1;    // seed of every stochastic tuner
  /// Smaller budgets (1 start, fewer GA/PSO-GSA evaluations) for smoke tests.
  bool quick = false;
  bool figures = true;
  /// Runs the trio section; given the sampled loop's options, fills *metrics
  /// from an LCM episode. Null: the trio is not available.
  std::function<bool(const Plant& plant, const PidGains& gains, double dt_s, double horizon_s,
                     Metrics* metrics, std::string* note)>
      trio_runner;
  /// What the trio section says when trio_runner is null.
  std::string trio_absent_note = "the LCM trio runner was not available in this build";
};

struct ReportData {
  ReportOptions options;
  std::vector<RowResult> rows;
  std::vector<Tuning> tunings;
  SampledSection sampled;
  std::vector<Figure> figures;
  MotorSection motor;          // "The motor itself" (motor_section.h)
  IdentifySection identified;  // "Identifying the motor" (identify_section.h)
  RobustSection robust;        // "Robust tuning" (robust_section.h)
  TwoDofSection two_dof;       // "Two degrees of freedom" (two_dof_section.h)
  /// Wall time of the computation, s (printed by the command, not in report.md).
  double compute_time_s = 0, figure_time_s = 0;
};

/// Re-evaluates every published row and runs every tuning (no files). A
/// failed Status (kRunnerFailed) names the stage that could not run.
Status ComputeReport(const ReportOptions& options, const std::vector<PaperRow>& paper, ReportData* data);

/// Draws the figures (if options.figures) and writes out_dir/report.md. A
/// failed Status (kIoFailed) if a figure or the file cannot be written.
Status WriteReport(ReportData* data);

/// The Markdown text of report.md.
std::string RenderMarkdown(const ReportData& data);

/// The report's metrics of an evaluation (step metrics NaN where not valid).
void FillFromEvaluation(const evaluation::Evaluation& evaluation, Metrics* metrics);

/// Metrics of `gains` on `plant` under the paper's continuous loop with a
/// ±amplitude square disturbance (period 2 s; 0: none). A failed Status
/// (kRunnerFailed) if the evaluation cannot run.
Status EvaluateMetrics(const Plant& plant, const PidGains& gains, double disturbance_amplitude,
                       Metrics* metrics);

}  // namespace pidlab::report
