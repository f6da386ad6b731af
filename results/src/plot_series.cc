#include "pidlab/results/plot_series.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/results/results_json.h"
#include "pidlab/spec/field.h"

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

constexpr double kPi = 3.14159265358979323846;
// The dead time's phase turns by at most this between neighbours of the grid
// (4 points per turn), and the served phase by at most kServedStepDeg.
constexpr double kDelayStepRad = kPi / 2.0;
constexpr double kServedStepDeg = 120.0;
constexpr int kPhaseRefinements = 8;

// `w` with points inserted evenly wherever the dead time's phase, -rate_s w
// (rad), turns by more than kDelayStepRad between neighbours; cut where it
// would exceed max_points (*cut_rad_s its last frequency, else +inf).
std::vector<double> DelayResolvedGrid(const std::vector<double>& w, double rate_s, int max_points,
                                      double* cut_rad_s) {
  *cut_rad_s = std::numeric_limits<double>::infinity();
  if (!(rate_s > 0.0) || w.empty()) return w;
  std::vector<double> out{w.front()};
  for (std::size_t i = 1; i < w.size(); ++i) {
    const double span = w[i] - w[i - 1];
    const double parts = std::max(1.0, std::ceil(span * rate_s / kDelayStepRad));
    if (static_cast<double>(out.size()) + parts > static_cast<double>(max_points)) {
      *cut_rad_s = out.back();
      break;
    }
    for (double k = 1.0; k < parts; k += 1.0) out.push_back(w[i - 1] + span * (k / parts));
    out.push_back(w[i]);
  }
  return out;
}

// `w` with the geometric midpoint of every interval whose phase step exceeds
// kServedStepDeg (a fast turn of the rational part), while within max_points.
std::vector<double> SplitPhaseSteps(const std::vector<double>& w, const std::vector<double>& phase_deg,
                                    int max_points) {
  std::vector<double> out{w.front()};
  std::size_t room = static_cast<std::size_t>(max_points) - std::min(w.size(), std::size_t(max_points));
  for (std::size_t i = 1; i < w.size(); ++i) {
    if (room > 0 && std::abs(phase_deg[i] - phase_deg[i - 1]) > kServedStepDeg) {
      out.push_back(std::sqrt(w[i - 1] * w[i]));
      --room;
    }
    out.push_back(w[i]);
  }
  return out;
}

// L, S, T, C S and the continuous phase of L (analysis::LoopPhaseDeg) on the
// grid: FrequencyGrid's, resolved for the dead time and the phase's turns.
Status ResolvedFrequencyResponse(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                                 const LoopAnalysis& analysis, const PlotSeriesOptions& o,
                                 std::vector<LoopFrequencyPoint>* response, std::vector<double>* phase_deg,
                                 std::vector<std::string>* notes) {
  std::vector<double> w = FrequencyGrid(analysis, options, o);
  const auto evaluate = [&]() {
    if (const Status st = analysis::LoopFrequencyResponse(plant, typed_gains, options, w, response); !st.ok())
      return st;
    return analysis::LoopPhaseDeg(plant, typed_gains, options, *response, phase_deg);
  };
  if (const Status st = evaluate(); !st.ok()) return st;
  // The dead time's phase is -rate w: its rate from the first point.
  const double rate_s = -response->front().delay_phase_rad / w.front();
  double cut_rad_s = std::numeric_limits<double>::infinity();
  if (rate_s > 0.0) {
    w = DelayResolvedGrid(w, rate_s, o.max_frequency_points, &cut_rad_s);
    if (const Status st = evaluate(); !st.ok()) return st;
  }
  for (int round = 0; round < kPhaseRefinements; ++round) {
    std::vector<double> refined = SplitPhaseSteps(w, *phase_deg, o.max_frequency_points);
    if (refined.size() == w.size()) break;
    w.swap(refined);
    if (const Status st = evaluate(); !st.ok()) return st;
  }
  if (std::isfinite(cut_rad_s))
    notes->push_back("the frequency plots end at " + spec::FormatNumber(cut_rad_s) +
                     " rad/s: above, the dead time's phase turns faster than " +
                     std::to_string(o.max_frequency_points) + " points resolve");
  return Status::Ok();
}

}  // namespace

Status PlotSeries(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                  const Evaluation& evaluation, const LoopAnalysis& analysis,
                  const PlotSeriesOptions& series_options, nlohmann::json* series) {
  if (!(series_options.frequency_points >= 10 && series_options.frequency_points <= 5000))
    return Status::InvalidInput("frequency_points " + std::to_string(series_options.frequency_points) +
                                " must be in 10..5000");
  if (!(series_options.max_frequency_points >= series_options.frequency_points + 3 &&
        series_options.max_frequency_points <= 20000))
    return Status::InvalidInput("max_frequency_points " +
                                std::to_string(series_options.max_frequency_points) +
                                " must be in frequency_points + 3..20000");
  std::vector<std::string> notes;
  *series = nlohmann::json::object();
  TimeSeries(plant, typed_gains, options, evaluation, series, &notes);
  std::vector<LoopFrequencyPoint> response;
  std::vector<double> phase_deg;
  if (const Status st = ResolvedFrequencyResponse(plant, typed_gains, options, analysis, series_options,
                                                  &response, &phase_deg, &notes);
      !st.ok())
    return Status::RunnerFailed(st.message());
  std::vector<double> w, s, t, cs, l_re, l_im;
  for (const LoopFrequencyPoint& p : response) {
    w.push_back(p.w_rad_s);
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
  (*series)["l_phase_deg"] = phase_deg;
  (*series)["gain_crossovers_rad_s"] = analysis.gain_crossovers_rad_s;
  (*series)["phase_crossover_rad_s"] = JsonNumber(analysis.phase_crossover_rad_s);
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
