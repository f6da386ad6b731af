// The continuous loop's frequency response (loop_frequency.h): the PID's
// polynomials, the analysis grid of the continuous loop, and the Nyquist
// count of the loop with its dead time.

#include "pidlab/evaluation/loop_frequency.h"

#include <algorithm>
#include <cmath>

namespace pidlab::evaluation {
namespace frequency {

// Log grid over [lo, hi] merged with the special frequencies inside it.
std::vector<double> Grid(double lo, double hi, double per_decade, const std::vector<double>& special) {
  std::vector<double> w;
  const double decades = std::log10(hi / lo);
  const int n = std::max(2, static_cast<int>(std::ceil(decades * per_decade)) + 1);
  for (int i = 0; i < n; ++i) w.push_back(lo * std::pow(10.0, decades * i / (n - 1)));
  w.back() = hi;
  for (double s : special)
    for (double f : {1.0 - 1e-3, 1.0, 1.0 + 1e-3})
      if (s * f > lo && s * f < hi) w.push_back(s * f);
  std::sort(w.begin(), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  return w;
}

// Every frequency a narrow feature can sit at.
std::vector<double> SpecialFrequencies(const std::vector<cd>& roots) {
  std::vector<double> w;
  for (const cd& p : roots) {
    if (std::abs(p) > 0.0 && std::isfinite(std::abs(p))) w.push_back(std::abs(p));
    if (std::abs(p.imag()) > 0.0 && std::isfinite(p.imag())) w.push_back(std::abs(p.imag()));
  }
  return w;
}

std::vector<double> OpenLoopFrequencies(const ContinuousResponse& r) {
  std::vector<double> special;
  if (r.delay() > 0.0) special.push_back(1.0 / r.delay());
  for (const auto& v : {PolynomialRoots(r.a()), PolynomialRoots(r.b())})
    for (double w : SpecialFrequencies(v)) special.push_back(w);
  return special;
}

}  // namespace frequency

void ContinuousPidPolynomials(const PidGains& g, std::vector<double>* num, std::vector<double>* den) {
  using frequency::Polynomial;
  const bool d = g.kd > 0.0, filtered = d && g.tf > 0.0, integral = g.ki > 0.0;
  if (filtered) {
    // (kp + kd/tf) - (kd/tf)/(tf s + 1) + ki/s over s (tf s + 1).
    *num = integral ? Polynomial{g.kp * g.tf + g.kd, g.kp + g.ki * g.tf, g.ki}
                    : Polynomial{g.kp * g.tf + g.kd, g.kp};
    *den = integral ? Polynomial{g.tf, 1.0, 0.0} : Polynomial{g.tf, 1.0};
  } else if (d) {
    *num = integral ? Polynomial{g.kd, g.kp, g.ki} : Polynomial{g.kd, g.kp};
    *den = integral ? Polynomial{1.0, 0.0} : Polynomial{1.0};
  } else {
    *num = integral ? Polynomial{g.kp, g.ki} : Polynomial{g.kp};
    *den = integral ? Polynomial{1.0, 0.0} : Polynomial{1.0};
  }
  *num = frequency::Trim(*num);
}

bool CountContinuousNyquist(const TransferFunction& tf, const PidGains& g, double delay_s,
                            double points_per_decade, NyquistCount* count, std::string* error) {
  using frequency::Point;
  const frequency::ContinuousResponse r(tf, g, delay_s);
  // The continuous loop's analysis grid: 1e-3 x the slowest to 1e3 x the
  // fastest open-loop feature (as the analysis, AnalysisGrid).
  const std::vector<double> special = frequency::OpenLoopFrequencies(r);
  double lo = frequency::kInf, hi = 0.0;
  for (double w : special) {
    if (!(w > 0.0) || !std::isfinite(w)) continue;
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  const std::vector<double> base = frequency::Grid(1e-3 * lo, 1e3 * hi, points_per_decade, special);
  // Reused per thread: the tuner counts once per evaluation, and a fresh
  // grid of large vectors each time costs more in page faults than the count.
  thread_local std::vector<double> w;
  thread_local std::vector<Point> pts;
  w = base;
  if (delay_s > 0.0) {
    double w_top = 0.0;
    if (!frequency::DelayGrid(r, base, &w, &pts, &w_top, error)) return false;
  } else {
    pts.resize(w.size());
    for (std::size_t i = 0; i < w.size(); ++i) pts[i] = r.At(w[i]);
  }
  *count = frequency::CountEncirclements(r, w, pts);
  return true;
}

}  // namespace pidlab::evaluation
