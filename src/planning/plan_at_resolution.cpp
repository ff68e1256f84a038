#include "attitude_planner/planning/plan_at_resolution.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "planning/solvers.hpp"

namespace attitude_planner {

double stepResidualTolerance(int steps, double step_angle) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double floor = step_angle > 0 ? 16.0 * eps * (1.0 / step_angle + steps) : 0.0;
  return kStepResidualTolerance + floor;
}

StepResidual measureStepResidual(const PlanningProblem& problem, const Maneuver& m) {
  const int N = m.steps();
  if (N < 1 || static_cast<int>(m.angular_velocity.size()) != N + 1 ||
      static_cast<int>(m.torque.size()) != N + 1) {
    throw InvalidInput("measureStepResidual: maneuver rows do not match its steps");
  }
  if (!schemeIsDiscretization(problem.scheme)) {
    throw InvalidInput("measureStepResidual: scheme '" + schemeName(problem.scheme) +
                       "' has no discrete equations (its step residual is the worst of its two "
                       "second_order solves, PlanResult::step_residual)");
  }
  const double T = problem.duration;
  const double h = m.time_step;
  const DiscreteScheme scheme(problem.scheme, problem.inertia, h);
  double max_rate = 0.0;
  for (int k = 0; k < N; ++k) max_rate = std::max(max_rate, m.angular_velocity[k].norm());
  const double W =
      max_rate + so3::angleBetween(problem.initial_attitude, problem.final_attitude) / T;
  const double P = Eigen::SelfAdjointEigenSolver<Matrix3>(problem.inertia).eigenvalues()(2) * W;
  StepResidual out;
  out.tolerance = stepResidualTolerance(N, h * W);
  // Relative to a zero scale (the zero maneuver) only an exact zero is consistent.
  const auto relative = [](double value, double scale) {
    return scale > 0 ? value / scale : (value == 0 ? 0.0 : std::numeric_limits<double>::infinity());
  };
  // The boundary velocities sit on row N − 1 (paper, variational: the last step's) or N (node
  // velocities, second_order).
  const bool nodes = scheme.hasEndTorques();
  const int last_velocity = nodes ? N : N - 1;
  double worst = std::max(so3::angleBetween(problem.initial_attitude, m.attitude[0]),
                          so3::angleBetween(problem.final_attitude, m.attitude[N]));
  worst = std::max(worst, relative((m.angular_velocity[0] - problem.initial_velocity).norm(), W));
  worst = std::max(
      worst, relative((m.angular_velocity[last_velocity] - problem.final_velocity).norm(), W));
  // a_k: what the body receives at node k (control and effects).
  std::vector<Vector3> applied(N + 1);
  for (int k = 0; k <= N; ++k) {
    applied[k] = m.torque[k];
    if (problem.effects) applied[k] += problem.effects->torque(m.attitude[k], k * h);
  }
  // c_k: the momentum step k carries, from the reported velocities (full precision): paper
  // exp(hΩ_k^) J Ω_k, variational J Ω_k; second_order Π_k + (h/2) a_k with Π_k = J Ω_k.
  std::vector<Vector3> carried(N);
  for (int k = 0; k < N; ++k) {
    carried[k] = nodes ? Vector3(problem.inertia * m.angular_velocity[k] + 0.5 * h * applied[k])
                       : scheme.momentumOfVelocity(m.angular_velocity[k]);
    const Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
    worst = std::max(worst, relative((scheme.momentumOfStep(so3::log(F)) - carried[k]).norm(), P));
  }
  // c_k = F_{k−1}ᵀ c_{k−1} + h a_k (seed 000, eq. 18; second_order: both half impulses).
  for (int k = 1; k < N; ++k) {
    const Matrix3 F_prev = m.attitude[k - 1].transpose() * m.attitude[k];
    const Vector3 r = carried[k] - F_prev.transpose() * carried[k - 1] - h * applied[k];
    worst = std::max(worst, relative(r.norm(), P));
  }
  if (nodes) {  // Π_N = F_{N−1}ᵀ c_{N−1} + (h/2) a_N
    const Matrix3 F_last = m.attitude[N - 1].transpose() * m.attitude[N];
    const Vector3 r = problem.inertia * m.angular_velocity[N] -
                      F_last.transpose() * carried[N - 1] - 0.5 * h * applied[N];
    worst = std::max(worst, relative(r.norm(), P));
  }
  out.relative = std::isfinite(worst) ? worst : std::numeric_limits<double>::infinity();
  return out;
}

std::string planInconsistency(const PlanningProblem& problem, const PlanResult& result,
                              bool constraints) {
  std::ostringstream why;
  const StepResidual residual = measureStepResidual(problem, result.maneuver);
  if (!(residual.relative <= residual.tolerance)) {
    why << "stationary point found, but its attitudes, velocities and torques miss the discrete "
           "equations of motion by "
        << residual.relative << " relative (tolerance " << residual.tolerance << ")";
    return why.str();
  }
  if (constraints && problem.hasNodeConstraints()) {
    const ConstraintCheck check = checkConstraints(problem, result.maneuver);
    if (!(check.max_relative_violation <= kNodeConstraintTolerance)) {
      why << "stationary point found, but it violates " << check.worst << " " << check.worst_where
          << " (" << check.max_relative_violation << " relative, tolerance "
          << kNodeConstraintTolerance << ")";
      return why.str();
    }
  }
  return "";
}

namespace {

/// The terminal errors of an open-loop replay and replay_miss, the larger of the attitude miss
/// and T × the velocity miss (one rule for every scheme's replay).
void setReplayMiss(const PlanningProblem& problem, const Maneuver& replayed, PlanResult* result) {
  const int N = problem.steps;
  result->terminal_attitude_error = so3::angleBetween(problem.final_attitude, replayed.attitude[N]);
  result->terminal_velocity_error = (replayed.angular_velocity[N] - problem.final_velocity).norm();
  result->replay_miss =
      std::max(result->terminal_attitude_error, problem.duration * result->terminal_velocity_error);
}

}  // namespace

void replayFigures(const PlanningProblem& problem, PlanResult* result, Maneuver* replay) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = result->maneuver.torque;
  input.effects = problem.effects.get();
  SimulationReport report;
  const Maneuver replayed = simulate(scheme, input, &report);
  result->dynamics_residual = report.max_step_residual;
  setReplayMiss(problem, replayed, result);
  if (replay) *replay = replayed;
}

void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result, const Maneuver* planned) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  result->scheme = problem.scheme;
  result->effects = problem.effects ? problem.effects->names() : std::vector<std::string>{};
  if (problem.hasTorqueBounds()) {
    result->effects.push_back(effectKindName(EffectKind::ActuatorLimits));
  }
  result->duration = problem.duration;
  result->cost = scheme.cost(torque);
  result->effort = scheme.timeStep() * result->cost;
  if (planned) {
    result->maneuver = *planned;
  } else {
    result->maneuver.torque = torque;
    Maneuver replay;
    replayFigures(problem, result, &replay);
    result->maneuver = replay;
  }
  result->step_residual = measureStepResidual(problem, result->maneuver).relative;
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
  if (schemeHasEndTorques(problem.scheme) && options.solver == SolverKind::Nlopt) {
    throw InvalidInput("scheme: '" + schemeName(problem.scheme) +
                       "' is not available with solver nlopt (use 'paper' or 'variational')");
  }
}

/// fourth_order: one Richardson extrapolation step of second_order (docs/fourth_order.md).
/// second_order is time-symmetric, so its node values have an error expansion in even powers of
/// h; X = X_{2N} + (X_{2N} − X_N)/3 at the N + 1 common nodes cancels the h² term. On the group,
/// R_k = R^{2N}_{2k} exp(⅓ log((R^N_k)ᵀ R^{2N}_{2k})). Both solves get the request's solver,
/// constraints, effects and what is left of its time budget; the coarse one its warm start. The
/// fine one starts cold: its grid continuation (N/2, N/8, … with Richardson-extrapolated step
/// rates) starts it better than the coarse plan refined at the step midpoints (torques are second
/// differences: an O(h²) attitude guess is an O(1) torque guess; measured 9 Newton iterations
/// instead of 2). The result converges only if both do.
PlanResult planFourthOrder(const PlanningProblem& problem, const SolverOptions& options,
                           std::chrono::steady_clock::time_point start) {
  const int N = problem.steps;
  PlanningProblem sub = problem;
  sub.scheme = SchemeKind::SecondOrder;
  const std::string what =
      "fourth_order (Richardson extrapolation of second_order at N = " + std::to_string(N) +
      " and 2N = " + std::to_string(2 * N) + ")";
  const PlanResult coarse = planAtResolution(sub, withRemainingBudget(options, start));
  const auto failed = [&](PlanResult sub_result, int steps) {
    sub_result.message = what + ": the second_order solve at N = " + std::to_string(steps) +
                         " did not converge (its plan is returned): " + sub_result.message;
    return sub_result;
  };
  if (!coarse.converged()) return failed(coarse, N);
  sub.steps = 2 * N;
  SolverOptions fine_options = withRemainingBudget(options, start);
  fine_options.warm_start = nullptr;
  fine_options.constrained_from_warm_start = false;
  const PlanResult fine = planAtResolution(sub, fine_options);
  if (!fine.converged()) return failed(fine, 2 * N);

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
  result.duration = problem.duration;
  result.message = what + ": N: " + coarse.message + " | 2N: " + fine.message;

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

  result.cost = schemeCost(SchemeKind::FourthOrder, m.torque);
  result.effort = problem.duration / N * result.cost;
  result.effects = fine.effects;
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = m.torque;
  input.effects = problem.effects.get();
  setReplayMiss(problem,
                replayPlan(SchemeKind::FourthOrder, problem.inertia, problem.duration / N, input),
                &result);
  return result;
}

}  // namespace

PlanResult planAtResolution(const PlanningProblem& problem, const SolverOptions& requested) {
  validateProblem(problem);
  validateOptions(requested);
  requireSchemeSupported(problem, requested);
  if (schemeIsDiscretization(problem.scheme)) requireBoundarySteps(problem);
  // A guess of another N is resampled to this grid (warm_start.hpp).
  SolverOptions options = requested;
  Maneuver on_grid;
  const bool guess_resampled =
      requested.warm_start && requested.warm_start->steps() != problem.steps;
  if (guess_resampled) {
    on_grid = initialGuessOnGrid(*requested.warm_start, problem);
    options.warm_start = &on_grid;
  }
  const auto start = std::chrono::steady_clock::now();
  PlanResult result;
  if (problem.scheme == SchemeKind::FourthOrder) {
    result = planFourthOrder(problem, options, start);
  } else if (options.solver == SolverKind::Newton && problem.hasNodeConstraints() &&
             options.warm_start && !options.constrained_from_warm_start && !guess_resampled) {
    // A plan of this N given as the initial guess (e.g. the remainder of the plan being flown):
    // the interior point from it directly, its multipliers re-derived; if that stops, from it
    // through the usual continuation. A resampled guess (another N) is off the bounds it rode
    // on by O(h) and starts the unconstrained optimum instead, as below (measured: torque_limited
    // 64 → 256, 29 interior-point iterations from the guess, 25 cold).
    result = solveWithInteriorPointFromGuess(problem, options);
    if (result.termination == Termination::NotConverged ||
        result.termination == Termination::Infeasible) {
      const PlanResult first = result;
      result = solveWithInteriorPoint(problem, withRemainingBudget(options, start));
      result.iterations += first.iterations;
      result.levels.insert(result.levels.begin(), first.levels.begin(), first.levels.end());
      result.message += "; after the start from the initial guess stopped: " + first.message;
    }
  } else if (options.solver == SolverKind::Newton && problem.hasNodeConstraints() &&
             options.constrained_from_warm_start && options.warm_start) {
    result = solveWithInteriorPoint(problem, options);
  } else if (options.solver == SolverKind::Newton && problem.hasNodeConstraints()) {
    // The unconstrained optimum first (fast path): if it meets every node constraint it is the
    // constrained optimum too; otherwise it starts the interior-point solver.
    result = solveWithNewton(problem, options);
    const ConstraintCheck unconstrained = result.maneuver.steps() == problem.steps
                                              ? checkConstraints(problem, result.maneuver)
                                              : ConstraintCheck{};
    if (!result.converged() || unconstrained.max_node_bound_violation > 0.0) {
      SolverOptions constrained = withRemainingBudget(options, start);
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
      const std::vector<LevelSummary> newton_levels = result.levels;
      result = solveWithInteriorPoint(problem, constrained);
      result.iterations += newton_iterations;
      result.levels.insert(result.levels.begin(), newton_levels.begin(), newton_levels.end());
      result.message += note.str();
    } else {
      result.message += "; constraints inactive at the unconstrained optimum";
    }
  } else if (options.solver == SolverKind::Newton) {
    result = solveWithNewton(problem, options);
  } else {
    result = solveWithNlopt(problem, options);
  }
  if (options.solver == SolverKind::Newton && schemeIsDiscretization(problem.scheme) &&
      result.maneuver.steps() == problem.steps) {
    // The Newton and interior-point plans are their own trajectories; their open-loop replay
    // (replay_miss, the terminal errors) is measured once, here, for the plan returned.
    try {
      replayFigures(problem, &result);
    } catch (const StepTooLarge& e) {
      result.termination = Termination::StepTooLarge;
      result.message = std::string("replay of the planned torques failed: ") + e.what() + " (" +
                       result.message + ")";
    }
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
