#include "pidlab/plant_sim/transfer_function.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace pidlab {
namespace {

std::vector<double> StripLeadingZeros(const std::vector<double>& p) {
  std::size_t i = 0;
  while (i + 1 < p.size() && p[i] == 0.0) ++i;
  return std::vector<double>(p.begin() + static_cast<std::ptrdiff_t>(i), p.end());
}

std::string PolyToString(const std::vector<double>& p) {
  std::ostringstream os;
  os << std::setprecision(10);
  for (std::size_t i = 0; i < p.size(); ++i) os << (i ? "," : "") << p[i];
  return os.str();
}

}  // namespace

Eigen::VectorXd BalanceInPlace(Eigen::MatrixXd* a) {
  const Eigen::Index n = a->rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  bool converged = false;
  for (int sweep = 0; sweep < 100 && !converged; ++sweep) {
    converged = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      double c = 0.0, r = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        c += std::abs((*a)(j, i));
        r += std::abs((*a)(i, j));
      }
      // Not finite (inf or NaN in A): halving and doubling would never
      // balance inf against a finite norm, so leave the row alone.
      if (c == 0.0 || r == 0.0 || !std::isfinite(c) || !std::isfinite(r)) continue;
      double f = 1.0;
      const double s = c + r;
      // Each step moves c / r by a factor 4; finite positive norms are within
      // 2^2100 of each other, so kMaxSteps is never reached for them.
      constexpr int kMaxSteps = 1100;
      for (int step = 0; step < kMaxSteps && c < r / 2.0; ++step) {
        c *= 2.0;
        r /= 2.0;
        f *= 2.0;
      }
      for (int step = 0; step < kMaxSteps && c >= r * 2.0; ++step) {
        c /= 2.0;
        r *= 2.0;
        f /= 2.0;
      }
      if ((c + r) < 0.95 * s) {
        converged = false;
        d(i) *= f;
        a->col(i) *= f;
        a->row(i) /= f;
      }
    }
  }
  return d;
}

bool TransferFunction::IsValid(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (den.empty()) return fail("denominator is empty");
  if (num.empty()) return fail("numerator is empty");
  const std::pair<const char*, const std::vector<double>*> polys[] = {{"numerator", &num},
                                                                      {"denominator", &den}};
  for (const auto& [name, poly] : polys) {
    if (poly->size() > static_cast<std::size_t>(kMaxTransferFunctionCoefficients))
      return fail(std::string(name) + " has " + std::to_string(poly->size()) + " coefficients, more than " +
                  std::to_string(kMaxTransferFunctionCoefficients));
    for (double v : *poly) {
      const double a = std::abs(v);
      const bool finite = std::isfinite(v);
      if (finite && (v == 0.0 || (a <= kMaxCoefficientMagnitude && a >= kMinCoefficientMagnitude))) continue;
      // The message is formatted only for a coefficient refused: every
      // simulation validates its plant, an identification thousands of times.
      std::ostringstream os;
      os << name << " coefficient " << v;
      if (!finite) return fail(os.str() + " is not finite");
      os << " must be 0 or of magnitude between " << kMinCoefficientMagnitude << " and "
         << kMaxCoefficientMagnitude;
      return fail(os.str());
    }
  }
  const auto d = StripLeadingZeros(den);
  const auto n = StripLeadingZeros(num);
  if (d.size() == 1 && d[0] == 0.0) return fail("denominator is zero");
  if (n.size() > d.size())
    return fail("numerator degree " + std::to_string(n.size() - 1) + " exceeds denominator degree " +
                std::to_string(d.size() - 1) + " (improper)");
  return true;
}

int TransferFunction::RelativeDegree() const {
  const auto d = StripLeadingZeros(den);
  const auto n = StripLeadingZeros(num);
  if (n.size() == 1 && n[0] == 0.0) return static_cast<int>(d.size()) - 1;
  return static_cast<int>(d.size()) - static_cast<int>(n.size());
}

double TransferFunction::DcGain() const {
  const double n0 = num.back(), d0 = den.back();
  if (d0 == 0.0)
    return n0 == 0.0 ? std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::infinity();
  return n0 / d0;
}

std::string TransferFunction::ToString() const {
  return "[" + PolyToString(num) + "]/[" + PolyToString(den) + "]";
}

StateSpace Realize(const TransferFunction& tf) {
  std::string error;
  if (!tf.IsValid(&error)) throw std::invalid_argument("transfer function: " + error);
  std::vector<double> den = StripLeadingZeros(tf.den);
  std::vector<double> num = StripLeadingZeros(tf.num);
  const int n = static_cast<int>(den.size()) - 1;
  const double lead = den[0];
  for (double& v : den) v /= lead;
  for (double& v : num) v /= lead;
  // Pad the numerator to n + 1 coefficients.
  std::vector<double> b(static_cast<std::size_t>(n + 1) - num.size(), 0.0);
  b.insert(b.end(), num.begin(), num.end());
  StateSpace ss;
  ss.d = b[0];
  ss.a = Eigen::MatrixXd::Zero(n, n);
  ss.b = Eigen::VectorXd::Zero(n);
  ss.c = Eigen::RowVectorXd::Zero(n);
  if (n == 0) return ss;
  for (int j = 0; j < n; ++j) ss.a(0, j) = -den[static_cast<std::size_t>(j + 1)];
  for (int i = 1; i < n; ++i) ss.a(i, i - 1) = 1.0;
  ss.b(0) = 1.0;
  for (int j = 0; j < n; ++j)
    ss.c(j) = b[static_cast<std::size_t>(j + 1)] - b[0] * den[static_cast<std::size_t>(j + 1)];
  const Eigen::VectorXd d = BalanceInPlace(&ss.a);
  // x = D x_bal: B_bal = D^-1 B, C_bal = C D.
  ss.b = ss.b.cwiseQuotient(d);
  ss.c = ss.c.cwiseProduct(d.transpose());
  return ss;
}

std::vector<std::complex<double>> PolynomialRoots(const std::vector<double>& p_in) {
  std::vector<double> p = StripLeadingZeros(p_in);
  const int n = static_cast<int>(p.size()) - 1;
  if (n <= 0) return {};
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) c(0, j) = -p[static_cast<std::size_t>(j + 1)] / p[0];
  for (int i = 1; i < n; ++i) c(i, i - 1) = 1.0;
  BalanceInPlace(&c);
  Eigen::EigenSolver<Eigen::MatrixXd> es(c, false);
  std::vector<std::complex<double>> roots;
  for (int i = 0; i < n; ++i) roots.push_back(es.eigenvalues()(i));
  return roots;
}

}  // namespace pidlab
