#pragma once
// The report's section "Robust tuning": on each plant, the
// paper's Nelder-Mead gains (Tables II-IV), pidlab's optimum of the paper's
// objective (`pidlab tune`'s default multi-start, the report's other tunings
// being single-method runs that stop short of it) and the `pidlab tune --robust`
// preset (ApplyRobustPreset), compared on the setpoint and load IAE, the
// loop analysis (Ms, Mt, margins, noise gain) and the Monte-Carlo stable
// fraction; the Bode magnitude of S and T and the Nyquist plot of L of the
// three sets (LoopFrequencyResponse). Computed by ComputeRobustSection (no
// files), rendered by RenderRobustSection, drawn by DrawRobustFigures.

#include <cstdint>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/tune.h"

namespace pidlab::report {

/// What the section gets for one plant from the rest of the report.
struct RobustInput {
  std::string plant;  // double_integrator | oscillator | stepper_motor
  PidGains paper;     // the paper's Nelder-Mead gains (Table II, III or IV)
};

/// One gain set on one plant, on the paper's continuous loop (unit step,
/// ts = 0.05 s, n = 25 s) with the set's own derivative filter (gains.tf).
struct RobustGainSet {
  std::string name;
  PidGains gains;  // tf filled in: 0 = the ideal derivative
  bool stable = false;
  double setpoint_iae = 0, load_iae = 0;  // eq. (4) of the step, and of a unit load step at the plant input
  analysis::LoopAnalysis analysis;
  analysis::MonteCarloSummary monte_carlo;
  std::vector<analysis::LoopFrequencyPoint> response;  // on RobustSection::frequencies_rad_s
};

struct RobustPlant {
  std::string plant;
  std::vector<RobustGainSet> sets;     // paper, pidlab paper objective (if stable), --robust
  double paper_objective_optimum = 0;  // the default tune's IAE (eq. 4)
};

struct RobustSection {
  int mc_samples = 200;
  double mc_spread = 0.1;
  std::uint64_t seed = 1;
  double max_ms = 1.6;  // the preset's bound (the circle and line of the figures)
  std::vector<double> frequencies_rad_s;
  std::vector<RobustPlant> plants;
  double compute_time_s = 0;
};

/// Runs the default tune and the preset on each plant (seeded) and evaluates
/// the three sets. `quick`: one start of the robust tune and 50 Monte-Carlo
/// draws. A failed Status (kRunnerFailed) only
/// if an evaluation cannot run.
Status ComputeRobustSection(const std::vector<RobustInput>& inputs, bool quick, std::uint64_t seed,
                            RobustSection* section);

/// The Markdown of the section (heading "## Robust tuning").
void RenderRobustSection(std::ostream& os, const RobustSection& section);

/// One PNG per plant, out_dir/fig_robust_<plant>.png: |S| and |T| in dB over
/// log10 w and the Nyquist plot of L with the circle |1 + L| = 1/max_ms.
/// Appends (file, caption) pairs. A failed Status (kIoFailed) if drawing fails.
Status DrawRobustFigures(const RobustSection& section, const std::string& out_dir,
                         std::vector<std::pair<std::string, std::string>>* figures);

}  // namespace pidlab::report
