// Evaluations per second of the paper's objective (IAE, eq. 4: 501 exact
// samples of the continuous loop, stability check included): the inner loop
// of every tuner, on ObjectiveEvaluator's fast path (fast_objective.h) and on
// the general path it falls back to (BM_GeneralPathContinuous: eigenvalues,
// dynamic matrices; what a disturbance or a plant above order 6 costs). Also
// the sampled loop at the dt each plant needs.
//
//   build/bin/objective_bench            (items_per_second = evaluations/s;
//                                         BM_TuneDefault = one whole `pidlab tune`)
//   bench/peers.sh                       (the same objective in scipy, ratio)

#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "pidlab/tune/tune.h"

namespace {

struct Case {
  const char* plant;
  pidlab::PidGains gains;  // the paper's Nelder-Mead gains (Tables II-IV)
};
const Case kCases[] = {{"double_integrator", {29.6558, 0.4977, 28.3216}},
                       {"oscillator", {0.0774, 14.7575, 14.9913}},
                       {"stepper_motor", {20.8836, 26.607, 12.4866}}};

void BM_PaperObjectiveContinuous(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  pidlab::Plant plant;
  pidlab::MakePlant(c.plant, {}, &plant).ok();
  const pidlab::evaluation::ObjectiveEvaluator dut(plant, pidlab::evaluation::LoopOptions{},
                                                   pidlab::evaluation::ObjectiveKind::kIae);
  double iae = 0.0;
  for (auto _ : state) {
    iae = dut(c.gains);
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  char label[96];
  std::snprintf(label, sizeof label, "%s iae=%.17g", c.plant, iae);  // bench/peers.sh checks it against scipy
  state.SetLabel(label);
}
BENCHMARK(BM_PaperObjectiveContinuous)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

void BM_GeneralPathContinuous(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  pidlab::Plant plant;
  pidlab::MakePlant(c.plant, {}, &plant).ok();
  const pidlab::StateSpace realization = pidlab::Realize(plant.tf);
  const pidlab::Disturbance none(pidlab::DisturbanceOptions{});
  const pidlab::evaluation::LoopOptions options;
  for (auto _ : state) {
    const double iae = pidlab::evaluation::GeneralContinuousObjective(
        realization, none, options, pidlab::evaluation::ObjectiveKind::kIae, c.gains);
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(c.plant);
}
BENCHMARK(BM_GeneralPathContinuous)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

void BM_PaperObjectiveSampled(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  pidlab::Plant plant;
  pidlab::MakePlant(c.plant, {}, &plant).ok();
  pidlab::evaluation::LoopOptions options;
  options.loop = pidlab::evaluation::LoopKind::kSampled;
  options.dt_s = plant.name == "stepper_motor" ? 1e-4 : 1e-3;
  options.pid = PidOptionsAt(options.pid, options.dt_s);
  const pidlab::evaluation::ObjectiveEvaluator dut(plant, options, pidlab::evaluation::ObjectiveKind::kIae);
  for (auto _ : state) {
    const double iae = dut(c.gains);
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(std::string(c.plant) + " dt=" + std::to_string(options.dt_s));
}
BENCHMARK(BM_PaperObjectiveSampled)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// Dead time (docs/deadtime.md): one evaluation of the objective on the same
// plant, 1/(s+1)^2 under the PI (0.5, 0.3), with and without L = 0.5 s, in
// the sampled loop (dt = 1e-3, the target: within 2x) and in the
// continuous loop (the fast path without delay, the method of steps with
// it). Arg: 0 = no delay, 1 = L = 0.5 s.
pidlab::Plant Sopdt(double delay_s) {
  pidlab::Plant p;
  p.name = "custom";
  p.tf = pidlab::TransferFunction{{1.0}, {1.0, 2.0, 1.0}};
  p.delay_s = delay_s;
  return p;
}

void BM_DelaySampled(benchmark::State& state) {
  pidlab::evaluation::LoopOptions options;
  options.loop = pidlab::evaluation::LoopKind::kSampled;
  options.pid = PidOptionsAt(options.pid, options.dt_s);
  const pidlab::evaluation::ObjectiveEvaluator dut(Sopdt(state.range(0) ? 0.5 : 0.0), options,
                                                   pidlab::evaluation::ObjectiveKind::kIae);
  for (auto _ : state) {
    const double iae = dut({0.5, 0.3, 0.0});
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(state.range(0) ? "L=0.5 dt=1e-3" : "L=0 dt=1e-3");
}
BENCHMARK(BM_DelaySampled)->DenseRange(0, 1)->Unit(benchmark::kMicrosecond);

void BM_DelayContinuous(benchmark::State& state) {
  const pidlab::evaluation::ObjectiveEvaluator dut(Sopdt(state.range(0) ? 0.5 : 0.0),
                                                   pidlab::evaluation::LoopOptions{},
                                                   pidlab::evaluation::ObjectiveKind::kIae);
  for (auto _ : state) {
    const double iae = dut({0.5, 0.3, 0.0});
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(state.range(0) ? "L=0.5 method of steps" : "L=0 fast path");
}
BENCHMARK(BM_DelayContinuous)->DenseRange(0, 1)->Unit(benchmark::kMicrosecond);

// A whole default tune (4-start Nelder-Mead on the paper's objective plus the
// Ceres cross-check): the "well under a second" per plant.
void BM_TuneDefault(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  pidlab::Plant plant;
  pidlab::MakePlant(c.plant, {}, &plant).ok();
  const pidlab::tune::TuneOptions options;
  int evaluations = 0;
  double iae = 0.0;
  for (auto _ : state) {
    pidlab::tune::TuneSummary summary;
    std::string error;
    if (const pidlab::Status st = pidlab::tune::Tune(plant, options, &summary); !st.ok())
      state.SkipWithError(st.message().c_str());
    // Tune() cannot be optimised away (it allocates and runs Ceres); no
    // DoNotOptimize on a double here: GCC 12 with benchmark 1.7's "+m,r"
    // constraint garbles the value read back.
    iae = summary.objective;
    evaluations = summary.evaluations;
  }
  state.SetLabel(std::string(c.plant) + " iae=" + std::to_string(iae) +
                 " evaluations=" + std::to_string(evaluations));
}
BENCHMARK(BM_TuneDefault)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// Polynomial coefficients, descending, to 17 digits.
std::string Coefficients(const std::vector<double>& p) {
  std::string out;
  for (double v : p) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%.17g", out.empty() ? "" : ",", v);
    out += buf;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // Every plant and its gains in the JSON context, so that bench/peers.sh
  // runs the same objective elsewhere: "num=...;den=...;gains=kp,ki,kd".
  for (const Case& c : kCases) {
    pidlab::Plant plant;
    pidlab::MakePlant(c.plant, {}, &plant).ok();
    benchmark::AddCustomContext(std::string("plant.") + c.plant,
                                "num=" + Coefficients(plant.tf.num) + ";den=" + Coefficients(plant.tf.den) +
                                    ";gains=" + Coefficients({c.gains.kp, c.gains.ki, c.gains.kd}));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
