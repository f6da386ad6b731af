#include "pidlab/optim/paper_nelder_mead.h"

#include <algorithm>
#include <array>
#include <sstream>

#include "internal.h"

namespace pidlab::optim {
namespace {

struct Point {
  Eigen::VectorXd x;
  double f;
};

// B, G, W in slots 0, 1, 2.
using Triangle = std::array<Point, 3>;

void SortTriangle(Triangle* t) {
  std::stable_sort(t->begin(), t->end(), [](const Point& a, const Point& b) { return a.f < b.f; });
}

Point Evaluated(Eigen::VectorXd x, Evaluator* evaluator) {
  const double f = evaluator->Evaluate(&x);
  return {std::move(x), f};
}

// One iteration of Figure 6 on a sorted triangle.
void Iterate(Triangle* t, Evaluator* evaluator) {
  Point& b = (*t)[0];
  Point& g = (*t)[1];
  Point& w = (*t)[2];
  const Eigen::VectorXd m = (b.x + g.x) / 2.0;
  const Point e = Evaluated(3.0 * m - 2.0 * w.x, evaluator);  // Projected onto the box.
  if (e.f < g.f) {
    w = e;
    return;
  }
  const Point r = Evaluated((m + e.x) / 2.0, evaluator);
  if (r.f < w.f) w = r;
  if (!(r.f >= g.f)) return;
  const Eigen::VectorXd c1_x = (w.x + m) / 2.0;
  const Eigen::VectorXd c2_x = (r.x + m) / 2.0;
  const Point c1 = Evaluated(c1_x, evaluator);
  const Point c = c1_x == c2_x ? c1 : [&] {
    Point c2 = Evaluated(c2_x, evaluator);
    return c1.f <= c2.f ? c1 : c2;
  }();
  if (c.f < w.f) {
    w = c;
    return;
  }
  const Eigen::VectorXd s_x = (b.x + w.x) / 2.0;
  g = Evaluated(m, evaluator);
  w = Evaluated(s_x, evaluator);
}

}  // namespace

bool PaperNelderMeadOptions::IsValid(std::string* error) const {
  const char* kOwner = "PaperNelderMeadOptions";
  if (max_iterations < 1) return FieldError(kOwner, "max_iterations", max_iterations, ">= 1", error);
  if (max_evaluations < 1) return FieldError(kOwner, "max_evaluations", max_evaluations, ">= 1", error);
  if (starts < 1) return FieldError(kOwner, "starts", starts, ">= 1", error);
  return true;
}

void PaperNelderMead(const ObjectiveFunction& f, const Bounds& bounds, const PaperNelderMeadOptions& options,
                     OptimizerSummary* summary, const ProgressCallback& progress) {
  if (summary == nullptr) return;
  if (!internal::StartRun(f, bounds, options, summary)) return;

  Evaluator evaluator(f, bounds, options.max_evaluations, progress, summary);
  Rng rng(options.seed);
  summary->starts = 0;
  try {
    for (int s = 0; s < options.starts; ++s) {
      summary->starts = s + 1;
      Triangle triangle;
      for (Point& p : triangle) p = Evaluated(rng.PointIn(bounds), &evaluator);
      SortTriangle(&triangle);
      for (int i = 0; i < options.max_iterations; ++i) {
        Iterate(&triangle, &evaluator);
        SortTriangle(&triangle);
        evaluator.EndIteration();
      }
    }
  } catch (const EvaluationBudgetExhausted&) {
    std::ostringstream os;
    os << "max_evaluations = " << options.max_evaluations << " reached during start " << summary->starts
       << " of " << options.starts;
    internal::Finish(TerminationType::kMaxEvaluations, os.str(), summary);
    return;
  }
  std::ostringstream os;
  os << "ran the paper's fixed " << options.max_iterations << " iterations in each of " << options.starts
     << (options.starts == 1 ? " start" : " starts") << " (the method has no convergence test)";
  internal::Finish(TerminationType::kMaxIterations, os.str(), summary);
}

}  // namespace pidlab::optim
