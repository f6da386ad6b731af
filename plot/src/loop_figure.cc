#include "pidlab/plot/loop_figure.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace pidlab::plot {
namespace {

// Colour-blind-safe palette (Okabe-Ito), cycled over runs.
const char* const kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"};

}  // namespace

LoopUnits UnitsOfPlant(const std::string& plant_name) {
  LoopUnits u;
  if (plant_name == "stepper_motor" || plant_name == "stepper") u.output = u.command = "rad";
  return u;
}

namespace {

// MakeLoopFigure() with the refusal's message in *error.
bool MakeLoopFigureOrExplain(const std::vector<LoopTrace>& traces, const LoopUnits& units,
                             const std::string& title, Figure* figure, std::string* error) {
  bool any_points = false, any_u = false;
  for (const LoopTrace& tr : traces) {
    for (const auto* v : {&tr.r, &tr.y, &tr.e, &tr.u, &tr.n}) {
      if (!v->empty() && v->size() != tr.t.size()) {
        if (error) *error = "run '" + tr.name + "' has vectors of different lengths";
        return false;
      }
    }
    any_points = any_points || !tr.t.empty();
    any_u = any_u || !tr.u.empty();
  }
  if (!any_points) {
    if (error) *error = "no run has any points to plot";
    return false;
  }
  const std::string x_label = "t [" + units.time + "]";
  Panel py{"step response", x_label, "y [" + units.output + "]", {}};
  Panel pe{"error e = r - y", x_label, "e [" + units.output + "]", {}};
  const bool held = std::any_of(traces.begin(), traces.end(), [](const LoopTrace& tr) { return tr.u_held; });
  Panel pu{held ? "control u (held over each step)" : "control u", x_label, "u [" + units.command + "]", {}};
  Panel pn{"disturbance n at the plant input", x_label, "n [" + units.command + "]", {}};
  bool reference_drawn = false;
  for (std::size_t i = 0; i < traces.size(); ++i) {
    const LoopTrace& tr = traces[i];
    if (tr.t.empty()) continue;
    const std::string color = kPalette[i % (sizeof kPalette / sizeof kPalette[0])];
    const bool several = traces.size() > 1;
    if (!tr.r.empty() && !reference_drawn) {
      py.series.push_back({"reference r", tr.t, tr.r, Style::kDashed, "#555555"});
      reference_drawn = true;
    }
    auto name = [&](const char* what) {
      return several ? tr.name : std::string(what) + (tr.name.empty() ? "" : " (" + tr.name + ")");
    };
    if (!tr.y.empty()) py.series.push_back({name("output y"), tr.t, tr.y, Style::kLines, color});
    if (!tr.e.empty()) pe.series.push_back({name("error e"), tr.t, tr.e, Style::kLines, color});
    if (!tr.u.empty())
      pu.series.push_back({name("command u"), tr.t, tr.u, tr.u_held ? Style::kSteps : Style::kLines, color});
    if (!tr.n.empty()) pn.series.push_back({name("disturbance n"), tr.t, tr.n, Style::kSteps, color});
  }
  // The derivative kick kd/dt of the first step dwarfs the rest of u: scale
  // the u axis to the steps after it and say where the kick went.
  if (any_u) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, kick = 0.0;
    for (const LoopTrace& tr : traces) {
      for (std::size_t k = 1; k < tr.u.size(); ++k) {
        if (std::isfinite(tr.u[k])) lo = std::min(lo, tr.u[k]), hi = std::max(hi, tr.u[k]);
      }
    }
    if (lo <= hi) {
      const double margin = 0.08 * std::max(hi - lo, 1e-9 + 1e-3 * std::abs(hi));
      for (const LoopTrace& tr : traces) {
        if (!tr.u.empty() && (tr.u[0] > hi + margin || tr.u[0] < lo - margin) &&
            std::abs(tr.u[0]) > std::abs(kick))
          kick = tr.u[0];
      }
      if (kick != 0.0) {
        pu.y_min = lo - margin;
        pu.y_max = hi + margin;
        std::ostringstream os;
        os << std::setprecision(4) << pu.title << "; first-step derivative kick u(0) = " << kick
           << " off scale";
        pu.title = os.str();
      }
    }
  }
  bool all_n_zero = true;
  for (const LoopTrace& tr : traces)
    for (double v : tr.n) all_n_zero = all_n_zero && v == 0.0;
  if (all_n_zero) pn.title += " (none: n = 0)";
  figure->title = title;
  figure->panels.clear();
  for (Panel* p : {&py, &pe, &pu, &pn}) {
    if (p == &pu && !any_u) continue;
    if (!p->series.empty()) figure->panels.push_back(std::move(*p));
  }
  return true;
}

}  // namespace

Status MakeLoopFigure(const std::vector<LoopTrace>& traces, const LoopUnits& units, const std::string& title,
                      Figure* figure) {
  std::string why;
  if (!MakeLoopFigureOrExplain(traces, units, title, figure, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::plot
