// The continuous-loop objective on fixed-size matrices (fast_objective.h).

#include "pidlab/evaluation/fast_objective.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "evaluation_internal.h"

namespace pidlab::evaluation {
namespace {

using internal::kInf;
constexpr int kMaxDegree = 15;

template <int L>
using Mat = Eigen::Matrix<double, L, L>;
template <int L>
using Vec = Eigen::Matrix<double, L, 1>;

// v -> a v + b: the loop's map over one sample on v = [x; z] with the
// reference r held (r' = 0, so exp of the loop matrix [[F, g], [0, 0]] keeps
// the form [[a, b], [0, 1]] and the products below are its blocks).
template <int V>
struct Affine {
  Mat<V> a;
  Vec<V> b;
};

// MatrixExp<double> of [[f, g], [0, 0]] on its blocks: the same scaling and
// squaring of the same truncated Taylor series (same norm, squarings and
// number of terms; the zero row adds only exact zeros), so the same result
// to rounding.
template <int V>
Affine<V> AffineExp(const Mat<V>& f, const Vec<V>& g) {
  double norm = 0.0;
  for (int i = 0; i < V; ++i) {
    double row = 0.0;
    for (int j = 0; j < V; ++j) row += std::abs(f(i, j));
    row += std::abs(g(i));
    norm = std::max(norm, row);
  }
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::min(1100.0, std::ceil(std::log2(norm / 0.5))));
  const double scale = std::ldexp(1.0, -squarings);
  const Mat<V> scaled_f = f * scale;
  const Vec<V> scaled_g = g * scale;
  Affine<V> result{Mat<V>::Identity(), Vec<V>::Zero()};
  Mat<V> term = Mat<V>::Identity();  // the [x; z] block of the k-th term
  double term_bound = 1.0;
  const double scaled_norm = norm * scale;
  for (int k = 1; k <= 30; ++k) {
    // [[T, t], [0, 0 or 1]] [[F, G], [0, 0]] = [[T F, T G], [0, 0]].
    const Vec<V> term_g = (term * scaled_g) * (1.0 / k);
    term = (term * scaled_f) * (1.0 / k);
    result.a += term;
    result.b += term_g;
    term_bound *= scaled_norm / k;
    if (term_bound < 1e-17) break;
  }
  for (int s = 0; s < squarings; ++s) {
    result.b = (result.a * result.b + result.b).eval();
    result.a = (result.a * result.a).eval();
  }
  return result;
}

// Samples per block of the output recursion.
constexpr int kBlock = 8;

// Error of one sample as the objective sums it (ObjectiveFromSamples).
template <ObjectiveKind K, typename E, typename Tm>
auto Term(const E& e, const Tm& t) {
  if constexpr (K == ObjectiveKind::kIse)
    return e * e;
  else if constexpr (K == ObjectiveKind::kItae)
    return t * e.abs();
  else
    return e.abs();
}

// The sum over m < num_samples of the objective's term of e_m = reference -
// c v_m, v_{m+1} = step.a v_m + step.b. That recursion is a chain of
// dependent products; in blocks of kBlock samples y_{k+j} = c a^j v_k + d_j
// are independent dot products, and the chain advances by the map of
// kBlock samples, kBlock times fewer links.
template <int V, ObjectiveKind K>
double SumOfErrors(const Affine<V>& step, const Eigen::Matrix<double, 1, V>& c, Vec<V> v, double reference,
                   double ts, int num_samples) {
  using Block = Eigen::Array<double, kBlock, 1>;
  Eigen::Matrix<double, kBlock, V> rows;  // c a^j
  Block offsets_y;                        // c (a^(j-1) b + ... + b)
  Eigen::Matrix<double, 1, V> row = c;
  Vec<V> s = Vec<V>::Zero();
  for (int j = 0; j < kBlock; ++j) {
    rows.row(j) = row;
    offsets_y(j) = c.dot(s);
    row = (row * step.a).eval();
    s = (step.a * s + step.b).eval();
  }
  Affine<V> block = step;
  for (int n = 1; n < kBlock; n *= 2) block = {block.a * block.a, block.a * block.b + block.b};
  const Block offsets_t = Block::LinSpaced(kBlock, 0.0, kBlock - 1.0);
  Block sum = Block::Zero();
  int k = 0;
  for (; k + kBlock <= num_samples; k += kBlock) {
    const Block e = (reference - offsets_y) - (rows * v).array();
    sum += Term<K>(e, (offsets_t + static_cast<double>(k)) * ts);
    v = (block.a * v + block.b).eval();
  }
  const Block e = (reference - offsets_y) - (rows * v).array();
  const Block tail = Term<K>(e, (offsets_t + static_cast<double>(k)) * ts);
  double total = sum.sum();
  for (int j = 0; j < num_samples - k; ++j) total += tail(j);
  return std::isfinite(total) ? total : kInf;
}

}  // namespace

bool IsHurwitz(const double* p, int degree) {
  if (degree < 0 || degree > kMaxDegree || !(p[0] != 0.0) || !std::isfinite(p[0])) return false;
  const double sign = p[0] > 0.0 ? 1.0 : -1.0;
  // Two rows of Routh's array, padded with zeros.
  double upper[kMaxDegree / 2 + 2] = {}, lower[kMaxDegree / 2 + 2] = {};
  const int width = degree / 2 + 1;
  for (int i = 0; i < width; ++i) {
    upper[i] = 2 * i <= degree ? sign * p[2 * i] : 0.0;
    lower[i] = 2 * i + 1 <= degree ? sign * p[2 * i + 1] : 0.0;
  }
  for (int row = 1; row <= degree; ++row) {
    if (!(lower[0] > 0.0) || !std::isfinite(lower[0])) return false;
    const double ratio = upper[0] / lower[0];
    for (int i = 0; i < width; ++i) {
      const double next = upper[i + 1] - ratio * lower[i + 1];
      upper[i] = lower[i];
      lower[i] = next;
    }
  }
  return true;
}

void ShiftPolynomial(double h, double* p, int degree) {
  // Repeated synthetic division (Horner's scheme for the Taylor shift).
  for (int i = 0; i < degree; ++i)
    for (int j = 1; j <= degree - i; ++j) p[j] += h * p[j - 1];
}

double RootRadiusBound(const double* p, int degree) {
  if (!(p[0] != 0.0) || !std::isfinite(p[0])) return std::numeric_limits<double>::quiet_NaN();
  double bound = 0.0;
  for (int k = 1; k <= degree; ++k) {
    double a = std::abs(p[k] / p[0]);
    if (k == degree) a *= 0.5;
    if (!std::isfinite(a)) return std::numeric_limits<double>::quiet_NaN();
    if (a == 0.0) continue;
    bound = std::max(bound, k == 1 ? a : (k == 2 ? std::sqrt(a) : std::pow(a, 1.0 / k)));
  }
  return 2.0 * bound;
}

PolynomialStability PolynomialStabilityTest(const double* p, int degree, double margin) {
  if (degree < 1 || degree > kMaxDegree) return PolynomialStability::kUndecided;
  const double rho = RootRadiusBound(p, degree);
  if (!std::isfinite(rho)) return PolynomialStability::kUndecided;
  const double scale = std::max(1.0, rho);
  double q[kMaxDegree + 1];
  std::copy(p, p + degree + 1, q);
  // q(s) = p(s - sigma) has the roots of p moved right by sigma.
  ShiftPolynomial(-(margin + kPolynomialTestBuffer) * scale, q, degree);
  if (IsHurwitz(q, degree)) return PolynomialStability::kStable;
  std::copy(p, p + degree + 1, q);
  ShiftPolynomial(kPolynomialTestBuffer * scale, q, degree);
  if (!IsHurwitz(q, degree)) return PolynomialStability::kUnstable;
  return PolynomialStability::kUndecided;
}

bool FastContinuousObjective::Covers(const TransferFunction& tf, const LoopOptions& options,
                                     ObjectiveKind kind) {
  if (options.loop != LoopKind::kContinuous) return false;
  if (options.disturbance.kind != DisturbanceKind::kNone) return false;
  if (kind != ObjectiveKind::kIae && kind != ObjectiveKind::kIse && kind != ObjectiveKind::kItae)
    return false;
  // The fast path runs the ideal PID only (tf = 0).
  if (options.derivative_filter_ratio > 0.0 || options.pid.derivative_filter_s != 0.0) return false;
  // and the 1-DOF PID (setpoint weights 1, 1).
  if (options.pid.setpoint_weight_b != 1.0 || options.pid.setpoint_weight_c != 1.0 ||
      options.pid.setpoint_filter_s != 0.0)
    return false;
  if (!tf.IsValid(nullptr) || tf.RelativeDegree() < 1) return false;
  const int order =
      static_cast<int>(tf.den.size()) - 1 -
      static_cast<int>(std::find_if(tf.den.begin(), tf.den.end(), [](double v) { return v != 0.0; }) -
                       tf.den.begin());
  return order >= 1 && order <= kMaxPlantOrder;
}

bool FastContinuousObjective::CoversPlant(const Plant& plant, const LoopOptions& options,
                                          ObjectiveKind kind) {
  return !plant.nonlinear && plant.delay_s == 0.0 && Covers(plant.tf, options, kind);
}

FastContinuousObjective::FastContinuousObjective(const TransferFunction& tf, const StateSpace& realization,
                                                 const LoopOptions& options, ObjectiveKind kind)
    : realization_(realization), options_(options), kind_(kind), none_(DisturbanceOptions{}) {
  if (!Covers(tf, options, kind))
    throw std::invalid_argument("the fast continuous objective does not cover this case");
  order_ = realization.order();
  num_samples_ = options.NumSamples();
  // The polynomials as Realize normalises them (over den's leading coefficient).
  std::vector<double> den(
      tf.den.begin() +
          (std::find_if(tf.den.begin(), tf.den.end(), [](double v) { return v != 0.0; }) - tf.den.begin()),
      tf.den.end());
  std::vector<double> num(
      tf.num.begin() +
          (std::find_if(tf.num.begin(), tf.num.end(), [](double v) { return v != 0.0; }) - tf.num.begin()),
      tf.num.end());
  den_ = Eigen::VectorXd::Zero(order_ + 1);
  num_ = Eigen::VectorXd::Zero(order_);
  for (int i = 0; i <= order_; ++i) den_(i) = den[static_cast<std::size_t>(i)] / den[0];
  // num has at most order_ coefficients (strictly proper), aligned on the right.
  const int offset = order_ - static_cast<int>(num.size());
  for (std::size_t i = 0; i < num.size(); ++i) num_(offset + static_cast<int>(i)) = num[i] / den[0];
  ca_ = realization_.c * realization_.a;
  cb_ = realization_.c.dot(realization_.b);
}

int FastContinuousObjective::CharacteristicPolynomial(const PidGains& g, bool integrator_connected,
                                                      double* p) const {
  // 1 + D(s) G(s) = 0 with D = kp + ki / s + kd s: s den + (kd s^2 + kp s + ki) num,
  // or den + (kd s + kp) num when ki does not reach u (the loop's order is n).
  const int n = order_;
  if (integrator_connected) {
    for (int k = 0; k <= n; ++k) p[k] = den_(k);
    p[n + 1] = 0.0;
    for (int j = 0; j < n; ++j) {  // num_(j) multiplies s^(n-1-j)
      p[j] += g.kd * num_(j);
      p[j + 1] += g.kp * num_(j);
      p[j + 2] += g.ki * num_(j);
    }
    return n + 1;
  }
  for (int k = 0; k <= n; ++k) p[k] = den_(k);
  for (int j = 0; j < n; ++j) {
    p[j] += g.kd * num_(j);
    p[j + 1] += g.kp * num_(j);
  }
  return n;
}

template <int N>
double FastContinuousObjective::Run(const PidGains& g) const {
  constexpr int V = N + 1;  // [x; z]; the reference state r is held
  constexpr int iz = N;
  const double reference = options_.reference;
  const double denom = 1.0 + g.kd * cb_;
  if (std::abs(denom) < 1e-12) return kInf;  // as BuildContinuousClosedLoop
  const double alpha = 1.0 / denom;
  const Eigen::Map<const Mat<N>> a(realization_.a.data());
  const Eigen::Map<const Vec<N>> b(realization_.b.data());
  const Eigen::Map<const Eigen::Matrix<double, 1, N>> c(realization_.c.data());

  // The loop matrix [[f, g_r], [0, 0]] exactly as BuildContinuousClosedLoop
  // writes it, u = u_row [x; z] + u_r r.
  Eigen::Matrix<double, 1, V> u_row;
  for (int j = 0; j < N; ++j) u_row(j) = -alpha * (g.kp * c(j) + g.kd * ca_(j));
  u_row(iz) = alpha * g.ki;
  const double u_r = alpha * g.kp;
  Mat<V> f = Mat<V>::Zero();
  Vec<V> g_r = Vec<V>::Zero();
  bool integrator_connected = false;
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) f(i, j) = a(i, j);
    for (int j = 0; j < V; ++j) f(i, j) += b(i) * u_row(j);
    g_r(i) = b(i) * u_r;
    integrator_connected = integrator_connected || f(i, iz) != 0.0;  // as EffectiveLoopOrder
  }
  for (int j = 0; j < N; ++j) f(iz, j) = -c(j);
  g_r(iz) = 1.0;

  double p[kMaxPlantOrder + 2];
  const int degree = CharacteristicPolynomial(g, integrator_connected, p);
  switch (PolynomialStabilityTest(p, degree, options_.stability_margin)) {
    case PolynomialStability::kUnstable:
      return kInf;
    case PolynomialStability::kUndecided:  // the eigenvalues decide, as in the general path
      return GeneralContinuousObjective(realization_, none_, options_, kind_, g);
    case PolynomialStability::kStable:
      break;
  }

  const double ts = options_.sample_time_s;
  Affine<V> step = AffineExp<V>(Mat<V>(f * ts), Vec<V>(g_r * ts));
  step.b *= reference;
  Vec<V> v = Vec<V>::Zero();
  for (int i = 0; i < N; ++i) v(i) = alpha * g.kd * (reference * b(i));
  Eigen::Matrix<double, 1, V> c_row = Eigen::Matrix<double, 1, V>::Zero();
  c_row.template head<N>() = c;
  switch (kind_) {
    case ObjectiveKind::kIae:
      return SumOfErrors<V, ObjectiveKind::kIae>(step, c_row, v, reference, ts, num_samples_);
    case ObjectiveKind::kIse:
      return SumOfErrors<V, ObjectiveKind::kIse>(step, c_row, v, reference, ts, num_samples_);
    case ObjectiveKind::kItae:
      return SumOfErrors<V, ObjectiveKind::kItae>(step, c_row, v, reference, ts, num_samples_);
    case ObjectiveKind::kIaeContinuous:
    case ObjectiveKind::kLoadIae:
    case ObjectiveKind::kSetpointLoad:
      break;  // not covered (Covers); never reached
  }
  return GeneralContinuousObjective(realization_, none_, options_, kind_, g);
}

double FastContinuousObjective::operator()(const PidGains& gains) const {
  switch (order_) {
    case 1:
      return Run<1>(gains);
    case 2:
      return Run<2>(gains);
    case 3:
      return Run<3>(gains);
    case 4:
      return Run<4>(gains);
    case 5:
      return Run<5>(gains);
    case 6:
      return Run<6>(gains);
    default:
      return GeneralContinuousObjective(realization_, none_, options_, kind_, gains);
  }
}

}  // namespace pidlab::evaluation
