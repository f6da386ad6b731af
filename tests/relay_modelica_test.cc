// The one relay state machine (RelayTuner, run bare by tuner/autotune's BareRelay) against
// the Modelica Buildings Library's PIDWithAutotuning (LBL, Berner's
// asymmetric relay plus AMIGO), on the plant, relay and reference results of
// its validation models.
//
// Source: github.com/lbl-srg/modelica-buildings, commit
// c4117ccec1f288ee6bc7f0ee0cb40a45d6940b0c, read:
//   Buildings/Controls/OBC/Utilities/PIDWithAutotuning/Validation/ReverseActingPIDWithFirstOrderAMIGO.mo
//   Buildings/Controls/OBC/Utilities/PIDWithAutotuning/Validation/ReverseActingPIWithFirstOrderAMIGO.mo
//   Buildings/Controls/OBC/Utilities/PIDWithAutotuning/FirstOrderAMIGO.mo, Relay/Controller.mo,
//     Relay/BaseClasses/{OnOffPeriod,HalfPeriodRatio,NormalizedTimeDelay,TuningMonitor}.mo,
//     SystemIdentification/FirstOrderTimeDelay/{ControlProcessModel,BaseClasses/Gain,
//     BaseClasses/TimeConstantDelay}.mo, AutoTuner/AMIGO/BaseClasses/{PIDGain,PIDIntegralTime,
//     PIDDerivativeTime,PIGain,PIIntegralTime}.mo
//   Buildings/Resources/ReferenceResults/Dymola/
//     Buildings_Controls_OBC_Utilities_PIDWithAutotuning_Validation_ReverseActingPIDWithFirstOrderAMIGO.txt
//     Buildings_Controls_OBC_Utilities_PIDWithAutotuning_Validation_ReverseActingPIWithFirstOrderAMIGO.txt
//   (Dymola, Cvode, tolerance 1e-6, stop 10000 s: the .mos scripts under
//   Buildings/Resources/Scripts/Dymola/Controls/OBC/Utilities/PIDWithAutotuning/Validation/).
//
// Their plant: the relay output u goes through uniDel2, a CDL UnitDelay with
// samplePeriod 240 s (u sampled at t = 240 j and put out from t = 240 (j+1):
// a zero-order hold plus one sample of delay), then through
// "sub2 = u_d - derivative2(u_d)" with derivative2 = k s/(T s + 1), k = T = 10,
// which is u_d/(10 s + 1). So K = 1, T = 10 s and a sampled delay of 240 to
// 480 s: L/T near 47, nearly a pure delay, and not a FOPDT (the delay depends
// on where a switch falls between samples).
//
// Their relay (FirstOrderAMIGO with yHig = 1, yLow = 0, yRef = 0.8,
// deaBan = 0.1, r = 1, yMax = 1, yMin = 0; setpoint 0.8, reverse acting):
// Relay/Controller.mo puts out yHig once (u_s - u_m)/r > deaBan, yLow once it
// is < -deaBan, and holds in between; the identification uses
// yHig - yRef = 0.2 and yRef - yLow = 0.8 as the relay's amplitudes. Onto
// pidlab's RelayOptions (e = y - r, v = u - u0):
//   setpoint = 0.8, u0 = yRef = 0.8 (the plant's gain is 1: y = r at rest),
//   d_high = yHig - yRef = 0.2, d_low = yRef - yLow = 0.8,
//   hysteresis = deaBan r = 0.1,
// so u = 1 below y = 0.7 and u = 0 above y = 0.9, as theirs.
//
// Their reference results hold the tuned gains, not K, T, L; the model is
// behind AMIGO's three PID formulas, which invert to it (InvertAmigoPid). The
// file holds two tunings: the first (triggered at 500 s, gains from 1924 s) and
// the final one (triggered at 6500 s, gains from 7943 s), which differ
// because their protocol (TuningMonitor.mo) ends a tuning at the third relay
// switch and takes K's integral over the last two half periods: in the first
// tuning those are on the limit cycle, in the second the off half period
// begins from the PID's steady state (see the second test).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/autotune/relay.h"
#include "pidlab/tune/design.h"

namespace pidlab {
namespace {

using autotune::RelayCycle;
using autotune::RelayEstimates;
using autotune::RelayOptions;

// The published gains, PIDWitTun.con.{k,Ti,Td} and PIWitTun.con.{k,Ti}
// (stored as float32 by Dymola) in the two reference files named above: the
// first tuning's (the value at t = 2000 s, unchanged to 6500 s) and the final
// one's (t = 10000 s).
struct PidGains3 {
  double k, ti_s, td_s;
};
struct PiGains2 {
  double k, ti_s;
};
constexpr PidGains3 kTheirFirstPid{0.2114173322916031, 196.134521484375, 36.44467926025391};
constexpr PidGains3 kTheirFinalPid{0.2124186754226685, 197.326171875, 23.21598815917969};
constexpr PiGains2 kTheirFirstPi{0.1563226282596588, 156.9215545654297};
constexpr PiGains2 kTheirFinalPi{0.1586953699588776, 163.3043823242188};
// The plant's output before the second tuning's first relay sample reaches
// it at 6960 s: PIDWitTun.u_m and PIWitTun.u_m at 6900 s in the two files
// (the PID's last sample, held since 6720 s; the relay is held high since
// 1924 s, u_m having stayed within 0.7..0.9).
constexpr double kTheirPidYBeforeSecondTuning = 0.7986278533935547;
constexpr double kTheirPiYBeforeSecondTuning = 0.7984354496002197;

// Their plant and relay (the file comment).
constexpr double kSamplePeriod = 240.0, kLag = 10.0;
constexpr double kYHig = 1.0, kYLow = 0.0, kYRef = 0.8, kDeaBan = 0.1, kSetpoint = 0.8;
constexpr double kHigh = kYHig - kYRef, kLow = kYRef - kYLow;  // 0.2, 0.8
constexpr double kStep = 1e-3;                                 // s; 240 s is 240000 steps
constexpr long kStepsPerSample = 240000;

RelayOptions TheirRelay() {
  RelayOptions o;
  o.setpoint = kSetpoint;
  o.u0 = kYRef;
  o.d_high = kHigh;
  o.d_low = kLow;
  o.hysteresis = kDeaBan;
  return o;
}

// Their plant from t = n0 h, at rest at y0 (the hold's current and pending
// samples y0), the relay sampling y every h: the hold's samples are exact
// (h divides 240 s) and the lag's update is exact for its held input, so the
// only error is the relay's switch, up to h late. `observe` sees (t, y, u)
// each step; the run stops when `stop` says so or at t_end.
void RunTheirPlant(RelayTuner* relay, double y0, long n0, double t_end,
                   const std::function<void(double, double, double)>& observe,
                   const std::function<bool()>& stop) {
  const double a = std::exp(-kStep / kLag);
  double x = y0, held = y0, out = y0;
  for (long n = n0; n * kStep < t_end; ++n) {
    const double t = n * kStep;
    const double u = relay->Step(t, kSetpoint, x);
    if (observe) observe(t, x, u);
    if (n % kStepsPerSample == 0) {  // UnitDelay: y = pre(sample), sample = u
      out = held;
      held = u;
    }
    x = a * x + (1.0 - a) * out;
    if (stop && stop()) return;
  }
}

// The mean of the last three cycles, as Estimate() averages them.
RelayCycle MeanOfSettled(const std::vector<RelayCycle>& cycles, int n) {
  RelayCycle m;
  for (int i = 0; i < n; ++i) {
    const RelayCycle& c = cycles[cycles.size() - 1 - i];
    m.t_on_s += c.t_on_s / n;
    m.t_off_s += c.t_off_s / n;
    m.e_max += c.e_max / n;
    m.e_min += c.e_min / n;
    m.integral_e += c.integral_e / n;
  }
  return m;
}

// Their identification (Berner 2017), as their blocks compute it, with
// yHig - yRef and yRef - yLow as the amplitudes (ControlProcessModel's
// yHig and yLow):
//   Gain.mo:               k = Iy / (tOn yHig - tOff yLow + 1e-3), Iy = integral of (u_m - u_s)/r
//   HalfPeriodRatio.mo:    rho = max(tOn, tOff) / min(tOn, tOff)
//   ResponseProcess.mo:    gamma = max(yHig, yLow) / min(yHig, yLow)
//   NormalizedTimeDelay.mo: tau = (gamma - rho) / (gamma - 1) / (0.35 rho + 0.65)
//   TimeConstantDelay.mo:  T = tOn / ln((deaBan/|k| - yLow + e^(tau/(1-tau)) (yHig + yLow)) / (yHig -
//   deaBan/|k|)),
//                          L = T tau / (1 - tau)
// The T equation is the FOPDT's exact t_on (relay.h's closed form, times
// e^(L/T) inside the logarithm); tau from rho is Berner's empirical fit.
struct Fopdt {
  double k, t_s, l_s;
};
Fopdt Berner(double t_on, double t_off, double integral_e) {
  const double k = integral_e / (t_on * kHigh - t_off * kLow + 1e-3);
  const double rho = std::max(t_on, t_off) / std::min(t_on, t_off);
  const double gamma = std::max(kHigh, kLow) / std::min(kHigh, kLow);
  const double tau = (gamma - rho) / (gamma - 1.0) / (0.35 * rho + 0.65);
  const double ratio = tau / (1.0 - tau);
  const double d = kDeaBan / std::abs(k);
  const double t = t_on / std::log((d - kLow + std::exp(ratio) * (kHigh + kLow)) / (kHigh - d));
  return {k, t, t * ratio};
}

// AMIGO (Åström and Hägglund 2004) as their AutoTuner/AMIGO/BaseClasses compute it.
PidGains3 AmigoPid(const Fopdt& m) {
  return {(0.2 + 0.45 * m.t_s / m.l_s) / m.k, m.l_s * (0.4 * m.l_s + 0.8 * m.t_s) / (m.l_s + 0.1 * m.t_s),
          0.5 * m.l_s * m.t_s / (0.3 * m.l_s + m.t_s)};
}
PiGains2 AmigoPi(const Fopdt& m) {
  const double t = m.t_s, l = m.l_s;
  return {0.15 / m.k + (0.35 - l * t / ((l + t) * (l + t))) * t / (m.k * l),
          0.35 * l + 13.0 * l * t * t / (t * t + 12.0 * l * t + 7.0 * l * l)};
}

// The model behind AMIGO PID gains: Ti/Td fixes x = T/L through
// (0.05 R - 0.8) x^2 + (0.5 R - 0.64) x - 0.12 = 0, R = Ti/Td; of its two
// roots the delay-dominant one (x < 1; the other gives K near 9 here), then
// L from Td and K from k.
Fopdt InvertAmigoPid(const PidGains3& g) {
  const double r = g.ti_s / g.td_s;
  const double a = 0.05 * r - 0.8, b = 0.5 * r - 0.64, c = -0.12;
  const double root1 = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  const double root2 = (-b - std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  const double x = (root1 > 0.0 && root1 < 1.0) ? root1 : root2;
  const double l = g.td_s * (0.3 + x) / (0.5 * x);
  return {(0.2 + 0.45 * x) / g.k, x * l, l};
}

double Rel(double got, double want) { return std::abs(got - want) / std::abs(want); }

// Tolerance against their published gains: 0.1 %. Their Dymola run locates
// events to its 1e-6 tolerance and stores float32; the switch here is up to
// h = 1 ms late, 2e-6 of a half period; Berner's T and L amplify the
// half-period ratio's error about tenfold (tau near 0.94, e^(tau/(1-tau))
// inside the logarithm), so agreement to 1e-4..1e-3 is what an identical
// cycle gives. The formulas are the same: only the cycle can differ.
constexpr double kGainTolerance = 1e-3;

// The limit cycle of their sampled plant, in closed form: a switch to high
// falls 10 ln(1/0.7) s after a sample instant (y falling from 1 crosses 0.7),
// a switch to low 10 ln(10) s after one (y rising from 0 crosses 0.9); the
// hold applies each two samples (480 s) after the instant before the switch.
// The plant's input is 480 s at 1 and 480 s at 0, so the integral of e over a
// period is (0.5 - 0.8) 960 s = -288.
const double kSwitchLow = kLag * std::log(10.0), kSwitchHigh = kLag * std::log(1.0 / 0.7);
const double kTOn = 2.0 * kSamplePeriod + kSwitchLow - kSwitchHigh;   // 499.459 s
const double kTOff = 2.0 * kSamplePeriod - kSwitchLow + kSwitchHigh;  // 460.541 s
constexpr double kIntegral = (0.5 - kSetpoint) * 4.0 * kSamplePeriod;

TEST(RelayAgainstModelicaBuildings, IdentifiesTheirValidationPlantAsTheirReferenceResultsDo) {
  RelayOptions o = TheirRelay();
  RelayTuner relay = autotune::BareRelay(o, kStep);
  RunTheirPlant(&relay, kSetpoint, 0, 40000.0, nullptr, [&] { return relay.phase() == RelayPhase::kDone; });
  ASSERT_EQ(relay.phase(), RelayPhase::kDone) << relay.why() << ": " << relay.cycles().size() << " cycles";
  const RelayCycle c = MeanOfSettled(relay.cycles(), o.settled_cycles);

  // pidlab's relay measures the sampled plant's limit cycle.
  EXPECT_NEAR(c.t_on_s, kTOn, 2.0 * kStep);
  EXPECT_NEAR(c.t_off_s, kTOff, 2.0 * kStep);
  EXPECT_LT(Rel(c.integral_e, kIntegral), 1e-4) << c.integral_e;

  // Their formulas on pidlab's cycle give their published gains, PID and PI.
  const Fopdt theirs = Berner(c.t_on_s, c.t_off_s, c.integral_e);
  const PidGains3 pid = AmigoPid(theirs);
  EXPECT_LT(Rel(pid.k, kTheirFirstPid.k), kGainTolerance) << pid.k;
  EXPECT_LT(Rel(pid.ti_s, kTheirFirstPid.ti_s), kGainTolerance) << pid.ti_s;
  EXPECT_LT(Rel(pid.td_s, kTheirFirstPid.td_s), kGainTolerance) << pid.td_s;
  const PiGains2 pi = AmigoPi(theirs);
  EXPECT_LT(Rel(pi.k, kTheirFirstPi.k), kGainTolerance) << pi.k;
  EXPECT_LT(Rel(pi.ti_s, kTheirFirstPi.ti_s), kGainTolerance) << pi.ti_s;

  // Their model, from their gains: K 1.0725, T 26.20 s, L 440.9 s.
  const Fopdt published = InvertAmigoPid(kTheirFirstPid);
  EXPECT_LT(Rel(theirs.k, published.k), kGainTolerance) << published.k;
  EXPECT_LT(Rel(theirs.t_s, published.t_s), kGainTolerance) << published.t_s;
  EXPECT_LT(Rel(theirs.l_s, published.l_s), kGainTolerance) << published.l_s;

  // pidlab's gain is theirs (the same integral over the same cycle, without
  // their 1e-3 guard): both 7.2 % above the plant's 1, because the hold delays
  // the switch to high 19.5 s less than the switch to low, so the relay's
  // duty (499.5 s high, 460.5 s low) is not the plant input's (480 s each).
  const RelayEstimates e = autotune::EstimateBare(o, relay);
  ASSERT_TRUE(e.converged);
  ASSERT_TRUE(e.model_found) << e.message;
  EXPECT_FALSE(e.model.integrating);
  EXPECT_LT(Rel(e.model.gain, published.k), kGainTolerance) << e.model.gain;
  EXPECT_NEAR(e.model.gain, 1.0725, 0.001);
  EXPECT_NEAR(e.period_s, 4.0 * kSamplePeriod, 2.0 * kStep);  // four samples
}

// Their second tuning: triggered at 6500 s (20 s after a sample instant)
// with y at the PID's steady state y0 and the relay held high. Their protocol
// (OnOffPeriod, TuningMonitor, Gain) integrates from the first switch to the
// third and takes tOff from the first to the second, tOn from the second to
// the third. pidlab's relay switches here; the window is kept alongside.
struct Window {
  std::vector<double> switches;
  double integral_e = 0.0;
};
Window SecondTuningWindow(double y0) {
  RelayTuner relay = autotune::BareRelay(TheirRelay(), kStep);
  Window w;
  double t_prev = 0.0, e_prev = 0.0, u_prev = -1.0;
  RunTheirPlant(
      &relay, y0, 6500000, 12000.0,
      [&](double t, double y, double u) {
        const double e = y - kSetpoint;
        if (w.switches.size() == 1 || w.switches.size() == 2)
          w.integral_e += 0.5 * (e + e_prev) * (t - t_prev);
        if (u_prev >= 0.0 && u != u_prev) w.switches.push_back(t);
        t_prev = t;
        e_prev = e;
        u_prev = u;
      },
      [&] { return w.switches.size() >= 3; });
  return w;
}

TEST(RelayAgainstModelicaBuildings, TheirFinalGainsComeFromAWindowThatStartsOffTheLimitCycle) {
  const Window w = SecondTuningWindow(kTheirPidYBeforeSecondTuning);
  ASSERT_EQ(w.switches.size(), 3u);
  // The first switch (to low) as y rises from y0 at 6960 s through 0.9.
  EXPECT_NEAR(w.switches[0], 6960.0 + kLag * std::log((1.0 - kTheirPidYBeforeSecondTuning) / 0.1),
              2.0 * kStep);
  const double t_on = w.switches[2] - w.switches[1], t_off = w.switches[1] - w.switches[0];
  EXPECT_NEAR(t_on, kTOn, 2.0 * kStep);  // on the limit cycle
  EXPECT_GT(t_off - kTOff, 15.0);        // 476.6 s, not the cycle's 460.5 s

  const Fopdt theirs = Berner(t_on, t_off, w.integral_e);
  const PidGains3 pid = AmigoPid(theirs);
  EXPECT_LT(Rel(pid.k, kTheirFinalPid.k), kGainTolerance) << pid.k;
  EXPECT_LT(Rel(pid.ti_s, kTheirFinalPid.ti_s), kGainTolerance) << pid.ti_s;
  EXPECT_LT(Rel(pid.td_s, kTheirFinalPid.td_s), kGainTolerance) << pid.td_s;
  // Their final model (K 1.012, T 15.5 s, L 464 s) is that window's.
  const Fopdt published = InvertAmigoPid(kTheirFinalPid);
  EXPECT_LT(Rel(theirs.k, published.k), kGainTolerance) << published.k;
  EXPECT_LT(Rel(theirs.t_s, published.t_s), kGainTolerance) << published.t_s;
  EXPECT_LT(Rel(theirs.l_s, published.l_s), kGainTolerance) << published.l_s;

  // The PI file's second tuning, from its own y0.
  const Window w_pi = SecondTuningWindow(kTheirPiYBeforeSecondTuning);
  ASSERT_EQ(w_pi.switches.size(), 3u);
  const PiGains2 pi = AmigoPi(
      Berner(w_pi.switches[2] - w_pi.switches[1], w_pi.switches[1] - w_pi.switches[0], w_pi.integral_e));
  EXPECT_LT(Rel(pi.k, kTheirFinalPi.k), kGainTolerance) << pi.k;
  EXPECT_LT(Rel(pi.ti_s, kTheirFinalPi.ti_s), kGainTolerance) << pi.ti_s;
}

// pidlab's own model of their plant against the plant and against theirs.
// The plant is no FOPDT: the hold makes the delay 480 s - 3.57 s = 476.4 s
// after a switch to high and 480 s - 23.03 s = 457.0 s after a switch to low,
// and L/T near 47 puts e^(-L/T) (4e-21) below anything the cycle's extremes
// can show: they measure only the gain's 7.2 % bias (e_max = 0.2, e_min =
// -0.8 exactly), and read as a FOPDT they give T 143.7 s, L 328.8 s. pidlab
// sees that the two half periods then give T 10 % apart (a FOPDT's agree),
// refuses the extremes and takes the model from the half periods and the
// integrals (FopdtFromTimes, the level the relay really switched at solved
// from the integral over the part at +d_high): K 1.0725, T 20.6 s, L 453.4 s,
// Ku 0.941, Pu 948 s. Berner's tau, fitted to the half-period ratio alone,
// gives T 26.2 s, L 440.9 s, Ku 0.947, Pu 934 s. The true ultimate point of
// the sampled loop (a gain k on z^-1 (1 - a)/(z - a), a = e^-24) is Ku =
// 1/(1 - a) = 1 and Pu = 4 samples = 960 s; the truth's T is 10 s and its L
// 457..476 s. pidlab's T, L and Pu are nearer the truth than theirs, its Ku
// as near.
TEST(RelayAgainstModelicaBuildings, OnTheirSampledNearPureDelayPlantPidlabsModelIsNearerTheTruthThanBerners) {
  RelayOptions o = TheirRelay();
  RelayTuner relay = autotune::BareRelay(o, kStep);
  RunTheirPlant(&relay, kSetpoint, 0, 40000.0, nullptr, [&] { return relay.phase() == RelayPhase::kDone; });
  const RelayEstimates e = autotune::EstimateBare(o, relay);
  ASSERT_TRUE(e.converged);
  ASSERT_TRUE(e.model_found) << e.message;
  const RelayCycle c = MeanOfSettled(relay.cycles(), o.settled_cycles);
  const Fopdt theirs = Berner(c.t_on_s, c.t_off_s, c.integral_e);
  const double l_after_low = 2.0 * kSamplePeriod - kSwitchLow;    // 457.0 s
  const double l_after_high = 2.0 * kSamplePeriod - kSwitchHigh;  // 476.4 s

  EXPECT_NEAR(c.e_max, kHigh, 1e-6);  // the extremes are the plant's gain, 1, times the amplitudes
  EXPECT_NEAR(c.e_min, -kLow, 1e-6);
  autotune::FopdtModel by_extremes;
  EXPECT_FALSE(autotune::FopdtFromCycle(o, c, &by_extremes).ok());
  EXPECT_EQ(e.model_from, "switching times and integrals");
  // K: the same 7.2 % bias in both (the first test).
  EXPECT_LT(Rel(e.model.gain, 1.0), 0.08);
  EXPECT_NEAR(e.model.gain, theirs.k, 1e-3);
  // T (truth 10 s): pidlab 20.6 s, theirs 26.2 s.
  EXPECT_LT(std::abs(e.model.time_constant_s - kLag), std::abs(theirs.t_s - kLag)) << e.model.time_constant_s;
  // L (truth 457..476 s): pidlab 0.8 % short of 457 s, theirs 3.5 %.
  EXPECT_GT(e.model.delay_s, 0.98 * l_after_low) << e.model.delay_s;
  EXPECT_LT(e.model.delay_s, l_after_high) << e.model.delay_s;
  EXPECT_GT(theirs.l_s, 0.95 * l_after_low) << theirs.l_s;
  EXPECT_LT(std::abs(e.model.delay_s - l_after_low), std::abs(theirs.l_s - l_after_low));
  // The ultimate point (truth Ku 1, Pu 960 s).
  EXPECT_NEAR(e.period_s, 4.0 * kSamplePeriod, 2.0 * kStep);
  autotune::FopdtModel their_model;
  their_model.gain = theirs.k;
  their_model.time_constant_s = theirs.t_s;
  their_model.delay_s = theirs.l_s;
  double ku = 0.0, pu = 0.0;
  ASSERT_TRUE(autotune::FopdtUltimate(their_model, &ku, &pu).ok());
  EXPECT_LT(Rel(ku, 1.0), 0.06) << ku;
  EXPECT_LT(Rel(pu, 4.0 * kSamplePeriod), 0.03) << pu;
  EXPECT_LT(Rel(e.ku, 1.0), 0.06) << e.ku;
  EXPECT_LT(Rel(e.pu_s, 4.0 * kSamplePeriod), 0.02) << e.pu_s;
  EXPECT_LT(Rel(e.pu_s, 4.0 * kSamplePeriod), Rel(pu, 4.0 * kSamplePeriod));
}

}  // namespace
}  // namespace pidlab

namespace pidlab {
namespace {

// Their plant is a sample-and-hold: the relay run on its 240 s grid (a PLC
// scans so), the estimates told so (RelayOptions::sample_period_s), fit the
// sampled first order plus dead time y(k+1) = a y(k) + (1 - a) K v(k - n):
// the cycle is 480 s high and 480 s low, the plant input's own duty, so K is
// the plant's 1 with no duty bias; n = 1 (the unit delay; the hold is in the
// ZOH image); a is e^-24 in truth, below the cycle's rounding, so only
// T < 240 s is known and does not matter. The sampled loop's ultimate point
// is then the truth's, Ku 1 and Pu 960 s, nearer than their first (0.947)
// and final (0.993) tunings' models. The design engine on the model and the
// sampled loop gives gains whose loop on the true plant meets its Ms.
TEST(RelayAgainstModelicaBuildings, OnTheirSampleGridTheSampledModelGivesTheTrueUltimatePointAndGains) {
  RelayOptions o = TheirRelay();
  o.sample_period_s = kSamplePeriod;
  RelayTuner relay = autotune::BareRelay(o, kSamplePeriod);
  const double a = std::exp(-kStep / kLag);
  double x = kSetpoint, held = kSetpoint, out = kSetpoint;
  for (long n = 0; n * kStep < 40000.0 && relay.phase() != RelayPhase::kDone; ++n) {
    if (n % kStepsPerSample == 0) {  // the relay samples y and the hold u at the same instant
      out = held;
      held = relay.Step(n * kStep, kSetpoint, x);
    }
    x = a * x + (1.0 - a) * out;
  }
  ASSERT_EQ(relay.phase(), RelayPhase::kDone) << relay.why();
  const RelayEstimates e = autotune::EstimateBare(o, relay);
  ASSERT_TRUE(e.model_found) << e.message;
  EXPECT_EQ(e.model_from, "the sampled cycle (a sample-and-hold of 240 s, the relay on its grid)");
  EXPECT_NEAR(e.model.gain, 1.0, 1e-6);
  EXPECT_EQ(e.model.delay_s, kSamplePeriod);
  EXPECT_LT(e.model.time_constant_s, kSamplePeriod);
  EXPECT_NEAR(e.ku, 1.0, 1e-6);
  EXPECT_NEAR(e.pu_s, 4.0 * kSamplePeriod, 1e-6 * 4.0 * kSamplePeriod);
  // Nearer the truth than either of their tunings' models, and than pidlab's continuous fit (0.941).
  double ku_first = 0.0, ku_final = 0.0, pu = 0.0;
  const Fopdt first = InvertAmigoPid(kTheirFirstPid), final = InvertAmigoPid(kTheirFinalPid);
  ASSERT_TRUE(autotune::FopdtUltimate({first.k, first.t_s, first.l_s}, &ku_first, &pu).ok());
  ASSERT_TRUE(autotune::FopdtUltimate({final.k, final.t_s, final.l_s}, &ku_final, &pu).ok());
  EXPECT_NEAR(ku_first, 0.9468, 1e-4);
  EXPECT_NEAR(ku_final, 0.9930, 1e-4);
  EXPECT_LT(std::abs(e.ku - 1.0), 0.1 * std::abs(ku_final - 1.0));

  // Gains: the design engine on the model, for the sampled loop at 240 s.
  Plant model;
  model.name = "custom";
  model.tf.num = {e.model.gain};
  model.tf.den = {e.model.time_constant_s, 1.0};
  model.delay_s = e.model.delay_s;
  tune::DesignOptions d;
  d.max_ms = 1.4;
  d.loop.loop = evaluation::LoopKind::kSampled;
  d.loop.dt_s = kSamplePeriod;
  d.loop.sample_time_s = kSamplePeriod;
  d.loop.horizon_s = 100 * kSamplePeriod;
  tune::DesignSummary g;
  ASSERT_TRUE(tune::DesignOptimal(model, d, &g).ok());
  Plant truth = model;
  truth.tf.num = {1.0};
  truth.tf.den = {kLag, 1.0};
  truth.delay_s = kSamplePeriod;
  analysis::LoopAnalysis on_truth;
  ASSERT_TRUE(analysis::AnalyzeLoop(truth, g.gains, d.loop, analysis::LoopAnalysisOptions{}, &on_truth).ok());
  EXPECT_TRUE(on_truth.stable);
  EXPECT_NEAR(on_truth.ms, 1.4, 0.014)
      << "kp " << g.gains.kp << ", ki " << g.gains.ki << ", kd " << g.gains.kd;
  std::printf(
      "sampled model: K %.6g, T %.4g s, L %.4g s; Ku %.6g, Pu %.6g s (their first %.4g, final %.4g); "
      "gains kp %.4g ki %.4g kd %.4g, Ms on the true plant %.4g\n",
      e.model.gain, e.model.time_constant_s, e.model.delay_s, e.ku, e.pu_s, ku_first, ku_final, g.gains.kp,
      g.gains.ki, g.gains.kd, on_truth.ms);
}

}  // namespace
}  // namespace pidlab
