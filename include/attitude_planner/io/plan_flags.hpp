// The planning flags of plan_maneuver (--steps, --scheme, --solver, ...): one parser and one place
// that applies them to a problem and solver options, shared by the command-line tool and the
// Python module (whose plan(problem, **options) takes the same flags as keywords).
#pragma once

#include <optional>
#include <string>

#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// The planning flags as typed values; each "absent" value leaves the scene's (or the default).
struct PlanFlags {
  std::optional<int> steps;  ///< absent: the scene's
  std::string scheme;        ///< "" : the scene's
  std::string solver = "newton";
  bool solver_given = false;  ///< --solver was given
  std::string precision = "auto";
  double tolerance = -1.0;     ///< < 0: the default
  int max_iterations = -1;     ///< < 0: the default
  double time_budget = 0.0;    ///< 0: none
  int threads = 0;             ///< 0: not given (the machine's cores)
  std::string target_flag;     ///< "--target-miss" / "--target-cost-error", "" if absent
  double target_value = 0.0;   ///< its value (> 0)
  std::string objective;       ///< "" : the scene's
  double time_margin = -1.0;   ///< < 0: the scene's
  std::string direction;       ///< "" : the scene's
  int extra_revolutions = -1;  ///< < 0: the scene's
  /// --point-body-axis / --point-world-direction "X,Y,Z": a pointing end condition replacing the
  /// scene's final attitude (both or neither).
  std::optional<Vector3> point_body_axis, point_world_direction;
  /// --advanced NAME=VALUE (repeatable): the solvers' tuning, each field checked as it is set
  /// (advanced_parameters.hpp, advancedFields names them).
  AdvancedParameters advanced;
};

/// Whether `flag` ("--steps") is one of the planning flags.
bool isPlanFlag(const std::string& flag);

/// Parses and checks the value of planning flag `flag` (as typed on a command line) into *flags.
/// Throws InvalidInput with field() = `flag` and the value for a bad value (not a number, out of
/// range, unknown name). A second --target-* flag replaces the first (the tool refuses it first).
void applyPlanFlag(const std::string& flag, const std::string& value, PlanFlags* flags);

/// Checks the combination: --scheme auto only with a --target-* flag, --steps not with one.
/// Throws InvalidInput whose message names the flags (the tool's usage error).
void checkPlanFlagCombination(const PlanFlags& flags);

/// Puts the flags into a rigid-body problem and solver options (the scene's values stay where a
/// flag is absent).
void applyPlanFlags(const PlanFlags& flags, PlanningProblem* problem, SolverOptions* options);

}  // namespace attitude_planner
