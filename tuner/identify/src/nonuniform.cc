#include "nonuniform.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::identify::internal {
namespace {

// The augmented matrix [[A, B], [0, 0]] of the largest model (a TF of
// kMaxTfPoles) fits; on the stack, since the fit takes an exponential for
// every piece of every interval of every simulation (the heap's allocations
// cost as much as the arithmetic).
constexpr int kMaxAugmented = 8;
static_assert(plant_sim::kMaxTfPoles + 1 <= kMaxAugmented);
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxAugmented, kMaxAugmented>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAugmented, 1>;

// exp(a) as MatrixExp (plant_sim/matrix_exp.h) computes it: scaling until the
// infinity norm is <= 1/2, the Taylor series cut below 1e-17 relative, then
// squaring.
SmallMatrix SmallExp(const SmallMatrix& a) {
  const Eigen::Index n = a.rows();
  const double norm = a.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::min(1100.0, std::ceil(std::log2(norm / 0.5))));
  const SmallMatrix scaled = a * std::ldexp(1.0, -squarings);
  SmallMatrix result = SmallMatrix::Identity(n, n);
  SmallMatrix term = SmallMatrix::Identity(n, n);
  double term_bound = 1.0;
  const double scaled_norm = norm * std::ldexp(1.0, -squarings);
  for (int k = 1; k <= 30; ++k) {
    term = (term * scaled) * (1.0 / k);
    result += term;
    term_bound *= scaled_norm / k;
    if (term_bound < 1e-17) break;
  }
  for (int i = 0; i < squarings; ++i) result = (result * result).eval();
  return result;
}

// x(t + h) = phi x(t) + gamma u over a piece of length h with u constant:
// the blocks of exp([[A, B], [0, 0]] h).
struct Piece {
  SmallMatrix phi;
  SmallVector gamma;
};

}  // namespace

std::vector<double> SimulateNonUniform(const ProcessModel& model, const std::vector<double>& t,
                                       const std::vector<double>& du) {
  const double td = model.delay_s();
  if (!(std::isfinite(td) && td >= 0.0))
    throw std::invalid_argument("the delay Td = " + std::to_string(td) + " s must be finite and >= 0");
  if (t.size() != du.size()) throw std::invalid_argument("t and u have different lengths");
  const StateSpace ss = Realize(model.ToTransferFunction());
  if (ss.d != 0.0) throw std::invalid_argument("the model is not strictly proper");
  const Eigen::Index order = ss.a.rows();
  SmallMatrix augmented = SmallMatrix::Zero(order + 1, order + 1);
  augmented.topLeftCorner(order, order) = ss.a;
  augmented.topRightCorner(order, 1) = ss.b;
  // Keyed by the exact piece length: a rounded key would integrate a piece
  // over a length it does not have.
  std::map<double, Piece> cache;
  const auto piece = [&](double h) -> const Piece& {
    auto it = cache.find(h);
    if (it == cache.end()) {
      const SmallMatrix e = SmallExp(augmented * h);
      it = cache.emplace(h, Piece{e.topLeftCorner(order, order), e.topRightCorner(order, 1)}).first;
    }
    return it->second;
  };
  const std::size_t n = t.size();
  std::vector<double> yhat(n, 0.0);
  SmallVector x = SmallVector::Zero(order);
  const SmallVector c = ss.c.transpose();
  std::size_t next = 0;  // the next input to take over, at t[next] + td
  double input = 0.0, now = n > 0 ? t[0] : 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    yhat[k] = c.dot(x);
    if (k + 1 == n) break;
    const double end = t[k + 1];
    while (now < end) {
      while (next < n && t[next] + td <= now) input = du[next++];
      const double stop = next < n ? std::min(end, t[next] + td) : end;
      const Piece& p = piece(stop - now);
      x = p.phi * x + p.gamma * input;
      now = stop;
    }
  }
  return yhat;
}

}  // namespace pidlab::identify::internal
