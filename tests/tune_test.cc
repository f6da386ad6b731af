#include "pidlab/tune/tune.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <thread>
#include <vector>

#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::optim::MultiStart;
using pidlab::tune::kMultiStartStarts;
using pidlab::tune::RefineSummary;
using pidlab::tune::RefineTermination;
using pidlab::tune::RefineVerdict;
using pidlab::tune::RefineWithCeres;
using pidlab::tune::Tune;
using pidlab::tune::TuneMethod;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;

namespace pidlab {
namespace {

Plant MakeBuiltin(const std::string& name) {
  Plant plant;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant(name, StepperMotorParameters{}, &plant)));
  return plant;
}

struct PaperCase {
  const char* plant;
  double paper_nelder_mead_iae;  // Tables II, III, IV
};

class TuneBeatsPaper : public ::testing::TestWithParam<PaperCase> {};

TEST_P(TuneBeatsPaper, DefaultTuneBeatsThePapersIaeWithAStrictlyStableLoop) {
  const PaperCase& c = GetParam();
  const Plant plant = MakeBuiltin(c.plant);
  TuneOptions options;
  TuneSummary dut;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  EXPECT_LT(dut.objective, c.paper_nelder_mead_iae);
  // Independent re-evaluation of the returned gains.
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(plant, dut.gains, LoopOptions{}, EvaluateOptions{}, &ev)));
  EXPECT_TRUE(ev.stability.stable);
  EXPECT_NEAR(ev.iae, dut.objective, 1e-9 * dut.objective);
  for (const auto& p : ev.stability.poles)
    EXPECT_LE(p.real(), -0.01 * std::max(1.0, std::abs(p)) * (1 - 1e-9));
  for (double g : {dut.gains.kp, dut.gains.ki, dut.gains.kd}) {
    EXPECT_GE(g, 0.0);
    EXPECT_LE(g, 30.0);
  }
  EXPECT_TRUE(dut.refine.ran);
  EXPECT_NE(dut.refine.verdict, RefineVerdict::kNotRun);
}

INSTANTIATE_TEST_SUITE_P(Plants, TuneBeatsPaper,
                         ::testing::Values(PaperCase{"double_integrator", 1.9151},
                                           PaperCase{"oscillator", 2.2304},
                                           PaperCase{"stepper_motor", 1.9751}),
                         [](const ::testing::TestParamInfo<PaperCase>& p) {
                           return std::string(p.param.plant);
                         });

TEST(Tune, IsDeterministicForASeed) {
  const Plant plant = MakeBuiltin("oscillator");
  TuneOptions options;
  options.method = TuneMethod::kPaperNelderMead;
  options.seed = 7;
  TuneSummary a, b;
  ASSERT_TRUE(IsOk(Tune(plant, options, &a)));
  ASSERT_TRUE(IsOk(Tune(plant, options, &b)));
  EXPECT_EQ(a.gains.kp, b.gains.kp);
  EXPECT_EQ(a.gains.ki, b.gains.ki);
  EXPECT_EQ(a.gains.kd, b.gains.kd);
  EXPECT_EQ(a.evaluations, b.evaluations);
}

// A ParallelFor with three threads taking indices as they come, like
// EpisodePool's workers: the bodies run at the same time in any order.
void ThreeThreads(int count, const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  std::vector<std::thread> workers;
  for (int w = 0; w < 3; ++w)
    workers.emplace_back([&] {
      for (int i; (i = next.fetch_add(1)) < count;) body(i);
    });
  for (auto& t : workers) t.join();
}

class TuneInParallel : public ::testing::TestWithParam<TuneMethod> {};

TEST_P(TuneInParallel, GivesTheSameBitsAsOneEvaluationAfterTheOther) {
  TuneOptions options;
  options.method = GetParam();
  options.loop.loop = LoopKind::kSampled;
  options.loop.horizon_s = 2.0;
  options.max_evaluations = 90;
  options.starts = 5;
  options.seed = 7;
  options.refine = false;
  TuneSummary one, parallel;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(MakeBuiltin("double_integrator"), options, &one)));
  options.parallel_for = ThreeThreads;
  ASSERT_TRUE(IsOk(Tune(MakeBuiltin("double_integrator"), options, &parallel)));
  EXPECT_EQ(parallel.evaluations, one.evaluations);
  EXPECT_EQ(parallel.iterations, one.iterations);
  EXPECT_EQ(parallel.objective, one.objective);  // bit for bit
  EXPECT_EQ(parallel.gains.kp, one.gains.kp);
  EXPECT_EQ(parallel.gains.ki, one.gains.ki);
  EXPECT_EQ(parallel.gains.kd, one.gains.kd);
  ASSERT_EQ(parallel.optimizer.trace.size(), one.optimizer.trace.size());
  for (std::size_t i = 0; i < one.optimizer.trace.size(); ++i)
    EXPECT_EQ(parallel.optimizer.trace[i].best_f, one.optimizer.trace[i].best_f) << "iteration " << i + 1;
  EXPECT_EQ(parallel.optimizer.message, one.optimizer.message);
}

INSTANTIATE_TEST_SUITE_P(Methods, TuneInParallel,
                         ::testing::Values(TuneMethod::kMultiStart, TuneMethod::kNelderMead,
                                           TuneMethod::kGeneticAlgorithm, TuneMethod::kPsoGsa),
                         [](const ::testing::TestParamInfo<TuneMethod>& p) {
                           std::string name = ToString(p.param);  // "multi-start": gtest names take no '-'
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// The done-when: for seeds 1-20 the default tune of each plant
// reaches the same objective to 0.1 %, and that objective is no worse (to
// 0.1 %) than the best the other methods find. The reference runs every other
// method (nelder-mead, paper-nm, ga, pso-gsa, each with the Ceres
// cross-check) with seed 1 only: over seeds 1-20 of all four
// (bench/tune_seeds.sh, docs/tuning.md) the best per plant is already one of
// these seed-1 runs (paper-nm on 1/s^2 and the stepper, nelder-mead on
// 1/(s^2+1)), and 80 tunes per plant would take minutes under ASan.
class DefaultTuneOverSeeds : public ::testing::TestWithParam<const char*> {};

TEST_P(DefaultTuneOverSeeds, ReachesTheSameObjectiveForEverySeedAndNoWorseThanAnyOtherMethod) {
  const Plant plant = MakeBuiltin(GetParam());
  double reference = std::numeric_limits<double>::infinity();
  std::string reference_method;
  for (TuneMethod method : {TuneMethod::kNelderMead, TuneMethod::kPaperNelderMead,
                            TuneMethod::kGeneticAlgorithm, TuneMethod::kPsoGsa}) {
    TuneOptions options;
    options.method = method;
    TuneSummary other;
    std::string error;
    ASSERT_TRUE(IsOk(Tune(plant, options, &other)));
    if (other.stable && other.objective < reference) {
      reference = other.objective;
      reference_method = ToString(method);
    }
  }
  ASSERT_TRUE(std::isfinite(reference));
  double lowest = std::numeric_limits<double>::infinity(), highest = 0.0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    TuneOptions options;  // the default: multi-start, Ceres from the best minima
    options.seed = seed;
    TuneSummary dut;
    std::string error;
    ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
    ASSERT_TRUE(dut.stable) << "seed " << seed;
    EXPECT_LE(dut.objective, reference * 1.001)
        << "seed " << seed << ": " << dut.BriefReport() << " vs " << reference_method << " " << reference;
    lowest = std::min(lowest, dut.objective);
    highest = std::max(highest, dut.objective);
  }
  EXPECT_LE(highest, lowest * 1.001) << "seeds 1-20 range over [" << lowest << ", " << highest << "]";
}

INSTANTIATE_TEST_SUITE_P(Plants, DefaultTuneOverSeeds,
                         ::testing::Values("double_integrator", "oscillator", "stepper_motor"),
                         [](const ::testing::TestParamInfo<const char*>& p) { return std::string(p.param); });

TEST(MultiStart, RefinesFromSeveralDistinctPolishedMinimaAndKeepsTheBest) {
  const Plant plant = MakeBuiltin("stepper_motor");
  TuneOptions options;
  TuneSummary dut;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  ASSERT_GE(dut.local_minima.size(), 2u);
  for (std::size_t i = 1; i < dut.local_minima.size(); ++i)
    EXPECT_LE(dut.local_minima[i - 1].f, dut.local_minima[i].f);
  EXPECT_EQ(dut.search_objective, dut.local_minima.front().f);
  EXPECT_EQ(dut.refine.runs, options.refine_starts);
  EXPECT_LE(dut.objective, dut.search_objective);
  const ObjectiveEvaluator exact(plant, options.loop, ObjectiveKind::kIae);
  EXPECT_EQ(exact(dut.gains), dut.objective);
}

TEST(NelderMeadStarts, ShareMaxEvaluationsInFixedPartsWhateverRunsThem) {
  TuneOptions options;
  options.method = TuneMethod::kNelderMead;
  options.max_evaluations = 10;
  options.starts = 4;  // shares 3, 3, 2, 2
  options.refine = false;
  options.parallel_for = ThreeThreads;
  TuneSummary s;
  std::string error;
  ASSERT_TRUE(IsOk(Tune(MakeBuiltin("double_integrator"), options, &s)));
  EXPECT_EQ(s.evaluations, 10);
  EXPECT_EQ(s.optimizer.starts, 4);
}

TEST(Tune, NeverAcceptsALoopThatIsNotStrictlyStable) {
  // With the evaluation margin near zero the search parks poles on the
  // imaginary axis; every candidate it accepts must still be strictly stable.
  const Plant plant = MakeBuiltin("oscillator");
  TuneOptions options;
  options.loop.stability_margin = 1e-9;
  options.refine = false;
  TuneSummary dut;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(plant, dut.gains, LoopOptions{}, EvaluateOptions{}, &ev)));
  for (const auto& p : ev.stability.poles) EXPECT_LT(p.real(), 0.0);
}

TEST(ObjectiveEvaluator, ReturnsInfinityForMarginalAndUnstableLoops) {
  const ObjectiveEvaluator dut(MakeBuiltin("double_integrator"), LoopOptions{}, ObjectiveKind::kIae);
  EXPECT_TRUE(std::isinf(dut(PidGains{1.0, 0.0, 0.0})));   // s^2 + 1: poles on the axis
  EXPECT_TRUE(std::isinf(dut(PidGains{1.0, 10.0, 0.1})));  // Routh: kd*kp < ki -> unstable
  EXPECT_TRUE(std::isfinite(dut(PidGains{29.6558, 0.4977, 28.3216})));
}

TEST(RefineWithCeres, SaysTheSearchStoppedShortWhenNelderMeadIsStoppedEarly) {
  const Plant plant = MakeBuiltin("double_integrator");
  TuneOptions options;
  options.method = TuneMethod::kNelderMead;
  options.starts = 1;
  options.max_evaluations = 8;  // a handful of evaluations: far from a minimum
  TuneSummary dut;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  ASSERT_TRUE(dut.refine.ran);
  EXPECT_EQ(dut.refine.verdict, RefineVerdict::kSearchStoppedShort);
  EXPECT_LT(dut.refine.objective, dut.search_objective * (1.0 - options.agree_tolerance));
  EXPECT_GT(dut.refine.relative_improvement, options.agree_tolerance);
  // The better gains are returned, and re-evaluate to the reported objective.
  EXPECT_EQ(dut.gains.kp, dut.refine.gains.kp);
  const ObjectiveEvaluator exact(plant, options.loop, ObjectiveKind::kIae);
  EXPECT_DOUBLE_EQ(exact(dut.gains), dut.objective);
}

TEST(RefineWithCeres, AgreesWithAConvergedNelderMead) {
  const Plant plant = MakeBuiltin("stepper_motor");
  TuneOptions options;
  options.method = TuneMethod::kNelderMead;
  TuneSummary dut;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  EXPECT_EQ(dut.refine.verdict, RefineVerdict::kAgree);
  EXPECT_EQ(dut.refine.termination, RefineTermination::kConvergence);
  EXPECT_LE(std::abs(dut.refine.relative_improvement), options.agree_tolerance);
}

TEST(RefineWithCeres, WorksOnTheSampledLoopToo) {
  const Plant plant = MakeBuiltin("double_integrator");
  TuneOptions options;
  options.loop.loop = LoopKind::kSampled;
  options.loop.dt_s = 1e-2;
  options.loop.horizon_s = 5.0;
  const PidGains start{10.0, 1.0, 5.0};
  const ObjectiveEvaluator exact(plant, options.loop, ObjectiveKind::kIae);
  const double f0 = exact(start);
  const RefineSummary dut = RefineWithCeres(plant, options, start, f0);
  ASSERT_TRUE(dut.ran);
  EXPECT_LT(dut.objective, f0);
  EXPECT_EQ(dut.verdict, RefineVerdict::kSearchStoppedShort);
}

TEST(RefineVerdict, PrintsTheTextOfTheJsonVerdictKey) {
  EXPECT_EQ(ToString(RefineVerdict::kNotRun, TuneMethod::kNelderMead), "not run");
  EXPECT_EQ(ToString(RefineVerdict::kAgree, TuneMethod::kGeneticAlgorithm), "agree");
  EXPECT_EQ(ToString(RefineVerdict::kSearchStoppedShort, TuneMethod::kNelderMead),
            "nelder-mead stopped short");
  EXPECT_EQ(ToString(RefineVerdict::kSearchStoppedShort, TuneMethod::kPaperNelderMead),
            "paper-nm stopped short");
  EXPECT_EQ(ToString(RefineVerdict::kSearchBetter, TuneMethod::kPsoGsa), "search better");
}

TEST(RefineTermination, PrintsCeresNamesAndNothingWhenNotRun) {
  EXPECT_EQ(ToString(RefineTermination::kNotRun), "");
  EXPECT_EQ(ToString(RefineTermination::kConvergence), "CONVERGENCE");
  EXPECT_EQ(ToString(RefineTermination::kNoConvergence), "NO_CONVERGENCE");
  EXPECT_EQ(ToString(RefineTermination::kFailure), "FAILURE");
}

TEST(RefineWithCeres, IsNotRunOnTheContinuousIae) {
  TuneOptions options;
  options.objective = ObjectiveKind::kIaeContinuous;
  const RefineSummary dut =
      RefineWithCeres(MakeBuiltin("double_integrator"), options, PidGains{10.0, 1.0, 5.0}, 1.0);
  EXPECT_FALSE(dut.ran);
  EXPECT_EQ(dut.verdict, RefineVerdict::kNotRun);
  EXPECT_EQ(dut.termination, RefineTermination::kNotRun);
  EXPECT_NE(dut.message.find("iae-continuous"), std::string::npos) << dut.message;
}

TEST(Tune, ZieglerNicholsOnTheDoubleIntegratorSaysItDoesNotApply) {
  TuneOptions options;
  options.method = TuneMethod::kZieglerNichols;
  TuneSummary dut;
  std::string error;
  EXPECT_FALSE(OkInto(Tune(MakeBuiltin("double_integrator"), options, &dut), &error));
  EXPECT_NE(error.find("does not apply"), std::string::npos) << error;
}

TEST(Tune, RespectsAnOvershootConstraint) {
  const Plant plant = MakeBuiltin("stepper_motor");
  TuneOptions options;
  options.method = TuneMethod::kNelderMead;
  options.max_overshoot_pct = 0.5;
  options.refine = false;
  TuneSummary dut;
  ASSERT_TRUE(IsOk(Tune(plant, options, &dut)));
  ASSERT_TRUE(dut.stable);
  Evaluation ev;
  ASSERT_TRUE(IsOk(Evaluate(plant, dut.gains, LoopOptions{}, EvaluateOptions{}, &ev)));
  EXPECT_LE(ev.step.overshoot_pct, 0.5);
}

TEST(TuneOptions, RejectsAnEmptyBox) {
  TuneOptions options;
  options.lower = 5.0;
  options.upper = 5.0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("bounds"), std::string::npos);
}

TEST(TuneOptions, RejectsNegativeLowerBound) {
  TuneOptions options;
  options.lower = -1.0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("-1"), std::string::npos);
}

TEST(TuneOptions, BoundsLoopStepsTimesTheEvaluationBudget) {
  TuneOptions options;
  options.loop.loop = LoopKind::kSampled;
  options.loop.dt_s = 1e-5;  // 2.5e6 steps x 20000 evaluations
  std::string error;
  EXPECT_EQ(options.EvaluationBudget(), 20000);
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("more than 5e9"), std::string::npos) << error;
  options.max_evaluations = 1000;  // 2.5e9 steps
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options.max_evaluations = 0;
  options.method = TuneMethod::kZieglerNichols;  // one evaluation
  EXPECT_EQ(options.EvaluationBudget(), 1);
  EXPECT_TRUE(options.IsValid(&error)) << error;
}

TEST(TuneOptions, RejectsAnUpperBoundAboveTheGainLimit) {
  TuneOptions options;
  options.upper = 1e13;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("1e+13"), std::string::npos) << error;
}

TEST(TuneOptions, RejectsNegativeStartsAndTakesZeroForTheMethodsDefault) {
  TuneOptions options;
  options.starts = -1;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("starts"), std::string::npos);
  options.starts = 0;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  EXPECT_EQ(options.StartCount(), kMultiStartStarts);
  options.method = TuneMethod::kNelderMead;
  EXPECT_EQ(options.StartCount(), 4);
}

TEST(TuneOptions, MultiStartNeedsTwoEvaluations) {
  TuneOptions options;
  options.max_evaluations = 1;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("at least 2 evaluations"), std::string::npos) << error;
  options.max_evaluations = 2;
  EXPECT_TRUE(options.IsValid(&error)) << error;
}

TEST(Tune, ATrioThatFailsUnderTheSearchIsARunnerFailedStatusNotAnException) {
  TuneOptions options;
  options.loop.loop = LoopKind::kSampled;
  options.loop.horizon_s = 2.0;
  std::atomic<int> calls{0};
  const evaluation::SampledRunner runner = [&calls](const Plant&, const PidGains&, const LoopOptions&,
                                                    const DisturbanceOptions&, std::vector<double>*,
                                                    std::vector<evaluation::SampledStep>*) {
    ++calls;
    return Status::RunnerFailed("pidlab-plant went silent");
  };
  TuneSummary dut;
  Status st;
  EXPECT_NO_THROW(st = Tune(MakeBuiltin("double_integrator"), options, &dut, nullptr, runner));
  EXPECT_EQ(st.code(), StatusCode::kRunnerFailed) << st.message();
  EXPECT_NE(st.message().find("pidlab-plant went silent"), std::string::npos) << st.message();
  EXPECT_GT(calls.load(), 0);
}

}  // namespace
}  // namespace pidlab
