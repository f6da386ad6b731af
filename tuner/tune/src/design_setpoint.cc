// The design engine's second stage (design.h): the setpoint weights b, c
// with the smallest setpoint \int|e|dt whose overshoot is within the target,
// and where no weights reach it, the first-order setpoint filter tr with
// them. The loop is linear, so the setpoint response of any b, c is
// y_i + b y_p + c y_d, three responses simulated once, and the filter's is
// theirs filtered.

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "design_engine.h"
#include "pidlab/spec/field.h"

namespace pidlab::tune::design {

namespace {

struct Channels {
  std::vector<double> i, p, d;
  double h = 0.0;
};

// Pads a settled response with its last value.
void PadTo(std::vector<double>* y, std::size_t n) {
  if (!y->empty() && y->size() < n) y->resize(n, y->back());
}

// x through 1 / (tr s + 1) from rest, exact for x linear between samples.
std::vector<double> Filtered(const std::vector<double>& x, double tr, double h) {
  std::vector<double> y(x.size(), 0.0);
  const double a = std::exp(-h / tr), ramp = 1.0 - tr * (1.0 - a) / h;
  for (std::size_t k = 1; k < x.size(); ++k)
    y[k] = a * y[k - 1] + (1.0 - a) * x[k - 1] + ramp * (x[k] - x[k - 1]);
  return y;
}

// The channels filtered by tr, padded so the filter's own tail settles.
Channels FilteredChannels(const Channels& ch, double tr) {
  const std::size_t n = ch.i.size() + static_cast<std::size_t>(std::ceil(12.0 * tr / ch.h));
  Channels out = ch;
  for (std::vector<double>* y : {&out.i, &out.p, &out.d}) {
    PadTo(y, n);
    *y = Filtered(*y, tr, ch.h);
  }
  return out;
}

struct Point {
  double b = 1.0, c = 1.0, iae = HUGE_VAL, overshoot = HUGE_VAL;
};

Point At(const Channels& ch, double b, double c) {
  std::vector<double> y(ch.i.size());
  double peak = -HUGE_VAL;
  for (std::size_t k = 0; k < y.size(); ++k) {
    y[k] = ch.i[k] + b * ch.p[k] + c * ch.d[k];
    peak = std::max(peak, y[k]);
  }
  Point pt;
  pt.b = b;
  pt.c = c;
  pt.iae = IntegralAbs(y, 1.0, ch.h);
  pt.overshoot = std::max(0.0, 100.0 * (peak - 1.0));
  return pt;
}

// Feasible before infeasible; then the smaller IAE, or the smaller overshoot.
bool Better(const Point& x, const Point& y, double target) {
  const bool fx = x.overshoot <= target, fy = y.overshoot <= target;
  if (fx != fy) return fx;
  return fx ? x.iae < y.iae : x.overshoot < y.overshoot;
}

// The best weights on a grid of `grid` points a side, then (refine) a
// pattern search from there, inside [0, 1]^2.
Point BestWeights(const Channels& ch, bool has_d, double target, int grid, bool refine) {
  Point best = At(ch, 1.0, has_d ? 1.0 : 0.0);
  for (int i = 0; i < grid; ++i)
    for (int j = 0; j < (has_d ? grid : 1); ++j) {
      const Point pt = At(ch, i / double(grid - 1), has_d ? j / double(grid - 1) : 0.0);
      if (Better(pt, best, target)) best = pt;
    }
  for (double step = 0.025; refine && step > 1e-4; step *= 0.5) {
    bool moved = true;
    while (moved) {
      moved = false;
      for (const auto& [db, dc] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        if (!has_d && dc != 0) continue;
        const double b = std::clamp(best.b + db * step, 0.0, 1.0);
        const double c = std::clamp(best.c + dc * step, 0.0, 1.0);
        const Point pt = At(ch, b, c);
        if (Better(pt, best, target)) best = pt, moved = true;
      }
    }
  }
  return best;
}

// The setpoint filter where no weights meet the target: the smallest tr
// with which some weights do (by bisection on log tr), then the tr from
// there up to 4 times it whose best weights give the smallest IAE.
// *tr = 0 where even a filter of 100 response times does not meet it.
Point WithFilter(const Channels& ch, bool has_d, double target, double response_time_s, double* tr) {
  const auto feasible = [&](double t) {
    return BestWeights(FilteredChannels(ch, t), has_d, target, 6, false).overshoot <= target;
  };
  response_time_s = std::max(response_time_s, 100.0 * ch.h);
  double lo = 0.0, hi = 0.1 * response_time_s;
  while (!feasible(hi)) {
    lo = hi;
    hi *= 2.0;
    if (hi > 100.0 * response_time_s) {
      *tr = 0.0;
      return Point{};
    }
  }
  for (int i = 0; i < 14 && (lo == 0.0 || hi / lo > 1.01); ++i) {
    const double mid = lo == 0.0 ? 0.5 * hi : std::sqrt(lo * hi);
    (feasible(mid) ? hi : lo) = mid;
  }
  Point best;
  *tr = hi;
  for (double f : {1.0, 1.25, 1.6, 2.0, 2.5, 3.2, 4.0}) {
    const Point pt = BestWeights(FilteredChannels(ch, f * hi), has_d, target, 11, true);
    if (Better(pt, best, target)) best = pt, *tr = f * hi;
  }
  return best;
}

Channels SetpointChannels(const Engine& engine, const PidGains& gains) {
  const LoopSimulator& sim = engine.Simulator();
  Channels ch;
  ch.h = sim.Step();
  Inputs in;
  in.r_i = 1.0;
  ch.i = sim.Run(gains, in, engine.MaxSteps()).y;
  in = Inputs{};
  in.r_p = 1.0;
  ch.p = sim.Run(gains, in, engine.MaxSteps()).y;
  in = Inputs{};
  in.r_d = 1.0;
  ch.d = gains.kd != 0.0 ? sim.Run(gains, in, engine.MaxSteps()).y : std::vector<double>(1, 0.0);
  const std::size_t n = std::max({ch.i.size(), ch.p.size(), ch.d.size()});
  PadTo(&ch.i, n);
  PadTo(&ch.p, n);
  PadTo(&ch.d, n);
  return ch;
}

}  // namespace

void SetpointStage(const Engine& engine, double max_overshoot_pct, DesignSummary* s) {
  const Channels ch = SetpointChannels(engine, s->gains);
  // The samples' peak can sit a little below the exact one: aim 0.5 % of
  // the target lower.
  const double target = max_overshoot_pct * 0.995;
  const bool has_d = s->gains.kd != 0.0;
  s->overshoot_unit_weights_pct = At(ch, 1.0, has_d ? 1.0 : 0.0).overshoot;
  Point best = BestWeights(ch, has_d, target, 21, true);
  s->setpoint_filter_s = 0.0;
  if (best.overshoot > target && std::isfinite(target)) {
    double tr = 0.0;
    const Point filtered = WithFilter(ch, has_d, target, s->response_time_s, &tr);
    if (tr > 0.0) best = filtered, s->setpoint_filter_s = tr;
  }
  s->b = best.b;
  s->c = has_d ? best.c : 0.0;
  s->setpoint_iae = best.iae;
  s->overshoot_pct = best.overshoot;
  s->overshoot_met = best.overshoot <= target;
  if (!s->overshoot_met) {
    std::ostringstream os;
    os << "the setpoint overshoot target " << spec::FormatNumber(max_overshoot_pct)
       << " % is not met: the weights b " << spec::FormatNumber(best.b) << ", c " << spec::FormatNumber(s->c)
       << " reach " << spec::FormatNumber(best.overshoot) << " % at the least";
    s->setpoint_note = os.str();
  }
}

}  // namespace pidlab::tune::design
