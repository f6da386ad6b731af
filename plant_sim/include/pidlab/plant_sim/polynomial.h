#pragma once
// Polynomials as coefficient vectors in descending powers of s, as
// TransferFunction holds them: the products that build plants from factors.

#include <vector>

namespace pidlab {

/// a(s) b(s). Either empty gives an empty product.
std::vector<double> PolynomialProduct(const std::vector<double>& a, const std::vector<double>& b);

/// prod (tau s + 1) over `time_constants` ({1} for none).
std::vector<double> LagProduct(const std::vector<double>& time_constants);

}  // namespace pidlab
