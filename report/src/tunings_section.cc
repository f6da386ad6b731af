// pidlab's own tunings in the paper report: computed and rendered.

#include <cmath>
#include <ostream>
#include <string>
#include <utility>

#include "format.h"
#include "report_internal.h"

using pidlab::tune::RefineSummary;
using pidlab::tune::Tune;
using pidlab::tune::TuneMethod;
using pidlab::tune::TuneOptions;

namespace pidlab::report {
namespace {

// One of pidlab's own tunings: `method` on `plant_name` under the paper's
// loop with a +/-amplitude square wave (0: none), with the tuner's acceptance
// margin. False only if the metrics of the tuned gains cannot be evaluated.
bool RunTuning(const ReportOptions& options, const std::string& plant_name, TuneMethod method,
               double amplitude, Tuning* t, std::string* error) {
  t->plant = plant_name;
  t->method = method;
  t->disturbance_amplitude = amplitude;
  TuneOptions o;
  o.method = method;
  o.seed = options.seed;
  o.loop = PaperLoop(amplitude);
  o.loop.stability_margin = TuneOptions::DefaultTuneLoop().stability_margin;
  if (options.quick) {
    o.starts = 1;
    if (method == TuneMethod::kGeneticAlgorithm || method == TuneMethod::kPsoGsa) o.max_evaluations = 400;
  }
  const Plant plant = BuiltinPlant(plant_name);
  if (const Status st = Tune(plant, o, &t->summary); !st.ok()) {
    t->status = TuningStatus::kNotApplicable;
    t->message = st.message();
  } else if (!t->summary.stable) {
    t->status = TuningStatus::kNoStableLoop;
    t->message = t->summary.message;
  } else {
    if (const Status metrics = EvaluateMetrics(plant, t->summary.gains, amplitude, &t->metrics);
        !metrics.ok()) {
      if (error) *error = metrics.message();
      return false;
    }
    t->status = TuningStatus::kTuned;
    t->message = t->summary.message;
  }
  return true;
}

// Loops that pass the tuner's strict-stability test but whose slowest pole is
// slower than the horizon: say what the objective rewarded.
void NearlyMarginalNotes(std::ostream& os, const std::vector<Tuning>& tunings, const std::string& plant,
                         double amplitude) {
  bool any = false;
  for (const Tuning& t : tunings) {
    if (t.plant != plant || std::abs(t.disturbance_amplitude - amplitude) > 1e-9 || !t.Tuned()) continue;
    if (!t.metrics.NearlyMarginal()) continue;
    if (!any) os << "Nearly marginal loops (**!**):\n\n";
    any = true;
    os << "- **!** " << ToString(t.method) << ": slowest closed-loop pole "
       << Num(t.metrics.slowest_pole_re, 3) << " +/- " << Num(t.metrics.slowest_pole_im, 3)
       << "j (time constant " << Num(-1.0 / t.metrics.slowest_pole_re, 3)
       << " s, beyond the 25 s horizon): strictly stable by the tuner's margin, but this slow mode is nearly "
          "cancelled by the PID zeros, so the 25 s objective barely sees it; its disturbance response decays "
          "just as slowly"
       << (t.metrics.step_note.empty() ? std::string() : "; stepinfo: " + t.metrics.step_note) << "\n";
  }
  if (any) os << "\n";
}

std::string Verdict(const Tuning& t) {
  if (t.method == TuneMethod::kZieglerNichols) return "not run (closed-form rule)";
  const RefineSummary& r = t.summary.refine;
  const std::string verdict = ToString(r.verdict, t.method);
  if (!r.ran) return verdict;
  std::string v =
      verdict + " (Ceres IAE " + Num(r.objective, 5) + ", " + std::to_string(r.iterations) + " it";
  if (r.relative_improvement > 0) v += ", " + Num(100 * r.relative_improvement, 3) + " % better";
  return v + ")";
}

void RenderTunings(std::ostream& os, const ReportData& data, const std::string& plant, double amplitude,
                   const PaperRow* paper_nm) {
  os << "| pidlab method | kp, ki, kd | rise [s] | overshoot [%] | settling [s] | IAE of y1 | IAE of y | "
        "evaluations | Ceres cross-check |\n|---|---|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Tuning& t : data.tunings) {
    if (t.plant != plant || std::abs(t.disturbance_amplitude - amplitude) > 1e-9) continue;
    if (!t.Tuned()) {
      os << "| " << ToString(t.method) << " | not applicable: " << t.message << " | | | | | | | |\n";
      continue;
    }
    os << "| " << ToString(t.method) << " | " << Gains(t.summary.gains) << " | "
       << Num(t.metrics.rise_time_s, 5) << " | " << Num(t.metrics.overshoot_pct, 5) << " | "
       << Num(t.metrics.settling_time_s, 5) << " | " << Num(t.metrics.iae, 5);
    if (paper_nm && amplitude == 0.0)
      os << (t.metrics.iae < paper_nm->paper_iae ? " (< paper)" : " (>= paper)");
    os << " | " << Num(t.metrics.iae_disturbed, 5) << " | " << t.summary.evaluations << " | " << Verdict(t)
       << " |\n";
  }
  os << "\n";
  NearlyMarginalNotes(os, data.tunings, plant, amplitude);
}

}  // namespace

// pidlab's own tunings: every method on every plant, then Nelder-Mead under
// each disturbance of Tables IV-VI and Fig. 21.
bool RunTunings(const ReportOptions& options, ReportData* data, std::string* error) {
  auto tune = [&](const std::string& plant_name, TuneMethod method, double amplitude) {
    Tuning t;
    if (!RunTuning(options, plant_name, method, amplitude, &t, error)) return false;
    data->tunings.push_back(std::move(t));
    return true;
  };
  const TuneMethod methods[] = {TuneMethod::kNelderMead, TuneMethod::kPaperNelderMead,
                                TuneMethod::kZieglerNichols, TuneMethod::kGeneticAlgorithm,
                                TuneMethod::kPsoGsa};
  for (const char* plant : {"double_integrator", "oscillator", "stepper_motor"})
    for (TuneMethod m : methods)
      if (!tune(plant, m, 0.0)) return false;
  for (double a : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.0})
    if (!tune("stepper_motor", TuneMethod::kNelderMead, a)) return false;
  return true;
}

// Every method on each plant, undisturbed, against the paper's Nelder-Mead.
void RenderOwnTunings(std::ostream& os, const ReportData& data) {
  os << "## pidlab's own tunings\n\n"
     << "Same objective, box [0, 30]^3 and seed for every method: `nelder-mead` (proper 4-point simplex, "
        "multi-start), `paper-nm` (the paper's three-point variant, which cannot leave the plane of its "
        "first triangle), `ziegler-nichols` (classic rule on the exact ultimate gain), `ga`, `pso-gsa`. "
        "Each search result is cross-checked by Ceres (bound-constrained least squares with automatic "
        "differentiation); the gains shown are the better of the two. \"< paper\" compares the IAE with "
        "the paper's Nelder-Mead.\n\n";
  for (const char* plant : {"double_integrator", "oscillator", "stepper_motor"}) {
    os << "### " << PlantTitle(plant) << "\n\n";
    const char* table = std::string(plant) == "double_integrator"
                            ? "II"
                            : (std::string(plant) == "oscillator" ? "III" : "IV");
    RenderTunings(os, data, plant, 0.0, FindRow(data.rows, table, plant, "nelder_mead"));
  }
}

// Nelder-Mead on the stepper motor tuned under each square wave.
void RenderDisturbanceTunings(std::ostream& os, const ReportData& data) {
  os << "### Stepper motor, Nelder-Mead tuned under each square-wave disturbance (Tables IV-VI, Fig. 21)\n\n"
     << "The objective during these tunings is the IAE of the disturbed output y; the tables above report "
        "the IAE of y1 for the paper's gains, so both are shown.\n\n";
  os << "| amplitude | kp, ki, kd | rise [s] | overshoot [%] | settling [s] | IAE of y1 | IAE of y | paper's "
        "IAE (of y1) | Ceres cross-check |\n|---:|---|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Tuning& t : data.tunings) {
    if (t.disturbance_amplitude == 0.0) continue;
    const PaperRow* row = nullptr;
    for (const char* table : {"IV", "V", "VI"})
      if (!row) row = FindRow(data.rows, table, "stepper_motor", "nelder_mead", t.disturbance_amplitude);
    os << "| +/-" << Num(t.disturbance_amplitude, 2) << " | ";
    if (!t.Tuned()) {
      os << "failed: " << t.message << " | | | | | | | |\n";
      continue;
    }
    os << Gains(t.summary.gains) << " | " << Num(t.metrics.rise_time_s, 5) << " | "
       << Num(t.metrics.overshoot_pct, 5) << " | " << Num(t.metrics.settling_time_s, 5) << " | "
       << Num(t.metrics.iae, 5) << " | " << Num(t.metrics.iae_disturbed, 5) << " | "
       << (row ? Num(row->paper_iae, 5) : std::string("not in the paper")) << " | " << Verdict(t) << " |\n";
  }
  os << "\n";
}

}  // namespace pidlab::report
