// The paper report: see report.h.

#include "pidlab/report/report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "format.h"
#include "pidlab/plot/plot.h"

namespace pidlab::report {
namespace {

constexpr double kSquarePeriodS = 2.0;  // pidlab's documented choice; the paper does not state it

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream is(line);
  while (std::getline(is, cell, ',')) out.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

// Column name -> index in paper_tables.csv.
using Columns = std::map<std::string, std::size_t>;

// The header line's columns; false with *error if a required one is missing.
bool ParseHeader(const std::string& line, const std::string& path, Columns* col, std::string* error) {
  const std::vector<std::string> header = SplitCsv(line);
  for (std::size_t i = 0; i < header.size(); ++i) (*col)[header[i]] = i;
  const char* required[] = {"table",
                            "plant",
                            "method",
                            "disturbance_amplitude",
                            "kp",
                            "ki",
                            "kd",
                            "paper_rise_time_s",
                            "paper_overshoot_pct",
                            "paper_settling_time_s",
                            "paper_iae",
                            "ref_rise_time_s",
                            "ref_overshoot_pct",
                            "ref_settling_time_s",
                            "ref_iae"};
  for (const char* name : required) {
    if (!col->count(name)) {
      *error = path + ": missing column " + name;
      return false;
    }
  }
  return true;
}

// One data line (line `number` of `path`); throws std::invalid_argument
// naming the line and column of a cell that is not a number.
PaperRow ParseRow(const std::vector<std::string>& cells, const Columns& col, const std::string& path,
                  int number) {
  auto text = [&](const char* name) {
    const std::size_t i = col.at(name);
    return i < cells.size() ? cells[i] : std::string();
  };
  auto value = [&](const char* name, double fallback, bool allow_empty) {
    const std::string s = text(name);
    if (s.empty() && allow_empty) return fallback;
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != s.size() || s.empty())
      throw std::invalid_argument(path + " line " + std::to_string(number) + ": column " + name + " = '" + s +
                                  "' is not a number");
    return v;
  };
  PaperRow r;
  r.table = text("table");
  r.plant = text("plant");
  r.method = text("method");
  r.disturbance_amplitude = value("disturbance_amplitude", 0.0, true);
  r.gains = {value("kp", 0, false), value("ki", 0, false), value("kd", 0, false)};
  r.paper_rise_time_s = value("paper_rise_time_s", 0, false);
  r.paper_overshoot_pct = value("paper_overshoot_pct", 0, false);
  r.paper_settling_time_s = value("paper_settling_time_s", 0, false);
  r.paper_iae = value("paper_iae", 0, false);
  r.ref_rise_time_s = value("ref_rise_time_s", 0, false);
  r.ref_overshoot_pct = value("ref_overshoot_pct", 0, false);
  r.ref_settling_time_s = value("ref_settling_time_s", 0, false);
  r.ref_iae = value("ref_iae", 0, false);
  return r;
}

std::string Gains(const PidGains& g) { return Num(g.kp, 5) + ", " + Num(g.ki, 5) + ", " + Num(g.kd, 5); }

std::string PlantTitle(const std::string& plant) {
  if (plant == "double_integrator") return "1/s^2 (the paper's \"linear system\")";
  if (plant == "oscillator") return "1/(s^2+1) (the paper's \"nonlinear system\")";
  if (plant == "stepper_motor") return "stepper motor, eq. (3) with Table I";
  return plant;
}

std::string MethodTitle(const std::string& csv_method) {
  if (csv_method == "ziegler_nichols") return "Ziegler-Nichols";
  if (csv_method == "nelder_mead") return "Nelder-Mead";
  if (csv_method == "pso_gsa") return "PSO-GSA";
  if (csv_method == "genetic_algorithm") return "GA";
  return csv_method;
}

bool RelClose(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b));
}

Plant BuiltinPlant(const std::string& name) {
  Plant p;
  std::string error;
  if (!MakePlant(name, StepperMotorParameters{}, &p, &error)) throw std::invalid_argument(error);
  return p;
}

LoopOptions PaperLoop(double amplitude) {
  LoopOptions o;  // continuous, ts = 0.05 s, n = 25 s
  if (amplitude > 0.0) {
    o.disturbance.kind = DisturbanceKind::kSquare;
    o.disturbance.amplitude = amplitude;
    o.disturbance.period_s = kSquarePeriodS;
  }
  return o;
}

// The one-line explanations of published figures pidlab does not reproduce.
std::vector<std::string> ExplainDifferences(const PaperRow& row, const Metrics& m) {
  std::vector<std::string> out;
  if (!RelClose(row.paper_iae, m.iae, 1e-3)) {
    out.push_back(
        "IAE: paper " + Num(row.paper_iae, 5) + " vs " + Num(m.iae, 5) +
        " (eq. 4: sum of |1 - y1| at t = 0, 0.05, ..., 25 s); the published gains do not give the "
        "published IAE on the loop the paper describes, which gives every other row's IAE to 4 digits");
  }
  if (!RelClose(row.paper_rise_time_s, m.rise_time_s, 0.03)) {
    out.push_back("rise time: paper " + Num(row.paper_rise_time_s, 5) + " s vs " + Num(m.rise_time_s, 5) +
                  " s for 10 % -> 90 % of the final value (ratio " +
                  Num(row.paper_rise_time_s / m.rise_time_s, 3) +
                  "); the paper does not state its definition and 10-90 % does not give its figure");
  }
  if (std::abs(row.paper_overshoot_pct - m.overshoot_pct) > 0.1 &&
      !RelClose(row.paper_overshoot_pct, m.overshoot_pct, 0.03)) {
    out.push_back(
        "overshoot: paper " + Num(row.paper_overshoot_pct, 5) + " % vs " + Num(m.overshoot_pct, 5) +
        " % (peak of the exact continuous response over its final value); the published value is not "
        "reproduced by the standard definition, most likely a coarser simulation grid missed the peak");
  }
  if (!RelClose(row.paper_settling_time_s, m.settling_time_s, 0.03)) {
    std::string why;
    if (row.paper_settling_time_s < 0.1 * m.settling_time_s) {
      why = "the slowest closed-loop pole pair " + Num(m.slowest_pole_re, 3) + " +/- " +
            Num(m.slowest_pole_im, 3) +
            "j leaves a small slow tail that keeps |y - y_final| above 2 % until " +
            Num(m.settling_time_s, 4) + " s; the paper's figure is not the 2 % settling time";
    } else {
      why = "the paper does not state its band; the 2 % band gives pidlab's figure";
    }
    out.push_back("settling time: paper " + Num(row.paper_settling_time_s, 5) + " s vs " +
                  Num(m.settling_time_s, 5) + " s (2 % band): " + why);
  }
  if (row.method == "ziegler_nichols" && row.plant != "stepper_motor") {
    out.push_back(
        "gains: labelled Ziegler-Nichols, but the ultimate-gain method has no finite Ku on this plant "
        "(marginally stable under every P gain); the paper does not say how they were obtained");
  }
  return out;
}

// ---------------------------------------------------------------- figures

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
  if (!Evaluate(plant, gains, o, what, &ev1, error)) return false;
  trace->name = name;
  trace->t = ev1.t;
  trace->y1 = ev1.y;
  trace->y = ev1.y;
  trace->y2.assign(ev1.y.size(), 0.0);
  trace->n.assign(ev1.y.size(), 0.0);
  if (amplitude > 0.0) {
    o.disturbance = PaperLoop(amplitude).disturbance;
    Evaluation ev;
    if (!Evaluate(plant, gains, o, what, &ev, error)) return false;
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

const PaperRow* FindRow(const std::vector<RowResult>& rows, const std::string& table,
                        const std::string& plant, const std::string& method, double amplitude = -1.0) {
  for (const RowResult& r : rows) {
    if (r.paper.table == table && r.paper.plant == plant && r.paper.method == method &&
        (amplitude < 0.0 || std::abs(r.paper.disturbance_amplitude - amplitude) < 1e-9))
      return &r.paper;
  }
  return nullptr;
}

const Tuning* FindTuning(const std::vector<Tuning>& tunings, const std::string& plant, TuneMethod method,
                         double amplitude) {
  for (const Tuning& t : tunings) {
    if (t.plant == plant && t.method == method && std::abs(t.disturbance_amplitude - amplitude) < 1e-9)
      return &t;
  }
  return nullptr;
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
  std::string e;
  if (!plot::DrawPng(fig, &e)) {
    *error = "figure " + fig.output_path + ": " + e;
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
  if (!DrawMotorFigure(data->motor, data->options.out_dir, file, &caption, error)) return false;
  data->figures.push_back({file, caption});
  return true;
}

bool DrawRobustSectionFigures(ReportData* data, std::string* error) {
  std::vector<std::pair<std::string, std::string>> drawn;
  if (!DrawRobustFigures(data->robust, data->options.out_dir, &drawn, error)) return false;
  for (auto& [file, caption] : drawn) data->figures.push_back({file, caption});
  return true;
}

bool DrawFigures(ReportData* data, std::string* error) {
  return DrawStepFigures(data, error) && DrawDisturbanceFigures(data, error) &&
         DrawVeryHighDisturbanceFigure(data, error) && DrawMotorSectionFigure(data, error) &&
         DrawRobustSectionFigures(data, error);
}

// ---------------------------------------------------------------- markdown

std::string MetricsCells(const Metrics& m) {
  if (!m.stable) return "unstable | | | ";
  return Num(m.rise_time_s, 5) + " | " + Num(m.overshoot_pct, 5) + " | " + Num(m.settling_time_s, 5) + " | " +
         Num(m.iae, 5);
}

std::string Mark(double paper, double ours, double rel) { return RelClose(paper, ours, rel) ? "" : " **≠**"; }

// The published rows of `table`, in the order of its columns.
std::vector<const RowResult*> TableRows(const ReportData& data, const std::string& table) {
  std::vector<const RowResult*> rows;
  for (const RowResult& r : data.rows)
    if (r.paper.table == table) rows.push_back(&r);
  if (table == "V") {
    // Table V's +/-0.2 column repeats Table IV's Nelder-Mead gains.
    for (const RowResult& r : data.rows)
      if (r.paper.table == "IV" && r.paper.method == "nelder_mead" && r.paper.disturbance_amplitude > 0 &&
          r.paper.disturbance_amplitude <= 0.3)
        rows.push_back(&r);
    std::stable_sort(rows.begin(), rows.end(), [](const RowResult* a, const RowResult* b) {
      return a->paper.disturbance_amplitude < b->paper.disturbance_amplitude;
    });
  }
  return rows;
}

// The table's heading and column headers: a paper and a pidlab column per row.
void RenderTableHeader(std::ostream& os, const std::vector<const RowResult*>& rows, const std::string& table,
                       const std::string& title) {
  os << "### Table " << table << ": " << title << "\n\n";
  os << "| | ";
  for (const RowResult* r : rows) {
    os << MethodTitle(r->paper.method);
    if (r->paper.disturbance_amplitude > 0)
      os << " (tuned at +/-" << Num(r->paper.disturbance_amplitude, 2) << ")";
    os << ": paper | pidlab | ";
  }
  os << "\n|---|";
  for (std::size_t i = 0; i < rows.size(); ++i) os << "---:|---:|";
  os << "\n";
}

// The gains, the step metrics and the IAE, paper against pidlab, with **≠**
// where pidlab does not reproduce the published figure.
void RenderTableLines(std::ostream& os, const std::vector<const RowResult*>& rows) {
  auto line = [&](const std::string& name, auto paper_of, auto ours_of, double rel, bool mark) {
    os << "| " << name << " | ";
    for (const RowResult* r : rows) {
      const double p = paper_of(*r), o = ours_of(*r);
      os << Num(p, 5) << " | " << Num(o, 5) << (mark ? Mark(p, o, rel) : "") << " | ";
    }
    os << "\n";
  };
  line(
      "kp", [](const RowResult& r) { return r.paper.gains.kp; },
      [](const RowResult& r) { return r.paper.gains.kp; }, 0, false);
  line(
      "ki", [](const RowResult& r) { return r.paper.gains.ki; },
      [](const RowResult& r) { return r.paper.gains.ki; }, 0, false);
  line(
      "kd", [](const RowResult& r) { return r.paper.gains.kd; },
      [](const RowResult& r) { return r.paper.gains.kd; }, 0, false);
  line(
      "rise time [s] (10-90 %)", [](const RowResult& r) { return r.paper.paper_rise_time_s; },
      [](const RowResult& r) { return r.pidlab.rise_time_s; }, 0.03, true);
  line(
      "overshoot [%]", [](const RowResult& r) { return r.paper.paper_overshoot_pct; },
      [](const RowResult& r) { return r.pidlab.overshoot_pct; }, 0.03, true);
  line(
      "settling time [s] (2 %)", [](const RowResult& r) { return r.paper.paper_settling_time_s; },
      [](const RowResult& r) { return r.pidlab.settling_time_s; }, 0.03, true);
  line(
      "Error(K) = IAE of y1", [](const RowResult& r) { return r.paper.paper_iae; },
      [](const RowResult& r) { return r.pidlab.iae; }, 1e-3, true);
  bool any_disturbed = false;
  for (const RowResult* r : rows) any_disturbed |= r->paper.disturbance_amplitude > 0;
  if (any_disturbed) {
    os << "| IAE of y = y1 + y2 (pidlab only) | ";
    for (const RowResult* r : rows) os << " | " << Num(r->pidlab.iae_disturbed, 5) << " | ";
    os << "\n";
  }
  os << "\n";
}

// One line per published figure pidlab does not reproduce.
void RenderDifferences(std::ostream& os, const std::vector<const RowResult*>& rows) {
  bool any = false;
  for (const RowResult* r : rows) {
    for (const std::string& d : r->differences) {
      if (!any) os << "Differences (**≠**):\n\n";
      any = true;
      os << "- " << MethodTitle(r->paper.method);
      if (r->paper.disturbance_amplitude > 0) os << " (+/-" << Num(r->paper.disturbance_amplitude, 2) << ")";
      os << ", " << d << "\n";
    }
  }
  if (!any) os << "Every published figure is reproduced.\n";
}

void RenderPaperTable(std::ostream& os, const ReportData& data, const std::string& table,
                      const std::string& title) {
  const std::vector<const RowResult*> rows = TableRows(data, table);
  if (rows.empty()) return;
  RenderTableHeader(os, rows, table, title);
  RenderTableLines(os, rows);
  RenderDifferences(os, rows);
  if (table == "V") {
    os << "\nTable V's +/-0.2 column repeats Table IV's Nelder-Mead gains; the paper prints 3.1799e-4 s and "
          "15.4589 % there but 3.1796e-4 s and 15.4599 % in Table IV (the CSV, and this table, hold Table "
          "IV's).\n";
  }
  os << "\n";
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

// Title, paper, loop, metric definitions and how to read the tables.
void RenderIntroduction(std::ostream& os, const ReportData& data) {
  os << "# pidlab report: Nelder-Mead PID tuning of a stepper motor, regenerated\n\n"
     << "Paper: W. Assawinchaichote and V. Sinlapakun, *Optimization Design of PID Controller Parameters "
        "Based on Nelder Mead Algorithm for Stepper Motors*. Generated by `pidlab report` (seed "
     << data.options.seed << (data.options.quick ? ", **quick mode: reduced budgets**" : "")
     << "). See docs/report.md for how to read it.\n\n"
     << "Loop: the paper's continuous loop (ideal PID of eq. 2, unit step, exact matrix-exponential "
        "solution), Error(K) = sum of |1 - y1(t)| at t = 0, 0.05, ..., 25 s (eq. 4), where y1 is the "
        "response to the reference alone (eq. 17). Metrics use MATLAB-stepinfo definitions on the exact "
        "response: rise time 10 % -> 90 % of the final value, overshoot in % of the final value, settling "
        "time into a 2 % band for good. Disturbances are square waves of period "
     << Num(kSquarePeriodS, 5) << " s (pidlab's choice; the paper does not state the period).\n\n"
     << "In the tables, *paper* is the published figure and *pidlab* is pidlab's re-evaluation of the "
        "published gains; **≠** marks a published figure pidlab does not reproduce (IAE within 0.1 %, "
        "others within 3 %), explained in one line below the table.\n\n";
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

void RenderSampledRow(std::ostream& os, const std::string& loop, const Metrics& m) {
  os << "| " << loop << " | " << (m.stable ? "yes" : "no") << " | " << MetricsCells(m) << " |\n";
}

// The table of the sampled section: continuous, sampled in process, and the
// trio's episode beside the in-process loop on its horizon.
void RenderSampledTable(std::ostream& os, const SampledSection& s) {
  os << "| loop | stable | rise [s] | overshoot [%] | settling [s] | IAE of y1 "
        "|\n|---|---|---:|---:|---:|---:|\n";
  RenderSampledRow(os, "continuous (exact)", s.continuous);
  RenderSampledRow(os, "sampled, in-process, dt = " + Num(s.dt_s, 5) + " s", s.sampled_in_process);
  RenderSampledRow(os, "sampled, in-process, dt = " + Num(s.fine_dt_s, 5) + " s", s.sampled_fine);
  if (s.trio_ran) {
    const std::string at = "dt = " + Num(s.dt_s, 5) + " s, horizon " + Num(s.trio_horizon_s, 5) + " s";
    RenderSampledRow(os, "sampled, in-process, " + at, s.sampled_trio_horizon);
    RenderSampledRow(os, "sampled, LCM trio, " + at, s.trio);
  }
  os << "\n";
}

// How the trio ran (or why not), and whether it matched the in-process loop.
void RenderTrioNote(std::ostream& os, const SampledSection& s) {
  os << (s.trio_ran ? "Trio run: " : "**The LCM trio run was not available**: ") << s.trio_note << ".";
  if (s.trio_ran) {
    const Metrics& a = s.trio;
    const Metrics& b = s.sampled_trio_horizon;
    const bool identical = a.stable == b.stable && a.iae == b.iae && a.rise_time_s == b.rise_time_s &&
                           a.overshoot_pct == b.overshoot_pct && a.settling_time_s == b.settling_time_s;
    if (s.trio_horizon_s < s.horizon_s) {
      os << " The episode covers " << Num(s.trio_horizon_s, 5) << " s instead of the paper's "
         << Num(s.horizon_s, 5) << " s; the slow tail after it adds "
         << Num(std::abs(s.sampled_in_process.iae - s.sampled_trio_horizon.iae), 3) << " to the IAE.";
    } else {
      os << " The episode covers the paper's full " << Num(s.trio_horizon_s, 5) << " s horizon.";
    }
    os << (identical
               ? std::string(" Its IAE and step metrics equal the in-process sampled loop's on the same "
                             "horizon bit for bit.")
               : " **Its results differ from the in-process sampled loop's** (IAE " + Num(a.iae, 17) +
                     " vs " + Num(b.iae, 17) + ").");
  }
  os << "\n\n";
}

// Why the sampled loop differs from the continuous one at dt, and converges
// at the finer dt.
void RenderSampledDiscussion(std::ostream& os, const SampledSection& s) {
  auto rel = [](double a, double b) { return 100.0 * std::abs(a - b) / std::abs(b); };
  os << "At dt = " << Num(s.dt_s, 5) << " s the sampled IAE is within "
     << Num(rel(s.sampled_in_process.iae, s.continuous.iae), 3)
     << " % of the continuous one and the overshoot is " << Num(s.sampled_in_process.overshoot_pct, 4)
     << " % against " << Num(s.continuous.overshoot_pct, 4) << " %: the plant's fastest pole is at "
     << Num(s.fastest_plant_pole_re, 4) << " rad/s (time constant " << Num(-1e3 / s.fastest_plant_pole_re, 3)
     << " ms) and the continuous rise time is " << Num(1e3 * s.continuous.rise_time_s, 3)
     << " ms, so one sample of the discrete PID (backward-Euler integral, backward-difference derivative) "
        "spans a large part of the transient. At dt = "
     << Num(s.fine_dt_s, 5) << " s the overshoot is " << Num(s.sampled_fine.overshoot_pct, 4)
     << " %: the sampled loop converges to the continuous one as dt shrinks. The 2 % settling time, set by "
        "the slow pole pair, is "
     << Num(s.sampled_in_process.settling_time_s, 4) << " s and " << Num(s.sampled_fine.settling_time_s, 4)
     << " s against " << Num(s.continuous.settling_time_s, 4) << " s continuous.\n\n";
}

// The stepper motor on the sampled loop (the LCM trio's loop).
void RenderSampledSection(std::ostream& os, const SampledSection& s) {
  os << "## Stepper motor on the sampled loop (the LCM trio's loop)\n\n"
     << "The paper's Table IV Nelder-Mead gains (" << Gains(s.gains)
     << ") on the lockstep sampled loop the process trio runs (discrete PID, ZOH plant, dt = "
     << Num(s.dt_s, 5) << " s) against the continuous loop. Sampled metrics use every step of the loop.\n\n";
  RenderSampledTable(os, s);
  RenderTrioNote(os, s);
  RenderSampledDiscussion(os, s);
}

void RenderFigureList(std::ostream& os, const std::vector<Figure>& figures) {
  if (figures.empty()) {
    os << "## Figures\n\nNot drawn (--no-figures).\n\n";
    return;
  }
  os << "## Figures\n\n";
  for (const Figure& f : figures) os << "![" << f.file << "](" << f.file << ")\n\n" << f.caption << "\n\n";
}

// ---------------------------------------------------------------- computation

// The paper's Table IV Nelder-Mead gains for the stepper motor (its printed
// values if the tables lack the row).
PidGains StepperNelderMeadGains(const std::vector<PaperRow>& paper) {
  PidGains gains{20.8836, 26.607, 12.4866};
  for (const PaperRow& row : paper)
    if (row.table == "IV" && row.plant == "stepper_motor" && row.method == "nelder_mead") gains = row.gains;
  return gains;
}

// The trio episode of the sampled section, run on its own thread from
// construction (if options.trio_runner is set); waited for on destruction.
class BackgroundTrio {
 public:
  BackgroundTrio(const ReportOptions& options, const SampledSection& s) {
    if (!options.trio_runner) return;
    episode_ = std::async(std::launch::async, [this, &options, gains = s.gains, dt_s = s.dt_s,
                                               horizon_s = s.trio_horizon_s] {
      try {
        return options.trio_runner(BuiltinPlant("stepper_motor"), gains, dt_s, horizon_s, &metrics_, &note_);
      } catch (const std::exception& e) {
        note_ = e.what();
        return false;
      }
    });
  }
  BackgroundTrio(const BackgroundTrio&) = delete;
  BackgroundTrio& operator=(const BackgroundTrio&) = delete;
  ~BackgroundTrio() {
    if (episode_.valid()) episode_.wait();
  }

  /// Waits for the episode and fills the trio fields of *s; without a runner,
  /// the note says why (absent_note).
  void Collect(const std::string& absent_note, SampledSection* s) {
    if (!episode_.valid()) {
      s->trio_note = absent_note;
      return;
    }
    s->trio_ran = episode_.get();
    s->trio = metrics_;
    s->trio_note = note_;
  }

 private:
  Metrics metrics_;
  std::string note_;
  std::future<bool> episode_;  // last: destroyed (after the wait) first
};

// Every published row re-evaluated. Tables report y1, the undisturbed
// response, even for gains tuned under a disturbance; the disturbed IAE is
// kept beside it.
bool EvaluatePaperRows(const std::vector<PaperRow>& paper, ReportData* data, std::string* error) {
  for (const PaperRow& row : paper) {
    RowResult r;
    r.paper = row;
    if (!EvaluateMetrics(BuiltinPlant(row.plant), row.gains, row.disturbance_amplitude, &r.pidlab, error))
      return false;
    r.differences = ExplainDifferences(row, r.pidlab);
    data->rows.push_back(std::move(r));
  }
  return true;
}

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
  std::string why;
  if (!Tune(plant, o, &t->summary, &why)) {
    t->status = TuningStatus::kNotApplicable;
    t->message = why;
  } else if (!t->summary.stable) {
    t->status = TuningStatus::kNoStableLoop;
    t->message = t->summary.message;
  } else {
    if (!EvaluateMetrics(plant, t->summary.gains, amplitude, &t->metrics, error)) return false;
    t->status = TuningStatus::kTuned;
    t->message = t->summary.message;
  }
  return true;
}

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

// The in-process part of the sampled section: the continuous loop, the
// sampled loop at dt and at the finer dt, the sampled loop over the trio's
// horizon, and the plant's fastest pole.
bool EvaluateSampledLoops(SampledSection* s, std::string* error) {
  const Plant stepper = BuiltinPlant("stepper_motor");
  if (!EvaluateMetrics(stepper, s->gains, 0.0, &s->continuous, error)) return false;
  LoopOptions sampled = PaperLoop(0.0);
  sampled.loop = LoopKind::kSampled;
  sampled.dt_s = s->dt_s;
  EvaluateOptions what;
  what.compute_iae_continuous = false;
  Evaluation ev;
  if (!Evaluate(stepper, s->gains, sampled, what, &ev, error)) return false;
  FillFromEvaluation(ev, &s->sampled_in_process);
  LoopOptions short_horizon = sampled;
  short_horizon.horizon_s = s->trio_horizon_s;
  Evaluation same_as_trio;
  if (!Evaluate(stepper, s->gains, short_horizon, what, &same_as_trio, error)) return false;
  FillFromEvaluation(same_as_trio, &s->sampled_trio_horizon);
  sampled.dt_s = s->fine_dt_s;
  Evaluation fine;
  if (!Evaluate(stepper, s->gains, sampled, what, &fine, error)) return false;
  FillFromEvaluation(fine, &s->sampled_fine);
  for (const auto& p : PolynomialRoots(stepper.tf.den))
    s->fastest_plant_pole_re = std::min(s->fastest_plant_pole_re, p.real());
  return true;
}

// "Robust tuning" (robust_section.h) with the paper's Nelder-Mead gains of
// Tables II-IV.
bool ComputeRobust(const ReportOptions& options, const std::vector<PaperRow>& paper, ReportData* data,
                   std::string* error) {
  std::vector<RobustInput> inputs;
  const std::pair<const char*, const char*> plants[] = {
      {"double_integrator", "II"}, {"oscillator", "III"}, {"stepper_motor", "IV"}};
  for (const auto& [plant, table] : plants) {
    RobustInput in;
    in.plant = plant;
    bool found = false;
    for (const PaperRow& row : paper) {
      if (row.table == table && row.plant == plant && row.method == "nelder_mead" && !found) {
        in.paper = row.gains;
        found = true;
      }
    }
    if (found) inputs.push_back(in);
  }
  if (!ComputeRobustSection(inputs, options.quick, options.seed, &data->robust, error)) {
    *error = "robust section: " + *error;
    return false;
  }
  return true;
}

}  // namespace

void FillFromEvaluation(const Evaluation& ev, Metrics* m) {
  m->stable = ev.stability.stable;
  m->iae = ev.iae_undisturbed;
  m->iae_disturbed = ev.iae;
  m->rise_time_s = ev.step.valid ? ev.step.rise_time_s : NAN;
  m->overshoot_pct = ev.step.valid ? ev.step.overshoot_pct : NAN;
  m->settling_time_s = ev.step.valid ? ev.step.settling_time_s : NAN;
  m->step_note = ev.step.note;
  double best_re = -HUGE_VAL;
  for (const auto& p : ev.stability.poles) {
    if (p.real() > best_re || (p.real() == best_re && p.imag() > m->slowest_pole_im)) {
      best_re = p.real();
      m->slowest_pole_re = p.real();
      m->slowest_pole_im = std::abs(p.imag());
    }
  }
}

bool ReadPaperTables(const std::string& path, std::vector<PaperRow>* rows, std::string* error) {
  std::ifstream file(path);
  if (!file) {
    *error = "cannot read the paper's tables at " + path;
    return false;
  }
  std::ostringstream text;
  text << file.rdbuf();
  return ParsePaperTables(text.str(), path, rows, error);
}

bool ParsePaperTables(const std::string& csv, const std::string& path, std::vector<PaperRow>* rows,
                      std::string* error) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line)) {
    *error = path + " is empty";
    return false;
  }
  Columns col;
  if (!ParseHeader(line, path, &col, error)) return false;
  rows->clear();
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (Trim(line).empty()) continue;
    try {
      rows->push_back(ParseRow(SplitCsv(line), col, path, number));
    } catch (const std::invalid_argument& e) {
      *error = e.what();
      return false;
    }
  }
  if (rows->empty()) {
    *error = path + " has no rows";
    return false;
  }
  return true;
}

bool EvaluateMetrics(const Plant& plant, const PidGains& gains, double amplitude, Metrics* metrics,
                     std::string* error) {
  EvaluateOptions what;
  what.compute_iae_continuous = false;
  Evaluation ev;
  if (!Evaluate(plant, gains, PaperLoop(amplitude), what, &ev, error)) return false;
  *metrics = Metrics{};
  FillFromEvaluation(ev, metrics);
  return true;
}

bool ComputeReport(const ReportOptions& options, const std::vector<PaperRow>& paper, ReportData* data,
                   std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *data = ReportData{};
  data->options = options;
  SampledSection& s = data->sampled;
  s.dt_s = 1e-4;
  s.gains = StepperNelderMeadGains(paper);
  // The trio episode (250,000 lockstep steps over LCM) runs beside the
  // in-process work.
  BackgroundTrio trio(options, s);
  // "The motor itself" (motor_section.h), beside the rest as well.
  auto motor = std::async(std::launch::async, [&options, data, gains = s.gains] {
    std::string e;
    return ComputeMotorSection(gains, options.quick, options.seed, &data->motor, &e) ? std::string()
                                                                                     : "motor section: " + e;
  });
  try {
    if (!EvaluatePaperRows(paper, data, error)) return false;
    if (!RunTunings(options, data, error)) return false;
    if (!EvaluateSampledLoops(&s, error)) return false;
    if (!ComputeRobust(options, paper, data, error)) return false;
    trio.Collect(options.trio_absent_note, &s);
    if (const std::string e = motor.get(); !e.empty()) throw std::runtime_error(e);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  data->compute_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

std::string RenderMarkdown(const ReportData& data) {
  std::ostringstream os;
  RenderIntroduction(os, data);
  os << "## Tables II-VI: the paper's gains re-evaluated\n\n";
  RenderPaperTable(os, data, "II", "1/s^2, Ziegler-Nichols and Nelder-Mead");
  RenderPaperTable(os, data, "III", "1/(s^2+1), Ziegler-Nichols and Nelder-Mead");
  RenderPaperTable(os, data, "IV", "stepper motor, four methods");
  RenderPaperTable(os, data, "V", "stepper motor, Nelder-Mead under low disturbance");
  RenderPaperTable(os, data, "VI", "stepper motor, Nelder-Mead under high disturbance");
  RenderOwnTunings(os, data);
  RenderDisturbanceTunings(os, data);
  RenderSampledSection(os, data.sampled);
  RenderMotorSection(os, data.motor);
  RenderRobustSection(os, data.robust);
  RenderFigureList(os, data.figures);
  return os.str();
}

bool WriteReport(ReportData* data, std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(data->options.out_dir, ec);
  if (ec) {
    *error = "cannot create " + data->options.out_dir + ": " + ec.message();
    return false;
  }
  const auto start = std::chrono::steady_clock::now();
  data->figures.clear();
  if (data->options.figures && !DrawFigures(data, error)) return false;
  data->figure_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string path = (std::filesystem::path(data->options.out_dir) / "report.md").string();
  std::ofstream out(path);
  out << RenderMarkdown(*data);
  if (!out) {
    *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace pidlab::report
