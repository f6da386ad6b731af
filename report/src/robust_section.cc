// The report's section "Robust tuning": see robust_section.h.

#include "pidlab/report/robust_section.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "format.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plot/plot.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::analysis::LoopFrequencyPoint;
using pidlab::analysis::LoopFrequencyResponse;
using pidlab::analysis::MonteCarloOptions;
using pidlab::analysis::RunMonteCarlo;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopGains;
using pidlab::evaluation::LoopOptions;
using pidlab::tune::ApplyRobustPreset;
using pidlab::tune::RobustPreset;
using pidlab::tune::Tune;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;

namespace pidlab::report {
namespace {

std::string Title(const std::string& plant) {
  if (plant == "double_integrator") return "1/s^2";
  if (plant == "oscillator") return "1/(s^2+1)";
  if (plant == "stepper_motor") return "stepper motor, eq. (3)";
  return plant;
}

std::string GainsText(const PidGains& g) {
  std::string s = Num(g.kp, 5) + ", " + Num(g.ki, 5) + ", " + Num(g.kd, 5);
  return s + (g.tf > 0.0 ? ", Tf " + Num(g.tf, 4) : ", ideal D");
}

// The set's IAEs on the paper's loop, its loop analysis and its Monte Carlo.
bool EvaluateSet(const Plant& plant, const StepperMotorParameters* stepper, const RobustSection& s,
                 RobustGainSet* set, std::string* error) {
  const LoopOptions loop;  // the paper's: continuous, unit step, ts = 0.05 s, n = 25 s
  EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  Evaluation ev;
  if (const Status st = Evaluate(plant, set->gains, loop, what, &ev); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  set->stable = ev.stability.stable;
  set->setpoint_iae = ev.iae_undisturbed;
  set->load_iae = ev.load_iae;
  if (const Status st = AnalyzeLoop(plant, set->gains, loop, LoopAnalysisOptions{}, &set->analysis);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  MonteCarloOptions mc;
  mc.samples = s.mc_samples;
  mc.spread = s.mc_spread;
  mc.seed = s.seed;
  mc.overshoot = false;  // only the stable fraction is reported
  if (const Status st = RunMonteCarlo(plant, stepper, set->gains, loop, mc, &set->monte_carlo); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  const Status st = LoopFrequencyResponse(plant, set->gains, loop, s.frequencies_rad_s, &set->response);
  if (!st.ok() && error) *error = st.message();
  return st.ok();
}

std::string MarginCell(double v, const std::string& unit) {
  return std::isfinite(v) ? Num(v, 4) + unit : "inf";
}

// What the optimum of the paper's objective gets wrong, from the numbers.
std::string Verdict(const RobustPlant& p, const RobustSection& s) {
  const RobustGainSet* opt = nullptr;
  const RobustGainSet* robust = nullptr;
  for (const RobustGainSet& set : p.sets) {
    if (set.name.rfind("pidlab, paper", 0) == 0) opt = &set;
    if (set.name.rfind("pidlab --robust", 0) == 0) robust = &set;
  }
  if (!opt || !robust) return "";
  std::ostringstream os;
  os << "On " << Title(p.plant) << " the optimum of the paper's objective has a load IAE of "
     << Num(opt->load_iae, 4) << " against " << Num(robust->load_iae, 4) << " for the preset, Ms "
     << Num(opt->analysis.ms, 4) << " against " << Num(robust->analysis.ms, 4) << ", and "
     << (std::isfinite(opt->analysis.noise_gain)
             ? "a noise gain of " + Num(opt->analysis.noise_gain, 4)
             : std::string("an unbounded noise gain (its ideal derivative passes measurement noise to u "
                           "without limit)"))
     << "; its slowest closed-loop time constant is " << Num(opt->analysis.slowest_time_constant_s, 4)
     << " s (preset: " << Num(robust->analysis.slowest_time_constant_s, 4) << " s)";
  if (opt->gains.ki == 0.0) os << " and with ki = 0 it has no integral action against a constant load";
  os << "; " << Num(100.0 * opt->monte_carlo.stable_fraction, 3) << " % of its perturbed plants stay stable ("
     << Num(100.0 * robust->monte_carlo.stable_fraction, 3) << " % for the preset). The preset pays with a "
     << "setpoint IAE of " << Num(robust->setpoint_iae, 4) << " against " << Num(opt->setpoint_iae, 4) << ".";
  if (robust->analysis.ms > s.max_ms * (1.0 + 1e-3))
    os << " **The preset's Ms exceeds " << Num(s.max_ms, 4) << " here.**";
  return os.str();
}

}  // namespace

namespace {

// ComputeRobustSection() with the refusal's message in *error.
bool ComputeRobustSectionOrExplain(const std::vector<RobustInput>& inputs, bool quick, std::uint64_t seed,
                                   RobustSection* section, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  RobustSection& s = *section;
  s = RobustSection{};
  s.seed = seed;
  s.mc_samples = quick ? 50 : 200;
  s.max_ms = RobustPreset::kMaxMs;
  for (int i = 0; i <= 7 * 60; ++i) s.frequencies_rad_s.push_back(std::pow(10.0, -2.0 + i / 60.0));
  const StepperMotorParameters table_one;
  for (const RobustInput& in : inputs) {
    Plant plant;
    if (const Status st = MakePlant(in.plant, table_one, &plant); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    const StepperMotorParameters* stepper = in.plant == "stepper_motor" ? &table_one : nullptr;
    RobustPlant p;
    p.plant = in.plant;
    RobustGainSet paper;
    paper.name = "paper Nelder-Mead";
    paper.gains = in.paper;
    p.sets.push_back(paper);
    TuneOptions d;  // `pidlab tune --plant P --method multi-start --seed S`
    d.seed = seed;
    TuneSummary optimum;
    if (const Status st = Tune(plant, d, &optimum); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    if (optimum.stable) {
      RobustGainSet opt;
      opt.name = "pidlab, paper objective";
      opt.gains = optimum.gains;
      p.paper_objective_optimum = optimum.objective;
      p.sets.push_back(opt);
    }
    TuneOptions o = d;  // `pidlab tune --plant P --seed S --robust`
    if (quick) o.starts = 1;
    ApplyRobustPreset(&o);
    TuneSummary summary;
    if (const Status st = Tune(plant, o, &summary); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    RobustGainSet robust;
    robust.name = "pidlab --robust";
    robust.gains = LoopGains(summary.gains, o.loop);
    p.sets.push_back(robust);
    for (RobustGainSet& set : p.sets)
      if (!EvaluateSet(plant, stepper, s, &set, error)) return false;
    s.plants.push_back(std::move(p));
  }
  s.compute_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace

Status ComputeRobustSection(const std::vector<RobustInput>& inputs, bool quick, std::uint64_t seed,
                            RobustSection* section) {
  std::string why;
  if (!ComputeRobustSectionOrExplain(inputs, quick, seed, section, &why)) return Status::RunnerFailed(why);
  return Status::Ok();
}

void RenderRobustSection(std::ostream& os, const RobustSection& s) {
  os << "## Robust tuning\n\n"
     << "Three gain sets per plant on the paper's continuous loop (unit step, ts = 0.05 s, n = 25 s): the "
        "paper's Nelder-Mead gains (Tables II-IV), pidlab's optimum of the paper's objective (`pidlab tune "
        "--plant P --seed "
     << s.seed
     << "`, the default multi-start, which finds a lower IAE than the single-method tunings above) and "
        "`pidlab tune --robust` (setpoint-load objective with W = 1, derivative filter Tf = kd/(10 kp), Ms "
        "<= "
     << Num(s.max_ms, 4)
     << ", slowest time constant <= 2.5 s; docs/robustness.md). Setpoint IAE is eq. (4) of the unit step; "
        "load IAE is eq. (4) of the output after a unit step at the plant input with r = 0. Ms, Mt, the "
        "margins and the noise gain ||C S||inf come from the loop analysis (`pidlab evaluate` prints the "
        "same); a gain margin below 1 is a gain-reduction margin (the loop goes unstable if the gain drops "
        "by that factor), inf means no phase crossover; \"unbounded\" is the ideal derivative's noise gain. "
        "MC stable: the fraction of "
     << s.mc_samples << " plants drawn with a uniform +/-" << Num(100.0 * s.mc_spread, 3)
     << " % spread (seed " << s.seed
     << "; the stepper's nine Table I parameters, the other plants' transfer-function coefficients) on which "
        "the loop stays stable.\n\n";
  for (const RobustPlant& p : s.plants) {
    os << "### " << Title(p.plant) << "\n\n"
       << "| gain set | kp, ki, kd | setpoint IAE | load IAE | Ms | Mt | gain margin | phase margin | noise "
          "gain | MC stable |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const RobustGainSet& set : p.sets) {
      const LoopAnalysis& a = set.analysis;
      os << "| " << set.name << " | " << GainsText(set.gains) << " | ";
      if (!set.stable) {
        os << "unstable | | | | | | | " << Num(100.0 * set.monte_carlo.stable_fraction, 3) << " % |\n";
        continue;
      }
      os << Num(set.setpoint_iae, 4) << " | " << Num(set.load_iae, 4) << " | " << Num(a.ms, 4) << " | "
         << Num(a.mt, 4) << " | " << MarginCell(a.gain_margin, "") << " | "
         << MarginCell(a.phase_margin_deg, " deg") << " | "
         << (std::isfinite(a.noise_gain) ? Num(a.noise_gain, 4) : std::string("unbounded")) << " | "
         << Num(100.0 * set.monte_carlo.stable_fraction, 3) << " % |\n";
    }
    os << "\n" << Verdict(p, s) << "\n\n";
  }
}

namespace {

// DrawRobustFigures() with the refusal's message in *error.
bool DrawRobustFiguresOrExplain(const RobustSection& s, const std::string& out_dir,
                                std::vector<std::pair<std::string, std::string>>* figures,
                                std::string* error) {
  static const char* kColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"};
  const double ms_db = 20.0 * std::log10(s.max_ms), radius = 1.0 / s.max_ms;
  for (const RobustPlant& p : s.plants) {
    plot::Figure fig;
    fig.title = "Robust tuning, " + Title(p.plant) + ": |S|, |T| and the Nyquist plot of L";
    fig.height_px = 1200;
    const std::string file = "fig_robust_" + p.plant + ".png";
    fig.output_path = (std::filesystem::path(out_dir) / file).string();
    plot::Panel bs, bt, ny;
    bs.x_label = bt.x_label = "log10 w [rad/s]";
    bs.y_label = "|S(jw)| [dB]";
    bt.y_label = "|T(jw)| [dB]";
    ny.x_label = "Re L(jw)";
    ny.y_label = "Im L(jw)";
    ny.y_min = -3.0;
    ny.y_max = 1.5;
    bs.y_min = bt.y_min = -40.0;
    bs.y_max = bt.y_max = 15.0;
    std::vector<double> lw;
    for (double w : s.frequencies_rad_s) lw.push_back(std::log10(w));
    bs.series.push_back({"Ms = " + Num(s.max_ms, 4) + " (" + Num(ms_db, 3) + " dB)",
                         {lw.front(), lw.back()},
                         {ms_db, ms_db},
                         plot::Style::kDashed,
                         "black"});
    std::vector<double> cx, cy;
    for (int i = 0; i <= 200; ++i) {
      const double phi = 2.0 * 3.14159265358979323846 * i / 200.0;
      cx.push_back(-1.0 + radius * std::cos(phi));
      cy.push_back(radius * std::sin(phi));
    }
    ny.series.push_back({"|1 + L| = 1/" + Num(s.max_ms, 4), cx, cy, plot::Style::kDashed, "black"});
    ny.series.push_back({"-1", {-1.0}, {0.0}, plot::Style::kPoints, "black"});
    std::size_t k = 0;
    for (const RobustGainSet& set : p.sets) {
      const std::string color = kColors[k++ % 4];
      std::vector<double> sdb, tdb, re, im;
      for (const LoopFrequencyPoint& f : set.response) {
        sdb.push_back(20.0 * std::log10(std::abs(f.s)));
        tdb.push_back(20.0 * std::log10(std::abs(f.t)));
        // The Nyquist panel shows the window around -1 (L grows without bound at low w).
        const bool in = std::isfinite(std::abs(f.l)) && f.l.real() >= -3.0 && f.l.real() <= 1.5 &&
                        f.l.imag() >= -3.0 && f.l.imag() <= 1.5;
        re.push_back(in ? f.l.real() : NAN);
        im.push_back(in ? f.l.imag() : NAN);
      }
      bs.series.push_back({set.name, lw, sdb, plot::Style::kLines, color});
      bt.series.push_back({set.name, lw, tdb, plot::Style::kLines, color});
      ny.series.push_back({set.name, re, im, plot::Style::kLines, color});
    }
    fig.panels = {bs, bt, ny};
    if (const Status st = plot::DrawPng(fig); !st.ok()) {
      *error = "figure " + fig.output_path + ": " + st.message();
      return false;
    }
    figures->push_back(
        {file,
         "Robust tuning on " + Title(p.plant) +
             ": |S| and |T| (dB) of the paper's Nelder-Mead gains, pidlab's optimum of "
             "the paper's objective and the --robust preset, with the Ms = " +
             Num(s.max_ms, 4) +
             " line; the Nyquist plot of L(jw) for w > 0 (the window -3..1.5 around -1, axes not to the same "
             "scale) with the "
             "circle of radius 1/" +
             Num(s.max_ms, 4) + " around -1 that Ms <= " + Num(s.max_ms, 4) + " keeps the curve out of."});
  }
  return true;
}

}  // namespace

Status DrawRobustFigures(const RobustSection& s, const std::string& out_dir,
                         std::vector<std::pair<std::string, std::string>>* figures) {
  std::string why;
  if (!DrawRobustFiguresOrExplain(s, out_dir, figures, &why)) return Status::IoFailed(why);
  return Status::Ok();
}

}  // namespace pidlab::report
