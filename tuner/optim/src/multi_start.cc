#include "pidlab/optim/multi_start.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>
#include <sstream>

#include "internal.h"
#include "pidlab/optim/sobol.h"

namespace pidlab::optim {
namespace {

constexpr int kMaxDesignPoints = 1 << 20;
constexpr double kMaxWarp = 40.0;

// The warp between the unit cube (u) and the box (x), coordinate by coordinate.
class Warp {
 public:
  Warp(const Bounds& bounds, double w) : bounds_(bounds), w_(w), scale_(w > 0.0 ? std::expm1(w) : 1.0) {}

  Eigen::VectorXd ToBox(const Eigen::VectorXd& u) const {
    Eigen::VectorXd x(u.size());
    for (Eigen::Index j = 0; j < u.size(); ++j) {
      const double t = w_ > 0.0 ? std::expm1(w_ * u[j]) / scale_ : u[j];
      const double width = bounds_.upper[j] - bounds_.lower[j];
      x[j] = std::clamp(bounds_.lower[j] + width * t, bounds_.lower[j], bounds_.upper[j]);
    }
    return x;
  }

 private:
  const Bounds& bounds_;
  const double w_;
  const double scale_;
};

// The first `starts` points by increasing f that lie min_separation apart.
std::vector<int> SelectStarts(const std::vector<Eigen::VectorXd>& u, const std::vector<double>& f,
                              const MultiStartOptions& options) {
  std::vector<int> order(u.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&f](int a, int b) {
    return f[static_cast<std::size_t>(a)] < f[static_cast<std::size_t>(b)];
  });
  std::vector<int> kept;
  for (int i : order) {
    if (static_cast<int>(kept.size()) >= options.starts) break;
    if (!std::isfinite(f[static_cast<std::size_t>(i)])) break;
    const bool apart = std::all_of(kept.begin(), kept.end(), [&](int k) {
      return (u[static_cast<std::size_t>(i)] - u[static_cast<std::size_t>(k)]).cwiseAbs().maxCoeff() >=
             options.min_separation;
    });
    if (apart) kept.push_back(i);
  }
  return kept;
}

struct Polish {
  OptimizerSummary part;  // in the unit cube
  bool out_of_budget = false;
  std::exception_ptr error;
};

// The Sobol design in the unit cube (u), in the box (x) and its values (f).
struct Design {
  std::vector<Eigen::VectorXd> u, x;
  std::vector<double> f;
};

// Evaluates the design all at once (one iteration of the trace).
Design EvaluateDesign(const ObjectiveFunction& f, const Bounds& bounds, const MultiStartOptions& options,
                      const Warp& warp, OptimizerSummary* summary) {
  const int n = static_cast<int>(bounds.lower.size());
  const SobolSequence sobol = options.scramble ? SobolSequence(n, options.seed) : SobolSequence(n);
  Design d;
  std::vector<Eigen::VectorXd>& u = d.u;
  std::vector<Eigen::VectorXd>& x = d.x;
  u.resize(static_cast<std::size_t>(options.design_points));
  x.resize(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = sobol.Point(static_cast<std::uint32_t>(i));
    x[i] = warp.ToBox(u[i]);
  }
  d.f.resize(u.size());
  const ProgressCallback no_progress;
  Evaluator design(f, bounds, options.design_points, no_progress, summary);
  design.Prefetch(x, options.parallel_for);
  for (std::size_t i = 0; i < u.size(); ++i) {
    Eigen::VectorXd xi = x[i];
    d.f[i] = design.Evaluate(&xi);
  }
  design.EndIteration();
  return d;
}

// Nelder-Mead from each kept design point, in the unit cube, with an equal
// share of the `rest` of the budget; rethrows the first start's exception.
std::vector<Polish> RunPolishes(const ObjectiveFunction& f, int n, const Warp& warp,
                                const MultiStartOptions& options, const std::vector<Eigen::VectorXd>& u,
                                const std::vector<int>& kept, int rest) {
  const int starts = static_cast<int>(kept.size());
  const Bounds cube{Eigen::VectorXd::Zero(n), Eigen::VectorXd::Ones(n)};
  const ObjectiveFunction g = [&f, &warp](const Eigen::VectorXd& v) { return f(warp.ToBox(v)); };
  std::vector<Polish> polishes(static_cast<std::size_t>(starts));
  RunParallel(options.parallel_for, starts, [&](int s) {
    Polish& p = polishes[static_cast<std::size_t>(s)];
    NelderMeadOptions o = options.polish;
    o.x0 = u[static_cast<std::size_t>(kept[static_cast<std::size_t>(s)])];
    o.starts = 1;
    o.seed = options.seed + static_cast<std::uint64_t>(s);  // only for redraws of a rejected x0
    o.max_evaluations = rest / starts + (s < rest % starts ? 1 : 0);
    o.parallel_for = nullptr;
    try {
      NelderMead(g, cube, o, &p.part);
      p.out_of_budget = p.part.termination == TerminationType::kMaxEvaluations;
    } catch (...) {
      p.error = std::current_exception();
    }
  });
  for (const Polish& p : polishes)
    if (p.error) std::rethrow_exception(p.error);
  return polishes;
}

// Appends the polishes' traces and counts to *summary in start order, keeps
// the best usable point, fills *minima (best first). Returns the best start
// (1-based; 0: the design).
int MergePolishes(const std::vector<Polish>& polishes, const std::vector<Eigen::VectorXd>& x,
                  const std::vector<int>& kept, const Warp& warp, const ProgressCallback& progress,
                  OptimizerSummary* summary, std::vector<LocalMinimum>* minima) {
  const int starts = static_cast<int>(polishes.size());
  int best_start = 0;  // 0: the design
  for (int s = 0; s < starts; ++s) {
    const OptimizerSummary& part = polishes[static_cast<std::size_t>(s)].part;
    for (const TracePoint& point : part.trace) {
      TracePoint merged;
      merged.iteration = ++summary->iterations;
      merged.evaluations = summary->evaluations + point.evaluations;
      if (point.best_f < summary->f) {
        merged.best_f = point.best_f;
        merged.best_x = warp.ToBox(point.best_x);
      } else {
        merged.best_f = summary->f;
        merged.best_x = summary->x;
      }
      summary->trace.push_back(merged);
      if (progress) progress(summary->trace.back());
    }
    summary->evaluations += part.evaluations;
    summary->rejected_evaluations += part.rejected_evaluations;
    if (part.IsUsable() && part.f < summary->f) {
      summary->f = part.f;
      summary->x = warp.ToBox(part.x);
      best_start = s + 1;
    }
    if (minima) {
      LocalMinimum m;
      m.start = x[static_cast<std::size_t>(kept[static_cast<std::size_t>(s)])];
      if (part.IsUsable()) m.x = warp.ToBox(part.x);
      m.f = part.f;
      m.evaluations = part.evaluations;
      m.termination = part.termination;
      minima->push_back(m);
    }
  }
  if (minima)
    std::stable_sort(minima->begin(), minima->end(),
                     [](const LocalMinimum& a, const LocalMinimum& b) { return a.f < b.f; });
  return best_start;
}

// Ends the run with the message and termination of the best start.
void FinishMultiStart(const MultiStartOptions& options, const std::vector<Polish>& polishes, int best_start,
                      OptimizerSummary* summary) {
  const int starts = static_cast<int>(polishes.size());
  std::ostringstream os;
  os << "best of " << options.design_points << " design points and " << starts
     << (starts == 1 ? " polished start" : " polished starts") << ", from ";
  if (best_start == 0) {
    os << "the design (no polish improved on it)";
    internal::Finish(TerminationType::kMaxIterations, os.str(), summary);
    return;
  }
  const OptimizerSummary& best = polishes[static_cast<std::size_t>(best_start - 1)].part;
  os << "start " << best_start << ": " << best.message;
  internal::Finish(best.termination, os.str(), summary);
}

}  // namespace

bool MultiStartOptions::IsValid(std::string* error) const {
  const char* kOwner = "MultiStartOptions";
  if (design_points < 1 || design_points > kMaxDesignPoints)
    return FieldError(kOwner, "design_points", design_points, "in [1, 2^20]", error);
  if (!(warp >= 0.0 && warp <= kMaxWarp)) return FieldError(kOwner, "warp", warp, "in [0, 40]", error);
  if (starts < 1) return FieldError(kOwner, "starts", starts, ">= 1", error);
  if (!(min_separation >= 0.0 && min_separation < 1.0))
    return FieldError(kOwner, "min_separation", min_separation, "in [0, 1)", error);
  if (max_evaluations <= design_points)
    return FieldError(kOwner, "max_evaluations", max_evaluations, "> design_points", error);
  std::string polish_error;
  if (!polish.IsValid(&polish_error)) {
    if (error) *error = "MultiStartOptions.polish: " + polish_error;
    return false;
  }
  return true;
}

void MultiStart(const ObjectiveFunction& f, const Bounds& bounds, const MultiStartOptions& options,
                OptimizerSummary* summary, const ProgressCallback& progress,
                std::vector<LocalMinimum>* minima) {
  if (minima) minima->clear();
  if (summary == nullptr) return;
  if (!internal::StartRun(f, bounds, options, summary)) return;
  const int n = static_cast<int>(bounds.lower.size());
  if (n > SobolSequence::kMaxDimensions) {
    std::ostringstream os;
    os << "MultiStart works in at most " << SobolSequence::kMaxDimensions << " dimensions, not " << n;
    internal::FailInvalid(os.str(), summary);
    return;
  }
  const Warp warp(bounds, options.warp);

  // 1. The design, evaluated all at once.
  const Design design = EvaluateDesign(f, bounds, options, warp, summary);
  if (progress) progress(summary->trace.back());

  // 2. The starts.
  const int rest = options.max_evaluations - options.design_points;
  std::vector<int> kept = SelectStarts(design.u, design.f, options);
  if (static_cast<int>(kept.size()) > rest) kept.resize(static_cast<std::size_t>(rest));  // a share each
  const int starts = static_cast<int>(kept.size());
  summary->starts = starts;
  if (starts == 0) {
    std::ostringstream os;
    os << "none of the " << options.design_points << " design points is feasible";
    internal::Finish(TerminationType::kNoFeasiblePoint, os.str(), summary);
    return;
  }

  // 3. The polishes, in the unit cube, merged in start order.
  const std::vector<Polish> polishes = RunPolishes(f, n, warp, options, design.u, kept, rest);
  const int best_start = MergePolishes(polishes, design.x, kept, warp, progress, summary, minima);
  FinishMultiStart(options, polishes, best_start, summary);
}

}  // namespace pidlab::optim
