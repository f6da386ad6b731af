// Starts from other fits' optima (fit_problem.h's NestedStarts and
// SameKindStart): the model a kind contains, and the same kind fitted with
// another loss, in Ceres's coordinates.

#include <algorithm>
#include <cmath>

#include "fit_problem.h"

namespace pidlab::identify::internal {

// Starts at the optimum `inner` of the model that `record`'s kind contains,
// in Ceres's coordinates (the offsets relative to the record's u0 and y0).
// P2D from P1D twice: a second lag at its lower bound (P1D's optimum as
// nearly as the bound allows: a free fit from a lag just above it can stall
// there, its step projected onto the bound), and one of half a sample taken
// out of the delay (a short lag and a short delay look alike).
std::vector<std::vector<double>> NestedStarts(const Record& record, const IdentifyResult& inner, double u0,
                                              double y0) {
  ProcessModelKind expected;
  if (!ContainedKind(record.kind, &expected) || inner.model.kind != expected) return {};
  const int p = ParameterCount(record);
  const std::vector<double>& v = inner.values;
  std::vector<double> theta(static_cast<std::size_t>(BlockSize(record)), 0.0);
  if (record.offset) theta[static_cast<std::size_t>(p)] = inner.y0 - y0;
  if (record.input_offset) theta[static_cast<std::size_t>(InputOffsetIndex(record))] = inner.u0 - u0;
  const auto log_lag = [&](double tau) {
    return std::clamp(std::log(tau), std::log(record.dt_s / kTimeConstantRange),
                      std::log(record.length_s * kTimeConstantRange));
  };
  const auto delay = [&](double td) { return std::clamp(td, 0.0, record.max_delay_s); };
  theta[0] = v[0];
  std::vector<std::vector<double>> starts;
  switch (record.kind) {
    case ProcessModelKind::kP2D:  // from Kp, Tp1, Td
      theta[1] = log_lag(v[1]);
      theta[2] = log_lag(record.dt_s / kTimeConstantRange);
      theta[3] = delay(v[2]);
      starts.push_back(theta);
      theta[2] = log_lag(record.dt_s / 2.0);
      theta[3] = delay(v[2] - record.dt_s / 2.0);
      starts.push_back(theta);
      break;
    case ProcessModelKind::kP2DU: {  // from Kp, Tp1, Tp2, Td
      const double tw = std::sqrt(v[1] * v[2]), zeta = (v[1] + v[2]) / (2.0 * tw);
      theta[1] = log_lag(tw);
      theta[2] = std::clamp(zeta, kMinZeta, kMaxZeta);
      theta[3] = delay(v[3]);
      starts.push_back(theta);
      // Lags too far apart for a pair: the critically damped pair of the
      // same sum of time constants (2 Zeta Tw = Tp1 + Tp2) too.
      if (zeta > kMaxZeta) {
        theta[1] = log_lag(0.5 * (v[1] + v[2]));
        theta[2] = kMaxZeta;
        starts.push_back(theta);
      }
      break;
    }
    case ProcessModelKind::kP2DZ:  // from Kp, Tp1, Tp2, Td; Tz = 0
      theta[1] = log_lag(v[1]);
      theta[2] = log_lag(v[2]);
      theta[3] = 0.0;
      theta[4] = delay(v[3]);
      starts.push_back(theta);
      break;
    default:
      break;
  }
  return starts;
}
// The optimum of the same kind fitted with another loss (the l2 fit before
// a robust one), in Ceres's coordinates, the offsets relative to the
// record's u0 and y0; empty if `prior` is of another kind.
std::vector<double> SameKindStart(const Record& record, const IdentifyResult& prior, double u0, double y0) {
  const int p = ParameterCount(record);
  if (prior.model.kind != record.kind || static_cast<int>(prior.values.size()) != p) return {};
  std::vector<double> theta(static_cast<std::size_t>(BlockSize(record)), 0.0);
  for (int i = 0; i < p; ++i) {
    const double v = prior.values[static_cast<std::size_t>(i)];
    double& t = theta[static_cast<std::size_t>(i)];
    if (IsLogParameter(record, i))
      t = std::clamp(std::log(v), std::log(record.dt_s / kTimeConstantRange),
                     std::log(record.length_s * kTimeConstantRange));
    else if (i == p - 1)
      t = std::clamp(v, 0.0, record.max_delay_s);
    else if (record.kind == ProcessModelKind::kP2DU && i == 2)
      t = std::clamp(v, kMinZeta, kMaxZeta);
    else
      t = v;
  }
  if (record.offset) theta[static_cast<std::size_t>(p)] = prior.y0 - y0;
  if (record.input_offset) theta[static_cast<std::size_t>(InputOffsetIndex(record))] = prior.u0 - u0;
  return theta;
}

}  // namespace pidlab::identify::internal
