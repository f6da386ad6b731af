// The continuous loop with dead time, fast and lean (docs/benchmarks.md,
// "Dead time, fast and lean"): one evaluation of the tuner's objective
// (ObjectiveEvaluator: stability by the crossing frequencies, the method of
// steps on the uniform grid) against the reference path, the same loop
// computed as before both (ReferenceDelayedObjective: the Nyquist count on
// the analysis grid, the method of steps node by node), in one run, with
// the ratio and the objectives' relative difference per case.
//
//   build/bin/delay_bench                  (the table at the end: evaluations/s, ratio)
//   build/bin/delay_bench --tune=fast      (a multi-start search of 200 evaluations on
//   build/bin/delay_bench --tune=reference  case 1's plant; peak RSS: bench/delay_bench.sh)

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "pidlab/optim/multi_start.h"
#include "pidlab/tune/tune.h"

namespace {

using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::ObjectiveEvaluator;
using pidlab::evaluation::ObjectiveKind;
using pidlab::evaluation::ReferenceDelayedObjective;

struct Case {
  const char* name;
  std::vector<double> num, den;
  double delay_s;
  pidlab::PidGains gains;
  double filter_s;      // tf, or 0 for the ratio
  double filter_ratio;  // N: tf = Td / N (migo's)
  double horizon_s, sample_time_s;
};
const Case kCases[] = {
    {"1/(10s+1)e^-2s tf=0.02", {1.0}, {10.0, 1.0}, 2.0, {3.0, 0.3, 1.0}, 0.02, 0.0, 25.0, 0.05},
    {"1/(10s+1)e^-2s tf=Td/10", {1.0}, {10.0, 1.0}, 2.0, {3.0, 0.3, 1.0}, 0.0, 10.0, 25.0, 0.05},
    {"2/(60s+1)e^-8s tf=Td/10", {2.0}, {60.0, 1.0}, 8.0, {2.0, 0.04, 8.0}, 0.0, 10.0, 400.0, 1.0},
};

pidlab::Plant PlantOf(const Case& c) {
  pidlab::Plant p;
  p.name = "custom";
  p.tf = pidlab::TransferFunction{c.num, c.den};
  p.delay_s = c.delay_s;
  return p;
}

LoopOptions OptionsOf(const Case& c) {
  LoopOptions o;
  o.pid.derivative_filter_s = c.filter_s;
  o.derivative_filter_ratio = c.filter_ratio;
  o.horizon_s = c.horizon_s;
  o.sample_time_s = c.sample_time_s;
  return o;
}

// Args: the case, then 0 = the fast path (ObjectiveEvaluator), 1 = the reference.
void BM_DelayedObjective(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const bool reference = state.range(1) == 1;
  const pidlab::Plant plant = PlantOf(c);
  const LoopOptions options = OptionsOf(c);
  const ObjectiveEvaluator fast(plant, options, ObjectiveKind::kIae);
  double iae = 0.0;
  for (auto _ : state) {
    iae = reference ? ReferenceDelayedObjective(plant, options, ObjectiveKind::kIae, c.gains) : fast(c.gains);
    benchmark::DoNotOptimize(&iae);
  }
  state.SetItemsProcessed(state.iterations());
  char label[96];
  std::snprintf(label, sizeof label, "%s %s iae=%.15g", c.name, reference ? "reference" : "fast", iae);
  state.SetLabel(label);
}
BENCHMARK(BM_DelayedObjective)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->MinTime(0.5);

// The console's lines, then per case the two paths' evaluations/s, their
// ratio and the objectives' relative difference.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) seconds_[r.benchmark_name()] = r.GetAdjustedRealTime() / 1e3;  // ms
  }
  void Table() const {
    std::printf("\n%-26s %14s %14s %9s %12s\n", "case", "reference /s", "fast /s", "ratio", "max rel diff");
    for (int i = 0; i < static_cast<int>(std::size(kCases)); ++i) {
      const auto fast = seconds_.find(Name(i, 0)), ref = seconds_.find(Name(i, 1));
      if (fast == seconds_.end() || ref == seconds_.end()) continue;
      const Case& c = kCases[i];
      const double a = ObjectiveEvaluator(PlantOf(c), OptionsOf(c), ObjectiveKind::kIae)(c.gains);
      const double b = ReferenceDelayedObjective(PlantOf(c), OptionsOf(c), ObjectiveKind::kIae, c.gains);
      std::printf("%-26s %14.1f %14.1f %8.1fx %12.2e\n", c.name, 1.0 / ref->second, 1.0 / fast->second,
                  ref->second / fast->second, std::abs(a - b) / std::abs(b));
    }
  }

 private:
  static std::string Name(int c, int path) {
    return "BM_DelayedObjective/" + std::to_string(c) + "/" + std::to_string(path) + "/min_time:0.500";
  }
  std::map<std::string, double> seconds_;
};

// A multi-start search as `pidlab tune --num 1 --den 10,1 --delay 2 --method
// multi-start --max-evals 200` runs it (its box, time scale and filter), on
// one path; prints the result and the process's peak RSS.
int TuneMode(bool reference) {
  const Case& c = kCases[1];
  const pidlab::Plant plant = PlantOf(c);
  LoopOptions options = OptionsOf(c);
  options.horizon_s = 100.0;
  options.sample_time_s = 0.2;
  const ObjectiveEvaluator fast(plant, options, ObjectiveKind::kIae);
  const pidlab::optim::ObjectiveFunction f = [&](const Eigen::VectorXd& x) {
    const pidlab::PidGains g{x(0), x(1), x(2)};
    return reference ? ReferenceDelayedObjective(plant, options, ObjectiveKind::kIae, g) : fast(g);
  };
  pidlab::optim::MultiStartOptions o;
  o.max_evaluations = 200;
  o.design_points = 100;
  o.starts = 16;
  o.warp = pidlab::tune::kGainWarp;
  o.min_separation = pidlab::tune::kMultiStartSeparation;
  const pidlab::optim::Bounds box{Eigen::VectorXd::Zero(3), Eigen::VectorXd::Constant(3, 24.5)};
  pidlab::optim::OptimizerSummary summary;
  const auto start = std::chrono::steady_clock::now();
  pidlab::optim::MultiStart(f, box, o, &summary);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("tune %s: objective %.10g at (%.6g, %.6g, %.6g), %d evaluations, %.3f s, peak RSS %ld kB\n",
              reference ? "reference" : "fast", summary.f, summary.x(0), summary.x(1), summary.x(2),
              summary.evaluations, wall, usage.ru_maxrss);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--tune=fast" || arg == "--tune=reference") return TuneMode(arg == "--tune=reference");
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.Table();
  benchmark::Shutdown();
  return 0;
}
