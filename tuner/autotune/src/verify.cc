// The verification step read through the measurement noise (verify.h).

#include "pidlab/autotune/verify.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pidlab::autotune {

namespace {

// The moving average of `y` over `w` samples (w odd, at most y's size):
// centred, and within w / 2 of an end the first or last w samples, so that
// every sample keeps the whole reduction of the noise.
std::vector<double> Smoothed(const std::vector<double>& y, int w) {
  const int n = static_cast<int>(y.size()), half = w / 2;
  std::vector<double> prefix(y.size() + 1, 0.0), out(y.size());
  for (int k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + y[k];
  for (int k = 0; k < n; ++k) {
    const int from = std::clamp(k - half, 0, n - w);
    out[k] = (prefix[from + w] - prefix[from]) / w;
  }
  return out;
}

}  // namespace

StepReading ReadVerificationStep(const std::vector<double>& t, const std::vector<double>& y, double reference,
                                 double noise_sigma, double pu_s) {
  StepReading r;
  r.noise_sigma = std::max(0.0, noise_sigma);
  r.tail_s = pu_s;
  r.settling_time_s = std::numeric_limits<double>::infinity();
  const double step = std::abs(reference);
  if (t.size() < 2 || t.size() != y.size() || !(step > 0.0)) return r;
  const double ts = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (r.noise_sigma > 0.0 && ts > 0.0) {
    const double wanted = std::ceil(std::pow(kBandSigmas * r.noise_sigma / (0.01 * step), 2.0));
    const double cap =
        std::min(std::floor(0.25 * pu_s / ts), std::floor(0.1 * static_cast<double>(y.size())));
    r.window = static_cast<int>(std::max(1.0, std::min(wanted, cap)));
    if (r.window % 2 == 0) r.window = std::max(1, r.window - 1);
  }
  r.residual_sigma = r.noise_sigma / std::sqrt(static_cast<double>(r.window));
  r.widening = kBandSigmas * r.residual_sigma;
  r.band = 0.02 * step + r.widening;
  const std::vector<double> s = r.window > 1 ? Smoothed(y, r.window) : y;
  double peak = -std::numeric_limits<double>::infinity();
  bool finite = true;
  for (double v : s) finite = finite && std::isfinite(v), peak = std::max(peak, reference > 0 ? v : -v);
  if (!finite) return r;
  r.overshoot_pct = std::max(0.0, 100.0 * (peak - step) / step);
  std::size_t last_out = s.size();  // the last sample outside the band
  for (std::size_t k = s.size(); k-- > 0;)
    if (std::abs(s[k] - reference) > r.band) {
      last_out = k;
      break;
    }
  if (last_out == s.size()) {
    r.settling_time_s = t.front();
  } else if (last_out + 1 < s.size()) {
    r.settling_time_s = t[last_out + 1];
  }
  r.settled = std::isfinite(r.settling_time_s) && r.settling_time_s <= t.back() - r.tail_s;
  return r;
}

}  // namespace pidlab::autotune
