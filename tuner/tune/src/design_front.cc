// The design engine along a knob (design.h, DesignOptions::monotone_front):
// the setpoint stage's overshoot target capped by the front's faster
// designs, so a slower design never overshoots more.
//
// The setpoint stage's least-IAE weights can lie inside the target (an
// overshoot of 3.7 % at Ms 1.4 on 1/(s+1)^3) and outside it one knot slower
// (more than 10 % at Ms 1.2), so the target alone leaves the overshoot free
// to rise as the loop slows. The front's knots Ms = 2.0, 1.9, ..., each
// designed with the target capped by the knots above it (walking down from
// the top), give a running least overshoot; a design at Ms bound m takes it
// over the knots above m. A direct design at a knot computes the same walk,
// so the knots' overshoots fall one way whichever is asked for first.

#include <cmath>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>

#include "design_engine.h"

namespace pidlab::tune::design {

namespace {

// The knots' overshoots of one front, by the knot's tenths of Ms, kept for
// the process (the workbench designs a knob's positions on one front): the
// same walk, computed once. A pure function's values; bounded.
struct KnotMemo {
  std::mutex mutex;
  std::map<std::string, std::map<int, double>> fronts;
};

KnotMemo& Memo() {
  static KnotMemo memo;
  return memo;
}

// What a knot's design depends on: the plant, and the options but Ms.
std::string FrontKey(const Plant& plant, const DesignOptions& o) {
  std::ostringstream os;
  os.precision(17);
  for (double v : plant.tf.num) os << v << ',';
  os << '/';
  for (double v : plant.tf.den) os << v << ',';
  os << '/' << plant.delay_s << '/' << o.pi << '/' << (o.crossover_rad_s > 0.0 ? o.Mt() : o.max_mt) << '/'
     << o.max_noise_gain << '/' << o.max_td_s << '/' << o.max_overshoot_pct << '/'
     << static_cast<int>(o.loop.loop) << '/' << o.loop.dt_s;
  return os.str();
}

}  // namespace

double FrontOvershootCap(const Plant& plant, const DesignOptions& options, double ms_bound, double* from_ms) {
  double cap = options.max_overshoot_pct;
  *from_ms = 0.0;
  if (!std::isfinite(cap)) return cap;
  const std::string key = FrontKey(plant, options);
  for (int tenth = static_cast<int>(std::lround(10.0 * kFrontMaxMs)); tenth / 10.0 > ms_bound * (1.0 + 1e-9);
       --tenth) {
    {
      std::lock_guard<std::mutex> lock(Memo().mutex);
      const std::map<int, double>& knots = Memo().fronts[key];
      if (const auto kept = knots.find(tenth); kept != knots.end()) {
        if (kept->second < cap) cap = kept->second, *from_ms = tenth / 10.0;
        continue;
      }
    }
    DesignOptions knot = options;
    knot.monotone_front = false;
    knot.unconstrained_gap = false;
    knot.crossover_rad_s = 0.0;
    knot.max_ms = tenth / 10.0;
    // The response-time front keeps its Mt bound (the top's); the robustness
    // knob's Mt follows Ms.
    knot.max_mt = options.crossover_rad_s > 0.0 ? options.Mt() : options.max_mt;
    knot.max_overshoot_pct = cap;
    DesignSummary s;
    const double overshoot = DesignOptimal(plant, knot, &s).ok() ? s.overshoot_pct : HUGE_VAL;
    {
      std::lock_guard<std::mutex> lock(Memo().mutex);
      if (Memo().fronts.size() > 64) Memo().fronts.clear();
      Memo().fronts[key][tenth] = overshoot;
    }
    if (overshoot < cap) {
      cap = overshoot;
      *from_ms = knot.max_ms;
    }
  }
  return cap;
}

}  // namespace pidlab::tune::design
