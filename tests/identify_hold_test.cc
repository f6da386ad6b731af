// pidlab::identify with a first-order hold and an initial condition other
// than rest (docs/identify.md, "Intersample behaviour and the initial
// condition"), against closed forms written here: the output of unit-gain
// first-order lags x' = (v - x) / T under an input v that is constant or
// linear between events, P2D by partial fractions.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "identify_records.h"
#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {
using test::kDt;
using test::StepRichInput;

// The record's input u(tau): `before` for tau < t_0, then held (ZOH) or
// linear between samples (FOH), held after the last; and its slope.
struct HeldInput {
  const std::vector<double>& t;
  const std::vector<double>& u;
  bool foh;
  double before;
  // The value at tau and the slope of the piece that holds tau_mid (a point
  // inside the piece: t_j + td - td may round below t_j).
  std::pair<double, double> At(double tau, double tau_mid) const {
    if (tau_mid < t.front()) return {before, 0.0};
    const auto j = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), tau_mid) - t.begin()) - 1;
    if (!foh || j + 1 >= t.size()) return {u[j], 0.0};
    const double slope = (u[j + 1] - u[j]) / (t[j + 1] - t[j]);
    return {u[j] + slope * (tau - t[j]), slope};
  }
};

// The unit-gain lag of time constant `lag` under the input delayed by td,
// from x(t_0) = x0, at every t_k: exact between consecutive events (sample
// times and the delayed input's breakpoints t_j + td), where the input is
// a + w (t - s) and x(s + h) = (a + w h - w T) + (x(s) - a + w T) e^(-h/T).
std::vector<double> Lag(double lag, double td, const HeldInput& input, double x0) {
  std::vector<double> events(input.t);
  for (double tj : input.t) events.push_back(tj + td);
  std::sort(events.begin(), events.end());
  std::vector<double> out;
  double x = x0;
  std::size_t k = 0;
  for (std::size_t e = 0; e < events.size() && k < input.t.size(); ++e) {
    const double s = events[e];
    if (s == input.t[k]) out.push_back(x), ++k;
    if (k == input.t.size() || e + 1 == events.size()) break;
    const double h = events[e + 1] - s;
    if (h == 0.0) continue;
    const auto [a, w] = input.At(s - td, s + 0.5 * h - td);
    x = (a + w * h - w * lag) + (x - a + w * lag) * std::exp(-h / lag);
  }
  return out;
}

// Kp e^(-Td s) / ((1 + T1 s)(1 + T2 s)) (T2 = 0: first order) from its
// steady state under the constant input x0_input (0: at rest).
std::vector<double> Response(double kp, double t1, double t2, double td, const HeldInput& input,
                             double x0_input = 0.0) {
  const std::vector<double> x1 = Lag(t1, td, input, x0_input);
  if (t2 == 0.0) {
    std::vector<double> y(x1);
    for (double& v : y) v *= kp;
    return y;
  }
  const std::vector<double> x2 = Lag(t2, td, input, x0_input);
  std::vector<double> y(x1.size());
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = kp * (t1 * x1[k] - t2 * x2[k]) / (t1 - t2);
  return y;
}

std::vector<double> UniformTimes(std::size_t n) {
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) * kDt;
  return t;
}

// A smooth input (a sum of sines), as a sampled chirp is: FOH's case.
std::vector<double> SmoothInput(const std::vector<double>& t) {
  std::vector<double> u;
  for (double s : t)
    u.push_back(std::sin(0.7 * s) + 0.5 * std::sin(2.3 * s + 1.0) + 0.25 * std::sin(5.1 * s));
  return u;
}

void ExpectRecovered(const IdentifyResult& dut, const std::vector<double>& truth, double tolerance = 1e-6) {
  ASSERT_EQ(dut.values.size(), truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    EXPECT_NEAR(dut.values[i], truth[i], tolerance * std::abs(truth[i])) << dut.names[i];
}

TEST(Hold, TheClosedFormAgreesWithTheLibrarysZohResponse) {
  // The test's reference against DiscretePlant, so that it can be trusted below.
  ProcessModel m;
  m.kind = ProcessModelKind::kP2D, m.kp = 1.7, m.tp1_s = 4.2, m.tp2_s = 1.3, m.td_s = 0.63;
  const std::vector<double> t = UniformTimes(200);
  const std::vector<double> u = StepRichInput(t.size(), 3);
  const std::vector<double> reference = Response(1.7, 4.2, 1.3, 0.63, HeldInput{t, u, false, 0.0});
  const std::vector<double> dut = SimulateModel(m, u, 0.0, kDt);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(dut[k], reference[k], 1e-12) << k;
}

TEST(Hold, AFirstOrderHoldRecoversP1dAndP2dFromASmoothInputExactly) {
  const std::vector<double> t = UniformTimes(300);
  const std::vector<double> u = SmoothInput(t);
  IdentifyOptions options;
  options.intersample = Intersample::kFoh;
  for (const bool second : {false, true}) {
    const std::vector<double> truth =
        second ? std::vector<double>{1.7, 4.2, 1.3, 0.63} : std::vector<double>{2.5, 3.1, 0.37};
    const std::vector<double> y = Response(truth[0], truth[1], second ? truth[2] : 0.0, truth.back(),
                                           HeldInput{t, u, true, u[0]}, u[0]);
    IdentifyResult dut;
    ASSERT_TRUE(
        Identify({t, u, y}, second ? ProcessModelKind::kP2D : ProcessModelKind::kP1D, options, &dut).ok());
    EXPECT_EQ(dut.intersample, Intersample::kFoh);
    ExpectRecovered(dut, truth);
    EXPECT_GT(dut.fit_percent, 100.0 * (1.0 - 1e-7));
  }
}

TEST(Hold, TheSameDataFittedWithAZeroOrderHoldIsBiased) {
  // Why the option exists: a held input where the data were linear shifts
  // the delay by about half a sample.
  const std::vector<double> t = UniformTimes(300);
  const std::vector<double> u = SmoothInput(t);
  const std::vector<double> y = Response(2.5, 3.1, 0.0, 0.37, HeldInput{t, u, true, u[0]}, u[0]);
  IdentifyResult dut;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1D, IdentifyOptions{}, &dut).ok());
  EXPECT_GT(std::abs(dut.model.td_s - 0.37), 0.02);
  EXPECT_LT(dut.fit_percent, 99.99);
}

TEST(Hold, AFirstOrderHoldOnAJitteredGridIsExactToo) {
  std::vector<double> t{0.0};
  for (std::size_t k = 1; k < 300; ++k) t.push_back(t.back() + kDt * (1.0 + 0.3 * std::sin(1.7 * k * k)));
  const std::vector<double> u = SmoothInput(t);
  const std::vector<double> y = Response(2.5, 3.1, 0.0, 0.37, HeldInput{t, u, true, u[0]}, u[0]);
  IdentifyOptions options;
  options.intersample = Intersample::kFoh;
  IdentifyResult dut;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1D, options, &dut).ok());
  EXPECT_FALSE(dut.sampling.uniform);
  ExpectRecovered(dut, {2.5, 3.1, 0.37});
}

// A record cut from a run in motion: 400 samples of a P2D from rest, the
// first `cut` dropped, the cut where the input has been constant for longer
// than the delay (what "the input before the record at u[0]" assumes).
IdentifyData CutRecord(std::size_t* cut_out) {
  const std::vector<double> t = UniformTimes(400);
  std::vector<double> u = StepRichInput(t.size(), 7);
  std::size_t cut = 60;
  while (!(u[cut] == u[cut - 8] && u[cut] == u[cut - 1] && u[cut + 1] != u[cut])) ++cut;
  const std::vector<double> y = Response(1.7, 4.2, 1.3, 0.63, HeldInput{t, u, false, 0.0});
  IdentifyData data;
  for (std::size_t k = cut; k < t.size(); ++k) {
    data.t.push_back(t[k]);
    data.u.push_back(u[k]);
    data.y.push_back(y[k]);
  }
  *cut_out = cut;
  return data;
}

TEST(InitialCondition, AnEstimatedStateRecoversP2dFromARecordCutInMotion) {
  std::size_t cut = 0;
  const IdentifyData data = CutRecord(&cut);
  IdentifyOptions options;
  options.initial_condition = InitialCondition::kEstimate;
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, options, &dut).ok());
  ExpectRecovered(dut, {1.7, 4.2, 1.3, 0.63});
  EXPECT_GT(dut.fit_percent, 100.0 * (1.0 - 1e-7));
  ASSERT_EQ(dut.initial_state.size(), 2U);
  EXPECT_GT(std::abs(dut.initial_state[0]) + std::abs(dut.initial_state[1]), 1e-3);
  EXPECT_EQ(dut.initial_condition, InitialCondition::kEstimate);
  EXPECT_TRUE(dut.covariance_ok);
}

TEST(InitialCondition, FromRestTheSameRecordIsMisfitted) {
  std::size_t cut = 0;
  const IdentifyData data = CutRecord(&cut);
  IdentifyResult dut;
  ASSERT_TRUE(Identify(data, ProcessModelKind::kP2D, IdentifyOptions{}, &dut).ok());
  EXPECT_LT(dut.fit_percent, 99.9);
}

TEST(InitialCondition, SteadyStateStartsFromTheFirstInputWhenTheOperatingPointIsGiven) {
  // At rest under u = 0.8 since long before t_0, operating point (0, 0) given.
  const std::vector<double> t = UniformTimes(300);
  std::vector<double> u = StepRichInput(t.size(), 5);
  for (std::size_t k = 0; k < 5; ++k) u[k] = 0.8;
  const std::vector<double> y = Response(2.5, 3.1, 0.0, 0.37, HeldInput{t, u, false, 0.8}, 0.8);
  IdentifyOptions options;
  options.u0 = 0.0, options.y0 = 0.0;
  options.initial_condition = InitialCondition::kSteadyState;
  IdentifyResult dut;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1D, options, &dut).ok());
  ExpectRecovered(dut, {2.5, 3.1, 0.37});
  options.initial_condition = InitialCondition::kZero;
  IdentifyResult at_rest;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1D, options, &at_rest).ok());
  EXPECT_LT(at_rest.fit_percent, 99.0);
}

TEST(InitialCondition, SteadyStateOfAnIntegratorAwayFromTheOperatingPointIsRefusedByName) {
  const std::vector<double> t = UniformTimes(100);
  std::vector<double> u = StepRichInput(t.size(), 5);
  u[0] = 0.8;
  IdentifyOptions options;
  options.u0 = 0.0;
  options.initial_condition = InitialCondition::kSteadyState;
  IdentifyResult dut;
  const Status status =
      Identify({t, u, std::vector<double>(t.size(), 1.0)}, ProcessModelKind::kP1DI, options, &dut);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(status.message().find("P1DI integrates"), std::string::npos) << status.message();
}

TEST(InitialCondition, NamesParseAndPrintBack) {
  for (const std::string name : {"zero", "steady-state", "estimate"}) {
    InitialCondition v;
    ASSERT_TRUE(ParseInitialCondition(name, &v));
    EXPECT_EQ(ToString(v), name);
  }
  for (const std::string name : {"zoh", "foh"}) {
    Intersample v;
    ASSERT_TRUE(ParseIntersample(name, &v));
    EXPECT_EQ(ToString(v), name);
  }
  InitialCondition v;
  EXPECT_FALSE(ParseInitialCondition("rest", &v));
}

// Kp e^(-Td s) / (s (1 + T s)) from rest, its input held (ZOH): y = Kp times
// the integral of the unit lag x, both exact between events (for a constant
// a over h: the integral grows by a h + (x - a) T (1 - e^(-h/T))).
std::vector<double> IntegratingResponse(double kp, double lag, double td, const std::vector<double>& t,
                                        const std::vector<double>& u) {
  const HeldInput input{t, u, false, 0.0};
  std::vector<double> events(t);
  for (double tj : t) events.push_back(tj + td);
  std::sort(events.begin(), events.end());
  std::vector<double> out;
  double x = 0.0, integral = 0.0;
  std::size_t k = 0;
  for (std::size_t e = 0; e < events.size() && k < t.size(); ++e) {
    if (events[e] == t[k]) out.push_back(kp * integral), ++k;
    if (k == t.size() || e + 1 == events.size()) break;
    const double h = events[e + 1] - events[e];
    if (h == 0.0) continue;
    const double a = input.At(events[e] - td, events[e] + 0.5 * h - td).first;
    const double decay = std::exp(-h / lag);
    integral += a * h + (x - a) * lag * (1.0 - decay);
    x = a + (x - a) * decay;
  }
  return out;
}

TEST(Offsets, AnIntegratorsInputBiasIsEstimated) {
  // The actuator's true zero is 0.3 below the recorded u: a ramp the fit must
  // explain by u0 (y0 given).
  const std::vector<double> t = UniformTimes(300);
  const std::vector<double> u = StepRichInput(t.size(), 5);
  std::vector<double> biased(u);
  for (double& v : biased) v -= 0.3;
  const std::vector<double> y = IntegratingResponse(0.8, 1.2, 0.37, t, biased);
  IdentifyOptions options;
  options.y0 = 0.0;
  options.estimate_u0 = true;
  IdentifyResult dut;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1DI, options, &dut).ok());
  EXPECT_TRUE(dut.u0_estimated);
  EXPECT_NEAR(dut.u0, 0.3, 1e-6);
  EXPECT_TRUE(std::isfinite(dut.u0_standard_error));
  ExpectRecovered(dut, {0.8, 1.2, 0.37});
  options.estimate_u0 = false;
  IdentifyResult given;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1DI, options, &given).ok());
  EXPECT_LT(given.fit_percent, 99.0);
}

TEST(Offsets, ANonIntegratingModelsInputOffsetIsSeenInTheFirstTransient) {
  // At rest at u0 = 0.4 before t_0, the record's first sample already 0.9:
  // the step at t_0 shows u0 (y0 given).
  const std::vector<double> t = UniformTimes(300);
  std::vector<double> u = StepRichInput(t.size(), 5);
  for (std::size_t k = 0; k < 5; ++k) u[k] = 0.9;
  std::vector<double> du(u);
  for (double& v : du) v -= 0.4;
  const std::vector<double> y = Response(2.5, 3.1, 0.0, 0.37, HeldInput{t, du, false, 0.0});
  IdentifyOptions options;
  options.y0 = 0.0;
  options.estimate_u0 = true;
  IdentifyResult dut;
  ASSERT_TRUE(Identify({t, u, y}, ProcessModelKind::kP1D, options, &dut).ok());
  EXPECT_NEAR(dut.u0, 0.4, 1e-6);
  ExpectRecovered(dut, {2.5, 3.1, 0.37});
}

}  // namespace
}  // namespace pidlab::identify
