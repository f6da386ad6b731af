// The relay (RelayTuner, run bare: autotune::BareRelay; issue 43) on first-order plus
// dead-time and integrating processes simulated in process: the ultimate gain and period
// from the asymmetric relay's FOPDT model against pidlab's own frequency
// analysis of the same process (within 5 %), the model against the process
// (within 10 %), and the plain describing function's error on a symmetric
// relay, which is why the model is fitted.

#include "pidlab/autotune/relay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "test_status.h"

namespace pidlab {
namespace {

using autotune::FopdtFromCycle;
using autotune::FopdtModel;
using autotune::FopdtUltimate;
using autotune::RelayEstimates;
using autotune::RelayOptions;

constexpr double kPi = 3.14159265358979323846;

// K e^(-sL)/(Ts + 1) at step h (L a multiple of h), the relay sampling y
// every step, from rest at y = r (u = u0); until converged or `cycles_max`.
RelayEstimates RunRelay(const FopdtModel& p, const RelayOptions& o, double h, RelayTuner* relay) {
  const int delay_steps = static_cast<int>(std::lround(p.delay_s / h));
  const double a = std::exp(-h / p.time_constant_s);
  std::vector<double> pipe(delay_steps, o.u0);  // inputs on their way
  double x = p.gain * o.u0;                     // y at rest
  std::size_t head = 0;
  const double t_end = 400.0 * (p.time_constant_s + p.delay_s);
  for (long k = 0; k * h < t_end; ++k) {
    const double u = relay->Step(k * h, o.setpoint, x);
    const double arriving = delay_steps > 0 ? pipe[head] : u;
    if (delay_steps > 0) pipe[head] = u, head = (head + 1) % pipe.size();
    if (p.integrating)
      x += h * p.gain * (arriving - o.u0);  // K e^(-sL)/s at rest at u0
    else
      x = a * x + (1.0 - a) * p.gain * arriving;  // exact for an input held over the step
    if (relay->phase() != RelayPhase::kRelay && relay->phase() != RelayPhase::kHold) break;
  }
  return autotune::EstimateBare(o, *relay);
}

// Ku (kp times the gain margin of a stable P loop) and Pu of the process by
// pidlab's analysis.
void ExactUltimate(const FopdtModel& p, double* ku, double* pu) {
  Plant plant;
  plant.name = "custom";
  plant.tf.num = {p.gain};
  plant.tf.den = p.integrating ? std::vector<double>{1.0, 0.0} : std::vector<double>{p.time_constant_s, 1.0};
  plant.delay_s = p.delay_s;
  PidGains g;
  g.kp = 0.01 / std::abs(p.gain);
  analysis::LoopAnalysis a;
  ASSERT_TRUE(
      IsOk(analysis::AnalyzeLoop(plant, g, evaluation::LoopOptions{}, analysis::LoopAnalysisOptions{}, &a)));
  ASSERT_TRUE(a.stable);
  *ku = g.kp * a.gain_margin;
  *pu = 2.0 * kPi / a.phase_crossover_rad_s;
}

double Rel(double got, double want) { return std::abs(got - want) / std::abs(want); }

TEST(Relay, AsymmetricRelayGivesTheUltimateGainAndPeriodWithin5PercentAndTheModelWithin10) {
  for (double l_over_t : {0.1, 0.5, 2.0}) {
    for (double eps : {0.0, 0.02}) {
      const FopdtModel p{2.0, 1.0, l_over_t};
      RelayOptions o;
      o.setpoint = 1.0;
      o.u0 = 0.5;  // K u0 = r
      o.d_high = 0.5;
      o.d_low = 0.25;
      o.hysteresis = eps;
      RelayTuner relay = autotune::BareRelay(o, p.delay_s / 400.0);
      const RelayEstimates e = RunRelay(p, o, p.delay_s / 400.0, &relay);
      const std::string what = "L/T " + std::to_string(l_over_t) + ", eps " + std::to_string(eps);
      ASSERT_TRUE(e.converged) << what << ": " << relay.cycles().size() << " cycles";
      ASSERT_TRUE(e.model_found) << what << ": " << e.message;
      double ku = 0.0, pu = 0.0;
      ExactUltimate(p, &ku, &pu);
      EXPECT_LT(Rel(e.ku, ku), 0.05) << what << ": Ku " << e.ku << ", exact " << ku;
      EXPECT_LT(Rel(e.pu_s, pu), 0.05) << what << ": Pu " << e.pu_s << ", exact " << pu;
      EXPECT_LT(Rel(e.model.gain, p.gain), 0.10) << what;
      EXPECT_LT(Rel(e.model.time_constant_s, p.time_constant_s), 0.10) << what;
      EXPECT_LT(Rel(e.model.delay_s, p.delay_s), 0.10) << what;
      EXPECT_GT(e.period_s, 0.0);
      EXPECT_GE(e.period_ci_s, 0.0);
      EXPECT_LT(e.period_ci_s, 0.01 * e.period_s) << what;
    }
  }
}

TEST(Relay, AsymmetricRelayOnAnIntegratingProcessGivesItsModelAndUltimatePoint) {
  for (double eps : {0.0, 0.02}) {
    FopdtModel p;
    p.gain = 0.5;
    p.delay_s = 1.0;
    p.integrating = true;
    RelayOptions o;
    o.setpoint = 1.0;
    o.u0 = 0.3;
    o.d_high = 0.5;
    o.d_low = 0.25;
    o.hysteresis = eps;
    RelayTuner relay = autotune::BareRelay(o, p.delay_s / 400.0);
    const RelayEstimates e = RunRelay(p, o, p.delay_s / 400.0, &relay);
    ASSERT_TRUE(e.converged) << "eps " << eps;
    ASSERT_TRUE(e.model_found) << e.message;
    EXPECT_TRUE(e.model.integrating) << "a first-order model was fitted";
    double ku = 0.0, pu = 0.0;
    ExactUltimate(p, &ku, &pu);
    EXPECT_LT(Rel(e.ku, ku), 0.05) << "eps " << eps << ": Ku " << e.ku << ", exact " << ku;
    EXPECT_LT(Rel(e.pu_s, pu), 0.05) << "eps " << eps << ": Pu " << e.pu_s << ", exact " << pu;
    EXPECT_LT(Rel(e.model.gain, p.gain), 0.10) << "eps " << eps << ": K " << e.model.gain;
    EXPECT_LT(Rel(e.model.delay_s, p.delay_s), 0.10) << "eps " << eps << ": L " << e.model.delay_s;
  }
}

TEST(Relay, PlainDescribingFunctionIsAbout15PercentLowOnASymmetricRelayAndTheGainIsRefused) {
  // The figure: 4d/(pi a) on e^(-0.5 s)/(s + 1).
  const FopdtModel p{1.0, 1.0, 0.5};
  RelayOptions o;
  o.setpoint = 1.0;
  o.u0 = 1.0;
  o.d_high = o.d_low = 0.3;
  RelayTuner relay = autotune::BareRelay(o, p.delay_s / 400.0);
  const RelayEstimates e = RunRelay(p, o, p.delay_s / 400.0, &relay);
  ASSERT_TRUE(e.converged);
  double ku = 0.0, pu = 0.0;
  ExactUltimate(p, &ku, &pu);
  const double low = 1.0 - e.ku_describing_function / ku;
  EXPECT_GT(low, 0.10) << "describing function " << e.ku_describing_function << ", exact " << ku;
  EXPECT_LT(low, 0.20) << "describing function " << e.ku_describing_function << ", exact " << ku;
  EXPECT_FALSE(e.model_found);
  EXPECT_NE(e.message.find("symmetric relay"), std::string::npos) << e.message;
}

TEST(Relay, FopdtUltimateMatchesTheFrequencyAnalysis) {
  for (const FopdtModel& m : {FopdtModel{1.0, 1.0, 0.1}, FopdtModel{2.0, 60.0, 8.0},
                              FopdtModel{0.5, 1.0, 10.0}, FopdtModel{0.5, 0.0, 1.0, true}}) {
    double ku = 0.0, pu = 0.0, exact_ku = 0.0, exact_pu = 0.0;
    ASSERT_TRUE(IsOk(FopdtUltimate(m, &ku, &pu)));
    ExactUltimate(m, &exact_ku, &exact_pu);
    EXPECT_NEAR(ku, exact_ku, 1e-6 * exact_ku);
    EXPECT_NEAR(pu, exact_pu, 1e-6 * exact_pu);
  }
  double ku = 0.0, pu = 0.0;
  EXPECT_FALSE(IsOk(FopdtUltimate(FopdtModel{1.0, 1.0, 0.0}, &ku, &pu)));
}

TEST(Relay, OptionsNameTheBadValue) {
  std::string error;
  RelayOptions o;
  o.d_low = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("d_low -1"), std::string::npos) << error;
  o = RelayOptions{};
  o.hysteresis = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("hysteresis"), std::string::npos) << error;
  o = RelayOptions{};
  o.settled_cycles = 1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("settled cycles 1"), std::string::npos) << error;
}

}  // namespace
}  // namespace pidlab

namespace pidlab {
namespace {

// A symmetric relay's cycle on K e^(-sL)/(Ts + 1), in closed form: the
// amplitude a = Kd - (Kd - eps) e^(-L/T), the half period
// h = L + T ln((Kd + a) / (Kd - eps)).
RelayCycle SymmetricCycle(const autotune::FopdtModel& p, double d, double eps) {
  const double x = p.gain * d, a = x - (x - eps) * std::exp(-p.delay_s / p.time_constant_s);
  const double h = p.delay_s + p.time_constant_s * std::log((x + a) / (x - eps));
  RelayCycle c;
  c.e_max = a;
  c.e_min = -a;
  c.t_on_s = c.t_off_s = h;
  return c;
}

TEST(Relay, ASymmetricRelaysCycleAndItsDelayToTheExtremesGiveTheFopdtBack) {
  for (const autotune::FopdtModel& p :
       {autotune::FopdtModel{2.0, 3.0, 1.0}, autotune::FopdtModel{0.5, 1.0, 2.0},
        autotune::FopdtModel{1.0, 1.0, 0.1}}) {
    for (const double eps : {0.0, 0.02}) {
      autotune::RelayOptions o;
      o.d_high = o.d_low = 0.7;
      o.hysteresis = eps;
      autotune::FopdtModel m;
      ASSERT_TRUE(IsOk(autotune::FopdtFromSymmetric(o, SymmetricCycle(p, 0.7, eps), p.delay_s, &m)));
      EXPECT_NEAR(m.gain, p.gain, 1e-9 * p.gain);
      EXPECT_NEAR(m.time_constant_s, p.time_constant_s, 1e-9 * p.time_constant_s);
      EXPECT_EQ(m.delay_s, p.delay_s);
    }
  }
}

TEST(Relay, ASymmetricRelaysHalfPeriodTooLongForItsDelayIsNoFopdt) {
  autotune::RelayOptions o;
  o.d_high = o.d_low = 1.0;
  RelayCycle c;
  c.e_max = 1.0;
  c.e_min = -1.0;
  c.t_on_s = c.t_off_s = 3.0;  // an integrator K/s with L = 1 has h = 2 L exactly: more is no FOPDT
  autotune::FopdtModel m;
  const Status st = autotune::FopdtFromSymmetric(o, c, 1.0, &m);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("too long"), std::string::npos) << st.message();
}

}  // namespace
}  // namespace pidlab

namespace pidlab {
namespace {

// K e^(-sL)/(Ts + 1) behind a sample-and-hold of period h, the relay on its
// grid: y(k+1) = a y(k) + (1 - a) K v(k - n), exact. The sampled fit gives
// K, T and L back, and its Ku and Pu are the sampled loop's own (pidlab's
// frequency analysis of a P gain on the loop sampled at h).
TEST(Relay, OnASampleAndHoldTheSampledFitGivesTheProcessAndTheSampledLoopsUltimatePoint) {
  const double h = 1.0;
  // (T/h, n): lags of half a sample to two (a scan slower than the process,
  // as Modelica's). Where T is long against h and the delay short (T/h 2,
  // n 0; T/h 8, n 1) the relay on the grid settles to no single period: its
  // half periods alternate between whole samples and it times out. There
  // the hold is small against the process and the continuous fit applies.
  const std::vector<std::pair<double, int>> cases = {{0.5, 0}, {0.5, 1}, {2.0, 1},
                                                     {0.5, 3}, {2.0, 3}, {8.0, 3}};
  for (const auto& [t_over_h, n] : cases) {
    {
      const double k = 2.0, t = t_over_h * h, a = std::exp(-h / t);
      RelayOptions o;
      o.setpoint = 1.0;
      o.u0 = 0.5;
      o.d_high = 0.5;
      o.d_low = 0.25;
      o.hysteresis = 0.02;
      o.tolerance = 1e-4;
      o.sample_period_s = h;
      RelayTuner relay = autotune::BareRelay(o, h);
      std::vector<double> v(static_cast<std::size_t>(n) + 1, 0.0);  // v(k - n) .. v(k)
      double y = 1.0;
      for (long i = 0; i < 4000 && (i == 0 || relay.phase() == RelayPhase::kRelay); ++i) {
        const double u = relay.Step(static_cast<double>(i) * h, o.setpoint, y);
        v.erase(v.begin());
        v.push_back(u - o.u0);
        y = a * y + (1.0 - a) * (k * o.u0 + k * v.front());
      }
      const std::string what = "T/h " + std::to_string(t_over_h) + ", n " + std::to_string(n);
      ASSERT_EQ(relay.phase(), RelayPhase::kDone) << what << ": " << relay.why();
      const RelayEstimates e = autotune::EstimateBare(o, relay);
      ASSERT_TRUE(e.model_found) << what << ": " << e.message;
      EXPECT_LT(Rel(e.model.gain, k), 1e-3) << what << ": K " << e.model.gain;
      EXPECT_LT(Rel(e.model.time_constant_s, t), 1e-3) << what << ": T " << e.model.time_constant_s;
      EXPECT_EQ(e.model.delay_s, n * h) << what;
      Plant plant;
      plant.name = "custom";
      plant.tf.num = {k};
      plant.tf.den = {t, 1.0};
      plant.delay_s = n * h;
      evaluation::LoopOptions loop;
      loop.loop = evaluation::LoopKind::kSampled;
      loop.dt_s = loop.sample_time_s = h;
      loop.horizon_s = 100 * h;
      PidGains g;
      g.kp = 0.01 / k;
      analysis::LoopAnalysis an;
      ASSERT_TRUE(IsOk(analysis::AnalyzeLoop(plant, g, loop, analysis::LoopAnalysisOptions{}, &an))) << what;
      // With no delay past the hold (n = 0) the phase reaches -pi only at the
      // Nyquist frequency, which the analysis does not count: there
      // |G(-1)| = K (1 - a) / (1 + a) and Pu = 2 h.
      const double ku = n > 0 ? g.kp * an.gain_margin : (1.0 + a) / (k * (1.0 - a));
      const double pu = n > 0 ? 2.0 * kPi / an.phase_crossover_rad_s : 2.0 * h;
      EXPECT_LT(Rel(e.ku, ku), 1e-3) << what << ": Ku " << e.ku << ", exact " << ku;
      EXPECT_LT(Rel(e.pu_s, pu), 1e-3) << what << ": Pu " << e.pu_s << ", exact " << pu;
    }
  }
}

}  // namespace
}  // namespace pidlab
