// Human and machine summaries of a plan: what plan_maneuver prints and writes with --summary.
#pragma once

#include <string>

#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// JSON object with converged, message, solver, scheme, steps, duration [s], iterations,
/// cost [N²·m²], terminal_attitude_error [rad], terminal_velocity_error [rad/s], max_residual,
/// dynamics_residual [N·m·s], solve_time_s [s]; numbers with %.17g (full precision).
std::string planResultJson(const PlanningProblem& problem, const PlanResult& result);

/// A few aligned lines for a terminal (units included).
std::string planResultText(const PlanningProblem& problem, const PlanResult& result);

/// `text` as a JSON string literal, quotes included.
std::string jsonString(const std::string& text);

/// %.17g, or null for a non-finite value (JSON has no NaN).
std::string jsonNumber(double value);

}  // namespace attitude_planner
