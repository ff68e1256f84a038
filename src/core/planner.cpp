#include "attitude_planner/planner.hpp"

#include <chrono>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/simulation.hpp"
#include "attitude_planner/solvers.hpp"

namespace attitude_planner {

void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = torque;
  input.effects = problem.effects.get();
  SimulationReport report;
  result->maneuver = simulate(scheme, input, &report);
  result->scheme = problem.scheme;
  result->effects = problem.effects ? problem.effects->names() : std::vector<std::string>{};
  result->dynamics_residual = report.max_step_residual;
  double cost = 0.0;
  for (const Vector3& t : torque) cost += 0.5 * t.squaredNorm();
  result->cost = cost;
  const int N = problem.steps;
  result->terminal_attitude_error =
      so3::angleBetween(problem.final_attitude, result->maneuver.attitude[N]);
  result->terminal_velocity_error =
      (result->maneuver.angular_velocity[N - 1] - problem.final_velocity).norm();
}

PlanResult planManeuver(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  const auto start = std::chrono::steady_clock::now();
  PlanResult result;
  if (options.solver == "newton") {
    result = solveWithNewton(problem, options);
  } else if (options.solver == "nlopt") {
    result = solveWithNlopt(problem, options);
  } else {
    throw InvalidInput("solver: unknown value '" + options.solver + "' (expected newton or nlopt)");
  }
  result.solver = options.solver;
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace attitude_planner
