#pragma once
// Golden-section search, a one-dimensional optimiser: used for the peak time
// of a step response (evaluation's metrics.cc) and the frequency of a
// sensitivity peak (analysis's loop_response.cc).

#include <cmath>

namespace pidlab::optim {

/// Narrows [a, b] around the maximum of a unimodal f, keeping the better of
/// the two interior points, until `done(a, b)` or `max_iterations`; returns
/// the midpoint of the last bracket.
template <typename F, typename Done>
double GoldenSectionArgMax(const F& f, double a, double b, int max_iterations, const Done& done) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - g * (b - a), d = a + g * (b - a), fc = f(c), fd = f(d);
  for (int it = 0; it < max_iterations && !done(a, b); ++it) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace pidlab::optim
