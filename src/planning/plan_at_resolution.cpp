#include "attitude_planner/planning/plan_at_resolution.hpp"

#include <chrono>
#include <sstream>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "planning/solvers.hpp"

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
  if (problem.hasTorqueBounds()) {
    result->effects.push_back(effectKindName(EffectKind::ActuatorLimits));
  }
  result->dynamics_residual = report.max_step_residual;
  const int N = problem.steps;
  result->duration = problem.duration;
  result->cost = scheme.cost(torque);
  result->effort = scheme.timeStep() * result->cost;
  result->terminal_attitude_error =
      so3::angleBetween(problem.final_attitude, result->maneuver.attitude[N]);
  result->terminal_velocity_error =
      (result->maneuver.angular_velocity[N] - problem.final_velocity).norm();
}

namespace {

/// The boundary steps F_0 (from Ω_0) and F_{N−1} (from Ω_{N−1}) are fixed by the data: if either
/// has no solution at h = T/N no solver can plan, so the request is refused up front, naming the
/// velocity (StepTooLarge: "step too large, increase steps: ...").
void requireBoundarySteps(const PlanningProblem& problem) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  const std::pair<const char*, const Vector3*> ends[] = {
      {"initial.angular_velocity", &problem.initial_velocity},
      {"final.angular_velocity", &problem.final_velocity}};
  for (const auto& [field, velocity] : ends) {
    try {
      scheme.stepFromVelocity(*velocity);
    } catch (const StepTooLarge& e) {
      std::ostringstream what;
      what << field << ": " << e.what() << " (N = " << problem.steps << ", T = " << problem.duration
           << " s)";
      throw StepTooLarge(what.str());
    }
  }
}

/// The NLopt cross-check (a direct method on τ_1..τ_{N−1}) knows only the schemes without end
/// torques.
void requireSchemeSupported(const PlanningProblem& problem, const SolverOptions& options) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  if (scheme.hasEndTorques() && options.solver == SolverKind::Nlopt) {
    throw InvalidInput("scheme: '" + schemeName(problem.scheme) +
                       "' is not available with solver nlopt (use 'paper' or 'variational')");
  }
}

}  // namespace

PlanResult planAtResolution(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  validateOptions(options);
  requireSchemeSupported(problem, options);
  requireBoundarySteps(problem);
  const auto start = std::chrono::steady_clock::now();
  PlanResult result;
  if (options.solver == SolverKind::Newton && problem.hasNodeConstraints()) {
    // The unconstrained optimum first (fast path): if it meets every node constraint it is the
    // constrained optimum too; otherwise it starts the interior-point solver.
    result = solveWithNewton(problem, options);
    const ConstraintCheck unconstrained = result.maneuver.steps() == problem.steps
                                              ? checkConstraints(problem, result.maneuver)
                                              : ConstraintCheck{};
    if (!result.converged() || unconstrained.max_node_bound_violation > 0.0) {
      SolverOptions constrained = options;
      if (options.time_budget_s > 0) {
        const double used =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        constrained.time_budget_s = std::max(options.time_budget_s - used, 1e-300);
      }
      const int newton_iterations = result.iterations;
      std::ostringstream note;
      if (result.converged()) {
        note << "; the unconstrained optimum (cost " << result.cost << ") violates ";
        if (unconstrained.worst.empty()) {
          note << "a cone's margin";  // the stated limits hold, a tightened node bound does not
        } else {
          note << unconstrained.worst << " " << unconstrained.worst_where;
        }
        note << " and started it (" << newton_iterations << " Newton iterations)";
      }
      const Maneuver unconstrained_plan = result.maneuver;
      constrained.warm_start = result.converged() ? &unconstrained_plan : options.warm_start;
      result = solveWithInteriorPoint(problem, constrained);
      result.iterations += newton_iterations;
      result.message += note.str();
    } else {
      result.message += "; constraints inactive at the unconstrained optimum";
    }
  } else if (options.solver == SolverKind::Newton) {
    result = solveWithNewton(problem, options);
  } else {
    result = solveWithNlopt(problem, options);
  }
  if (result.solver.empty()) result.solver = solverName(options.solver);
  if (problem.hasNodeConstraints() && result.maneuver.steps() == problem.steps) {
    const ConstraintCheck check = checkConstraints(problem, result.maneuver);
    result.constraints = check.names;
    result.max_constraint_violation = check.max_violation;
    result.max_violation_between_nodes = check.max_violation_between_nodes;
    result.active_constraints = check.active;
  }
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace attitude_planner
