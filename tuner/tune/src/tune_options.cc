// TuneOptions and the names of the methods, verdicts and terminations: what
// a tuning is asked and how it is named (tune.h). Tune() itself is tune.cc.

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "pidlab/optim/genetic_algorithm.h"
#include "pidlab/optim/nelder_mead.h"
#include "pidlab/optim/paper_nelder_mead.h"
#include "pidlab/optim/pso_gsa.h"
#include "pidlab/spec/field.h"
#include "pidlab/tune/tune.h"

namespace pidlab::tune {

bool ParseTuneMethod(const std::string& s, TuneMethod* method) {
  if (s == "multi-start")
    *method = TuneMethod::kMultiStart;
  else if (s == "nelder-mead")
    *method = TuneMethod::kNelderMead;
  else if (s == "paper-nm")
    *method = TuneMethod::kPaperNelderMead;
  else if (s == "ziegler-nichols")
    *method = TuneMethod::kZieglerNichols;
  else if (s == "ga")
    *method = TuneMethod::kGeneticAlgorithm;
  else if (s == "pso-gsa")
    *method = TuneMethod::kPsoGsa;
  else if (s == "simc")
    *method = TuneMethod::kSimc;
  else if (s == "amigo")
    *method = TuneMethod::kAmigo;
  else if (s == "migo")
    *method = TuneMethod::kMigo;
  else if (s == "optimal")
    *method = TuneMethod::kOptimal;
  else
    return false;
  return true;
}

std::string ToString(TuneMethod method) {
  switch (method) {
    case TuneMethod::kMultiStart:
      return "multi-start";
    case TuneMethod::kNelderMead:
      return "nelder-mead";
    case TuneMethod::kPaperNelderMead:
      return "paper-nm";
    case TuneMethod::kZieglerNichols:
      return "ziegler-nichols";
    case TuneMethod::kGeneticAlgorithm:
      return "ga";
    case TuneMethod::kPsoGsa:
      return "pso-gsa";
    case TuneMethod::kSimc:
      return "simc";
    case TuneMethod::kAmigo:
      return "amigo";
    case TuneMethod::kMigo:
      return "migo";
    case TuneMethod::kOptimal:
      return "optimal";
  }
  return "multi-start";
}

bool IsTuningRule(TuneMethod method) {
  return method == TuneMethod::kZieglerNichols || method == TuneMethod::kSimc ||
         method == TuneMethod::kAmigo || method == TuneMethod::kMigo || method == TuneMethod::kOptimal;
}

std::string ToString(RefineTermination termination) {
  switch (termination) {
    case RefineTermination::kNotRun:
      return "";
    case RefineTermination::kConvergence:
      return "CONVERGENCE";
    case RefineTermination::kNoConvergence:
      return "NO_CONVERGENCE";
    case RefineTermination::kFailure:
      return "FAILURE";
    case RefineTermination::kUserSuccess:
      return "USER_SUCCESS";
    case RefineTermination::kUserFailure:
      return "USER_FAILURE";
  }
  return "";
}

std::string ToString(RefineVerdict verdict, TuneMethod method) {
  switch (verdict) {
    case RefineVerdict::kNotRun:
      return "not run";
    case RefineVerdict::kAgree:
      return "agree";
    case RefineVerdict::kSearchStoppedShort:
      return ToString(method) + " stopped short";
    case RefineVerdict::kSearchBetter:
      return "search better";
  }
  return "not run";
}

void ApplyRobustPreset(TuneOptions* o, const RobustPresetKeep& keep) {
  if (!keep.objective) o->objective = evaluation::ObjectiveKind::kSetpointLoad;
  if (!keep.load_weight) o->load_weight = RobustPreset::kLoadWeight;
  if (!keep.derivative_filter) {
    o->loop.pid.derivative_filter_s = 0.0;
    o->loop.derivative_filter_ratio = RobustPreset::kFilterRatio;
    if (o->loop.loop == evaluation::LoopKind::kSampled) o->loop.derivative_filter_min_s = o->loop.dt_s;
  }
  if (!keep.max_ms) o->bounds.max_ms = RobustPreset::kMaxMs;
  if (!keep.max_time_constant)
    o->bounds.max_time_constant_s = RobustPreset::kTimeConstantFraction * o->loop.horizon_s;
}

bool TuneOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!std::isfinite(lower) || !std::isfinite(upper) || lower < 0.0 || !(lower < upper) || upper > kMaxGain)
    os << "bounds [" << lower << ", " << upper << "] must be finite with 0 <= lower < upper <= " << kMaxGain;
  else if (method == TuneMethod::kMigo && rule == RuleForm::kPid && !(loop.derivative_filter_ratio > 0.0))
    os << "migo's PID designs its derivative filter as tf = Td / N: give a derivative filter ratio N "
          "(--derivative-filter-ratio 10; the command line sets it when no filter is given)";
  else if (!start.empty() && (start.size() != 3 || std::any_of(start.begin(), start.end(), [this](double g) {
                                return !(g >= lower && g <= upper);
                              })))
    os << "start must be three gains inside the box [" << lower << ", " << upper << "]";
  else if (max_iterations < 0)
    os << "max iterations " << max_iterations << " must be >= 0";
  else if (max_evaluations < 0)
    os << "max evaluations " << max_evaluations << " must be >= 0";
  else if (starts < 0)
    os << "starts " << starts << " must be >= 0 (0: the method's default)";
  else if (method == TuneMethod::kMultiStart && (design_points < 1 || design_points > (1 << 20)))
    os << "design points " << design_points << " must be in [1, 1048576]";
  else if (method == TuneMethod::kMultiStart && EvaluationBudget() < 2)
    os << "multi-start needs at least 2 evaluations (a design point and a polish), not "
       << EvaluationBudget();
  else if (!(load_weight >= 0.0) || !std::isfinite(load_weight))
    os << "load weight " << load_weight << " must be finite and >= 0";
  else if (refine_starts < 1)
    os << "refine starts " << refine_starts << " must be >= 1";
  else if (std::isnan(max_overshoot_pct) || max_overshoot_pct < 0.0)
    os << "max overshoot " << max_overshoot_pct << " % must be >= 0";
  else if (std::isnan(max_settling_time_s) || !(max_settling_time_s > 0.0))
    os << "max settling time " << max_settling_time_s << " s must be positive";
  else if (!bounds.IsValid(error))
    return false;
  else if (robust_samples < 0 || robust_samples > 10000)
    os << "robust samples " << robust_samples << " must be in [0, 10000]";
  else if (!(robust_spread >= 0.0) || !(robust_spread < 1.0))
    os << "robust spread " << robust_spread << " must be in [0, 1)";
  else if (!(robust_quantile > 0.0) || !(robust_quantile <= 1.0))
    os << "robust quantile " << robust_quantile << " must be in (0, 1]";
  else if (!(agree_tolerance > 0.0) || !(agree_tolerance < 1.0))
    os << "agree tolerance " << agree_tolerance << " must be in (0, 1)";
  else if (!loop.IsValid(error))
    return false;
  else if (EvaluationBudget() * loop.StepsPerEvaluation() > kMaxTuneSteps)
    os << EvaluationBudget() << " evaluations x " << loop.StepsPerEvaluation()
       << " loop steps each = " << EvaluationBudget() * loop.StepsPerEvaluation()
       << " steps is more than 5e9: use a coarser dt or sample time, a shorter horizon, a slower disturbance "
          "or fewer evaluations";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

int TuneOptions::EvaluationBudget() const {
  if (IsTuningRule(method)) return 1;
  if (max_evaluations > 0) return max_evaluations;
  switch (method) {
    case TuneMethod::kMultiStart:
      return kMultiStartEvaluations;
    case TuneMethod::kNelderMead:
      return optim::NelderMeadOptions{}.max_evaluations;
    case TuneMethod::kPaperNelderMead:
      return optim::PaperNelderMeadOptions{}.max_evaluations;
    case TuneMethod::kGeneticAlgorithm:
      return optim::GeneticAlgorithmOptions{}.max_evaluations;
    case TuneMethod::kPsoGsa:
      return optim::PsoGsaOptions{}.max_evaluations;
    case TuneMethod::kZieglerNichols:
    case TuneMethod::kSimc:
    case TuneMethod::kAmigo:
    case TuneMethod::kMigo:
    case TuneMethod::kOptimal:
      break;
  }
  return 1;
}

int TuneOptions::StartCount() const {
  if (starts > 0) return starts;
  return method == TuneMethod::kMultiStart ? kMultiStartStarts : 4;
}

std::string TuneSummary::BriefReport() const {
  std::ostringstream os;
  os << ToString(method) << ": kp=" << gains.kp << " ki=" << gains.ki << " kd=" << gains.kd
     << " objective=" << objective << " evaluations=" << evaluations
     << " refine=" << ToString(refine.verdict, method);
  return os.str();
}

}  // namespace pidlab::tune
