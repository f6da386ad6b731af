// Loop analysis (loop_analysis.h): the closed-loop poles and the controller's
// zeros, then the margins (loop_margins.cc) and the peaks of S, T and C S
// (loop_response.cc) over the loop's frequency response (loop_response.h).

#include "pidlab/analysis/loop_analysis.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>

#include "loop_response.h"

namespace pidlab::analysis {
namespace {

using evaluation::frequency::OpenLoopFrequencies;
using loop_internal::cd;
using loop_internal::ContinuousResponse;
using loop_internal::CountEncirclements;
using loop_internal::Crossings;
using loop_internal::DelayGrid;
using loop_internal::Eval;
using loop_internal::FindCrossings;
using loop_internal::Grid;
using loop_internal::kInf;
using loop_internal::kNaN;
using loop_internal::kPi;
using loop_internal::Mul;
using loop_internal::Peak;
using loop_internal::PeakOnGrid;
using loop_internal::Point;
using loop_internal::Response;
using loop_internal::SampledResponse;
using loop_internal::SetMargins;
using loop_internal::SlowestTimeConstant;
using loop_internal::SpecialFrequencies;

// s-plane image of a pole or zero of the loop kind.
std::vector<cd> ToS(const std::vector<cd>& roots, evaluation::LoopKind kind, double dt) {
  if (kind == evaluation::LoopKind::kContinuous) return roots;
  std::vector<cd> out;
  for (const cd& z : roots)
    if (std::abs(z) > 1e-300) out.push_back(std::log(z) / dt);
  return out;
}

std::vector<Cancellation> FindCancellations(const std::vector<cd>& s_poles, const std::vector<cd>& s_zeros,
                                            double tolerance) {
  std::vector<Cancellation> out;
  for (const cd& q : s_zeros) {
    if (!(std::abs(q) > 0.0)) continue;
    for (const cd& p : s_poles) {
      const double d = std::abs(p - q) / std::abs(q);
      if (d <= tolerance) out.push_back({p, q, d});
    }
  }
  return out;
}

// A dead time the analysis can use: finite and >= 0; in the continuous loop
// any (e^(-jwL) exactly, stability by the Nyquist count), in the sampled loop
// what its stored inputs allow (evaluation::DelayIsValid).
bool DelayIsValid(const Plant& plant, const evaluation::LoopOptions& options, std::string* error) {
  std::ostringstream os;
  if (!(plant.delay_s >= 0.0) || !std::isfinite(plant.delay_s))
    os << "dead time " << plant.delay_s << " s must be finite and >= 0";
  else if (options.loop != evaluation::LoopKind::kContinuous)  // the stored inputs' bound, a linear plant
    if (const Status st = evaluation::DelayIsValid(plant, options, "delay"); !st.ok())
      os << st.message();
    else
      return true;
  else
    return true;
  if (error) *error = os.str();
  return false;
}

// The inputs AnalyzeLoop accepts, and the loop gains *g of typed_gains.
bool CheckAnalysisInputs(const Plant& plant, const PidGains& typed_gains,
                         const evaluation::LoopOptions& options, const LoopAnalysisOptions& ao, PidGains* g,
                         std::string* error) {
  if (!GainsAreValid(typed_gains, error) || !options.IsValid(error) || !ao.IsValid(error) ||
      !plant.tf.IsValid(error) || !DelayIsValid(plant, options, error))
    return false;
  if (plant.tf.RelativeDegree() < 1) {
    if (error) *error = "plant " + plant.tf.ToString() + " must be strictly proper";
    return false;
  }
  *g = evaluation::LoopGains(typed_gains, options);
  return GainsAreValid(*g, error);
}

const char* AnalysisMethod(bool continuous) {
  return continuous ? "log grid + closed-loop/open-loop pole and zero frequencies, golden-section "
                      "refinement of every local maximum, Bruinsma-Steinbuch Hamiltonian iteration"
                    : "log grid up to pi/dt + closed-loop pole frequencies, golden-section refinement "
                      "of every local maximum";
}

// The closed loop's poles and the controller's zeros (s-plane), the
// frequencies a narrow feature can sit at, and the loop's response.
struct LoopModel {
  bool stable = false;
  std::vector<cd> s_poles, s_zeros;
  std::vector<double> special;
  std::unique_ptr<Response> response;
};

bool ContinuousModel(const Plant& plant, const PidGains& g, const evaluation::LoopOptions& options,
                     LoopModel* m, std::string* error) {
  evaluation::ContinuousClosedLoop<double> loop;
  if (const Status st = evaluation::BuildContinuousClosedLoop<double>(
          Realize(plant.tf), g, Disturbance(DisturbanceOptions{}), &loop);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  const evaluation::Stability st = evaluation::ContinuousStability(loop, options.stability_margin);
  m->stable = st.stable;
  m->s_poles = st.poles;
  auto r = std::make_unique<ContinuousResponse>(plant.tf, g);
  m->s_zeros = PolynomialRoots(r->controller_num());
  m->special = SpecialFrequencies(m->s_poles);
  for (const auto& v : {PolynomialRoots(r->a()), PolynomialRoots(r->b())})
    for (double w : SpecialFrequencies(v)) m->special.push_back(w);
  m->response.reset(r.release());
  return true;
}

void SampledModel(const Plant& plant, const PidGains& g, const evaluation::LoopOptions& options,
                  const PidOptions& pid, LoopModel* m) {
  const DiscretePlant discrete = evaluation::SampledPlant(plant, options.dt_s);
  const evaluation::Stability st = evaluation::SampledStability(discrete, g, pid, options.stability_margin);
  m->stable = st.stable;
  m->s_poles = ToS(st.poles, evaluation::LoopKind::kSampled, options.dt_s);
  auto r = std::make_unique<SampledResponse>(discrete, g, pid);
  m->s_zeros = ToS(PolynomialRoots(r->controller_num()), evaluation::LoopKind::kSampled, options.dt_s);
  m->special = SpecialFrequencies(m->s_poles);
  m->response.reset(r.release());
}

void MarkUnstable(LoopAnalysis* a) {
  a->gain_margin_note = a->phase_margin_note = a->noise_gain_note = "unstable loop: no margins or peaks";
  a->gain_margin = a->phase_margin_deg = a->delay_margin_s = kNaN;
}

// The analysis grid: 1e-3 x the slowest to 1e3 x the fastest special
// frequency (sampled: up to pi/dt), with the special frequencies.
std::vector<double> AnalysisGrid(const std::vector<double>& special, const evaluation::LoopOptions& options,
                                 const LoopAnalysisOptions& ao) {
  double lo = kInf, hi = 0.0;
  for (double w : special) {
    if (!(w > 0.0) || !std::isfinite(w)) continue;
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  double w_lo = 1e-3 * lo, w_hi = 1e3 * hi;
  if (options.loop != evaluation::LoopKind::kContinuous) {
    w_hi = kPi / options.dt_s;
    w_lo = std::min(w_lo, 1e-3 * w_hi);
  }
  return Grid(w_lo, w_hi, ao.points_per_decade, special);
}

// Raises the grid's peak *value (at *w) of the continuous loop to its limits
// w -> 0 and w -> inf, then to the Bruinsma-Steinbuch norm when asked.
void RaiseContinuousPeak(const ContinuousResponse& r, Peak which, const LoopAnalysisOptions& ao,
                         double* value, double* w) {
  const Polynomial& x = which == Peak::kS ? r.b() : (which == Peak::kT ? r.a() : r.c());
  const double at0 = std::abs(Eval(x, 0.0) / Eval(r.p(), 0.0));
  if (at0 > *value) {
    *value = at0;
    *w = 0.0;
  }
  const double at_inf = r.AtInfinity(x);
  if (at_inf > *value) {
    *value = at_inf;
    *w = kInf;
  }
  if (std::isfinite(*value) && ao.hamiltonian_check && !(r.delay() > 0.0)) {
    double wp = *w;
    const double h = HinfNormBruinsmaSteinbuch(x, r.p(), *value, *w, 1e-7, &wp);
    if (h > *value * (1.0 + 1e-6)) {
      *value = h;
      *w = wp;
    }
  }
}

// Ms, Mt and the noise gain with their frequencies: peaks on the grid, then
// the limits w -> 0 and w -> inf (continuous).
void SetPeaks(const Response& response, const std::vector<double>& w, const std::vector<Point>& pts,
              bool continuous, const LoopAnalysisOptions& ao, LoopAnalysis* a) {
  struct Target {
    Peak which;
    double* value;
    double* w;
  };
  const Target targets[] = {{Peak::kS, &a->ms, &a->ms_rad_s},
                            {Peak::kT, &a->mt, &a->mt_rad_s},
                            {Peak::kCs, &a->noise_gain, &a->noise_gain_rad_s}};
  for (const Target& t : targets) {
    *t.value = PeakOnGrid(response, w, pts, t.which, ao.refine_peaks, -kInf, t.w);
    if (continuous)
      RaiseContinuousPeak(static_cast<const ContinuousResponse&>(response), t.which, ao, t.value, t.w);
  }
}

// The stable delayed loop's slowest time constant -1/alpha from its spectral
// abscissa, or NaN with a note saying why not.
bool SetDelayedTimeConstant(const Plant& plant, const PidGains& g, const LoopAnalysisOptions& ao,
                            LoopAnalysis* a, std::string* error) {
  if (!ao.delayed_time_constant) {
    a->time_constant_note = "dead time: the spectral abscissa was not asked for";
    return true;
  }
  evaluation::SpectralAbscissa sa;
  if (const Status st =
          evaluation::ContinuousSpectralAbscissa(plant.tf, g, plant.delay_s, ao.points_per_decade, &sa);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  if (sa.found && sa.alpha < 0.0) {
    a->slowest_time_constant_s = -1.0 / sa.alpha;
    a->time_constant_note.clear();
  } else {
    a->time_constant_note = sa.found ? "dead time: spectral abscissa >= 0" : "dead time: " + sa.note;
  }
  return true;
}

// The continuous loop with dead time: the open-loop features and 1/L on the
// analysis grid, e^{-jwL} resolved below the band's top, stability by the
// Nyquist count, crossovers within the band, peaks without the Hamiltonian
// iteration (which needs a rational loop).
bool AnalyzeDelayedLoop(const Plant& plant, const PidGains& g, const evaluation::LoopOptions& options,
                        const LoopAnalysisOptions& ao, LoopAnalysis* a, std::string* error) {
  a->delay_s = plant.delay_s;
  a->method =
      "log grid + open-loop pole and zero frequencies, points every pi/16 of e^(-jwL) up to where |L| < "
      "0.01 for good, golden-section refinement of every local maximum (no Hamiltonian iteration "
      "with dead time); the slowest time constant from the spectral abscissa (Nyquist counts on shifted "
      "lines, bisection, Newton)";
  a->time_constant_note = "dead time: unstable loop, no spectral abscissa";
  const ContinuousResponse r(plant.tf, g, plant.delay_s);
  std::vector<double> w;
  std::vector<Point> pts;
  double w_top = 0.0;
  if (const Status st = DelayGrid(r, AnalysisGrid(OpenLoopFrequencies(r), options, ao), &w, &pts, &w_top);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  const NyquistCount n = CountEncirclements(r, w, pts);
  a->stable = n.stable;
  a->stability_note = n.note;
  if (!a->stable) {
    MarkUnstable(a);
    return true;
  }
  if (!SetDelayedTimeConstant(plant, g, ao, a, error)) return false;
  Crossings c = FindCrossings(r, w, pts);
  for (auto* list : {&c.gain, &c.phase})
    list->erase(std::remove_if(list->begin(), list->end(), [&](double x) { return x > w_top; }), list->end());
  SetMargins(r, c, a);
  SetPeaks(r, w, pts, true, ao, a);
  if (std::isinf(a->noise_gain))
    a->noise_gain_note = g.kd != 0.0 && !(g.tf > 0.0) ? "ideal derivative: unbounded" : "unbounded";
  return true;
}

}  // namespace

namespace loop_internal {

double SlowestTimeConstant(const std::vector<cd>& s_poles) {
  double slowest = kInf;
  for (const cd& p : s_poles) slowest = std::min(slowest, std::abs(p.real()));
  return s_poles.empty() ? kNaN : 1.0 / slowest;
}

}  // namespace loop_internal

bool LoopAnalysisOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(points_per_decade > 0.0) || !(points_per_decade <= 10000.0))
    os << "points per decade " << points_per_decade << " must be in (0, 10000]";
  else if (!(cancellation_tolerance >= 0.0) || !(cancellation_tolerance < 1.0))
    os << "cancellation tolerance " << cancellation_tolerance << " must be in [0, 1)";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

namespace {

// AnalyzeLoop() with the refusal's message in *error.
bool AnalyzeLoopOrExplain(const Plant& plant, const PidGains& typed_gains,
                          const evaluation::LoopOptions& options, const LoopAnalysisOptions& ao,
                          LoopAnalysis* out, std::string* error) {
  PidGains g;
  if (!CheckAnalysisInputs(plant, typed_gains, options, ao, &g, error)) return false;
  *out = LoopAnalysis();
  LoopAnalysis& a = *out;
  a.loop = options.loop;
  const bool continuous = options.loop == evaluation::LoopKind::kContinuous;
  // The sampled loop's dead time is in its plant (stored inputs, eigenvalues).
  if (continuous && plant.delay_s > 0.0) return AnalyzeDelayedLoop(plant, g, options, ao, &a, error);
  a.method = AnalysisMethod(continuous);
  const PidOptions pid = options.Pid();
  LoopModel m;
  if (continuous) {
    if (!ContinuousModel(plant, g, options, &m, error)) return false;
  } else {
    SampledModel(plant, g, options, pid, &m);
  }
  a.stable = m.stable;
  a.slowest_time_constant_s = SlowestTimeConstant(m.s_poles);
  a.cancellations = FindCancellations(m.s_poles, m.s_zeros, ao.cancellation_tolerance);
  if (!a.stable) {
    MarkUnstable(&a);
    return true;
  }
  const std::vector<double> w = AnalysisGrid(m.special, options, ao);
  std::vector<Point> pts(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) pts[i] = m.response->At(w[i]);
  SetMargins(*m.response, FindCrossings(*m.response, w, pts), &a);
  SetPeaks(*m.response, w, pts, continuous, ao, &a);
  if (std::isinf(a.noise_gain)) {
    a.noise_gain_note = g.kd != 0.0 && !(g.tf > 0.0) ? "ideal derivative: unbounded" : "unbounded";
  }
  return true;
}

}  // namespace

namespace {

// The last analyses of this thread, by their inputs. A served evaluation
// asks for the same loop's analysis three times (its time scale, the
// figure's frame and the result), each at another horizon: the analysis
// reads neither the horizon nor the sample time, and every other input is in
// the key, compared bit for bit, so a hit is the answer a new analysis gives.
// Only valid options of a linear plant without an uncertainty model are kept.
struct AnalysisMemo {
  struct Entry {
    std::string plant;
    std::vector<double> key;
    Status status;
    LoopAnalysis result;
  };
  static constexpr std::size_t kEntries = 4;
  std::vector<Entry> entries;  // the newest last
};

// A field added here must join the key below.
static_assert(sizeof(PidGains) == 4 * sizeof(double));
static_assert(sizeof(LoopAnalysisOptions) == 3 * 8 + 8);

std::vector<double> AnalysisKey(const Plant& plant, const PidGains& g, const evaluation::LoopOptions& o,
                                const LoopAnalysisOptions& ao) {
  evaluation::LoopOptions timeless = o;  // the analysis reads neither
  timeless.horizon_s = 0.0;
  timeless.sample_time_s = 0.0;
  std::vector<double> k = evaluation::LoopOptionsKey(timeless);
  k.insert(k.end(), {static_cast<double>(plant.tf.num.size()), plant.delay_s, g.kp, g.ki, g.kd, g.tf,
                     ao.points_per_decade, ao.refine_peaks ? 1.0 : 0.0, ao.hamiltonian_check ? 1.0 : 0.0,
                     ao.cancellation_tolerance, ao.delayed_time_constant ? 1.0 : 0.0});
  k.insert(k.end(), plant.tf.num.begin(), plant.tf.num.end());
  k.insert(k.end(), plant.tf.den.begin(), plant.tf.den.end());
  return k;
}

}  // namespace

Status AnalyzeLoop(const Plant& plant, const PidGains& typed_gains, const evaluation::LoopOptions& options,
                   const LoopAnalysisOptions& ao, LoopAnalysis* out) {
  const bool kept = !plant.nonlinear && !plant.model && options.IsValid(nullptr);
  thread_local AnalysisMemo memo;
  std::vector<double> key;
  if (kept) {
    key = AnalysisKey(plant, typed_gains, options, ao);
    for (const AnalysisMemo::Entry& e : memo.entries)
      if (e.plant == plant.name && e.key.size() == key.size() &&
          std::memcmp(e.key.data(), key.data(), key.size() * sizeof(double)) == 0) {
        *out = e.result;
        return e.status;
      }
  }
  std::string why;
  const Status status = AnalyzeLoopOrExplain(plant, typed_gains, options, ao, out, &why)
                            ? Status::Ok()
                            : Status::InvalidInput(why);
  if (kept) {
    if (memo.entries.size() == AnalysisMemo::kEntries) memo.entries.erase(memo.entries.begin());
    memo.entries.push_back({plant.name, std::move(key), status, *out});
  }
  return status;
}

Status CountNyquist(const Plant& plant, const PidGains& typed_gains, const evaluation::LoopOptions& options,
                    NyquistCount* count) {
  PidGains g;
  evaluation::LoopOptions continuous = options;
  continuous.loop = evaluation::LoopKind::kContinuous;
  const LoopAnalysisOptions ao;
  std::string why;
  if (!CheckAnalysisInputs(plant, typed_gains, continuous, ao, &g, &why)) return Status::InvalidInput(why);
  return evaluation::CountContinuousNyquist(plant.tf, g, plant.delay_s, ao.points_per_decade, count);
}

namespace {

// One point of the response from the loop's L = a/b and C S = c/(a + b).
LoopFrequencyPoint FrequencyPoint(double w, cd a, cd b, cd c) {
  const cd sum = a + b;
  LoopFrequencyPoint p;
  p.w_rad_s = w;
  p.l = b == 0.0 ? cd(kInf, 0.0) : a / b;
  p.s = b / sum;
  p.t = a / sum;
  p.cs = c / sum;
  return p;
}

}  // namespace

namespace {

// LoopFrequencyResponse() with the refusal's message in *error.
bool LoopFrequencyResponseOrExplain(const Plant& plant, const PidGains& typed_gains,
                                    const evaluation::LoopOptions& options,
                                    const std::vector<double>& w_rad_s,
                                    std::vector<LoopFrequencyPoint>* response, std::string* error) {
  if (!GainsAreValid(typed_gains, error) || !options.IsValid(error) || !plant.tf.IsValid(error) ||
      !DelayIsValid(plant, options, error))
    return false;
  const PidGains g = evaluation::LoopGains(typed_gains, options);
  if (!GainsAreValid(g, error)) return false;
  const bool sampled = options.loop == evaluation::LoopKind::kSampled;
  const double nyquist = sampled ? kPi / options.dt_s : kInf;
  for (const double w : w_rad_s)
    if (!(std::isfinite(w) && w > 0.0 && w <= nyquist)) {
      if (error)
        *error = "LoopFrequencyResponse: frequency " + std::to_string(w) + " is not finite and > 0" +
                 (sampled ? " and <= pi/dt" : "");
      return false;
    }
  response->clear();
  response->reserve(w_rad_s.size());
  if (sampled) {
    const SampledResponse r(evaluation::SampledPlant(plant, options.dt_s), g, options.Pid());
    for (const double w : w_rad_s) {
      const Point p = r.At(w);
      response->push_back(FrequencyPoint(w, p.a, p.b, p.c));
      response->back().delay_phase_rad = r.DelayPhase(w);
    }
    return true;
  }
  Polynomial c_num, c_den;
  ContinuousPidPolynomials(g, &c_num, &c_den);
  const Polynomial a = Mul(c_num, plant.tf.num), b = Mul(c_den, plant.tf.den), c = Mul(c_num, plant.tf.den);
  for (const double w : w_rad_s) {
    cd av = Eval(a, cd(0.0, w));
    if (plant.delay_s > 0.0) av *= std::polar(1.0, -w * plant.delay_s);
    response->push_back(FrequencyPoint(w, av, Eval(b, cd(0.0, w)), Eval(c, cd(0.0, w))));
    response->back().delay_phase_rad = -w * plant.delay_s;
  }
  return true;
}

}  // namespace

Status LoopFrequencyResponse(const Plant& plant, const PidGains& typed_gains,
                             const evaluation::LoopOptions& options, const std::vector<double>& w_rad_s,
                             std::vector<LoopFrequencyPoint>* response) {
  std::string why;
  if (!LoopFrequencyResponseOrExplain(plant, typed_gains, options, w_rad_s, response, &why))
    return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::analysis
