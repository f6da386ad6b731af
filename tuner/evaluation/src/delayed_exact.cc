// The method of steps without a stored interpolant (delayed_exact.h).

#include "delayed_exact.h"

#include <Eigen/StdVector>
#include <algorithm>
#include <cmath>

namespace pidlab::evaluation::internal {
namespace {

// Largest denominator b tried for L / ts = a / b.
constexpr long kMaxRatioDenominator = 1000;
// The first h tried has rate h <= this (the rate of the delayed path's
// kernel, SampleExactDelayedLoop); BlocksUsable checks that the blocks fall.
constexpr double kCouplingStep = 2.0;
// Blocks Psi_0 .. Psi_T at most; a run whose stack is deeper drops the rest,
// which must be below kDroppedBlock of the sum of the blocks' norms.
constexpr int kMaxBlocks = 24;
constexpr double kDroppedBlock = 1e-17;
// Above this sum of the blocks' norms, rounding in the sum would show: a
// smaller h is taken.
constexpr double kMaxBlockSum = 1e3;
// Halvings of h tried before leaving the run to the Hermite store.
constexpr int kMaxHalvings = 6;
// Bound on the stored states (doubles): the ring of T m + 1 nodes.
constexpr double kMaxRingDoubles = 1 << 22;

// L / ts = a / b with the least b <= kMaxRatioDenominator, to 1e-9.
bool Ratio(double delay_s, double ts, long* a, long* b) {
  for (long d = 1; d <= kMaxRatioDenominator; ++d) {
    const double x = delay_s * static_cast<double>(d) / ts, n = std::round(x);
    if (n >= 1.0 && std::abs(x - n) <= 1e-9 * x) {
      *a = static_cast<long>(n);
      *b = d;
      return true;
    }
  }
  return false;
}

template <int N>
using Mat = Eigen::Matrix<double, N, N>;
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;
template <int N>
using Blocks = std::vector<Mat<N>, Eigen::aligned_allocator<Mat<N>>>;

// (a * b)_i = sum_{l <= i} a_l b_(i-l): the product of two block lower
// triangular Toeplitz matrices, by their first block columns.
template <int N>
Blocks<N> ToeplitzProduct(const Blocks<N>& a, const Blocks<N>& b) {
  Blocks<N> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    out[i] = a[0] * b[i];
    for (std::size_t l = 1; l <= i; ++l) out[i].noalias() += a[l] * b[i - l];
  }
  return out;
}

// Psi_0 .. Psi_T: the first block column of exp of the block bidiagonal
// matrix with m h on the diagonal and c h below it, by the scaling and
// squaring of MatrixExp (plant_sim/matrix_exp.h) in the block Toeplitz
// algebra (where a term times the generator is two block products).
template <int N>
Blocks<N> BlockExp(const Mat<N>& m, const Mat<N>& c, double h, int blocks) {
  const Eigen::Index n = m.rows();
  const double norm =
      (m * h).cwiseAbs().rowwise().sum().maxCoeff() + (c * h).cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::min(1100.0, std::ceil(std::log2(norm / 0.5))));
  const double scale = std::ldexp(h, -squarings);
  const Mat<N> x0 = m * scale, x1 = c * scale;
  const Mat<N> zero = Mat<N>::Zero(n, n);
  Blocks<N> result(static_cast<std::size_t>(blocks) + 1, zero), term = result;
  result[0] = term[0] = Mat<N>::Identity(n, n);
  double term_bound = 1.0;
  const double scaled_norm = norm * std::ldexp(1.0, -squarings);
  for (int k = 1; k <= 30; ++k) {
    for (std::size_t i = term.size(); i-- > 0;) {  // descending: term[i - 1] is still the old one
      Mat<N> next = term[i] * x0;
      if (i > 0) next.noalias() += term[i - 1] * x1;
      term[i] = next * (1.0 / k);
      result[i] += term[i];
    }
    term_bound *= scaled_norm / k;
    if (term_bound < 1e-17) break;
  }
  for (int s = 0; s < squarings; ++s) result = ToeplitzProduct<N>(result, result);
  return result;
}

// The blocks are usable: finite, the dropped ones negligible, the sum small
// enough for its rounding not to show.
template <int N>
bool BlocksUsable(const Blocks<N>& psi, bool truncated) {
  double sum = 0.0, last = 0.0;
  for (const Mat<N>& p : psi) {
    last = p.cwiseAbs().rowwise().sum().maxCoeff();
    if (!std::isfinite(last)) return false;
    sum += last;
  }
  return sum <= kMaxBlockSum && (!truncated || last <= kDroppedBlock * sum);
}

// The run on the state of size N (Eigen::Dynamic for the larger loops) with
// p steps per sample and m per delay: false when no h down to ts / (p
// 2^kMaxHalvings) gives usable blocks or the ring would be too large.
template <int N>
bool Run(const DelayedClosedLoop& loop, double ts, int num_samples, long p, long m, std::vector<double>* y,
         DelayedTrace* trace) {
  const Eigen::Index n = loop.m.rows();
  Mat<N> a = loop.m;
  Eigen::Matrix<double, 1, N> kq = loop.kq;
  const int ir = loop.reference_index;  // the reference state, held
  if (loop.w0(ir) == 0.0) {
    // A zero reference (the load response) stays 0: its columns go (r's and
    // the setpoint filter's r_f, which stays 0 too), so that the setpoint
    // weights, which only multiply them, leave the rounding alone.
    for (int j = ir; j < loop.exo_index; ++j) {
      a.col(j).setZero();
      kq(j) = 0.0;
    }
  }
  const Mat<N> c = loop.e * kq;
  const double t_end = (num_samples - 1) * ts;
  const int depth = static_cast<int>(std::min<double>(kMaxBlocks, std::floor(t_end / loop.delay_s + 1e-9)));
  const bool truncated = std::floor(t_end / loop.delay_s + 1e-9) > kMaxBlocks;
  Blocks<N> psi;
  for (int halving = 0;; ++halving, p *= 2, m *= 2) {
    if (halving > kMaxHalvings ||
        static_cast<double>(depth * m + 1) * static_cast<double>(n) > kMaxRingDoubles ||
        static_cast<double>(num_samples - 1) * static_cast<double>(p) >
            static_cast<double>(kMaxDelayedPieces))
      return false;
    psi = BlockExp<N>(a, c, ts / static_cast<double>(p), depth);
    if (BlocksUsable<N>(psi, truncated)) break;
  }
  Eigen::Matrix<double, 1, N> out = Eigen::Matrix<double, 1, N>::Zero(1, n);
  out.head(loop.plant_order) = loop.c;
  const std::size_t size = static_cast<std::size_t>(depth * m + 1);
  std::vector<Vec<N>, Eigen::aligned_allocator<Vec<N>>> ring(size, Vec<N>::Zero(n));
  ring[0] = loop.w0;
  y->assign(static_cast<std::size_t>(num_samples), 0.0);
  (*y)[0] = out.dot(ring[0]);
  const long steps = (num_samples - 1) * p;
  const bool kick = loop.impulse.any();
  Vec<N> next(n);
  for (long j = 0; j < steps; ++j) {
    const int terms = static_cast<int>(std::min<long>(j / m, depth));
    const std::size_t slot = static_cast<std::size_t>(j % static_cast<long>(size));
    next.noalias() = psi[0] * ring[slot];
    for (int i = 1; i <= terms; ++i) {
      const long back = static_cast<long>(slot) - i * m;
      next.noalias() += psi[static_cast<std::size_t>(i)] *
                        ring[static_cast<std::size_t>(back >= 0 ? back : back + static_cast<long>(size))];
    }
    const long node = j + 1;
    if (node % p == 0) (*y)[static_cast<std::size_t>(node / p)] = out.dot(next);
    if (kick && node == m) next += loop.impulse;  // the ideal derivative's kick reaches the plant
    ring[static_cast<std::size_t>(node % static_cast<long>(size))] = next;
  }
  if (trace) trace->pieces = steps, trace->step_s = ts / static_cast<double>(p);
  return true;
}

}  // namespace

bool SampleExactDelayedLoop(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts,
                            int num_samples, std::vector<double>* y, DelayedTrace* trace) {
  const double t_end = (num_samples - 1) * ts;
  if (loop.exo_size == 1 && disturbance.IsPiecewiseConstant() && disturbance.NextBreakpoint(0.0) <= t_end)
    return false;
  long a = 0, b = 0;
  if (num_samples < 2 || !(loop.delay_s > 0.0) || !Ratio(loop.delay_s, ts, &a, &b)) return false;
  // h = ts / p with p a multiple of b (so that h divides L too) and
  // rate h <= kCouplingStep, rate the delayed path's kernel g(t) = kq
  // e^(mt) e near 0, |g(0)| + |g'(0)|^(1/2): C = e kq is of rank one, so
  // the blocks fall as the powers of g's convolution over h.
  const double coupling = std::abs(loop.kq.dot(loop.e)) + std::sqrt(std::abs(loop.kq.dot(loop.m * loop.e)));
  if (!std::isfinite(coupling)) return false;
  const double least = std::max(1.0, std::ceil(ts * coupling / (kCouplingStep * static_cast<double>(b))));
  if (least > 1e9) return false;
  const long p = b * static_cast<long>(least), m = a * static_cast<long>(least);
  switch (loop.m.rows()) {
    case 3:
      return Run<3>(loop, ts, num_samples, p, m, y, trace);
    case 4:
      return Run<4>(loop, ts, num_samples, p, m, y, trace);
    case 5:
      return Run<5>(loop, ts, num_samples, p, m, y, trace);
    case 6:
      return Run<6>(loop, ts, num_samples, p, m, y, trace);
    case 7:
      return Run<7>(loop, ts, num_samples, p, m, y, trace);
    default:
      return Run<Eigen::Dynamic>(loop, ts, num_samples, p, m, y, trace);
  }
}

}  // namespace pidlab::evaluation::internal
