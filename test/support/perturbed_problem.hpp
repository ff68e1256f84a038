// A reduced problem away from its first guess, for the transcription's derivative tests.
#pragma once

#include <Eigen/Core>
#include <random>

#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner::test_support {

/// The problem with its free attitudes moved off the geodesic by N(0, 0.05) rotation vectors
/// (seeded), so torques and curvature are generic.
inline ReducedProblem perturbedReducedProblem(const PlanningProblem& problem, unsigned seed) {
  ReducedProblem rp(problem);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd delta(rp.unknowns());
  for (int i = 0; i < delta.size(); ++i) delta(i) = n(rng);
  rp.setCurrent(rp.retract(delta, 1.0));
  return rp;
}

}  // namespace attitude_planner::test_support
