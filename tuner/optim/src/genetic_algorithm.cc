#include "pidlab/optim/genetic_algorithm.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <vector>

#include "internal.h"

namespace pidlab::optim {
namespace {

struct Individual {
  Eigen::VectorXd x;
  double f;
};

class Breeder {
 public:
  Breeder(const GeneticAlgorithmOptions& options, const Bounds& bounds, Rng* rng)
      : options_(options),
        bounds_(bounds),
        rng_(rng),
        mutation_probability_(options.mutation_probability.value_or(1.0 / bounds.lower.size())) {}

  // Best of tournament_size individuals drawn with replacement; the first drawn wins ties.
  const Individual& Select(const std::vector<Individual>& population) {
    const Individual* winner = &population[rng_->Index(static_cast<int>(population.size()))];
    for (int k = 1; k < options_.tournament_size; ++k) {
      const Individual& rival = population[rng_->Index(static_cast<int>(population.size()))];
      if (rival.f < winner->f) winner = &rival;
    }
    return *winner;
  }

  // Two children of two parents: crossover (maybe), mutation, clamping.
  void Breed(const Eigen::VectorXd& p1, const Eigen::VectorXd& p2, Eigen::VectorXd* c1, Eigen::VectorXd* c2) {
    *c1 = p1;
    *c2 = p2;
    if (rng_->Uniform() < options_.crossover_probability) {
      if (options_.crossover == GaCrossover::kSbx) {
        Sbx(p1, p2, c1, c2);
      } else {
        Blx(p1, p2, c1, c2);
      }
    }
    Mutate(c1);
    Mutate(c2);
  }

 private:
  // Bounded SBX as in Deb's NSGA-II reference code (realcross).
  void Sbx(const Eigen::VectorXd& p1, const Eigen::VectorXd& p2, Eigen::VectorXd* c1, Eigen::VectorXd* c2) {
    const double eta = options_.sbx_eta;
    for (Eigen::Index j = 0; j < p1.size(); ++j) {
      if (rng_->Uniform() > 0.5) continue;
      if (std::abs(p1[j] - p2[j]) <= 1e-14 * (bounds_.upper[j] - bounds_.lower[j])) continue;
      const double y1 = std::min(p1[j], p2[j]);
      const double y2 = std::max(p1[j], p2[j]);
      const double lo = bounds_.lower[j];
      const double hi = bounds_.upper[j];
      const double u = rng_->Uniform();
      auto spread = [eta, u](double beta) {
        const double alpha = 2.0 - std::pow(beta, -(eta + 1.0));
        return u <= 1.0 / alpha ? std::pow(u * alpha, 1.0 / (eta + 1.0))
                                : std::pow(1.0 / (2.0 - u * alpha), 1.0 / (eta + 1.0));
      };
      const double beta_q1 = spread(1.0 + 2.0 * (y1 - lo) / (y2 - y1));
      const double beta_q2 = spread(1.0 + 2.0 * (hi - y2) / (y2 - y1));
      const double a = std::clamp(0.5 * ((y1 + y2) - beta_q1 * (y2 - y1)), lo, hi);
      const double b = std::clamp(0.5 * ((y1 + y2) + beta_q2 * (y2 - y1)), lo, hi);
      const bool swap = rng_->Uniform() <= 0.5;
      (*c1)[j] = swap ? b : a;
      (*c2)[j] = swap ? a : b;
    }
  }

  void Blx(const Eigen::VectorXd& p1, const Eigen::VectorXd& p2, Eigen::VectorXd* c1, Eigen::VectorXd* c2) {
    for (Eigen::Index j = 0; j < p1.size(); ++j) {
      const double d = std::abs(p1[j] - p2[j]);
      const double lo = std::min(p1[j], p2[j]) - options_.blx_alpha * d;
      const double hi = std::max(p1[j], p2[j]) + options_.blx_alpha * d;
      (*c1)[j] = std::clamp(rng_->Uniform(lo, hi), bounds_.lower[j], bounds_.upper[j]);
      (*c2)[j] = std::clamp(rng_->Uniform(lo, hi), bounds_.lower[j], bounds_.upper[j]);
    }
  }

  // Bounded polynomial mutation as in Deb's NSGA-II reference code (realmutate).
  void Mutate(Eigen::VectorXd* x) {
    const double eta = options_.mutation_eta;
    for (Eigen::Index j = 0; j < x->size(); ++j) {
      if (!(rng_->Uniform() < mutation_probability_)) continue;
      const double lo = bounds_.lower[j];
      const double hi = bounds_.upper[j];
      const double y = (*x)[j];
      const double u = rng_->Uniform();
      const double power = 1.0 / (eta + 1.0);
      double delta_q;
      if (u <= 0.5) {
        const double xy = 1.0 - (y - lo) / (hi - lo);
        const double val = 2.0 * u + (1.0 - 2.0 * u) * std::pow(xy, eta + 1.0);
        delta_q = std::pow(val, power) - 1.0;
      } else {
        const double xy = 1.0 - (hi - y) / (hi - lo);
        const double val = 2.0 * (1.0 - u) + 2.0 * (u - 0.5) * std::pow(xy, eta + 1.0);
        delta_q = 1.0 - std::pow(val, power);
      }
      (*x)[j] = std::clamp(y + delta_q * (hi - lo), lo, hi);
    }
  }

  const GeneticAlgorithmOptions& options_;
  const Bounds& bounds_;
  Rng* rng_;
  const double mutation_probability_;
};

bool InUnitInterval(double p) { return p >= 0.0 && p <= 1.0; }
bool FiniteNonNegative(double v) { return v >= 0.0 && std::isfinite(v); }

}  // namespace

bool GeneticAlgorithmOptions::IsValid(std::string* error) const {
  const char* kOwner = "GeneticAlgorithmOptions";
  if (population_size < 2) return FieldError(kOwner, "population_size", population_size, ">= 2", error);
  if (max_generations < 1) return FieldError(kOwner, "max_generations", max_generations, ">= 1", error);
  if (max_evaluations < 1) return FieldError(kOwner, "max_evaluations", max_evaluations, ">= 1", error);
  if (tournament_size < 1) return FieldError(kOwner, "tournament_size", tournament_size, ">= 1", error);
  if (!InUnitInterval(crossover_probability)) {
    return FieldError(kOwner, "crossover_probability", crossover_probability, "in [0, 1]", error);
  }
  if (!FiniteNonNegative(sbx_eta)) return FieldError(kOwner, "sbx_eta", sbx_eta, "finite and >= 0", error);
  if (!FiniteNonNegative(blx_alpha)) {
    return FieldError(kOwner, "blx_alpha", blx_alpha, "finite and >= 0", error);
  }
  if (mutation_probability && !InUnitInterval(*mutation_probability)) {
    return FieldError(kOwner, "mutation_probability", *mutation_probability, "in [0, 1]", error);
  }
  if (!FiniteNonNegative(mutation_eta)) {
    return FieldError(kOwner, "mutation_eta", mutation_eta, "finite and >= 0", error);
  }
  if (elite_count < 0 || elite_count >= population_size) {
    return FieldError(kOwner, "elite_count", elite_count, ">= 0 and < population_size", error);
  }
  return true;
}

void GeneticAlgorithm(const ObjectiveFunction& f, const Bounds& bounds,
                      const GeneticAlgorithmOptions& options, OptimizerSummary* summary,
                      const ProgressCallback& progress) {
  if (summary == nullptr) return;
  if (!internal::StartRun(f, bounds, options, summary)) return;

  Evaluator evaluator(f, bounds, options.max_evaluations, progress, summary);
  Rng rng(options.seed);
  Breeder breeder(options, bounds, &rng);
  const std::size_t size = static_cast<std::size_t>(options.population_size);
  const std::size_t elites = static_cast<std::size_t>(options.elite_count);
  int generation = 0;
  try {
    // Each generation's points are drawn first and evaluated together
    // (Prefetch: at the same time on several trios); drawing never depends
    // on the new values, so the draws and the result are those of
    // evaluating one by one.
    std::vector<Eigen::VectorXd> points;
    for (std::size_t i = 0; i < size; ++i) points.push_back(rng.PointIn(bounds));
    evaluator.Prefetch(points, options.parallel_for);
    std::vector<Individual> population;
    for (Eigen::VectorXd& x : points) {
      const double fx = evaluator.Evaluate(&x);
      population.push_back({std::move(x), fx});
    }
    for (generation = 1; generation <= options.max_generations; ++generation) {
      std::stable_sort(population.begin(), population.end(),
                       [](const Individual& a, const Individual& b) { return a.f < b.f; });
      std::vector<Individual> next(population.begin(),
                                   population.begin() + static_cast<std::ptrdiff_t>(elites));
      std::vector<Eigen::VectorXd> offspring;
      while (next.size() + offspring.size() < size) {
        const Eigen::VectorXd& p1 = breeder.Select(population).x;
        const Eigen::VectorXd& p2 = breeder.Select(population).x;
        Eigen::VectorXd children[2];
        breeder.Breed(p1, p2, &children[0], &children[1]);
        for (Eigen::VectorXd& child : children) {
          // Odd number of places: the second child is dropped unevaluated.
          if (next.size() + offspring.size() == size) break;
          offspring.push_back(std::move(child));
        }
      }
      evaluator.Prefetch(offspring, options.parallel_for);
      for (Eigen::VectorXd& child : offspring) {
        const double fc = evaluator.Evaluate(&child);
        next.push_back({std::move(child), fc});
      }
      population.swap(next);
      evaluator.EndIteration();
    }
  } catch (const EvaluationBudgetExhausted&) {
    std::ostringstream os;
    os << "max_evaluations = " << options.max_evaluations << " reached in generation " << generation
       << (generation == 0 ? " (the initial population)" : "");
    internal::Finish(TerminationType::kMaxEvaluations, os.str(), summary);
    return;
  }
  std::ostringstream os;
  os << "ran max_generations = " << options.max_generations << " generations of " << options.population_size;
  internal::Finish(TerminationType::kMaxIterations, os.str(), summary);
}

}  // namespace pidlab::optim
