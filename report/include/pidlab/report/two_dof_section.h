#pragma once
// The report's section "Two degrees of freedom": on each paper plant, the
// `pidlab tune --robust` gains of the robust section with setpoint weights
// b, c tuned by `tune --two-dof`'s second stage (tune/two_dof.h) on the
// paper's continuous loop with the set's derivative filter. The table shows
// the setpoint step before and after, and that the load IAE and Ms do not
// move (docs/two_dof.md). Computed by ComputeTwoDofSection (no files),
// rendered by RenderTwoDofSection.

#include <ostream>
#include <string>
#include <vector>

#include "pidlab/report/robust_section.h"
#include "pidlab/spec/status.h"
#include "pidlab/tune/two_dof.h"

namespace pidlab::report {

struct TwoDofRow {
  std::string plant;
  PidGains gains;  // the robust set's, tf filled in
  tune::TwoDofSummary summary;
};

struct TwoDofSection {
  std::vector<TwoDofRow> rows;
  double compute_time_s = 0;
};

/// Tunes b, c for the "pidlab --robust" set of every plant of `robust`.
/// A failed Status (kRunnerFailed) if a loop cannot be evaluated.
Status ComputeTwoDofSection(const RobustSection& robust, TwoDofSection* section);

/// The Markdown of the section (heading "## Two degrees of freedom").
void RenderTwoDofSection(std::ostream& os, const TwoDofSection& section);

}  // namespace pidlab::report
