// Human and machine summaries of a plan: what plan_maneuver prints and writes with --summary.
#pragma once

#include <string>

#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// JSON object with converged, message, solver, scheme, steps, duration [s], iterations,
/// cost [N²·m²], terminal_attitude_error [rad], terminal_velocity_error [rad/s], max_residual,
/// dynamics_residual [N·m·s], step_residual (relative), replay_miss [rad], solve_time_s [s];
/// numbers with %.17g (full precision).
std::string planResultJson(const PlanningProblem& problem, const PlanResult& result);

/// A few aligned lines for a terminal (units included).
std::string planResultText(const PlanningProblem& problem, const PlanResult& result);

/// JSON object of a drift + two-input plan: converged, message, system, steps, duration [s],
/// control_weights [c1, c2], iterations, continuation_stages, cost [cost units],
/// terminal_attitude_error [rad], initial_costate [p1, p2, p3] (found), initial_costate_guess
/// (null if none), solve_time_s [s]; numbers %.17g.
std::string driftTwoInputPlanJson(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s);

/// A few aligned lines for a terminal (units included).
std::string driftTwoInputPlanText(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s);

/// `text` as a JSON string literal, quotes included.
std::string jsonString(const std::string& text);

/// %.17g, or null for a non-finite value (JSON has no NaN).
std::string jsonNumber(double value);

}  // namespace attitude_planner
