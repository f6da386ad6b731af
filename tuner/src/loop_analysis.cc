// Loop analysis (loop_analysis.h): frequency responses of S, T and C S on a
// pole-informed log grid, golden-section refinement of every local maximum,
// the Bruinsma-Steinbuch Hamiltonian iteration for the continuous loop,
// crossovers by sign change and bisection.

#include "pidlab/tuner/loop_analysis.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>

#include "golden_section.h"

namespace pidlab {
namespace {

using cd = std::complex<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

Polynomial Trim(Polynomial p) {
  std::size_t i = 0;
  while (i + 1 < p.size() && p[i] == 0.0) ++i;
  p.erase(p.begin(), p.begin() + static_cast<long>(i));
  if (p.empty()) p.push_back(0.0);
  return p;
}

Polynomial Mul(const Polynomial& a, const Polynomial& b) {
  Polynomial r(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return Trim(r);
}

Polynomial Add(const Polynomial& a, const Polynomial& b) {
  const std::size_t n = std::max(a.size(), b.size());
  Polynomial r(n, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) r[n - a.size() + i] += a[i];
  for (std::size_t i = 0; i < b.size(); ++i) r[n - b.size() + i] += b[i];
  return Trim(r);
}

int Degree(const Polynomial& p) {
  const Polynomial t = Trim(p);
  return t.size() == 1 && t[0] == 0.0 ? -1 : static_cast<int>(t.size()) - 1;
}

cd Eval(const Polynomial& p, cd s) {
  cd v = 0.0;
  for (double c : p) v = v * s + c;
  return v;
}

// The loop at one frequency: L = a / b, S = b / (a + b), T = a / (a + b),
// C S = c / (a + b). Non-finite where L has a pole on the axis.
struct Point {
  cd a, b, c;
  bool Finite() const {
    return std::isfinite(std::abs(a)) && std::isfinite(std::abs(b)) && std::isfinite(std::abs(c)) &&
           std::abs(a + b) > 0.0;
  }
};

enum class Peak { kS, kT, kCs };

double Magnitude(const Point& p, Peak which) {
  const cd den = p.a + p.b;
  switch (which) {
    case Peak::kS:
      return std::abs(p.b / den);
    case Peak::kT:
      return std::abs(p.a / den);
    case Peak::kCs:
      return std::abs(p.c / den);
  }
  return kNaN;
}

// The frequency response of one loop, continuous or sampled.
class Response {
 public:
  virtual ~Response() = default;
  virtual Point At(double w) const = 0;
};

class ContinuousResponse : public Response {
 public:
  ContinuousResponse(const TransferFunction& plant, const PidGains& g) {
    ContinuousPidPolynomials(g, &nc_, &dc_);
    ng_ = Trim(plant.num);
    dg_ = Trim(plant.den);
    a_ = Mul(nc_, ng_);
    b_ = Mul(dc_, dg_);
    c_ = Mul(nc_, dg_);
    p_ = Add(a_, b_);
  }
  Point At(double w) const override {
    const cd s(0.0, w);
    return {Eval(a_, s), Eval(b_, s), Eval(c_, s)};
  }
  const Polynomial& a() const { return a_; }
  const Polynomial& b() const { return b_; }
  const Polynomial& c() const { return c_; }
  const Polynomial& p() const { return p_; }
  const Polynomial& controller_num() const { return nc_; }
  // The limit of |x / p| as w -> inf (x of degree <= deg p, else +inf).
  double AtInfinity(const Polynomial& x) const {
    const int dx = Degree(x), dp = Degree(p_);
    if (dx < dp) return 0.0;
    if (dx > dp) return kInf;
    return std::abs(Trim(x)[0] / Trim(p_)[0]);
  }

 private:
  Polynomial nc_, dc_, ng_, dg_, a_, b_, c_, p_;
};

class SampledResponse : public Response {
 public:
  SampledResponse(const DiscretePlant& plant, const PidGains& g, const PidOptions& o)
      : phi_(plant.phi()), gamma_(plant.gamma()), c_(plant.c()), dt_(o.dt_s) {
    // C(z) = kp + I(z) + b (z - 1)/(z - a) over the common denominator.
    const double tf = EffectiveDerivativeFilter(g, o), dt = o.dt_s;
    const double a = tf / (tf + dt), b = g.kd / (tf + dt);
    Polynomial num{g.kp}, den{1.0};
    if (g.ki > 0.0) {
      Polynomial inum;
      switch (o.integral) {
        case IntegralMethod::kBackwardEuler:
          inum = {g.ki * dt, 0.0};
          break;
        case IntegralMethod::kForwardEuler:
          inum = {g.ki * dt};
          break;
        case IntegralMethod::kTrapezoidal:
          inum = {0.5 * g.ki * dt, 0.5 * g.ki * dt};
          break;
      }
      num = Add(Mul(num, {1.0, -1.0}), inum);
      den = {1.0, -1.0};
    }
    if (g.kd > 0.0) {
      num = Add(Mul(num, {1.0, -a}), Mul(Mul({b}, {1.0, -1.0}), den));
      den = Mul(den, {1.0, -a});
    }
    nc_ = num;
    dc_ = den;
  }
  Point At(double w) const override {
    const cd z = std::polar(1.0, w * dt_);
    const int n = static_cast<int>(phi_.rows());
    Eigen::MatrixXcd m = -phi_.cast<cd>();
    for (int i = 0; i < n; ++i) m(i, i) += z;
    const Eigen::VectorXcd x = m.partialPivLu().solve(gamma_.cast<cd>());
    const cd g = (c_.cast<cd>() * x)(0);
    const cd nc = Eval(nc_, z);
    return {nc * g, Eval(dc_, z), nc};
  }
  const Polynomial& controller_num() const { return nc_; }

 private:
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma_;
  Eigen::RowVectorXd c_;
  double dt_;
  Polynomial nc_, dc_;
};

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

// Golden-section search for the maximum of f on [log a, log b].
double GoldenMax(const std::function<double(double)>& f, double a, double b, double* w_best) {
  auto F = [&](double lw) {
    const double v = f(std::exp(lw));
    return std::isfinite(v) ? v : -kInf;
  };
  const double lw = internal::GoldenSectionArgMax(F, std::log(a), std::log(b), 80,
                                                  [](double la, double lb) { return !(lb - la > 1e-13); });
  *w_best = std::exp(lw);
  return F(lw);
}

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

// Root of g on [a, b] (signs differ) by bisection on log w.
double BisectLog(const std::function<double(double)>& g, double a, double b) {
  double la = std::log(a), lb = std::log(b), ga = g(a);
  for (int i = 0; i < 100 && lb - la > 1e-14 * std::max(1.0, std::abs(lb)); ++i) {
    const double lm = 0.5 * (la + lb), gm = g(std::exp(lm));
    if (!std::isfinite(gm)) break;
    if ((gm < 0.0) == (ga < 0.0)) {
      la = lm;
      ga = gm;
    } else {
      lb = lm;
    }
  }
  return std::exp(0.5 * (la + lb));
}

struct Crossings {
  std::vector<double> gain, phase;
};

// Gain crossovers (|L| = 1) and phase crossovers (L real negative).
Crossings FindCrossings(const Response& r, const std::vector<double>& w, const std::vector<Point>& pts) {
  auto log_ratio = [](const Point& p) { return std::log(std::abs(p.a)) - std::log(std::abs(p.b)); };
  auto sin_arg = [](const Point& p) {
    const cd z = p.a * std::conj(p.b);
    return z.imag() / std::abs(z);
  };
  auto at_log = [&](double x) { return log_ratio(r.At(x)); };
  auto at_sin = [&](double x) { return sin_arg(r.At(x)); };
  Crossings c;
  for (std::size_t i = 1; i < w.size(); ++i) {
    const Point& p0 = pts[i - 1];
    const Point& p1 = pts[i];
    const double g0 = log_ratio(p0), g1 = log_ratio(p1);
    if (std::isfinite(g0) && std::isfinite(g1) && (g0 < 0.0) != (g1 < 0.0))
      c.gain.push_back(BisectLog(at_log, w[i - 1], w[i]));
    const double s0 = sin_arg(p0), s1 = sin_arg(p1);
    if (std::isfinite(s0) && std::isfinite(s1) && (s0 < 0.0) != (s1 < 0.0)) {
      const double x = BisectLog(at_sin, w[i - 1], w[i]);
      const Point p = r.At(x);
      const cd z = p.a * std::conj(p.b);
      // L real and negative, finite (not the phase jump at a pole on the axis).
      if (z.real() < 0.0 && std::abs(p.b) > 1e-9 * std::abs(p.a)) c.phase.push_back(x);
    }
  }
  return c;
}

void SetMargins(const Response& r, const Crossings& c, LoopAnalysis* a) {
  a->gain_crossovers_rad_s = c.gain;
  a->phase_crossovers_rad_s = c.phase;
  for (double w : c.gain) {
    const Point p = r.At(w);
    double pm = std::arg(p.a / p.b) + kPi;  // (0, 2 pi]
    if (pm > kPi) pm -= 2.0 * kPi;          // (-pi, pi]
    const double lag = pm > 0.0 ? pm : pm + 2.0 * kPi;
    const double pm_deg = pm * 180.0 / kPi;
    if (pm_deg < a->phase_margin_deg) {
      a->phase_margin_deg = pm_deg;
      a->gain_crossover_rad_s = w;
    }
    a->delay_margin_s = std::min(a->delay_margin_s, lag / w);
  }
  double best = kInf;
  for (double w : c.phase) {
    const Point p = r.At(w);
    const double gm = std::abs(p.b) / std::abs(p.a);
    if (std::abs(std::log(gm)) < best) {
      best = std::abs(std::log(gm));
      a->gain_margin = gm;
      a->phase_crossover_rad_s = w;
    }
  }
  if (c.phase.empty()) a->gain_margin_note = "no phase crossover: infinite gain margin";
  if (c.gain.empty()) a->phase_margin_note = "no gain crossover: infinite phase and delay margins";
}

// s-plane image of a pole or zero of the loop kind.
std::vector<cd> ToS(const std::vector<cd>& roots, LoopKind kind, double dt) {
  if (kind == LoopKind::kContinuous) return roots;
  std::vector<cd> out;
  for (const cd& z : roots)
    if (std::abs(z) > 1e-300) out.push_back(std::log(z) / dt);
  return out;
}

double SlowestTimeConstant(const std::vector<cd>& s_poles) {
  double slowest = kInf;
  for (const cd& p : s_poles) slowest = std::min(slowest, std::abs(p.real()));
  return s_poles.empty() ? kNaN : 1.0 / slowest;
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

// Every frequency a narrow feature can sit at.
std::vector<double> SpecialFrequencies(const std::vector<cd>& roots) {
  std::vector<double> w;
  for (const cd& p : roots) {
    if (std::abs(p) > 0.0 && std::isfinite(std::abs(p))) w.push_back(std::abs(p));
    if (std::abs(p.imag()) > 0.0 && std::isfinite(p.imag())) w.push_back(std::abs(p.imag()));
  }
  return w;
}

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

void ContinuousPidPolynomials(const PidGains& g, Polynomial* num, Polynomial* den) {
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
  *num = Trim(*num);
}

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

bool AnalyzeLoop(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                 const LoopAnalysisOptions& ao, LoopAnalysis* out, std::string* error) {
  if (!GainsAreValid(typed_gains, error) || !options.IsValid(error) || !ao.IsValid(error) ||
      !plant.tf.IsValid(error))
    return false;
  if (plant.tf.RelativeDegree() < 1) {
    if (error) *error = "plant " + plant.tf.ToString() + " must be strictly proper";
    return false;
  }
  const PidGains g = LoopGains(typed_gains, options);
  if (!GainsAreValid(g, error)) return false;
  *out = LoopAnalysis();
  LoopAnalysis& a = *out;
  a.loop = options.loop;
  const bool continuous = options.loop == LoopKind::kContinuous;
  a.method = continuous ? "log grid + closed-loop/open-loop pole and zero frequencies, golden-section "
                          "refinement of every local maximum, Bruinsma-Steinbuch Hamiltonian iteration"
                        : "log grid up to pi/dt + closed-loop pole frequencies, golden-section refinement "
                          "of every local maximum";
  std::vector<cd> s_poles, s_zeros;
  std::unique_ptr<Response> response;
  PidOptions pid = options.Pid();
  std::vector<double> special;
  if (continuous) {
    ContinuousClosedLoop<double> loop;
    if (!BuildContinuousClosedLoop<double>(Realize(plant.tf), g, Disturbance(DisturbanceOptions{}), &loop,
                                           error))
      return false;
    const Stability st = ContinuousStability(loop, options.stability_margin);
    a.stable = st.stable;
    s_poles = st.poles;
    auto r = std::make_unique<ContinuousResponse>(plant.tf, g);
    s_zeros = PolynomialRoots(r->controller_num());
    special = SpecialFrequencies(s_poles);
    for (const auto& v : {PolynomialRoots(r->a()), PolynomialRoots(r->b())})
      for (double w : SpecialFrequencies(v)) special.push_back(w);
    response.reset(r.release());
  } else {
    const DiscretePlant discrete(plant.tf, options.dt_s);
    const Stability st = SampledStability(discrete, g, pid, options.stability_margin);
    a.stable = st.stable;
    s_poles = ToS(st.poles, LoopKind::kSampled, options.dt_s);
    auto r = std::make_unique<SampledResponse>(discrete, g, pid);
    s_zeros = ToS(PolynomialRoots(r->controller_num()), LoopKind::kSampled, options.dt_s);
    special = SpecialFrequencies(s_poles);
    response.reset(r.release());
  }
  a.slowest_time_constant_s = SlowestTimeConstant(s_poles);
  a.cancellations = FindCancellations(s_poles, s_zeros, ao.cancellation_tolerance);
  if (!a.stable) {
    a.gain_margin_note = a.phase_margin_note = a.noise_gain_note = "unstable loop: no margins or peaks";
    a.gain_margin = a.phase_margin_deg = a.delay_margin_s = kNaN;
    return true;
  }
  // Frequency range.
  double lo = kInf, hi = 0.0;
  for (double w : special) {
    if (!(w > 0.0) || !std::isfinite(w)) continue;
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  double w_lo = 1e-3 * lo, w_hi = 1e3 * hi;
  if (!continuous) {
    w_hi = kPi / options.dt_s;
    w_lo = std::min(w_lo, 1e-3 * w_hi);
  }
  const std::vector<double> w = Grid(w_lo, w_hi, ao.points_per_decade, special);
  std::vector<Point> pts(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) pts[i] = response->At(w[i]);
  SetMargins(*response, FindCrossings(*response, w, pts), &a);
  // Peaks on the grid, then the limits w -> 0 and w -> inf (continuous).
  struct Target {
    Peak which;
    double* value;
    double* w;
  };
  const Target targets[] = {{Peak::kS, &a.ms, &a.ms_rad_s},
                            {Peak::kT, &a.mt, &a.mt_rad_s},
                            {Peak::kCs, &a.noise_gain, &a.noise_gain_rad_s}};
  for (const Target& t : targets) {
    *t.value = PeakOnGrid(*response, w, pts, t.which, ao.refine_peaks, -kInf, t.w);
    if (continuous) {
      const auto& r = static_cast<const ContinuousResponse&>(*response);
      const Polynomial& x = t.which == Peak::kS ? r.b() : (t.which == Peak::kT ? r.a() : r.c());
      const double at0 = std::abs(Eval(x, 0.0) / Eval(r.p(), 0.0));
      if (at0 > *t.value) {
        *t.value = at0;
        *t.w = 0.0;
      }
      const double at_inf = r.AtInfinity(x);
      if (at_inf > *t.value) {
        *t.value = at_inf;
        *t.w = kInf;
      }
      if (std::isfinite(*t.value) && ao.hamiltonian_check) {
        double wp = *t.w;
        const double h = HinfNormBruinsmaSteinbuch(x, r.p(), *t.value, *t.w, 1e-7, &wp);
        if (h > *t.value * (1.0 + 1e-6)) {
          *t.value = h;
          *t.w = wp;
        }
      }
    }
  }
  if (std::isinf(a.noise_gain)) {
    a.noise_gain_note = g.kd > 0.0 && !(g.tf > 0.0) ? "ideal derivative: unbounded" : "unbounded";
  }
  return true;
}

bool LoopFrequencyResponse(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                           const std::vector<double>& w_rad_s, std::vector<LoopFrequencyPoint>* response,
                           std::string* error) {
  if (!GainsAreValid(typed_gains, error) || !options.IsValid(error) || !plant.tf.IsValid(error)) return false;
  if (options.loop != LoopKind::kContinuous) {
    if (error) *error = "LoopFrequencyResponse: the loop must be continuous";
    return false;
  }
  const PidGains g = LoopGains(typed_gains, options);
  if (!GainsAreValid(g, error)) return false;
  Polynomial c_num, c_den;
  ContinuousPidPolynomials(g, &c_num, &c_den);
  const Polynomial a = Mul(c_num, plant.tf.num), b = Mul(c_den, plant.tf.den);
  response->clear();
  response->reserve(w_rad_s.size());
  for (const double w : w_rad_s) {
    if (!(std::isfinite(w) && w > 0.0)) {
      if (error) *error = "LoopFrequencyResponse: frequency " + std::to_string(w) + " is not finite and > 0";
      return false;
    }
    const cd av = Eval(a, cd(0.0, w)), bv = Eval(b, cd(0.0, w)), sum = av + bv;
    LoopFrequencyPoint p;
    p.w_rad_s = w;
    p.l = bv == 0.0 ? cd(kInf, 0.0) : av / bv;
    p.s = bv / sum;
    p.t = av / sum;
    response->push_back(p);
  }
  return true;
}

bool LoopBounds::Any() const {
  return std::isfinite(max_ms) || std::isfinite(max_mt) || std::isfinite(max_noise_gain) ||
         min_phase_margin_deg > 0.0 || min_gain_margin > 0.0 || std::isfinite(max_time_constant_s);
}

bool LoopBounds::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(max_ms >= 1.0))
    os << "max Ms " << max_ms << " must be >= 1 (Ms >= 1 for every loop with a strictly proper plant)";
  else if (!(max_mt > 0.0))
    os << "max Mt " << max_mt << " must be positive";
  else if (!(max_noise_gain > 0.0))
    os << "max noise gain " << max_noise_gain << " must be positive";
  else if (!(min_phase_margin_deg >= 0.0) || !(min_phase_margin_deg < 180.0))
    os << "min phase margin " << min_phase_margin_deg << " deg must be in [0, 180)";
  else if (!(min_gain_margin == 0.0 || (min_gain_margin > 1.0 && std::isfinite(min_gain_margin))))
    os << "min gain margin " << min_gain_margin << " must be a factor > 1 (or 0 for none)";
  else if (!(max_time_constant_s > 0.0))
    os << "max time constant " << max_time_constant_s << " s must be positive";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

std::vector<std::string> LoopBoundsViolations(const LoopAnalysis& a, const LoopBounds& b) {
  std::vector<std::string> out;
  auto add = [&](const auto&... parts) {
    std::ostringstream os;
    os.precision(4);
    (os << ... << parts);
    out.push_back(os.str());
  };
  if (!a.stable) {
    add("unstable loop");
    return out;
  }
  if (a.ms > b.max_ms) add("Ms ", a.ms, " > ", b.max_ms);
  if (a.mt > b.max_mt) add("Mt ", a.mt, " > ", b.max_mt);
  if (a.noise_gain > b.max_noise_gain) add("noise gain ", a.noise_gain, " > ", b.max_noise_gain);
  if (a.phase_margin_deg < b.min_phase_margin_deg)
    add("phase margin ", a.phase_margin_deg, " deg < ", b.min_phase_margin_deg);
  if (b.min_gain_margin > 0.0 && std::abs(std::log(a.gain_margin)) < std::log(b.min_gain_margin))
    add("gain margin ", a.gain_margin, " within a factor ", b.min_gain_margin, " of 1");
  if (a.slowest_time_constant_s > b.max_time_constant_s)
    add("time constant ", a.slowest_time_constant_s, " s > ", b.max_time_constant_s);
  return out;
}

std::string LoopBoundsViolation(const LoopAnalysis& a, const LoopBounds& b) {
  const std::vector<std::string> v = LoopBoundsViolations(a, b);
  return v.empty() ? "" : v.front();
}

bool ContinuousLoopMeetsBounds(const TransferFunction& plant, const PidGains& g, const Stability& stability,
                               const LoopBounds& bounds) {
  if (!stability.stable) return false;
  if (SlowestTimeConstant(stability.poles) > bounds.max_time_constant_s) return false;
  const bool ideal_derivative = g.kd > 0.0 && !(g.tf > 0.0);
  if (std::isfinite(bounds.max_noise_gain) && ideal_derivative) return false;  // unbounded
  const ContinuousResponse r(plant, g);
  std::vector<double> special = SpecialFrequencies(stability.poles);
  double lo = kInf, hi = 0.0;
  for (double w : special) {
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  if (!(hi > 0.0)) lo = hi = 1.0;
  // Coarse: 12 points a decade over 1e-2 x slowest .. 1e2 x fastest, plus the
  // closed-loop pole frequencies where a narrow peak would sit.
  const std::vector<double> w = Grid(1e-2 * lo, 1e2 * hi, 12.0, special);
  std::vector<Point> pts(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) pts[i] = r.At(w[i]);
  const std::pair<Peak, double> peaks[] = {
      {Peak::kS, bounds.max_ms}, {Peak::kT, bounds.max_mt}, {Peak::kCs, bounds.max_noise_gain}};
  for (const auto& [which, bound] : peaks) {
    if (!std::isfinite(bound)) continue;
    const Polynomial& x = which == Peak::kS ? r.b() : (which == Peak::kT ? r.a() : r.c());
    if (r.AtInfinity(x) > bound) return false;
    if (std::abs(Eval(x, 0.0) / Eval(r.p(), 0.0)) > bound) return false;
    double wp = 0.0;
    // Refine only the local maxima within 10 % of the bound.
    if (PeakOnGrid(r, w, pts, which, true, bound / 1.1, &wp) > bound) return false;
  }
  if (bounds.min_phase_margin_deg > 0.0 || bounds.min_gain_margin > 0.0) {
    LoopAnalysis a;
    a.stable = true;
    SetMargins(r, FindCrossings(r, w, pts), &a);
    a.slowest_time_constant_s = 0.0;
    a.ms = a.mt = a.noise_gain = 0.0;
    if (!LoopBoundsViolation(a, bounds).empty()) return false;
  }
  return true;
}

}  // namespace pidlab
