// The exported C controller (controller/export/) compiled by the C compiler
// against DiscretePid, the controller it must reproduce: bit for bit in
// double, within 1e-5 relative in float, over 10^5 random steps with
// saturation, every integration rule and anti-windup, filter on and off,
// gain and sample-time changes and manual/auto switches.

#include "pidlab/controller_export/export.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "export/compiled_module.h"
#include "pidlab/controller/pid.h"
#include "pidlab/controller/relay.h"

namespace pidlab {

// DiscretePid's state, read and written by the test only: the explicit
// instantiation of a template may name private members, and the friend
// function it defines hands out the member pointer. The reference needs it to
// carry the state across a change of gains or sample time (DiscretePid has
// no setters) and to track a manual output.
template <typename Tag, typename Tag::type Member>
struct StateAccess {
  friend typename Tag::type Get(Tag) { return Member; }
};
struct IntegralTag {
  using type = double DiscretePid<double>::*;
  friend type Get(IntegralTag);
};
struct DerivativeTag {
  using type = double DiscretePid<double>::*;
  friend type Get(DerivativeTag);
};
struct PrevErrorTag {
  using type = double DiscretePid<double>::*;
  friend type Get(PrevErrorTag);
};
struct PrevSignalTag {
  using type = double DiscretePid<double>::*;
  friend type Get(PrevSignalTag);
};
template struct StateAccess<IntegralTag, &DiscretePid<double>::integral_>;
template struct StateAccess<DerivativeTag, &DiscretePid<double>::derivative_>;
template struct StateAccess<PrevErrorTag, &DiscretePid<double>::prev_error_>;
template struct StateAccess<PrevSignalTag, &DiscretePid<double>::prev_signal_>;

namespace controller_export {
namespace {

double& Integral(DiscretePid<double>* p) { return p->*Get(IntegralTag{}); }
double& Derivative(DiscretePid<double>* p) { return p->*Get(DerivativeTag{}); }
double& PrevError(DiscretePid<double>* p) { return p->*Get(PrevErrorTag{}); }
double& PrevSignal(DiscretePid<double>* p) { return p->*Get(PrevSignalTag{}); }

// The derivative's setpoint weight c (1 on the error, 0 on the measurement)
// in DiscretePid's options: derivative_on today, setpoint_weight_c once the
// 2-DOF PID replaces it; each is set where it exists (overload resolution
// takes the int overload where it compiles), so the test runs on both.
template <typename O>
auto SetDerivativeOnField(O* o, double c, int) -> decltype(o->derivative_on = DerivativeOn::kError, void()) {
  o->derivative_on = c == 1.0 ? DerivativeOn::kError : DerivativeOn::kMeasurement;
}
template <typename O>
void SetDerivativeOnField(O*, double, long) {}
template <typename O>
auto SetWeightDField(O* o, double c, int) -> decltype(o->setpoint_weight_c = c, void()) {
  o->setpoint_weight_c = c;
}
template <typename O>
void SetWeightDField(O*, double, long) {}
void SetWeightD(PidOptions* o, double c) {
  SetDerivativeOnField(o, c, 0);
  SetWeightDField(o, c, 0);
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// DiscretePid with the exported module's run-time operations, each written
/// in DiscretePid's terms: a gain change is a new DiscretePid with the old
/// state, its integrator moved by the change of the last proportional term;
/// manual is a normal step whose integrator is then set to u - p - D. With
/// b = 1 (today's DiscretePid); c = 1 is derivative on error, 0 on
/// measurement.
class Reference {
 public:
  Reference(const PidGains& g, const PidOptions& o, double c) : gains_(g), options_(o), c_(c) {
    SetWeightD(&options_, c_);
    pid_ = std::make_unique<DiscretePid<double>>(gains_, options_);
  }
  double c() const { return c_; }

  int Step(double r, double y, double* u) {
    if (!manual_) {
      const int status = static_cast<int>(pid_->Step(r, y, u));
      if (status != static_cast<int>(PidStatus::kInvalidInput)) Remember(r, y);
      return status;
    }
    double ignored = 0.0;
    if (pid_->Step(r, y, &ignored) == PidStatus::kInvalidInput) return 2;
    const double p = gains_.kp * (1.0 * r - y);
    Integral(pid_.get()) = manual_output_ - p - Derivative(pid_.get());
    *u = manual_output_;
    Remember(r, y);
    return 0;
  }
  void SetManual(double u) {
    manual_ = true;
    if (u > options_.output_max) u = options_.output_max;
    if (u < options_.output_min) u = options_.output_min;
    manual_output_ = u;
    Integral(pid_.get()) = manual_output_ - LastP() - Derivative(pid_.get());
  }
  void SetAuto() { manual_ = false; }
  void SetGains(const PidGains& g) {
    const double before = LastP();
    gains_ = g;
    Rebuild();
    Integral(pid_.get()) += before - LastP();
  }
  void SetC(double c) {
    c_ = c;
    SetWeightD(&options_, c);
    Rebuild();
    PrevSignal(pid_.get()) = c * prev_r_ - prev_y_;
  }
  void SetSampleTime(double dt_s) {
    options_.dt_s = dt_s;
    Rebuild();
  }
  const PidGains& gains() const { return gains_; }
  const PidOptions& options() const { return options_; }
  bool manual() const { return manual_; }
  /// How far the inputs alone moved the unsaturated output at the last step:
  /// |p_k - p_{k-1}| + |I_k - I_{k-1}| (before anti-windup) + |D_k - D_{k-1}|.
  double jump_bound() const { return jump_bound_; }
  /// The largest term of the last output, |p|, |I| or |D|: the size float's
  /// rounding is relative to.
  double term_scale() const { return term_scale_; }
  /// The largest term_scale() so far: what float's integrator rounded at.
  double peak_term_scale() const { return peak_term_scale_; }

 private:
  double LastP() const { return gains_.kp * (1.0 * prev_r_ - prev_y_); }
  void Remember(double r, double y) {
    jump_bound_ = std::fabs(gains_.kp * (r - y) - LastP()) +
                  std::fabs(gains_.ki) * options_.dt_s * (std::fabs(r - y) + std::fabs(prev_r_ - prev_y_)) +
                  std::fabs(Derivative(pid_.get()) - last_d_);
    last_d_ = Derivative(pid_.get());
    term_scale_ =
        std::max({std::fabs(gains_.kp * (r - y)), std::fabs(Integral(pid_.get())), std::fabs(last_d_)});
    peak_term_scale_ = std::max(peak_term_scale_, term_scale_);
    prev_r_ = r;
    prev_y_ = y;
  }
  void Rebuild() {
    auto next = std::make_unique<DiscretePid<double>>(gains_, options_);
    Integral(next.get()) = Integral(pid_.get());
    Derivative(next.get()) = Derivative(pid_.get());
    PrevError(next.get()) = PrevError(pid_.get());
    PrevSignal(next.get()) = PrevSignal(pid_.get());
    pid_ = std::move(next);
  }
  PidGains gains_;
  PidOptions options_;
  std::unique_ptr<DiscretePid<double>> pid_;
  double c_ = 1.0;
  double prev_r_ = 0.0, prev_y_ = 0.0, last_d_ = 0.0, jump_bound_ = 0.0, term_scale_ = 0.0,
         peak_term_scale_ = 0.0;
  bool manual_ = false;
  double manual_output_ = 0.0;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

bool IsFixed(Scalar s) { return s == Scalar::kQ31 || s == Scalar::kQ15; }

/// A random controller: every integration rule and anti-windup, filter on
/// or off, limits or none, derivative on error or measurement.
Controller RandomController(std::mt19937* rng, Scalar scalar) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Controller c;
  c.gains.kp = 10.0 * unit(*rng);
  c.gains.ki = 20.0 * unit(*rng);
  c.gains.kd = unit(*rng) < 0.2 ? 0.0 : unit(*rng);
  c.gains.tf = unit(*rng) < 0.4 ? 0.0 : 0.001 + 0.1 * unit(*rng);
  c.pid.dt_s = std::pow(10.0, -4.0 + 2.0 * unit(*rng));
  const int limits = static_cast<int>(4.0 * unit(*rng));
  c.pid.output_min = limits == 0 || limits == 2 ? -kInf : -0.5 - 2.0 * unit(*rng);
  c.pid.output_max = limits == 0 || limits == 3 ? kInf : 0.5 + 2.0 * unit(*rng);
  c.pid.anti_windup = static_cast<AntiWindup>(static_cast<int>(3.0 * unit(*rng)));
  if (IsFixed(scalar)) {
    // Fixed point: finite limits (they set the output's scale) and an
    // anti-windup (without one its integrator saturates where DiscretePid's
    // grows on: documented, tested apart).
    c.pid.output_min = -0.5 - 2.0 * unit(*rng);
    c.pid.output_max = 0.5 + 2.0 * unit(*rng);
    if (c.pid.anti_windup == AntiWindup::kNone) c.pid.anti_windup = AntiWindup::kClamping;
  }
  c.pid.back_calculation_gain = 0.1 + 50.0 * unit(*rng);
  c.pid.integral = static_cast<IntegralMethod>(static_cast<int>(3.0 * unit(*rng)));
  if (unit(*rng) < 0.5) c.setpoint_weight_c = 0.0;  // derivative on measurement
  return c;
}

ShimConfig ToShim(const Controller& c) {
  ShimConfig s;
  s.kp = c.gains.kp;
  s.ki = c.gains.ki;
  s.kd = c.gains.kd;
  s.tf = EffectiveDerivativeFilter(c.gains, c.pid);
  s.b = c.setpoint_weight_b;
  s.c = c.setpoint_weight_c;
  s.dt_s = c.pid.dt_s;
  s.has_output_min = std::isfinite(c.pid.output_min) ? 1 : 0;
  s.output_min = s.has_output_min ? c.pid.output_min : 0.0;
  s.has_output_max = std::isfinite(c.pid.output_max) ? 1 : 0;
  s.output_max = s.has_output_max ? c.pid.output_max : 0.0;
  s.anti_windup = static_cast<int>(c.pid.anti_windup);
  s.back_calculation_gain = c.pid.back_calculation_gain;
  s.integral = static_cast<int>(c.pid.integral);
  return s;
}

std::string ShimPath(const char* name) { return std::string(PIDLAB_EXPORT_TEST_DIR) + "/" + name; }

GeneratedCode Code(Scalar scalar, const Controller& c) {
  Options o;
  o.scalar = scalar;
  o.input_min = -4.0;
  o.input_max = 4.0;
  o.plant = "oscillator = 1/(s^2+1)";
  o.spec_json = "{\"plant\": \"oscillator\", \"gains\": [1, 2, 3]}";
  o.pidlab_version = "test";
  return Generate(o, c);
}

/// What one random run found.
struct Comparison {
  long steps = 0, mismatches = 0, saturated = 0, manual_switches = 0, changes = 0, outside_limits = 0;
  long jumps = 0;
  double worst_relative = 0.0;       // to Scale(u, peak)
  double worst_relative_to_u = 0.0;  // to Scale(u, no peak)
  double worst_lsb = 0.0;            // fixed point: |u_q - u| in LSB of the output
  // Reverse-acting runs: the gains all <= 0, a tenth of the gain changes
  // turning the direction (counted).
  bool reverse = false;
  long direction_changes = 0;
};

/// Scale of the output for a relative error: the largest of |u|, the
/// limits' half span (1 without limits) and, with `peak`, the largest term
/// |p|, |I|, |D| so far (float rounds at the size of its operands, and what
/// the integrator rounded off while it was large stays in it).
double Scale(double u, const Reference& ref, bool peak = true) {
  const PidOptions& o = ref.options();
  const double span = std::isfinite(o.output_max - o.output_min) ? 0.5 * (o.output_max - o.output_min) : 1.0;
  return std::max({std::fabs(u), span, peak ? ref.peak_term_scale() : 0.0});
}

/// An output limit as the scalar holds it.
double Limit(double v, Scalar scalar, const CompiledModule& m) {
  if (IsFixed(scalar)) return m.quantize_output_(v);
  return scalar == Scalar::kFloat ? static_cast<float>(v) : v;
}

/// A random event between steps: a gain change, a sample-time change, a
/// switch of c, manual/auto.
void RandomEvent(std::mt19937* rng, const CompiledModule& m, void* dut, Reference* ref, Comparison* out) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double what = unit(*rng);
  if (what < 0.3) {
    PidGains g = ref->gains();
    double sign = GainsAreReverse(g) ? -1.0 : 1.0;
    if (out->reverse && unit(*rng) < 0.1) {
      sign = -sign;
      ++out->direction_changes;
    }
    g.kp = sign * 10.0 * unit(*rng);
    g.ki = sign * 20.0 * unit(*rng);
    g.kd = sign * unit(*rng);
    g.tf = unit(*rng) < 0.3 ? 0.0 : 0.001 + 0.1 * unit(*rng);
    if (m.quantize_input_) g.kd *= 100.0 * ref->options().dt_s;
    const int status = m.set_gains_(dut, g.kp, g.ki, g.kd, g.tf);
    if (status == 3 && m.quantize_input_) return;  // beyond the fixed-point range analysis: refused
    ASSERT_EQ(status, 0);
    ref->SetGains(g);
  } else if (what < 0.5) {
    const double dt = std::pow(10.0, -4.0 + 2.0 * unit(*rng));
    const int status = m.set_sample_time_(dut, dt);
    if (status == 3 && m.quantize_input_) return;
    ASSERT_EQ(status, 0);
    ref->SetSampleTime(dt);
  } else if (what < 0.6) {
    const double c = ref->c() == 1.0 ? 0.0 : 1.0;
    const int status = m.set_weights_(dut, 1.0, c);
    if (status == 3 && m.quantize_input_) return;
    ASSERT_EQ(status, 0);
    ref->SetC(c);
  } else if (ref->manual() && what < 0.8) {
    m.set_auto_(dut);
    ref->SetAuto();
    ++out->manual_switches;
  } else {
    double u = -3.0 + 6.0 * unit(*rng);
    if (m.quantize_output_) u = m.quantize_output_(u);
    ASSERT_EQ(m.set_manual_(dut, u), 0);
    ref->SetManual(u);
    ++out->manual_switches;
  }
  ++out->changes;
}

/// `steps` random steps of the compiled module against the reference.
/// exact: compare bits; else the relative error's worst case.
Comparison RunRandom(Scalar scalar, std::uint32_t seed, int controllers, int steps_each,
                     double lsb_tolerance = 0.0, bool reverse = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Comparison out;
  out.reverse = reverse;
  // A double or float module takes every gain and option at run time
  // (shim_new), so one compiled module serves every random controller; a
  // fixed-point module is compiled for each, its Q formats coming from that
  // controller's range analysis.
  std::unique_ptr<CompiledModule> shared, own;
  for (int n = 0; n < controllers; ++n) {
    Controller c = RandomController(&rng, scalar);
    if (IsFixed(scalar)) {
      // A derivative the fixed-point range analysis takes (kd/dt <= 100).
      c.gains.kd *= 100.0 * c.pid.dt_s;
    }
    if (reverse) c.gains = {-c.gains.kp, -c.gains.ki, -c.gains.kd, c.gains.tf};
    std::unique_ptr<CompiledModule>& slot = IsFixed(scalar) ? own : shared;
    if (!slot || IsFixed(scalar))
      slot = std::make_unique<CompiledModule>(Code(scalar, c),
                                              ShimPath(IsFixed(scalar) ? "shim_fixed.c" : "shim_real.c"));
    CompiledModule& m = *slot;
    PidGains g = c.gains;
    g.tf = EffectiveDerivativeFilter(c.gains, c.pid);
    PidOptions o = c.pid;
    o.derivative_filter_s = 0.0;  // the filter in the gains, as the module holds it
    Reference ref(g, o, c.setpoint_weight_c);
    const ShimConfig config = ToShim(c);
    void* dut = m.new_(&config);
    EXPECT_NE(dut, nullptr);
    if (!dut) return out;
    double r = 0.0, y = 0.0, last_u = 0.0;
    bool was_manual = false;
    for (int k = 0; k < steps_each; ++k) {
      if (unit(rng) < 0.01) r = -2.0 + 4.0 * unit(rng);
      y = 0.9 * y + 0.1 * (r + 0.5 * (unit(rng) - 0.5)) + 0.3 * (unit(rng) - 0.5);
      if (scalar == Scalar::kFloat) {
        // The inputs a float controller can be given: the comparison is of
        // the arithmetic, not of rounding y (which kd/dt would amplify).
        r = static_cast<float>(r);
        y = static_cast<float>(y);
      }
      if (IsFixed(scalar)) {
        r = m.quantize_input_(r);
        y = m.quantize_input_(y);
      }
      if (unit(rng) < 0.004) RandomEvent(&rng, m, dut, &ref, &out);
      double u_ref = 0.0, u_dut = 0.0;
      const int s_ref = ref.Step(r, y, &u_ref);
      const int s_dut = m.step_(dut, r, y, &u_dut);
      ++out.steps;
      if (s_ref == 1) ++out.saturated;
      bool same = false;
      if (scalar == Scalar::kDouble)
        same = SameBits(u_ref, u_dut) && s_ref == s_dut;
      else if (scalar == Scalar::kFloat)
        same = std::fabs(u_dut - u_ref) <= 1e-5 * Scale(u_ref, ref);
      else
        same = std::fabs(u_dut - u_ref) <= lsb_tolerance * m.output_lsb_();
      if (IsFixed(scalar))
        out.worst_lsb = std::max(out.worst_lsb, std::fabs(u_dut - u_ref) / m.output_lsb_());
      if (!same && ++out.mismatches <= 5)
        ADD_FAILURE() << "controller " << n << " (dt " << ref.options().dt_s << ", tf " << ref.gains().tf
                      << ", kd " << ref.gains().kd << ", kp " << ref.gains().kp << ", ki " << ref.gains().ki
                      << ", term scale " << ref.term_scale() << ", manual " << ref.manual() << ") step " << k
                      << ": u " << u_dut << " (C) vs " << u_ref << " (DiscretePid), status " << s_dut
                      << " vs " << s_ref;
      out.worst_relative = std::max(out.worst_relative, std::fabs(u_dut - u_ref) / Scale(u_ref, ref));
      out.worst_relative_to_u =
          std::max(out.worst_relative_to_u, std::fabs(u_dut - u_ref) / Scale(u_ref, ref, /*peak=*/false));
      if (u_dut > Limit(ref.options().output_max, scalar, m) ||
          u_dut < Limit(ref.options().output_min, scalar, m))
        ++out.outside_limits;
      // No jump at a manual-to-auto switch: the first automatic output moves
      // from the manual one by no more than the inputs moved it.
      if (was_manual && !ref.manual() &&
          std::fabs(u_dut - last_u) > ref.jump_bound() + 1e-9 * Scale(last_u, ref))
        ++out.jumps;
      was_manual = ref.manual();
      last_u = u_dut;
    }
    m.free_(dut);
  }
  return out;
}

/// The message Generate throws for `c` with `o`, or "" if it does not.
std::string GenerateError(const Options& o, const Controller& c) {
  try {
    Generate(o, c);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Generate, ThrowsNamingGainsThatDifferInSign) {
  Controller c;
  c.gains.kp = -2.0;
  c.gains.ki = 1.0;
  EXPECT_NE(GenerateError(Options{}, c).find("kp = -2"), std::string::npos) << GenerateError(Options{}, c);
}

TEST(Generate, TakesAReverseActingPidInDoubleAndInFixedPointWithTheSameRangeAnalysis) {
  Controller c;
  c.gains = {-2.0, -1.0, -0.1, 0.01};
  c.pid.output_min = -1.0;
  c.pid.output_max = 1.0;
  EXPECT_EQ(GenerateError(Options{}, c), "");
  Options q;
  q.scalar = Scalar::kQ31;
  EXPECT_EQ(GenerateError(q, c), "");
  Controller direct = c;
  direct.gains = {2.0, 1.0, 0.1, 0.01};
  const FixedScale r = FixedPointScale(q, c), d = FixedPointScale(q, direct);
  EXPECT_EQ(r.input_full_scale, d.input_full_scale);
  EXPECT_EQ(r.output_full_scale, d.output_full_scale);
}

TEST(Generate, ThrowsNamingASetpointWeightOutsideZeroOne) {
  Controller c;
  c.setpoint_weight_b = 1.5;
  EXPECT_NE(GenerateError(Options{}, c).find("b = 1.5"), std::string::npos) << GenerateError(Options{}, c);
}

TEST(Generate, ThrowsNamingAnEmptyInputRange) {
  Options o;
  o.input_min = 2.0;
  o.input_max = 2.0;
  EXPECT_NE(GenerateError(o, Controller{}).find("input range [2, 2]"), std::string::npos);
}

TEST(Generate, FixedPointThrowsWithoutFiniteOutputLimits) {
  Options o;
  o.scalar = Scalar::kQ31;
  EXPECT_NE(GenerateError(o, Controller{}).find("finite output limits"), std::string::npos);
}

TEST(Generate, FixedPointThrowsWhenTheWorstCaseDoesNotFit) {
  Options o;
  o.scalar = Scalar::kQ15;
  Controller c;
  c.gains.kd = 1e9;
  c.pid.output_min = -1e-3;
  c.pid.output_max = 1e-3;
  EXPECT_NE(GenerateError(o, c).find("fixed point cannot hold"), std::string::npos) << GenerateError(o, c);
}

TEST(Generate, TheDoubleModuleHoldsTheTunedValuesAndIncludesNothingButItsHeader) {
  Controller c;
  c.gains = {1.25, 0.5, 0.125, 0.0};
  c.pid.derivative_filter_s = 0.01;
  c.pid.dt_s = 0.002;
  const GeneratedCode code = Code(Scalar::kDouble, c);
  EXPECT_NE(code.source.find("1.25, /* kp */"), std::string::npos);
  EXPECT_NE(code.source.find("0.01, /* tf, s */"), std::string::npos) << "tf from the options' filter";
  EXPECT_NE(code.source.find("0.002, /* dt_s, s */"), std::string::npos);
  EXPECT_EQ(code.source.find("#include <"), std::string::npos);
  EXPECT_EQ(code.header.find("#include <"), std::string::npos);
  EXPECT_NE(code.header.find("Plant: oscillator"), std::string::npos);
  EXPECT_NE(code.header.find("Generated by pidlab test"), std::string::npos);
}

TEST(Generate, AStringInTheSpecCannotEndTheComment) {
  Options o;
  const std::string trigraph = std::string("??") + "/";  // spelled apart: C++ warns of it too
  o.spec_json = R"({"model": "x*/ int evil; /*)" + trigraph + "\"}";
  const GeneratedCode code = Generate(o, Controller{});
  EXPECT_EQ(code.header.find("x*/"), std::string::npos);
  EXPECT_EQ(code.header.find(trigraph), std::string::npos);
}

TEST(ExportedPid, DoubleEqualsDiscretePidBitForBitOver100000RandomSteps) {
  const Comparison c = RunRandom(Scalar::kDouble, 20261124, 20, 5000);
  EXPECT_EQ(c.steps, 100000);
  EXPECT_EQ(c.mismatches, 0);
  EXPECT_EQ(c.outside_limits, 0);
  EXPECT_GT(c.saturated, 1000) << "the runs must saturate";
  EXPECT_GT(c.changes, 200);
  EXPECT_GT(c.manual_switches, 50);
  EXPECT_EQ(c.jumps, 0);
}

TEST(ExportedPid, FloatIsWithin1e5RelativeOfDiscretePidOver100000RandomSteps) {
  const Comparison c = RunRandom(Scalar::kFloat, 7, 20, 5000);
  EXPECT_EQ(c.mismatches, 0) << "worst relative error " << c.worst_relative;
  EXPECT_EQ(c.outside_limits, 0);
  std::printf(
      "float: worst |u_float - u_double| / max(|u|, limits' half span, largest term so far) = %.3g; "
      "/ max(|u|, half span) = %.3g\n",
      c.worst_relative, c.worst_relative_to_u);
}

TEST(ExportedPid, Q31IsWithin2LsbOfDiscretePidOver100000RandomSteps) {
  const Comparison c = RunRandom(Scalar::kQ31, 31, 20, 5000, 2.0);
  EXPECT_EQ(c.steps, 100000);
  EXPECT_GT(c.changes, 200);
  EXPECT_GT(c.manual_switches, 50);
  EXPECT_EQ(c.mismatches, 0) << "worst " << c.worst_lsb << " LSB";
  EXPECT_EQ(c.outside_limits, 0);
  EXPECT_GT(c.saturated, 1000);
  EXPECT_EQ(c.jumps, 0);
  std::printf("q31: worst |u_q31 - u_double| = %.3g LSB; %ld saturated steps, %ld changes\n", c.worst_lsb,
              c.saturated, c.changes);
}

TEST(ExportedPid, AReverseActingPidInDoubleEqualsDiscretePidBitForBitAndTurnsDirectionWithoutABump) {
  const Comparison c = RunRandom(Scalar::kDouble, 20261202, 20, 5000, 0.0, true);
  EXPECT_EQ(c.steps, 100000);
  EXPECT_EQ(c.mismatches, 0);
  EXPECT_EQ(c.outside_limits, 0);
  EXPECT_GT(c.saturated, 1000);
  EXPECT_GT(c.direction_changes, 5);
  EXPECT_EQ(c.jumps, 0);
}

TEST(ExportedPid, AReverseActingPidInQ31IsWithin2LsbOfDiscretePidAndTurnsDirectionWithoutABump) {
  const Comparison c = RunRandom(Scalar::kQ31, 3102, 20, 5000, 2.0, true);
  EXPECT_EQ(c.steps, 100000);
  EXPECT_EQ(c.mismatches, 0) << "worst " << c.worst_lsb << " LSB";
  EXPECT_EQ(c.outside_limits, 0);
  EXPECT_GT(c.saturated, 1000);
  EXPECT_GT(c.direction_changes, 5);
  EXPECT_EQ(c.jumps, 0);
}

TEST(ExportedPid, Q15IsWithin1LsbOfDiscretePidOver100000RandomSteps) {
  const Comparison c = RunRandom(Scalar::kQ15, 15, 20, 5000, 1.0);
  EXPECT_EQ(c.steps, 100000);
  EXPECT_GT(c.changes, 200);
  EXPECT_EQ(c.mismatches, 0) << "worst " << c.worst_lsb << " LSB";
  EXPECT_EQ(c.outside_limits, 0);
  EXPECT_EQ(c.jumps, 0);
  std::printf("q15: worst |u_q15 - u_double| = %.3g LSB\n", c.worst_lsb);
}

// ---- The relay autotune (--autotune): the generated pidlab_relay.c against
// RelayTuner (controller/relay.h) on a simulated process, in double and in
// q31 and q15 (RelayTuneOptions::q_bits).

/// What the random relay runs found.
struct RelayComparison {
  long runs = 0, steps = 0, mismatches = 0, cycles = 0, done = 0, aborted = 0, restarted = 0, no_pid = 0;
  long cycles_differ = 0, phases_differ = 0, noise_ends = 0;
  double worst_lsb = 0.0;
};

RelayComparison RunRelayRandom(Scalar scalar, unsigned seed, int runs) {
  RelayComparison out;
  std::mt19937 rng(seed), small_rng(seed + 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Controller headroom;  // the module's range analysis: gains up to these
  headroom.gains = {2.0, 2.0, 0.0};
  headroom.pid.dt_s = 0.01;
  headroom.pid.output_min = -2.0;
  headroom.pid.output_max = 2.0;
  const GeneratedCode code = [&] {
    Options o;
    o.scalar = scalar;
    o.input_min = -4.0;
    o.input_max = 4.0;
    o.autotune = true;
    return Generate(o, headroom);
  }();
  CompiledModule m(code, ShimPath(IsFixed(scalar) ? "shim_fixed.c" : "shim_real.c"));
  EXPECT_NE(m.relay_step_, nullptr);
  if (!m.relay_step_) return out;
  RelayTuneOptions base;
  if (IsFixed(scalar)) {
    Options o;
    o.scalar = scalar;
    o.input_min = -4.0;
    o.input_max = 4.0;
    const FixedScale f = FixedPointScale(o, headroom);
    base.q_bits = f.bits;
    base.input_full_scale = f.input_full_scale;
    base.output_full_scale = f.output_full_scale;
  }
  for (int run = 0; run < runs; ++run) {
    // A FOPDT process K e^(-Ls)/(Ts+1), sometimes noisy, sometimes with a
    // load step; a PI in place or an open-loop hold; a symmetric or biased
    // relay, a heat-only range, and guards that sometimes end the test.
    const double gain = 0.5 + 1.5 * unit(rng), tau = 0.2 + 1.8 * unit(rng), delay = 0.05 + 0.95 * unit(rng);
    const double noise = unit(rng) < 0.3 ? 0.01 + 0.02 * unit(rng) : 0.0;
    const bool load_run = unit(rng) < 0.3;  // a load step while the relay runs, and more cycles
    const bool heat = unit(rng) < 0.25, pid_in_place = unit(rng) < 0.6;
    Controller c = headroom;
    c.pid.output_min = heat ? 0.0 : -2.0;
    c.gains = pid_in_place ? PidGains{0.3 / gain, 0.3 / gain / tau, 0.0} : PidGains{0.0, 0.0, 0.0};
    RelayTuneOptions r = base;
    r.hold_s = 1.0 + 3.0 * unit(rng);
    r.u0 = heat ? 0.5 : 0.0;
    r.amplitude = 0.2 + 0.4 * unit(rng);
    r.bias = unit(rng) < 0.5 ? 0.0 : r.amplitude * (0.6 * unit(rng) - 0.3);
    r.hysteresis = unit(rng) < 0.5 ? 0.0 : 0.01 * unit(rng);
    r.noise_multiple = 3.0;
    r.y_limit = unit(rng) < 0.15 ? 0.05 + 0.2 * unit(rng) : std::numeric_limits<double>::infinity();
    r.settled_cycles = load_run ? 12 : 2 + static_cast<int>(3 * unit(rng));
    r.tolerance = load_run ? 0.01 : 0.01 + 0.04 * unit(rng);
    const double load_at = load_run ? r.hold_s + 6.0 * tau + 6.0 * delay : -1.0;
    const double load = (unit(rng) < 0.5 ? -1.0 : 1.0) * (0.3 + 0.3 * unit(rng)) * r.amplitude * gain;
    r.timeout_periods = r.settled_cycles + 2.0 + 20.0 * unit(rng);
    r.max_restarts = static_cast<int>(3 * unit(rng));
    // Sometimes a relay too small for the noise: K d under the hysteresis 3 sigma.
    // (its own draws, so that the other runs stay as they were)
    if (noise > 0.0 && unit(small_rng) < 0.4) {
      const double small = noise * (0.5 + 1.5 * unit(small_rng)) / gain;
      r.bias *= small / r.amplitude;
      r.amplitude = small;
    }
    const double ref = heat ? 0.3 : 0.0;
    const ShimConfig config = ToShim(c);
    void* pid = m.new_(&config);
    const double v[9] = {r.hold_s,         r.u0,      r.amplitude, r.bias,           r.hysteresis,
                         r.noise_multiple, r.y_limit, r.tolerance, r.timeout_periods};
    void* relay = pid ? m.relay_new_(pid, v, r.settled_cycles, r.max_restarts) : nullptr;
    EXPECT_NE(relay, nullptr) << "run " << run;
    if (!relay) {
      if (pid) m.free_(pid);
      continue;
    }
    RelayTuner tuner(r, c.gains, c.pid);
    const double lsb = IsFixed(scalar) ? std::ldexp(base.output_full_scale, -base.q_bits) : 0.0;
    const int delay_steps = static_cast<int>(std::lround(delay / c.pid.dt_s));
    std::vector<double> pipe(static_cast<std::size_t>(delay_steps) + 1, heat ? 0.5 : 0.0);
    double x = heat ? 0.5 * gain : 0.0;
    const double a = std::exp(-c.pid.dt_s / tau);
    for (int k = 0; k < 8000; ++k) {
      const double t = k * c.pid.dt_s;
      const double y = x + noise * normal(rng) + (load_at >= 0.0 && t >= load_at ? load : 0.0);
      const double u_dut = m.relay_step_(relay, t, ref, y);
      const double u_ref = tuner.Step(t, ref, y);
      ++out.steps;
      const bool same = lsb == 0.0 ? std::memcmp(&u_dut, &u_ref, sizeof u_dut) == 0
                                   : std::abs(u_dut - u_ref) <= FixedRelayLsb(base.q_bits) * lsb;
      if (lsb > 0.0) out.worst_lsb = std::max(out.worst_lsb, std::abs(u_dut - u_ref) / lsb);
      if (!same && ++out.mismatches <= 3)
        ADD_FAILURE() << "run " << run << " step " << k << ": the module's u " << u_dut << ", RelayTuner's "
                      << u_ref << " (phase " << ToString(tuner.phase()) << ")";
      pipe[static_cast<std::size_t>(k) % pipe.size()] = u_dut;
      const double u_delayed = pipe[static_cast<std::size_t>(k + 1) % pipe.size()];
      x = a * x + (1.0 - a) * gain * u_delayed;
    }
    ++out.runs;
    if (m.relay_phase_(relay) != static_cast<int>(tuner.phase())) ++out.phases_differ;
    out.done += tuner.phase() == RelayPhase::kDone;
    out.aborted += tuner.phase() == RelayPhase::kAborted;
    out.noise_ends += tuner.why().find("cannot beat the noise") != std::string::npos;
    out.restarted += tuner.restarts() > 0;
    out.no_pid += !pid_in_place;
    const long n = m.relay_cycle_count_(relay);
    if (n != static_cast<long>(tuner.cycles().size())) ++out.cycles_differ;
    for (long i = 0; i < n && i < static_cast<long>(tuner.cycles().size()); ++i) {
      double got[7];
      const RelayCycle& e = tuner.cycles()[static_cast<std::size_t>(i)];
      const double want[7] = {e.start_s, e.t_on_s,     e.t_off_s,      e.e_max,
                              e.e_min,   e.integral_e, e.integral_on_e};
      ++out.cycles;
      if (!m.relay_cycle_(relay, i, got) || std::memcmp(got, want, sizeof got) != 0) ++out.cycles_differ;
    }
    m.relay_free_(relay);
    m.free_(pid);
  }
  return out;
}

void ExpectRelayEqual(const RelayComparison& c, const char* name) {
  EXPECT_EQ(c.runs, 60);
  EXPECT_EQ(c.mismatches, 0);
  EXPECT_EQ(c.phases_differ, 0);
  EXPECT_EQ(c.cycles_differ, 0);
  EXPECT_GT(c.done, 10) << "the runs must converge";
  EXPECT_GT(c.aborted, 3) << "the guards must end some runs";
  EXPECT_GT(c.restarted, 0) << "a load step must restart some run";
  EXPECT_GT(c.noise_ends, 0) << "a relay too small for the noise must be stopped in some run";
  EXPECT_GT(c.no_pid, 5);
  EXPECT_GT(c.cycles, 250);
  std::printf(
      "%s relay: %ld runs, %ld steps, %ld done, %ld aborted (%ld by the noise), %ld restarted, %ld cycles "
      "equal; worst |u - RelayTuner's| = %.3g LSB\n",
      name, c.runs, c.steps, c.done, c.aborted, c.noise_ends, c.restarted, c.cycles, c.worst_lsb);
}

TEST(ExportedRelay, DoubleEqualsRelayTunerBitForBitOver60RandomProcesses) {
  ExpectRelayEqual(RunRelayRandom(Scalar::kDouble, 43, 60), "double");
}

TEST(ExportedRelay, Q31SwitchesWithRelayTunerAndStaysWithin3LsbOver60RandomProcesses) {
  ExpectRelayEqual(RunRelayRandom(Scalar::kQ31, 4331, 60), "q31");
}

TEST(ExportedRelay, Q15SwitchesWithRelayTunerAndStaysWithin2LsbOver60RandomProcesses) {
  ExpectRelayEqual(RunRelayRandom(Scalar::kQ15, 4315, 60), "q15");
}

TEST(Generate, TheRelayIsRefusedInFloat) {
  Options o;
  o.scalar = Scalar::kFloat;
  o.autotune = true;
  try {
    Generate(o, Controller{});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("float"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace controller_export
}  // namespace pidlab
