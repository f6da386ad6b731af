#pragma once
// What the parts of the paper report (report.cc and the files beside it)
// share: the paper's loop, the built-in plants, titles, look-ups, and each
// section's computation and rendering. Not installed.

#include <ostream>
#include <string>
#include <vector>

#include "pidlab/report/report.h"

namespace pidlab::report {

inline constexpr double kSquarePeriodS = 2.0;  // pidlab's documented choice; the paper does not state it

// ------------------------------------------------------------- common (report_common.cc)

/// "kp, ki, kd" with 5 significant digits each.
std::string Gains(const PidGains& g);
/// A plant's heading, with the paper's name for it.
std::string PlantTitle(const std::string& plant);
/// A paper_tables.csv method as the paper names it.
std::string MethodTitle(const std::string& csv_method);
/// |a - b| within rel of the larger magnitude.
bool RelClose(double a, double b, double rel);
/// A built-in plant by name; throws std::invalid_argument if unknown.
Plant BuiltinPlant(const std::string& name);
/// The paper's loop, with a +/-amplitude square wave (0: none).
evaluation::LoopOptions PaperLoop(double amplitude);
/// The published row of `table`, `plant` and `method` (and `amplitude` if
/// >= 0); null if none.
const PaperRow* FindRow(const std::vector<RowResult>& rows, const std::string& table,
                        const std::string& plant, const std::string& method, double amplitude = -1.0);
/// pidlab's tuning of `plant` by `method` under `amplitude`; null if none.
const Tuning* FindTuning(const std::vector<Tuning>& tunings, const std::string& plant,
                         tune::TuneMethod method, double amplitude);

// ------------------------------------------------------------- Tables II-VI (paper_table_section.cc)

/// Every published row re-evaluated, with its differences explained.
bool EvaluatePaperRows(const std::vector<PaperRow>& paper, ReportData* data, std::string* error);
/// One published table, paper against pidlab.
void RenderPaperTable(std::ostream& os, const ReportData& data, const std::string& table,
                      const std::string& title);

// ------------------------------------------------------------- pidlab's tunings (tunings_section.cc)

/// Every method on every plant, then Nelder-Mead under each disturbance.
bool RunTunings(const ReportOptions& options, ReportData* data, std::string* error);
void RenderOwnTunings(std::ostream& os, const ReportData& data);
void RenderDisturbanceTunings(std::ostream& os, const ReportData& data);

// ------------------------------------------------------------- the sampled loop (sampled_section.cc)

/// The in-process loops of the sampled section.
bool EvaluateSampledLoops(SampledSection* s, std::string* error);
void RenderSampledSection(std::ostream& os, const SampledSection& s);

// ------------------------------------------------------------- figures (figures.cc)

/// Every figure into data->options.out_dir, listed in data->figures.
bool DrawFigures(ReportData* data, std::string* error);

}  // namespace pidlab::report
