#include "piecewise_response.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::identify::internal {
namespace {

// The augmented matrix of the largest model (a TF of kMaxTfPoles) with a
// first-order hold fits; on the stack, since the fit takes an exponential
// for every piece of every interval of every simulation (the heap's
// allocations cost as much as the arithmetic).
constexpr int kMaxAugmented = 8;
static_assert(plant_sim::kMaxTfPoles + 2 <= kMaxAugmented);
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

// x(s + h) = phi x(s) + gamma v(s) + slope_gamma w over a piece of length h
// on which the input is v(s) + w (t - s): the blocks of e^(M h).
struct Piece {
  SmallMatrix phi;
  SmallVector gamma, slope_gamma;
};

// The delayed input v(t) = u(t - Td) of the hold, and its slope, at `now`
// inside the piece that starts there; `next` is the first sample whose
// delayed time t_j + Td is after `now`.
struct Input {
  double value = 0.0, slope = 0.0;
};
Input DelayedInput(const std::vector<double>& t, const std::vector<double>& du, double td, Intersample hold,
                   double before, std::size_t next, double now) {
  if (next == 0) return {before, 0.0};
  const std::size_t j = next - 1;  // t_j + Td <= now < t_(j+1) + Td
  if (hold == Intersample::kZoh || next >= t.size()) return {du[j], 0.0};
  const double slope = (du[next] - du[j]) / (t[next] - t[j]);
  return {du[j] + slope * (now - (t[j] + td)), slope};
}

}  // namespace

int ModelOrder(const ProcessModel& model) {
  return static_cast<int>(Realize(model.ToTransferFunction()).a.rows());
}

bool SteadyState(const ProcessModel& model, double v, std::vector<double>* state) {
  const StateSpace ss = Realize(model.ToTransferFunction());
  const Eigen::Index n = ss.a.rows();
  state->assign(static_cast<std::size_t>(n), 0.0);
  if (v == 0.0) return true;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(ss.a);
  if (!lu.isInvertible()) return false;
  const Eigen::VectorXd x = -lu.solve(ss.b * v);
  for (Eigen::Index i = 0; i < n; ++i) (*state)[static_cast<std::size_t>(i)] = x(i);
  return true;
}

std::vector<double> SimulatePiecewise(const ProcessModel& model, const std::vector<double>& t,
                                      const std::vector<double>& du, Intersample hold,
                                      const PiecewiseStart& start) {
  const double td = model.delay_s();
  if (!(std::isfinite(td) && td >= 0.0))
    throw std::invalid_argument("the delay Td = " + std::to_string(td) + " s must be finite and >= 0");
  if (t.size() != du.size()) throw std::invalid_argument("t and u have different lengths");
  const StateSpace ss = Realize(model.ToTransferFunction());
  if (ss.d != 0.0) throw std::invalid_argument("the model is not strictly proper");
  const Eigen::Index order = ss.a.rows();
  if (!start.state.empty() && static_cast<Eigen::Index>(start.state.size()) != order)
    throw std::invalid_argument("the initial state's length is not the model's order");
  const Eigen::Index size = order + (hold == Intersample::kFoh ? 2 : 1);
  SmallMatrix augmented = SmallMatrix::Zero(size, size);
  augmented.topLeftCorner(order, order) = ss.a;
  augmented.block(0, order, order, 1) = ss.b;
  if (hold == Intersample::kFoh) augmented(order, order + 1) = 1.0;
  // Keyed by the exact piece length: a rounded key would integrate a piece
  // over a length it does not have.
  std::map<double, Piece> cache;
  const auto piece = [&](double h) -> const Piece& {
    auto it = cache.find(h);
    if (it == cache.end()) {
      const SmallMatrix e = SmallExp(augmented * h);
      Piece p{e.topLeftCorner(order, order), e.block(0, order, order, 1), SmallVector::Zero(order)};
      if (hold == Intersample::kFoh) p.slope_gamma = e.block(0, order + 1, order, 1);
      it = cache.emplace(h, std::move(p)).first;
    }
    return it->second;
  };
  const std::size_t n = t.size();
  std::vector<double> yhat(n, 0.0);
  SmallVector x = SmallVector::Zero(order);
  for (std::size_t i = 0; i < start.state.size(); ++i) x(static_cast<Eigen::Index>(i)) = start.state[i];
  const SmallVector c = ss.c.transpose();
  std::size_t next = 0;  // the first sample whose delayed time is after `now`
  double now = n > 0 ? t[0] : 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    yhat[k] = c.dot(x);
    if (k + 1 == n) break;
    const double end = t[k + 1];
    while (now < end) {
      while (next < n && t[next] + td <= now) ++next;
      const double stop = next < n ? std::min(end, t[next] + td) : end;
      const Input v = DelayedInput(t, du, td, hold, start.input_before, next, now);
      const Piece& p = piece(stop - now);
      x = p.phi * x + p.gamma * v.value;
      if (v.slope != 0.0) x += p.slope_gamma * v.slope;
      now = stop;
    }
  }
  return yhat;
}

std::vector<double> FitInitialState(const ProcessModel& model, const std::vector<double>& t, Intersample hold,
                                    const std::vector<double>& target, std::vector<double>* yhat) {
  const int order = ModelOrder(model);
  const auto rows = static_cast<Eigen::Index>(t.size());
  Eigen::MatrixXd free(rows, order);
  const std::vector<double> zero(t.size(), 0.0);
  PiecewiseStart start;
  for (int i = 0; i < order; ++i) {
    start.state.assign(static_cast<std::size_t>(order), 0.0);
    start.state[static_cast<std::size_t>(i)] = 1.0;
    const std::vector<double> column = SimulatePiecewise(model, t, zero, hold, start);
    for (Eigen::Index k = 0; k < rows; ++k) free(k, i) = column[static_cast<std::size_t>(k)];
  }
  Eigen::VectorXd rest(rows);
  for (Eigen::Index k = 0; k < rows; ++k)
    rest(k) = target[static_cast<std::size_t>(k)] - (*yhat)[static_cast<std::size_t>(k)];
  const Eigen::VectorXd x = free.colPivHouseholderQr().solve(rest);
  const Eigen::VectorXd fitted = free * x;
  for (Eigen::Index k = 0; k < rows; ++k) (*yhat)[static_cast<std::size_t>(k)] += fitted(k);
  return std::vector<double>(x.data(), x.data() + x.size());
}

}  // namespace pidlab::identify::internal
