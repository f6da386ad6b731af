// Evaluations per second of the paper's objective (IAE, eq. 4: 501 exact
// samples of the continuous loop, stability check included): the inner loop
// of every tuner. Also the sampled loop at the dt each plant needs.
//
//   build/bin/objective_bench            (items_per_second = evaluations/s)

#include <benchmark/benchmark.h>

#include "pidlab/tuner/evaluation.h"

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
  pidlab::MakePlant(c.plant, {}, &plant, nullptr);
  const pidlab::ObjectiveEvaluator dut(plant, pidlab::LoopOptions{}, pidlab::ObjectiveKind::kIae);
  double sink = 0.0;
  for (auto _ : state) {
    sink += dut(c.gains);
    benchmark::DoNotOptimize(sink);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(c.plant);
}
BENCHMARK(BM_PaperObjectiveContinuous)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

void BM_PaperObjectiveSampled(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  pidlab::Plant plant;
  pidlab::MakePlant(c.plant, {}, &plant, nullptr);
  pidlab::LoopOptions options;
  options.loop = pidlab::LoopKind::kSampled;
  options.dt_s = plant.name == "stepper_motor" ? 1e-4 : 1e-3;
  options.pid.dt_s = options.dt_s;
  const pidlab::ObjectiveEvaluator dut(plant, options, pidlab::ObjectiveKind::kIae);
  double sink = 0.0;
  for (auto _ : state) {
    sink += dut(c.gains);
    benchmark::DoNotOptimize(sink);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(std::string(c.plant) + " dt=" + std::to_string(options.dt_s));
}
BENCHMARK(BM_PaperObjectiveSampled)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
