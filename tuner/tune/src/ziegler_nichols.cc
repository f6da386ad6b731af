// Ziegler-Nichols ultimate gain, computed from the plant's polynomials.
//
// Under P control the characteristic polynomial is p_K(s) = den(s) + K num(s).
// A pair of poles sits at s = +/- j w exactly when
//   Re den(jw) + K Re num(jw) = 0  and  Im den(jw) + K Im num(jw) = 0.
// Eliminating K gives F(w) = Re den Im num - Im den Re num = 0. F is odd in w
// (even powers times odd powers), so F(w) = w G(w^2) and the crossings are
// the positive real roots x of G, w = sqrt(x). For each, K follows from
// either equation; Ku is the smallest positive K at which the loop, stable
// just below it, stops being stable.

#include "pidlab/tune/ziegler_nichols.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <vector>

namespace pidlab::tune {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Coefficients in ascending powers (c[k] multiplies s^k), leading zeros removed.
std::vector<double> Ascending(const std::vector<double>& descending) {
  std::size_t first = 0;
  while (first + 1 < descending.size() && descending[first] == 0.0) ++first;
  return std::vector<double>(descending.rbegin(), descending.rend() - static_cast<std::ptrdiff_t>(first));
}

// p(jw) = R(w) + j I(w), as polynomials in w (ascending).
void SplitOnImaginaryAxis(const std::vector<double>& p, std::vector<double>* re, std::vector<double>* im) {
  re->assign(p.size(), 0.0);
  im->assign(p.size(), 0.0);
  for (std::size_t k = 0; k < p.size(); ++k) {
    const double sign = (k / 2) % 2 == 0 ? 1.0 : -1.0;  // j^k = (+1, +j, -1, -j, ...)
    (k % 2 == 0 ? *re : *im)[k] = sign * p[k];
  }
}

std::vector<double> Multiply(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}

double Horner(const std::vector<double>& ascending, double x) {
  double v = 0.0;
  for (auto it = ascending.rbegin(); it != ascending.rend(); ++it) v = v * x + *it;
  return v;
}

double MaxAbs(const std::vector<double>& p) {
  double m = 0.0;
  for (double v : p) m = std::max(m, std::abs(v));
  return m;
}

// den + K num, descending powers.
std::vector<double> ClosedLoopPolynomial(const std::vector<double>& den_asc,
                                         const std::vector<double>& num_asc, double k) {
  std::vector<double> p = den_asc;
  for (std::size_t i = 0; i < num_asc.size(); ++i) p[i] += k * num_asc[i];
  return std::vector<double>(p.rbegin(), p.rend());
}

// Largest real part of the roots, relative to the root magnitudes, so that
// the answer does not depend on the plant's time scale.
enum class LoopState { kStable, kMarginal, kUnstable };
LoopState ClassifyLoop(const std::vector<double>& den_asc, const std::vector<double>& num_asc, double k) {
  const auto roots = PolynomialRoots(ClosedLoopPolynomial(den_asc, num_asc, k));
  LoopState state = LoopState::kStable;
  for (const auto& r : roots) {
    const double tol = 1e-9 * std::max(1.0, std::abs(r));
    if (r.real() > tol) return LoopState::kUnstable;
    if (r.real() >= -tol) state = LoopState::kMarginal;
  }
  return state;
}

std::string Fmt(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

// den(jw) and num(jw) split into real and imaginary parts, polynomials in w.
struct OnImaginaryAxis {
  std::vector<double> den_re, den_im, num_re, num_im;
};

OnImaginaryAxis SplitLoop(const std::vector<double>& den_asc, const std::vector<double>& num_asc) {
  OnImaginaryAxis axis;
  SplitOnImaginaryAxis(den_asc, &axis.den_re, &axis.den_im);
  SplitOnImaginaryAxis(num_asc, &axis.num_re, &axis.num_im);
  return axis;
}

// G with F(w) = Re den Im num - Im den Re num = w G(w^2), ascending in
// x = w^2, with negligible leading coefficients dropped. Empty: F is zero
// for every w.
std::vector<double> CrossingPolynomial(const OnImaginaryAxis& axis, const std::vector<double>& den_asc,
                                       const std::vector<double>& num_asc) {
  std::vector<double> f = Multiply(axis.den_re, axis.num_im);
  const std::vector<double> f2 = Multiply(axis.den_im, axis.num_re);
  for (std::size_t i = 0; i < f.size(); ++i) f[i] -= f2[i];
  // G's coefficients are F's odd ones.
  std::vector<double> g;
  for (std::size_t i = 1; i < f.size(); i += 2) g.push_back(f[i]);
  const double scale = MaxAbs(Multiply(den_asc, num_asc));
  while (!g.empty() && std::abs(g.back()) <= 1e-13 * scale) g.pop_back();
  return g;
}

// Candidate crossing frequencies w = sqrt(x) for the positive real roots x
// of G (ascending).
std::vector<double> CandidateFrequencies(const std::vector<double>& g) {
  std::vector<double> candidates_w;
  if (g.size() < 2) return candidates_w;
  const std::vector<double> g_desc(g.rbegin(), g.rend());
  for (const auto& root : PolynomialRoots(g_desc)) {
    if (std::abs(root.imag()) > 1e-6 * std::max(1.0, std::abs(root))) continue;
    double x = root.real();
    if (x <= 0.0) continue;
    // Newton polish on G (the companion eigenvalues lose digits on badly
    // scaled plants such as the stepper motor).
    for (int it = 0; it < 20; ++it) {
      double value = 0.0, slope = 0.0;
      for (auto c = g.rbegin(); c != g.rend(); ++c) {
        slope = slope * x + value;
        value = value * x + *c;
      }
      if (slope == 0.0) break;
      const double step = value / slope;
      x -= step;
      if (std::abs(step) <= 1e-15 * std::abs(x)) break;
    }
    if (x > 0.0) candidates_w.push_back(std::sqrt(x));
  }
  return candidates_w;
}

// A gain K > 0 that puts poles of den + K num at s = +/- j w.
struct Crossing {
  double k, w;
};

// The crossings at the candidate frequencies, by increasing K: K from the
// real part, kept where it also zeroes the imaginary part.
std::vector<Crossing> CrossingGains(const OnImaginaryAxis& axis, const std::vector<double>& candidates_w) {
  std::vector<Crossing> crossings;
  for (double w : candidates_w) {
    const double dr = Horner(axis.den_re, w), di = Horner(axis.den_im, w);
    const double nr = Horner(axis.num_re, w), ni = Horner(axis.num_im, w);
    const double n2 = nr * nr + ni * ni;
    if (n2 == 0.0) continue;  // a zero of the plant on the axis
    const double k = -(dr * nr + di * ni) / n2;
    const double residual = std::hypot(dr + k * nr, di + k * ni);
    if (residual > 1e-6 * std::max(std::hypot(dr, di), 1e-300)) continue;
    if (k > 0.0 && std::isfinite(k)) crossings.push_back({k, w});
  }
  std::sort(crossings.begin(), crossings.end(),
            [](const Crossing& a, const Crossing& b) { return a.k < b.k; });
  return crossings;
}

// Relative offset of K either side of a crossing when classifying the loop.
constexpr double kSide = 1e-4;

// The first crossing (smallest K) that takes the loop from stable just below
// it to not stable just above; null if none does.
const Crossing* UltimateCrossing(const std::vector<double>& den_asc, const std::vector<double>& num_asc,
                                 const std::vector<Crossing>& crossings) {
  for (const Crossing& c : crossings) {
    if (ClassifyLoop(den_asc, num_asc, c.k * (1.0 - kSide)) != LoopState::kStable) continue;
    if (ClassifyLoop(den_asc, num_asc, c.k * (1.0 + kSide)) == LoopState::kStable) continue;  // touches only
    return &c;
  }
  return nullptr;
}

// Why no crossing qualified as the ultimate gain (the text after "does not apply: ").
std::string NoUltimateGain(const TransferFunction& tf, const std::vector<double>& den_asc,
                           const std::vector<double>& num_asc, const std::vector<Crossing>& crossings) {
  if (crossings.empty())
    return "the P-only loop " + tf.ToString() +
           " never reaches the stability boundary for K > 0 (no imaginary-axis crossing)";
  if (ClassifyLoop(den_asc, num_asc, crossings[0].k * kSide) != LoopState::kStable)
    return "the P-only loop " + tf.ToString() +
           " is not stable for small K, and no crossing takes it from stable to unstable";
  return "no imaginary-axis crossing of the P-only loop takes it from stable to unstable";
}

// The rule's Kp, Ti, Td from Ku and Tu, as gains (ki = Kp/Ti, kd = Kp Td) and
// a one-line summary in *message.
PidGains ApplyRule(ZieglerNicholsRule rule, double ku, double tu, double wu, std::string* message) {
  double kp = 0.0, ti = 0.0, td = 0.0;
  switch (rule) {
    case ZieglerNicholsRule::kClassic:
      kp = 0.6 * ku, ti = tu / 2.0, td = tu / 8.0;
      break;
    case ZieglerNicholsRule::kPessen:
      kp = 0.7 * ku, ti = 0.4 * tu, td = 0.15 * tu;
      break;
    case ZieglerNicholsRule::kSomeOvershoot:
      kp = 0.33 * ku, ti = tu / 2.0, td = tu / 3.0;
      break;
    case ZieglerNicholsRule::kNoOvershoot:
      kp = 0.2 * ku, ti = tu / 2.0, td = tu / 3.0;
      break;
  }
  *message = "Ku = " + Fmt(ku) + ", wu = " + Fmt(wu) + " rad/s, Tu = " + Fmt(tu) + " s; " + ToString(rule) +
             " rule: Kp = " + Fmt(kp) + ", Ti = " + Fmt(ti) + " s, Td = " + Fmt(td) + " s";
  return PidGains{kp, kp / ti, kp * td};
}

}  // namespace

bool ParseZieglerNicholsRule(const std::string& s, ZieglerNicholsRule* rule) {
  if (s == "classic")
    *rule = ZieglerNicholsRule::kClassic;
  else if (s == "pessen")
    *rule = ZieglerNicholsRule::kPessen;
  else if (s == "some-overshoot")
    *rule = ZieglerNicholsRule::kSomeOvershoot;
  else if (s == "no-overshoot")
    *rule = ZieglerNicholsRule::kNoOvershoot;
  else
    return false;
  return true;
}

std::string ToString(ZieglerNicholsRule rule) {
  switch (rule) {
    case ZieglerNicholsRule::kClassic:
      return "classic";
    case ZieglerNicholsRule::kPessen:
      return "pessen";
    case ZieglerNicholsRule::kSomeOvershoot:
      return "some-overshoot";
    case ZieglerNicholsRule::kNoOvershoot:
      return "no-overshoot";
  }
  return "classic";
}

namespace {

// ZieglerNicholsTune() with the refusal's message in *error.
bool ZieglerNicholsTuneOrExplain(const TransferFunction& tf, ZieglerNicholsRule rule,
                                 ZieglerNicholsResult* result, std::string* error) {
  *result = ZieglerNicholsResult{};
  auto not_applicable = [&](const std::string& why) {
    result->applicable = false;
    result->message = "Ziegler-Nichols does not apply: " + why;
    if (error) *error = result->message;
    return false;
  };
  std::string invalid;
  if (!tf.IsValid(&invalid)) return not_applicable("invalid plant: " + invalid);
  const std::vector<double> den = Ascending(tf.den);
  std::vector<double> num = Ascending(tf.num);
  if (MaxAbs(num) == 0.0) return not_applicable("the plant's numerator is zero");
  num.resize(den.size(), 0.0);  // deg num <= deg den (checked by IsValid)

  const OnImaginaryAxis axis = SplitLoop(den, num);
  const std::vector<double> g = CrossingPolynomial(axis, den, num);
  if (g.empty()) {
    // Every w is a candidate: den and num are both even (or both odd) in s,
    // so the loop has no damping at any gain.
    if (ClassifyLoop(den, num, 1.0) == LoopState::kMarginal) {
      return not_applicable("the P-only loop " + tf.ToString() +
                            " is marginally stable (undamped poles on the imaginary axis) for every K > 0, "
                            "so there is no finite ultimate gain");
    }
    return not_applicable("the P-only loop has no isolated imaginary-axis crossing (no damping term)");
  }
  const std::vector<Crossing> crossings = CrossingGains(axis, CandidateFrequencies(g));
  const Crossing* ultimate = UltimateCrossing(den, num, crossings);
  if (!ultimate) return not_applicable(NoUltimateGain(tf, den, num, crossings));

  result->applicable = true;
  result->ultimate_gain = ultimate->k;
  result->crossover_rad_s = ultimate->w;
  result->ultimate_period_s = 2.0 * kPi / ultimate->w;
  result->gains = ApplyRule(rule, result->ultimate_gain, result->ultimate_period_s, result->crossover_rad_s,
                            &result->message);
  if (error) error->clear();
  return true;
}

}  // namespace

Status ZieglerNicholsTune(const TransferFunction& tf, ZieglerNicholsRule rule, ZieglerNicholsResult* result) {
  std::string why;
  if (!ZieglerNicholsTuneOrExplain(tf, rule, result, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::tune
