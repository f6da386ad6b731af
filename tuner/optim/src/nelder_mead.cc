#include "pidlab/optim/nelder_mead.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>
#include <sstream>
#include <vector>

#include "internal.h"

namespace pidlab::optim {
namespace {

struct Coefficients {
  double reflection;   // rho
  double expansion;    // chi
  double contraction;  // gamma
  double shrink;       // sigma
};

Coefficients CoefficientsFor(int n, bool adaptive) {
  if (!adaptive || n < 2) return {1.0, 2.0, 0.5, 0.5};
  const double dn = n;
  return {1.0, 1.0 + 2.0 / dn, 0.75 - 1.0 / (2.0 * dn), 1.0 - 1.0 / dn};
}

struct Simplex {
  std::vector<Eigen::VectorXd> x;  // n + 1 vertices
  std::vector<double> f;

  // Stable: among equal values the older order is kept.
  void Sort() {
    std::vector<std::size_t> order(x.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [this](std::size_t a, std::size_t b) { return f[a] < f[b]; });
    std::vector<Eigen::VectorXd> xs;
    std::vector<double> fs;
    for (std::size_t i : order) {
      xs.push_back(x[i]);
      fs.push_back(f[i]);
    }
    x.swap(xs);
    f.swap(fs);
  }
};

struct StartResult {
  TerminationType type;
  std::string detail;
};

// One start of the method; the evaluator carries the counters and best point.
class NelderMeadStart {
 public:
  NelderMeadStart(const NelderMeadOptions& options, Evaluator* evaluator, Rng* rng)
      : options_(options),
        evaluator_(evaluator),
        rng_(rng),
        bounds_(evaluator->bounds()),
        n_(static_cast<int>(bounds_.lower.size())),
        width_(bounds_.upper - bounds_.lower),
        c_(CoefficientsFor(n_, options.adaptive)) {}

  // x0 == nullptr: random base point. Throws EvaluationBudgetExhausted.
  StartResult Run(const Eigen::VectorXd* x0) {
    Eigen::VectorXd base = x0 != nullptr ? *x0 : rng_->PointIn(bounds_);
    double f_base = evaluator_->Evaluate(&base);
    for (int k = 0; k < options_.max_initial_redraws && !std::isfinite(f_base); ++k) {
      base = rng_->PointIn(bounds_);
      f_base = evaluator_->Evaluate(&base);
    }
    Simplex simplex;
    Build(base, f_base, &simplex);
    if (std::none_of(simplex.f.begin(), simplex.f.end(), [](double v) { return std::isfinite(v); })) {
      return {TerminationType::kNoFeasiblePoint, "every vertex of the initial simplex was rejected"};
    }

    int iterations = 0;
    int restarts = 0;
    for (;;) {
      simplex.Sort();
      double diameter = 0.0, spread = 0.0;
      if (Converged(simplex, &diameter, &spread)) {
        if (restarts < options_.restarts_on_convergence) {
          ++restarts;
          const Eigen::VectorXd best = simplex.x[0];
          Build(best, simplex.f[0], &simplex);
          continue;
        }
        std::ostringstream os;
        os << "converged after " << restarts << (restarts == 1 ? " restart" : " restarts")
           << ": relative simplex diameter " << diameter << " <= x_tolerance " << options_.x_tolerance;
        if (std::isfinite(spread)) {
          os << ", f spread " << spread << " <= f_tolerance (1 + |f|)";
        } else {
          os << " with some vertices rejected (the simplex straddles the edge of the feasible region)";
        }
        return {TerminationType::kConverged, os.str()};
      }
      if (iterations >= options_.max_iterations) {
        std::ostringstream os;
        os << "ran out of max_iterations = " << options_.max_iterations << " with relative simplex diameter "
           << diameter;
        return {TerminationType::kMaxIterations, os.str()};
      }
      Step(&simplex);
      ++iterations;
      evaluator_->EndIteration();
    }
  }

 private:
  // Simplex around `base` (already evaluated): base plus one vertex per axis.
  void Build(const Eigen::VectorXd& base, double f_base, Simplex* simplex) {
    simplex->x.assign(1, base);
    simplex->f.assign(1, f_base);
    for (int j = 0; j < n_; ++j) {
      const double h = options_.initial_step_fraction * width_[j];
      const double sign = base[j] + h <= bounds_.upper[j] ? 1.0 : -1.0;
      Eigen::VectorXd vertex = base;
      double f_vertex = Evaluator::kInfinity;
      // Tries +h, -h, +h/2, -h/2, +h/4, ... relative to the preferred sign.
      for (int k = 0; k <= options_.max_initial_redraws; ++k) {
        const double step = sign * (k % 2 == 0 ? 1.0 : -1.0) * h * std::ldexp(1.0, -(k / 2));
        Eigen::VectorXd candidate = base;
        candidate[j] = std::clamp(base[j] + step, bounds_.lower[j], bounds_.upper[j]);
        if (candidate[j] == base[j]) continue;  // Clamped back onto the base point.
        vertex = candidate;
        f_vertex = evaluator_->Evaluate(&vertex);
        if (std::isfinite(f_vertex)) break;
      }
      simplex->x.push_back(vertex);
      simplex->f.push_back(f_vertex);
    }
  }

  // Expects a sorted simplex.
  bool Converged(const Simplex& s, double* diameter, double* spread) const {
    *diameter = 0.0;
    for (int i = 1; i <= n_; ++i) {
      *diameter = std::max(*diameter, ((s.x[i] - s.x[0]).cwiseAbs().array() / width_.array()).maxCoeff());
    }
    *spread = s.f[n_] - s.f[0];
    if (*diameter > options_.x_tolerance) return false;
    if (!std::isfinite(s.f[n_])) return true;  // Straddles the feasible region's edge.
    return *spread <= options_.f_tolerance * (1.0 + std::abs(s.f[0]));
  }

  // One iteration on a sorted simplex.
  void Step(Simplex* s) {
    const Eigen::VectorXd& worst = s->x[n_];
    Eigen::VectorXd centroid = Eigen::VectorXd::Zero(n_);
    for (int i = 0; i < n_; ++i) centroid += s->x[i];
    centroid /= n_;
    const Eigen::VectorXd d = centroid - worst;

    Eigen::VectorXd xr = centroid + c_.reflection * d;
    const double fr = evaluator_->Evaluate(&xr);
    if (fr < s->f[0]) {
      Eigen::VectorXd xe = centroid + c_.reflection * c_.expansion * d;
      const double fe = evaluator_->Evaluate(&xe);
      if (fe < fr) {
        Replace(s, xe, fe);
      } else {
        Replace(s, xr, fr);
      }
    } else if (fr < s->f[n_ - 1]) {
      Replace(s, xr, fr);
    } else if (fr < s->f[n_]) {
      Eigen::VectorXd xc = centroid + c_.reflection * c_.contraction * d;
      const double fc = evaluator_->Evaluate(&xc);
      if (fc <= fr) {
        Replace(s, xc, fc);
      } else {
        Shrink(s);
      }
    } else {
      Eigen::VectorXd xc = centroid - c_.contraction * d;
      const double fc = evaluator_->Evaluate(&xc);
      if (fc < s->f[n_]) {
        Replace(s, xc, fc);
      } else {
        Shrink(s);
      }
    }
  }

  void Replace(Simplex* s, const Eigen::VectorXd& x, double f) const {
    s->x[n_] = x;
    s->f[n_] = f;
  }

  void Shrink(Simplex* s) {
    for (int i = 1; i <= n_; ++i) {
      s->x[i] = s->x[0] + c_.shrink * (s->x[i] - s->x[0]);
      s->f[i] = evaluator_->Evaluate(&s->x[i]);
    }
  }

  const NelderMeadOptions& options_;
  Evaluator* evaluator_;
  Rng* rng_;
  const Bounds& bounds_;
  const int n_;
  const Eigen::VectorXd width_;
  const Coefficients c_;
};

bool CheckX0(const NelderMeadOptions& options, const Bounds& bounds, std::string* error) {
  if (options.x0.size() == 0) return true;
  std::ostringstream os;
  if (options.x0.size() != bounds.lower.size()) {
    os << "NelderMeadOptions.x0 has size " << options.x0.size() << " but the bounds have size "
       << bounds.lower.size();
    *error = os.str();
    return false;
  }
  for (Eigen::Index j = 0; j < options.x0.size(); ++j) {
    if (!(options.x0[j] >= bounds.lower[j] && options.x0[j] <= bounds.upper[j])) {
      os << "NelderMeadOptions.x0[" << j << "] = " << options.x0[j] << " must lie in the bounds ["
         << bounds.lower[j] << ", " << bounds.upper[j] << "]";
      *error = os.str();
      return false;
    }
  }
  return true;
}

}  // namespace

bool NelderMeadOptions::IsValid(std::string* error) const {
  const char* kOwner = "NelderMeadOptions";
  for (Eigen::Index j = 0; j < x0.size(); ++j) {
    if (!std::isfinite(x0[j])) {
      const std::string field = "x0[" + std::to_string(j) + "]";
      return FieldError(kOwner, field.c_str(), x0[j], "finite", error);
    }
  }
  if (!(initial_step_fraction > 0.0 && initial_step_fraction <= 1.0)) {
    return FieldError(kOwner, "initial_step_fraction", initial_step_fraction, "in (0, 1]", error);
  }
  if (max_iterations < 1) return FieldError(kOwner, "max_iterations", max_iterations, ">= 1", error);
  if (max_evaluations < 1) return FieldError(kOwner, "max_evaluations", max_evaluations, ">= 1", error);
  if (!(x_tolerance >= 0.0 && std::isfinite(x_tolerance))) {
    return FieldError(kOwner, "x_tolerance", x_tolerance, "finite and >= 0", error);
  }
  if (!(f_tolerance >= 0.0 && std::isfinite(f_tolerance))) {
    return FieldError(kOwner, "f_tolerance", f_tolerance, "finite and >= 0", error);
  }
  if (starts < 1) return FieldError(kOwner, "starts", starts, ">= 1", error);
  if (restarts_on_convergence < 0) {
    return FieldError(kOwner, "restarts_on_convergence", restarts_on_convergence, ">= 0", error);
  }
  if (max_initial_redraws < 0) {
    return FieldError(kOwner, "max_initial_redraws", max_initial_redraws, ">= 0", error);
  }
  return true;
}

namespace {

// The random stream of start s: start 0 keeps the seed itself (one start
// draws exactly what it always did), the others a SplitMix64 of it.
std::uint64_t StartSeed(std::uint64_t seed, int s) {
  if (s == 0) return seed;
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * static_cast<std::uint64_t>(s);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Start s's fixed share of the evaluation budget.
int StartBudget(int max_evaluations, int starts, int s) {
  return max_evaluations / starts + (s < max_evaluations % starts ? 1 : 0);
}

struct StartRun {
  OptimizerSummary part;  // this start's counters, best point and trace
  StartResult result{TerminationType::kNoFeasiblePoint, "no feasible point"};
  bool out_of_budget = false;
  std::exception_ptr error;
};

}  // namespace

void NelderMead(const ObjectiveFunction& f, const Bounds& bounds, const NelderMeadOptions& options,
                OptimizerSummary* summary, const ProgressCallback& progress) {
  if (summary == nullptr) return;
  if (!internal::StartSummary(f, bounds, summary)) return;
  std::string error;
  if (!options.IsValid(&error) || !CheckX0(options, bounds, &error)) {
    internal::FailInvalid(error, summary);
    return;
  }

  const int starts = std::min(options.starts, options.max_evaluations);
  std::vector<StartRun> runs(static_cast<std::size_t>(starts));
  RunParallel(options.parallel_for, starts, [&](int s) {
    StartRun& run = runs[static_cast<std::size_t>(s)];
    const ProgressCallback no_progress;  // the merge below reports progress
    Evaluator evaluator(f, bounds, StartBudget(options.max_evaluations, starts, s), no_progress, &run.part);
    Rng rng(StartSeed(options.seed, s));
    NelderMeadStart start(options, &evaluator, &rng);
    try {
      const bool use_x0 = s == 0 && options.x0.size() > 0;
      run.result = start.Run(use_x0 ? &options.x0 : nullptr);
    } catch (const EvaluationBudgetExhausted&) {
      run.out_of_budget = true;
    } catch (...) {
      run.error = std::current_exception();
    }
  });
  for (const StartRun& run : runs)
    if (run.error) std::rethrow_exception(run.error);

  // Merge in start order.
  int best_start = 0;
  summary->starts = starts;
  for (int s = 0; s < starts; ++s) {
    const OptimizerSummary& part = runs[static_cast<std::size_t>(s)].part;
    for (const TracePoint& point : part.trace) {
      TracePoint merged = point;
      merged.iteration = ++summary->iterations;
      merged.evaluations = summary->evaluations + point.evaluations;
      if (!(point.best_f < summary->f)) {  // the earlier starts' best stands
        merged.best_f = summary->f;
        merged.best_x = summary->x;
      }
      summary->trace.push_back(merged);
      if (progress) progress(summary->trace.back());
    }
    summary->evaluations += part.evaluations;
    summary->rejected_evaluations += part.rejected_evaluations;
    if (part.f < summary->f) {
      summary->f = part.f;
      summary->x = part.x;
      best_start = s + 1;
    }
  }
  std::ostringstream os;
  if (best_start == 0) {
    os << "the initial simplex of each of the " << starts << " starts had no feasible vertex";
    internal::Finish(TerminationType::kNoFeasiblePoint, os.str(), summary);
    return;
  }
  const StartRun& best = runs[static_cast<std::size_t>(best_start - 1)];
  os << "best of " << starts << (starts == 1 ? " start" : " starts") << " from start " << best_start
     << ", which ";
  if (best.out_of_budget) {
    os << "used up its share of max_evaluations = " << options.max_evaluations << " ("
       << StartBudget(options.max_evaluations, starts, best_start - 1) << " of them)";
    internal::Finish(TerminationType::kMaxEvaluations, os.str(), summary);
    return;
  }
  os << best.result.detail;
  internal::Finish(best.result.type, os.str(), summary);
}

}  // namespace pidlab::optim
