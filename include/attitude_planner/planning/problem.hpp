// What a caller asks the planner for: the problem (seed 000, Problem 3.2) and the solver settings,
// with the one validation function for each. Every entry point (scene parser, CLI, nodes) builds
// these and calls validateProblem / validateOptions, so each rule lives here once.
//
// Problem: minimize Σ_{k=1}^{N−1} ½|τ_k|² subject to the discrete dynamics of the chosen scheme
// (dynamics/discrete_scheme.hpp) and the boundary data R_0, Ω_0, R_N, Ω_{N−1}.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/input_rules.hpp"
#include "attitude_planner/name_table.hpp"
#include "attitude_planner/planning/accuracy_target.hpp"
#include "attitude_planner/planning/advanced_parameters.hpp"
#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/reaction_wheels.hpp"

namespace attitude_planner {

/// Which way the maneuver turns from R_1 to R_{N−1} (the planner's initial guess; Newton then
/// finds the extremal next to it).
enum class RotationDirection {
  Shortest,  ///< the geodesic (angle ≤ π); near π both ways are solved and the cheaper is kept
  LongWay,   ///< the other way round the same axis (angle 2π − θ)
};

/// The names of the directions (scene key `direction`, --direction, request field `direction`).
inline constexpr NamedValue<RotationDirection> kRotationDirectionNames[] = {
    {RotationDirection::Shortest, "shortest"},
    {RotationDirection::LongWay, "long_way"},
};

/// "shortest" or "long_way".
inline std::string directionName(RotationDirection direction) {
  return nameIn(kRotationDirectionNames, direction);
}
/// The direction named `text`; throws InvalidInput naming `field`, the value and the accepted
/// names.
inline RotationDirection parseDirection(const std::string& text, const std::string& field) {
  return parseIn(kRotationDirectionNames, text, field);
}

/// Which solver plans the maneuver.
enum class SolverKind {
  /// The package's own structured solvers, O(N) per iteration: trust-region Newton on the
  /// optimality conditions, and the interior point when node constraints are in force (named
  /// "newton" for users: CLI, srv field, JSON).
  Structured,
  Nlopt,  ///< NLopt SLSQP: the independent cross-check (and the bounded-torque solver)
  /// For downstream code written against this name.
  Newton [[deprecated("use SolverKind::Structured")]] = Structured,
};

/// The names of the solvers (--solver, request field `solver`, ~solver, JSON `solver`).
inline constexpr NamedValue<SolverKind> kSolverNames[] = {
    {SolverKind::Structured, "newton"},
    {SolverKind::Nlopt, "nlopt"},
};

/// "newton" or "nlopt".
inline std::string solverName(SolverKind solver) {
  return nameIn(kSolverNames, solver);
}
/// The solver named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline SolverKind parseSolver(const std::string& text, const std::string& field) {
  return parseIn(kSolverNames, text, field);
}

/// The arithmetic of the interior point's condensed Newton system (SolverOptions::precision). At
/// a bound the system's condition grows like N⁴/μ; the smooth modes need more than double above
/// about N = 1024 (interior_point/grid_solve.hpp).
enum class Precision {
  Auto,      ///< double to kAutoDoubleMaxSteps, extended to kAutoExtendedMaxSteps, then
             ///< double-double (extended only where long double is the x87 format)
  Double,    ///< IEEE double throughout
  Extended,  ///< long double where it is the x87 format (64-bit significand), else double-double
  DoubleDouble,  ///< double-double arithmetic (~106-bit significand, software)
};

/// The names of the precisions (--precision, scene key `precision`).
inline constexpr NamedValue<Precision> kPrecisionNames[] = {
    {Precision::Auto, "auto"},
    {Precision::Double, "double"},
    {Precision::Extended, "extended"},
    {Precision::DoubleDouble, "double_double"},
};

/// "auto", "double", "extended" or "double_double".
inline std::string precisionName(Precision precision) {
  return nameIn(kPrecisionNames, precision);
}
/// The precision named `text`; throws InvalidInput naming `field`, the value and the accepted
/// names.
inline Precision parsePrecision(const std::string& text, const std::string& field) {
  return parseIn(kPrecisionNames, text, field);
}

/// Precision::Auto: double up to this N ...
constexpr int kAutoDoubleMaxSteps = 1024;
/// ... extended (x87 long double) up to this N, double-double above.
constexpr int kAutoExtendedMaxSteps = 8192;

/// What the plan minimizes (scene key `objective`, --objective, request field `objective`).
enum class Objective {
  MinimumEffort,  ///< ½∫|τ|²dt at the given duration (the seed's problem; default)
  MinimumTime,    ///< the duration T*, under the torque bounds and constraints in force
};

inline constexpr NamedValue<Objective> kObjectiveNames[] = {
    {Objective::MinimumEffort, "minimum_effort"},
    {Objective::MinimumTime, "minimum_time"},
};

/// "minimum_effort" or "minimum_time".
inline std::string objectiveName(Objective objective) {
  return nameIn(kObjectiveNames, objective);
}
/// The objective named `text`; throws InvalidInput naming `field`, the value and the accepted
/// names.
inline Objective parseObjective(const std::string& text, const std::string& field) {
  return parseIn(kObjectiveNames, text, field);
}

/// The scheme value that lets the planner choose the scheme (with an accuracy target only).
inline constexpr const char* kAutoSchemeName = "auto";

/// Fewest steps N of a rigid-body plan (validateProblem).
constexpr int kMinSteps = 4;
/// Most steps N of a rigid-body plan: the Newton solver holds ~2.3 kB per step (measured at
/// N = 1e6, 2.3 GB peak; docs/results/performance.md), so N = 2e6 needs ~4.6 GB. The former limit,
/// 1e7, would need ~23 GB and be killed for memory on a 24 GB machine instead of being refused.
constexpr int kMaxSteps = 2000000;
/// The magnitudes the planner works in, in SI units: every moment of inertia, duration, step,
/// bound and the torque scale J/T² within [1/kMagnitudeRange, kMagnitudeRange]. The solvers form
/// squares and fourth powers of them (the cost, the Hessian's h⁻⁴ terms), which stay normal
/// doubles there; outside it a "converged" answer could rest on an overflowed cost or a denormal
/// step, so such a request is refused by name (validateProblem).
constexpr double kMagnitudeRange = 1e50;

/// How the end attitude is asked for (scene `final.attitude` or `final.pointing`).
enum class EndConditionKind {
  FixedAttitude,  ///< R_N = PlanningProblem::final_attitude (default)
  /// R_N b = d: a body axis b aimed at a world direction d, the twist ψ about b free (the planner
  /// chooses it; planning/pointing.hpp): R_N = R_ref(b, d) exp(ψ b^).
  Pointing,
};

/// The end condition of a plan. With Pointing, PlanningProblem::final_attitude is ignored as a
/// target (the planner writes the chosen R_N into the result's maneuver).
struct EndCondition {
  EndConditionKind kind = EndConditionKind::FixedAttitude;
  Vector3 body_axis = Vector3::UnitZ();        ///< b, body frame (any nonzero length; normalized)
  Vector3 world_direction = Vector3::UnitZ();  ///< d, world frame (any nonzero length; normalized)
  bool pointing() const { return kind == EndConditionKind::Pointing; }
};

/// A rest-to-rest / slew problem for the fully actuated rigid body.
struct PlanningProblem {
  Matrix3 inertia = Matrix3::Identity();           ///< J [kg·m²], body frame, SPD
  double duration = 1.0;                           ///< T [s]
  int steps = 64;                                  ///< N (h = T/N)
  Matrix3 initial_attitude = Matrix3::Identity();  ///< R_0
  Vector3 initial_velocity = Vector3::Zero();      ///< Ω_0 [rad/s], body
  Matrix3 final_attitude = Matrix3::Identity();    ///< R_N (EndConditionKind::FixedAttitude)
  /// What R_N must satisfy: final_attitude (default), or a pointing condition with a free twist.
  EndCondition end_condition;
  Vector3 final_velocity = Vector3::Zero();  ///< Ω_{N−1} [rad/s], body
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
  /// τ_d [N m], world: the effects' torque when it is constant in the world frame (zero without
  /// effects or with any other; reaction wheels plan with this kind only, validateProblem).
  Vector3 worldDisturbance() const {
    if (!effects) return Vector3::Zero();
    return effects->constantWorldTorque().value_or(Vector3::Zero());
  }
  /// Per-axis bound |τ_i| ≤ max_torque_i [N m] on the control (actuator_limits); +∞: unbounded.
  /// A problem whose unconstrained optimum violates a bound or a constraint is solved by the
  /// interior-point solver (drivers/constrained_recipe.cpp), O(N) per iteration.
  Vector3 max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  bool hasTorqueBounds() const { return max_torque.allFinite(); }
  /// Constraints at every node (scene key `constraints:`, constraints.hpp); empty: none.
  std::vector<PlanningConstraint> constraints;
  /// Reaction wheels (scene `actuators: {reaction_wheels: …}`, reaction_wheels.hpp): their
  /// torque and momentum limits are node constraints of the plan. Empty: none.
  ReactionWheels reaction_wheels;
  /// Any keep-out or keep-in cone among the constraints (a cone has sides: its solves depend on
  /// the start in ways a bound's do not).
  bool hasCones() const {
    return std::any_of(constraints.begin(), constraints.end(),
                       [](const PlanningConstraint& c) { return c.isCone(); });
  }
  /// At rest at both ends with R_0 already meeting the end condition, in the shortest class with
  /// no extra revolutions and no effect pushing the body: the zero maneuver (no torque, no
  /// motion) is a plan at any duration, of cost 0, which no plan beats (planning_problem.cpp).
  bool zeroManeuverReachesTheEnd() const;
  /// Any per-axis bound, node constraint or reaction-wheel limit.
  bool hasNodeConstraints() const {
    return hasTorqueBounds() || !constraints.empty() || reaction_wheels.present();
  }
  /// A requested accuracy instead of `steps`: planManeuver chooses N (and the scheme if asked)
  /// from the measured order and a two-resolution estimate (accuracy.hpp). Inactive by default.
  AccuracyTarget accuracy;
  /// Minimum effort at `duration` (default), or minimum time (minimum_time.hpp): then `duration`
  /// is an upper bound and the first guess (≤ 0: none), and a torque bound must be in force.
  Objective objective = Objective::MinimumEffort;
  /// With minimum_time: plan the minimum-effort maneuver at (1 + time_margin) T* instead of the
  /// bang–bang one at T*; ≥ 0.
  double time_margin = 0.0;
};

/// What an attempt was for: the role of one solve in the planner's order of attempts.
enum class AttemptStage {
  Solve,              ///< the request's own solve (a named class, or a warm start)
  ClassSurvey,        ///< a class left free: one homotopy class solved on the survey grid
  ClassRefine,        ///< a surveyed class carried to the requested grid, the cheapest kept
  RateContinuation,   ///< spinning ends: from rest to rest, boundary rates raised in stages
  CoastingRetry,      ///< spinning ends: from the coasting start after the others stalled
  MoreStarts,         ///< a slow spinning solve: further starts in its class, the cheapest kept
  Constrained,        ///< the interior point, after the unconstrained optimum violated a bound
  ConstrainedRetry,   ///< the interior point once more (other formulation, or cones first)
  FourthOrderCoarse,  ///< fourth_order: the N solve of its Richardson pair
  FourthOrderFine,    ///< fourth_order: the 2N solve of its Richardson pair
  MinimumTimeProbe,   ///< minimum_time: one duration tried by the search
  MinimumTimeMargin,  ///< minimum_time with time_margin: the plan at (1 + m) T*
  MinimumTimeSolve,   ///< minimum_time: one free-time interior-point solve from one start
  /// minimum_time: a minimum-effort solve at T*: fourth_order's non-binding second_order plan at
  /// the pair's T* (the free-time plan itself is every other scheme's answer).
  MinimumTimePolish,
  ConstrainedClass,  ///< under constraints, a class left free: another class's whole solve
  /// bounded minimum effort at T > T*: one duration of the ladder climbed from the minimum-time
  /// plan when the direct start from it did not converge
  DurationLadder,
};
inline constexpr NamedValue<AttemptStage> kAttemptStageNames[] = {
    {AttemptStage::Solve, "solve"},
    {AttemptStage::ClassSurvey, "class_survey"},
    {AttemptStage::ClassRefine, "class_refine"},
    {AttemptStage::RateContinuation, "rate_continuation"},
    {AttemptStage::CoastingRetry, "coasting_retry"},
    {AttemptStage::MoreStarts, "more_starts"},
    {AttemptStage::Constrained, "constrained"},
    {AttemptStage::ConstrainedRetry, "constrained_retry"},
    {AttemptStage::FourthOrderCoarse, "fourth_order_coarse"},
    {AttemptStage::FourthOrderFine, "fourth_order_fine"},
    {AttemptStage::MinimumTimeProbe, "minimum_time_probe"},
    {AttemptStage::MinimumTimeMargin, "minimum_time_margin"},
    {AttemptStage::MinimumTimeSolve, "minimum_time_solve"},
    {AttemptStage::MinimumTimePolish, "minimum_time_polish"},
    {AttemptStage::ConstrainedClass, "constrained_class"},
    {AttemptStage::DurationLadder, "duration_ladder"},
};

/// Which homotopy class a maneuver belongs to: the way round and the extra whole turns.
struct HomotopyClass {
  /// The other way round: the second-nearest lift of the rotation between the ends
  /// (RotationDirection::LongWay); rest to rest, the other way than the shortest rotation.
  bool long_way = false;
  int extra_revolutions = 0;  ///< extra full turns in the sense of the way
};

/// The attempt an iteration belongs to (SolveContext::Scope), so that a convergence plot (the
/// action's feedback) tells one attempt from the next and a discarded attempt from the kept one.
struct AttemptTag {
  /// 1, 2, ... in the order the request's attempts began (nested solves included); 0: outside
  /// any attempt.
  int number = 0;
  AttemptStage stage = AttemptStage::Solve;
  HomotopyClass homotopy;  ///< the class its start was in
};

/// Progress of one iteration, for feedback (action) and logging.
struct IterationInfo {
  int iteration = 0;
  double cost = 0.0;           ///< Σ ½|τ_k|² [N²·m²]
  double gradient_norm = 0.0;  ///< optimality residual (Newton: relative Newton decrement)
  /// step accepted (Newton: 1, damped by its shift instead; the free-time interior point: 0 for
  /// an iteration that lowered the barrier parameter at the same iterate)
  double step_length = 0.0;
  int steps = 0;        ///< N of the grid level iterated on (0: not reported)
  double effort = 0.0;  ///< h · cost at that level [N²·m²·s], comparable across levels
  AttemptTag attempt;   ///< which attempt iterated (filled by SolveContext::reportIteration)
};

/// Solver settings. Defaults solve to round-off on the seed's examples. (The pragmas keep the
/// compiler from reporting the deprecated fields where the options are built or copied by the
/// implicit constructors; a user's own read or write of one is still reported.)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
struct SolverOptions {
  SolverKind solver = SolverKind::Structured;
  double tolerance = 1e-10;  ///< relative torque accuracy (Newton decrement / |τ|₂)
  /// Newton: per grid level (coarse levels start the fine one) and start; the coasting start of a
  /// spinning solve (after the others stalled, or as one of the more starts of a slow one) may
  /// take 25× this (newton_solver.cpp).
  int max_iterations = 200;
  double time_budget_s = 0.0;  ///< wall-time limit; 0 = none
  /// Called after every iteration, numbered across grid levels (the first ones may run on
  /// coarser grids); return false to cancel (the result says "cancelled").
  std::function<bool(const IterationInfo&)> on_iteration;
  /// Optional cancel flag another thread may set (e.g. an action's cancel): polled inside long
  /// iterations as well as between them, so a cancel ends the solve promptly ("cancelled").
  const std::atomic<bool>* cancel_requested = nullptr;
  /// Optional warm start: a maneuver with the same N (attitudes R_k are used).
  const Maneuver* warm_start = nullptr;
  /// The arithmetic of the interior point's Newton system; `auto` chooses by N.
  Precision precision = Precision::Auto;
  /// Deprecated (the planner's drivers hand it to their solvers as part of the start, not through
  /// the user's options; still honoured for one release): with node constraints and a warm start,
  /// start the interior point from the warm start itself instead of from its unconstrained
  /// optimum.
  [[deprecated("a driver's start, not a user's option")]] bool constrained_from_warm_start = false;
  /// Deprecated with constrained_from_warm_start: the warm start meets every constraint with room
  /// (a plan at T* time-scaled to a longer T), so the interior point takes a request's own recipe.
  [[deprecated("a driver's start, not a user's option")]] bool warm_start_strictly_inside = false;
  /// Deprecated with constrained_from_warm_start: with node constraints and no warm start, the
  /// request's unconstrained optimum already solved on its grid in its class.
  [[deprecated("a driver's start, not a user's option")]] const Maneuver* unconstrained_optimum =
      nullptr;
  /// A request that leaves its homotopy class free (direction shortest, no extra revolutions, no
  /// warm start) is solved in every class of the class survey and the cheapest plan kept
  /// (newton_solver.cpp); false: in the nearest lift's class only, as a named class is.
  bool enumerate_classes = true;
  /// Independent solves a driver runs at once (minimum time's starts on the start grid, the class
  /// survey and refinements), each on its own thread; 0: as many as the machine has cores, 1: one
  /// after the other. The answer does not depend on it beyond the order minimum time's watch sees
  /// its starts (drivers/minimum_time_free_time).
  int threads = 0;
  /// The solvers' tuning (advanced_parameters.hpp): the planner's defaults unless set;
  /// validateOptions checks every field's range.
  AdvancedParameters advanced;
};
#pragma GCC diagnostic pop

/// The request asks for the default homotopy class (shortest way, no extra turns) from no guess
/// of its own: only then are the classes enumerated (unless the caller pins the nearest), by
/// Newton for the unconstrained optimum and, under constraints, by the constrained class search
/// (drivers/constrained_classes.hpp).
inline bool classLeftFree(const PlanningProblem& problem, const SolverOptions& options) {
  return problem.direction == RotationDirection::Shortest && problem.extra_revolutions == 0 &&
         !options.warm_start && options.enumerate_classes;
}

/// The time budget withRemainingBudget leaves once the budget is spent.
constexpr double kSpentBudget = 1e-300;

/// `options` with what is left of its time budget after `start` (several solves sharing one
/// budget). A budget of 0 (none) stays 0; a spent one becomes kSpentBudget, so the next solve ends
/// TimedOut at once. Deprecated: kept for API users for one release; the planner itself keeps
/// one budget per request in its solve context (src/planning/problem/solve_context.hpp).
[[deprecated("one budget per request: the planner's SolveContext keeps it")]] inline SolverOptions
withRemainingBudget(const SolverOptions& options, std::chrono::steady_clock::time_point start) {
  SolverOptions remaining = options;
  if (options.time_budget_s > 0) {
    const double used =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    remaining.time_budget_s = std::max(options.time_budget_s - used, kSpentBudget);
  }
  return remaining;
}

/// `remaining` (from withRemainingBudget) has a budget, and nothing of it is left. Deprecated
/// with withRemainingBudget.
[[deprecated("one budget per request: the planner's SolveContext keeps it")]] inline bool
budgetSpent(const SolverOptions& remaining) {
  return remaining.time_budget_s > 0 && remaining.time_budget_s <= kSpentBudget;
}

/// Checks the problem (finite numbers, SPD and physical inertia, T > 0, kMinSteps ≤ N ≤
/// kMaxSteps, `auto` scheme only with an accuracy target, ...): throws InvalidInput naming the
/// field and the value.
void validateProblem(const PlanningProblem& problem);

/// Throws InvalidInput naming `field` and the value unless extra_revolutions ≥ 0.
void requireExtraRevolutions(int extra_revolutions, const std::string& field);

/// Throws StepTooLarge ("increase steps") naming extra_revolutions, the steps and the least N
/// that can represent them, unless a plan of `steps` steps can turn K extra times (2K < N − 2: each
/// step turns less than π rad). A class the grid cannot represent is refused, never answered with
/// another.
void requireRepresentableTurns(int extra_revolutions, int steps);

/// Sets the scheme of `problem` from its name, or lets the planner choose it for "auto"
/// (accuracy.choose_scheme; validateProblem requires an accuracy target then). Throws
/// InvalidInput naming `field`, the value and the accepted names (the schemes and auto).
void applySchemeName(const std::string& text, const std::string& field, PlanningProblem* problem);

/// Checks the solver settings (tolerance finite and > 0, max_iterations ≥ 0, time budget finite
/// and ≥ 0, every advanced parameter in its range): throws InvalidInput naming the option and the
/// value.
void validateOptions(const SolverOptions& options);

/// A node constraint is counted active when its slack to the node bound (a cone's half angle
/// tightened by its margin) is within this fraction of its limit (torque, rate) or this many
/// radians (cones).
constexpr double kActiveConstraintTolerance = 1e-6;

/// The node constraints of `problem` (per-axis bounds and PlanningProblem::constraints) checked
/// on a maneuver's own rows, independently of any solver (transcription/stage_constraints.cpp).
struct ConstraintCheck {
  std::vector<std::string> names;  ///< the keys in force ("actuator_limits" first if bounded)
  double max_violation = 0.0;      ///< worst violation, each in its own unit, ≥ 0
  /// Worst violation of the node bounds (cones tightened by their margin) relative to the
  /// constraint's scale (limit, or 1 rad for cones), ≥ 0.
  double max_relative_violation = 0.0;
  int active = 0;     ///< node constraints at their bound
  std::string worst;  ///< the worst violated constraint, e.g. "|tau_x| <= 0.1 N m"; empty if none
  std::string worst_where;  ///< its violation and node, e.g. "by 0.02 at k = 64 (t = 6.4 s)"
  /// Worst violation of the node bounds the planner imposes (cones tightened by their margin).
  double max_node_bound_violation = 0.0;
  /// Worst violation of the stated limits over the continuous motion between the nodes too
  /// (R_k exp(s ω_k^), torques held; constraints.hpp), each in its own unit, ≥ max_violation.
  double max_violation_between_nodes = 0.0;
  /// The plan meets its node constraints (every relative violation within
  /// kNodeConstraintTolerance): the one test drivers and verdicts apply to a plan.
  bool withinBounds() const { return max_relative_violation <= kNodeConstraintTolerance; }
};
ConstraintCheck checkConstraints(const PlanningProblem& problem, const Maneuver& maneuver);

/// Throws InvalidInput naming the inertia and its principal moments unless J1 + J2 ≥ J3 (a mass
/// distribution exists). validateProblem applies it unless
/// allow_nonphysical_inertia; the dynamics themselves only need SPD.
void requirePhysicalInertia(const Matrix3& inertia);

}  // namespace attitude_planner
