// The continuous loop's frequency response (loop_frequency.h): the PID's
// polynomials, the analysis grid of the continuous loop, and the Nyquist
// count of the loop with its dead time.

#include "pidlab/evaluation/loop_frequency.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

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
  const bool d = g.kd != 0.0, filtered = d && g.tf > 0.0, integral = g.ki != 0.0;
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

Status CountContinuousNyquist(const TransferFunction& tf, const PidGains& g, double delay_s,
                              double points_per_decade, NyquistCount* count) {
  // Reused per thread: the tuner counts once per evaluation, and a fresh
  // grid of large vectors each time costs more in page faults than the count.
  thread_local std::vector<double> w;
  thread_local std::vector<frequency::Point> pts;
  return frequency::CountOnAnalysisGrid(frequency::ContinuousResponse(tf, g, delay_s), points_per_decade, &w,
                                        &pts, count);
}

namespace frequency {

namespace {

// CountOnAnalysisGrid() with the refusal's message in *error.
bool CountOnAnalysisGridOrExplain(const ContinuousResponse& r, double per_decade, std::vector<double>* w,
                                  std::vector<Point>* pts, NyquistCount* count, std::string* error) {
  // The continuous loop's analysis grid: 1e-3 x the slowest to 1e3 x the
  // fastest open-loop feature (as the analysis, AnalysisGrid).
  const std::vector<double> special = OpenLoopFrequencies(r);
  double lo = kInf, hi = 0.0;
  for (double x : special) {
    if (!(x > 0.0) || !std::isfinite(x)) continue;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  const std::vector<double> base = Grid(1e-3 * lo, 1e3 * hi, per_decade, special);
  *w = base;
  if (r.delay() > 0.0) {
    double w_top = 0.0;
    if (const Status st = DelayGrid(r, base, w, pts, &w_top); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
  } else {
    pts->resize(w->size());
    for (std::size_t i = 0; i < w->size(); ++i) (*pts)[i] = r.At((*w)[i]);
  }
  *count = CountEncirclements(r, *w, *pts);
  return true;
}

}  // namespace

Status CountOnAnalysisGrid(const ContinuousResponse& r, double per_decade, std::vector<double>* w,
                           std::vector<Point>* pts, NyquistCount* count) {
  std::string why;
  if (!CountOnAnalysisGridOrExplain(r, per_decade, w, pts, count, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace frequency
namespace {

using frequency::cd;
using frequency::kNaN;
using frequency::Polynomial;

// The strip [lo, hi] that holds alpha is narrowed to this fraction of |hi|.
constexpr double kStripFraction = 1e-7;
// Newton's polish from this many of the best points on the strip's line.
constexpr std::size_t kNewtonStarts = 6;
// The certified guess's strip, as a fraction of |alpha|: within the
// bisection's kStripFraction.
constexpr double kGuessStrip = 0.4 * kStripFraction;

Polynomial Derivative(const Polynomial& p) {
  Polynomial d;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) d.push_back(p[i] * static_cast<double>(p.size() - 1 - i));
  if (d.empty()) d.push_back(0.0);
  return d;
}

// The characteristic function f(s) = b(s) + a(s) e^{-sL} (L = a/b) and f'.
struct Characteristic {
  Polynomial a, b, da, db;
  double delay = 0.0;
  cd F(cd s) const { return frequency::Eval(b, s) + frequency::Eval(a, s) * std::exp(-s * delay); }
  cd DF(cd s) const {
    return frequency::Eval(db, s) +
           (frequency::Eval(da, s) - delay * frequency::Eval(a, s)) * std::exp(-s * delay);
  }
};

// Newton from s: the root (Im >= 0), or NaN when 60 steps do not converge.
cd NewtonRoot(const Characteristic& f, cd s) {
  for (int i = 0; i < 60; ++i) {
    const cd d = f.F(s) / f.DF(s);
    if (!std::isfinite(std::abs(d))) break;
    s -= d;
    if (std::abs(d) <= 1e-14 * std::max(1.0, std::abs(s))) return s.imag() < 0.0 ? std::conj(s) : s;
  }
  return {kNaN, kNaN};
}

// One shifted count on the line *sigma (moved clear of the open-loop poles):
// the roots right of it, or -1 with *why when the count fails or does not
// decide.
int RootsRightOf(const frequency::ContinuousResponse& r, const std::vector<cd>& poles, double per_decade,
                 double* sigma, std::vector<double>* w, std::vector<frequency::Point>* pts, int* counts,
                 std::string* why) {
  *sigma = frequency::LineClearOfPoles(poles, *sigma);
  NyquistCount n;
  ++*counts;
  if (const Status st = frequency::CountOnAnalysisGrid(r.Shifted(*sigma), per_decade, w, pts, &n); !st.ok()) {
    *why = st.message();
    return -1;
  }
  if (n.decided) return n.closed_loop_rhp_poles;
  std::ostringstream os;
  os << "the count on the line Re s = " << *sigma << " does not decide (" << n.note << ")";
  *why = os.str();
  return -1;
}

// The smallest positive open-loop frequency of r (its poles', zeros' and 1/L).
double SlowestFeature(const frequency::ContinuousResponse& r) {
  double lo = frequency::kInf;
  for (double x : frequency::OpenLoopFrequencies(r))
    if (x > 0.0 && std::isfinite(x)) lo = std::min(lo, x);
  return lo;
}

// The frequencies of the kNewtonStarts best local minima of |1 + L| on a
// line's grid (w, pts), 0 first.
std::vector<double> BestMinima(const std::vector<double>& w, const std::vector<frequency::Point>& pts) {
  auto residual = [&](std::size_t i) {
    return std::abs(pts[i].a + pts[i].b) / (std::abs(pts[i].a) + std::abs(pts[i].b));
  };
  std::vector<std::pair<double, double>> minima{{0.0, 0.0}};  // (residual, w); w = 0 always tried
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double ri = residual(i);
    if ((i == 0 || ri <= residual(i - 1)) && (i + 1 == w.size() || ri <= residual(i + 1)) &&
        std::isfinite(ri))
      minima.push_back({ri, w[i]});
  }
  std::sort(minima.begin() + 1, minima.end());
  if (minima.size() > kNewtonStarts) minima.resize(kNewtonStarts);
  std::vector<double> starts;
  for (const auto& m : minima) starts.push_back(m.second);
  return starts;
}

// Newton from the best local minima of |1 + L| on the line of the strip's
// middle (its grid w, pts): the rightmost root found inside [lo, hi], widened
// by the polish's own tolerance, into *out.
void Polish(const frequency::ContinuousResponse& r, double lo, double hi, const std::vector<double>& w,
            const std::vector<frequency::Point>& pts, SpectralAbscissa* out) {
  const Characteristic f{r.a(), r.b(), Derivative(r.a()), Derivative(r.b()), r.delay()};
  const double mid = 0.5 * (lo + hi), slack = hi - lo + 1e-12 * std::max(1.0, std::abs(hi));
  for (double wi : BestMinima(w, pts)) {
    const cd root = NewtonRoot(f, cd(mid, wi));
    if (!(root.real() >= lo - slack && root.real() <= hi + slack)) continue;
    if (!out->polished || root.real() > out->alpha) {
      out->polished = true;
      out->alpha = root.real();
      out->root = root;
    }
  }
}

// A guess at alpha from the stable side: Newton from the best local minima
// of |1 + L| on the line Re s = sigma (its grid w, pts), the rightmost root
// found left of the line (Im >= 0). False when no start converges.
bool GuessRightmost(const frequency::ContinuousResponse& r, double sigma, const std::vector<double>& w,
                    const std::vector<frequency::Point>& pts, cd* rightmost) {
  const Characteristic f{r.a(), r.b(), Derivative(r.a()), Derivative(r.b()), r.delay()};
  bool found = false;
  for (double wi : BestMinima(w, pts)) {
    const cd root = NewtonRoot(f, cd(sigma, wi));
    if (root.real() < sigma && (!found || root.real() > rightmost->real())) *rightmost = root, found = true;
  }
  return found;
}

}  // namespace

namespace {

// ContinuousSpectralAbscissa() with the refusal's message in *error.
bool ContinuousSpectralAbscissaOrExplain(const TransferFunction& tf, const PidGains& g, double delay_s,
                                         double points_per_decade, SpectralAbscissa* out,
                                         std::string* error) {
  *out = SpectralAbscissa();
  if (!(delay_s > 0.0) || !std::isfinite(delay_s) || !(points_per_decade > 0.0)) {
    if (error) *error = "the spectral abscissa needs a dead time > 0 and a grid density > 0";
    return false;
  }
  const frequency::ContinuousResponse r(tf, g, delay_s);
  if (frequency::Degree(r.a()) >= frequency::Degree(r.b())) {
    out->note =
        "neutral loop: its roots crowd towards a vertical line, the spectral abscissa is not computed";
    return true;
  }
  const std::vector<cd> poles = PolynomialRoots(r.b());
  thread_local std::vector<double> w;
  thread_local std::vector<frequency::Point> pts;
  // Left from the stable loop's line Re s = 0 by doublings until a root lies
  // right of the line, then bisection of the strip (unless a guess is
  // certified first).
  const double start = 1e-3 * SlowestFeature(r);
  double hi = 0.0, lo = -start;
  std::string why;
  // First a guess, certified by two counts: no root right of guess + d and
  // one right of guess - d, d = kGuessStrip |guess|. The strip then needs no
  // bisection; where either count does not confirm it, the walk below runs
  // from the start.
  {
    double line = -start;
    cd guess;
    if (RootsRightOf(r, poles, points_per_decade, &line, &w, &pts, &out->counts, &why) == 0 &&
        GuessRightmost(r, line, w, pts, &guess)) {
      const double d = kGuessStrip * std::abs(guess.real());
      double right = guess.real() + d, left = guess.real() - d;
      if (right < line &&
          RootsRightOf(r, poles, points_per_decade, &right, &w, &pts, &out->counts, &why) == 0 &&
          RootsRightOf(r, poles, points_per_decade, &left, &w, &pts, &out->counts, &why) > 0 &&
          left < guess.real() && guess.real() < right && right < line) {
        // The guess is a root (Newton's), inside the strip that holds alpha.
        out->strip_width = right - left;
        out->polished = true;
        out->alpha = guess.real();
        out->root = guess;
        out->found = true;
        return true;
      }
    }
    why.clear();
  }
  for (int k = 0;; ++k, lo *= 2.0) {
    const int z = k < 200 ? RootsRightOf(r, poles, points_per_decade, &lo, &w, &pts, &out->counts, &why) : -1;
    if (z < 0) {
      out->note = "spectral abscissa not computed: " + (k < 200 ? why : std::string("no root found"));
      return true;
    }
    if (z > 0) break;
    hi = lo;
  }
  // (A root within rounding of 0, alpha = -1e-300, stops at the floor.)
  for (int k = 0; k < 200 && hi - lo > std::max(kStripFraction * std::abs(hi), 1e-15 * start); ++k) {
    double mid = 0.5 * (lo + hi);
    const int z = RootsRightOf(r, poles, points_per_decade, &mid, &w, &pts, &out->counts, &why);
    if (z < 0 || !(mid > lo && mid < hi)) break;
    (z > 0 ? lo : hi) = mid;
  }
  out->strip_width = hi - lo;
  double mid = 0.5 * (lo + hi);
  if (RootsRightOf(r, poles, points_per_decade, &mid, &w, &pts, &out->counts, &why) >= 0)
    Polish(r, lo, hi, w, pts, out);
  if (!out->polished) {
    out->alpha = hi;  // the strip's right edge: no root lies right of it
    std::ostringstream os;
    os << "rightmost root not polished by Newton: alpha is the strip's right edge, within "
       << out->strip_width << " 1/s" << (why.empty() ? "" : " (" + why + ")");
    out->note = os.str();
  }
  out->found = true;
  return true;
}

}  // namespace

namespace {

// The last answers of ContinuousSpectralAbscissa on this thread: a pure
// function of its inputs, asked for the same loop by the time scale, the
// evaluation's analysis and the figure's frame of one request (each about
// 15 ms with dead time). A hit compares every input bit for bit, so the
// answer is the one a new computation gives.
struct AbscissaMemo {
  struct Entry {
    std::vector<double> key;
    Status status;
    SpectralAbscissa result;
  };
  static constexpr std::size_t kEntries = 4;
  std::vector<Entry> entries;  // the newest last

  static std::vector<double> Key(const TransferFunction& tf, const PidGains& g, double delay_s,
                                 double points_per_decade) {
    std::vector<double> k = {
        static_cast<double>(tf.num.size()), delay_s, points_per_decade, g.kp, g.ki, g.kd, g.tf};
    k.insert(k.end(), tf.num.begin(), tf.num.end());
    k.insert(k.end(), tf.den.begin(), tf.den.end());
    return k;
  }
  static bool Same(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
  }
};

}  // namespace

Status ContinuousSpectralAbscissa(const TransferFunction& tf, const PidGains& g, double delay_s,
                                  double points_per_decade, SpectralAbscissa* out) {
  thread_local AbscissaMemo memo;
  std::vector<double> key = AbscissaMemo::Key(tf, g, delay_s, points_per_decade);
  for (const AbscissaMemo::Entry& e : memo.entries)
    if (AbscissaMemo::Same(e.key, key)) {
      *out = e.result;
      return e.status;
    }
  std::string why;
  const Status status = ContinuousSpectralAbscissaOrExplain(tf, g, delay_s, points_per_decade, out, &why)
                            ? Status::Ok()
                            : Status::InvalidInput(why);
  if (memo.entries.size() == AbscissaMemo::kEntries) memo.entries.erase(memo.entries.begin());
  memo.entries.push_back({std::move(key), status, *out});
  return status;
}

}  // namespace pidlab::evaluation
