// The one description of a loop (pidlab/spec/loop_spec.h), walked field by
// field: every field of the evaluate and tune specs is a flag of the command
// line, survives the JSON form, and, where it travels to the trio, changes
// the episode configuration and survives the wire. A field added to a spec
// with its example is checked here without touching this file.

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "cli_common.h"
#include "cli_spec.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/transport/episode_spec.h"
#include "spec_build.h"  // internal to pidlab::tune: the steps tested one by one
#include "test_status.h"

using pidlab::episode_client::MakeEpisodeSpec;
using pidlab::evaluation::LoopOptions;
using pidlab::spec::NameStyle;
using pidlab::tune::BuildGains;
using pidlab::tune::BuildLoopOptions;
using pidlab::tune::BuildPlant;
using pidlab::tune::ResolveRobustPreset;
using pidlab::tune::TuneOptions;

namespace pidlab {
namespace {

using nlohmann::json;

template <typename Spec>
std::vector<spec::FieldEntry> FieldsOf() {
  return spec::Fields<Spec>();
}

// JSON values equal as a spec means them (numbers as doubles).
bool SameValue(const json& a, const json& b) {
  if (a.is_number() && b.is_number()) return a.get<double>() == b.get<double>();
  if (a.is_array() && b.is_array()) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!SameValue(a[i], b[i])) return false;
    return true;
  }
  if (a.is_object() && b.is_object()) {
    if (a.size() != b.size()) return false;
    for (const auto& item : a.items())
      if (!b.contains(item.key()) || !SameValue(item.value(), b[item.key()])) return false;
    return true;
  }
  return a == b;
}

template <typename Spec>
void ExpectEveryFieldHasAValidExampleThatRoundTripsThroughJson() {
  std::set<std::string> keys;
  for (const spec::FieldEntry& e : FieldsOf<Spec>()) {
    SCOPED_TRACE(e.field.key);
    EXPECT_TRUE(keys.insert(e.field.key).second) << "two fields share the key";
    EXPECT_GT(std::string(e.field.help).size(), 10u);
    const json example = json::parse(e.field.example, nullptr, false);
    ASSERT_FALSE(example.is_discarded()) << "the example is not JSON: " << e.field.example;
    EXPECT_FALSE(SameValue(example, e.default_value)) << "the example is the default";
    Spec s;
    std::set<std::string> given;
    std::string error;
    ASSERT_TRUE(IsOk(spec::FromJson(json{{e.field.key, example}}, &s, &given)));
    EXPECT_EQ(given, std::set<std::string>{e.field.key});
    const json back = spec::ToJson(s);
    EXPECT_TRUE(SameValue(back.at(e.field.key), example)) << back.at(e.field.key);
    // Written and read again: the same spec, bit for bit.
    Spec again;
    ASSERT_TRUE(IsOk(spec::FromJson(json::parse(back.dump()), &again, nullptr)));
    EXPECT_EQ(spec::ToJson(again).dump(), back.dump());
  }
}

TEST(Spec, EveryEvaluateFieldHasAnExampleThatRoundTripsThroughJson) {
  ExpectEveryFieldHasAValidExampleThatRoundTripsThroughJson<spec::EvaluateSpec>();
}

TEST(Spec, EveryTuneFieldHasAnExampleThatRoundTripsThroughJson) {
  ExpectEveryFieldHasAValidExampleThatRoundTripsThroughJson<spec::TuningSpec>();
}

TEST(Spec, JsonNamesAnUnknownKeyAWrongTypeAndAnotherVersion) {
  spec::EvaluateSpec s;
  std::string error;
  EXPECT_FALSE(OkInto(spec::FromJson(json{{"horizn", 3}}, &s, nullptr), &error));
  EXPECT_NE(error.find("'horizn' is unknown"), std::string::npos) << error;
  EXPECT_FALSE(OkInto(spec::FromJson(json{{"horizon", "long"}}, &s, nullptr), &error));
  EXPECT_NE(error.find("'horizon' must be a number"), std::string::npos) << error;
  EXPECT_FALSE(OkInto(spec::FromJson(json{{"seed", -1}}, &s, nullptr), &error));
  EXPECT_NE(error.find("'seed'"), std::string::npos) << error;
  EXPECT_FALSE(OkInto(spec::FromJson(json{{"version", 99}}, &s, nullptr), &error));
  EXPECT_NE(error.find("99"), std::string::npos) << error;
  EXPECT_FALSE(OkInto(spec::FromJson(json::array(), &s, nullptr), &error));
}

TEST(Spec, InfinityIsWrittenAsTextAndReadBack) {
  spec::EvaluateSpec s;
  s.loop.output_limits = {-spec::kInf, 3.0};
  const json j = spec::ToJson(s);
  EXPECT_EQ(j["output_limits"], json::array({"-inf", 3.0}));
  EXPECT_EQ(j["voltage_limit"], "inf");
  spec::EvaluateSpec back;
  std::string error;
  ASSERT_TRUE(IsOk(spec::FromJson(j, &back, nullptr)));
  EXPECT_TRUE(std::isinf(back.loop.output_limits.first) && back.loop.output_limits.first < 0);
  // Not where the field takes no infinity.
  EXPECT_FALSE(OkInto(spec::FromJson(json{{"horizon", "inf"}}, &back, nullptr), &error));
}

// The command-line words of one field's value, as a user types them.
struct TextOf {
  std::vector<std::string>* args;
  const char* key;
  std::string flag;
  void Visit(const spec::Field& f, bool* v) {
    if (std::string(f.key) == key && *v) args->push_back(flag);
  }
  void Visit(const spec::Field& f, std::map<std::string, double>* v) {
    if (std::string(f.key) != key) return;
    for (const auto& [name, x] : *v) {
      args->push_back(flag);
      args->push_back(name + "=" + cli::FlagText(x));
    }
  }
  template <typename T>
  void Visit(const spec::Field& f, T* v) {
    if (std::string(f.key) != key) return;
    args->push_back(flag);
    args->push_back(cli::FlagText(*v));
  }
};

// The command line: a flag per field, and the flag's text of the example
// reaches the spec.
template <typename Spec>
void ExpectEveryFieldIsAFlag() {
  for (const spec::FieldEntry& e : FieldsOf<Spec>()) {
    SCOPED_TRACE(e.field.key);
    Spec example_spec;
    std::string error;
    ASSERT_TRUE(
        IsOk(spec::FromJson(json{{e.field.key, json::parse(e.field.example)}}, &example_spec, nullptr)));
    // The example as the user types it: the flag's own text of the value.
    std::vector<std::string> args = {"pidlab"};
    const std::string flag = spec::FlagName(e.field.key);
    TextOf text{&args, e.field.key, flag};
    example_spec.Serialize(&text);
    CLI::App app;
    cli::SpecFlags flags;
    flags.Register(&app, Spec{});
    ASSERT_NE(app.get_option_no_throw(flag), nullptr) << "no flag " << flag;
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    app.parse(static_cast<int>(argv.size()), argv.data());
    Spec parsed;
    std::set<std::string> given;
    flags.Apply(&parsed, &given);
    EXPECT_EQ(given, std::set<std::string>{e.field.key});
    EXPECT_EQ(spec::ToJson(parsed).dump(), spec::ToJson(example_spec).dump());
  }
}

TEST(Spec, EveryEvaluateFieldIsAFlagWhoseTextReachesTheSpec) {
  ExpectEveryFieldIsAFlag<spec::EvaluateSpec>();
}

TEST(Spec, EveryTuneFieldIsAFlagWhoseTextReachesTheSpec) { ExpectEveryFieldIsAFlag<spec::TuningSpec>(); }

// ---- The episode: every field marked kEpisode changes the configuration
// the trio receives, and the configuration survives the wire.

std::vector<uint8_t> Encode(const lcmt_episode_config& m) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// The configuration of an evaluation spec's episode; false where the spec
// does not build.
bool ConfigOf(const spec::EvaluateSpec& s, lcmt_episode_config* out) {
  Plant plant;
  PidGains gains;
  LoopOptions options;
  std::string error;
  if (!BuildPlant(s.plant, NameStyle::kKey, &plant, &error) ||
      !BuildGains(s.gains, NameStyle::kKey, &gains, &error) ||
      !BuildLoopOptions(s.loop, NameStyle::kKey, &options, &error))
    return false;
  *out = transport::MakeEpisodeConfig(
      MakeEpisodeSpec(42, plant, gains, options, options.disturbance, transport::RecoveryOptions{}));
  return true;
}

std::vector<spec::EvaluateSpec> Bases() {
  spec::EvaluateSpec linear;
  linear.plant.plant = "oscillator";
  linear.gains = {1.0, 0.5, 0.2};
  linear.loop.loop = "sampled";
  linear.loop.horizon_s = 2.0;
  spec::EvaluateSpec motor = linear;
  motor.plant.plant = "stepper_nonlinear";
  motor.loop.dt_s = 1e-4;
  motor.loop.sample_time_s = 0.01;
  motor.loop.horizon_s = 0.05;
  spec::EvaluateSpec custom = linear;
  custom.plant.plant = "custom";
  custom.plant.num = {1.0};
  custom.plant.den = {1.0, 2.0, 1.0};
  return {linear, motor, custom};
}

TEST(Spec, EveryEpisodeFieldChangesTheEpisodeConfigurationAndSurvivesTheWire) {
  int checked = 0;
  for (const spec::FieldEntry& e : FieldsOf<spec::EvaluateSpec>()) {
    if (!e.field.Has(spec::kEpisode)) continue;
    SCOPED_TRACE(e.field.key);
    bool reached = false;
    for (const spec::EvaluateSpec& base : Bases()) {
      lcmt_episode_config before, after;
      ASSERT_TRUE(ConfigOf(base, &before));
      spec::EvaluateSpec changed = base;
      std::string error;
      ASSERT_TRUE(OkInto(spec::FromJson(json{{e.field.key, json::parse(e.field.example)}}, &changed, nullptr),
                         &error));
      if (!ConfigOf(changed, &after) || Encode(after) == Encode(before)) continue;
      transport::EpisodeSpec decoded;
      ASSERT_TRUE(IsOk(transport::ParseEpisodeConfig(after, &decoded)));
      EXPECT_EQ(Encode(transport::MakeEpisodeConfig(decoded)), Encode(after));
      reached = true;
      break;
    }
    EXPECT_TRUE(reached) << "no base spec with the example " << e.field.example << " changes the episode";
    ++checked;
  }
  EXPECT_GE(checked, 25);
}

TEST(Spec, FieldsNotMarkedForTheEpisodeLeaveItAlone) {
  const spec::EvaluateSpec base = Bases().front();
  lcmt_episode_config before, after;
  ASSERT_TRUE(ConfigOf(base, &before));
  for (const char* key : {"stability_margin", "max_ms", "monte_carlo"}) {
    SCOPED_TRACE(key);
    spec::EvaluateSpec changed = base;
    std::string error;
    for (const spec::FieldEntry& e : FieldsOf<spec::EvaluateSpec>())
      if (std::string(e.field.key) == key) {
        EXPECT_FALSE(e.field.Has(spec::kEpisode));
        ASSERT_TRUE(IsOk(spec::FromJson(json{{key, json::parse(e.field.example)}}, &changed, nullptr)));
      }
    ASSERT_TRUE(ConfigOf(changed, &after));
    EXPECT_EQ(Encode(after), Encode(before));
  }
}

// ---- What a spec means, validated once for every front end.

TEST(SpecBuild, NamesTheFieldAsTheFrontEndDoes) {
  spec::LoopSpec s;
  s.loop = "discrete";
  LoopOptions o;
  std::string error;
  EXPECT_FALSE(BuildLoopOptions(s, NameStyle::kFlag, &o, &error));
  EXPECT_EQ(error, "--loop 'discrete' must be continuous or sampled");
  EXPECT_FALSE(BuildLoopOptions(s, NameStyle::kKey, &o, &error));
  EXPECT_EQ(error, "loop 'discrete' must be continuous or sampled");
}

TEST(SpecBuild, RefusesANumberOutOfRangeFromAnyFrontEnd) {
  spec::LoopSpec s;
  s.horizon_s = 1e300;
  LoopOptions o;
  std::string error;
  EXPECT_FALSE(BuildLoopOptions(s, NameStyle::kKey, &o, &error));
  EXPECT_NE(error.find("horizon 1e+300 is out of range"), std::string::npos) << error;
}

TEST(SpecBuild, ThePidRunsAtTheLoopsPeriod) {
  spec::LoopSpec s;
  s.loop = "sampled";
  s.dt_s = 2.5e-4;
  LoopOptions o;
  std::string error;
  ASSERT_TRUE(BuildLoopOptions(s, NameStyle::kKey, &o, &error)) << error;
  EXPECT_EQ(o.pid.dt_s, 2.5e-4);
}

TEST(SpecBuild, ARatiosFilterOnTheSampledLoopIsAtLeastOnePeriod) {
  spec::LoopSpec s;
  s.derivative_filter_ratio = 10.0;
  LoopOptions o;
  std::string error;
  ASSERT_TRUE(BuildLoopOptions(s, NameStyle::kKey, &o, &error)) << error;
  EXPECT_EQ(o.derivative_filter_min_s, 0.0) << "the continuous loop has no period";
  s.loop = "sampled";
  s.dt_s = 1.0;
  s.sample_time_s = 1.0;
  ASSERT_TRUE(BuildLoopOptions(s, NameStyle::kKey, &o, &error)) << error;
  EXPECT_EQ(o.derivative_filter_min_s, 1.0);
  EXPECT_EQ(pidlab::evaluation::LoopGains(PidGains{4.0, 0.1, 12.0}, o).tf, 1.0) << "Td / N = 0.3 s < dt";
}

TEST(SpecBuild, TheRobustPresetFillsWhatTheUserDidNotGiveAndKeepsWhatTheyDid) {
  spec::TuningSpec s;
  s.tune.robust = true;
  s.bounds.max_ms = 1.3;
  ResolveRobustPreset(&s, {"robust", "max_ms"});
  EXPECT_EQ(s.tune.objective, "setpoint-load");
  EXPECT_EQ(s.tune.load_weight, 1.0);
  EXPECT_EQ(s.loop.derivative_filter_ratio, 10.0);
  EXPECT_EQ(s.bounds.max_ms, 1.3);
  EXPECT_EQ(s.bounds.max_time_constant_s, 2.5);
  // Resolved, then given in full (a result's spec run again): unchanged.
  spec::TuningSpec again = s;
  std::set<std::string> all;
  for (const spec::FieldEntry& e : FieldsOf<spec::TuningSpec>()) all.insert(e.field.key);
  ResolveRobustPreset(&again, all);
  EXPECT_EQ(spec::ToJson(again).dump(), spec::ToJson(s).dump());
}

TEST(SpecBuild, TheTunersLoopStartsFromTheAcceptanceMargin) {
  EXPECT_EQ(spec::TuningSpec{}.loop.stability_margin, TuneOptions::DefaultTuneLoop().stability_margin);
  EXPECT_EQ(spec::EvaluateSpec{}.loop.stability_margin, LoopOptions{}.stability_margin);
}

}  // namespace
}  // namespace pidlab
