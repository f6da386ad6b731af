// Crossovers, margins and bounds of the loop (loop_analysis.h): gain and
// phase crossovers by sign change on the grid and bisection, the margins at
// them, and the bounds a tuning may impose on the analysis.

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "loop_response.h"

namespace pidlab::analysis {
namespace loop_internal {
namespace {

// Root of g on [a, b] (signs differ) by bisection on log w.
double BisectLog(const std::function<double(double)>& g, double a, double b) {
  double la = std::log(a), lb = std::log(b), ga = g(a);
  for (int i = 0; i < 100 && lb - la > 1e-14 * std::max(1.0, std::abs(lb)); ++i) {
    const double lm = 0.5 * (la + lb), gm = g(std::exp(lm));
    if (!std::isfinite(gm)) break;
    if ((gm < 0.0) == (ga < 0.0)) {
      la = lm;
      ga = gm;
    } else {
      lb = lm;
    }
  }
  return std::exp(0.5 * (la + lb));
}

}  // namespace

// Gain crossovers (|L| = 1) and phase crossovers (L real negative).
Crossings FindCrossings(const Response& r, const std::vector<double>& w, const std::vector<Point>& pts) {
  auto log_ratio = [](const Point& p) { return std::log(std::abs(p.a)) - std::log(std::abs(p.b)); };
  auto sin_arg = [](const Point& p) {
    const cd z = p.a * std::conj(p.b);
    return z.imag() / std::abs(z);
  };
  auto at_log = [&](double x) { return log_ratio(r.At(x)); };
  auto at_sin = [&](double x) { return sin_arg(r.At(x)); };
  Crossings c;
  for (std::size_t i = 1; i < w.size(); ++i) {
    const Point& p0 = pts[i - 1];
    const Point& p1 = pts[i];
    const double g0 = log_ratio(p0), g1 = log_ratio(p1);
    if (std::isfinite(g0) && std::isfinite(g1) && (g0 < 0.0) != (g1 < 0.0))
      c.gain.push_back(BisectLog(at_log, w[i - 1], w[i]));
    const double s0 = sin_arg(p0), s1 = sin_arg(p1);
    if (std::isfinite(s0) && std::isfinite(s1) && (s0 < 0.0) != (s1 < 0.0)) {
      const double x = BisectLog(at_sin, w[i - 1], w[i]);
      const Point p = r.At(x);
      const cd z = p.a * std::conj(p.b);
      // L real and negative, finite (not the phase jump at a pole on the axis).
      if (z.real() < 0.0 && std::abs(p.b) > 1e-9 * std::abs(p.a)) c.phase.push_back(x);
    }
  }
  return c;
}

void SetMargins(const Response& r, const Crossings& c, LoopAnalysis* a) {
  a->gain_crossovers_rad_s = c.gain;
  a->phase_crossovers_rad_s = c.phase;
  for (double w : c.gain) {
    const Point p = r.At(w);
    double pm = std::arg(p.a / p.b) + kPi;  // (0, 2 pi]
    if (pm > kPi) pm -= 2.0 * kPi;          // (-pi, pi]
    // The extra delay that brings this crossover to -180 deg.
    const double lag = pm > 0.0 ? pm : pm + 2.0 * kPi;
    const double pm_deg = pm * 180.0 / kPi;
    a->phase_margins_deg.push_back(pm_deg);
    // The margin a user reads: the distance in phase to -180 deg (MATLAB's margin).
    if (std::abs(pm_deg) < a->phase_margin_deg) {
      a->phase_margin_deg = std::abs(pm_deg);
      a->gain_crossover_rad_s = w;
    }
    a->delay_margin_s = std::min(a->delay_margin_s, lag / w);
  }
  double best = kInf;
  for (double w : c.phase) {
    const Point p = r.At(w);
    const double gm = std::abs(p.b) / std::abs(p.a);
    a->gain_margins.push_back(gm);
    if (std::abs(std::log(gm)) < best) {
      best = std::abs(std::log(gm));
      a->gain_margin = gm;
      a->phase_crossover_rad_s = w;
    }
  }
  if (c.phase.empty()) a->gain_margin_note = "no phase crossover: infinite gain margin";
  if (c.gain.empty()) a->phase_margin_note = "no gain crossover: infinite phase and delay margins";
}

}  // namespace loop_internal

namespace {

using loop_internal::ContinuousResponse;
using loop_internal::Eval;
using loop_internal::FindCrossings;
using loop_internal::Grid;
using loop_internal::kInf;
using loop_internal::Peak;
using loop_internal::PeakOnGrid;
using loop_internal::Point;
using loop_internal::SetMargins;
using loop_internal::SlowestTimeConstant;
using loop_internal::SpecialFrequencies;

}  // namespace

bool LoopBounds::Any() const {
  return std::isfinite(max_ms) || std::isfinite(max_mt) || std::isfinite(max_noise_gain) ||
         min_phase_margin_deg > 0.0 || min_gain_margin > 0.0 || std::isfinite(max_time_constant_s);
}

bool LoopBounds::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(max_ms >= 1.0))
    os << "max Ms " << max_ms << " must be >= 1 (Ms >= 1 for every loop with a strictly proper plant)";
  else if (!(max_mt > 0.0))
    os << "max Mt " << max_mt << " must be positive";
  else if (!(max_noise_gain > 0.0))
    os << "max noise gain " << max_noise_gain << " must be positive";
  else if (!(min_phase_margin_deg >= 0.0) || !(min_phase_margin_deg < 180.0))
    os << "min phase margin " << min_phase_margin_deg << " deg must be in [0, 180)";
  else if (!(min_gain_margin == 0.0 || (min_gain_margin > 1.0 && std::isfinite(min_gain_margin))))
    os << "min gain margin " << min_gain_margin << " must be a factor > 1 (or 0 for none)";
  else if (!(max_time_constant_s > 0.0))
    os << "max time constant " << max_time_constant_s << " s must be positive";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

std::vector<std::string> LoopBoundsViolations(const LoopAnalysis& a, const LoopBounds& b) {
  std::vector<std::string> out;
  auto add = [&](const auto&... parts) {
    std::ostringstream os;
    os.precision(4);
    (os << ... << parts);
    out.push_back(os.str());
  };
  if (!a.stable) {
    add("unstable loop");
    return out;
  }
  if (a.ms > b.max_ms) add("Ms ", a.ms, " > ", b.max_ms);
  if (a.mt > b.max_mt) add("Mt ", a.mt, " > ", b.max_mt);
  if (a.noise_gain > b.max_noise_gain) add("noise gain ", a.noise_gain, " > ", b.max_noise_gain);
  if (a.phase_margin_deg < b.min_phase_margin_deg)
    add("phase margin ", a.phase_margin_deg, " deg < ", b.min_phase_margin_deg);
  if (b.min_gain_margin > 0.0 && std::abs(std::log(a.gain_margin)) < std::log(b.min_gain_margin))
    add("gain margin ", a.gain_margin, " within a factor ", b.min_gain_margin, " of 1");
  if (a.slowest_time_constant_s > b.max_time_constant_s)
    add("time constant ", a.slowest_time_constant_s, " s > ", b.max_time_constant_s);
  else if (std::isfinite(b.max_time_constant_s) && !a.time_constant_note.empty())
    add("time constant unknown (", a.time_constant_note, ")");
  return out;
}

std::string LoopBoundsViolation(const LoopAnalysis& a, const LoopBounds& b) {
  const std::vector<std::string> v = LoopBoundsViolations(a, b);
  return v.empty() ? "" : v.front();
}

bool ContinuousLoopMeetsBounds(const TransferFunction& plant, const PidGains& g,
                               const evaluation::Stability& stability, const LoopBounds& bounds) {
  if (!stability.stable) return false;
  if (SlowestTimeConstant(stability.poles) > bounds.max_time_constant_s) return false;
  const bool ideal_derivative = g.kd != 0.0 && !(g.tf > 0.0);
  if (std::isfinite(bounds.max_noise_gain) && ideal_derivative) return false;  // unbounded
  const ContinuousResponse r(plant, g);
  std::vector<double> special = SpecialFrequencies(stability.poles);
  double lo = kInf, hi = 0.0;
  for (double w : special) {
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  // Coarse: 12 points a decade over 1e-2 x slowest .. 1e2 x fastest, plus the
  // closed-loop pole frequencies where a narrow peak would sit.
  const std::vector<double> w = Grid(1e-2 * lo, 1e2 * hi, 12.0, special);
  std::vector<Point> pts(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) pts[i] = r.At(w[i]);
  const std::pair<Peak, double> peaks[] = {
      {Peak::kS, bounds.max_ms}, {Peak::kT, bounds.max_mt}, {Peak::kCs, bounds.max_noise_gain}};
  for (const auto& [which, bound] : peaks) {
    if (!std::isfinite(bound)) continue;
    const Polynomial& x = which == Peak::kS ? r.b() : (which == Peak::kT ? r.a() : r.c());
    if (r.AtInfinity(x) > bound) return false;
    if (std::abs(Eval(x, 0.0) / Eval(r.p(), 0.0)) > bound) return false;
    double wp = 0.0;
    // Refine only the local maxima within 10 % of the bound.
    if (PeakOnGrid(r, w, pts, which, true, bound / 1.1, &wp) > bound) return false;
  }
  if (bounds.min_phase_margin_deg > 0.0 || bounds.min_gain_margin > 0.0) {
    LoopAnalysis a;
    a.stable = true;
    SetMargins(r, FindCrossings(r, w, pts), &a);
    a.slowest_time_constant_s = 0.0;
    a.ms = a.mt = a.noise_gain = 0.0;
    if (!LoopBoundsViolation(a, bounds).empty()) return false;
  }
  return true;
}

}  // namespace pidlab::analysis
