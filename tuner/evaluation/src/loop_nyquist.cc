// The continuous loop with dead time (loop_frequency.h, docs/deadtime.md):
// the grid on which e^{-jwL} is resolved, and the Nyquist count of
// encirclements of -1 by L(jw) with the open-loop poles on the imaginary axis
// indented.

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pidlab/evaluation/loop_frequency.h"

namespace pidlab::evaluation::frequency {
namespace {

// The largest turn of e^{-jwL} between neighbours of the delay grid.
constexpr double kMaxDelayTurn = kPi / 16.0;

double LoopGain(const Point& p) { return std::abs(p.a) / std::abs(p.b); }

// Wrapped to (-pi, pi].
double Wrap(double x) {
  x = std::remainder(x, 2.0 * kPi);
  return x <= -kPi ? x + 2.0 * kPi : x;
}

// `base` below w_top filled so that neighbours are at most `step` apart, then
// `base` above it; log points appended when w_top lies beyond base.back().
std::vector<double> FillBelow(const std::vector<double>& base, double w_top, double step) {
  std::vector<double> b = base;
  while (b.back() < w_top) b.push_back(b.back() * std::pow(10.0, 0.01));
  std::vector<double> w{b.front()};
  for (std::size_t i = 1; i < b.size(); ++i) {
    const double lo = b[i - 1], hi = b[i];
    if (lo < w_top && hi - lo > step) {
      const double n = std::ceil((hi - lo) / step);
      for (double k = 1.0; k < n; k += 1.0) w.push_back(lo + (hi - lo) * (k / n));
    }
    w.push_back(hi);
  }
  return w;
}

bool HasPhaseCrossoverBelow(const std::vector<double>& w, const std::vector<Point>& pts, double w_top) {
  for (std::size_t i = 1; i < w.size() && w[i] <= w_top; ++i) {
    const cd z0 = pts[i - 1].a * std::conj(pts[i - 1].b), z1 = pts[i].a * std::conj(pts[i].b);
    if ((z0.imag() < 0.0) != (z1.imag() < 0.0) && (z0.real() < 0.0 || z1.real() < 0.0)) return true;
  }
  return false;
}

// An open-loop pole on the imaginary axis at j w0 (w0 >= 0), of multiplicity m.
struct AxisPole {
  double w0 = 0.0;
  int m = 0;
};

// The open-loop poles (roots of b): the count in the open right half-plane,
// and those on the axis with w0 >= 0 (the origin's exactly, from b's
// trailing zeros; others within 1e-9 |p| of the axis).
int SortOpenLoopPoles(const Polynomial& b_in, std::vector<AxisPole>* axis, int* axis_count) {
  Polynomial b = Trim(b_in);
  int m0 = 0;
  while (b.size() > 1 && b.back() == 0.0) {
    b.pop_back();
    ++m0;
  }
  axis->clear();
  *axis_count = m0;
  if (m0 > 0) axis->push_back({0.0, m0});
  int rhp = 0;
  for (const cd& p : PolynomialRoots(b)) {
    const double tol = 1e-9 * std::max(1.0, std::abs(p));
    if (p.real() > tol) {
      ++rhp;
    } else if (p.real() >= -tol) {
      ++*axis_count;
      if (p.imag() <= 0.0) continue;
      auto same = std::find_if(axis->begin(), axis->end(), [&](const AxisPole& q) {
        return std::abs(q.w0 - p.imag()) <= 1e-6 * p.imag();
      });
      if (same == axis->end())
        axis->push_back({p.imag(), 1});
      else
        ++same->m;
    }
  }
  std::sort(axis->begin(), axis->end(), [](const AxisPole& x, const AxisPole& y) { return x.w0 < y.w0; });
  return rhp;
}

// arg(1 + L) at w; *near_zero when |1 + L| <= 1e-12 (relative to |a| + |b|).
double ArgOnePlusL(const Response& r, double w, bool* near_zero) {
  const Point p = r.At(w);
  const cd num = p.a + p.b;
  if (std::abs(num) <= 1e-12 * (std::abs(p.a) + std::abs(p.b))) *near_zero = true;
  return std::arg(num) - std::arg(p.b);
}

// The continuous change of arg(1 + L) from w0 to w1, bisecting (on log w;
// linearly from w0 = 0) where the wrapped change exceeds pi/4.
double ArgChange(const Response& r, double w0, double w1, double arg0, double arg1, int depth,
                 bool* near_zero) {
  const double d = Wrap(arg1 - arg0);
  if (std::abs(d) < 0.25 * kPi || depth >= 48 || !(w1 > w0)) return d;
  const double wm = w0 > 0.0 ? std::sqrt(w0 * w1) : 0.5 * w1, am = ArgOnePlusL(r, wm, near_zero);
  return ArgChange(r, w0, wm, arg0, am, depth + 1, near_zero) +
         ArgChange(r, wm, w1, am, arg1, depth + 1, near_zero);
}

// The half-width of the semicircle around j w0: small enough that |L| >= 1e3
// at both ends (so that 1 + L turns with L, by -m pi).
double IndentRadius(const Response& r, const AxisPole& pole, double start) {
  double eps = start;
  for (int i = 0; i < 200; ++i, eps *= 0.1) {
    const bool lo_ok = pole.w0 == 0.0 || LoopGain(r.At(pole.w0 - eps)) >= 1e3;
    if (lo_ok && LoopGain(r.At(pole.w0 + eps)) >= 1e3) break;
  }
  return eps;
}

// The change of arg(1 + L) on the semicircle around j w0 from arg_lo (below)
// to arg_hi (above): -m pi, corrected by the wrapped difference of its ends.
double IndentChange(const AxisPole& pole, double arg_lo, double arg_hi) {
  const double turn = -pole.m * kPi;
  return turn + Wrap(arg_hi - arg_lo - turn);
}

// q(p) = x(p + sigma), descending powers (repeated synthetic division).
Polynomial TaylorShift(Polynomial x, double sigma) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i + 1 < n; ++i)
    for (std::size_t j = 1; j < n - i; ++j) x[j] += sigma * x[j - 1];
  return x;
}

}  // namespace

double LineClearOfPoles(const std::vector<cd>& poles, double sigma) {
  for (int pass = 0; pass < 8; ++pass) {
    bool moved = false;
    for (const cd& p : poles) {
      const double gap = kLineGapFromPoles * std::max(1.0, std::abs(p));
      if (std::abs(sigma - p.real()) < gap) {
        sigma = p.real() - gap;
        moved = true;
      }
    }
    if (!moved) break;
  }
  return sigma;
}

ContinuousResponse ContinuousResponse::Shifted(double sigma) const {
  ContinuousResponse r = *this;
  const double gain = delay_ > 0.0 ? std::exp(-sigma * delay_) : 1.0;
  r.nc_ = TaylorShift(nc_, sigma);
  r.dc_ = TaylorShift(dc_, sigma);
  r.ng_ = TaylorShift(ng_, sigma);
  r.dg_ = TaylorShift(dg_, sigma);
  r.a_ = TaylorShift(a_, sigma);
  for (double& x : r.a_) x *= gain;
  r.b_ = TaylorShift(b_, sigma);
  r.c_ = TaylorShift(c_, sigma);
  r.p_ = Add(r.a_, r.b_);
  return r;
}

namespace {

// DelayGrid() with the refusal's message in *error.
bool DelayGridOrExplain(const ContinuousResponse& r, const std::vector<double>& base, std::vector<double>* w,
                        std::vector<Point>* pts, double* w_top, std::string* error) {
  const double delay = r.delay(), step = kMaxDelayTurn / delay;
  std::size_t last = 0;
  for (std::size_t i = 0; i < base.size(); ++i)
    if (!(LoopGain(r.At(base[i])) < kSmallLoopGain)) last = i;
  *w_top = std::max(base[std::min(last + 1, base.size() - 1)], 4.0 * kPi / delay);
  for (int attempt = 0; attempt < 60; ++attempt, *w_top *= 2.0) {
    if (*w_top / step > static_cast<double>(kMaxDelayGridPoints)) break;
    *w = FillBelow(base, *w_top, step);
    pts->resize(w->size());
    for (std::size_t i = 0; i < w->size(); ++i) (*pts)[i] = r.At((*w)[i]);
    if (HasPhaseCrossoverBelow(*w, *pts, *w_top)) return true;
  }
  if (error) {
    std::ostringstream os;
    os << "dead time " << delay << " s: the loop's gain stays above " << kSmallLoopGain << " up to " << *w_top
       << " rad/s, more than " << kMaxDelayGridPoints
       << " points to resolve e^(-jwL) (delay too long for the "
       << "loop's bandwidth)";
    *error = os.str();
  }
  return false;
}

}  // namespace

Status DelayGrid(const ContinuousResponse& r, const std::vector<double>& base, std::vector<double>* w,
                 std::vector<Point>* pts, double* w_top) {
  std::string why;
  if (!DelayGridOrExplain(r, base, w, pts, w_top, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

NyquistCount CountEncirclements(const ContinuousResponse& r, const std::vector<double>& w,
                                const std::vector<Point>& pts) {
  NyquistCount n;
  std::vector<AxisPole> axis;
  n.open_loop_rhp_poles = SortOpenLoopPoles(r.b(), &axis, &n.open_loop_axis_poles);
  bool near_zero = false;
  double total = 0.0, w_prev = w.front(), arg_prev = ArgOnePlusL(r, w_prev, &near_zero);
  std::size_t next_pole = 0;
  if (!axis.empty() && axis[0].w0 == 0.0) {
    // The semicircle at the origin counts once; w from -eps to eps.
    const double eps = IndentRadius(r, axis[0], w.front());
    const double a_eps = ArgOnePlusL(r, eps, &near_zero);
    total += IndentChange(axis[0], -a_eps, a_eps);
    total += 2.0 * ArgChange(r, eps, w_prev, a_eps, arg_prev, 0, &near_zero);
    next_pole = 1;
  } else {
    // From w = 0 (1 + L real there) to the grid's first point, taken twice: a
    // closed-loop root near the contour at w = 0 (a shifted line's) turns the
    // arg below the grid.
    const double a_0 = ArgOnePlusL(r, 0.0, &near_zero);
    total += 2.0 * ArgChange(r, 0.0, w_prev, a_0, arg_prev, 0, &near_zero);
  }
  std::vector<double> radius(axis.size(), 0.0);
  for (std::size_t k = next_pole; k < axis.size(); ++k)
    radius[k] = IndentRadius(r, axis[k], 1e-6 * axis[k].w0);
  for (std::size_t i = 1; i < w.size(); ++i) {
    // A grid point within the semicircle's radius (where arg b is mostly
    // rounding) is passed over: the semicircle is taken first.
    while (next_pole < axis.size() && axis[next_pole].w0 - radius[next_pole] <= w[i]) {
      const double eps = radius[next_pole];
      const AxisPole& pole = axis[next_pole++];
      if (pole.w0 - eps <= w_prev) continue;  // below the grid: not reachable here
      const double a_lo = ArgOnePlusL(r, pole.w0 - eps, &near_zero);
      const double a_hi = ArgOnePlusL(r, pole.w0 + eps, &near_zero);
      total += 2.0 * (ArgChange(r, w_prev, pole.w0 - eps, arg_prev, a_lo, 0, &near_zero) +
                      IndentChange(pole, a_lo, a_hi));
      w_prev = pole.w0 + eps;
      arg_prev = a_hi;
    }
    if (!(w[i] > w_prev) || !pts[i].Finite()) continue;
    const double a_i = std::arg(pts[i].a + pts[i].b) - std::arg(pts[i].b);
    total += 2.0 * ArgChange(r, w_prev, w[i], arg_prev, a_i, 0, &near_zero);
    w_prev = w[i];
    arg_prev = a_i;
  }
  // Beyond the grid |L| < 1: 1 + L stays in Re > 0 up to w = inf, over the
  // large semicircle and back down to -w_prev, so its arg ends at -arg_prev.
  const double l_end = LoopGain(r.At(w_prev));
  total += -2.0 * Wrap(arg_prev);
  n.winding_turns = total / (2.0 * kPi);
  n.encirclements = -static_cast<int>(std::lround(n.winding_turns));
  n.closed_loop_rhp_poles = n.encirclements + n.open_loop_rhp_poles;
  n.decided = !near_zero && std::abs(n.winding_turns + n.encirclements) < 0.1 && l_end < 1.0;
  n.stable = n.decided && n.closed_loop_rhp_poles == 0;
  std::ostringstream os;
  os << "Nyquist: P = " << n.open_loop_rhp_poles << " open-loop right-half-plane poles, "
     << n.open_loop_axis_poles << " on the axis (indented), N = " << n.encirclements
     << " clockwise encirclements of -1, Z = N + P = " << n.closed_loop_rhp_poles;
  if (near_zero) os << "; L(jw) passes within 1e-12 of -1 (marginal): undecided";
  if (!(l_end < 1.0)) os << "; |L| >= 1 at the grid's end (" << l_end << "): undecided";
  n.note = os.str();
  return n;
}

}  // namespace pidlab::evaluation::frequency

namespace pidlab::evaluation {

Status CountContinuousRootsRightOf(const TransferFunction& tf, const PidGains& g, double delay_s,
                                   double sigma, double points_per_decade, NyquistCount* count) {
  const frequency::ContinuousResponse r(tf, g, delay_s);
  if (sigma != 0.0) sigma = frequency::LineClearOfPoles(PolynomialRoots(r.b()), sigma);
  thread_local std::vector<double> w;
  thread_local std::vector<frequency::Point> pts;
  return frequency::CountOnAnalysisGrid(sigma == 0.0 ? r : r.Shifted(sigma), points_per_decade, &w, &pts,
                                        count);
}

}  // namespace pidlab::evaluation
