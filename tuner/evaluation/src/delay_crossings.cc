// Stability of the retarded loop by its crossing frequencies
// (delay_crossings.h).

#include "pidlab/evaluation/delay_crossings.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "pidlab/evaluation/loop_frequency.h"
#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::evaluation {
namespace {

using frequency::cd;
using frequency::kPi;
using frequency::Polynomial;

// |x(jw)|^2 as a polynomial in nu = w^2, ascending powers: x(jw) = R(nu) +
// j w I(nu), so |x|^2 = R^2 + nu I^2.
Polynomial SquaredModulus(const Polynomial& descending) {
  const int d = static_cast<int>(descending.size()) - 1;
  Polynomial re(static_cast<std::size_t>(d / 2 + 1), 0.0), im(static_cast<std::size_t>(d / 2 + 1), 0.0);
  for (int i = 0; i <= d; ++i) {
    const double c = descending[static_cast<std::size_t>(d - i)] * ((i / 2) % 2 == 0 ? 1.0 : -1.0);
    (i % 2 == 0 ? re : im)[static_cast<std::size_t>(i / 2)] = c;
  }
  Polynomial out(static_cast<std::size_t>(d + 1), 0.0);
  for (std::size_t i = 0; i < re.size(); ++i)
    for (std::size_t j = 0; j < re.size(); ++j) {
      if (i + j < out.size()) out[i + j] += re[i] * re[j];
      if (i + j + 1 < out.size()) out[i + j + 1] += im[i] * im[j];
    }
  return out;
}

// F(nu), F'(nu) and sum |F_i| nu^i (the scale of F's rounding) by Horner,
// F in ascending powers.
struct FValue {
  double f = 0.0, df = 0.0, scale = 0.0;
};
FValue EvalAscending(const Polynomial& f, double nu) {
  FValue v;
  for (std::size_t i = f.size(); i-- > 0;) {
    v.df = v.df * nu + v.f;
    v.f = v.f * nu + f[i];
    v.scale = v.scale * nu + std::abs(f[i]);
  }
  return v;
}

// The real root of F near nu, polished by Newton.
double Polish(const Polynomial& f, double nu) {
  for (int i = 0; i < 4; ++i) {
    const FValue v = EvalAscending(f, nu);
    if (!(v.df != 0.0)) break;
    const double next = nu - v.f / v.df;
    if (!std::isfinite(next) || !(next > 0.0)) break;
    nu = next;
  }
  return nu;
}

// Z(0): the roots of a + b right of the axis; -1 when one is within
// kCrossingRootTolerance of it (or the roots are not finite).
int RootsRightWithoutDelay(const Polynomial& a, const Polynomial& b) {
  int right = 0;
  for (const cd& r : PolynomialRoots(frequency::Add(a, b))) {
    if (!std::isfinite(r.real()) || !std::isfinite(r.imag())) return -1;
    if (std::abs(r.real()) <= kCrossingRootTolerance * std::max(1.0, std::abs(r))) return -1;
    if (r.real() > 0.0) ++right;
  }
  return right;
}

// One crossing frequency w (F(w^2) = 0, slope sign `direction`): adds to
// *count the pairs that crossed below the delay; false when the delay is
// within kCrossingPhaseTolerance of a crossing.
bool AddCrossing(const Polynomial& a, const Polynomial& b, double w, int direction, double delay_s,
                 CrossingCount* count) {
  const cd s(0.0, w), av = frequency::Eval(a, s), bv = frequency::Eval(b, s);
  if (!(std::abs(av) > 0.0) || !std::isfinite(std::abs(av)) || !std::isfinite(std::abs(bv))) return false;
  // e^(-j w tau) = -b / a: tau = (theta + 2 pi k) / w, theta in [0, 2 pi).
  double theta = std::fmod(-std::arg(-bv / av), 2.0 * kPi);
  if (theta < 0.0) theta += 2.0 * kPi;
  const double x = w * delay_s - theta;
  const double turns = x > 0.0 ? std::ceil(x / (2.0 * kPi)) : 0.0;
  const double gap = x <= 0.0 ? -x : std::min(std::fmod(x, 2.0 * kPi), 2.0 * kPi - std::fmod(x, 2.0 * kPi));
  const double relative_gap = gap / std::max(1.0, w * delay_s);
  count->phase_gap = std::min(count->phase_gap, relative_gap);
  ++count->crossings;
  if (!(relative_gap > kCrossingPhaseTolerance)) return false;
  count->roots_right += 2 * direction * static_cast<int>(turns);
  return true;
}

// The crossing frequencies: the positive real roots of F, each simple and
// apart from the others; false (undecided) otherwise.
bool CrossingFrequencies(const Polynomial& f_ascending, std::vector<std::pair<double, int>>* crossings) {
  Polynomial descending(f_ascending.rbegin(), f_ascending.rend());
  crossings->clear();
  for (const cd& r : PolynomialRoots(descending)) {
    if (!std::isfinite(r.real()) || !std::isfinite(r.imag())) return false;
    if (!(r.real() > 0.0)) continue;
    if (r.imag() != 0.0) {
      // A complex pair this near the real axis may be a double root split
      // by rounding: |L| touching 1.
      if (std::abs(r.imag()) <= kCrossingRootTolerance * std::abs(r)) return false;
      continue;
    }
    const double nu = Polish(f_ascending, r.real());
    const FValue v = EvalAscending(f_ascending, nu);
    if (!(std::abs(v.df) * nu > kCrossingRootTolerance * v.scale)) return false;  // (near) double root
    crossings->push_back({std::sqrt(nu), v.df > 0.0 ? 1 : -1});
  }
  std::sort(crossings->begin(), crossings->end());
  for (std::size_t i = 1; i < crossings->size(); ++i)
    if ((*crossings)[i].first - (*crossings)[i - 1].first <= kCrossingRootTolerance * (*crossings)[i].first)
      return false;
  return true;
}

}  // namespace

CrossingCount CountRootsByCrossings(const std::vector<double>& a_in, const std::vector<double>& b_in,
                                    double delay_s) {
  CrossingCount count;
  const Polynomial a = frequency::Trim(a_in), b = frequency::Trim(b_in);
  const int da = frequency::Degree(a), db = frequency::Degree(b);
  if (db < 1 || da >= db || !(delay_s > 0.0) || !std::isfinite(delay_s)) return count;
  count.roots_without_delay = RootsRightWithoutDelay(a, b);
  if (count.roots_without_delay < 0) return count;
  count.roots_right = count.roots_without_delay;
  Polynomial f = SquaredModulus(b);
  const Polynomial sa = SquaredModulus(a);
  for (std::size_t i = 0; i < sa.size(); ++i) f[i] -= sa[i];
  std::vector<std::pair<double, int>> crossings;
  if (!CrossingFrequencies(f, &crossings)) return count;
  for (const auto& [w, direction] : crossings)
    if (!AddCrossing(a, b, w, direction, delay_s, &count)) return count;
  if (count.roots_right < 0) return count;  // inconsistent: leave it to the count
  count.verdict = count.roots_right == 0 ? CrossingVerdict::kStable : CrossingVerdict::kUnstable;
  return count;
}

}  // namespace pidlab::evaluation
