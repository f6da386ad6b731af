// Evaluation of a PID loop (evaluation.h): the objectives, Evaluate, the
// tuner's ObjectiveEvaluator and MATLAB-stepinfo metrics, continuous ones on
// an adaptive grid that follows the fastest live pole.

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "evaluation_internal.h"
#include "pidlab/evaluation/delayed_loop.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/evaluation/fast_objective.h"
#include "pidlab/optim/golden_section.h"

namespace pidlab::evaluation {
namespace {

using internal::kInf;
using internal::kNaN;
// Grid step as a fraction of the time constant 1/|p| of the fastest live pole.
constexpr double kGridFraction = 0.05;
// A mode is dead once e^{Re p * tau} < e^-36 (about 2e-16).
constexpr double kDeadExponent = -36.0;
constexpr long kMaxGridPoints = 2000000;

// Walks the continuous loop on a grid whose step follows the fastest pole
// still alive since the last excitation (t = 0 or a disturbance breakpoint).
// Steps are h0 * 2^j, so one matrix exponential per level is enough.
class AdaptiveWalker {
 public:
  AdaptiveWalker(const ContinuousClosedLoop<double>& loop, const Disturbance* disturbance,
                 const Stability& stability)
      : loop_(loop), disturbance_(disturbance), poles_(stability.poles) {
    // The setpoint filter's mode is the response's, not the loop's.
    if (loop.reference_filter_order) poles_.emplace_back(-loop.reference_filter_rate(), 0.0);
    double fastest = 0.0;
    for (const auto& p : poles_) fastest = std::max(fastest, std::abs(p));
    if (loop.exo_size == 2) fastest = std::max(fastest, ExoFrequency());
    h0_ = kGridFraction / std::max(fastest, 1e-12);
  }

  /// Calls visit(t, w) at t = 0 and every grid point up to t_end (included).
  /// Returns false if the grid would exceed kMaxGridPoints.
  bool Run(double t_end, const std::function<void(double, const Eigen::VectorXd&)>& visit) {
    Eigen::VectorXd w = loop_.w0;
    double t = 0.0, excited = 0.0;
    const bool piecewise = loop_.exo_size == 1 && disturbance_ != nullptr;
    const int ie = loop_.exo_index();
    visit(t, w);
    long points = 1;
    while (t < t_end) {
      double stop = t_end;
      double tb = kInf;
      if (piecewise) {
        tb = disturbance_->NextBreakpoint(t);
        stop = std::min(stop, tb);
      }
      const double h = StepAt(t - excited);
      if (t + h < stop - 1e-12 * std::max(1.0, stop)) {
        w = Phi(h) * w;
        t += h;
      } else {
        w = MatrixExp<double>(Eigen::MatrixXd(loop_.m * (stop - t))) * w;
        t = stop;
        if (piecewise && stop == tb) {
          w(ie) = disturbance_->Value(t);
          excited = t;
        }
      }
      visit(t, w);
      if (++points > kMaxGridPoints) return false;
    }
    return true;
  }

  /// Exact state at t0 + tau from w at t0 (no breakpoint in between).
  Eigen::VectorXd Propagate(const Eigen::VectorXd& w, double tau) const {
    return MatrixExp<double>(Eigen::MatrixXd(loop_.m * tau)) * w;
  }

 private:
  double ExoFrequency() const { return std::abs(loop_.m(loop_.exo_index(), loop_.exo_index() + 1)); }

  double StepAt(double tau) const {
    double fastest = 0.0;
    for (const auto& p : poles_)
      if (p.real() * tau > kDeadExponent) fastest = std::max(fastest, std::abs(p));
    if (loop_.exo_size == 2) fastest = std::max(fastest, ExoFrequency());
    if (fastest == 0.0) return h0_ * std::ldexp(1.0, 40);
    const int level = std::max(0, static_cast<int>(std::floor(std::log2(kGridFraction / fastest / h0_))));
    return h0_ * std::ldexp(1.0, std::min(level, 40));
  }

  const Eigen::MatrixXd& Phi(double h) {
    auto it = cache_.find(h);
    if (it == cache_.end()) it = cache_.emplace(h, MatrixExp<double>(Eigen::MatrixXd(loop_.m * h))).first;
    return it->second;
  }

  const ContinuousClosedLoop<double>& loop_;
  const Disturbance* disturbance_;
  std::vector<std::complex<double>> poles_;
  double h0_ = 0.0;
  std::map<double, Eigen::MatrixXd> cache_;
};

// Root of g on [a, b] with g(a), g(b) of opposite signs, by bisection.
double Bisect(const std::function<double(double)>& g, double a, double b) {
  double ga = g(a);
  for (int i = 0; i < 80 && b - a > 1e-15 * std::max(1.0, std::abs(b)); ++i) {
    const double mid = 0.5 * (a + b);
    const double gm = g(mid);
    if ((gm < 0.0) == (ga < 0.0)) {
      a = mid;
      ga = gm;
    } else {
      b = mid;
    }
  }
  return 0.5 * (a + b);
}

// The loop without its exosystem input: the undisturbed step response y1.
ContinuousClosedLoop<double> UndisturbedLoop(const ContinuousClosedLoop<double>& loop) {
  ContinuousClosedLoop<double> y1 = loop;
  if (loop.exo_size > 0) {
    const int size = loop.exo_index();
    y1.m = loop.m.topLeftCorner(size, size);
    y1.w0 = loop.w0.head(size);
    y1.exo_size = 0;
  }
  return y1;
}

// A response on the walker's grid (times ts, outputs ys, states ws), with
// exact values between grid points.
struct GridResponse {
  const ContinuousClosedLoop<double>& loop;
  const AdaptiveWalker& walker;
  std::vector<double> ts, ys;
  std::vector<Eigen::VectorXd> ws;

  /// y(t) for t at or after ts[i], propagated exactly from ws[i].
  double At(std::size_t i, double t) const { return loop.Output(walker.Propagate(ws[i], t - ts[i])); }
};

// First time y reaches `level` (a fraction of the final value yf) from the
// side of 0, refined by bisection; NaN if it never does.
double FirstCrossing(const GridResponse& r, double level, double yf) {
  for (std::size_t i = 0; i < r.ys.size(); ++i) {
    if ((r.ys[i] - level) * (yf > 0 ? 1 : -1) >= 0.0) {
      if (i == 0) return r.ts[0];
      return Bisect([&](double t) { return (r.At(i - 1, t) - level) * (yf > 0 ? 1 : -1); }, r.ts[i - 1],
                    r.ts[i]);
    }
  }
  return kNaN;
}

// The largest |y| on the grid, refined by golden-section search on the exact
// response over the neighbouring intervals.
void FindPeak(const GridResponse& r, double* peak, double* peak_t) {
  std::size_t ip = 0;
  for (std::size_t i = 1; i < r.ys.size(); ++i)
    if (std::abs(r.ys[i]) > std::abs(r.ys[ip])) ip = i;
  *peak = std::abs(r.ys[ip]);
  *peak_t = r.ts[ip];
  if (ip == 0 || ip + 1 >= r.ys.size()) return;
  auto f = [&](double t) { return std::abs(r.At(ip - 1, t)); };
  const double tp = optim::GoldenSectionArgMax(f, r.ts[ip - 1], r.ts[ip + 1], 100, [](double a, double b) {
    return !(b - a > 1e-15 * std::max(1.0, b));
  });
  const double yp = f(tp);
  if (yp > *peak) {
    *peak = yp;
    *peak_t = tp;
  }
}

// The 2 % settling time: the last exit from the band, refined on the exact
// response (0 if y never leaves it). False if y is still outside the band at
// the end of the grid.
bool SettlingTime(const GridResponse& r, double yf, double* settling_time_s) {
  const double band = 0.02 * std::abs(yf);
  std::size_t last_out = r.ys.size();
  for (std::size_t i = r.ys.size(); i-- > 0;) {
    if (std::abs(r.ys[i] - yf) > band) {
      last_out = i;
      break;
    }
  }
  if (last_out == r.ys.size()) {
    *settling_time_s = 0.0;
    return true;
  }
  if (last_out + 1 == r.ys.size()) return false;
  *settling_time_s = Bisect([&](double t) { return std::abs(r.At(last_out, t) - yf) - band; }, r.ts[last_out],
                            r.ts[last_out + 1]);
  return true;
}

}  // namespace

bool ParseObjectiveKind(const std::string& s, ObjectiveKind* kind) {
  if (s == "iae")
    *kind = ObjectiveKind::kIae;
  else if (s == "ise")
    *kind = ObjectiveKind::kIse;
  else if (s == "itae")
    *kind = ObjectiveKind::kItae;
  else if (s == "iae-continuous")
    *kind = ObjectiveKind::kIaeContinuous;
  else if (s == "load-iae")
    *kind = ObjectiveKind::kLoadIae;
  else if (s == "setpoint-load")
    *kind = ObjectiveKind::kSetpointLoad;
  else
    return false;
  return true;
}

std::string ToString(ObjectiveKind kind) {
  switch (kind) {
    case ObjectiveKind::kIae:
      return "iae";
    case ObjectiveKind::kIse:
      return "ise";
    case ObjectiveKind::kItae:
      return "itae";
    case ObjectiveKind::kIaeContinuous:
      return "iae-continuous";
    case ObjectiveKind::kLoadIae:
      return "load-iae";
    case ObjectiveKind::kSetpointLoad:
      return "setpoint-load";
  }
  return "iae";
}

double ObjectiveFromSamples(ObjectiveKind kind, const std::vector<double>& y, double ts, double reference) {
  double sum = 0.0;
  for (std::size_t m = 0; m < y.size(); ++m) {
    const double e = reference - y[m];
    switch (kind) {
      case ObjectiveKind::kIae:
        sum += std::abs(e);
        break;
      case ObjectiveKind::kIse:
        sum += e * e;
        break;
      case ObjectiveKind::kItae:
        sum += static_cast<double>(m) * ts * std::abs(e);
        break;
      case ObjectiveKind::kIaeContinuous:
        throw std::logic_error("iae-continuous is not a sample sum");
      case ObjectiveKind::kLoadIae:
      case ObjectiveKind::kSetpointLoad:
        throw std::logic_error(ToString(kind) + " is not a sum over one response");
    }
  }
  return std::isfinite(sum) ? sum : kInf;
}

double ContinuousFinalValue(const ContinuousClosedLoop<double>& loop) {
  const std::vector<int> live = LiveLoopStates(loop);
  const int n = static_cast<int>(live.size());
  // At rest the setpoint filter's r_f is r: its column joins r's.
  const int ir = loop.reference_index(), is = loop.setpoint_index();
  Eigen::VectorXd rhs(n);
  for (int i = 0; i < n; ++i) rhs(i) = -loop.m(live[i], ir) - (is != ir ? loop.m(live[i], is) : 0.0);
  const Eigen::VectorXd w = LiveLoopMatrix(loop).partialPivLu().solve(rhs);
  return loop.reference * loop.c.dot(w.head(loop.plant_order));  // the plant's states come first
}

StepInfo ContinuousStepInfo(const ContinuousClosedLoop<double>& loop, const Stability& stability) {
  StepInfo info;
  if (!stability.stable) {
    info.note = "unstable loop: no step metrics";
    return info;
  }
  const ContinuousClosedLoop<double> y1 = UndisturbedLoop(loop);
  const double yf = ContinuousFinalValue(y1);
  info.final_value = yf;
  // Walk until the slowest mode has died out.
  double slowest = kInf;
  for (const auto& p : stability.poles) slowest = std::min(slowest, -p.real());
  if (y1.reference_filter_order) slowest = std::min(slowest, y1.reference_filter_rate());
  const double t_end = -kDeadExponent / slowest;
  AdaptiveWalker walker(y1, nullptr, stability);
  GridResponse response{y1, walker, {}, {}, {}};
  const bool complete = walker.Run(t_end, [&](double t, const Eigen::VectorXd& w) {
    response.ts.push_back(t);
    response.ys.push_back(y1.Output(w));
    response.ws.push_back(w);
  });
  if (!complete) {
    info.note = "response too slow to settle within the grid budget";
    return info;
  }
  if (!(std::abs(yf) > 1e-12)) {
    info.note = "final value is zero: stepinfo is undefined";
    return info;
  }
  info.rise_time_s = FirstCrossing(response, 0.9 * yf, yf) - FirstCrossing(response, 0.1 * yf, yf);
  FindPeak(response, &info.peak, &info.peak_time_s);
  info.overshoot_pct = std::max(0.0, 100.0 * (info.peak - std::abs(yf)) / std::abs(yf));
  if (!SettlingTime(response, yf, &info.settling_time_s)) {
    info.note = "response not settled at the end of the grid";
    return info;
  }
  info.valid = std::isfinite(info.rise_time_s);
  if (!info.valid) info.note = "response never reaches 90 % of its final value";
  return info;
}

double ContinuousIntegralAbsError(const ContinuousClosedLoop<double>& loop, const Disturbance& disturbance,
                                  const Stability& stability, double horizon_s) {
  if (!stability.stable) return kInf;
  AdaptiveWalker walker(loop, &disturbance, stability);
  double sum = 0.0, t_prev = 0.0, e_prev = 0.0;
  bool first = true;
  const bool ok = walker.Run(horizon_s, [&](double t, const Eigen::VectorXd& w) {
    const double e = loop.reference - loop.Output(w);
    if (!first) {
      const double h = t - t_prev;
      if ((e > 0) == (e_prev > 0) || e == 0.0 || e_prev == 0.0) {
        sum += 0.5 * h * (std::abs(e) + std::abs(e_prev));
      } else {  // a sign change inside: integrate the two triangles
        const double f = std::abs(e_prev) / (std::abs(e_prev) + std::abs(e));
        sum += 0.5 * h * (f * std::abs(e_prev) + (1.0 - f) * std::abs(e));
      }
    }
    first = false;
    t_prev = t;
    e_prev = e;
  });
  return ok ? sum : kNaN;
}

StepInfo SampledStepInfo(const std::vector<double>& t, const std::vector<double>& y, double yf) {
  StepInfo info;
  info.final_value = yf;
  if (y.size() < 2 || !(std::abs(yf) > 1e-12)) {
    info.note = "final value is zero or no samples: stepinfo is undefined";
    return info;
  }
  const double sgn = yf > 0 ? 1.0 : -1.0;
  auto crossing = [&](double level) {
    for (std::size_t i = 0; i < y.size(); ++i)
      if ((y[i] - level) * sgn >= 0.0) {
        if (i == 0) return t[0];
        return t[i - 1] + (t[i] - t[i - 1]) * (level - y[i - 1]) / (y[i] - y[i - 1]);
      }
    return kNaN;
  };
  info.rise_time_s = crossing(0.9 * yf) - crossing(0.1 * yf);
  std::size_t ip = 0;
  for (std::size_t i = 1; i < y.size(); ++i)
    if (std::abs(y[i]) > std::abs(y[ip])) ip = i;
  info.peak = std::abs(y[ip]);
  info.peak_time_s = t[ip];
  info.overshoot_pct = std::max(0.0, 100.0 * (info.peak - std::abs(yf)) / std::abs(yf));
  const double band = 0.02 * std::abs(yf);
  std::size_t last_out = y.size();
  for (std::size_t i = y.size(); i-- > 0;)
    if (std::abs(y[i] - yf) > band) {
      last_out = i;
      break;
    }
  if (last_out == y.size()) {
    info.settling_time_s = 0.0;
  } else if (last_out + 1 == y.size()) {
    info.note = "response not settled within the horizon";
    return info;
  } else {
    const double a = std::abs(y[last_out] - yf) - band, b = std::abs(y[last_out + 1] - yf) - band;
    info.settling_time_s = t[last_out] + (t[last_out + 1] - t[last_out]) * a / (a - b);
  }
  info.valid = std::isfinite(info.rise_time_s);
  if (!info.valid) info.note = "response never reaches 90 % of its final value within the horizon";
  return info;
}

double Evaluation::Objective(ObjectiveKind kind, double load_weight) const {
  switch (kind) {
    case ObjectiveKind::kLoadIae:
      return load_iae;
    case ObjectiveKind::kSetpointLoad:
      return load_weight == 0.0 ? iae : iae + load_weight * load_iae;
    case ObjectiveKind::kIae:
      return iae;
    case ObjectiveKind::kIse:
      return ise;
    case ObjectiveKind::kItae:
      return itae;
    case ObjectiveKind::kIaeContinuous:
      return iae_continuous;
  }
  return iae;
}

DisturbanceOptions UnitLoadStep() {
  DisturbanceOptions d;
  d.kind = DisturbanceKind::kStep;
  d.amplitude = 1.0;
  d.step_time_s = 0.0;
  return d;
}

namespace internal {

double LoadIaeOfStableLoop(const StateSpace& realization, const DiscretePlant* discrete,
                           const PidGains& gains, const LoopOptions& options, const Disturbance& step) {
  thread_local std::vector<double> y;
  if (options.loop == LoopKind::kContinuous) {
    ContinuousClosedLoop<double> loop;
    if (!BuildContinuousClosedLoop<double>(realization, gains, step, &loop, 0.0).ok()) return kInf;
    SampleContinuousLoop<double>(loop, step, options.sample_time_s, options.NumSamples(), &y);
  } else {
    PidOptions pid = options.Pid();
    if (RunSampledLoop<double>(*discrete, gains, pid, step, options.TotalSteps(), options.StepsPerSample(),
                               &y, nullptr, 0.0) == PidStatus::kInvalidInput)
      return kInf;
  }
  double sum = 0.0;
  for (double v : y) sum += std::abs(v);
  return std::isfinite(sum) ? sum : kInf;
}

}  // namespace internal

double LoadIntegralAbsError(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options) {
  // A dead time the loop cannot take (the continuous loop's) has no load
  // response here: NaN, not a number of the undelayed plant.
  if (!DelayIsValid(plant, options, "delay").ok()) return std::numeric_limits<double>::quiet_NaN();
  const PidGains gains = LoopGains(typed_gains, options);
  if (options.loop == LoopKind::kContinuous && plant.delay_s > 0.0) {
    Stability s;
    if (!DelayedLoopIsRetarded(plant.tf, gains).ok()) return std::numeric_limits<double>::quiet_NaN();
    if (!internal::DelayedStability(plant, gains, &s).ok() || !s.stable) return kInf;
    return internal::DelayedLoadIae(plant, gains, options);
  }
  const StateSpace realization = Realize(plant.tf);
  ContinuousClosedLoop<double> loop;
  if (!BuildContinuousClosedLoop<double>(realization, gains, Disturbance(DisturbanceOptions{}), &loop).ok())
    return kInf;
  std::unique_ptr<DiscretePlant> discrete;
  if (options.loop == LoopKind::kSampled) {
    discrete = std::make_unique<DiscretePlant>(SampledPlant(plant, options.dt_s));
    PidOptions pid = options.Pid();
    if (!SampledLoopIsStable(*discrete, gains, pid, options.stability_margin)) return kInf;
  } else if (!ContinuousStability(loop, options.stability_margin).stable) {
    return kInf;
  }
  return internal::LoadIaeOfStableLoop(realization, discrete.get(), gains, options,
                                       Disturbance(UnitLoadStep()));
}

ObjectiveEvaluator::ObjectiveEvaluator(const Plant& plant, const LoopOptions& options, ObjectiveKind kind,
                                       SampledRunner runner, double load_weight)
    : plant_(plant),
      options_(options),
      kind_(kind),
      load_weight_(load_weight),
      disturbance_(options.disturbance),
      runner_(std::move(runner)) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
  if (!(load_weight >= 0.0) || !std::isfinite(load_weight))
    throw std::invalid_argument("load weight " + std::to_string(load_weight) + " must be finite and >= 0");
  const bool load = kind == ObjectiveKind::kLoadIae || kind == ObjectiveKind::kSetpointLoad;
  if (load && runner_)
    throw std::invalid_argument(ToString(kind) + " runs the loop in process, not over another runner");
  if (load && plant.nonlinear)
    throw std::invalid_argument(ToString(kind) + " needs a linear plant, not " + plant.name);
  if (!plant.tf.IsValid(&error)) throw std::invalid_argument(error);
  if (const Status st = DelayIsValid(plant, options, "delay"); !st.ok())
    throw std::invalid_argument(st.message());
  realization_ = Realize(plant.tf);
  if (plant.nonlinear && options.loop != LoopKind::kSampled)
    throw std::invalid_argument("plant " + plant.name +
                                " is nonlinear: tune it on the sampled loop (--loop sampled)");
  if (options.loop == LoopKind::kSampled) {
    options_.pid = PidOptionsAt(options_.pid, options.dt_s);
    discrete_ = std::make_unique<DiscretePlant>(SampledPlant(plant, options.dt_s));
  }
  if (FastContinuousObjective::CoversPlant(plant, options_, kind_))
    fast_ = std::make_shared<const FastContinuousObjective>(plant.tf, realization_, options_, kind_);
}

double GeneralContinuousObjective(const StateSpace& realization, const Disturbance& disturbance,
                                  const LoopOptions& options, ObjectiveKind kind, const PidGains& gains) {
  thread_local std::vector<double> y;  // reused: no allocation per evaluation
  ContinuousClosedLoop<double> loop;
  if (!BuildContinuousClosedLoop<double>(realization, gains, disturbance, &loop, options.reference,
                                         SetpointWeightsOf(options.pid))
           .ok())
    return kInf;
  const Stability s = ContinuousStability(loop, options.stability_margin);
  if (!s.stable) return kInf;
  if (kind == ObjectiveKind::kIaeContinuous)
    return ContinuousIntegralAbsError(loop, disturbance, s, options.horizon_s);
  SampleContinuousLoop<double>(loop, disturbance, options.sample_time_s, options.NumSamples(), &y);
  return ObjectiveFromSamples(kind, y, options.sample_time_s, options.reference);
}

double ObjectiveEvaluator::LoadIae(const PidGains& gains) const {
  return internal::LoadIaeOfStableLoop(realization_, discrete_.get(), gains, options_, load_step_);
}

double ObjectiveEvaluator::operator()(const PidGains& typed_gains) const {
  ++evaluations_;
  thread_local std::vector<double> y;  // reused: no allocation per evaluation
  const PidGains gains = LoopGains(typed_gains, options_);
  if (!GainsAreValid(gains, nullptr)) return kInf;
  if (options_.loop == LoopKind::kContinuous && plant_.delay_s > 0.0)  // the exact path, not the fast one
    return internal::DelayedContinuousObjective(plant_, options_, kind_, load_weight_, gains);
  const double ts = options_.sample_time_s;
  if (kind_ == ObjectiveKind::kLoadIae || kind_ == ObjectiveKind::kSetpointLoad) {
    // The poles do not depend on r or n: one stability test for both responses.
    bool stable = false;
    if (options_.loop == LoopKind::kContinuous) {
      ContinuousClosedLoop<double> loop;
      stable = BuildContinuousClosedLoop<double>(realization_, gains, disturbance_, &loop, options_.reference,
                                                 SetpointWeightsOf(options_.pid))
                   .ok() &&
               ContinuousStability(loop, options_.stability_margin).stable;
      if (stable && kind_ == ObjectiveKind::kSetpointLoad)
        SampleContinuousLoop<double>(loop, disturbance_, ts, options_.NumSamples(), &y);
    } else {
      stable = SampledLoopIsStable(*discrete_, gains, options_.pid, options_.stability_margin);
      if (stable && kind_ == ObjectiveKind::kSetpointLoad &&
          RunSampledLoop<double>(*discrete_, gains, options_.pid, disturbance_, options_.TotalSteps(),
                                 options_.StepsPerSample(), &y, nullptr,
                                 options_.reference) == PidStatus::kInvalidInput)
        return kInf;
    }
    if (!stable) return kInf;
    const double load = LoadIae(gains);
    if (kind_ == ObjectiveKind::kLoadIae) return load;
    const double setpoint = ObjectiveFromSamples(ObjectiveKind::kIae, y, ts, options_.reference);
    const double sum = load_weight_ == 0.0 ? setpoint : setpoint + load_weight_ * load;
    return std::isfinite(sum) ? sum : kInf;
  }
  if (fast_ && gains.tf == 0.0) return (*fast_)(gains);
  if (options_.loop == LoopKind::kContinuous)
    return GeneralContinuousObjective(realization_, disturbance_, options_, kind_, gains);
  if (!SampledLoopIsStable(*discrete_, gains, options_.pid, options_.stability_margin)) return kInf;
  if (runner_ || kind_ == ObjectiveKind::kIaeContinuous || plant_.nonlinear) {
    if (plant_.nonlinear && !runner_) {
      RunSampledLoopInProcess(plant_, gains, options_, options_.disturbance, &y, nullptr);
    } else if (runner_) {
      if (const Status ran = runner_(plant_, gains, options_, options_.disturbance, &y, nullptr); !ran.ok())
        throw RunnerFailure("sampled-loop runner failed: " + ran.message());
    } else if (RunSampledLoop<double>(*discrete_, gains, options_.pid, disturbance_, options_.TotalSteps(), 1,
                                      &y, nullptr, options_.reference) == PidStatus::kInvalidInput) {
      return kInf;
    }
    if (kind_ != ObjectiveKind::kIaeContinuous) {
      std::vector<double> samples;
      const int per = options_.StepsPerSample();
      for (std::size_t k = 0; k < y.size(); k += static_cast<std::size_t>(per)) samples.push_back(y[k]);
      return ObjectiveFromSamples(kind_, samples, ts, options_.reference);
    }
    double integral = 0.0;
    for (std::size_t k = 1; k < y.size(); ++k)
      integral += 0.5 * options_.dt_s *
                  (std::abs(options_.reference - y[k]) + std::abs(options_.reference - y[k - 1]));
    return integral;
  }
  if (RunSampledLoop<double>(*discrete_, gains, options_.pid, disturbance_, options_.TotalSteps(),
                             options_.StepsPerSample(), &y, nullptr,
                             options_.reference) == PidStatus::kInvalidInput)
    return kInf;
  return ObjectiveFromSamples(kind_, y, ts, options_.reference);
}

}  // namespace pidlab::evaluation
