// DecimateRecord (identify.h): a record longer than the fit's limit on
// samples shortened by an integer factor with an anti-alias average
// (docs/identify.md, "Long records").

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {

// The time-weighted mean of u over [t_begin, t_end) of samples begin..end-1,
// each held until the next sample; the last sample of the record, which
// holds over no interval, counts with the mean interval.
double HeldMean(const IdentifyData& data, std::size_t begin, std::size_t end, double mean_interval) {
  double integral = 0.0, span = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    const double h = i + 1 < data.t.size() ? data.t[i + 1] - data.t[i] : mean_interval;
    integral += data.u[i] * h;
    span += h;
  }
  return integral / span;
}

// The plain mean of `x` over the samples within `half` of sample k on both
// sides, the window cut symmetric at the record's ends (centred on k).
double CentredMean(const std::vector<double>& x, std::size_t k, std::size_t half) {
  const std::size_t h = std::min({half, k, x.size() - 1 - k});
  double sum = 0.0;
  for (std::size_t i = k - h; i <= k + h; ++i) sum += x[i];
  return sum / static_cast<double>(2 * h + 1);
}

}  // namespace

std::size_t DecimationFactor(std::size_t samples, std::size_t max_samples) {
  return samples <= max_samples || max_samples == 0 ? 1 : (samples + max_samples - 1) / max_samples;
}

Status DecimateRecord(const IdentifyData& data, std::size_t max_samples, Intersample hold, IdentifyData* out,
                      Decimation* decimation) {
  if (max_samples < kMinMaxSamples || max_samples > kMaxMaxSamples)
    return Status::InvalidInput("max_samples = " + std::to_string(max_samples) + " must be in [" +
                                std::to_string(kMinMaxSamples) + ", " + std::to_string(kMaxMaxSamples) + "]");
  const std::size_t n = data.y.size();
  *decimation = Decimation{1, n, n, max_samples};
  if (n <= max_samples || n < 2) {
    *out = data;
    return Status::Ok();
  }
  const std::size_t q = DecimationFactor(n, max_samples);
  const double mean_interval = (data.t.back() - data.t.front()) / static_cast<double>(n - 1);
  IdentifyData d;
  for (std::size_t k = 0; k < n; k += q) {
    d.t.push_back(data.t[k]);
    d.u.push_back(hold == Intersample::kZoh ? HeldMean(data, k, std::min(n, k + q), mean_interval)
                                            : CentredMean(data.u, k, q / 2));
    d.y.push_back(CentredMean(data.y, k, q / 2));
  }
  decimation->factor = static_cast<int>(q);
  decimation->samples = d.y.size();
  *out = std::move(d);
  return Status::Ok();
}

}  // namespace pidlab::identify
