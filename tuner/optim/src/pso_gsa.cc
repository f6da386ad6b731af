#include "pidlab/optim/pso_gsa.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "internal.h"

namespace pidlab::optim {
namespace {

// The swarm in coordinates normalised to the unit box.
struct Swarm {
  std::vector<Eigen::VectorXd> z;  // positions in [0, 1]^n
  std::vector<Eigen::VectorXd> v;  // velocities
  std::vector<double> f;
};

class SwarmEvaluator {
 public:
  SwarmEvaluator(const Bounds& bounds, Evaluator* evaluator)
      : lower_(bounds.lower), width_(bounds.upper - bounds.lower), evaluator_(evaluator) {}

  double Evaluate(const Eigen::VectorXd& z) {
    Eigen::VectorXd x = Denormalised(z);
    return evaluator_->Evaluate(&x);
  }
  /// Evaluates the swarm's positions in order (at the same time with a
  /// ParallelFor: Evaluator::Prefetch).
  void EvaluateAll(const std::vector<Eigen::VectorXd>& z, std::vector<double>* f,
                   const ParallelFor& parallel_for) {
    std::vector<Eigen::VectorXd> points;
    for (const Eigen::VectorXd& zi : z) points.push_back(Denormalised(zi));
    evaluator_->Prefetch(points, parallel_for);
    f->resize(z.size());
    for (std::size_t i = 0; i < z.size(); ++i) (*f)[i] = Evaluate(z[i]);
  }
  Eigen::VectorXd Denormalised(const Eigen::VectorXd& z) const { return lower_ + z.cwiseProduct(width_); }
  Eigen::VectorXd Normalised(const Eigen::VectorXd& x) const {
    return ((x - lower_).array() / width_.array()).matrix();
  }

 private:
  const Eigen::VectorXd lower_;
  const Eigen::VectorXd width_;
  Evaluator* evaluator_;
};

Eigen::VectorXd UniformUnit(Eigen::Index n, Rng* rng) {
  Eigen::VectorXd z(n);
  for (Eigen::Index d = 0; d < n; ++d) z[d] = rng->Uniform();
  return z;
}

// GSA masses M_i (sum 1 over feasible agents; 0 for rejected ones).
std::vector<double> Masses(const std::vector<double>& f) {
  double best = Evaluator::kInfinity, worst = -Evaluator::kInfinity;
  for (double v : f) {
    if (!std::isfinite(v)) continue;
    best = std::min(best, v);
    worst = std::max(worst, v);
  }
  std::vector<double> m(f.size(), 0.0);
  double sum = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (!std::isfinite(f[i])) continue;
    m[i] = best == worst ? 1.0 : (f[i] - worst) / (best - worst);
    sum += m[i];
  }
  if (sum > 0.0) {
    for (double& mi : m) mi /= sum;
  }
  return m;
}

}  // namespace

bool PsoGsaOptions::IsValid(std::string* error) const {
  const char* kOwner = "PsoGsaOptions";
  auto finite_at_least_zero = [](double v) { return v >= 0.0 && std::isfinite(v); };
  auto in_unit = [](double v) { return v >= 0.0 && v <= 1.0; };
  if (population_size < 2) return FieldError(kOwner, "population_size", population_size, ">= 2", error);
  if (max_iterations < 1) return FieldError(kOwner, "max_iterations", max_iterations, ">= 1", error);
  if (max_evaluations < 1) return FieldError(kOwner, "max_evaluations", max_evaluations, ">= 1", error);
  if (!(g0 > 0.0 && std::isfinite(g0))) return FieldError(kOwner, "g0", g0, "finite and > 0", error);
  if (!finite_at_least_zero(alpha)) return FieldError(kOwner, "alpha", alpha, "finite and >= 0", error);
  if (!finite_at_least_zero(c1)) return FieldError(kOwner, "c1", c1, "finite and >= 0", error);
  if (!finite_at_least_zero(c2)) return FieldError(kOwner, "c2", c2, "finite and >= 0", error);
  if (!in_unit(inertia_start)) return FieldError(kOwner, "inertia_start", inertia_start, "in [0, 1]", error);
  if (!in_unit(inertia_end)) return FieldError(kOwner, "inertia_end", inertia_end, "in [0, 1]", error);
  if (!(max_velocity_fraction > 0.0 && max_velocity_fraction <= 1.0)) {
    return FieldError(kOwner, "max_velocity_fraction", max_velocity_fraction, "in (0, 1]", error);
  }
  if (!(epsilon > 0.0 && std::isfinite(epsilon))) {
    return FieldError(kOwner, "epsilon", epsilon, "finite and > 0", error);
  }
  return true;
}

void PsoGsa(const ObjectiveFunction& f, const Bounds& bounds, const PsoGsaOptions& options,
            OptimizerSummary* summary, const ProgressCallback& progress) {
  if (summary == nullptr) return;
  if (!internal::StartRun(f, bounds, options, summary)) return;

  Evaluator evaluator(f, bounds, options.max_evaluations, progress, summary);
  SwarmEvaluator swarm_evaluator(bounds, &evaluator);
  Rng rng(options.seed);
  const Eigen::Index n = bounds.lower.size();
  const std::size_t agents = static_cast<std::size_t>(options.population_size);
  const double v_max = options.max_velocity_fraction;
  const double iterations = options.max_iterations;
  int t = 0;
  try {
    Swarm swarm;
    // The positions of an iteration are all drawn first, then evaluated
    // together (no draw depends on a new value): the draws and the result
    // are those of evaluating one by one.
    for (std::size_t i = 0; i < agents; ++i) {
      swarm.z.push_back(UniformUnit(n, &rng));
      swarm.v.push_back(Eigen::VectorXd::Zero(n));
    }
    swarm_evaluator.EvaluateAll(swarm.z, &swarm.f, options.parallel_for);
    for (t = 1; t <= options.max_iterations; ++t) {
      if (!evaluator.HasFeasiblePoint()) {
        for (std::size_t i = 0; i < agents; ++i) {
          swarm.z[i] = UniformUnit(n, &rng);
          swarm.v[i].setZero();
        }
        swarm_evaluator.EvaluateAll(swarm.z, &swarm.f, options.parallel_for);
        evaluator.EndIteration();
        continue;
      }
      const Eigen::VectorXd g_best = swarm_evaluator.Normalised(summary->x);
      const std::vector<double> mass = Masses(swarm.f);
      const double gravity = options.g0 * std::exp(-options.alpha * t / iterations);
      const double w_linear = options.max_iterations == 1
                                  ? options.inertia_start
                                  : options.inertia_start + (options.inertia_end - options.inertia_start) *
                                                                (t - 1) / (iterations - 1);

      std::vector<Eigen::VectorXd> acceleration(agents, Eigen::VectorXd::Zero(n));
      for (std::size_t i = 0; i < agents; ++i) {
        for (std::size_t j = 0; j < agents; ++j) {
          if (j == i) continue;
          const Eigen::VectorXd delta = swarm.z[j] - swarm.z[i];
          acceleration[i] += rng.Uniform() * gravity * mass[j] / (delta.norm() + options.epsilon) * delta;
        }
      }
      for (std::size_t i = 0; i < agents; ++i) {
        for (Eigen::Index d = 0; d < n; ++d) {
          const double w = options.inertia == PsoGsaInertia::kRandom ? rng.Uniform() : w_linear;
          const double r1 = rng.Uniform();
          const double r2 = rng.Uniform();
          double& v = swarm.v[i][d];
          v = w * v + options.c1 * r1 * acceleration[i][d] + options.c2 * r2 * (g_best[d] - swarm.z[i][d]);
          v = std::clamp(v, -v_max, v_max);
          double& z = swarm.z[i][d];
          z += v;
          if (z < 0.0 || z > 1.0) {
            z = std::clamp(z, 0.0, 1.0);
            v = 0.0;
          }
        }
      }
      swarm_evaluator.EvaluateAll(swarm.z, &swarm.f, options.parallel_for);
      evaluator.EndIteration();
    }
  } catch (const EvaluationBudgetExhausted&) {
    std::ostringstream os;
    os << "max_evaluations = " << options.max_evaluations << " reached in iteration " << t
       << (t == 0 ? " (the initial swarm)" : "");
    internal::Finish(TerminationType::kMaxEvaluations, os.str(), summary);
    return;
  }
  std::ostringstream os;
  os << "ran max_iterations = " << options.max_iterations << " iterations of " << options.population_size
     << " agents";
  internal::Finish(TerminationType::kMaxIterations, os.str(), summary);
}

}  // namespace pidlab::optim
