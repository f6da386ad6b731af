#pragma once
// Hybrid particle swarm / gravitational search (PSOGSA) of Mirjalili & Hashim
// (2010), the PSO GSA baseline of the paper's comparison (its reference [11]).
//
// Agents i = 1..N with positions X_i and velocities V_i. Each iteration t = 1..T:
//   masses     m_i = (f_i - worst) / (best - worst),  M_i = m_i / sum_j m_j
//              (best, worst over the feasible agents; all m_i = 1 if best == worst;
//              a rejected agent, f = +inf, gets the worst mass, 0)
//   gravity    G(t) = g0 * exp(-alpha * t / T)
//   accel.     a_i = sum_{j != i} rand_ij * G(t) * M_j * (X_j - X_i) / (R_ij + epsilon),
//              R_ij = |X_i - X_j| (Euclidean); the passive mass M_i cancels
//              against the inertial mass as in GSA
//   velocity   V_i = w * V_i + c1 * r1 * a_i + c2 * r2 * (gBest - X_i)
//   position   X_i = X_i + V_i
// then every agent is evaluated; gBest is the best feasible point found so far.
// rand_ij is one draw per pair; w (with kRandom), r1 and r2 are drawn per agent
// and per coordinate, uniform in [0, 1).
//
// Choices the original leaves open, documented here:
//   * Coordinates are normalised to the box, X = (x - lower) / (upper - lower),
//     so G, epsilon and the velocity limit mean the same for a [0, 30]^3 gain
//     box as for the unit cube. For the unit cube this is the original.
//   * Inertia w: uniform random in [0, 1) per the authors' code (kRandom, the
//     default), or linearly decreasing from inertia_start to inertia_end
//     (kLinearDecreasing, the classic PSO schedule).
//   * Velocities start at zero; each coordinate is clamped to
//     +-max_velocity_fraction of the (normalised) box width.
//   * Positions are clamped to the box; a clamped coordinate's velocity is
//     zeroed so the agent does not keep pushing against the face.
//   * While no feasible point has been found there is no gBest and every mass
//     is zero: the agents are then re-drawn uniformly each iteration (pure
//     random search) until one is feasible.
// Evaluations: N for the initial swarm plus N per iteration, N (T + 1) in all
// unless max_evaluations stops the run first. Termination is kMaxIterations
// after T iterations (no convergence test), kMaxEvaluations when the
// evaluation budget stopped it, kNoFeasiblePoint if nothing feasible was
// evaluated.

#include <cstdint>
#include <string>

#include "pidlab/optim/optimizer.h"

namespace pidlab::optim {

enum class PsoGsaInertia { kRandom, kLinearDecreasing };

struct PsoGsaOptions {
  /// Agents, >= 2.
  int population_size = 30;
  /// Iterations T, >= 1.
  int max_iterations = 100;
  /// Hard cap on objective calls, >= 1.
  int max_evaluations = 5000;
  /// Initial gravitational constant G0, finite, > 0 (normalised coordinates).
  double g0 = 1.0;
  /// Decay rate of G(t) = g0 exp(-alpha t / T), finite, >= 0.
  double alpha = 20.0;
  /// Weight c1' of the gravitational acceleration, finite, >= 0.
  double c1 = 0.5;
  /// Weight c2' of the attraction to gBest, finite, >= 0.
  double c2 = 1.5;
  PsoGsaInertia inertia = PsoGsaInertia::kRandom;
  /// Inertia at t = 1 and t = T for kLinearDecreasing, finite, in [0, 1].
  double inertia_start = 0.9;
  double inertia_end = 0.4;
  /// Velocity limit per coordinate as a fraction of the box width, in (0, 1].
  double max_velocity_fraction = 0.2;
  /// Softening of the distance in the force, normalised units, finite, > 0.
  double epsilon = 1e-10;
  /// Seed of the random stream.
  std::uint64_t seed = 1;
  /// Evaluates each generation's new points together (e.g. one per LCM
  /// trio); empty: one after the other. Never changes the result.
  ParallelFor parallel_for;

  /// Checks every field; on failure names the field, its value and the rule.
  bool IsValid(std::string* error) const;
};

/// Minimises f over `bounds`. Never throws (exceptions from f propagate).
void PsoGsa(const ObjectiveFunction& f, const Bounds& bounds, const PsoGsaOptions& options,
            OptimizerSummary* summary, const ProgressCallback& progress = nullptr);

}  // namespace pidlab::optim
