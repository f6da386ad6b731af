#pragma once
// Real-coded genetic algorithm in a box, the GA baseline of the paper's
// comparison (its reference [12]).
//
// Generation 0: population_size points uniform in the box. Each generation
// then keeps the elite_count best individuals unchanged (not re-evaluated) and
// fills the rest of the population with children:
//   * two parents, each the best of tournament_size individuals drawn uniformly
//     with replacement (a rejected individual, f = +inf, loses to every
//     feasible one; ties go to the first drawn);
//   * with probability crossover_probability, crossover of the pair:
//       kSbx: simulated binary crossover (Deb & Agrawal 1995), bounded form of
//             Deb's NSGA-II code, distribution index sbx_eta, each gene crossed
//             with probability 1/2 and the two children swapped with
//             probability 1/2;
//       kBlxAlpha: each child gene uniform in [min - a d, max + a d], d = |p1 - p2|,
//             a = blx_alpha;
//     otherwise the children are copies of the parents;
//   * polynomial mutation (Deb's bounded form), distribution index mutation_eta,
//     each gene with probability mutation_probability (default 1/n);
//   * children are clamped to the box.
// One evaluation per child: population_size + max_generations *
// (population_size - elite_count) evaluations in all, unless max_evaluations
// stops the run first.
//
// The best feasible point ever evaluated is returned. Termination is
// kMaxIterations after max_generations generations (a GA has no convergence
// test here), kMaxEvaluations when the evaluation budget stopped it,
// kNoFeasiblePoint if nothing feasible was evaluated. One trace point per
// generation after generation 0.

#include <cstdint>
#include <optional>
#include <string>

#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {

enum class GaCrossover { kSbx, kBlxAlpha };

struct GeneticAlgorithmOptions {
  /// Individuals per generation, >= 2 and > elite_count.
  int population_size = 40;
  /// Generations after the initial population, >= 1.
  int max_generations = 100;
  /// Hard cap on objective calls, >= 1.
  int max_evaluations = 5000;
  /// Individuals per selection tournament, >= 1 (1 = uniform random selection).
  int tournament_size = 3;
  GaCrossover crossover = GaCrossover::kSbx;
  /// Probability that a parent pair is crossed, in [0, 1].
  double crossover_probability = 0.9;
  /// SBX distribution index, finite, >= 0 (larger = children closer to the parents).
  double sbx_eta = 15.0;
  /// BLX-alpha extension of the parents' interval, finite, >= 0.
  double blx_alpha = 0.5;
  /// Per-gene mutation probability in [0, 1]; unset = 1/n.
  std::optional<double> mutation_probability;
  /// Polynomial mutation distribution index, finite, >= 0.
  double mutation_eta = 20.0;
  /// Best individuals copied unchanged into the next generation, >= 0, < population_size.
  int elite_count = 2;
  /// Seed of the random stream.
  std::uint64_t seed = 1;
  /// Evaluates each generation's new points together (e.g. one per LCM
  /// trio); empty: one after the other. Never changes the result.
  ParallelFor parallel_for;

  /// Checks every field; on failure names the field, its value and the rule.
  bool IsValid(std::string* error) const;
};

/// Minimises f over `bounds`. Never throws (exceptions from f propagate).
void GeneticAlgorithm(const ObjectiveFunction& f, const Bounds& bounds,
                      const GeneticAlgorithmOptions& options, OptimizerSummary* summary,
                      const ProgressCallback& progress = nullptr);

}  // namespace pidlab::optim
