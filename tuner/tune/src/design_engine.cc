// The design engine's optimisation for one set of bounds (design_engine.h).
//
// The gains are searched as a shape, (log Ti, log Td, log N) with Ti = kp/ki,
// Td = kd/kp and tf = Td/N (PI: log Ti), and a loop gain kp: for each shape
// the largest kp whose loop meets the bounds on the frequency grid, because
// the load IAE falls as the loop gets faster until a bound stops it. Where
// that is not so (a loose bound), a fourth coordinate lowers kp below it.
// Nelder-Mead runs from the shapes of the SIMC and AMIGO rules and of a
// generic start, and the best is polished once more.

#include "design_engine.h"

#include <algorithm>
#include <cmath>

#include "pidlab/optim/nelder_mead.h"
#include "pidlab/plant_sim/polynomial.h"
#include "pidlab/tune/migo.h"
#include "pidlab/tune/tuning_rules.h"

namespace pidlab::tune::design {

using cd = std::complex<double>;

namespace {

constexpr double kPointsPerDecade = 50.0;
// The cost of a shape no gain makes feasible, times 1 + its least violation.
constexpr double kInfeasible = 1e200;
// Samples of the load response per radian of the first estimate of the
// crossover: about 190 per period.
constexpr double kStepsPerRadian = 30.0;
// The first estimate's shape on a plant no rule applies to.
constexpr double kGenericTiFactor = 1.0;
// The evaluations of a search from a warm start alone.
constexpr int kWarmOnlyEvaluations = 80;

// The rule's shape (Ti, Td, N = 10) where SIMC or AMIGO applies.
bool RuleShape(const Plant& plant, TuningRule rule, bool pi, Eigen::VectorXd* shape) {
  TuningRuleResult r;
  if (!ApplyTuningRule(plant, rule, pi ? RuleForm::kPi : RuleForm::kPid, &r).ok()) return false;
  const PidGains& g = r.gains;
  if (!(g.kp > 0.0) || !(g.ki > 0.0)) return false;
  const double ti = g.kp / g.ki;
  if (pi) {
    *shape = Eigen::VectorXd::Constant(1, std::log(ti));
    return true;
  }
  const double td = g.kd > 0.0 ? g.kd / g.kp : 0.1 * ti;
  *shape = Eigen::Vector3d(std::log(ti), std::log(td), std::log(10.0));
  return true;
}

}  // namespace

Engine::Engine(const Plant& plant, bool pi, double min_tf_s, double crossover_hint, double speed_cap)
    : plant_(plant), pi_(pi), min_tf_s_(min_tf_s), sim_(plant, 1.0) {
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  speed_cap_ = speed_cap > 0.0 ? speed_cap : kMigoSpeedCap / fastest;
  // The poles at the origin exactly (the denominator's trailing zeros; their
  // computed roots scatter by the square root of the precision), then the rest.
  std::vector<double> den = plant.tf.den;
  while (den.size() > 1 && den.back() == 0.0) {
    den.pop_back();
    ++origin_poles_;
  }
  for (const cd& p : PolynomialRoots(den)) {
    if (std::abs(p) <= 1e-12 * std::max(1.0, 1.0 / fastest))
      ++origin_poles_;
    else if (p.real() > 0.0)
      ++rhp_poles_;
  }
  grid_ = MakeFrequencyGrid(plant, 1e-3 / slowest, std::max(300.0 / fastest, 30.0 * speed_cap_),
                            kPointsPerDecade);
  // The first estimate of the crossover: the rule's shape (or a PI with Ti
  // the slowest time) as fast as Ms 1.4 allows.
  Eigen::VectorXd shape;
  if (!RuleShape(plant, TuningRule::kAmigo, pi, &shape) && !RuleShape(plant, TuningRule::kSimc, pi, &shape)) {
    shape = pi ? Eigen::VectorXd::Constant(1, std::log(kGenericTiFactor * slowest))
               : Eigen::VectorXd(Eigen::Vector3d(std::log(slowest), std::log(0.1 * slowest), std::log(10.0)));
  }
  Bounds b;
  b.ms = b.mt = kMigoDefaultMs;
  b.noise_gain = std::numeric_limits<double>::infinity();
  b.crossover_cap = speed_cap_;
  b.td_max_s = std::numeric_limits<double>::infinity();
  const double kp = MaxKp(shape, b, 0.0);
  double wc = crossover_hint > 0.0 ? crossover_hint
              : kp > 0.0           ? PeaksOf(grid_, ShapeGains(shape, kp)).crossover
                                   : 0.0;
  if (!(wc > 0.0)) wc = 1.0 / slowest;
  wc = std::min(wc, speed_cap_);
  time_s_ = 1.0 / wc;
  sim_ = LoopSimulator(plant, 1.0 / (kStepsPerRadian * wc));
  // Sixty periods of the crossover at most, and at least 200 delays.
  max_steps_ = static_cast<int>(std::ceil(60.0 * 2.0 * M_PI / wc / sim_.Step()));
  if (plant.delay_s > 0.0)
    max_steps_ = std::max(max_steps_, static_cast<int>(200.0 * plant.delay_s / sim_.Step()));
  max_steps_ = std::min(max_steps_, 200000);
}

Eigen::VectorXd Engine::ShapeOf(const PidGains& g) const {
  if (pi_) return Eigen::VectorXd::Constant(1, std::log(g.kp / g.ki));
  const double td = g.kd / g.kp;
  return Eigen::Vector3d(std::log(g.kp / g.ki), std::log(td), std::log(td / g.tf));
}

PidGains Engine::ShapeGains(const Eigen::VectorXd& shape, double kp) const {
  PidGains g;
  g.kp = kp;
  g.ki = kp / std::exp(shape(0));
  if (!pi_) {
    const double td = std::exp(shape(1));
    g.kd = kp * td;
    g.tf = std::max(td / std::exp(shape(2)), min_tf_s_);
  }
  return g;
}

namespace {

// One shape's loop on the grid at any gain: L = kp Ls, C = kp Cs.
class GainScan {
 public:
  GainScan(const FrequencyGrid& grid, const PidGains& unit, const Bounds& bounds, int rhp_poles,
           int origin_poles, const Plant* rational)
      : grid_(grid), b_(bounds), rhp_(rhp_poles), origin_(origin_poles), rational_(rational), unit_(unit) {
    const std::size_t n = grid.w.size();
    ls_.resize(n);
    mls_.resize(n);
    cs_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const cd c = ControllerAt(unit, grid.w[i]);
      ls_[i] = c * grid.g[i];
      mls_[i] = std::abs(ls_[i]);
      cs_[i] = std::abs(c);
    }
    c_inf_ = unit.kp + (unit.kd > 0.0 ? unit.kd / unit.tf : 0.0);
    while (cap_ + 1 < n && grid.w[cap_] < bounds.crossover_cap) ++cap_;
  }

  // A gain above which the loop crosses over beyond the cap.
  double Top() const { return 2.0 / std::max(std::abs(ls_[cap_]), 1e-300); }

  // The largest peak over its bound (<= 1: the bounds are met); 2 for a
  // crossover beyond the cap or |L| >= 1 where the grid is coarse. Once the
  // peak passes `stop` the rest of the grid is skipped: a value > stop.
  // (Magnitudes by sqrt(norm): no overflow is possible at these sizes, and
  // hypot's care costs a third of the design's time.)
  double Violation(double kp, double stop = HUGE_VAL) const {
    double v = 0.0;
    const double inv_ms = 1.0 / b_.ms, inv_mt = 1.0 / b_.mt, inv_noise = 1.0 / b_.noise_gain;
    for (std::size_t i = 0; i < ls_.size(); ++i) {
      const double ml = kp * mls_[i];
      if (ml >= 1.0 && (grid_.w[i] > b_.crossover_cap || grid_.coarse[i])) return 2.0;
      const double d = grid_.coarse[i] ? 1.0 - ml : std::sqrt(std::norm(1.0 + kp * ls_[i]));
      v = std::max(v, std::max({inv_ms, ml * inv_mt, kp * cs_[i] * inv_noise}) / d);
      if (v > stop) return v;
    }
    const double l_inf = kp * c_inf_ * grid_.g_inf, d_inf = std::abs(1.0 + l_inf);
    return std::max(
        {v, 1.0 / (b_.ms * d_inf), std::abs(l_inf) / (b_.mt * d_inf), kp * c_inf_ / (b_.noise_gain * d_inf)});
  }

  // The Nyquist criterion on the grid: Z = P - (2 D - k pi) / (2 pi)
  // closed-loop poles in the right half-plane, D the change of arg(1 + L)
  // from 0+ to infinity, k the poles at the origin (indented to the right)
  // and P the plant's in the right half-plane. Where the grid is coarse for
  // the delay, |L| < 1 (feasible), so 1 + L stays right of the axis and the
  // principal differences are exact.
  bool Stable(double kp) const {
    if (rational_) return RationalStable(kp);
    double d = 0.0;
    cd prev = 1.0 + kp * ls_[0];
    for (std::size_t i = 1; i < ls_.size(); ++i) {
      const cd next = 1.0 + kp * ls_[i];
      d += std::arg(next * std::conj(prev));
      prev = next;
    }
    d += std::arg((1.0 + kp * c_inf_ * grid_.g_inf) * std::conj(prev));
    return std::abs(rhp_ - (2.0 * d - origin_ * M_PI) / (2.0 * M_PI)) < 0.5;
  }

  bool Good(double kp) const { return Violation(kp, 1.0) <= 1.0 && Stable(kp); }

 private:
  // Without dead time, the closed loop's poles themselves: the roots of
  // den s (1 + tf s) + num ((kp s + ki)(1 + tf s) + kd s^2), which a grid
  // cannot miss at a lightly damped resonance.
  bool RationalStable(double kp) const {
    const PidGains g{kp * unit_.kp, kp * unit_.ki, kp * unit_.kd, unit_.tf};
    const bool filter = g.kd > 0.0;
    const std::vector<double> c = filter ? std::vector<double>{g.kp * g.tf + g.kd, g.kp + g.ki * g.tf, g.ki}
                                         : std::vector<double>{g.kp, g.ki};
    const std::vector<double> s =
        filter ? std::vector<double>{g.tf, 1.0, 0.0} : std::vector<double>{1.0, 0.0};
    std::vector<double> p = PolynomialProduct(rational_->tf.den, s);
    const std::vector<double> q = PolynomialProduct(rational_->tf.num, c);
    for (std::size_t i = 0; i < q.size(); ++i) p[p.size() - q.size() + i] += q[i];
    while (p.size() > 1 && p.front() == 0.0) p.erase(p.begin());
    for (const cd& r : PolynomialRoots(p))
      if (!(r.real() < 0.0)) return false;
    return true;
  }

  const FrequencyGrid& grid_;
  Bounds b_;
  int rhp_, origin_;
  std::vector<cd> ls_;
  std::vector<double> mls_, cs_;
  double c_inf_ = 0.0;
  std::size_t cap_ = 0;
  const Plant* rational_;
  PidGains unit_;
};

// The least violation in (lo, hi) by golden sections on log kp.
double LeastViolation(const GainScan& scan, double lo, double hi, double* at) {
  constexpr double kGolden = 0.6180339887498949;
  double a = std::log(lo), b = std::log(hi);
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  double f1 = scan.Violation(std::exp(x1)), f2 = scan.Violation(std::exp(x2));
  for (int i = 0; i < 24; ++i) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - kGolden * (b - a), f1 = scan.Violation(std::exp(x1));
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + kGolden * (b - a), f2 = scan.Violation(std::exp(x2));
    }
  }
  *at = std::exp(f1 < f2 ? x1 : x2);
  return std::min(f1, f2);
}

}  // namespace

double Engine::MaxKp(const Eigen::VectorXd& shape, const Bounds& bounds, double hint,
                     double* least_violation) const {
  (void)hint;
  const GainScan scan(grid_, ShapeGains(shape, 1.0), bounds, rhp_poles_, origin_poles_,
                      plant_.delay_s > 0.0 ? nullptr : &plant_);
  // Down from a gain whose crossover lies beyond the cap, by 1.25 over 19
  // decades, to the first gain that meets the bounds with a stable loop;
  // then bisection up to the edge: the largest such gain, whichever band of
  // gains it lies in (an integral-heavy shape on a lag can be feasible at a
  // small gain, not at a moderate one, and again at a larger one). A band
  // narrower than a step (a conditionally stable loop, an integrating
  // plant's) shows as a dip of the violation: the dips under 1.3 are
  // searched, highest gain first.
  constexpr double kStep = 1.25;
  double kp = 0.0, bad = scan.Top();
  std::vector<double> k, v;
  double least = HUGE_VAL;
  for (int i = 0; i < 200; ++i) {
    k.push_back(bad / kStep);
    // (Exact where it can be a dip, < 1.3, or the least so far.)
    v.push_back(scan.Violation(k.back(), std::max(1.3, least)));
    least = std::min(least, v.back());
    if (v.back() <= 1.0 && scan.Stable(k.back())) {
      kp = k.back();
      break;
    }
    bad = k.back();
  }
  // The dips above the first feasible gain too (its band may be a slower
  // one below a narrow faster band: the corner where Ms and Mt meet).
  const std::size_t scanned = v.size();
  for (std::size_t i = 1; i + 1 < scanned; ++i) {
    if (!(v[i] <= v[i - 1] && v[i] <= v[i + 1] && v[i] < 1.3)) continue;
    double at = 0.0;
    if (LeastViolation(scan, k[i + 1], k[i - 1], &at) <= 1.0 && scan.Stable(at) && at > kp) {
      kp = at, bad = k[i - 1];
      break;
    }
  }
  if (!(kp > 0.0)) {
    if (least_violation) *least_violation = *std::min_element(v.begin(), v.end());
    return 0.0;
  }
  for (int i = 0; i < 14; ++i) {
    const double mid = std::sqrt(kp * bad);
    (scan.Good(mid) ? kp : bad) = mid;
  }
  return kp;
}

double Engine::LoadIae(const PidGains& g) const {
  Inputs in;
  in.load = 1.0;
  const Response r = sim_.Run(g, in, max_steps_);
  double peak = 0.0;
  for (double y : r.y) peak = std::max(peak, std::abs(y));
  if (r.y.empty() || (!r.settled && !(std::abs(r.y.back()) <= 1e-4 * peak)))
    return std::numeric_limits<double>::infinity();
  return IntegralAbs(r.y, 0.0, sim_.Step());
}

double Engine::Cost(const Eigen::VectorXd& shape, double alpha, const Bounds& bounds, double* kp_hint,
                    PidGains* gains) const {
  ++evaluations_;
  if (!pi_ && std::exp(shape(1)) > bounds.td_max_s * (1.0 + 1e-12)) return HUGE_VAL;
  double least = HUGE_VAL;
  const double kp_max = MaxKp(shape, bounds, *kp_hint, &least);
  // A shape with no feasible gain: a value above every feasible one that
  // falls as the shape nears feasibility, so the simplex can walk out of it.
  if (!(kp_max > 0.0)) return std::isfinite(least) ? kInfeasible * (1.0 + least) : HUGE_VAL;
  *kp_hint = kp_max;
  const PidGains g = ShapeGains(shape, kp_max * std::exp(std::min(alpha, 0.0)));
  if (gains) *gains = g;
  return LoadIae(g);
}

std::vector<Eigen::VectorXd> Engine::Starts(const Bounds& bounds) const {
  std::vector<Eigen::VectorXd> starts;
  Eigen::VectorXd s;
  if (RuleShape(plant_, TuningRule::kAmigo, pi_, &s)) starts.push_back(s);
  if (RuleShape(plant_, TuningRule::kSimc, pi_, &s)) starts.push_back(s);
  // Generic: Ti from the crossover estimate (a PI's and four times it), Td
  // a quarter of it.
  for (const double ti : {2.0 * time_s_, 8.0 * time_s_}) {
    if (pi_)
      starts.push_back(Eigen::VectorXd::Constant(1, std::log(ti)));
    else
      starts.push_back(Eigen::Vector3d(std::log(ti), std::log(std::min(0.25 * ti, 0.9 * bounds.td_max_s)),
                                       std::log(10.0)));
  }
  for (Eigen::VectorXd& x : starts)
    if (!pi_) x(1) = std::min(x(1), std::log(0.9 * bounds.td_max_s));
  return starts;
}

bool Engine::Optimize(const Bounds& bounds, const Eigen::VectorXd& warm, Optimum* best,
                      bool warm_only) const {
  evaluations_ = 0;
  const int dims = pi_ ? 1 : 3;
  optim::Bounds box{Eigen::VectorXd(dims), Eigen::VectorXd(dims)};
  const double t = time_s_;
  box.lower(0) = std::log(1e-3 * t);
  box.upper(0) = std::log(1e4 * t);
  if (!pi_) {
    box.lower(1) = std::log(1e-4 * std::min(t, bounds.td_max_s));
    box.upper(1) = std::log(bounds.td_max_s);
    box.lower(2) = std::log(kDesignMinFilterRatio);
    box.upper(2) = std::log(kDesignMaxFilterRatio);
  }
  std::vector<Eigen::VectorXd> starts;
  if (!(warm_only && warm.size() == dims)) starts = Starts(bounds);
  if (warm.size() == dims) starts.insert(starts.begin(), warm);
  double kp_hint = 0.0;
  const optim::ObjectiveFunction f = [&](const Eigen::VectorXd& x) {
    return Cost(x, 0.0, bounds, &kp_hint, nullptr);
  };
  optim::OptimizerSummary result;
  // One Nelder-Mead run from x0, kept where it improves on the best.
  const auto run = [&](const Eigen::VectorXd& x0, double step, int evaluations, double x_tol, double f_tol,
                       int restarts) {
    optim::NelderMeadOptions o;
    o.x0 = x0;
    o.initial_step_fraction = step;
    o.max_evaluations = evaluations;
    o.x_tolerance = x_tol;
    o.f_tolerance = f_tol;
    o.restarts_on_convergence = restarts;
    kp_hint = 0.0;
    optim::OptimizerSummary s;
    optim::NelderMead(f, box, o, &s);
    if (s.IsUsable() && s.f < kInfeasible && s.f < result.f) result = s;
  };
  for (const Eigen::VectorXd& x0 : starts)
    run(x0.cwiseMax(box.lower).cwiseMin(box.upper), 0.03,
        warm_only                                       ? kWarmOnlyEvaluations
        : warm.size() == dims && &x0 != &starts.front() ? 60
                                                        : 160,
        1e-5, 1e-7, 0);
  if (!result.IsUsable()) return false;
  // Polish from the best, with a fresh simplex (not from a warm start alone:
  // a quick look nearby).
  const Eigen::VectorXd from = result.x;
  if (!warm_only) run(from, 0.01, 120, 1e-6, 1e-9, 1);
  kp_hint = 0.0;
  PidGains g;
  double value = Cost(result.x, 0.0, bounds, &kp_hint, &g);
  // A bound that is not active: kp below the largest (a fourth coordinate).
  PidGains lower;
  double hint = kp_hint;
  if (!warm_only && Cost(result.x, std::log(0.97), bounds, &hint, &lower) < value) {
    Eigen::VectorXd x0(dims + 1), lo(dims + 1), hi(dims + 1);
    x0 << result.x, std::log(0.97);
    lo << box.lower, -4.0;
    hi << box.upper, 0.0;
    const optim::ObjectiveFunction f4 = [&](const Eigen::VectorXd& x) {
      return Cost(x.head(dims), x(dims), bounds, &kp_hint, nullptr);
    };
    optim::NelderMeadOptions o;
    o.x0 = x0;
    o.initial_step_fraction = 0.02;
    o.max_evaluations = 300;
    o.x_tolerance = 1e-6;
    o.f_tolerance = 1e-9;
    optim::OptimizerSummary s;
    kp_hint = 0.0;
    optim::NelderMead(f4, optim::Bounds{lo, hi}, o, &s);
    if (s.IsUsable() && s.f < kInfeasible && s.f < value) {
      kp_hint = 0.0;
      value = Cost(s.x.head(dims), s.x(dims), bounds, &kp_hint, &g);
      result.x = s.x.head(dims);
    }
  }
  if (!(value < kInfeasible)) return false;
  best->gains = g;
  best->load_iae = value;
  best->shape = result.x;
  best->evaluations = evaluations_;
  return true;
}

}  // namespace pidlab::tune::design
