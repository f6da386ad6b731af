#pragma once
// Internal to pidlab::tune: the steps of what a spec (pidlab/spec/loop_spec.h)
// means: the plant, loop, gains, bounds and tuning options it describes. Front
// ends do not chain them: they call the one function of their job
// (pidlab/tune/problem.h: BuildEvaluation, BuildTuning, ...), which does. Each
// step returns false with *error naming the field as `style` names it (a flag
// on the command line, a key in Python and JSON), its value and the rule
// broken. Unit tests of a step include this header (tests/CMakeLists.txt).

#include <set>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/tune.h"

namespace pidlab::tune {

using spec::NameStyle;

/// Every number of `s` finite (where its field takes no infinity) and at most
/// spec::kMaxInputMagnitude in magnitude.
template <typename Spec>
bool CheckSpecNumbers(Spec s, NameStyle style, std::string* error);

/// The Table I parameters with the spec's overrides.
bool BuildStepperParameters(const spec::PlantSpec& s, NameStyle style, StepperMotorParameters* out,
                            std::string* error);
/// The nonlinear stepper's options (plant stepper_nonlinear).
bool BuildNonlinearOptions(const spec::PlantSpec& s, NameStyle style, NonlinearStepperOptions* out,
                           std::string* error);
/// The plant, with its dead time (delay: >= 0, finite, at most
/// kMaxDelaySeconds; not for stepper_nonlinear yet).
bool BuildPlant(const spec::PlantSpec& s, NameStyle style, Plant* out, std::string* error);
/// The plant in its loop: a dead time needs the sampled loop (the continuous
/// loop with dead time is not supported yet) and at most
/// evaluation::kMaxAnalysedDelaySteps stored inputs at its dt
/// (evaluation::DelayIsValid, with the field named as `style` names it).
bool CheckPlantInLoop(const Plant& plant, const evaluation::LoopOptions& loop, NameStyle style,
                      std::string* error);
/// Three gains kp, ki, kd, each finite, >= 0 and at most kMaxGain.
bool BuildGains(const std::vector<double>& g, NameStyle style, PidGains* out, std::string* error);
bool BuildLoopOptions(const spec::LoopSpec& s, NameStyle style, evaluation::LoopOptions* out,
                      std::string* error);
bool BuildBounds(const spec::BoundsSpec& s, NameStyle style, analysis::LoopBounds* out, std::string* error);
/// --monte-carlo N (>= 0; 0 builds one draw) and --spread, seeded by the loop's seed.
bool BuildMonteCarlo(const spec::EvaluateSpec& s, NameStyle style, analysis::MonteCarloOptions* out,
                     std::string* error);

/// The robust preset on a spec: with tune.robust set, every field of the
/// preset that is not in `given` (the keys the user gave) takes the preset's
/// value (objective setpoint-load, load weight 1, derivative filter ratio 10
/// with no fixed filter, Ms <= 1.6, slowest time constant <= horizon / 10).
/// The result is what ran, so a resolved spec run again is the same tuning.
void ResolveRobustPreset(spec::TuningSpec* s, const std::set<std::string>& given);
/// The tuning options of a (resolved) tuning spec, its loop, bounds and
/// stepper parameters included.
bool BuildTuneOptions(const spec::TuningSpec& s, NameStyle style, TuneOptions* out, std::string* error);

// ---- implementation

namespace internal {
bool CheckNumber(const spec::Field& f, double v, NameStyle style, std::string* error);
}  // namespace internal

/// Archive for CheckSpecNumbers: the first number out of range.
class NumberChecker {
 public:
  NumberChecker(NameStyle style, std::string* error) : style_(style), error_(error) {}
  void Visit(const spec::Field& f, double* v) { Check(f, *v); }
  void Visit(const spec::Field& f, std::vector<double>* v) {
    for (double x : *v) Check(f, x);
  }
  void Visit(const spec::Field& f, std::pair<double, double>* v) {
    Check(f, v->first);
    Check(f, v->second);
  }
  void Visit(const spec::Field& f, std::map<std::string, double>* v) {
    for (const auto& kv : *v) Check(f, kv.second);
  }
  template <typename T>
  void Visit(const spec::Field&, T*) {}
  bool ok() const { return ok_; }

 private:
  void Check(const spec::Field& f, double v) {
    if (ok_) ok_ = internal::CheckNumber(f, v, style_, error_);
  }
  NameStyle style_;
  std::string* error_;
  bool ok_ = true;
};

template <typename Spec>
bool CheckSpecNumbers(Spec s, NameStyle style, std::string* error) {
  NumberChecker c(style, error);
  s.Serialize(&c);
  return c.ok();
}

}  // namespace pidlab::tune
