// The general transfer function in the fit (tf_start.h).

#include "tf_start.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "arx_start.h"
#include "pidlab/plant_sim/discrete_plant.h"

namespace pidlab::identify::internal {
namespace {

// s^k / den(s) sampled with the delay; false if it cannot be simulated.
bool BasisResponse(int k, const std::vector<double>& den, const std::vector<double>& du, double dt_s,
                   double td_s, Eigen::Ref<Eigen::VectorXd> out) {
  std::vector<double> num(static_cast<std::size_t>(k + 1), 0.0);
  num[0] = 1.0;
  try {
    DiscretePlant plant(TransferFunction{num, den}, dt_s, td_s);
    for (std::size_t j = 0; j < du.size(); ++j) {
      out[static_cast<Eigen::Index>(j)] = plant.Output();
      plant.Step(du[j]);
    }
  } catch (const std::exception&) {
    return false;
  }
  return out.allFinite();
}

}  // namespace

Status CheckTfShape(ProcessModelKind kind, int poles, int zeros) {
  if (kind != ProcessModelKind::kTf) {
    if (poles != 0 || zeros != 0)
      return Status::InvalidInput("poles = " + std::to_string(poles) +
                                  " and zeros = " + std::to_string(zeros) +
                                  " apply to the model tf only, not " + ToString(kind));
    return Status::Ok();
  }
  if (poles < 1 || poles > plant_sim::kMaxTfPoles)
    return Status::InvalidInput("poles = " + std::to_string(poles) + " must be in 1.." +
                                std::to_string(plant_sim::kMaxTfPoles));
  if (zeros < 0 || zeros >= poles)
    return Status::InvalidInput("zeros = " + std::to_string(zeros) + " must be in 0.." +
                                std::to_string(poles - 1) + " (fewer than the " + std::to_string(poles) +
                                " poles: a strictly proper tf)");
  return Status::Ok();
}

bool TfDenominatorIsAdmissible(const std::vector<double>& a, double dt_s) {
  if (!plant_sim::IsHurwitz(a)) return false;
  const auto n = static_cast<Eigen::Index>(a.size());
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) companion(0, j) = -a[static_cast<std::size_t>(n - 1 - j)];
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  const Eigen::VectorXcd poles = companion.eigenvalues();
  const double nyquist = M_PI / dt_s;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(std::abs(poles[i].imag()) < nyquist)) return false;
  return true;
}

void SnapTinyCoefficients(std::vector<double>* values) {
  for (std::size_t i = 0; i + 1 < values->size(); ++i)
    if (std::abs((*values)[i]) < kMinCoefficientMagnitude) (*values)[i] = 0.0;
}

int TfDesignDimensions(int poles) { return poles > 1 ? 3 : 2; }

std::vector<double> SpreadLags(int poles, double h_slow, double h_fast, double lo, double hi) {
  const double slow = lo + h_slow * (hi - lo), fast = lo + h_fast * (slow - lo);
  std::vector<double> taus(static_cast<std::size_t>(poles));
  for (int i = 0; i < poles; ++i)
    taus[static_cast<std::size_t>(i)] = std::exp(poles > 1 ? slow + (fast - slow) * i / (poles - 1) : slow);
  return taus;
}

void SetDenominatorFromLags(int zeros, const std::vector<double>& taus_s, std::vector<double>* theta) {
  // Ascending coefficients of prod (s + 1 / tau), built one factor at a time.
  std::vector<double> c = {1.0};
  for (double tau : taus_s) {
    std::vector<double> next(c.size() + 1, 0.0);
    for (std::size_t i = 0; i < c.size(); ++i) {
      next[i] += c[i] / tau;
      next[i + 1] += c[i];
    }
    c = std::move(next);
  }
  for (std::size_t i = 0; i + 1 < c.size(); ++i) (*theta)[static_cast<std::size_t>(zeros + 1) + i] = c[i];
}

void SetNumeratorByLeastSquares(int poles, int zeros, const std::vector<double>& du,
                                const std::vector<double>& dy, double dt_s, bool offset,
                                std::vector<double>* theta) {
  const auto nb = static_cast<std::size_t>(zeros + 1), p = nb + static_cast<std::size_t>(poles) + 1;
  std::vector<double> values(theta->begin(), theta->begin() + static_cast<long>(p));
  SnapTinyCoefficients(&values);
  const std::vector<double> a(values.begin() + static_cast<long>(nb), values.end() - 1);
  for (std::size_t i = 0; i < nb; ++i) (*theta)[i] = i == 0 ? a[0] : 0.0;
  if (offset) (*theta)[p] = 0.0;
  if (!plant_sim::IsHurwitz(a)) return;
  std::vector<double> den = {1.0};
  den.insert(den.end(), a.rbegin(), a.rend());
  const auto n = static_cast<Eigen::Index>(dy.size());
  const auto columns = static_cast<Eigen::Index>(nb) + (offset ? 1 : 0);
  Eigen::MatrixXd g(n, columns);
  for (int k = 0; k <= zeros; ++k)
    if (!BasisResponse(k, den, du, dt_s, std::max(0.0, values.back()), g.col(k))) return;
  if (offset) g.col(columns - 1).setOnes();
  // Columns scaled to unit norm: s^k / den spans decades of magnitude.
  Eigen::VectorXd scale = g.colwise().norm().transpose();
  if (!(scale.minCoeff() > 0.0)) return;
  const Eigen::MatrixXd gs = g * scale.cwiseInverse().asDiagonal();
  const auto qr = gs.colPivHouseholderQr();
  if (qr.rank() < columns) return;
  const Eigen::VectorXd x = qr.solve(Eigen::Map<const Eigen::VectorXd>(dy.data(), n)).cwiseQuotient(scale);
  if (!x.allFinite()) return;
  for (std::size_t i = 0; i < nb; ++i) (*theta)[i] = x[static_cast<Eigen::Index>(i)];
  if (offset) (*theta)[p] = x[columns - 1];
}

std::vector<std::vector<double>> TfArxCandidates(int poles, int zeros, const std::vector<double>& du,
                                                 const std::vector<double>& dy, double dt_s,
                                                 double max_delay_s) {
  std::vector<std::vector<double>> candidates;
  for (const ArxFit& fit : ArxFits(poles, du, dy, dt_s, max_delay_s)) {
    // Ascending coefficients of prod (s - s_i), complex until the end.
    std::vector<std::complex<double>> c = {1.0};
    bool usable = true;
    for (const std::complex<double>& z : fit.z) {
      if (!(std::abs(z) > 0.0)) usable = false;
      const std::complex<double> s = std::log(z) / fit.h_s;
      std::vector<std::complex<double>> next(c.size() + 1, 0.0);
      for (std::size_t i = 0; i < c.size(); ++i) {
        next[i] -= c[i] * s;
        next[i + 1] += c[i];
      }
      c = std::move(next);
    }
    std::vector<double> values(static_cast<std::size_t>(zeros + 1), 0.0);
    for (std::size_t i = 0; i + 1 < c.size() && usable; ++i) {
      // A negative real z has no conjugate partner: its s leaves the polynomial complex.
      if (std::abs(c[i].imag()) > 1e-9 * std::max(1.0, std::abs(c[i]))) usable = false;
      values.push_back(c[i].real());
    }
    if (!usable) continue;
    const std::vector<double> a(values.begin() + zeros + 1, values.end());
    if (!plant_sim::IsHurwitz(a)) continue;
    values.push_back(fit.td_s);
    candidates.push_back(values);
  }
  return candidates;
}

}  // namespace pidlab::identify::internal
