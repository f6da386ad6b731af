// pidlab::identify on a non-uniformly sampled record: the exact response
// interval by interval (docs/identify.md, "Non-uniform sampling"), checked
// against closed forms written here, independent of the library's
// matrix exponentials.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "identify_records.h"
#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {
using test::StepRichInput;

// Sample times 0, h_0, h_0 + h_1, ... with h_k = dt (1 + U(-0.3, 0.3)), seeded.
std::vector<double> JitteredTimes(std::size_t n, double dt, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<double> t(n, 0.0);
  for (std::size_t k = 1; k < n; ++k) t[k] = t[k - 1] + dt * (1.0 + jitter(rng));
  return t;
}

// The response at every t_k of Kp e^(-Td s) / ((1 + T1 s)(1 + T2 s)) (T2 = 0:
// first order) to u_j held on [t_j + Td, t_(j+1) + Td), from rest: the two
// lags x1' = (Kp v - x1) / T1, x2' = (x1 - x2) / T2 advanced in closed form
// between consecutive events (sample times and delayed input changes, merged
// in time order).
std::vector<double> ClosedFormResponse(double kp, double t1, double t2, double td,
                                       const std::vector<double>& t, const std::vector<double>& u) {
  struct Event {
    double time;
    int sample;  // >= 0: a sample time; < 0: input -sample - 1 takes over
  };
  std::vector<Event> events;
  for (std::size_t k = 0; k < t.size(); ++k) {
    events.push_back({t[k], static_cast<int>(k)});
    events.push_back({t[k] + td, -static_cast<int>(k) - 1});
  }
  // At equal times the input changes first: u_k acts from t_k + Td on.
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
    return a.time < b.time || (a.time == b.time && a.sample < 0 && b.sample >= 0);
  });
  std::vector<double> y(t.size(), 0.0);
  double x1 = 0.0, x2 = 0.0, v = 0.0, now = t[0];
  for (const Event& e : events) {
    const double h = e.time - now;
    const double c = kp * v, e1 = std::exp(-h / t1);
    if (t2 > 0.0) {
      const double e2 = std::exp(-h / t2), a = (x1 - c) * t1 / (t1 - t2);
      x2 = x2 * e2 + c * (1.0 - e2) + a * (e1 - e2);
    }
    x1 = c + (x1 - c) * e1;
    now = e.time;
    if (e.sample < 0)
      v = u[static_cast<std::size_t>(-e.sample - 1)];
    else
      y[static_cast<std::size_t>(e.sample)] = t2 > 0.0 ? x2 : x1;
  }
  return y;
}

IdentifyData JitteredRecord(double kp, double t1, double t2, double td) {
  IdentifyData data;
  data.t = JitteredTimes(300, 0.1, 11);
  const std::vector<double> du = StepRichInput(300, 7);
  const std::vector<double> dy = ClosedFormResponse(kp, t1, t2, td, data.t, du);
  for (std::size_t k = 0; k < du.size(); ++k) {
    data.u.push_back(0.5 + du[k]);
    data.y.push_back(2.0 + dy[k]);
  }
  return data;
}

void ExpectRecovered(const IdentifyResult& dut, const std::vector<double>& truth) {
  ASSERT_EQ(dut.values.size(), truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    EXPECT_NEAR(dut.values[i], truth[i], 1e-6 * std::abs(truth[i])) << dut.names[i];
}

TEST(NonUniform, TheClosedFormAgreesWithTheLibrarysResponseOnAUniformGrid) {
  // The test's reference against DiscretePlant, so that it can be trusted below.
  ProcessModel m;
  m.kind = ProcessModelKind::kP2D, m.kp = 1.7, m.tp1_s = 4.2, m.tp2_s = 1.3, m.td_s = 0.63;
  std::vector<double> t(200);
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = 0.1 * static_cast<double>(k);
  const std::vector<double> u = StepRichInput(t.size(), 3);
  const std::vector<double> reference = ClosedFormResponse(1.7, 4.2, 1.3, 0.63, t, u);
  const std::vector<double> dut = SimulateModel(m, u, 0.0, 0.1);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(dut[k], reference[k], 1e-12) << k;
}

TEST(NonUniform, AJitteredRecordIsSaidAndItsSamplingMeasured) {
  IdentifyData data = JitteredRecord(2.5, 3.1, 0.0, 0.37);
  Sampling dut;
  ASSERT_TRUE(CheckData(data, &dut).ok());
  EXPECT_FALSE(dut.uniform);
  EXPECT_GT(dut.min_interval_s, 0.07 - 1e-12);
  EXPECT_LT(dut.min_interval_s, 0.075);
  EXPECT_LT(dut.max_interval_s, 0.13 + 1e-12);
  EXPECT_GT(dut.max_interval_s, 0.125);
  EXPECT_DOUBLE_EQ(dut.mean_interval_s, data.t.back() / 299.0);
}

TEST(NonUniform, P1dWithAFractionalDelayIsRecoveredFromAJitteredGrid) {
  IdentifyResult dut;
  ASSERT_TRUE(
      Identify(JitteredRecord(2.5, 3.1, 0.0, 0.37), ProcessModelKind::kP1D, IdentifyOptions{}, &dut).ok());
  EXPECT_FALSE(dut.sampling.uniform);
  ExpectRecovered(dut, {2.5, 3.1, 0.37});
  EXPECT_NEAR(dut.y0, 2.0, 1e-9);
  EXPECT_GT(dut.fit_percent, 100.0 * (1.0 - 1e-7));
}

TEST(NonUniform, P2dWithAFractionalDelayIsRecoveredFromAJitteredGrid) {
  IdentifyResult dut;
  ASSERT_TRUE(
      Identify(JitteredRecord(1.7, 4.2, 1.3, 0.63), ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  EXPECT_FALSE(dut.sampling.uniform);
  ExpectRecovered(dut, {1.7, 4.2, 1.3, 0.63});
}

TEST(NonUniform, AGridOfTwoAlternatingIntervalsIsFittedExactly) {
  // 0.0625 s and 0.125 s in turn (exact in binary, so that pieces of equal
  // length recur and come from the cache), a delay of 0.3 s off both grids.
  IdentifyData data;
  const std::vector<double> du = StepRichInput(240, 13);
  for (std::size_t k = 0; k < du.size(); ++k)
    data.t.push_back(k == 0 ? 0.0 : data.t.back() + (k % 2 == 1 ? 0.0625 : 0.125));
  const std::vector<double> dy = ClosedFormResponse(1.7, 4.2, 1.3, 0.3, data.t, du);
  for (std::size_t k = 0; k < du.size(); ++k) {
    data.u.push_back(du[k]);
    data.y.push_back(dy[k]);
  }
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  EXPECT_FALSE(dut.sampling.uniform);
  EXPECT_EQ(dut.sampling.min_interval_s, 0.0625);
  EXPECT_EQ(dut.sampling.max_interval_s, 0.125);
  ExpectRecovered(dut, {1.7, 4.2, 1.3, 0.3});
}

TEST(NonUniform, AUniformRecordKeepsTheUniformPath) {
  // Within the tolerance of uniform sampling: DiscretePlant over the mean
  // interval, as before, so every bit of the result is the same as for the
  // exactly uniform grid of that mean.
  IdentifyData uniform;
  std::vector<double> u = StepRichInput(200, 5);
  ProcessModel m;
  m.kind = ProcessModelKind::kP1D, m.kp = 2.5, m.tp1_s = 3.1, m.td_s = 0.37;
  const std::vector<double> y = SimulateModel(m, u, 0.0, 0.125);
  for (std::size_t k = 0; k < u.size(); ++k) {
    uniform.t.push_back(0.125 * static_cast<double>(k));
    uniform.u.push_back(u[k]);
    uniform.y.push_back(y[k]);
  }
  IdentifyData nudged = uniform;
  nudged.t[50] += 1e-9;  // 8e-9 of the interval
  IdentifyResult a, b;
  IdentifyOptions options;
  options.starts = 4;
  ASSERT_TRUE(Identify(uniform, ProcessModelKind::kP1D, options, &a).ok());
  ASSERT_TRUE(Identify(nudged, ProcessModelKind::kP1D, options, &b).ok());
  EXPECT_TRUE(a.sampling.uniform);
  EXPECT_TRUE(b.sampling.uniform);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.start_costs, b.start_costs);
}

}  // namespace
}  // namespace pidlab::identify
