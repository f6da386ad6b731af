// The paper report's figures (Figs 9-21 and the sections' own).

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "format.h"
#include "pidlab/plot/plot.h"
#include "report_internal.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopOptions;
using pidlab::tune::TuneMethod;

namespace pidlab::report {
namespace {

struct Trace {
  std::string name;
  std::vector<double> t, y1, y2, y, n;
};

// y1 (undisturbed), y (disturbed) and y2 = y - y1 on t = 0, ts, ..., horizon.
bool Simulate(const Plant& plant, const PidGains& gains, double amplitude, double ts, double horizon,
              const std::string& name, Trace* trace, std::string* error) {
  LoopOptions o = PaperLoop(0.0);
  o.sample_time_s = ts;
  o.horizon_s = horizon;
  EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  Evaluation ev1;
  if (const Status st = Evaluate(plant, gains, o, what, &ev1); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  trace->name = name;
  trace->t = ev1.t;
  trace->y1 = ev1.y;
  trace->y = ev1.y;
  trace->y2.assign(ev1.y.size(), 0.0);
  trace->n.assign(ev1.y.size(), 0.0);
  if (amplitude > 0.0) {
    o.disturbance = PaperLoop(amplitude).disturbance;
    Evaluation ev;
    if (const Status st = Evaluate(plant, gains, o, what, &ev); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    trace->y = ev.y;
    trace->n = ev.n;
    for (std::size_t i = 0; i < ev.y.size(); ++i) trace->y2[i] = ev.y[i] - ev1.y[i];
  }
  return true;
}

std::vector<double> Scaled(const std::vector<double>& v, double s) {
  std::vector<double> out(v);
  for (double& x : out) x *= s;
  return out;
}

std::vector<double> ErrorOf(const std::vector<double>& y) {
  std::vector<double> e(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) e[i] = 1.0 - y[i];
  return e;
}

enum class Signal { kY1, kE1, kY2, kY, kE, kN };

plot::Panel MakePanel(const std::vector<Trace>& traces, Signal s, double time_scale,
                      const std::string& t_label, const std::string& y_label, bool reference, bool band) {
  plot::Panel p;
  p.x_label = t_label;
  p.y_label = y_label;
  if (traces.empty()) return p;
  const std::vector<double> t = Scaled(traces[0].t, time_scale);
  if (reference)
    p.series.push_back({"reference r", t, std::vector<double>(t.size(), 1.0), plot::Style::kDashed, "black"});
  if (band) {
    p.series.push_back(
        {"+/- 2 % band", t, std::vector<double>(t.size(), 0.02), plot::Style::kDashed, "gray"});
    p.series.push_back({"", t, std::vector<double>(t.size(), -0.02), plot::Style::kDashed, "gray"});
  }
  static const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                   "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#000080", "#800000"};
  std::size_t index = 0;
  for (const Trace& tr : traces) {
    const std::string color = kPalette[index++ % (sizeof(kPalette) / sizeof(kPalette[0]))];
    std::vector<double> v;
    switch (s) {
      case Signal::kY1:
        v = tr.y1;
        break;
      case Signal::kE1:
        v = ErrorOf(tr.y1);
        break;
      case Signal::kY2:
        v = tr.y2;
        break;
      case Signal::kY:
        v = tr.y;
        break;
      case Signal::kE:
        v = ErrorOf(tr.y);
        break;
      case Signal::kN:
        v = tr.n;
        break;
    }
    p.series.push_back({tr.name, Scaled(tr.t, time_scale), v,
                        s == Signal::kN ? plot::Style::kSteps : plot::Style::kLines, color});
  }
  return p;
}

// Grid step of a figure over [0, horizon]: 1001 points (401 with --quick).
double FigureStep(const ReportData& data, double horizon) {
  const int points = data.options.quick ? 401 : 1001;
  return horizon / (points - 1);
}

std::string OutPath(const ReportData& data, const std::string& file) {
  return (std::filesystem::path(data.options.out_dir) / file).string();
}

bool Draw(const plot::Figure& fig, ReportData* data, const std::string& caption, std::string* error) {
  if (const Status st = plot::DrawPng(fig); !st.ok()) {
    *error = "figure " + fig.output_path + ": " + st.message();
    return false;
  }
  data->figures.push_back({std::filesystem::path(fig.output_path).filename().string(), caption});
  return true;
}

// Fig. 9-14: step responses and errors of every method on one plant.
bool DrawStepFigure(ReportData* data, const std::string& plant_name, const std::string& file, double horizon,
                    double ts, double time_scale, const std::string& t_label, bool band,
                    const std::string& caption, std::string* error) {
  const Plant plant = BuiltinPlant(plant_name);
  std::vector<Trace> traces;
  for (const RowResult& r : data->rows) {
    if (r.paper.plant != plant_name ||
        (r.paper.table != "II" && r.paper.table != "III" && r.paper.table != "IV"))
      continue;
    Trace tr;
    if (!Simulate(plant, r.paper.gains, 0.0, ts, horizon, "paper " + MethodTitle(r.paper.method), &tr, error))
      return false;
    traces.push_back(std::move(tr));
  }
  for (const Tuning& t : data->tunings) {
    if (t.plant != plant_name || t.disturbance_amplitude != 0.0 || !t.Tuned()) continue;
    Trace tr;
    if (!Simulate(plant, t.summary.gains, 0.0, ts, horizon, "pidlab " + ToString(t.method), &tr, error))
      return false;
    traces.push_back(std::move(tr));
  }
  plot::Figure fig;
  fig.title = "Step response and error, " + PlantTitle(plant_name);
  fig.output_path = OutPath(*data, file);
  fig.panels.push_back(MakePanel(traces, Signal::kY1, time_scale, t_label, "y(t)", true, false));
  fig.panels.push_back(MakePanel(traces, Signal::kE1, time_scale, t_label, "e(t) = 1 - y(t)", false, band));
  return Draw(fig, data, caption, error);
}

// Figs 9-14: the step figure of each plant, and the stepper's slow tail.
bool DrawStepFigures(ReportData* data, std::string* error) {
  auto ts_for = [&](double horizon) { return FigureStep(*data, horizon); };
  if (!DrawStepFigure(data, "double_integrator", "fig09_10_double_integrator.png", 10.0, ts_for(10.0), 1.0,
                      "t [s]", false,
                      "Figs 9-10: step response y(t) and error e(t) of 1/s^2 under the paper's gains and "
                      "pidlab's tunings.",
                      error))
    return false;
  if (!DrawStepFigure(
          data, "oscillator", "fig11_12_oscillator.png", 25.0, ts_for(25.0), 1.0, "t [s]", false,
          "Figs 11-12: step response and error of 1/(s^2+1) under the paper's gains and pidlab's tunings.",
          error))
    return false;
  if (!DrawStepFigure(data, "stepper_motor", "fig13_14_stepper_motor.png", 0.05, ts_for(0.05), 1e3, "t [ms]",
                      false, "Figs 13-14: stepper-motor step response and error, first 50 ms.", error))
    return false;
  return DrawStepFigure(
      data, "stepper_motor", "fig13_14_stepper_motor_tail.png", 10.0, ts_for(10.0), 1.0, "t [s]", true,
      "Figs 13-14, continued to 10 s with the +/-2 % band: the slow tail that sets the 2 % settling "
      "times (about 1.5 s for the paper's Nelder-Mead gains, not the paper's ~1 ms).",
      error);
}

// Figs 16-19: the paper's stepper-motor Nelder-Mead gains for each
// square-wave amplitude of Tables IV-VI, first 5 ms (y1) and 10 s (y2, y, n).
bool DrawDisturbanceFigures(ReportData* data, std::string* error) {
  const Plant stepper = BuiltinPlant("stepper_motor");
  std::vector<Trace> fast, slow;
  for (double a : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}) {
    const PaperRow* row = nullptr;
    for (const char* table : {"IV", "V", "VI"})
      if (!row) row = FindRow(data->rows, table, "stepper_motor", "nelder_mead", a);
    if (!row) continue;
    const std::string name = "+/-" + Num(a, 2);
    Trace tf, tsl;
    if (!Simulate(stepper, row->gains, a, FigureStep(*data, 0.005), 0.005, name, &tf, error)) return false;
    if (!Simulate(stepper, row->gains, a, FigureStep(*data, 10.0), 10.0, name, &tsl, error)) return false;
    fast.push_back(std::move(tf));
    slow.push_back(std::move(tsl));
  }
  plot::Figure y1;
  y1.title = "Stepper motor, paper's Nelder-Mead gains per disturbance: y1(t) and its error (first 5 ms)";
  y1.output_path = OutPath(*data, "fig16_18_disturbance_y1.png");
  y1.panels.push_back(MakePanel(fast, Signal::kY1, 1e3, "t [ms]", "y1(t) [rad]", true, false));
  y1.panels.push_back(MakePanel(fast, Signal::kE1, 1e3, "t [ms]", "e1(t) = 1 - y1(t) [rad]", false, false));
  if (!Draw(y1, data,
            "Figs 16 and 18: y1, the response to the reference alone (eq. 17), and its error, for the "
            "gains of "
            "Tables IV-VI (one per square-wave amplitude).",
            error))
    return false;
  plot::Figure y2;
  y2.title = "Stepper motor under +/-0.1 ... +/-0.6 square waves (period 2 s): y2(t) and y(t)";
  y2.output_path = OutPath(*data, "fig17_19_disturbance_y2_y.png");
  y2.panels.push_back(MakePanel(slow, Signal::kY2, 1.0, "t [s]", "y2(t) [rad]", false, false));
  y2.panels.push_back(MakePanel(slow, Signal::kY, 1.0, "t [s]", "y(t) = y1 + y2 [rad]", true, false));
  y2.panels.push_back(MakePanel(slow, Signal::kN, 1.0, "t [s]", "n(t)", false, false));
  return Draw(y2, data,
              "Figs 17 and 19: y2, the response to the disturbance alone (eq. 18), and y = y1 + y2, with the "
              "square waves n(t).",
              error);
}

// Fig. 21: a +/-1 square wave against the paper's Table IV gains and
// pidlab's Nelder-Mead tuned under that wave.
bool DrawVeryHighDisturbanceFigure(ReportData* data, std::string* error) {
  const Plant stepper = BuiltinPlant("stepper_motor");
  const double ts = FigureStep(*data, 10.0);
  std::vector<Trace> very_high;
  for (const char* method : {"nelder_mead", "pso_gsa", "genetic_algorithm", "ziegler_nichols"}) {
    const PaperRow* row = FindRow(data->rows, "IV", "stepper_motor", method);
    if (!row) continue;
    Trace tr;
    if (!Simulate(stepper, row->gains, 1.0, ts, 10.0, "paper " + MethodTitle(method), &tr, error))
      return false;
    very_high.push_back(std::move(tr));
  }
  if (const Tuning* t = FindTuning(data->tunings, "stepper_motor", TuneMethod::kNelderMead, 1.0);
      t && t->Tuned()) {
    Trace tr;
    if (!Simulate(stepper, t->summary.gains, 1.0, ts, 10.0, "pidlab nelder-mead tuned at +/-1", &tr, error))
      return false;
    very_high.push_back(std::move(tr));
  }
  plot::Figure fig;
  fig.title = "Stepper motor under a +/-1 square-wave disturbance (period 2 s)";
  fig.output_path = OutPath(*data, "fig21_very_high_disturbance.png");
  fig.panels.push_back(MakePanel(very_high, Signal::kY, 1.0, "t [s]", "y(t) [rad]", true, false));
  fig.panels.push_back(MakePanel(very_high, Signal::kE, 1.0, "t [s]", "e(t) = 1 - y(t) [rad]", false, false));
  return Draw(fig, data,
              "Fig. 21: the paper's Nelder-Mead gains (Table IV) against its PSO-GSA, GA and Ziegler-Nichols "
              "gains, and pidlab's Nelder-Mead tuned under the +/-1 wave itself.",
              error);
}

bool DrawMotorSectionFigure(ReportData* data, std::string* error) {
  std::string caption;
  const std::string file = "fig_motor_itself.png";
  if (const Status st = DrawMotorFigure(data->motor, data->options.out_dir, file, &caption); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  data->figures.push_back({file, caption});
  return true;
}

bool DrawIdentifySectionFigure(ReportData* data, std::string* error) {
  std::string caption;
  const std::string file = "fig_motor_identified.png";
  if (const Status st = DrawIdentifyFigure(data->identified, data->options.out_dir, file, &caption);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  data->figures.push_back({file, caption});
  return true;
}

bool DrawRobustSectionFigures(ReportData* data, std::string* error) {
  std::vector<std::pair<std::string, std::string>> drawn;
  if (const Status st = DrawRobustFigures(data->robust, data->options.out_dir, &drawn); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  for (auto& [file, caption] : drawn) data->figures.push_back({file, caption});
  return true;
}

}  // namespace

bool DrawFigures(ReportData* data, std::string* error) {
  return DrawStepFigures(data, error) && DrawDisturbanceFigures(data, error) &&
         DrawVeryHighDisturbanceFigure(data, error) && DrawMotorSectionFigure(data, error) &&
         DrawIdentifySectionFigure(data, error) && DrawRobustSectionFigures(data, error);
}

}  // namespace pidlab::report
