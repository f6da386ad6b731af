// The design engine (design.h): bounds, the exact check, the front and the
// setpoint stage around the optimisation of design_engine.cc.

#include "pidlab/tune/design.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "design_engine.h"
#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/spec/field.h"
#include "pidlab/tune/migo.h"

namespace pidlab::tune {

using spec::FormatNumber;

// The sampled loop's highest crossover, per unit of the sample rate 1/dt.
constexpr double kSampledCrossoverPerRate = 0.5;

bool DesignOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(max_ms > 1.0 && max_ms <= 4.0))
    os << "robustness " << FormatNumber(max_ms) << " is not an Ms bound in (1, 4]";
  else if (!std::isnan(max_mt) && !(max_mt >= 1.0))
    os << "max_mt " << FormatNumber(max_mt) << " must be >= 1";
  else if (!(max_noise_gain > 0.0))
    os << "max_noise_gain " << FormatNumber(max_noise_gain) << " must be > 0 (inf: none)";
  else if (!(crossover_rad_s >= 0.0) || !std::isfinite(crossover_rad_s))
    os << "crossover " << FormatNumber(crossover_rad_s) << " must be >= 0 and finite (rad/s)";
  else if (!(max_td_s >= 0.0))
    os << "max_td " << FormatNumber(max_td_s) << " must be >= 0 (s)";
  else if (!(max_overshoot_pct >= 0.0))
    os << "max_overshoot " << FormatNumber(max_overshoot_pct) << " must be >= 0 (%)";
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

double DesignOptions::Mt() const { return std::isnan(max_mt) ? max_ms : max_mt; }

double DominantTimeConstant(const Plant& plant) {
  double slowest = 0.0;
  int integrators = 0;
  for (const std::complex<double>& p : RootsOffTheOrigin(plant.tf.den, &integrators))
    if (p.real() < 0.0 && std::abs(p) > 1e-12) slowest = std::max(slowest, -1.0 / p.real());
  // Two or more integrators dominate any lag: a PID holds them with a
  // derivative time near the plant's unity-gain time, whatever its lags.
  if (integrators >= 2) return std::max(slowest, UnityGainTime(plant));
  if (slowest > 0.0) return slowest;
  double fastest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  return slowest;
}

namespace {

// The exact analysis of the loop of g (continuous by default).
bool Analyse(const Plant& plant, const PidGains& g, const evaluation::LoopOptions& loop,
             analysis::LoopAnalysis* a) {
  return analysis::AnalyzeLoop(plant, g, loop, analysis::LoopAnalysisOptions{}, a).ok() && a->stable;
}

bool Meets(const analysis::LoopAnalysis& a, const design::Bounds& b) {
  constexpr double kTolerance = 1.0 + 1e-3;
  return a.ms <= b.ms * kTolerance && a.mt <= b.mt * kTolerance && a.noise_gain <= b.noise_gain * kTolerance;
}

// The largest ratio of a peak to its bound.
double Excess(const analysis::LoopAnalysis& a, const design::Bounds& b) {
  return std::max({a.ms / b.ms, a.mt / b.mt, a.noise_gain / b.noise_gain});
}

PidGains Scaled(PidGains g, double f) {
  g.kp *= f;
  g.ki *= f;
  g.kd *= f;
  return g;
}

// The grid's optimum checked by the exact analysis: where the exact peaks
// break a bound (the grid missed a sliver of a peak), the loop gain is
// scaled back until they do not. False when no scale gives a stable loop.
bool ExactlyWithin(const Plant& plant, const design::Engine& engine, const design::Bounds& b,
                   design::Optimum* o, analysis::LoopAnalysis* a) {
  bool stable = Analyse(plant, o->gains, b.loop, a);
  if (stable && Meets(*a, b)) return true;
  // By 3 % steps down to half the gain, so as to stay in the design's band
  // of gains (a larger step can land in a slower band below it); given up
  // where a step raises the excess (an integrating plant's Mt rises as the
  // gain falls).
  double lo = 0.97, hi = 1.0, excess = stable ? Excess(*a, b) : HUGE_VAL;
  analysis::LoopAnalysis at;
  while (!((stable = Analyse(plant, Scaled(o->gains, lo), b.loop, &at)) && Meets(at, b))) {
    if (stable && Excess(at, b) > excess) return false;
    if (stable) excess = Excess(at, b);
    hi = lo;
    lo *= 0.97;
    if (lo < 0.5) return false;
  }
  for (int i = 0; i < 14; ++i) {
    const double mid = std::sqrt(lo * hi);
    (Analyse(plant, Scaled(o->gains, mid), b.loop, &at) && Meets(at, b) ? lo : hi) = mid;
  }
  o->gains = Scaled(o->gains, lo);
  o->load_iae = engine.LoadIae(o->gains);
  return Analyse(plant, o->gains, b.loop, a) && std::isfinite(o->load_iae);
}

// A design bound corrected by the exact peak it gave against the peak
// wanted: (bound - 1) scaled by (wanted - 1) / (peak - 1), within [1.001, 4].
double Corrected(double bound, double wanted, double peak) {
  const double f = (wanted - 1.0) / std::max(peak - 1.0, 1e-6);
  return std::clamp(1.0 + (bound - 1.0) * f, 1.0 + 1e-3, 4.0);
}

// The design's bounds tightened after an optimum whose exact peaks broke
// `check`: by the peaks' excess (a little more), or by a tenth where the
// loop is not stable.
void Tighten(const Plant& plant, const design::Bounds& check, const design::Optimum& failed,
             design::Bounds* design) {
  analysis::LoopAnalysis at;
  if (Analyse(plant, failed.gains, check.loop, &at)) {
    design->ms = Corrected(design->ms, check.ms, std::max(at.ms, check.ms) * 1.002);
    design->mt = Corrected(design->mt, check.mt, std::max(at.mt, check.mt) * 1.002);
  } else {
    design->ms = 1.0 + 0.9 * (design->ms - 1.0);
    design->mt = 1.0 + 0.9 * (design->mt - 1.0);
  }
}

// The point at Ms bound `ms` with the design's bounds corrected until the
// exact peaks meet them, the active one within 1 % (at most 8 designs): the
// sampled loop's (the engine designs on the plant with the hold's half
// sample of delay), or a continuous one the grid's peaks missed where
// scaling the gain back cannot help (an integrating plant's Mt, which rises
// as the gain falls).
bool CorrectedPoint(const Plant& plant, const design::Engine& engine, const design::Bounds& check,
                    design::Bounds design, Eigen::VectorXd warm, design::Optimum* o,
                    analysis::LoopAnalysis* a) {
  bool found = false;
  for (int i = 0; i < 8; ++i) {
    design::Optimum trial;
    analysis::LoopAnalysis at;
    if (!engine.Optimize(design, warm, &trial)) {
      design.ms = 1.0 + 0.9 * (design.ms - 1.0);
      design.mt = 1.0 + 0.9 * (design.mt - 1.0);
      continue;
    }
    if (!ExactlyWithin(plant, engine, check, &trial, &at)) {
      Tighten(plant, check, trial, &design);
      warm = trial.shape;
      continue;
    }
    if (!found || trial.load_iae < o->load_iae) {
      *o = trial;
      *a = at;
    }
    found = true;
    if (at.ms >= 0.99 * check.ms || at.mt >= 0.99 * check.mt) return true;
    warm = trial.shape;
    design.ms = Corrected(design.ms, check.ms, at.ms);
    design.mt = Corrected(design.mt, check.mt, at.mt);
  }
  return found;
}

// The sampled loop's point at Ms bound ms.
bool SampledPoint(const Plant& plant, const design::Engine& engine, design::Bounds b, double ms,
                  const Eigen::VectorXd& warm, design::Optimum* o, analysis::LoopAnalysis* a) {
  b.ms = ms;
  return CorrectedPoint(plant, engine, b, b, warm, o, a);
}

// One point of the front: the optimum at Ms bound ms, checked exactly.
bool FrontPoint(const Plant& plant, const design::Engine& engine, design::Bounds b, double ms,
                const Eigen::VectorXd& warm, design::Optimum* o, analysis::LoopAnalysis* a) {
  b.ms = ms;
  if (!engine.Optimize(b, warm, o)) return false;
  if (ExactlyWithin(plant, engine, b, o, a)) return true;
  design::Bounds design = b;
  Tighten(plant, b, *o, &design);
  return CorrectedPoint(plant, engine, b, design, o->shape, o, a);
}

double HighestCrossover(const analysis::LoopAnalysis& a) {
  return a.gain_crossovers_rad_s.empty() ? 0.0 : a.gain_crossovers_rad_s.back();
}

// The front's point whose crossover is `w`: bisection on the Ms bound in
// [kFrontMinMs, ms_cap]. kInvalidInput naming the reachable range.
Status OnTheFront(const Plant& plant, const design::Engine& engine, const design::Bounds& b, double w,
                  design::Optimum* o, analysis::LoopAnalysis* a, double* ms_bound, std::string* note) {
  design::Optimum lo_o, hi_o;
  analysis::LoopAnalysis lo_a, hi_a;
  double lo = kFrontMinMs, hi = b.ms;
  if (!FrontPoint(plant, engine, b, hi, Eigen::VectorXd(), &hi_o, &hi_a) ||
      !FrontPoint(plant, engine, b, lo, hi_o.shape, &lo_o, &lo_a))
    return Status::InvalidInput("optimal: no stable loop on the front of plant " + plant.name);
  const double w_lo = HighestCrossover(lo_a), w_hi = HighestCrossover(hi_a);
  if (w < w_lo * 0.98 || w > w_hi * 1.02) {
    std::ostringstream os;
    os << "crossover " << FormatNumber(w) << " rad/s (response time " << FormatNumber(2.0 / w)
       << " s) is outside what plant " << plant.name << " reaches on the optimal front, Ms "
       << FormatNumber(kFrontMinMs) << " to " << FormatNumber(b.ms) << ": " << FormatNumber(w_lo) << " to "
       << FormatNumber(w_hi) << " rad/s (response time " << FormatNumber(2.0 / w_hi) << " to "
       << FormatNumber(2.0 / w_lo) << " s)";
    return Status::InvalidInput(os.str());
  }
  *o = std::abs(w - w_lo) < std::abs(w - w_hi) ? lo_o : hi_o;
  *a = std::abs(w - w_lo) < std::abs(w - w_hi) ? lo_a : hi_a;
  *ms_bound = std::abs(w - w_lo) < std::abs(w - w_hi) ? lo : hi;
  for (int i = 0; i < 30 && std::abs(HighestCrossover(*a) / w - 1.0) > 0.005 && hi - lo > 1e-4; ++i) {
    const double mid = 0.5 * (lo + hi);
    design::Optimum m;
    analysis::LoopAnalysis ma;
    if (!FrontPoint(plant, engine, b, mid, o->shape, &m, &ma)) break;
    (HighestCrossover(ma) < w ? lo : hi) = mid;
    if (std::abs(HighestCrossover(ma) / w - 1.0) < std::abs(HighestCrossover(*a) / w - 1.0))
      *o = m, *a = ma, *ms_bound = mid;
  }
  // The front can jump (another optimum takes over between two bounds):
  // the nearest point, said so.
  if (std::abs(HighestCrossover(*a) / w - 1.0) > 0.01) {
    std::ostringstream os;
    os << "the optimal front jumps past crossover " << FormatNumber(w) << " rad/s near Ms "
       << FormatNumber(*ms_bound) << ": the nearest design crosses over at "
       << FormatNumber(HighestCrossover(*a)) << " rad/s";
    *note = os.str();
  }
  return Status::Ok();
}

std::vector<std::string> ActiveBounds(const analysis::LoopAnalysis& a, const design::Bounds& b,
                                      const PidGains& g) {
  std::vector<std::string> active;
  if (a.ms >= 0.99 * b.ms) active.push_back("ms");
  if (a.mt >= 0.99 * b.mt) active.push_back("mt");
  if (std::isfinite(b.noise_gain) && a.noise_gain >= 0.99 * b.noise_gain) active.push_back("noise_gain");
  if (g.kd > 0.0 && g.kd / g.kp >= 0.99 * b.td_max_s) active.push_back("td");
  return active;
}

// The gap to the unconstrained design (DesignSummary::unconstrained_*):
// the bounds active at the optimum other than Ms dropped, searched from the
// optimum's shape, and checked exactly under Ms alone.
void Unconstrained(const Plant& plant, const design::Engine& engine, design::Bounds b,
                   const design::Optimum& o, DesignSummary* s) {
  s->dropped.clear();
  for (const std::string& name : s->active)
    if (name != "ms") s->dropped.push_back(name);
  if (s->dropped.empty()) {
    s->unconstrained_load_iae = s->load_iae;
    s->unconstrained_gap_pct = 0.0;
    s->unconstrained_note = "no bound but Ms is active: the unconstrained design is this one";
    return;
  }
  b.mt = b.noise_gain = std::numeric_limits<double>::infinity();
  b.td_max_s = std::max(b.td_max_s, 1e4 * engine.Time());
  design::Optimum u;
  analysis::LoopAnalysis a;
  if (!engine.Optimize(b, o.shape, &u, true) || !ExactlyWithin(plant, engine, b, &u, &a) ||
      !(u.load_iae <= s->load_iae)) {
    u = o;  // no better design found from here: a gap of 0 at the least
  }
  s->unconstrained_load_iae = u.load_iae;
  s->unconstrained_gap_pct = 100.0 * (s->load_iae / u.load_iae - 1.0);
  std::string names;
  for (const std::string& name : s->dropped) names += (names.empty() ? "" : ", ") + name;
  s->unconstrained_note = "without the " + names + " bound" + (s->dropped.size() > 1 ? "s" : "") +
                          " (Ms <= " + FormatNumber(b.ms) + " alone) the load \u222b|e|dt would be " +
                          FormatNumber(u.load_iae) + ": they cost " + FormatNumber(s->unconstrained_gap_pct) +
                          " %";
}

}  // namespace

namespace design {
void SetpointStage(const Engine& engine, double max_overshoot_pct, DesignSummary* s);
}  // namespace design

namespace {

// The setpoint step's overshoot with the weights of s, by the evaluation
// library's exact response and stepinfo (NaN where it cannot tell).
double ExactOvershoot(const Plant& plant, const DesignSummary& s, evaluation::LoopOptions loop) {
  loop.pid.setpoint_weight_b = s.b;
  loop.pid.setpoint_weight_c = s.c;
  loop.pid.setpoint_filter_s = s.setpoint_filter_s;
  loop.disturbance = DisturbanceOptions{};
  loop.derivative_filter_ratio = 0.0;
  loop.pid.derivative_filter_s = 0.0;
  const double horizon = 40.0 * s.response_time_s + 20.0 * plant.delay_s + 12.0 * s.setpoint_filter_s;
  const bool sampled = loop.loop == evaluation::LoopKind::kSampled;
  const double spacing =
      sampled ? std::max(1.0, std::round(horizon / 4000.0 / loop.dt_s)) * loop.dt_s : horizon / 4000.0;
  loop.sample_time_s = spacing;
  loop.horizon_s = std::ceil(horizon / spacing) * spacing;
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  evaluation::Evaluation ev;
  if (!evaluation::Evaluate(plant, s.gains, loop, what, &ev).ok() || !ev.step.valid)
    return std::numeric_limits<double>::quiet_NaN();
  return ev.step.overshoot_pct;
}

// The setpoint stage, its overshoot checked on the exact response: where
// the samples' peak fell short of it, the stage runs again aiming lower by
// the difference and a half (at most eight times).
void ShapeSetpoint(const Plant& plant, const design::Engine& engine, const DesignOptions& options,
                   DesignSummary* s) {
  const double target = options.max_overshoot_pct;
  double aim = target;
  for (int i = 0; i < 8; ++i) {
    design::SetpointStage(engine, aim, s);
    // The stage's own least overshoot is above its aim: no lower aim helps.
    const bool reachable = s->overshoot_met;
    const double exact = ExactOvershoot(plant, *s, options.loop);
    if (std::isnan(exact)) return;
    s->overshoot_pct = exact;
    s->overshoot_met = exact <= target + 1e-9;
    if (s->overshoot_met || !reachable || !std::isfinite(target) || aim <= 0.0) break;
    aim = std::max(0.0, aim - 1.5 * (exact - target) - 0.05);
  }
  if (s->overshoot_met) s->setpoint_note.clear();
  if (!s->overshoot_met)
    s->setpoint_note =
        "the setpoint overshoot target " + FormatNumber(target) + " % is not met: b " + FormatNumber(s->b) +
        ", c " + FormatNumber(s->c) +
        (s->setpoint_filter_s > 0.0 ? " and the setpoint filter " + FormatNumber(s->setpoint_filter_s) + " s"
                                    : std::string()) +
        " reach " + FormatNumber(s->overshoot_pct) + " % at the least";
}

// Along a knob: the setpoint stage again under the front's cap where the
// design overshoots more than a faster knot (FrontOvershootCap).
void CapAlongTheFront(const Plant& plant, const design::Engine& engine, const DesignOptions& options,
                      DesignSummary* s) {
  s->overshoot_target_pct = options.max_overshoot_pct;
  if (!options.monotone_front) return;
  double from = 0.0;
  const double cap = design::FrontOvershootCap(plant, options, s->ms_bound, &from);
  if (!(from > 0.0) || s->overshoot_pct <= cap) return;
  DesignOptions capped = options;
  capped.max_overshoot_pct = cap;
  ShapeSetpoint(plant, engine, capped, s);
  s->overshoot_target_pct = cap;
  s->overshoot_cap_note = "the overshoot target " + FormatNumber(options.max_overshoot_pct) +
                          " % capped at " + FormatNumber(cap) + " %, the front's faster design at Ms " +
                          FormatNumber(from) + ": a slower design never overshoots more";
}

// migo's design as the engine's start. Where migo finds none on a plant of
// two or more integrators (their lags take its grid), its design on the
// integrators alone k / (a s^n) is the start.
bool MigoStart(const Plant& plant, const MigoOptions& mo, MigoDesign* migo) {
  if (DesignMigo(plant, mo, migo).ok() && migo->crossover_rad_s > 0.0) return true;
  int integrators = 0;
  RootsOffTheOrigin(plant.tf.den, &integrators);
  if (integrators < 2 || plant.tf.num.back() == 0.0) return false;
  Plant core = plant;
  core.tf.num = {plant.tf.num.back()};
  core.tf.den.assign(integrators + 1, 0.0);
  core.tf.den[0] = plant.tf.den[plant.tf.den.size() - 1 - integrators];
  return DesignMigo(core, mo, migo).ok() && migo->crossover_rad_s > 0.0;
}

// The design with one engine (its grid and step).
Status DesignOn(const Plant& plant, const design::Engine& engine, const DesignOptions& options, bool sampled,
                const DesignSummary* previous, DesignSummary* summary);
}  // namespace

Status DesignOptimal(const Plant& plant, const DesignOptions& options, DesignSummary* summary) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  if (plant.nonlinear)
    return Status::InvalidInput("optimal designs on a linear plant: it does not take plant " + plant.name +
                                " (use its linearisation, plant stepper)");
  // A reverse-acting plant (negative gain) is designed as -G, and the
  // gains change sign: the same loop, the same peaks and responses.
  const double dc = plant.tf.DcGain();
  const bool reverse =
      dc < 0.0 || (std::isinf(dc) && plant.tf.num.back() * plant.tf.den[plant.tf.den.size() - 2] < 0.0);
  if (reverse) {
    Plant forward = plant;
    for (double& n : forward.tf.num) n = -n;
    const Status st = DesignOptimal(forward, options, summary);
    if (!st.ok()) return st;
    summary->gains.kp = -summary->gains.kp;
    summary->gains.ki = -summary->gains.ki;
    summary->gains.kd = -summary->gains.kd;
    summary->reverse_acting = true;
    summary->message += "; the loop acts in reverse (the plant's gain is negative): so do the gains";
    return st;
  }
  // The sampled loop: the plant with the zero-order hold's half sample of
  // delay as a lag 1 / (dt s / 2 + 1) (a delay of a few microseconds would
  // cost the simulation millions of steps), the derivative filter no faster
  // than dt, checked on the sampled loop.
  const bool sampled = options.loop.loop == evaluation::LoopKind::kSampled;
  Plant design_plant = plant;
  if (sampled) {
    std::vector<double> den(design_plant.tf.den.size() + 1, 0.0);
    for (std::size_t i = 0; i < design_plant.tf.den.size(); ++i) {
      den[i] += 0.5 * options.loop.dt_s * design_plant.tf.den[i];
      den[i + 1] += design_plant.tf.den[i];
    }
    design_plant.tf.den = den;
  }
  // The grid's step is chosen for the crossover of migo's design at the same
  // bound (the largest ki: a little slower than the engine's), which is also
  // a start (its gains meet every bound); where migo has none, for the
  // rules' shapes. A design that crosses over much faster than its step was
  // chosen for is designed again on a step chosen for it.
  MigoOptions mo;
  mo.ms = std::min(options.max_ms, 4.0);
  mo.pi = options.pi;
  MigoDesign migo;
  const bool has_migo = MigoStart(design_plant, mo, &migo);
  double hint = has_migo ? migo.crossover_rad_s : 0.0;
  DesignSummary previous;
  if (has_migo) previous.gains = migo.gains;
  // The sampled loop's crossover: migo's cap on the plant itself, and at
  // most kSampledCrossoverPerRate / dt (the hold's lag there is 14 deg).
  double cap = 0.0;
  if (sampled) {
    double fastest = 0.0, slowest = 0.0;
    PlantTimes(plant, &fastest, &slowest);
    cap = std::min(kMigoSpeedCap / fastest, kSampledCrossoverPerRate / options.loop.dt_s);
  }
  for (int pass = 0; pass < 3; ++pass) {
    const design::Engine engine(design_plant, options.pi, sampled ? options.loop.dt_s : 0.0, hint, cap);
    const bool warm = has_migo || pass > 0;
    const Status st = DesignOn(plant, engine, options, sampled, warm ? &previous : nullptr, summary);
    if (!st.ok() || pass == 2 || !(summary->crossover_rad_s > 3.0 * engine.Crossover())) {
      if (st.ok()) CapAlongTheFront(plant, engine, options, summary);
      return st;
    }
    hint = summary->crossover_rad_s;
    previous = *summary;
  }
  return Status::Ok();
}

namespace {

Status DesignOn(const Plant& plant, const design::Engine& engine, const DesignOptions& options, bool sampled,
                const DesignSummary* previous, DesignSummary* summary) {
  const Eigen::VectorXd warm = previous ? engine.ShapeOf(previous->gains) : Eigen::VectorXd();
  design::Bounds b;
  // Checked for strict stability as evaluate is (the tuner's search margin
  // of 0.01 is for candidates the objective cannot see).
  b.loop = options.loop;
  b.loop.stability_margin = evaluation::LoopOptions{}.stability_margin;
  b.ms = options.max_ms;
  b.mt = options.Mt();
  b.noise_gain = options.max_noise_gain;
  b.td_max_s = options.max_td_s > 0.0 ? options.max_td_s : DominantTimeConstant(plant);
  b.crossover_cap = engine.SpeedCap();
  design::Optimum o;
  analysis::LoopAnalysis a;
  double ms_bound = b.ms;
  std::string front_note;
  if (options.crossover_rad_s > 0.0) {
    if (const Status st =
            OnTheFront(plant, engine, b, options.crossover_rad_s, &o, &a, &ms_bound, &front_note);
        !st.ok())
      return st;
  } else if (sampled ? !SampledPoint(plant, engine, b, b.ms, warm, &o, &a)
                     : !FrontPoint(plant, engine, b, b.ms, warm, &o, &a)) {
    std::ostringstream os;
    os << "optimal: no stable " << (options.pi ? "PI" : "PID") << " meets Ms <= " << FormatNumber(b.ms)
       << ", Mt <= " << FormatNumber(b.mt) << " and noise gain <= " << FormatNumber(b.noise_gain)
       << " on plant " << plant.name << ": raise --robustness or --max-noise-gain";
    return Status::InvalidInput(os.str());
  }
  DesignSummary s;
  s.gains = o.gains;
  s.load_iae = o.load_iae;
  s.ms = a.ms;
  s.mt = a.mt;
  s.noise_gain = a.noise_gain;
  s.crossover_rad_s = HighestCrossover(a);
  s.response_time_s = s.crossover_rad_s > 0.0 ? 2.0 / s.crossover_rad_s : 0.0;
  s.phase_margin_deg = a.phase_margin_deg;
  s.ms_bound = ms_bound;
  s.front_note = front_note;
  s.mt_bound = b.mt;
  s.noise_gain_bound = b.noise_gain;
  s.td_bound_s = b.td_max_s;
  b.ms = ms_bound;
  s.active = ActiveBounds(a, b, s.gains);
  s.evaluations = o.evaluations;
  if (options.unconstrained_gap) Unconstrained(plant, engine, b, o, &s);
  ShapeSetpoint(plant, engine, options, &s);
  std::ostringstream os;
  os << "optimal: the least load \u222b|e|dt with Ms <= " << FormatNumber(ms_bound)
     << ", Mt <= " << FormatNumber(b.mt) << ", noise gain <= " << FormatNumber(b.noise_gain)
     << (options.pi ? std::string(" (PI)") : ", Td <= " + FormatNumber(b.td_max_s) + " s") << ": kp "
     << FormatNumber(s.gains.kp) << ", ki " << FormatNumber(s.gains.ki) << ", kd " << FormatNumber(s.gains.kd)
     << ", tf " << FormatNumber(s.gains.tf) << ", load \u222b|e|dt " << FormatNumber(s.load_iae) << ", Ms "
     << FormatNumber(s.ms) << ", crossover " << FormatNumber(s.crossover_rad_s) << " rad/s";
  s.message = os.str();
  *summary = s;
  return Status::Ok();
}

}  // namespace

Status DesignMsForPhaseMargin(const Plant& plant, double phase_margin_deg, DesignOptions* options) {
  const auto margin = [&](double ms, double* pm) {
    DesignOptions o = *options;
    o.max_ms = ms;
    o.crossover_rad_s = 0.0;
    DesignSummary d;
    if (!DesignOptimal(plant, o, &d).ok()) return false;
    *pm = std::isfinite(d.phase_margin_deg) ? d.phase_margin_deg : 180.0;
    return true;
  };
  double lo = 1.05, hi = 4.0, pm = 0.0;
  if (!margin(lo, &pm) || pm < phase_margin_deg) {
    std::ostringstream os;
    os << "optimal: no design keeps a phase margin of " << FormatNumber(phase_margin_deg) << " deg on plant "
       << plant.name << " (at Ms 1.05 it is " << FormatNumber(pm) << " deg): lower --robustness";
    return Status::InvalidInput(os.str());
  }
  if (margin(hi, &pm) && pm >= phase_margin_deg) lo = hi;
  for (int i = 0; i < 12 && lo < hi; ++i) {
    const double mid = std::sqrt(lo * hi);
    (margin(mid, &pm) && pm >= phase_margin_deg ? lo : hi) = mid;
  }
  options->max_ms = lo;
  return Status::Ok();
}

double UltimateGain(const Plant& plant, double* w180) {
  // The phase, continuous by construction: each root's angle and -wL.
  const std::vector<std::complex<double>> zeros = PolynomialRoots(plant.tf.num);
  const std::vector<std::complex<double>> poles = PolynomialRoots(plant.tf.den);
  const auto phase = [&](double w) {
    double ph = -w * plant.delay_s;
    const std::complex<double> s(0.0, w);
    for (const auto& z : zeros) ph += std::arg(s - z);
    for (const auto& p : poles) ph -= std::arg(s - p);
    return ph;
  };
  const auto gain = [&](double w) {
    const std::complex<double> s(0.0, w);
    std::complex<double> num = 0.0, den = 0.0;
    for (double c : plant.tf.num) num = num * s + c;
    for (double c : plant.tf.den) den = den * s + c;
    return std::abs(num / den);
  };
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  const double lo = std::log(1e-4 / slowest), hi = std::log(1e4 / fastest);
  constexpr int kPoints = 2000;
  double prev_w = std::exp(lo), prev = phase(prev_w);
  for (int i = 1; i <= kPoints; ++i) {
    const double w = std::exp(lo + (hi - lo) * i / kPoints), ph = phase(w);
    // Strictly past -180 deg: a pole on the axis (an oscillator's) jumps
    // to -180 deg exactly, at an infinite gain.
    if (prev > -M_PI && ph < -M_PI - 1e-9) {
      double a = prev_w, b = w;
      for (int k = 0; k < 60; ++k) {
        const double m = std::sqrt(a * b);
        (phase(m) > -M_PI ? a : b) = m;
      }
      *w180 = std::sqrt(a * b);
      return 1.0 / gain(*w180);
    }
    prev_w = w, prev = ph;
  }
  *w180 = 0.0;
  return std::numeric_limits<double>::infinity();
}

double DefaultNoiseGain(const Plant& plant, std::string* why) {
  double w180 = 0.0;
  const double ku = plant.nonlinear ? std::numeric_limits<double>::infinity() : UltimateGain(plant, &w180);
  if (!std::isfinite(ku)) {
    *why = "none: the plant's phase never reaches -180 deg, so it has no ultimate gain to scale by";
    return std::numeric_limits<double>::infinity();
  }
  *why = FormatNumber(kDefaultNoiseGainPerUltimateGain) + " x the ultimate gain Ku = " + FormatNumber(ku) +
         " (at " + FormatNumber(w180) +
         " rad/s): Ziegler-Nichols' PID, 0.6 Ku with the usual N = 10, has 6.6 Ku";
  return kDefaultNoiseGainPerUltimateGain * ku;
}

double DesignLoadIae(const Plant& plant, const PidGains& gains) {
  const design::Engine engine(plant, gains.kd == 0.0);
  return engine.LoadIae(gains);
}

}  // namespace pidlab::tune
