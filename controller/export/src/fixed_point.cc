// The fixed-point module (q31, q15): its scalings, its range analysis, and
// the text (c_fixed_template.cc).
//
// Scalings, all powers of two so that the step only shifts:
//   inputs r, y: full scale X >= max(|lo|, |hi|) of the declared input range;
//     inside the step in "input units" of X 2^-31 (q15 inputs times 2^16);
//   output u: full scale U >= max(|output limits|);
//   p, I, D and p + I + D: int64 "accumulator units" of U 2^-(31+G), the
//     guard bits G chosen so that 8 times the worst case fits in 63 bits.
// Coefficients are m 2^-s with a 64-bit m: exactly the double that
// DiscretePid multiplies by (kp, ki dt, ...) times a power of two, and
// the derivative runs as D + (kd ds - dt D) / (tf + dt), the same number as
// DiscretePid's, without rounding the pole tf / (tf + dt) near 1.

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "templates.h"

namespace pidlab::controller_export::internal {
namespace {

double PowerOfTwoAtLeast(double v) {
  double p = 1.0;
  while (p < v) p *= 2.0;
  while (p / 2.0 >= v) p /= 2.0;
  return p;
}

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s = buf;
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

std::string Int(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

void Replace(std::string* text, const std::string& key, const std::string& value) {
  const std::string token = "@" + key + "@";
  for (std::size_t at = text->find(token); at != std::string::npos; at = text->find(token, at + value.size()))
    text->replace(at, token.size(), value);
}

/// The scalings and bounds of one controller.
struct Scaling {
  int nio = 31;
  double range = 0.0, span = 0.0, x = 1.0, u_limit = 0.0, u = 1.0;
  double p_max = 0.0, d_max = 0.0, worst = 0.0, worst_max = 0.0;
  int guard = 0;
  double integral_max = 0.0, input_lo = 0.0, input_hi = 0.0;
};

Scaling Scale(const Options& o, const Controller& c) {
  Scaling s;
  s.nio = o.scalar == Scalar::kQ15 ? 15 : 31;
  if (!std::isfinite(c.pid.output_min) || !std::isfinite(c.pid.output_max))
    throw std::invalid_argument(
        "--scalar " + ToString(o.scalar) +
        " needs finite output limits (--output-limits LO,HI): they set the output's scale");
  s.range = std::max(std::fabs(o.input_min), std::fabs(o.input_max));
  s.span = o.input_max - o.input_min;
  s.x = PowerOfTwoAtLeast(s.range);
  s.u_limit = std::max(std::fabs(c.pid.output_min), std::fabs(c.pid.output_max));
  s.u = PowerOfTwoAtLeast(s.u_limit);
  const double tf = EffectiveDerivativeFilter(c.gains, c.pid);
  (void)tf;
  s.p_max = std::fabs(c.gains.kp) * (c.setpoint_weight_b + 1.0) * s.range;
  s.d_max = std::fabs(c.gains.kd) * (1.0 + c.setpoint_weight_c) * s.span / c.pid.dt_s;
  s.worst = s.p_max + s.d_max + s.u_limit;
  s.worst_max = 2.0 * s.worst;
  s.guard = std::min(30, 32 - static_cast<int>(std::ceil(std::log2(8.0 * s.worst_max / s.u))));
  if (s.guard < 1)
    throw std::invalid_argument("fixed point cannot hold this controller: its worst case |p| + |D| + |u| = " +
                                Num(s.worst) + " is more than 2^28 times the output limit " + Num(s.u_limit) +
                                " (smaller gains, a larger dt, or a narrower --input-range)");
  s.integral_max = std::round(s.worst_max * std::ldexp(1.0, 31 + s.guard) / s.u);
  s.input_lo = std::max(-2147483648.0, std::ceil(o.input_min * 2147483648.0 / s.x));
  s.input_hi = std::min(2147483647.0, std::floor(o.input_max * 2147483648.0 / s.x));
  return s;
}

std::string RangeAnalysis(const Options& o, const Controller& c, const Scaling& s) {
  const double lsb = s.u / std::ldexp(1.0, s.nio);
  std::string t;
  t += " * Fixed point (" + ToString(o.scalar) + "), the range analysis:\n";
  t += " *   declared input range [" + Num(o.input_min) + ", " + Num(o.input_max) +
       "]: r and y are clipped to it; input full scale X = " + Num(s.x) + "\n";
  t += " *   output limits [" + Num(c.pid.output_min) + ", " + Num(c.pid.output_max) +
       "]: output full scale U = " + Num(s.u) + ", one LSB of u = " + Num(lsb) + "\n";
  t += " *   |e| = |r - y| <= " + Num(s.span) +
       ", |b r - y| <= " + Num((c.setpoint_weight_b + 1.0) * s.range) +
       ", |s_k - s_{k-1}| <= " + Num((1.0 + c.setpoint_weight_c) * s.span) + " (< 2^33 input units)\n";
  t += " *   |p| <= kp (b + 1) max|x| = " + Num(s.p_max) + "\n";
  t += " *   |D| <= kd (1 + c) span / dt = " + Num(s.d_max) + " (the filter's gain at the Nyquist rate)\n";
  t += " *   |I| <= |u| + |p| + |D| while it matters; held in +-" + Num(s.worst_max) +
       " (saturating: with anti-windup none and a saturated output the integrator stops there)\n";
  t += " *   |p + I + D| <= " + Num(3.0 * s.worst_max) + "; the int64 accumulator holds +-" +
       Num(std::ldexp(s.u, 32 - s.guard)) + " (guard bits G = " + std::to_string(s.guard) + ")\n";
  t += " *   every product a m 2^-s: |a| < 2^63, m < 2^64 (the coefficient's double exactly), a 128-bit\n"
       " *   product from four 32x32 -> 64-bit ones, rounded to nearest and saturated to int64\n";
  t += " *   run-time changes are refused when kp (b+1) max|x| + kd (1+c) span / dt + max|limit| exceeds " +
       Num(s.worst_max) + " (twice this controller's " + Num(s.worst) + ")\n";
  t += " * So no intermediate can overflow inside the declared range; outside it the inputs are\n"
       " * clipped and every sum saturates: the output saturates, it never wraps.\n";
  return t;
}

std::string FixedConfig(const Controller& c) {
  const double tf = EffectiveDerivativeFilter(c.gains, c.pid);
  const auto line = [](const std::string& v, const char* what) {
    return "    " + v + ", /* " + what + " */\n";
  };
  const char* aw = c.pid.anti_windup == AntiWindup::kNone       ? "PIDLAB_ANTI_WINDUP_NONE"
                   : c.pid.anti_windup == AntiWindup::kClamping ? "PIDLAB_ANTI_WINDUP_CLAMPING"
                                                                : "PIDLAB_ANTI_WINDUP_BACK_CALCULATION";
  const char* rule = c.pid.integral == IntegralMethod::kBackwardEuler  ? "PIDLAB_INTEGRAL_BACKWARD_EULER"
                     : c.pid.integral == IntegralMethod::kForwardEuler ? "PIDLAB_INTEGRAL_FORWARD_EULER"
                                                                       : "PIDLAB_INTEGRAL_TRAPEZOIDAL";
  std::string s;
  s += line(Num(c.gains.kp), "kp") + line(Num(c.gains.ki), "ki, 1/s") + line(Num(c.gains.kd), "kd, s");
  s += line(Num(tf), "tf, s") + line(Num(c.setpoint_weight_b), "b") + line(Num(c.setpoint_weight_c), "c");
  s += line(Num(c.pid.setpoint_filter_s), "setpoint_filter_s, s");
  s += line(Num(c.pid.dt_s), "dt_s, s") + line(Num(c.pid.output_min), "output_min");
  s += line(Num(c.pid.output_max), "output_max") + line(aw, "anti_windup");
  s += line(Num(c.pid.back_calculation_gain), "back_calculation_gain, 1/s");
  s += "    " + std::string(rule) + " /* integral */\n";
  return s;
}

}  // namespace

FixedScale Scales(const Options& options, const Controller& controller) {
  const Scaling s = Scale(options, controller);
  return FixedScale{s.nio, s.x, s.u};
}

GeneratedCode GenerateFixed(const Options& options, const Controller& controller,
                            const std::string& comment) {
  const Scaling s = Scale(options, controller);
  GeneratedCode code{kFixedHeader, kFixedSource, "", ""};
  Replace(&code.header, "COMMENT", comment + " *\n" + RangeAnalysis(options, controller, s));
  for (std::string* text : {&code.header, &code.source}) {
    Replace(text, "QNAME", s.nio == 31 ? "Q31" : "Q15");
    Replace(text, "QTYPE", s.nio == 31 ? "int32_t" : "int16_t");
    Replace(text, "NIO", std::to_string(s.nio));
    Replace(text, "TWO_NIO", Num(std::ldexp(1.0, s.nio)));
    Replace(text, "X", Num(s.x));
    Replace(text, "U", Num(s.u));
  }
  Replace(&code.source, "CONFIG", FixedConfig(controller));
  Replace(&code.source, "INPUT_LO", Int(s.input_lo));
  Replace(&code.source, "INPUT_HI", Int(s.input_hi));
  Replace(&code.source, "GUARD", std::to_string(s.guard));
  Replace(&code.source, "ACC_PER_INPUT", Num(s.x / s.u * std::ldexp(1.0, s.guard)));
  Replace(&code.source, "ACC_ONE", Num(std::ldexp(1.0, 31 + s.guard) / s.u));
  Replace(&code.source, "IO_SHIFT", std::to_string(s.guard + 31 - s.nio));
  Replace(&code.source, "INPUT_MUL", Int(std::ldexp(1.0, 31 - s.nio)));
  Replace(&code.source, "INTEGRAL_MAX", Int(s.integral_max));
  Replace(&code.source, "WORST_MAX", Num(s.worst_max));
  Replace(&code.source, "INPUT_RANGE", Num(s.range));
  Replace(&code.source, "INPUT_SPAN", Num(s.span));
  return code;
}

}  // namespace pidlab::controller_export::internal
