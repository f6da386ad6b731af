// results::BuildAutotune: the autotune spec (spec/autotune_spec.h) made the
// experiment's and the design's options, the one function every front end
// (pidlab autotune, pidlab.autotune) calls.

#include <gtest/gtest.h>

#include <limits>
#include <set>
#include <string>

#include "pidlab/controller_export/export.h"
#include "pidlab/results/autotune_json.h"
#include "pidlab/spec/json.h"

namespace pidlab {
namespace {

using results::AutotuneRun;
using results::BuildAutotune;
using spec::AutotuneSpec;
using spec::NameStyle;

PidOptions PidWithin(double lo, double hi) {
  PidOptions pid;
  pid.dt_s = 0.01;
  pid.output_min = lo;
  pid.output_max = hi;
  return pid;
}

const PidGains kPrevious{0.5, 0.5, 0.0};

TEST(BuildAutotune, ADefaultSpecSizesTheRelayFromTheOutputRangeWithTheRelayOptionsDefaults) {
  AutotuneRun dut;
  ASSERT_TRUE(
      BuildAutotune(AutotuneSpec{}, {}, kPrevious, PidWithin(0.0, 2.0), 2.0, NameStyle::kFlag, &dut).ok());
  const RelayTuneOptions defaults;
  const RelayTuneOptions& r = dut.experiment.relay;
  EXPECT_DOUBLE_EQ(r.amplitude, 0.4);  // 20 % of the output range
  EXPECT_DOUBLE_EQ(r.bias, 0.4 / 3.0);
  EXPECT_EQ(r.hysteresis, 0.0);
  EXPECT_EQ(r.noise_multiple, 3.0);  // 3 sigma of the hold's noise
  EXPECT_EQ(r.hold_s, defaults.hold_s);
  EXPECT_EQ(r.u0, defaults.u0);
  EXPECT_EQ(r.y_limit, defaults.y_limit);
  EXPECT_EQ(r.settled_cycles, defaults.settled_cycles);
  EXPECT_EQ(r.tolerance, defaults.tolerance);
  EXPECT_EQ(r.timeout_periods, defaults.timeout_periods);
  EXPECT_EQ(r.max_restarts, defaults.max_restarts);
  EXPECT_EQ(r.q_bits, 0);
  EXPECT_EQ(dut.experiment.first_window_s, autotune::ExperimentOptions{}.first_window_s);
  EXPECT_EQ(dut.experiment.max_window_s, autotune::ExperimentOptions{}.max_window_s);
  EXPECT_EQ(dut.experiment.previous.kp, 0.5);
  const results::AutotuneDesignOptions design_defaults;
  EXPECT_EQ(dut.design.method, design_defaults.method);
  EXPECT_EQ(dut.design.robustness, design_defaults.robustness);
  EXPECT_EQ(dut.design.response_time_s, design_defaults.response_time_s);
  EXPECT_EQ(dut.design.max_overshoot_pct, design_defaults.max_overshoot_pct);
  EXPECT_EQ(dut.design.max_ms, 2.0);
}

TEST(BuildAutotune, AnUnlimitedOutputGetsAUnitRelayAndGivenValuesAreKept) {
  AutotuneSpec s;
  AutotuneRun dut;
  ASSERT_TRUE(BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut).ok());
  EXPECT_EQ(dut.experiment.relay.amplitude, 1.0);
  s.relay_amplitude = 0.3;
  s.relay_bias = "0";
  s.hysteresis = 0.02;
  s.method = "simc";
  s.relay_time_s = 30.0;
  ASSERT_TRUE(BuildAutotune(s, {"hysteresis"}, kPrevious, PidOptions{}, 1.6, NameStyle::kFlag, &dut).ok());
  EXPECT_EQ(dut.experiment.relay.amplitude, 0.3);
  EXPECT_EQ(dut.experiment.relay.bias, 0.0);
  EXPECT_EQ(dut.experiment.relay.hysteresis, 0.02);
  EXPECT_EQ(dut.experiment.relay.noise_multiple, 0.0);
  EXPECT_EQ(dut.experiment.first_window_s, 30.0);
  EXPECT_EQ(dut.design.method, "simc");
  EXPECT_EQ(dut.design.max_ms, 1.6);
}

TEST(BuildAutotune, NamesABadValueAsTheFlagOrTheKeywordDoes) {
  AutotuneSpec s;
  s.relay_bias = "abc";
  AutotuneRun dut;
  const Status as_flag = BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut);
  const Status as_key = BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kKey, &dut);
  EXPECT_EQ(as_flag.code(), StatusCode::kInvalidInput);
  EXPECT_NE(as_flag.message().find("--relay-bias 'abc'"), std::string::npos) << as_flag.message();
  EXPECT_EQ(as_key.message().find("--"), std::string::npos) << as_key.message();
  EXPECT_NE(as_key.message().find("relay_bias 'abc'"), std::string::npos) << as_key.message();
  s.relay_bias.clear();
  s.relay_amplitude = -1.0;
  EXPECT_NE(BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut)
                .message()
                .find("--relay-amplitude -1 must be > 0"),
            std::string::npos);
  s.relay_amplitude = 0.0;
  s.method = "pso";
  EXPECT_NE(
      BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut).message().find("'pso'"),
      std::string::npos);
}

TEST(BuildAutotune, RefusesANegativeHysteresisGivenAndTakesThreeSigmaWhenNotGiven) {
  AutotuneSpec s;
  s.hysteresis = -1.0;
  AutotuneRun dut;
  const Status given = BuildAutotune(s, {"hysteresis"}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut);
  EXPECT_NE(given.message().find("--hysteresis -1 must be >= 0"), std::string::npos) << given.message();
  ASSERT_TRUE(BuildAutotune(s, {}, kPrevious, PidOptions{}, 2.0, NameStyle::kFlag, &dut).ok());
  EXPECT_EQ(dut.experiment.relay.noise_multiple, 3.0);
}

TEST(BuildAutotune, FixedPointTakesTheGridsPidlabExportScalesTheModuleTo) {
  AutotuneSpec s;
  s.scalar = "q15";
  s.input_range = {-2.0, 2.0};
  AutotuneRun dut;
  const PidOptions pid = PidWithin(0.0, 2.0);
  ASSERT_TRUE(BuildAutotune(s, {}, kPrevious, pid, 2.0, NameStyle::kFlag, &dut).ok());
  controller_export::Options o;
  o.scalar = controller_export::Scalar::kQ15;
  o.input_min = -2.0;
  o.input_max = 2.0;
  controller_export::Controller c;
  c.gains = kPrevious;
  c.pid = pid;
  const controller_export::FixedScale want = controller_export::FixedPointScale(o, c);
  EXPECT_EQ(dut.experiment.relay.q_bits, want.bits);
  EXPECT_EQ(dut.experiment.relay.input_full_scale, want.input_full_scale);
  EXPECT_EQ(dut.experiment.relay.output_full_scale, want.output_full_scale);
}

TEST(CheckAutotuneScalar, RefusesFloatAFixedPointWithoutARangeAndARangeInDouble) {
  AutotuneSpec s;
  s.scalar = "float";
  EXPECT_NE(results::CheckAutotuneScalar(s, NameStyle::kFlag).message().find("--scalar 'float'"),
            std::string::npos);
  s.scalar = "q31";
  EXPECT_NE(results::CheckAutotuneScalar(s, NameStyle::kKey).message().find("needs input_range LO,HI"),
            std::string::npos);
  s.scalar = "double";
  s.input_range = {-1.0, 1.0};
  EXPECT_NE(results::CheckAutotuneScalar(s, NameStyle::kFlag).message().find("--input-range is for --scalar"),
            std::string::npos);
}

TEST(AutotuneSpec, ItsJsonFormReadsBackToTheSameSpec) {
  AutotuneSpec s;
  s.relay_bias = "0.1";
  s.y_limit = std::numeric_limits<double>::infinity();
  s.input_range = {-2.0, 2.0};
  s.settled_cycles = 4;
  AutotuneSpec back;
  std::set<std::string> given;
  ASSERT_TRUE(spec::FromJson(spec::ToJson(s), &back, &given).ok());
  EXPECT_EQ(spec::ToJson(back), spec::ToJson(s));
  EXPECT_EQ(given.size(), spec::Fields<AutotuneSpec>().size());
}

}  // namespace
}  // namespace pidlab
