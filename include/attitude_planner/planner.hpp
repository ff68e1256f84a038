// The one entry point for planning a fully actuated maneuver: the CLI `plan_maneuver`, the planner
// node and the benchmarks all call planManeuver().
//
// Problem (seed 000, Problem 3.2): minimize Σ_{k=1}^{N−1} ½|τ_k|² subject to the discrete dynamics
// of the chosen scheme (discrete_scheme.hpp) and the boundary data R_0, Ω_0, R_N, Ω_{N−1}.
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "attitude_planner/accuracy_target.hpp"
#include "attitude_planner/constraints.hpp"
#include "attitude_planner/discrete_scheme.hpp"
#include "attitude_planner/effects.hpp"
#include "attitude_planner/maneuver.hpp"

namespace attitude_planner {

/// Which way the maneuver turns from R_1 to R_{N−1} (the planner's initial guess; Newton then
/// finds the extremal next to it).
enum class RotationDirection {
  Shortest,  ///< the geodesic (angle ≤ π); near π both ways are solved and the cheaper is kept
  LongWay,   ///< the other way round the same axis (angle 2π − θ)
};

/// A rest-to-rest / slew problem for the fully actuated rigid body.
struct PlanningProblem {
  Matrix3 inertia = Matrix3::Identity();           ///< J [kg·m²], body frame, SPD
  double duration = 1.0;                           ///< T [s]
  int steps = 64;                                  ///< N (h = T/N)
  Matrix3 initial_attitude = Matrix3::Identity();  ///< R_0
  Vector3 initial_velocity = Vector3::Zero();      ///< Ω_0 [rad/s], body
  Matrix3 final_attitude = Matrix3::Identity();    ///< R_N
  Vector3 final_velocity = Vector3::Zero();        ///< Ω_{N−1} [rad/s], body
  SchemeKind scheme = SchemeKind::Paper;
  /// Accept an inertia whose principal moments violate J1 + J2 ≥ J3 (no rigid body has one).
  /// The seed's example inertia is such a matrix (moments 3.146, 12.538, 32.186), so its scenes
  /// opt in explicitly; the mathematics only needs J symmetric positive definite.
  bool allow_nonphysical_inertia = false;
  RotationDirection direction = RotationDirection::Shortest;
  /// Extra full turns (2π each) about the same axis in the same sense, ≥ 0.
  int extra_revolutions = 0;
  /// Known external torques the plan must account for (gravity gradient, disturbances); null or
  /// empty: none. Shared, immutable: several solves may use one model.
  std::shared_ptr<const EffectModel> effects;
  /// Per-axis bound |τ_i| ≤ max_torque_i [N m] on the control (actuator_limits); +∞: unbounded.
  /// A problem whose unconstrained optimum violates a bound or a constraint is solved by the
  /// interior-point solver (interior_point_solver.cpp), O(N) per iteration.
  Vector3 max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  bool hasTorqueBounds() const { return max_torque.allFinite(); }
  /// Constraints at every node (scene key `constraints:`, constraints.hpp); empty: none.
  std::vector<PlanningConstraint> constraints;
  /// Any per-axis bound or node constraint.
  bool hasNodeConstraints() const { return hasTorqueBounds() || !constraints.empty(); }
  /// A requested accuracy instead of `steps`: planManeuver chooses N (and the scheme if asked)
  /// from the measured order and a two-resolution estimate (accuracy.hpp). Inactive by default.
  AccuracyTarget accuracy;
};

/// Progress of one iteration, for feedback (action) and logging.
struct IterationInfo {
  int iteration = 0;
  double cost = 0.0;           ///< Σ ½|τ_k|² [N²·m²]
  double gradient_norm = 0.0;  ///< optimality residual (Newton: relative Newton decrement)
  double step_length = 0.0;    ///< line-search step accepted
};

/// Solver settings. Defaults solve to round-off on the seed's examples.
struct SolverOptions {
  std::string solver = "newton";  ///< "newton" (ours) or "nlopt" (independent cross-check)
  double tolerance = 1e-10;       ///< relative torque accuracy (Newton decrement / |τ|₂)
  int max_iterations = 200;       ///< Newton: per grid level (coarse levels start the fine one)
  double time_budget_s = 0.0;     ///< wall-time limit; 0 = none
  /// Called after every iteration, numbered across grid levels (the first ones may run on
  /// coarser grids); return false to cancel (the result says "cancelled").
  std::function<bool(const IterationInfo&)> on_iteration;
  /// Optional warm start: a maneuver with the same N (attitudes R_k are used).
  const Maneuver* warm_start = nullptr;
};

/// What a solve returns. `converged` is false with a reason in `message` otherwise.
struct PlanResult {
  bool converged = false;
  bool cancelled = false;  ///< the on_iteration callback asked to stop
  /// Failed because an implicit step has no solution at this h (h·|Ω| too large): the message
  /// says "increase steps". The node answers STEP_TOO_LARGE.
  bool step_too_large = false;
  std::string message;  ///< human-readable outcome ("converged", or why not)
  std::string solver;   ///< "newton" or "nlopt"
  SchemeKind scheme = SchemeKind::Paper;
  Maneuver maneuver;   ///< R_k, Ω_k, τ_k, k = 0..N
  double cost = 0.0;   ///< Σ_{k=1}^{N−1} ½|τ_k|² [N²·m²]
  int iterations = 0;  ///< Newton iterations, coarser continuation levels included
  /// First-order optimality residual at the end: max-norm of ∇C relative to |∂τ/∂R|·max|τ|.
  double max_residual = 0.0;
  /// Newton: √(gᵀH⁻¹g)/|τ|₂ of the last iteration, ≈ the relative ℓ2 torque error before the
  /// final step (the convergence test); NLopt: 0.
  double newton_decrement = 0.0;
  double dynamics_residual = 0.0;        ///< worst implicit-step residual on replay [N·m·s]
  double terminal_attitude_error = 0.0;  ///< ‖log(R_N*ᵀ R_N)‖ [rad] of the replayed maneuver
  double terminal_velocity_error = 0.0;  ///< |Ω_{N−1} − Ω*_{N−1}| [rad/s] of the replay
  double solve_time_s = 0.0;             ///< wall time [s]
  std::vector<IterationInfo> history;    ///< one entry per iteration
  /// Which extremal was found, e.g. "short way: 3.14159 rad about [1, 0, 0]" (Newton), with the
  /// cost of the other way when both were solved.
  std::string extremal;
  /// The effects in the planning model (scene keys), in order; "actuator_limits" last when the
  /// control torques are bounded.
  std::vector<std::string> effects;
  /// The accuracy of the plan when PlanningProblem::accuracy was given (requested = true).
  AccuracyEstimate accuracy;
  /// The request cannot be met: a bound or constraint excludes every maneuver the solver could
  /// reach (message names it, with the closest violation found).
  bool infeasible = false;
  /// The node constraints in force (scene keys, in order; "actuator_limits" first when bounded).
  std::vector<std::string> constraints;
  /// Worst violation over all nodes and constraints, each in its own unit (N m, rad/s, rad), ≥ 0,
  /// measured on the returned maneuver (checkConstraints).
  double max_constraint_violation = 0.0;
  /// Node constraints at their bound (within kActiveConstraintTolerance relative) on the result.
  int active_constraints = 0;
};

/// Checks the problem (finite numbers, SPD and physical inertia, T > 0, N ≥ 4, ...): throws
/// InvalidInput naming the field and the value.
void validateProblem(const PlanningProblem& problem);

/// Checks the solver settings (tolerance finite and > 0, max_iterations ≥ 0, time budget finite
/// and ≥ 0): throws InvalidInput naming the option and the value.
void validateOptions(const SolverOptions& options);

/// Plans the maneuver. Throws InvalidInput for a bad problem or options, StepTooLarge if a
/// boundary velocity has no step at h = T/N (the message names it and says "increase steps");
/// never throws for a solve that does not converge (PlanResult::converged = false says so, with
/// the reason). With an active problem.accuracy it chooses N itself (planToAccuracy,
/// accuracy.hpp).
PlanResult planManeuver(const PlanningProblem& problem, const SolverOptions& options = {});

}  // namespace attitude_planner

namespace attitude_planner {

/// Replays τ_1..τ_{N−1} (torque[k], k = 0..N, τ_0 = τ_N = 0) through the problem's scheme from
/// R_0, Ω_0 and fills result->maneuver, cost, dynamics_residual and the terminal errors.
/// Both solvers finish through here, so every reported figure is measured on the same replay.
/// Throws StepTooLarge if the replay's implicit step fails.
void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result);

/// A node constraint is counted active when its slack is within this fraction of its limit
/// (torque, rate) or this many radians (cones).
constexpr double kActiveConstraintTolerance = 1e-6;

/// The node constraints of `problem` (per-axis bounds and PlanningProblem::constraints) checked
/// on a maneuver's own rows, independently of any solver.
struct ConstraintCheck {
  std::vector<std::string> names;  ///< the keys in force ("actuator_limits" first if bounded)
  double max_violation = 0.0;      ///< worst violation, each in its own unit, ≥ 0
  int active = 0;                  ///< node constraints at their bound
  std::string worst;  ///< the worst violated constraint, e.g. "|tau_x| <= 0.1 N m"; empty if none
  std::string worst_where;  ///< its violation and node, e.g. "by 0.02 at k = 64 (t = 6.4 s)"
};
ConstraintCheck checkConstraints(const PlanningProblem& problem, const Maneuver& maneuver);

}  // namespace attitude_planner
