// The verdict on a plan: the figures every solver's result is judged by, measured the same way
// for every solver (the step residual of the discrete equations, the node constraints, the
// open-loop replay).
#include "planning/problem/verdict.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/verdict.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

double stepResidualTolerance(int steps, double step_angle) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double floor = step_angle > 0 ? 16.0 * eps * (1.0 / step_angle + steps) : 0.0;
  return kStepResidualTolerance + floor;
}

namespace {

/// What the body receives at node k of plan m: its control torque and the effects at (R_k, t_k).
Vector3 appliedAt(const PlanningProblem& problem, const Maneuver& m, int k) {
  Vector3 a = m.torque[k];
  if (problem.effects) a += problem.effects->torque(m.attitude[k], k * m.time_step);
  return a;
}

/// c_k: the momentum step k of plan m carries, from its reported velocity (full precision):
/// paper exp(hΩ_k^) J Ω_k, variational J Ω_k; second_order Π_k + (h/2) a_k with Π_k = J Ω_k
/// (a_0 enters only second_order's c_0).
Vector3 carriedMomentum(const PlanningProblem& problem, const DiscreteScheme& scheme,
                        const Maneuver& m, int k) {
  if (!scheme.hasEndTorques()) return scheme.momentumOfVelocity(m.angular_velocity[k]);
  return problem.inertia * m.angular_velocity[k] + 0.5 * m.time_step * appliedAt(problem, m, k);
}

}  // namespace

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
  const auto applied = [&](int k) { return appliedAt(problem, m, k); };
  // One pass over the steps (each F_k = R_kᵀR_{k+1} and c_k formed once, nothing of size N
  // allocated: at N = 1e5 this check is a fifth of a stopped solve's hand-over).
  // c_k (carriedMomentum) must be F_k's own momentum, and c_k = F_{k−1}ᵀ c_{k−1} + h a_k (seed
  // 000, eq. 18; second_order: both half impulses).
  Vector3 carried_prev = Vector3::Zero();
  Matrix3 F_prev = Matrix3::Identity();
  for (int k = 0; k < N; ++k) {
    const Vector3 carried = carriedMomentum(problem, scheme, m, k);
    const Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
    worst = std::max(worst, relative((scheme.momentumOfStep(so3::log(F)) - carried).norm(), P));
    if (k >= 1) {
      const Vector3 r = carried - F_prev.transpose() * carried_prev - h * applied(k);
      worst = std::max(worst, relative(r.norm(), P));
    }
    carried_prev = carried;
    F_prev = F;
  }
  if (nodes) {  // Π_N = F_{N−1}ᵀ c_{N−1} + (h/2) a_N
    const Vector3 r = problem.inertia * m.angular_velocity[N] - F_prev.transpose() * carried_prev -
                      0.5 * h * applied(N);
    worst = std::max(worst, relative(r.norm(), P));
  }
  out.relative = std::isfinite(worst) ? worst : std::numeric_limits<double>::infinity();
  return out;
}

std::string planInconsistency(const PlanningProblem& problem, const PlanResult& result,
                              bool constraints, const StepResidual* measured,
                              const StepwiseReplay* replayed) {
  std::ostringstream why;
  const StepResidual residual =
      measured ? *measured : measureStepResidual(problem, result.maneuver);
  if (!(residual.relative <= residual.tolerance)) {
    why << "stationary point found, but its attitudes, velocities and torques miss the discrete "
           "equations of motion by "
        << residual.relative << " relative (tolerance " << residual.tolerance << ")";
    return why.str();
  }
  // A plan can meet its equations with a step on another root of the step's momentum map (past
  // a fold): not the motion the scheme's own step integrates from the plan's state.
  const StepwiseReplay stepwise = replayed ? *replayed : replayStepByStep(problem, result.maneuver);
  if (!stepwise.reproduces()) {
    why << "stationary point found, but its step k = " << stepwise.worst_step
        << " is not the step the replay solves from the plan's own state (";
    if (std::isfinite(stepwise.worst_angle)) {
      why << stepwise.worst_angle << " rad apart: another root of the step's momentum map)";
    } else {
      why << "no root found)";
    }
    return why.str();
  }
  if (constraints && problem.hasNodeConstraints()) {
    const ConstraintCheck check = checkConstraints(problem, result.maneuver);
    if (!check.withinBounds()) {
      why << "stationary point found, but it violates " << check.worst << " " << check.worst_where
          << " (" << check.max_relative_violation << " relative, tolerance "
          << kNodeConstraintTolerance << ")";
      return why.str();
    }
  }
  return "";
}

bool provesFeasible(const PlanningProblem& problem, const PlanResult& r) {
  if (r.converged()) return true;
  if (r.termination != Termination::NotConverged || r.maneuver.steps() != problem.steps ||
      !schemeIsDiscretization(problem.scheme)) {
    return false;
  }
  return planInconsistency(problem, r, true).empty();
}

StepwiseReplay replayStepByStep(const PlanningProblem& problem, const Maneuver& plan) {
  std::vector<double> apart(plan.steps());
  stepReplayAngles(problem, plan, 0, plan.steps(), &apart);
  return worstStepReplay(apart);
}

void stepReplayAngles(const PlanningProblem& problem, const Maneuver& plan, int first, int last,
                      std::vector<double>* apart) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, plan.time_step);
  // The open-loop replay's warm start for step k is its step k − 1 (F_0: exp(hΩ_0)).
  const auto plannedStep = [&](int k) {
    return Matrix3(plan.attitude[k].transpose() * plan.attitude[k + 1]);
  };
  Matrix3 guess = first == 0 ? so3::exp(Vector3(plan.time_step * problem.initial_velocity))
                             : plannedStep(first - 1);
  for (int k = first; k < last; ++k) {
    const Matrix3 planned = plannedStep(k);
    StepSolveReport report;
    const Matrix3 F = scheme.solveStep(carriedMomentum(problem, scheme, plan, k), guess, &report);
    (*apart)[k] =
        report.converged ? so3::angleBetween(F, planned) : std::numeric_limits<double>::infinity();
    guess = planned;
  }
}

StepwiseReplay worstStepReplay(const std::vector<double>& apart) {
  StepwiseReplay out;
  for (int k = 0; k < static_cast<int>(apart.size()); ++k) {
    if (!(apart[k] <= out.worst_angle)) {
      out.worst_angle = apart[k];
      out.worst_step = k;
    }
  }
  return out;
}

void judgeFailedReplay(const PlanningProblem& problem, const std::string& what,
                       PlanResult* result) {
  if (!result->converged()) {
    addNote(result, notes::LastIterateDoesNotReplay{what});
    return;
  }
  const StepwiseReplay stepwise = replayStepByStep(problem, result->maneuver);
  const double not_measured = std::numeric_limits<double>::quiet_NaN();
  result->dynamics_residual = result->terminal_attitude_error = not_measured;
  result->terminal_velocity_error = not_measured;
  result->replay_miss = std::numeric_limits<double>::infinity();
  if (stepwise.reproduces()) {
    addNote(result, notes::OpenLoopReplayParted{what, stepwise.worst_angle});
  } else {
    result->termination = Termination::NotConverged;
    frameMessage(result, frames::ReplayFailed{what, stepwise.worst_step, stepwise.worst_angle});
  }
}

void setReplayMiss(const PlanningProblem& problem, const Maneuver& replayed, PlanResult* result) {
  const int N = problem.steps;
  result->terminal_attitude_error = so3::angleBetween(problem.final_attitude, replayed.attitude[N]);
  result->terminal_velocity_error = (replayed.angular_velocity[N] - problem.final_velocity).norm();
  result->replay_miss =
      std::max(result->terminal_attitude_error, problem.duration * result->terminal_velocity_error);
}

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

void recordConstraintFigures(const PlanningProblem& problem, PlanResult* result) {
  const ConstraintCheck check = checkConstraints(problem, result->maneuver);
  result->constraints = check.names;
  result->max_constraint_violation = check.max_violation;
  result->max_violation_between_nodes = check.max_violation_between_nodes;
  result->active_constraints = check.active;
}

void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result, const Maneuver* planned, StepResidual* residual) {
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
    if (planned != &result->maneuver) result->maneuver = *planned;  // else built in place
  } else {
    result->maneuver.torque = torque;
    Maneuver replay;
    replayFigures(problem, result, &replay);
    result->maneuver = replay;
  }
  const StepResidual measured = measureStepResidual(problem, result->maneuver);
  result->step_residual = measured.relative;
  if (residual) *residual = measured;
}

std::string classInconsistency(const PlanResult& result) {
  const Maneuver& plan = result.maneuver;
  const ExtremalSummary& extremal = result.extremal_summary;
  if (!extremal.known || plan.steps() < 3) return "";
  double turned = 0.0;  // Σ |log(R_kᵀR_{k+1})|, k = 1..N−2: the path from R_1 to R_{N−1}
  for (int k = 1; k + 1 < plan.steps(); ++k) {
    turned += so3::log(Matrix3(plan.attitude[k].transpose() * plan.attitude[k + 1])).norm();
  }
  // Within half a turn short of its lift a plan still counts as its class: the lift classes
  // are finer than the topology (lifts two turns apart are one homotopy class), and the solve
  // may end on a plan a little short of the lift (measured: θ = 2π − 0.1 + 1 turn on the seed's
  // body, 6.364 rad against 6.383). More than half a turn short, its turns round to another
  // class's.
  if (turned >= extremal.angle - M_PI) return "";
  std::ostringstream why;
  why << "the plan turns " << exactNumber(turned) << " rad from R_1 to R_{N-1}, more than half "
      << "a turn less than the " << exactNumber(extremal.angle)
      << " rad of its class's lift, so it is in another class";
  return why.str();
}

}  // namespace attitude_planner
