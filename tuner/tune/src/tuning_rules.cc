#include "pidlab/tune/tuning_rules.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <sstream>

namespace pidlab::tune {

bool ParseRuleForm(const std::string& s, RuleForm* form) {
  if (s == "pi")
    *form = RuleForm::kPi;
  else if (s == "pid")
    *form = RuleForm::kPid;
  else
    return false;
  return true;
}

std::string ToString(RuleForm form) { return form == RuleForm::kPi ? "pi" : "pid"; }

std::string ToString(TuningRule rule) { return rule == TuningRule::kSimc ? "simc" : "amigo"; }

std::string ToString(ProcessModelKind kind) {
  switch (kind) {
    case ProcessModelKind::kFopdt:
      return "fopdt";
    case ProcessModelKind::kSopdt:
      return "sopdt";
    case ProcessModelKind::kIntegrating:
      return "ipdt";
  }
  return "fopdt";
}

PidGains SeriesToParallel(double kc, double ti_s, double td_s) {
  // Kc (1 + 1/(ti s)) (td s + 1) = Kc (1 + td/ti) + (Kc/ti)/s + Kc td s.
  PidGains g;
  g.kp = kc * (1.0 + td_s / ti_s);
  g.ki = kc / ti_s;
  g.kd = kc * td_s;
  return g;
}

namespace {

// A root counts as real when its imaginary part is below this fraction of its
// magnitude: the companion matrix splits an m-fold real root into a small
// cluster (about eps^(1/m) wide), which is a repeated real pole, not an
// oscillation.
constexpr double kRealTolerance = 1e-4;

std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string Root(const std::complex<double>& r) {
  std::ostringstream os;
  os << r.real();
  if (r.imag() != 0.0) os << (r.imag() > 0 ? "+" : "-") << std::abs(r.imag()) << "j";
  return os.str();
}

// p without leading zeros; *trailing = how many trailing zeros it had (factors
// of s), which are removed too.
std::vector<double> StripZeros(std::vector<double> p, int* trailing) {
  while (!p.empty() && p.front() == 0.0) p.erase(p.begin());
  *trailing = 0;
  while (!p.empty() && p.back() == 0.0) {
    p.pop_back();
    ++*trailing;
  }
  return p;
}

using Factored = FactoredPlant;

Status Factor(const Plant& plant, Factored* f) {
  const std::string tf = plant.tf.ToString();
  const std::string who = "plant " + plant.name + (tf.size() <= 80 ? " (" + tf + ")" : std::string());
  int num_origin = 0;
  const std::vector<double> num = StripZeros(plant.tf.num, &num_origin);
  const std::vector<double> den = StripZeros(plant.tf.den, &f->integrators);
  if (num.empty() || den.empty()) return Status::InvalidInput(who + " has no numerator or denominator");
  if (num_origin > 0)
    return Status::InvalidInput(who + " has a zero at s = 0 (no static gain): the tuning rules do not apply");
  if (f->integrators > 1)
    return Status::InvalidInput(who + " has " + std::to_string(f->integrators) +
                                " poles at s = 0: the tuning rules take at most one integrator");
  for (const std::complex<double>& p : PolynomialRoots(den)) {
    if (std::abs(p.imag()) > kRealTolerance * std::abs(p))
      return Status::InvalidInput(who + " has complex poles (" + Root(p) +
                                  "): the half rule takes real poles only");
    if (!(p.real() < 0.0))
      return Status::InvalidInput(who + " has an unstable pole at " + Root(p) +
                                  ": the tuning rules take stable or integrating plants only");
    f->lags.push_back(-1.0 / p.real());
  }
  for (const std::complex<double>& z : PolynomialRoots(num)) {
    if (std::abs(z.imag()) > kRealTolerance * std::abs(z))
      return Status::InvalidInput(who + " has complex zeros (" + Root(z) +
                                  "): the half rule takes real zeros only");
    if (!(z.real() > 0.0))
      return Status::InvalidInput(who + " has a zero at " + Root(z) +
                                  " (a lead): the half rule's lead approximations are not implemented");
    f->inverse.push_back(1.0 / z.real());
  }
  std::sort(f->lags.begin(), f->lags.end(), std::greater<double>());
  f->gain = num.back() / den.back();
  if (!(f->gain > 0.0) || !std::isfinite(f->gain))
    return Status::InvalidInput(who + " has gain " + Num(f->gain) +
                                ": the tuning rules need a positive gain (pidlab's gains are >= 0)");
  return Status::Ok();
}

// The half rule: keep the `keep` largest lags; the largest neglected one goes
// half to the smallest kept one (if any is kept; an integrator is an infinite
// time constant that takes nothing) and half to the dead time; the rest and
// every inverse-response time constant go to the dead time.
ProcessModel HalfRule(const Factored& f, std::size_t keep) {
  const double delay_s = f.delay_s;
  ProcessModel m;
  m.gain = f.gain;
  m.delay_s = delay_s;
  keep = std::min(keep, f.lags.size());
  m.time_constants.assign(f.lags.begin(), f.lags.begin() + static_cast<std::ptrdiff_t>(keep));
  for (std::size_t i = keep; i < f.lags.size(); ++i) {
    const bool split = i == keep;
    if (split && keep > 0) m.time_constants.back() += 0.5 * f.lags[i];
    m.delay_s += split ? 0.5 * f.lags[i] : f.lags[i];
  }
  for (double t0 : f.inverse) m.delay_s += t0;
  m.half_rule = keep < f.lags.size() || !f.inverse.empty();
  return m;
}

std::string ModelText(const ProcessModel& m) {
  std::ostringstream os;
  os << ToString(m.kind) << " K" << (m.kind == ProcessModelKind::kIntegrating ? "'" : "") << " = " << m.gain;
  for (std::size_t i = 0; i < m.time_constants.size(); ++i)
    os << ", T"
       << (m.kind == ProcessModelKind::kFopdt
               ? std::string()
               : std::to_string(i + (m.kind == ProcessModelKind::kIntegrating ? 2 : 1)))
       << " = " << m.time_constants[i];
  os << ", L = " << m.delay_s << (m.half_rule ? " (half rule)" : " (exact)");
  return os.str();
}

Status Finish(TuningRuleResult* r) {
  std::string error;
  if (!(r->kc > 0.0) || !GainsAreValid(r->gains, &error))
    return Status::InvalidInput(ToString(r->rule) + " on the model " + ModelText(r->model) +
                                " gives gains out of range: " + error);
  std::ostringstream os;
  os << ToString(r->rule) << " " << ToString(r->form) << " on " << ModelText(r->model) << ": Kc = " << r->kc
     << ", Ti = " << r->ti_s << " s, Td = " << r->td_s << " s (" << r->controller_form << ")";
  r->message = os.str();
  return Status::Ok();
}

Status NeedDelay(TuningRule rule, const ProcessModel& m) {
  if (m.delay_s > 0.0 && std::isfinite(m.delay_s)) return Status::Ok();
  return Status::InvalidInput(
      ToString(rule) + " needs a dead time: the model " + ModelText(m) +
      " has L = 0 (the rule sets the closed-loop speed by L; give the plant a delay)");
}

}  // namespace

Status ReduceModel(const Plant& plant, TuningRule rule, RuleForm form, ProcessModel* model) {
  if (!std::isfinite(plant.delay_s) || plant.delay_s < 0.0)
    return Status::InvalidInput("plant delay " + Num(plant.delay_s) + " s must be finite and >= 0");
  if (plant.nonlinear)
    return Status::InvalidInput(
        "plant " + plant.name +
        " is nonlinear: the tuning rules take a transfer function (tune --plant stepper)");
  Factored f;
  const Status factored = Factor(plant, &f);
  if (!factored.ok()) return factored;
  f.delay_s = plant.delay_s;
  if (f.lags.empty() && f.integrators == 0)
    return Status::InvalidInput("plant " + plant.name + " has no pole: nothing to reduce");
  return ReduceFactored(f, rule, form, model);
}

Status ReduceFactored(const FactoredPlant& plant, TuningRule rule, RuleForm form, ProcessModel* model) {
  FactoredPlant f = plant;
  if (!std::isfinite(f.delay_s) || f.delay_s < 0.0)
    return Status::InvalidInput("plant delay " + Num(f.delay_s) + " s must be finite and >= 0");
  if (!(f.gain > 0.0) || !std::isfinite(f.gain) || f.integrators < 0 || f.integrators > 1)
    return Status::InvalidInput("a factored plant needs a positive gain and at most one integrator");
  if (f.lags.empty() && f.integrators == 0)
    return Status::InvalidInput("a plant with no pole: nothing to reduce");
  std::sort(f.lags.begin(), f.lags.end(), std::greater<double>());
  const bool sopdt = rule == TuningRule::kSimc && form == RuleForm::kPid;
  if (f.integrators == 1) {
    *model = HalfRule(f, sopdt ? 1 : 0);
    model->kind = ProcessModelKind::kIntegrating;
    return Status::Ok();
  }
  *model = HalfRule(f, sopdt ? 2 : 1);
  // The second-order model is symmetric in T1 and T2; the half rule can make
  // the kept smaller one the larger ((s+1)^3: 1 and 1.5), SIMC wants T1 >= T2.
  std::sort(model->time_constants.begin(), model->time_constants.end(), std::greater<double>());
  model->kind = model->time_constants.size() == 2 ? ProcessModelKind::kSopdt : ProcessModelKind::kFopdt;
  return Status::Ok();
}

Status SimcTune(const ProcessModel& m, RuleForm form, TuningRuleResult* r, double tau_c_s) {
  r->rule = TuningRule::kSimc;
  r->form = form;
  r->model = m;
  r->controller_form = "series";
  // tau_c given: the model may have no dead time (the closed loop's speed is given).
  const Status delayed = tau_c_s > 0.0 ? Status::Ok() : NeedDelay(r->rule, m);
  if (!delayed.ok()) return delayed;
  const double tau_c = tau_c_s > 0.0 ? tau_c_s : m.delay_s;  // default: tight tuning, tau_c = theta
  const double t = tau_c + m.delay_s;
  if (m.kind == ProcessModelKind::kIntegrating) {
    r->kc = 1.0 / (m.gain * t);
    r->ti_s = 4.0 * t;
  } else {
    r->kc = m.time_constants[0] / (m.gain * t);
    r->ti_s = std::min(m.time_constants[0], 4.0 * t);
  }
  const bool lag = (m.kind == ProcessModelKind::kSopdt && m.time_constants.size() == 2) ||
                   (m.kind == ProcessModelKind::kIntegrating && m.time_constants.size() == 1);
  r->td_s = form == RuleForm::kPid && lag ? m.time_constants.back() : 0.0;
  r->gains = SeriesToParallel(r->kc, r->ti_s, r->td_s);
  const Status finished = Finish(r);
  if (finished.ok() && tau_c_s > 0.0) {
    std::ostringstream os;
    os << ", tau_c = " << tau_c << " s (given)";
    r->message += os.str();
  }
  return finished;
}

Status AmigoTune(const ProcessModel& m, RuleForm form, TuningRuleResult* r) {
  r->rule = TuningRule::kAmigo;
  r->form = form;
  r->model = m;
  r->controller_form = "parallel";
  const Status delayed = NeedDelay(r->rule, m);
  if (!delayed.ok()) return delayed;
  if (m.kind == ProcessModelKind::kSopdt ||
      (m.kind == ProcessModelKind::kIntegrating && !m.time_constants.empty()))
    return Status::InvalidInput("amigo takes an fopdt or an ipdt model, not " + ModelText(m));
  const double k = m.gain, l = m.delay_s;
  const bool pid = form == RuleForm::kPid;
  if (m.kind == ProcessModelKind::kIntegrating) {
    r->kc = (pid ? 0.45 : 0.35) / (k * l);
    r->ti_s = (pid ? 8.0 : 13.4) * l;
    r->td_s = pid ? 0.5 * l : 0.0;
  } else if (pid) {
    const double t = m.time_constants[0];
    r->kc = (0.2 + 0.45 * t / l) / k;
    r->ti_s = (0.4 * l + 0.8 * t) / (l + 0.1 * t) * l;
    r->td_s = 0.5 * l * t / (0.3 * l + t);
  } else {
    const double t = m.time_constants[0];
    r->kc = 0.15 / k + (0.35 - l * t / ((l + t) * (l + t))) * t / (k * l);
    r->ti_s = 0.35 * l + 13.0 * l * t * t / (t * t + 12.0 * l * t + 7.0 * l * l);
    r->td_s = 0.0;
  }
  r->gains.kp = r->kc;
  r->gains.ki = r->kc / r->ti_s;
  r->gains.kd = r->kc * r->td_s;
  return Finish(r);
}

Status ApplyTuningRule(const Plant& plant, TuningRule rule, RuleForm form, TuningRuleResult* result,
                       double tau_c_s) {
  if (!(tau_c_s >= 0.0) || !std::isfinite(tau_c_s))
    return Status::InvalidInput("tau_c " + std::to_string(tau_c_s) + " must be >= 0 and finite (s)");
  ProcessModel model;
  const Status reduced = ReduceModel(plant, rule, form, &model);
  if (!reduced.ok()) return reduced;
  const Status tuned =
      rule == TuningRule::kSimc ? SimcTune(model, form, result, tau_c_s) : AmigoTune(model, form, result);
  result->plant_delay_s = plant.delay_s;
  return tuned;
}

}  // namespace pidlab::tune
