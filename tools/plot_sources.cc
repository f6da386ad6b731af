#include "plot_sources.h"

#include <iomanip>
#include <sstream>

#include "loop_figure.h"

namespace pidlab::cli {

std::string GainsLabel(const PidGains& g) {
  std::ostringstream os;
  os << std::setprecision(6) << "kp=" << g.kp << " ki=" << g.ki << " kd=" << g.kd;
  return os.str();
}

bool EvaluationFigure(const Plant& plant, const std::vector<PidGains>& gains, const LoopOptions& options,
                      plot::Figure* figure, std::string* error) {
  std::vector<plot::LoopTrace> traces;
  EvaluateOptions what;
  what.record_trajectory = true;
  what.compute_iae_continuous = false;
  for (const PidGains& g : gains) {
    Evaluation ev;
    if (!Evaluate(plant, g, options, what, &ev, error)) return false;
    plot::LoopTrace tr;
    std::ostringstream name;
    name << GainsLabel(g) << std::setprecision(6) << " (IAE " << ev.iae
         << (ev.stability.stable ? "" : ", UNSTABLE") << ")";
    tr.name = name.str();
    if (!ev.stability.stable) {
      // Unstable: nothing was simulated; keep the legend entry honest with no curve.
      if (error) *error = "gains " + GainsLabel(g) + " give an unstable loop: nothing to plot";
      return false;
    }
    if (options.loop == LoopKind::kSampled) {
      for (const SampledStep& s : ev.trajectory) {
        tr.t.push_back(s.t);
        tr.r.push_back(s.r);
        tr.y.push_back(s.y);
        tr.e.push_back(s.r - s.y);
        tr.u.push_back(s.u);
        tr.n.push_back(s.n);
      }
    } else {
      tr.t = ev.t;
      tr.y = ev.y;
      tr.n = ev.n;
      tr.r.assign(ev.t.size(), 1.0);
      for (double y : ev.y) tr.e.push_back(1.0 - y);
    }
    traces.push_back(std::move(tr));
  }
  std::ostringstream title;
  title << std::setprecision(6) << plant.name << ", G(s) = " << plant.tf.ToString() << "\n";
  if (options.loop == LoopKind::kSampled)
    title << "sampled loop, dt = " << options.dt_s << " s, every step";
  else
    title << "continuous loop (exact), y, e, n at the sample times ts = " << options.sample_time_s
          << " s; no sampled u";
  if (options.disturbance.kind != DisturbanceKind::kNone)
    title << ", " << ToString(options.disturbance.kind) << " disturbance " << options.disturbance.amplitude;
  return plot::MakeLoopFigure(traces, plot::UnitsOfPlant(plant.name), title.str(), figure, error);
}

bool LogFigure(const std::string& log_path, const std::vector<long>& episodes, plot::Figure* figure,
               std::string* report, std::string* error) {
  (void)log_path;
  (void)episodes;
  (void)figure;
  (void)report;
  if (error) *error = "--log: not available yet";
  return false;
}

}  // namespace pidlab::cli
