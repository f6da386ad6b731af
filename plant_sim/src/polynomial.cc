#include "pidlab/plant_sim/polynomial.h"

namespace pidlab {

std::vector<double> PolynomialProduct(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || b.empty()) return {};
  std::vector<double> c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}

std::vector<double> LagProduct(const std::vector<double>& time_constants) {
  std::vector<double> p{1.0};
  for (double tau : time_constants) p = PolynomialProduct(p, {tau, 1.0});
  return p;
}

}  // namespace pidlab
