#include "pidlab/optim/optimizer.h"

#include <cmath>
#include <sstream>

#include "internal.h"

namespace pidlab::optim {

bool Bounds::IsValid(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  std::ostringstream os;
  if (lower.size() != upper.size()) {
    os << "Bounds.lower has size " << lower.size() << " but Bounds.upper has size " << upper.size()
       << ": they must match";
    return fail(os.str());
  }
  if (lower.size() == 0) return fail("Bounds.lower and Bounds.upper are empty: need at least one dimension");
  for (Eigen::Index i = 0; i < lower.size(); ++i) {
    if (!std::isfinite(lower[i])) {
      os << "Bounds.lower[" << i << "] = " << lower[i] << " must be finite";
      return fail(os.str());
    }
    if (!std::isfinite(upper[i])) {
      os << "Bounds.upper[" << i << "] = " << upper[i] << " must be finite";
      return fail(os.str());
    }
    if (!(lower[i] < upper[i])) {
      os << "Bounds.lower[" << i << "] = " << lower[i] << " must be < Bounds.upper[" << i
         << "] = " << upper[i];
      return fail(os.str());
    }
  }
  return true;
}

std::string ToString(TerminationType type) {
  switch (type) {
    case TerminationType::kConverged:
      return "CONVERGED";
    case TerminationType::kMaxIterations:
      return "MAX_ITERATIONS";
    case TerminationType::kMaxEvaluations:
      return "MAX_EVALUATIONS";
    case TerminationType::kNoFeasiblePoint:
      return "NO_FEASIBLE_POINT";
    case TerminationType::kInvalidOptions:
      return "INVALID_OPTIONS";
  }
  return "UNKNOWN";
}

bool OptimizerSummary::IsUsable() const { return x.size() > 0 && std::isfinite(f); }

std::string OptimizerSummary::BriefReport() const {
  std::ostringstream os;
  os.precision(10);
  os << ToString(termination) << ": ";
  if (IsUsable()) {
    os << "f = " << f << " at x = [";
    for (Eigen::Index i = 0; i < x.size(); ++i) os << (i > 0 ? ", " : "") << x[i];
    os << "]";
  } else {
    os << "no feasible point";
  }
  os << ", " << iterations << " iterations, " << evaluations << " evaluations (" << rejected_evaluations
     << " rejected), " << starts << (starts == 1 ? " start" : " starts");
  if (!message.empty()) os << ". " << message;
  return os.str();
}

namespace internal {

bool StartSummary(const ObjectiveFunction& f, const Bounds& bounds, OptimizerSummary* summary) {
  *summary = OptimizerSummary();
  std::string error;
  if (!f) {
    FailInvalid("objective function is empty", summary);
    return false;
  }
  if (!bounds.IsValid(&error)) {
    FailInvalid(error, summary);
    return false;
  }
  return true;
}

void FailInvalid(const std::string& error, OptimizerSummary* summary) {
  summary->termination = TerminationType::kInvalidOptions;
  summary->message = error;
}

void Finish(TerminationType type, const std::string& message, OptimizerSummary* summary) {
  if (!summary->IsUsable()) {
    summary->termination = TerminationType::kNoFeasiblePoint;
    summary->message = "every evaluated point was rejected (" + message + ")";
    return;
  }
  summary->termination = type;
  summary->message = message;
}

}  // namespace internal
void RunParallel(const ParallelFor& parallel_for, int count, const std::function<void(int index)>& body) {
  if (count <= 0) return;
  if (parallel_for) {
    parallel_for(count, body);
    return;
  }
  for (int i = 0; i < count; ++i) body(i);
}

}  // namespace pidlab::optim
