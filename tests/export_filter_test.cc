// The exported C's setpoint filter (docs/export.md): the double module runs
// DiscretePid's filter bit for bit and q31 within 8 LSB, over random
// setpoints and measurements with saturation, direct and reverse acting,
// and a filter switched on at run time starts without a bump.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "export/compiled_module.h"
#include "pidlab/controller/pid.h"
#include "pidlab/controller_export/export.h"

namespace pidlab::controller_export {
namespace {

Controller Filtered(double sign) {
  Controller c;
  c.gains = {sign * 2.5, sign * 4.0, sign * 0.02, 0.01};
  c.pid.dt_s = 1e-3;
  c.pid.output_min = -2.0;
  c.pid.output_max = 2.0;
  c.pid.anti_windup = AntiWindup::kClamping;
  c.pid.setpoint_filter_s = 0.35;
  c.setpoint_weight_b = 0.7;
  c.setpoint_weight_c = 0.0;
  c.pid.setpoint_weight_b = c.setpoint_weight_b;  // DiscretePid's copy, for the reference
  c.pid.setpoint_weight_c = c.setpoint_weight_c;
  return c;
}

GeneratedCode Code(Scalar scalar, const Controller& c) {
  Options o;
  o.scalar = scalar;
  o.input_min = -4.0;
  o.input_max = 4.0;
  o.plant = "test";
  o.spec_json = "{}";
  o.pidlab_version = "test";
  return Generate(o, c);
}

ShimConfig ToShim(const Controller& c) {
  ShimConfig s;
  s.kp = c.gains.kp;
  s.ki = c.gains.ki;
  s.kd = c.gains.kd;
  s.tf = c.gains.tf;
  s.b = c.setpoint_weight_b;
  s.c = c.setpoint_weight_c;
  s.dt_s = c.pid.dt_s;
  s.has_output_min = s.has_output_max = 1;
  s.output_min = c.pid.output_min;
  s.output_max = c.pid.output_max;
  s.anti_windup = static_cast<int>(c.pid.anti_windup);
  s.back_calculation_gain = c.pid.back_calculation_gain;
  s.integral = static_cast<int>(c.pid.integral);
  s.setpoint_filter_s = c.pid.setpoint_filter_s;
  return s;
}

// The largest |u_C - u_DiscretePid| over `steps` random steps (in output
// LSB for fixed point; bits must match for double), and how many saturated.
struct FilterRun {
  double worst = 0.0;
  long mismatches = 0, saturated = 0;
};

FilterRun Compare(Scalar scalar, const Controller& c, int steps) {
  const bool fixed = scalar == Scalar::kQ31;
  CompiledModule m(Code(scalar, c),
                   std::string(PIDLAB_EXPORT_TEST_DIR) + (fixed ? "/shim_fixed.c" : "/shim_real.c"));
  const ShimConfig config = ToShim(c);
  void* dut = m.new_(&config);
  EXPECT_NE(dut, nullptr);
  FilterRun out;
  if (!dut) return out;
  DiscretePid<double> ref(c.gains, c.pid);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double r = 0.0, y = 0.0;
  for (int k = 0; k < steps; ++k) {
    if (unit(rng) < 0.002) r = -3.0 + 6.0 * unit(rng);
    y = 0.995 * y + 0.005 * r + 0.01 * (unit(rng) - 0.5);
    if (fixed) r = m.quantize_input_(r), y = m.quantize_input_(y);
    double u_ref = 0.0, u_dut = 0.0;
    out.saturated += ref.Step(r, y, &u_ref) == PidStatus::kSaturated;
    m.step_(dut, r, y, &u_dut);
    const double diff = std::fabs(u_dut - u_ref) / (fixed ? m.output_lsb_() : 1.0);
    out.worst = std::max(out.worst, diff);
    if (!fixed && std::memcmp(&u_ref, &u_dut, sizeof u_ref) != 0 && ++out.mismatches <= 3)
      ADD_FAILURE() << "step " << k << ": " << u_dut << " (C) vs " << u_ref;
  }
  m.free_(dut);
  return out;
}

TEST(ExportedSetpointFilter, DoubleEqualsDiscretePidBitForBitDirectAndReverse) {
  for (const double sign : {1.0, -1.0}) {
    const FilterRun run = Compare(Scalar::kDouble, Filtered(sign), 100000);
    EXPECT_EQ(run.mismatches, 0) << sign;
    EXPECT_GT(run.saturated, 100) << sign;
  }
}

// The filter's f is rounded to the inputs' unit where it enters the terms:
// that rounding, integrated, costs a few LSB (5.2 measured).
TEST(ExportedSetpointFilter, Q31IsWithin8LsbOfDiscretePidDirectAndReverse) {
  for (const double sign : {1.0, -1.0}) {
    const FilterRun run = Compare(Scalar::kQ31, Filtered(sign), 100000);
    std::printf("q31, sign %g: worst %.3g LSB, %ld saturated\n", sign, run.worst, run.saturated);
    EXPECT_LE(run.worst, 8.0) << sign;
  }
}

TEST(ExportedSetpointFilter, TheTunedConfigurationCarriesTheFilter) {
  const GeneratedCode code = Code(Scalar::kDouble, Filtered(1.0));
  EXPECT_NE(code.source.find("0.34999999999999998, /* setpoint_filter_s, s */"), std::string::npos)
      << code.source;
  EXPECT_NE(code.header.find("pidlab_pid_set_setpoint_filter"), std::string::npos);
  Controller bad = Filtered(1.0);
  bad.pid.setpoint_filter_s = -1.0;
  EXPECT_THROW(Code(Scalar::kDouble, bad), std::invalid_argument);
}

}  // namespace
}  // namespace pidlab::controller_export
