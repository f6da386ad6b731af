#include "pidlab/results/plot_series.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace pidlab::results {
namespace {
using analysis::LoopAnalysis;
using analysis::LoopFrequencyPoint;
using evaluation::Evaluation;
using evaluation::LoopKind;
using evaluation::LoopOptions;

// The command and the load response of the loop at the sample times.
void TimeSeries(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                const Evaluation& ev, nlohmann::json* out, std::vector<std::string>* notes) {
  evaluation::CommandSeries series;
  evaluation::CommandAndLoadSeries(plant, typed_gains, options, ev, &series);
  notes->insert(notes->end(), series.notes.begin(), series.notes.end());
  const std::vector<double>&u = series.u, &load_y = series.load_y, &load_u = series.load_u;
  (*out)["t"] = ev.t;
  (*out)["y"] = ev.y;
  (*out)["u"] = u.empty() ? nlohmann::json(nullptr) : nlohmann::json(u);
  (*out)["load_y"] = load_y.empty() ? nlohmann::json(nullptr) : nlohmann::json(load_y);
  (*out)["load_u"] = load_u.empty() ? nlohmann::json(nullptr) : nlohmann::json(load_u);
}

// The log grid around the gain crossover (the sampled loop's up to pi/dt),
// with the peaks' frequencies that fall within it.
std::vector<double> FrequencyGrid(const LoopAnalysis& a, const LoopOptions& options,
                                  const PlotSeriesOptions& o) {
  const double top = options.loop == LoopKind::kSampled ? 3.14159265358979323846 / options.dt_s
                                                        : std::numeric_limits<double>::infinity();
  const double centre =
      std::isfinite(a.gain_crossover_rad_s) && a.gain_crossover_rad_s > 0.0 ? a.gain_crossover_rad_s : 1.0;
  const double lo = std::log10(centre) - o.decades_around_crossover;
  const double hi = std::min(std::log10(centre) + o.decades_around_crossover, std::log10(top));
  std::vector<double> w;
  for (int i = 0; i < o.frequency_points; ++i)
    w.push_back(std::min(top, std::pow(10.0, lo + (hi - lo) * i / (o.frequency_points - 1))));
  // A peak's frequency joins the grid within its span only: Mt's peak of a
  // loop with integral action may sit at 1e-23 rad/s (|T| -> 1 at DC), which
  // would stretch the axis over twenty decades.
  const double first = std::pow(10.0, lo), last = std::min(top, std::pow(10.0, hi));
  for (double peak : {a.ms_rad_s, a.mt_rad_s, a.noise_gain_rad_s})
    if (std::isfinite(peak) && peak >= first && peak <= last) w.push_back(peak);
  std::sort(w.begin(), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  return w;
}

}  // namespace

Status PlotSeries(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                  const Evaluation& evaluation, const LoopAnalysis& analysis,
                  const PlotSeriesOptions& series_options, nlohmann::json* series) {
  if (!(series_options.frequency_points >= 10 && series_options.frequency_points <= 5000))
    return Status::InvalidInput("frequency_points " + std::to_string(series_options.frequency_points) +
                                " must be in 10..5000");
  std::vector<std::string> notes;
  *series = nlohmann::json::object();
  TimeSeries(plant, typed_gains, options, evaluation, series, &notes);
  const std::vector<double> w = FrequencyGrid(analysis, options, series_options);
  std::vector<LoopFrequencyPoint> response;
  if (const Status st = analysis::LoopFrequencyResponse(plant, typed_gains, options, w, &response); !st.ok())
    return Status::RunnerFailed(st.message());
  std::vector<double> s, t, cs, l_re, l_im;
  for (const LoopFrequencyPoint& p : response) {
    s.push_back(std::abs(p.s));
    t.push_back(std::abs(p.t));
    cs.push_back(std::abs(p.cs));
    l_re.push_back(p.l.real());
    l_im.push_back(p.l.imag());
  }
  (*series)["w"] = w;
  (*series)["s"] = s;
  (*series)["t_mag"] = t;
  (*series)["cs"] = cs;
  (*series)["l_re"] = l_re;
  (*series)["l_im"] = l_im;
  (*series)["frequency_loop"] = evaluation::ToString(options.loop);
  (*series)["ms"] = analysis.ms;
  (*series)["mt"] = analysis.mt;
  (*series)["noise_gain"] = analysis.noise_gain;
  (*series)["stable"] = analysis.stable;
  (*series)["notes"] = notes;
  return Status::Ok();
}

Status MonteCarloBand(const Plant& nominal, const StepperMotorParameters* stepper,
                      const PidGains& typed_gains, const LoopOptions& options,
                      const analysis::MonteCarloOptions& mc, nlohmann::json* band) {
  const std::vector<Plant> draws = analysis::DrawPlants(nominal, stepper, mc);
  std::vector<double> lo, hi;
  int stable = 0, invalid = 0;
  evaluation::EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  for (const Plant& draw : draws) {
    if (draw.tf.den.empty()) {
      ++invalid;
      continue;
    }
    Evaluation ev;
    if (const Status st = evaluation::Evaluate(draw, typed_gains, options, what, &ev); !st.ok())
      return Status::RunnerFailed(st.message());
    if (!ev.stability.stable) continue;
    if (stable++ == 0) {
      lo = hi = ev.y;
      continue;
    }
    for (std::size_t m = 0; m < ev.y.size() && m < lo.size(); ++m) {
      lo[m] = std::min(lo[m], ev.y[m]);
      hi[m] = std::max(hi[m], ev.y[m]);
    }
  }
  *band = {{"draws", draws.size()}, {"stable", stable}, {"invalid", invalid}};
  (*band)["y_min"] = stable > 0 ? nlohmann::json(lo) : nlohmann::json(nullptr);
  (*band)["y_max"] = stable > 0 ? nlohmann::json(hi) : nlohmann::json(nullptr);
  return Status::Ok();
}

}  // namespace pidlab::results
