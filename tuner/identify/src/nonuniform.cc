#include "nonuniform.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "pidlab/plant_sim/matrix_exp.h"
#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab::identify::internal {
namespace {

// x(t + h) = phi x(t) + gamma u over a piece of length h with u constant.
struct Piece {
  Eigen::MatrixXd phi;
  Eigen::MatrixXd gamma;
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
  const Eigen::MatrixXd b = ss.b;
  // Keyed by the exact piece length: a rounded key would integrate a piece
  // over a length it does not have.
  std::map<double, Piece> cache;
  const auto piece = [&](double h) -> const Piece& {
    auto it = cache.find(h);
    if (it == cache.end()) {
      Piece p;
      ZeroOrderHold<double>(ss.a, b, h, &p.phi, &p.gamma);
      it = cache.emplace(h, std::move(p)).first;
    }
    return it->second;
  };
  const std::size_t n = t.size();
  std::vector<double> yhat(n, 0.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ss.a.rows());
  std::size_t next = 0;  // the next input to take over, at t[next] + td
  double input = 0.0, now = n > 0 ? t[0] : 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    yhat[k] = (ss.c * x).value();
    if (k + 1 == n) break;
    const double end = t[k + 1];
    while (now < end) {
      while (next < n && t[next] + td <= now) input = du[next++];
      const double stop = next < n ? std::min(end, t[next] + td) : end;
      const Piece& p = piece(stop - now);
      x = p.phi * x + p.gamma.col(0) * input;
      now = stop;
    }
  }
  return yhat;
}

}  // namespace pidlab::identify::internal
