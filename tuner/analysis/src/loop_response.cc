// The loop's frequency response searched (loop_response.h): peaks of S, T and
// C S on a pole-informed log grid with golden-section refinement of every
// local maximum, and the Bruinsma-Steinbuch Hamiltonian iteration for the
// H-infinity norm of the continuous loop.

#include "loop_response.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "pidlab/optim/golden_section.h"

namespace pidlab::analysis {
namespace loop_internal {
namespace {

// Golden-section search for the maximum of f on [log a, log b].
double GoldenMax(const std::function<double(double)>& f, double a, double b, double* w_best) {
  auto F = [&](double lw) {
    const double v = f(std::exp(lw));
    return std::isfinite(v) ? v : -kInf;
  };
  const double lw = optim::GoldenSectionArgMax(F, std::log(a), std::log(b), 80,
                                               [](double la, double lb) { return !(lb - la > 1e-13); });
  *w_best = std::exp(lw);
  return F(lw);
}

}  // namespace

// The grid's largest value, refined at every local maximum when `refine`
// (only at those above `refine_above`).
double PeakOnGrid(const Response& r, const std::vector<double>& w, const std::vector<Point>& pts, Peak which,
                  bool refine, double refine_above, double* w_peak) {
  std::vector<double> f(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) f[i] = pts[i].Finite() ? Magnitude(pts[i], which) : -kInf;
  double best = -kInf;
  for (std::size_t i = 0; i < w.size(); ++i)
    if (f[i] > best) {
      best = f[i];
      *w_peak = w[i];
    }
  if (!refine) return best;
  auto mag = [&](double x) {
    const Point p = r.At(x);
    return p.Finite() ? Magnitude(p, which) : -kInf;
  };
  // Strict local maxima (a plateau counts once), the largest kMaxRefined of them.
  std::vector<std::size_t> maxima;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const bool left = i == 0 || f[i] > f[i - 1];
    const bool right = i + 1 == w.size() || f[i] >= f[i + 1];
    if (left && right && f[i] > refine_above) maxima.push_back(i);
  }
  constexpr std::size_t kMaxRefined = 12;
  if (maxima.size() > kMaxRefined) {
    std::partial_sort(maxima.begin(), maxima.begin() + kMaxRefined, maxima.end(),
                      [&](std::size_t x, std::size_t y) { return f[x] > f[y]; });
    maxima.resize(kMaxRefined);
  }
  for (const std::size_t i : maxima) {
    const double a = i == 0 ? w[0] : w[i - 1], b = i + 1 == w.size() ? w[i] : w[i + 1];
    if (!(b > a)) continue;
    double wb = w[i];
    const double v = GoldenMax(mag, a, b, &wb);
    if (v > best) {
      best = v;
      *w_peak = wb;
    }
  }
  return best;
}

// Every frequency a narrow feature can sit at.
}  // namespace loop_internal

namespace {

using loop_internal::cd;
using loop_internal::Degree;
using loop_internal::Eval;
using loop_internal::kInf;
using loop_internal::Trim;

// Controllable canonical realisation of num/den (deg num <= deg den, den of
// degree >= 1), balanced: x' = A x + B u, y = C x + D u.
void RealizeRatio(const Polynomial& num_in, const Polynomial& den_in, Eigen::MatrixXd* a, Eigen::VectorXd* b,
                  Eigen::RowVectorXd* c, double* d) {
  const Polynomial den = Trim(den_in);
  const int n = static_cast<int>(den.size()) - 1;
  Polynomial num = Trim(num_in);
  const double lead = den[0];
  Polynomial pd(den.size()), pn(den.size(), 0.0);
  for (std::size_t i = 0; i < den.size(); ++i) pd[i] = den[i] / lead;
  for (std::size_t i = 0; i < num.size(); ++i) pn[den.size() - num.size() + i] = num[i] / lead;
  *d = pn[0];
  *a = Eigen::MatrixXd::Zero(n, n);
  *b = Eigen::VectorXd::Zero(n);
  *c = Eigen::RowVectorXd::Zero(n);
  for (int j = 0; j < n; ++j) {
    (*a)(0, j) = -pd[static_cast<std::size_t>(j) + 1];
    (*c)(j) = pn[static_cast<std::size_t>(j) + 1] - *d * pd[static_cast<std::size_t>(j) + 1];
  }
  for (int i = 1; i < n; ++i) (*a)(i, i - 1) = 1.0;
  (*b)(0) = 1.0;
  const Eigen::VectorXd scale = BalanceInPlace(a);
  for (int i = 0; i < n; ++i) {
    (*b)(i) /= scale(i);
    (*c)(i) *= scale(i);
  }
}

}  // namespace

double HinfNormBruinsmaSteinbuch(const Polynomial& num, const Polynomial& den, double gamma_lower,
                                 double w_lower, double tol, double* w_peak) {
  *w_peak = w_lower;
  if (Degree(den) < 1) return gamma_lower;
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
  RealizeRatio(num, den, &a, &b, &c, &d);
  const int n = static_cast<int>(a.rows());
  auto gain = [&](double w) { return std::abs(Eval(num, cd(0.0, w)) / Eval(den, cd(0.0, w))); };
  double lb = std::max(gamma_lower, std::abs(d));
  if (std::abs(d) > gamma_lower) *w_peak = kInf;
  const double at0 = gain(0.0);
  if (std::isfinite(at0) && at0 > lb) {
    lb = at0;
    *w_peak = 0.0;
  }
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double gamma = (1.0 + 2.0 * tol) * lb;
    // H = [A - B d C / R, -gamma B B' / R; gamma C' C / R, -A' + C' d B' / R],
    // R = d^2 - gamma^2: an eigenvalue j w <=> gamma is a singular value of G(j w).
    const double r = d * d - gamma * gamma;
    Eigen::MatrixXd h(2 * n, 2 * n);
    h.topLeftCorner(n, n) = a - b * (d / r) * c;
    h.topRightCorner(n, n) = -(gamma / r) * b * b.transpose();
    h.bottomLeftCorner(n, n) = (gamma / r) * c.transpose() * c;
    h.bottomRightCorner(n, n) = -a.transpose() + c.transpose() * (d / r) * b.transpose();
    Eigen::EigenSolver<Eigen::MatrixXd> es(h, false);
    if (es.info() != Eigen::Success) break;
    std::vector<double> ws;
    for (int i = 0; i < 2 * n; ++i) {
      const cd l = es.eigenvalues()(i);
      if (l.imag() > 0.0 && std::abs(l.real()) <= 1e-8 * std::max(1.0, std::abs(l))) ws.push_back(l.imag());
    }
    if (ws.empty()) break;
    std::sort(ws.begin(), ws.end());
    // |G| > gamma between consecutive crossings; an odd count means the
    // first interval starts at w = 0 (or the last one runs to infinity).
    if (ws.size() % 2 == 1) ws.insert(ws.begin(), 0.0);
    double best = lb;
    auto probe = [&](double w) {
      const double v = gain(w);
      if (v > best) {
        best = v;
        *w_peak = w;
      }
    };
    for (std::size_t i = 1; i < ws.size(); i += 2) probe(0.5 * (ws[i - 1] + ws[i]));
    if (!(best > lb)) break;
    lb = best;
  }
  return lb;
}

}  // namespace pidlab::analysis
