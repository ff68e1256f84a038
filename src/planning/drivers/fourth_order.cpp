#include "planning/drivers/fourth_order.hpp"

#include <algorithm>

#include "attitude_planner/dynamics/simulation.hpp"
#include "planning/problem/verdict.hpp"

namespace attitude_planner {

namespace {

/// The figures of a fourth_order plan (result->maneuver, N + 1 nodes at problem.duration): the
/// scheme's effort quadrature, the replay (cubic hold, RKMK4) and the node constraint figures.
void measureFourthOrderPlan(const PlanningProblem& problem, PlanResult* result) {
  const int N = problem.steps;
  const Maneuver& m = result->maneuver;
  result->cost = schemeCost(SchemeKind::FourthOrder, m.torque);
  result->effort = problem.duration / N * result->cost;
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = m.torque;
  input.effects = problem.effects.get();
  setReplayMiss(problem,
                replayPlan(SchemeKind::FourthOrder, problem.inertia, problem.duration / N, input),
                result);
  // The combination is not re-solved under the constraints: its node figures are measured.
  if (problem.hasNodeConstraints()) recordConstraintFigures(problem, result);
}

}  // namespace

PlanResult richardsonCombination(const PlanningProblem& problem, const PlanResult& coarse,
                                 const PlanResult& fine) {
  const int N = problem.steps;
  PlanResult result;
  result.termination = Termination::Converged;
  result.solver = fine.solver;
  result.scheme = SchemeKind::FourthOrder;
  result.levels = coarse.levels;
  result.levels.insert(result.levels.end(), fine.levels.begin(), fine.levels.end());
  result.iterations = coarse.iterations + fine.iterations;
  result.max_residual = std::max(coarse.max_residual, fine.max_residual);
  result.newton_decrement = std::max(coarse.newton_decrement, fine.newton_decrement);
  result.step_residual = std::max(coarse.step_residual, fine.step_residual);
  result.dynamics_residual = std::max(coarse.dynamics_residual, fine.dynamics_residual);
  result.history = coarse.history;
  result.history.insert(result.history.end(), fine.history.begin(), fine.history.end());
  result.extremal = fine.extremal;
  result.extremal_summary = fine.extremal_summary;
  result.duration = problem.duration;

  Maneuver& m = result.maneuver;
  m = coarse.maneuver;
  const Maneuver& f = fine.maneuver;
  for (int k = 0; k <= N; ++k) {
    const Matrix3& R_fine = f.attitude[2 * k];
    const Vector3 d = so3::log(Matrix3(m.attitude[k].transpose() * R_fine));
    m.attitude[k] = R_fine * so3::exp(Vector3(d / 3.0));
    m.angular_velocity[k] =
        f.angular_velocity[2 * k] + (f.angular_velocity[2 * k] - m.angular_velocity[k]) / 3.0;
    m.torque[k] = f.torque[2 * k] + (f.torque[2 * k] - m.torque[k]) / 3.0;
  }
  m.attitude.front() = problem.initial_attitude;  // the boundary data exactly
  m.attitude.back() = problem.final_attitude;
  // The switching function (per-axis torque bounds) is a node quantity like τ_k: combined alike.
  if (coarse.switching_function.size() == static_cast<size_t>(N + 1) &&
      fine.switching_function.size() == static_cast<size_t>(2 * N + 1)) {
    result.switching_function.resize(N + 1);
    for (int k = 0; k <= N; ++k) {
      const Vector3& s_fine = fine.switching_function[2 * k];
      result.switching_function[k] = s_fine + (s_fine - coarse.switching_function[k]) / 3.0;
    }
  }

  result.effects = fine.effects;
  measureFourthOrderPlan(problem, &result);
  return result;
}

PlanResult richardsonCombinationWithinTheBounds(const PlanningProblem& problem,
                                                const PlanResult& coarse, const PlanResult& fine,
                                                bool* replaced) {
  PlanResult result = richardsonCombination(problem, coarse, fine);
  if (replaced) *replaced = false;
  if (!problem.hasNodeConstraints() || checkConstraints(problem, result.maneuver).withinBounds()) {
    return result;
  }
  result.maneuver = coarse.maneuver;
  result.switching_function = coarse.switching_function;
  measureFourthOrderPlan(problem, &result);
  if (replaced) *replaced = true;
  return result;
}

}  // namespace attitude_planner
