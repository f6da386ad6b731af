#pragma once
// Implementation details shared by the optimisers; not part of the public API.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {
namespace internal {

/// Portable uniform random numbers: std::mt19937_64 is fully specified by the
/// standard, the distributions are not, so we map the raw bits ourselves.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform in [a, b) (b itself only by rounding).
  double Uniform(double a, double b) { return a + (b - a) * Uniform(); }
  /// Uniform integer in [0, n), n >= 1.
  int Index(int n) {
    const int i = static_cast<int>(Uniform() * n);
    return i < n ? i : n - 1;
  }
  /// Uniform point in the box.
  Eigen::VectorXd PointIn(const Bounds& bounds) {
    Eigen::VectorXd x(bounds.lower.size());
    for (Eigen::Index j = 0; j < x.size(); ++j) x[j] = Uniform(bounds.lower[j], bounds.upper[j]);
    return x;
  }

 private:
  std::mt19937_64 engine_;
};

/// Euclidean projection onto the box (coordinate-wise clamping).
inline Eigen::VectorXd Project(const Bounds& bounds, const Eigen::VectorXd& x) {
  return x.cwiseMax(bounds.lower).cwiseMin(bounds.upper);
}

/// Thrown by Evaluator::Evaluate instead of calling the objective once the
/// evaluation budget is spent; caught by the optimiser's driver, never escapes.
struct EvaluationBudgetExhausted {};

/// Wraps the objective: projects onto the box, enforces the evaluation budget,
/// maps non-finite values to +inf, keeps the best feasible point and the
/// counters in the summary, and records the per-iteration trace.
class Evaluator {
 public:
  Evaluator(const ObjectiveFunction& f, const Bounds& bounds, int max_evaluations,
            const ProgressCallback& progress, OptimizerSummary* summary)
      : f_(f), bounds_(bounds), max_evaluations_(max_evaluations), progress_(progress), summary_(summary) {}

  /// Projects *x onto the box in place, then evaluates it. Returns the value,
  /// +inf for a rejected point.
  double Evaluate(Eigen::VectorXd* x) {
    *x = Project(bounds_, *x);
    if (summary_->evaluations >= max_evaluations_) throw EvaluationBudgetExhausted{};
    ++summary_->evaluations;
    double value;
    if (next_ < prefetched_.size() && prefetched_[next_].first == *x) {
      value = prefetched_[next_++].second;  // computed by Prefetch, in this order
    } else {
      value = f_(*x);
    }
    if (!std::isfinite(value)) {
      ++summary_->rejected_evaluations;
      value = kInfinity;
    } else if (value < summary_->f) {
      summary_->f = value;
      summary_->x = *x;
    }
    return value;
  }

  /// With a ParallelFor: evaluates the points the optimiser is about to pass
  /// to Evaluate, in this order, all at once (as many as the budget still
  /// allows), so that those Evaluate calls only count and record. The
  /// counters, best point, trace and result are exactly those of calling
  /// Evaluate alone. Without one: nothing.
  void Prefetch(const std::vector<Eigen::VectorXd>& points, const ParallelFor& parallel_for) {
    prefetched_.clear();
    next_ = 0;
    if (!parallel_for) return;
    const std::size_t room = static_cast<std::size_t>(std::max(0, max_evaluations_ - summary_->evaluations));
    const std::size_t n = std::min(points.size(), room);
    prefetched_.resize(n);
    for (std::size_t i = 0; i < n; ++i) prefetched_[i].first = Project(bounds_, points[i]);
    RunParallel(parallel_for, static_cast<int>(n), [this](int i) {
      auto& entry = prefetched_[static_cast<std::size_t>(i)];
      entry.second = f_(entry.first);
    });
  }

  /// Counts a completed iteration, appends its trace point and reports it.
  void EndIteration() {
    ++summary_->iterations;
    TracePoint point;
    point.iteration = summary_->iterations;
    point.evaluations = summary_->evaluations;
    point.best_f = summary_->f;
    point.best_x = summary_->x;
    summary_->trace.push_back(point);
    if (progress_) progress_(summary_->trace.back());
  }

  bool HasFeasiblePoint() const { return std::isfinite(summary_->f); }
  int evaluations() const { return summary_->evaluations; }
  int max_evaluations() const { return max_evaluations_; }
  const Bounds& bounds() const { return bounds_; }

  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

 private:
  const ObjectiveFunction& f_;
  const Bounds& bounds_;
  const int max_evaluations_;
  const ProgressCallback& progress_;
  OptimizerSummary* summary_;
  std::vector<std::pair<Eigen::VectorXd, double>> prefetched_;
  std::size_t next_ = 0;
};

/// Resets *summary and checks the problem (objective and bounds). On failure
/// sets kInvalidOptions with the reason and returns false.
bool StartSummary(const ObjectiveFunction& f, const Bounds& bounds, OptimizerSummary* summary);

/// Sets kInvalidOptions with `error` as the message.
void FailInvalid(const std::string& error, OptimizerSummary* summary);

/// The start every optimiser shares: StartSummary, then options.IsValid;
/// false (with the summary failed as invalid input) if either refuses.
template <typename Options>
bool StartRun(const ObjectiveFunction& f, const Bounds& bounds, const Options& options,
              OptimizerSummary* summary) {
  if (!StartSummary(f, bounds, summary)) return false;
  std::string error;
  if (!options.IsValid(&error)) {
    FailInvalid(error, summary);
    return false;
  }
  return true;
}

/// Sets the termination and message; kNoFeasiblePoint replaces `type` (and
/// prefixes the message) when no feasible point was found.
void Finish(TerminationType type, const std::string& message, OptimizerSummary* summary);

/// Formats "Struct.field = value must be <rule>" into *error; returns false.
template <typename T>
bool FieldError(const char* owner, const char* field, const T& value, const char* rule, std::string* error) {
  if (error != nullptr) {
    std::ostringstream os;
    os << owner << '.' << field << " = " << value << " must be " << rule;
    *error = os.str();
  }
  return false;
}

}  // namespace internal

// The optimisers' own files name these without the prefix.
using internal::EvaluationBudgetExhausted;
using internal::Evaluator;
using internal::FieldError;
using internal::Rng;

}  // namespace pidlab::optim
