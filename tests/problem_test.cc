// One run assembly (pidlab/tune/problem.h): the refusals BuildEvaluation and
// BuildTuning make for every front end, and runs that give the same bits as
// the steps chained by hand.

#include "pidlab/tune/problem.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/two_dof.h"
#include "spec_build.h"  // internal to pidlab::tune: the old chain, for comparison
#include "test_status.h"

namespace pidlab::tune {
namespace {

using spec::NameStyle;

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

spec::EvaluateSpec Oscillator() {
  spec::EvaluateSpec s;
  s.plant.plant = "oscillator";
  s.gains = {2.0, 1.0, 1.5};
  return s;
}

BuildOptions Flags(Backend backend = Backend::kInProcess) {
  BuildOptions o;
  o.style = NameStyle::kFlag;
  o.backend = backend;
  return o;
}

// A refusal: kInvalidInput with exactly `message`, and *problem untouched.
template <typename Spec, typename Problem>
void ExpectRefused(Status (*build)(const Spec&, const BuildOptions&, Problem*), const Spec& s,
                   const BuildOptions& options, const std::string& message) {
  Problem dut;
  dut.spec.plant.plant = "untouched";
  const Status status = build(s, options, &dut);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput) << status.message();
  EXPECT_EQ(status.message(), message);
  EXPECT_EQ(dut.spec.plant.plant, "untouched");
}

TEST(BuildEvaluation, AsksTheCommandLineForGainsAndNamesTheKeyElsewhere) {
  spec::EvaluateSpec s = Oscillator();
  s.gains.clear();
  ExpectRefused(&BuildEvaluation, s, Flags(), "--gains is required (or --spec FILE)");
  ExpectRefused(&BuildEvaluation, s, BuildOptions{}, "gains  must be three numbers KP,KI,KD");
}

TEST(BuildEvaluation, RefusesMonteCarloOnARunnerWithADelayAndOnANonlinearPlant) {
  spec::EvaluateSpec s = Oscillator();
  s.monte_carlo = 10;
  ExpectRefused(&BuildEvaluation, s, Flags(Backend::kRunner),
                "--monte-carlo runs in process: use --backend local");
  spec::EvaluateSpec delayed = s;
  delayed.plant.delay_s = 0.1;
  delayed.loop.loop = "sampled";
  ExpectRefused(&BuildEvaluation, delayed, Flags(),
                "--monte-carlo with --delay is not supported yet (its draws are undelayed plants)");
  ExpectRefused(&BuildEvaluation, delayed, BuildOptions{},
                "monte_carlo with delay is not supported yet (its draws are undelayed plants)");
  spec::EvaluateSpec motor = s;
  motor.plant.plant = "stepper_nonlinear";
  motor.loop.loop = "sampled";
  motor.loop.dt_s = 1e-4;
  ExpectRefused(&BuildEvaluation, motor, BuildOptions{},
                "monte_carlo draws linear plants: it does not take plant 'stepper_nonlinear'");
}

TEST(BuildEvaluation, RunsTheSampledLoopOnARunnerAndRefusesAnotherLoopGiven) {
  spec::EvaluateSpec s = Oscillator();
  EvaluationProblem dut;
  ASSERT_TRUE(BuildEvaluation(s, Flags(Backend::kRunner), &dut).ok());
  EXPECT_EQ(dut.spec.loop.loop, "sampled") << "the echo says the loop that ran";
  EXPECT_EQ(dut.loop.loop, evaluation::LoopKind::kSampled);
  BuildOptions given = Flags(Backend::kRunner);
  given.given = {"loop"};
  ExpectRefused(&BuildEvaluation, s, given, "--backend lcm runs the sampled loop, not --loop 'continuous'");
}

TEST(BuildEvaluation, DerivesTheTimeScaleOfASampledLoopWhoseDtEqFourSpacingIsNoMultipleOf) {
  // A thermal plant sampled every second: eq. (4)'s 0.05 s is no multiple of
  // dt = 1 s, and neither horizon nor spacing was given, so both come from
  // the closed loop, the spacing a multiple of dt.
  spec::EvaluateSpec s;
  s.plant.plant = "custom";
  s.plant.num = {1.0};
  s.plant.den = {100.0, 1.0};
  s.plant.delay_s = 10.0;
  s.gains = {2.0, 0.02, 0.0};
  s.loop.loop = "sampled";
  s.loop.dt_s = 1.0;
  EvaluationProblem dut;
  const Status status = BuildEvaluation(s, Flags(), &dut);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(dut.time_scale.source, "plant");
  EXPECT_GE(dut.spec.loop.sample_time_s, 1.0);
  EXPECT_EQ(dut.spec.loop.sample_time_s, std::round(dut.spec.loop.sample_time_s));
  EXPECT_GT(dut.spec.loop.horizon_s, 100.0) << "ten closed-loop time constants of a 100 s plant";
}

TEST(BuildController, BuildsTheSampledControllerAtADtEqFourSpacingIsNoMultipleOf) {
  spec::EvaluateSpec s = Oscillator();
  s.loop.loop = "sampled";
  s.loop.dt_s = 1.0;
  PidGains gains;
  evaluation::LoopOptions loop;
  const Status status = BuildController(s, NameStyle::kKey, &gains, &loop);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(loop.dt_s, 1.0);
  EXPECT_EQ(gains.kp, 2.0);
}

TEST(BuildEvaluation, RefusesADeadTimeLongerThanTheSampledLoopsDelayLine) {
  spec::EvaluateSpec s = Oscillator();
  s.loop.loop = "sampled";
  s.plant.delay_s = 10.0;  // 1e4 steps of the default dt
  EvaluationProblem dut;
  const Status status = BuildEvaluation(s, Flags(), &dut);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(status.message().rfind("--delay", 0), 0u) << status.message();
}

TEST(BuildTuning, RefusesANonlinearPlantOrARunnerOffTheSampledLoop) {
  spec::TuningSpec s;
  s.plant.plant = "stepper_nonlinear";
  ExpectRefused(
      &BuildTuning, s, Flags(),
      "--plant stepper_nonlinear is nonlinear: tune it on the sampled loop (--loop sampled --dt 1e-4)");
  ExpectRefused(&BuildTuning, s, BuildOptions{},
                "plant stepper_nonlinear is nonlinear: tune it on the sampled loop (loop sampled)");
  spec::TuningSpec linear;
  linear.plant.plant = "oscillator";
  ExpectRefused(&BuildTuning, linear, Flags(Backend::kRunner),
                "--backend lcm runs the sampled loop: add --loop sampled");
}

TEST(BuildTuning, WritesThePresetAndTheBoxThatRunIntoTheEcho) {
  spec::TuningSpec s;
  s.plant.plant = "oscillator";
  s.tune.robust = true;
  BuildOptions options;
  options.given = {"plant", "robust"};
  TuningProblem dut;
  ASSERT_TRUE(BuildTuning(s, options, &dut).ok());
  spec::TuningSpec resolved = s;
  resolved.plant.Normalize();
  const SearchBox box = ResolveTuningSpec(&resolved, options.given);
  EXPECT_EQ(spec::ToJson(dut.spec), spec::ToJson(resolved));
  EXPECT_EQ(dut.box.source, box.source);
  EXPECT_EQ(dut.box.upper, box.upper);
  EXPECT_EQ(dut.spec.bounds.max_ms, RobustPreset::kMaxMs);
}

TEST(RunEvaluation, GivesTheBitsOfTheStepsChainedByHand) {
  for (const char* loop : {"continuous", "sampled"}) {
    spec::EvaluateSpec s = Oscillator();
    s.loop.loop = loop;
    s.loop.disturbance = "step";
    s.loop.disturbance_amplitude = 0.5;
    s.monte_carlo = 20;
    EvaluationProblem problem;
    ASSERT_TRUE(BuildEvaluation(s, BuildOptions{}, &problem).ok());
    EvaluationResult dut;
    ASSERT_TRUE(RunEvaluation(problem, EvaluationRunOptions{}, &dut).ok());

    std::string error;
    Plant p;
    PidGains g;
    evaluation::LoopOptions options;
    analysis::MonteCarloOptions mc;
    ASSERT_TRUE(BuildPlant(s.plant, NameStyle::kKey, &p, &error) &&
                BuildGains(s.gains, NameStyle::kKey, &g, &error) &&
                BuildLoopOptions(s.loop, NameStyle::kKey, &options, &error) &&
                CheckPlantInLoop(p, options, NameStyle::kKey, &error) &&
                BuildMonteCarlo(s, NameStyle::kKey, &mc, &error))
        << error;
    evaluation::Evaluation ev;
    analysis::LoopAnalysis a;
    analysis::MonteCarloSummary draws;
    ASSERT_TRUE(OkInto(evaluation::Evaluate(p, g, options, evaluation::EvaluateOptions{}, &ev), &error) &&
                OkInto(analysis::AnalyzeLoop(p, g, options, analysis::LoopAnalysisOptions{}, &a), &error) &&
                OkInto(analysis::RunMonteCarlo(p, nullptr, g, options, mc, &draws), &error))
        << error;
    EXPECT_TRUE(SameBits(dut.evaluation.y, ev.y)) << loop;
    EXPECT_TRUE(SameBits(dut.evaluation.iae, ev.iae)) << loop;
    EXPECT_TRUE(SameBits(dut.analysis.ms, a.ms)) << loop;
    EXPECT_TRUE(dut.monte_carlo_ran);
    EXPECT_EQ(dut.monte_carlo.stable, draws.stable);
    EXPECT_TRUE(SameBits(dut.monte_carlo.iae.median, draws.iae.median)) << loop;
  }
}

TEST(RunTuning, GivesTheBitsOfTheStepsChainedByHand) {
  spec::TuningSpec s;
  s.plant.plant = "oscillator";
  s.tune.method = "nelder-mead";
  s.tune.max_evals = 300;
  s.tune.refine = "none";
  BuildOptions given;  // what a front end passes: the keys the user gave
  given.given = {"method", "max_evals", "refine"};
  TuningProblem problem;
  ASSERT_TRUE(BuildTuning(s, given, &problem).ok());
  TuningResult dut;
  ASSERT_TRUE(RunTuning(problem, TuningRunOptions{}, &dut).ok());

  spec::TuningSpec ts = s;
  ResolveRobustPreset(&ts, given.given);
  ResolveSearchBox(&ts, given.given);
  std::string error;
  Plant p;
  TuneOptions o;
  ASSERT_TRUE(BuildPlant(ts.plant, NameStyle::kKey, &p, &error) &&
              BuildTuneOptions(ts, NameStyle::kKey, &o, &error) &&
              CheckPlantInLoop(p, o.loop, NameStyle::kKey, &error))
      << error;
  TuneSummary summary;
  ASSERT_TRUE(IsOk(Tune(p, o, &summary)));
  ASSERT_TRUE(summary.stable);
  evaluation::Evaluation ev;
  const evaluation::LoopOptions loop = WithSetpointWeights(o.loop, summary.two_dof);
  ASSERT_TRUE(
      OkInto(evaluation::Evaluate(p, summary.gains, loop, evaluation::EvaluateOptions{}, &ev), &error))
      << error;

  ASSERT_TRUE(dut.summary.stable);
  EXPECT_TRUE(SameBits(dut.summary.gains.kp, summary.gains.kp));
  EXPECT_TRUE(SameBits(dut.summary.gains.ki, summary.gains.ki));
  EXPECT_TRUE(SameBits(dut.summary.gains.kd, summary.gains.kd));
  EXPECT_TRUE(SameBits(dut.summary.objective, summary.objective));
  EXPECT_TRUE(SameBits(dut.evaluation.y, ev.y));
}

TEST(BuildTuning, EveryFieldTaggedSearchButTheEnginesBoundsAsksForASearchAndNoneGivenIsTheEngine) {
  const nlohmann::json plant = {{"plant", "custom"}, {"num", {1}}, {"den", {10, 1}}, {"delay", 2}};
  const auto method_of = [](const nlohmann::json& j, std::string* method) {
    spec::TuningSpec s;
    BuildOptions o;
    std::string error;
    if (!OkInto(spec::FromJson(j, &s, &o.given), &error)) return Status::InvalidInput(error);
    TuningProblem problem;
    const Status built = BuildTuning(s, o, &problem);
    *method = ToString(problem.options.method);
    return built;
  };
  std::string method;
  ASSERT_TRUE(method_of(plant, &method).ok());
  EXPECT_EQ(method, "optimal");
  // The bounds the design engine takes itself keep it.
  const std::set<std::string> engine_takes = {"max_ms", "max_mt", "max_noise_gain", "max_overshoot"};
  int tagged = 0;
  for (const spec::FieldEntry& e : spec::Fields<spec::TuningSpec>()) {
    if (!e.field.Has(spec::kSearch)) continue;
    ++tagged;
    nlohmann::json j = plant;
    j[e.field.key] = nlohmann::json::parse(e.field.example);
    const Status built = method_of(j, &method);
    ASSERT_TRUE(built.ok()) << e.field.key << ": " << built.message();
    if (engine_takes.count(e.field.key) > 0)
      EXPECT_EQ(method, "optimal") << e.field.key << " given: the engine takes it";
    else
      EXPECT_EQ(method, "multi-start") << e.field.key << " given: a search";
  }
  EXPECT_EQ(tagged, 21);
}

TEST(RunTuning, GivesTheBestFilteredPidWhereAnIdealDerivativeMakesEveryLoopNeutral) {
  spec::TuningSpec s;
  s.plant.plant = "custom";
  s.plant.num = {1.0};
  s.plant.den = {10.0, 1.0};
  s.plant.delay_s = 2.0;
  s.tune.method = "nelder-mead";
  s.tune.max_evals = 200;
  s.loop.derivative_filter_ratio = 0.0;
  BuildOptions given;
  given.given = {"num", "den", "delay", "method", "max_evals", "derivative_filter_ratio"};
  TuningProblem problem;
  ASSERT_TRUE(BuildTuning(s, given, &problem).ok());
  ASSERT_EQ(problem.options.loop.derivative_filter_ratio, 0.0) << "the ideal derivative asked for";
  TuningResult dut;
  ASSERT_TRUE(RunTuning(problem, TuningRunOptions{}, &dut).ok());
  ASSERT_TRUE(dut.summary.stable);
  EXPECT_EQ(dut.options.loop.derivative_filter_ratio, kMigoFilterRatio);
  EXPECT_EQ(dut.loop.derivative_filter_ratio, kMigoFilterRatio);
  EXPECT_NE(dut.fallback.find("tuned the best filtered PID instead"), std::string::npos) << dut.fallback;
  EXPECT_DOUBLE_EQ(dut.summary.gains.tf, dut.summary.gains.kd / (kMigoFilterRatio * dut.summary.gains.kp));

  // Tune() itself (a library caller) still says why, and which flag helps.
  TuneSummary alone;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(problem.plant, problem.options, &alone)));
  EXPECT_FALSE(alone.stable);
  EXPECT_NE(alone.message.find("makes the loop neutral); what helps: filter the derivative"),
            std::string::npos)
      << alone.message;
}

}  // namespace
}  // namespace pidlab::tune
