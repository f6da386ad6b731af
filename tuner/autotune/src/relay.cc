// The relay experiment and its estimates (relay.h).

#include "pidlab/autotune/relay.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace pidlab::autotune {
namespace {

constexpr double kPi = 3.14159265358979323846;
// How far the T of the two half periods may differ, relative, for the
// extremes' closed forms (FopdtFromCycle) to be used.
constexpr double kHalfPeriodAgreement = 0.02;

// Student's t at 97.5 % for n - 1 degrees of freedom (n = 2..10), else 1.96.
double T975(int n) {
  static const double t[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262};
  return n >= 2 && n <= 10 ? t[n - 2] : 1.96;
}

// Mean and 95 % half width of values.
void MeanInterval(const std::vector<double>& v, double* mean, double* half_width) {
  double m = 0.0;
  for (double x : v) m += x;
  m /= static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - m) * (x - m);
  const int n = static_cast<int>(v.size());
  *mean = m;
  *half_width = n > 1 ? T975(n) * std::sqrt(ss / (n - 1)) / std::sqrt(static_cast<double>(n)) : 0.0;
}

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

bool RelayOptions::IsValid(std::string* error) const {
  std::string e;
  if (!std::isfinite(setpoint))
    e = "setpoint " + Number(setpoint) + " must be finite";
  else if (!std::isfinite(u0))
    e = "u0 " + Number(u0) + " must be finite";
  else if (!(d_high > 0.0) || !std::isfinite(d_high))
    e = "relay amplitude d_high " + Number(d_high) + " must be > 0 and finite";
  else if (!(d_low > 0.0) || !std::isfinite(d_low))
    e = "relay amplitude d_low " + Number(d_low) + " must be > 0 and finite";
  else if (!(hysteresis >= 0.0) || !std::isfinite(hysteresis))
    e = "hysteresis " + Number(hysteresis) + " must be >= 0 and finite";
  else if (settled_cycles < 2)
    e = "settled cycles " + std::to_string(settled_cycles) + " must be at least 2";
  else if (!(tolerance > 0.0 && tolerance < 1.0))
    e = "tolerance " + Number(tolerance) + " must be in (0, 1)";
  else if (!(sample_period_s >= 0.0) || !std::isfinite(sample_period_s))
    e = "sample period " + Number(sample_period_s) + " s must be >= 0 and finite";
  if (e.empty()) return true;
  if (error) *error = e;
  return false;
}

RelayTuner BareRelay(const RelayOptions& o, double dt_s) {
  RelayTuneOptions t;
  t.hold_s = 0.0;
  t.u0 = o.u0;
  t.amplitude = 0.5 * (o.d_high + o.d_low);
  t.bias = 0.5 * (o.d_high - o.d_low);
  t.hysteresis = o.hysteresis;
  t.settled_cycles = o.settled_cycles;
  t.tolerance = o.tolerance;
  PidOptions pid;
  pid.dt_s = dt_s;
  return RelayTuner(t, PidGains{}, pid);
}

RelayEstimates EstimateBare(const RelayOptions& o, const RelayTuner& relay) {
  return EstimateFromCycles(o, relay.cycles(), relay.phase() == RelayPhase::kDone, 0.0);
}

namespace {

// Which fit the estimates take (EstimateFromCycles).
enum class Fit { kSampled, kSymmetric, kIntegrating, kTimes, kExtremes };

Status FitCycle(const RelayOptions& o, const RelayCycle& c, Fit fit, double delay_s, FopdtModel* m) {
  if (fit == Fit::kSampled) return SampledFopdtFromCycle(o, c, m);
  if (fit == Fit::kSymmetric) return FopdtFromSymmetric(o, c, delay_s, m);
  if (fit == Fit::kIntegrating) return IntegratingFromCycle(o, c, m);
  return fit == Fit::kTimes ? FopdtFromTimes(o, c, m) : FopdtFromCycle(o, c, m);
}

Status UltimateOf(const RelayOptions& o, Fit fit, const FopdtModel& m, double* ku, double* pu) {
  return fit == Fit::kSampled ? SampledUltimate(m, o.sample_period_s, ku, pu) : FopdtUltimate(m, ku, pu);
}

const char* FitName(Fit fit) {
  return fit == Fit::kSymmetric
             ? "the period, the amplitude and the delay to the extremes (a symmetric relay)"
         : fit == Fit::kTimes ? "switching times and integrals"
                              : "extremes";  // (kSampled is named with its period by the caller)
}

// The intervals: the same fit on each of the last n cycles alone, the
// spread of its K, T, L, Ku and Pu (95 %, Student's t); NaN where a cycle
// alone gives no model.
void CycleIntervals(const RelayOptions& o, const std::vector<RelayCycle>& cycles, int n, Fit fit,
                    double delay_s, RelayEstimates* r) {
  std::vector<double> ks, ts, ls, kus, pus;
  for (int i = 0; i < n; ++i) {
    FopdtModel m;
    double ku = 0.0, pu = 0.0;
    if (!FitCycle(o, cycles[cycles.size() - 1 - i], fit, delay_s, &m).ok() ||
        !UltimateOf(o, fit, m, &ku, &pu).ok()) {
      r->gain_ci = r->time_constant_ci_s = r->delay_ci_s = r->ku_ci = r->pu_ci_s =
          std::numeric_limits<double>::quiet_NaN();
      return;
    }
    ks.push_back(m.gain);
    ts.push_back(m.time_constant_s);
    ls.push_back(m.delay_s);
    kus.push_back(ku);
    pus.push_back(pu);
  }
  double centre = 0.0;
  MeanInterval(ks, &centre, &r->gain_ci);
  MeanInterval(ts, &centre, &r->time_constant_ci_s);
  MeanInterval(ls, &centre, &r->delay_ci_s);
  MeanInterval(kus, &centre, &r->ku_ci);
  MeanInterval(pus, &centre, &r->pu_ci_s);
}

}  // namespace

RelayEstimates EstimateFromCycles(const RelayOptions& o, const std::vector<RelayCycle>& cycles,
                                  bool converged, double noise_sigma, double delay_s) {
  RelayEstimates r;
  r.converged = converged;
  const int available = static_cast<int>(cycles.size()) - 1;  // without the approach
  const int n = std::min(o.settled_cycles, available);
  if (n < 1) {
    r.message = "no full relay cycle after the first yet (" + std::to_string(cycles.size()) + " cycles)";
    return r;
  }
  r.cycles = n;
  std::vector<double> periods, amplitudes;
  RelayCycle mean;
  for (int i = 0; i < n; ++i) {
    const RelayCycle& c = cycles[cycles.size() - 1 - i];
    periods.push_back(c.period_s());
    amplitudes.push_back(c.amplitude());
    mean.t_on_s += c.t_on_s / n;
    mean.t_off_s += c.t_off_s / n;
    mean.e_max += c.e_max / n;
    mean.e_min += c.e_min / n;
    mean.integral_e += c.integral_e / n;
    mean.integral_on_e += c.integral_on_e / n;
  }
  MeanInterval(periods, &r.period_s, &r.period_ci_s);
  MeanInterval(amplitudes, &r.amplitude, &r.amplitude_ci);
  const double d = 0.5 * (o.d_high + o.d_low), eps = o.hysteresis;
  if (r.amplitude > eps)
    r.ku_describing_function = 4.0 * d / (kPi * std::sqrt(r.amplitude * r.amplitude - eps * eps));
  const double mean_v = o.d_high * mean.t_on_s - o.d_low * mean.t_off_s;
  const bool integrating =
      o.d_high != o.d_low && std::abs(mean_v) <= 0.02 * (o.d_high * mean.t_on_s + o.d_low * mean.t_off_s);
  Fit fit = o.sample_period_s > 0.0 && !integrating  ? Fit::kSampled
            : o.d_high == o.d_low && delay_s > 0.0   ? Fit::kSymmetric
            : integrating                            ? Fit::kIntegrating
            : 3.0 * noise_sigma > 0.01 * r.amplitude ? Fit::kTimes
                                                     : Fit::kExtremes;
  Status fitted = FitCycle(o, mean, fit, delay_s, &r.model);
  if (!fitted.ok() && fit == Fit::kExtremes) {  // no FOPDT by its extremes: its half periods and integrals
    fit = Fit::kTimes;
    fitted = FitCycle(o, mean, fit, delay_s, &r.model);
  }
  r.model_from = fit == Fit::kSampled ? "the sampled cycle (a sample-and-hold of " +
                                            Number(o.sample_period_s) + " s, the relay on its grid)"
                                      : FitName(fit);
  if (!fitted.ok()) {
    r.message = fitted.message();
    return r;
  }
  if (const Status ultimate = UltimateOf(o, fit, r.model, &r.ku, &r.pu_s); !ultimate.ok()) {
    r.message = ultimate.message();
    return r;
  }
  r.model_found = true;
  CycleIntervals(o, cycles, n, fit, delay_s, &r);
  return r;
}

namespace {

// tau = L/T and T of K e^(-sL)/(Ts + 1) from a cycle's half periods under a
// relay d_high, d_low switching at e = -eps (to high) and +eps (to low):
// t_on = T g_on(tau), t_off = T g_off(tau), E = e^(-tau). False if no tau fits.
bool TauFromHalfPeriods(double k, double eps, double dh, double dl, double t_on, double t_off,
                        double* tau_out, double* t_out) {
  const double kh = k * dh, kl = k * dl;
  if (!(kh > eps) || !(kl > eps) || !(kh + kl - (kl - eps) > 0.0)) return false;
  const auto g_on = [&](double tau) {
    const double e = std::exp(-tau);
    return tau + std::log((kh + kl - (kl - eps) * e) / (kh - eps));
  };
  const auto g_off = [&](double tau) {
    const double e = std::exp(-tau);
    return tau + std::log((kh + kl - (kh - eps) * e) / (kl - eps));
  };
  // f(tau) = t_on g_off - t_off g_on changes sign once on (0, inf).
  const auto f = [&](double tau) { return t_on * g_off(tau) - t_off * g_on(tau); };
  double lo = 1e-9, hi = 1.0;
  const double f_lo = f(lo);
  while (hi < 1e3 && (f(hi) > 0.0) == (f_lo > 0.0)) hi *= 2.0;
  if ((f(hi) > 0.0) == (f_lo > 0.0) || !std::isfinite(f_lo)) return false;
  for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((f(mid) > 0.0) == (f_lo > 0.0) ? lo : hi) = mid;
  }
  const double tau = 0.5 * (lo + hi);
  const double t = 0.5 * (t_on / g_on(tau) + t_off / g_off(tau));
  if (!(t > 0.0) || !std::isfinite(t)) return false;
  *tau_out = tau;
  *t_out = t;
  return true;
}

// The integral of e over the part at +d_high (from e = -eps, the input low
// for L more, then high until t_on).
double OnIntegral(double k, double t, double l, double eps, double dh, double dl, double t_on) {
  const double big_e = std::exp(-l / t);
  const double e_min = -k * dl + (k * dl - eps) * big_e;
  const double before = -k * dl * l + (k * dl - eps) * t * (1.0 - big_e);
  const double d = t_on - l;
  return before + k * dh * d + (e_min - k * dh) * t * (1.0 - std::exp(-d / t));
}

// The static gain of a first-order process under relay `o` from one cycle:
// the integral of e over the mean output, both fits' first step. Refuses
// invalid options, a cycle whose mean output is zero (a symmetric relay, or
// an integrating process) and a gain that is not positive.
Status FirstOrderGain(const RelayOptions& o, const RelayCycle& c, double* k) {
  std::string error;
  if (!o.IsValid(&error)) return Status::InvalidInput(error);
  const double dh = o.d_high, dl = o.d_low;
  const double mean_v = dh * c.t_on_s - dl * c.t_off_s;
  if (!(std::abs(mean_v) > 1e-6 * (dh * c.t_on_s + dl * c.t_off_s)))
    return Status::InvalidInput(
        "the relay's mean output over a cycle is zero (a symmetric relay, or an integrating process): a "
        "first-order process's gain cannot be identified; make d_low differ from d_high");
  *k = c.integral_e / mean_v;
  if (!(*k > 0.0) || !std::isfinite(*k))
    return Status::InvalidInput("the identified gain " + Number(*k) +
                                " is not positive (the relay is reverse acting: a process of positive gain)");
  return Status::Ok();
}

}  // namespace

Status FopdtFromTimes(const RelayOptions& o, const RelayCycle& c, FopdtModel* model) {
  double k = 0.0;
  if (Status s = FirstOrderGain(o, c, &k); !s.ok()) return s;
  const double dh = o.d_high, dl = o.d_low;
  // The level eps_eff the relay really switched at: noise on y crosses the
  // band before the process does, so eps_eff < eps. It is the one whose
  // model gives the measured integral over the part at +d_high.
  const double top = 0.99 * k * std::min(dh, dl);
  const auto mismatch = [&](double eps, double* tau, double* t) {
    if (!TauFromHalfPeriods(k, eps, dh, dl, c.t_on_s, c.t_off_s, tau, t))
      return std::numeric_limits<double>::quiet_NaN();
    return OnIntegral(k, *t, *t * *tau, eps, dh, dl, c.t_on_s) - c.integral_on_e;
  };
  double tau = 0.0, t = 0.0;
  const int kGrid = 200;
  double a = std::numeric_limits<double>::quiet_NaN(), fa = a, b = a, fb = a;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i + 1 < kGrid; ++i) {  // on [0, top]: the sign change nearest the nominal hysteresis
    const double e0 = top * i / (kGrid - 1), e1 = top * (i + 1) / (kGrid - 1);
    const double f0 = mismatch(e0, &tau, &t), f1 = mismatch(e1, &tau, &t);
    if (!std::isfinite(f0) || !std::isfinite(f1) || (f0 > 0.0) == (f1 > 0.0)) continue;
    const double distance = std::abs(0.5 * (e0 + e1) - o.hysteresis);
    if (distance < best) {
      best = distance;
      a = e0, fa = f0, b = e1, fb = f1;
    }
  }
  if (!std::isfinite(best)) {  // no level fits the integral: the nominal hysteresis
    if (!TauFromHalfPeriods(k, o.hysteresis, dh, dl, c.t_on_s, c.t_off_s, &tau, &t))
      return Status::InvalidInput("the half periods " + Number(c.t_on_s) + " s and " + Number(c.t_off_s) +
                                  " s fit no first order plus dead time under this relay");
    model->gain = k;
    model->time_constant_s = t;
    model->delay_s = t * tau;
    model->integrating = false;
    return Status::Ok();
  }
  for (int i = 0; i < 200 && b - a > 1e-14 * std::max(1.0, std::abs(a)); ++i) {
    const double m = 0.5 * (a + b);
    const double fm = mismatch(m, &tau, &t);
    if (!std::isfinite(fm)) break;
    if ((fm > 0.0) == (fa > 0.0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
      fb = fm;
    }
  }
  (void)fb;
  if (!std::isfinite(mismatch(0.5 * (a + b), &tau, &t)))
    return Status::InvalidInput("the half periods give no time constant");
  model->gain = k;
  model->time_constant_s = t;
  model->delay_s = t * tau;
  model->integrating = false;
  return Status::Ok();
}

Status FopdtUltimate(const FopdtModel& m, double* ku, double* pu_s) {
  if (m.integrating) {
    if (!(m.gain != 0.0) || !std::isfinite(m.gain) || !(m.delay_s > 0.0) || !std::isfinite(m.delay_s) ||
        !(m.time_constant_s >= 0.0) || !std::isfinite(m.time_constant_s))
      return Status::InvalidInput("an integrating model needs a gain != 0, T >= 0 and L > 0 (K " +
                                  Number(m.gain) + ", T " + Number(m.time_constant_s) + " s, L " +
                                  Number(m.delay_s) + " s)");
    if (m.time_constant_s == 0.0) {
      const double w = kPi / (2.0 * m.delay_s);
      *ku = w / std::abs(m.gain);
      *pu_s = 4.0 * m.delay_s;
      return Status::Ok();
    }
    // K e^(-sL) / (s (Ts + 1)): atan(wT) + wL = pi / 2.
    double lo = 0.0, hi = kPi / (2.0 * m.delay_s);
    for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
      const double w = 0.5 * (lo + hi);
      (std::atan(w * m.time_constant_s) + w * m.delay_s < 0.5 * kPi ? lo : hi) = w;
    }
    const double w = 0.5 * (lo + hi);
    *ku = w * std::sqrt(1.0 + w * m.time_constant_s * (w * m.time_constant_s)) / std::abs(m.gain);
    *pu_s = 2.0 * kPi / w;
    return Status::Ok();
  }
  if (!(m.gain != 0.0) || !std::isfinite(m.gain) || !(m.time_constant_s >= 0.0) || !(m.delay_s > 0.0) ||
      !std::isfinite(m.time_constant_s) || !std::isfinite(m.delay_s))
    return Status::InvalidInput(
        "a FOPDT model needs a gain != 0, T >= 0 and L > 0 for a phase crossover (K " + Number(m.gain) +
        ", T " + Number(m.time_constant_s) + " s, L " + Number(m.delay_s) + " s)");
  // atan(wT) + wL is increasing: -pi at 0, > 0 at w = pi / L.
  double lo = 0.0, hi = kPi / m.delay_s;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double w = 0.5 * (lo + hi);
    (std::atan(w * m.time_constant_s) + w * m.delay_s < kPi ? lo : hi) = w;
  }
  const double w = 0.5 * (lo + hi);
  *ku = std::sqrt(1.0 + w * m.time_constant_s * (w * m.time_constant_s)) / std::abs(m.gain);
  *pu_s = 2.0 * kPi / w;
  return Status::Ok();
}

Status IntegratingFromCycle(const RelayOptions& o, const RelayCycle& c, FopdtModel* model) {
  std::string error;
  if (!o.IsValid(&error)) return Status::InvalidInput(error);
  const double eps = o.hysteresis, dh = o.d_high, dl = o.d_low;
  const double kl = (c.e_max - c.e_min - 2.0 * eps) / (dh + dl);  // K L
  const double k_on = (kl + (2.0 * eps + kl * dl) / dh) / c.t_on_s;
  const double k_off = (kl + (2.0 * eps + kl * dh) / dl) / c.t_off_s;
  const double k = 0.5 * (k_on + k_off);
  if (!(kl > 0.0) || !(k > 0.0) || !std::isfinite(k))
    return Status::InvalidInput("the cycle gives K L = " + Number(kl) + " and K = " + Number(k) +
                                ": not an integrating process of positive gain");
  model->gain = k;
  model->time_constant_s = 0.0;
  model->delay_s = kl / k;
  model->integrating = true;
  return Status::Ok();
}

Status FopdtFromCycle(const RelayOptions& o, const RelayCycle& c, FopdtModel* model) {
  double k = 0.0;
  if (Status s = FirstOrderGain(o, c, &k); !s.ok()) return s;
  const double eps = o.hysteresis, dh = o.d_high, dl = o.d_low;
  const double kh = k * dh, kl = k * dl;
  const double e1 = (kh - c.e_max) / (kh - eps), e2 = (kl + c.e_min) / (kl - eps);
  const double big_e = 0.5 * (e1 + e2);  // e^(-L/T) from either extreme
  if (!(big_e > 0.0 && big_e < 1.0) || !(kh > eps) || !(kl > eps))
    return Status::InvalidInput("the cycle's extremes give e^(-L/T) = " + Number(big_e) +
                                ", not in (0, 1): the process is no first order plus dead time");
  const double l_over_t = -std::log(big_e);
  const double on = l_over_t + std::log((kh - c.e_min) / (kh - eps));
  const double off = l_over_t + std::log((kl + c.e_max) / (kl - eps));
  const double t_from_on = c.t_on_s / on, t_from_off = c.t_off_s / off;
  const double t = 0.5 * (t_from_on + t_from_off);
  if (!(t > 0.0) || !std::isfinite(t))
    return Status::InvalidInput("the cycle's half periods give a time constant " + Number(t) + " s");
  // A first order plus dead time gives the same T from either half period;
  // where they differ the process is not one, and its extremes mislead (a
  // near-pure delay: e^(-L/T) near 0 leaves them only the gain).
  if (!(std::abs(t_from_on - t_from_off) <= kHalfPeriodAgreement * t))
    return Status::InvalidInput("the half periods give T " + Number(t_from_on) + " s and " +
                                Number(t_from_off) + " s: no first order plus dead time by its extremes");
  model->gain = k;
  model->time_constant_s = t;
  model->delay_s = t * l_over_t;
  model->integrating = false;
  return Status::Ok();
}

Status FopdtFromSymmetric(const RelayOptions& o, const RelayCycle& c, double delay_s, FopdtModel* model) {
  const double d = 0.5 * (o.d_high + o.d_low), eps = o.hysteresis, l = delay_s;
  const double a = 0.5 * (c.e_max - c.e_min), h = 0.5 * (c.t_on_s + c.t_off_s);
  if (!(l > 0.0) || !(h > l) || !(a > eps) || !(d > 0.0))
    return Status::InvalidInput("a symmetric relay's cycle (amplitude " + Number(a) + ", half period " +
                                Number(h) + " s, delay to the extremes " + Number(l) +
                                " s) gives no first order plus dead time");
  // g(x), x = Kd: the half period the amplitude's T gives, less the measured.
  const auto g = [&](double x) {
    return l * std::log((x + a) / (x - eps)) / std::log((x - eps) / (x - a)) - (h - l);
  };
  if (!(l * (a + eps) / (a - eps) - (h - l) > 0.0))
    return Status::InvalidInput("a symmetric relay's half period " + Number(h) +
                                " s is too long for its delay " + Number(l) + " s and amplitude " +
                                Number(a) +
                                ": no first order plus dead time (an integrating or higher-order process)");
  double lo = std::log(1e-12 * a), hi = std::log(1e12 * a);
  for (int i = 0; i < 200 && hi - lo > 1e-14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (g(a + std::exp(mid)) < 0.0 ? lo : hi) = mid;
  }
  const double x = a + std::exp(0.5 * (lo + hi));
  const double t = l / std::log((x - eps) / (x - a));
  if (!(t > 0.0) || !std::isfinite(t))
    return Status::InvalidInput("a symmetric relay's cycle gives a time constant " + Number(t) + " s");
  model->gain = x / d;
  model->time_constant_s = t;
  model->delay_s = l;
  model->integrating = false;
  return Status::Ok();
}

}  // namespace pidlab::autotune

namespace pidlab::autotune {

namespace {

// The whole number of samples h in t, or -1 if t is off the grid.
long Samples(double t, double h) {
  const double n = std::round(t / h);
  return n >= 1.0 && std::abs(t - n * h) <= 1e-6 * h ? static_cast<long>(n) : -1;
}

// The samples the sampled process takes from e0 towards its final value
// `to` until it is beyond `level` (up: above it), 0 if it never is.
long SamplesToCross(double a, double e0, double to, double level, bool up, long most) {
  double e = e0;
  for (long j = 1; j <= most; ++j) {
    e = to + a * (e - to);
    if (up ? e > level : e < level) return j;
  }
  return 0;
}

}  // namespace

Status SampledFopdtFromCycle(const RelayOptions& o, const RelayCycle& c, FopdtModel* model) {
  const double h = o.sample_period_s, eps = o.hysteresis;
  const long n_on = h > 0.0 ? Samples(c.t_on_s, h) : -1, n_off = h > 0.0 ? Samples(c.t_off_s, h) : -1;
  if (n_on < 0 || n_off < 0)
    return Status::InvalidInput("the half periods " + Number(c.t_on_s) + " s and " + Number(c.t_off_s) +
                                " s are not whole samples of " + Number(h) +
                                " s: the relay did not switch on the process's sample grid");
  double k = 0.0;
  if (Status s = FirstOrderGain(o, c, &k); !s.ok()) return s;
  const double kh = k * o.d_high, kl = k * o.d_low;
  const double r_on = (kh - c.e_max) / (kh - c.e_min), r_off = (kl + c.e_min) / (kl + c.e_max);
  if (!(r_on >= 0.0 && r_on < 1.0) || !(r_off >= 0.0 && r_off < 1.0))
    return Status::InvalidInput("the cycle's extremes " + Number(c.e_max) + ", " + Number(c.e_min) +
                                " lie beyond the gain " + Number(k) +
                                " times the relay: no sampled first order");
  const double a_on = std::pow(r_on, 1.0 / n_on), a_off = std::pow(r_off, 1.0 / n_off);
  // Relative on h/T = -ln a near a = 1, absolute near a = 0.
  if (!(std::abs(a_on - a_off) <= 0.02 * std::max(1.0 - a_on, 1.0 - a_off)))
    return Status::InvalidInput("the half periods give a = e^(-h/T) " + Number(a_on) + " and " +
                                Number(a_off) + ": no sampled first order plus dead time");
  const double a = 0.5 * (a_on + a_off);
  const long j_on = SamplesToCross(a, c.e_min, kh, eps, true, n_on);
  const long j_off = SamplesToCross(a, c.e_max, -kl, -eps, false, n_off);
  const long delay_on = n_on - j_on, delay_off = n_off - j_off;
  if (j_on == 0 || j_off == 0 || delay_on != delay_off || delay_on < 0)
    return Status::InvalidInput("the half periods give a delay of " + std::to_string(delay_on) + " and " +
                                std::to_string(delay_off) +
                                " samples: no sampled first order plus dead time");
  model->gain = k;
  model->time_constant_s = a > 0.0 ? -h / std::log(a) : 0.0;
  model->delay_s = static_cast<double>(delay_on) * h;
  model->integrating = false;
  return Status::Ok();
}

Status SampledUltimate(const FopdtModel& m, double h, double* ku, double* pu_s) {
  if (!(h > 0.0) || !(m.gain != 0.0) || m.integrating || !(m.time_constant_s >= 0.0) || !(m.delay_s >= 0.0))
    return Status::InvalidInput("no sampled ultimate point for this model at h " + Number(h) + " s");
  const double a = m.time_constant_s > 0.0 ? std::exp(-h / m.time_constant_s) : 0.0;
  const double n = std::round(m.delay_s / h);
  // The phase of G(e^(j w h)) is -n w h - arg(e^(j w h) - a): from 0 down to
  // -(n + 1) pi over w h in (0, pi], so -pi once (n = 0: at pi).
  const auto phase = [&](double th) { return -n * th - std::atan2(std::sin(th), std::cos(th) - a); };
  double lo = 0.0, hi = kPi;
  for (int i = 0; i < 200 && hi - lo > 1e-15 && n > 0.0; ++i) {
    const double mid = 0.5 * (lo + hi);
    (phase(mid) + kPi > 0.0 ? lo : hi) = mid;
  }
  const double th = n > 0.0 ? 0.5 * (lo + hi) : kPi;
  *ku = std::hypot(std::cos(th) - a, std::sin(th)) / (std::abs(m.gain) * (1.0 - a));
  *pu_s = 2.0 * kPi * h / th;
  return Status::Ok();
}

}  // namespace pidlab::autotune
