// The MIGO design on the plant's frequency response (migo.h).

#include "pidlab/tune/migo.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/spec/field.h"

namespace pidlab::tune {
namespace {

using cd = std::complex<double>;
// Grid points per decade of the design's frequency response.
constexpr double kPointsPerDecade = 60.0;
// The ki scan's factor; the bisection after it.
constexpr double kKiStep = 1.3;
constexpr int kKiBisections = 12;
// No gain beyond this (the tuner's kMaxGain).
constexpr double kMaxMigoGain = 1e12;

cd PolyAt(const std::vector<double>& p, cd s) {
  cd r = 0.0;
  for (double c : p) r = r * s + c;
  return r;
}

cd PlantAt(const Plant& plant, double w) {
  const cd s(0.0, w);
  return PolyAt(plant.tf.num, s) / PolyAt(plant.tf.den, s) * std::exp(cd(0.0, -w * plant.delay_s));
}

// The plant's response on a log grid around its characteristic times.
struct Grid {
  std::vector<double> w;
  std::vector<cd> g;
};

Grid MakeGrid(const Plant& plant, double fastest_s, double slowest_s) {
  Grid grid;
  const double lo = std::log10(1e-3 / slowest_s), hi = std::log10(300.0 / fastest_s);
  const int n = std::min(4000, static_cast<int>(std::ceil((hi - lo) * kPointsPerDecade)) + 1);
  for (int i = 0; i < n; ++i) {
    const double w = std::pow(10.0, lo + (hi - lo) * i / (n - 1));
    grid.w.push_back(w);
    grid.g.push_back(PlantAt(plant, w));
  }
  return grid;
}

cd ControllerAt(const PidGains& g, double w) {
  const cd s(0.0, w);
  return g.kp + g.ki / s + g.kd * s / (1.0 + g.tf * s);
}

// Peaks of |S| and |T| and the highest gain crossover on the grid.
struct Peaks {
  double ms = 0.0, mt = 0.0, crossover = 0.0;
};

Peaks PeaksOn(const Grid& grid, const PidGains& g) {
  // Squared magnitudes: no hypot in the inner loop.
  double s2 = 0.0, t2 = 0.0;
  Peaks p;
  for (std::size_t i = 0; i < grid.w.size(); ++i) {
    const cd l = ControllerAt(g, grid.w[i]) * grid.g[i];
    const double l2 = std::norm(l), d2 = std::norm(1.0 + l);
    s2 = std::max(s2, 1.0 / d2);
    t2 = std::max(t2, l2 / d2);
    if (l2 >= 1.0) p.crossover = grid.w[i];
  }
  p.ms = std::sqrt(s2);
  p.mt = std::sqrt(t2);
  return p;
}

class Designer {
 public:
  Designer(const Plant& plant, const MigoOptions& o, double fastest_s, double slowest_s)
      : o_(o),
        grid_(MakeGrid(plant, fastest_s, slowest_s)),
        fastest_(fastest_s),
        slowest_(slowest_s),
        rational_(!(plant.delay_s > 0.0)),
        num_(plant.tf.num),
        den_(plant.tf.den) {
    for (std::size_t i = 0; i < grid_.w.size(); ++i) {
      const cd b = grid_.g[i] / cd(0.0, grid_.w[i]);
      br_.push_back(b.real());
      bi_.push_back(b.imag());
    }
    const double wmax = MaxCrossover();
    above_max_crossover_ =
        static_cast<std::size_t>(std::upper_bound(grid_.w.begin(), grid_.w.end(), wmax) - grid_.w.begin());
  }

  // The loop at (kp, td) apart from ki, L = A + ki B on the grid: A = kp G
  // (1 + td s / (1 + tf s)), B = G / s. MaxKi's scan varies ki only, so the
  // peaks of each step cost a multiply-add per point, no complex division.
  struct Loop {
    double kp = 0.0, td = 0.0;
    std::vector<double> ar, ai;
  };

  void LoopAt(double kp, double td, Loop* loop) const {
    loop->kp = kp;
    loop->td = td;
    const std::size_t n = grid_.w.size();
    loop->ar.resize(n);
    loop->ai.resize(n);
    const double tf = td > 0.0 ? td / o_.filter_ratio : 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const cd s(0.0, grid_.w[i]);
      const cd a = kp * grid_.g[i] * (td > 0.0 ? 1.0 + td * s / (1.0 + tf * s) : cd(1.0));
      loop->ar[i] = a.real();
      loop->ai[i] = a.imag();
    }
  }

  // The peaks' test of Feasible on L = A + ki B: Ms, Mt <= the bound and no
  // gain crossover above MaxCrossover(). The point that failed last is
  // tried first, so that a step past the bound costs a few points.
  bool PeaksFeasible(const Loop& loop, double ki) const {
    const std::size_t n = grid_.w.size();
    const double ms2 = o_.ms * o_.ms;
    const auto fails = [&](std::size_t i) {
      const double lr = loop.ar[i] + ki * br_[i], li = loop.ai[i] + ki * bi_[i];
      const double l2 = lr * lr + li * li, d2 = (1.0 + lr) * (1.0 + lr) + li * li;
      return !(ms2 * d2 >= 1.0) || !(l2 <= ms2 * d2) || (i >= above_max_crossover_ && l2 >= 1.0);
    };
    if (last_failed_ < n && fails(last_failed_)) return false;
    for (std::size_t i = 0; i < n; ++i)
      if (fails(i)) {
        last_failed_ = i;
        return false;
      }
    return true;
  }

  bool Feasible(const Loop& loop, double ki) const {
    const double kp = loop.kp;
    if (!(kp > 0.0) || !(ki > 0.0) || !(ki <= kMaxMigoGain) || !(kp <= kMaxMigoGain)) return false;
    if (!PeaksFeasible(loop, ki)) return false;
    return rational_ ? RationalLoopIsStable(Gains(kp, ki, loop.td)) : true;
  }

  // Without dead time the closed loop's poles are the roots of
  // den s (1 + tf s) + num ((kp s + ki)(1 + tf s) + kd s^2): an encirclement
  // the peaks on a grid cannot see is seen here.
  bool RationalLoopIsStable(const PidGains& g) const {
    const std::vector<double> c = {g.kp * g.tf + g.kd, g.kp + g.ki * g.tf,
                                   g.ki};               // (kp s + ki)(1 + tf s) + kd s^2
    const std::vector<double> s_tf = {g.tf, 1.0, 0.0};  // s (1 + tf s)
    const std::vector<double> p = Add(Multiply(den_, s_tf), Multiply(num_, c));
    for (const cd& r : PolynomialRoots(p))
      if (!(r.real() < 0.0)) return false;
    return true;
  }

  static std::vector<double> Multiply(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> r(a.size() + b.size() - 1, 0.0);
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
    return r;
  }
  static std::vector<double> Add(std::vector<double> a, std::vector<double> b) {
    if (a.size() < b.size()) a.swap(b);
    const std::size_t shift = a.size() - b.size();
    for (std::size_t i = 0; i < b.size(); ++i) a[shift + i] += b[i];
    while (a.size() > 1 && a.front() == 0.0) a.erase(a.begin());
    return a;
  }

  // 2 / T for a response time T; else ten times the plant's fastest rate,
  // which bounds a plant whose Ms allows any speed (no dead time, relative
  // degree 1).
  double MaxCrossover() const {
    return o_.response_time_s > 0.0 ? 2.0 / o_.response_time_s : kMigoSpeedCap / fastest_;
  }

  PidGains Gains(double kp, double ki, double td) const {
    PidGains g;
    g.kp = kp;
    g.ki = ki;
    g.kd = kp * td;
    g.tf = td > 0.0 ? td / o_.filter_ratio : 0.0;
    return g;
  }

  // The largest feasible ki at (kp, td), scanned up from `from` (0: none).
  double MaxKi(double kp, double td, double from) const {
    LoopAt(kp, td, &loop_);
    double ki = from;
    if (!Feasible(loop_, ki)) return 0.0;
    double bad = 0.0;
    for (int i = 0; i < 400; ++i) {
      const double next = ki * kKiStep;
      if (!Feasible(loop_, next)) {
        bad = next;
        break;
      }
      ki = next;
    }
    if (bad == 0.0) return ki;
    for (int i = 0; i < kKiBisections; ++i) {
      const double mid = std::sqrt(ki * bad);
      (Feasible(loop_, mid) ? ki : bad) = mid;
    }
    return ki;
  }

  double KiFloor(double kp) const { return kp * 1e-4 / slowest_; }

  // Along kp from tiny, upward while some ki is feasible: the best (kp, ki).
  void ScanKp(double kp0, double td, double* best_kp, double* best_ki) const {
    double ki_prev = 0.0;
    for (double kp = kp0; kp<kp0 * 1e8; kp *= ki_prev> 0.0 ? 1.25 : 2.0) {
      const double from = ki_prev > 0.0 ? std::max(KiFloor(kp), ki_prev / 16.0) : KiFloor(kp);
      double ki = MaxKi(kp, td, from);
      if (ki == 0.0 && from > KiFloor(kp)) ki = MaxKi(kp, td, KiFloor(kp));
      if (ki == 0.0) {
        if (ki_prev > 0.0) break;  // past the feasible kp
        continue;
      }
      ki_prev = ki;
      if (ki > *best_ki) *best_ki = ki, *best_kp = kp;
    }
  }

  // A pattern search on (ln kp, ln td) from the grid's best.
  void Polish(double* kp, double* td, double* ki) const {
    for (double step = 0.2; step > 0.005; step *= 0.5) {
      bool moved = true;
      while (moved) {
        moved = false;
        for (const auto& [dk, dt] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          if (dt != 0 && *td == 0.0) continue;
          const double k = *kp * std::exp(dk * step), t = *td * std::exp(dt * step);
          const double i = MaxKi(k, t, std::max(KiFloor(k), *ki / 4.0));
          if (i > *ki * (1.0 + 1e-9)) *kp = k, *td = t, *ki = i, moved = true;
        }
      }
    }
  }

  double Fastest() const { return fastest_; }
  double Slowest() const { return slowest_; }
  Peaks PeaksOf(const PidGains& g) const { return PeaksOn(grid_, g); }

 private:
  MigoOptions o_;
  Grid grid_;
  double fastest_, slowest_;
  bool rational_;
  std::vector<double> num_, den_;
  std::vector<double> br_, bi_;          // B = G / s on the grid
  std::size_t above_max_crossover_ = 0;  // the first grid point above MaxCrossover()
  mutable Loop loop_;                    // MaxKi's A
  mutable std::size_t last_failed_ = static_cast<std::size_t>(-1);
};

}  // namespace

bool MigoOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(ms > 1.0 && ms <= 4.0))
    os << "robustness " << spec::FormatNumber(ms) << " is not an Ms bound in (1, 4]";
  else if (!(response_time_s >= 0.0) || !std::isfinite(response_time_s))
    os << "response_time " << spec::FormatNumber(response_time_s) << " must be >= 0 and finite (s)";
  else if (!(filter_ratio > 0.0) || !std::isfinite(filter_ratio))
    os << "derivative filter ratio " << spec::FormatNumber(filter_ratio) << " must be > 0 and finite";
  else if (!(max_overshoot_pct >= 0.0))
    os << "max_overshoot " << spec::FormatNumber(max_overshoot_pct) << " must be >= 0 (%)";
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

std::vector<cd> RootsOffTheOrigin(std::vector<double> coefficients, int* at_origin) {
  int n = 0;
  while (coefficients.size() > 1 && coefficients.back() == 0.0) coefficients.pop_back(), ++n;
  if (at_origin != nullptr) *at_origin = n;
  return PolynomialRoots(coefficients);
}

double UnityGainTime(const Plant& plant) {
  double lo = -12.0, hi = 12.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::abs(PlantAt(plant, std::pow(10.0, mid))) > 1.0 ? lo : hi) = mid;
  }
  return std::pow(10.0, -0.5 * (lo + hi));
}

void PlantTimes(const Plant& plant, double* fastest_s, double* slowest_s) {
  std::vector<double> times;
  for (const auto* p : {&plant.tf.num, &plant.tf.den})
    for (const cd& r : RootsOffTheOrigin(*p, nullptr))
      if (std::abs(r) > 1e-12) times.push_back(1.0 / std::abs(r));
  if (plant.delay_s > 0.0) times.push_back(plant.delay_s);
  // No pole, zero or delay off the origin (k / s^n): the gain crossover.
  if (times.empty()) times.push_back(UnityGainTime(plant));
  *fastest_s = *std::min_element(times.begin(), times.end());
  *slowest_s = *std::max_element(times.begin(), times.end());
}

Status MigoMsForPhaseMargin(const Plant& plant, double phase_margin_deg, MigoOptions* options) {
  const auto margin = [&plant, options](double ms, double* pm) {
    MigoOptions o = *options;
    o.ms = ms;
    MigoDesign d;
    analysis::LoopAnalysis a;
    if (!DesignMigo(plant, o, &d).ok() ||
        !analysis::AnalyzeLoop(plant, d.gains, evaluation::LoopOptions{}, analysis::LoopAnalysisOptions{}, &a)
             .ok() ||
        !a.stable)
      return false;
    *pm = std::isfinite(a.phase_margin_deg) ? a.phase_margin_deg : 180.0;
    return true;
  };
  double lo = 1.05, hi = 4.0, pm = 0.0;
  if (!margin(lo, &pm) || pm < phase_margin_deg) {
    std::ostringstream os;
    os << "migo: no design keeps a phase margin of " << spec::FormatNumber(phase_margin_deg)
       << " deg on plant " << plant.name << " (at Ms 1.05 it is " << spec::FormatNumber(pm)
       << " deg): lower --robustness";
    return Status::InvalidInput(os.str());
  }
  if (margin(hi, &pm) && pm >= phase_margin_deg) lo = hi;
  for (int i = 0; i < 10 && lo < hi; ++i) {
    const double mid = std::sqrt(lo * hi);
    (margin(mid, &pm) && pm >= phase_margin_deg ? lo : hi) = mid;
  }
  options->ms = lo;
  return Status::Ok();
}

double NiceUp(double v) {
  const double e = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * e >= v * (1.0 - 1e-12)) return m * e;
  return 10.0 * e;
}

TimeScale LoopTimeScale(double fastest_s, double slowest_s, double delay_s) {
  TimeScale t;
  t.source = "plant";
  t.horizon_s = NiceUp(10.0 * slowest_s + delay_s);
  t.sample_time_s = t.horizon_s / 500.0;
  while (t.sample_time_s > fastest_s / 5.0 && t.horizon_s / t.sample_time_s < 20000.0) t.sample_time_s /= 2.0;
  std::ostringstream os;
  os << "10 x the slowest closed-loop time constant " << spec::FormatNumber(slowest_s) << " s";
  if (delay_s > 0.0) os << " + the dead time " << spec::FormatNumber(delay_s) << " s";
  os << ", rounded up; samples at most 1/5 of the fastest, " << spec::FormatNumber(fastest_s) << " s";
  t.reason = os.str();
  return t;
}

namespace {

// The last design of this thread, by its inputs: the run assembly designs
// once to find the time scale and Tune() again for the gains.
struct MigoMemo {
  std::vector<double> num, den;
  double delay = -1.0, ms = 0.0, response_time = 0.0, overshoot = 0.0, ratio = 0.0;
  bool pi = false;
  MigoDesign design;
  bool Matches(const Plant& p, const MigoOptions& o) const {
    return num == p.tf.num && den == p.tf.den && delay == p.delay_s && ms == o.ms &&
           response_time == o.response_time_s && overshoot == o.max_overshoot_pct &&
           ratio == o.filter_ratio && pi == o.pi;
  }
};

Status DesignMigoUncached(const Plant& plant, const MigoOptions& options, MigoDesign* design);

}  // namespace

Status DesignMigo(const Plant& plant, const MigoOptions& options, MigoDesign* design) {
  thread_local MigoMemo memo;
  if (!plant.nonlinear && memo.Matches(plant, options)) {
    *design = memo.design;
    return Status::Ok();
  }
  const Status status = DesignMigoUncached(plant, options, design);
  if (status.ok() && !plant.nonlinear)
    memo = {plant.tf.num,
            plant.tf.den,
            plant.delay_s,
            options.ms,
            options.response_time_s,
            options.max_overshoot_pct,
            options.filter_ratio,
            options.pi,
            *design};
  return status;
}

namespace {

Status DesignMigoUncached(const Plant& plant, const MigoOptions& options, MigoDesign* design) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  if (plant.nonlinear)
    return Status::InvalidInput("migo designs on a linear plant: it does not take plant " + plant.name +
                                " (use its linearisation, plant stepper)");
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  const Designer d(plant, options, fastest, slowest);
  // kp's scale: the plant's gain at the geometric mean of its times.
  // (Off any pole on the axis: 0.7 of the mean rate.)
  const double g0 = std::abs(PlantAt(plant, 0.7 / std::sqrt(fastest * slowest)));
  const double kp0 = 1e-4 / (std::isfinite(g0) && g0 > 0.0 ? g0 : 1.0);
  std::vector<double> tds = {0.0};
  if (!options.pi)
    for (double t = fastest / 10.0; t <= 3.0 * slowest; t *= 2.0) tds.push_back(t);
  double kp = 0.0, ki = 0.0, td = 0.0;
  for (double t : tds) {
    double k = 0.0, i = 0.0;
    d.ScanKp(kp0, t, &k, &i);
    if (i > ki) kp = k, ki = i, td = t;
  }
  if (!(ki > 0.0)) {
    std::ostringstream os;
    os << "migo: no PID with ki > 0 keeps Ms and Mt <= " << spec::FormatNumber(options.ms) << " on plant "
       << plant.name << (options.response_time_s > 0.0 ? " at the response time given" : "")
       << ": raise --robustness";
    return Status::InvalidInput(os.str());
  }
  d.Polish(&kp, &td, &ki);
  // The peaks on a grid cannot see an encirclement: the exact stability
  // check, and where it fails, the largest stable ki below (bisection).
  const auto stable = [&plant](const PidGains& g) {
    analysis::LoopAnalysis a;
    return analysis::AnalyzeLoop(plant, g, evaluation::LoopOptions{}, analysis::LoopAnalysisOptions{}, &a)
               .ok() &&
           a.stable;
  };
  bool unstable_at_max = false;
  if (!stable(d.Gains(kp, ki, td))) {
    unstable_at_max = true;
    double lo = d.KiFloor(kp), hi = ki;
    if (!stable(d.Gains(kp, lo, td)))
      return Status::InvalidInput("migo: the design's loop on plant " + plant.name +
                                  " is unstable even at the smallest ki (the frequency grid missed it): "
                                  "tune it with --method multi-start");
    for (int i = 0; i < 40; ++i) {
      const double mid = std::sqrt(lo * hi);
      (stable(d.Gains(kp, mid, td)) ? lo : hi) = mid;
    }
    ki = lo;
  }
  MigoDesign r;
  r.gains = d.Gains(kp, ki, td);
  const Peaks p = d.PeaksOf(r.gains);
  r.ms = p.ms;
  r.mt = p.mt;
  r.crossover_rad_s = p.crossover;
  r.ms_bound = options.ms;
  r.plant_time_s = slowest;
  std::ostringstream os;
  os << "migo: the largest ki with Ms, Mt <= " << spec::FormatNumber(options.ms)
     << (options.pi ? std::string(" (PI)")
                    : " (PID, tf = Td/" + spec::FormatNumber(options.filter_ratio) + ")")
     << ": kp " << spec::FormatNumber(kp) << ", ki " << spec::FormatNumber(ki) << ", kd "
     << spec::FormatNumber(r.gains.kd) << ", Ms " << spec::FormatNumber(r.ms) << ", crossover "
     << spec::FormatNumber(r.crossover_rad_s) << " rad/s"
     << (unstable_at_max
             ? " (ki lowered to the largest stable value: the peaks' bound allowed an unstable loop)"
             : "");
  r.message = os.str();
  *design = r;
  return Status::Ok();
}

}  // namespace

Status MigoSetpointWeights(const Plant& plant, const evaluation::LoopOptions& loop,
                           const MigoOptions& options, MigoDesign* design, TwoDofSummary* two_dof) {
  evaluation::LoopOptions l = loop;
  l.pid.derivative_filter_s = 0.0;
  l.derivative_filter_ratio = 0.0;  // the design's own tf
  if (const Status st =
          SetpointWeightForOvershoot(plant, design->gains, l, 0.0, options.max_overshoot_pct, two_dof);
      !st.ok())
    return st;
  design->b = two_dof->b;
  design->c = two_dof->c;
  return Status::Ok();
}

Status DesignMigoForSetpoint(const Plant& plant, const evaluation::LoopOptions& loop,
                             const MigoOptions& options, MigoDesign* design, TwoDofSummary* two_dof) {
  MigoOptions o = options;
  Status status;
  for (;;) {
    status = DesignMigo(plant, o, design);
    if (status.ok()) status = MigoSetpointWeights(plant, loop, o, design, two_dof);
    if (!status.ok() || two_dof->after.overshoot_pct <= kMigoMaxOvershootAtZeroB || o.ms <= 1.2 + 1e-9) break;
    o.ms = std::max(1.2, o.ms - 0.05);
  }
  if (status.ok() && o.ms < options.ms)
    design->message += " (bound tightened from " + spec::FormatNumber(options.ms) +
                       ": the setpoint overshoot exceeded " + spec::FormatNumber(kMigoMaxOvershootAtZeroB) +
                       " % at b = 0)";
  return status;
}

}  // namespace pidlab::tune
