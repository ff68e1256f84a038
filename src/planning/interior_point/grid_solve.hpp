// The interior point on one grid: one formulation, one barrier rule, one start (grid_solve.cpp).
#pragma once

#include <functional>
#include <string>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/barrier_update.hpp"
#include "planning/interior_point/constrained_system.hpp"
#include "planning/interior_point/local_lower_bound.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// The largest relative Newton decrement at which a FeasibleIterate is reported: its bound is
/// local, and farther from a minimum the solve may still end elsewhere
/// (docs/notes/interior_point_tuning.md).
inline constexpr double kLocalBoundDecrement = 0.1;

/// An iterate of a minimum-effort interior point (free slacks) that meets every constraint
/// (c ≥ 0), whose barrier Newton matrix is definite without a shift (locally convex there) and
/// whose step is small (relative decrement at most kLocalBoundDecrement).
struct FeasibleIterate {
  double cost = 0.0;  ///< C at the iterate [N²·m²]
  /// C − Σ z c + ½ gᵀΔ (g, Δ: the barrier merit's gradient and Newton step, gᵀΔ < 0): the
  /// Lagrangian's value at the model's minimum, below which the solve cannot end locally
  /// (weak duality in the locally convex region; the barrier problem's minimum lies ½|gᵀΔ|
  /// below the iterate's merit in its quadratic model).
  double lower_bound = 0.0;
  /// √(−gᵀΔ / 2C): the step's relative size (the Newton decrement over |τ|₂).
  double relative_decrement = 0.0;
  int iteration = 0;
  /// Its cost and lower bound, which holds here (definite without a shift).
  LocalLowerBound bound() const { return {cost, lower_bound, true}; }
};

/// Asked at each FeasibleIterate of a solve; a non-empty reason stops it there, NotConverged
/// with that reason and GridOutcome::stopped_by_watch.
using FeasibleIterateWatch = std::function<std::string(const FeasibleIterate&)>;

/// How one grid solve is posed.
struct GridRequest {
  Formulation formulation = Formulation::FreeSlacks;
  BarrierRule barrier = BarrierRule::Mehrotra;
  /// A coarser grid's solution to start from (with a small initial barrier); null: from
  /// options.warm_start (the unconstrained optimum), else the geodesic.
  const ReducedProblem::StepVectors* coarse_steps = nullptr;
  /// The coarser grid's multipliers and slacks (free slacks with Mehrotra only); null: none.
  const LevelDuals* coarse_duals = nullptr;
  /// A solve stopped (cancelled, out of time) on this grid still evaluates its plan; false on a
  /// coarser level of a continuation, whose iterate is carried to the requested grid instead.
  bool evaluate_when_stopped = true;
  /// Where given, asked at every FeasibleIterate (free slacks only).
  const FeasibleIterateWatch* watch = nullptr;
};

/// What one grid solve leaves: its result, its iterate and (free slacks) its duals.
struct GridOutcome {
  PlanResult result;
  ReducedProblem::StepVectors steps;
  LevelDuals duals;
  Formulation formulation = Formulation::FreeSlacks;  ///< of the solve whose result this is
  bool stopped_by_watch = false;  ///< NotConverged because GridRequest::watch stopped it
};

/// The arithmetic of the condensed system (SolverOptions::precision resolved).
enum class SystemPrecision { Double, LongDouble, DoubleDouble };

/// `precision` resolved for N steps: `auto` is double up to N = 1024, long double up to 8192
/// where it is the x87 format, double-double above.
/// Why: at a bound a constraint's condensed term g gᵀ/D (D → 0) exceeds the curvature
/// ∇²f − Σ z∇²c by up to ~1e12, and the smooth modes' curvature falls like N⁻⁴ against the
/// largest (torques are second differences of attitudes); the step along the active constraints'
/// null space depends on that curvature alone. Above 1024 where long double is not x87 (aarch64's
/// is a software quad, slower than double-double) double-double too. The measurements behind the
/// thresholds: docs/notes/interior_point_tuning.md.
SystemPrecision resolvePrecision(Precision precision, int steps);

/// The interior point on one grid in the resolved precision (`options`: this solve's tolerance,
/// iteration limit, warm start). Polls `context` (cancel, deadline) between iterations and inside
/// the assembly and the factorization; an interrupted solve returns its last accepted iterate
/// with Cancelled or TimedOut. Reports its iterations through the context.
GridOutcome solveOnGrid(const PlanningProblem& problem, const SolverOptions& options,
                        const InteriorPointParameters& parameters, SolveContext& context,
                        const GridRequest& request);

/// A coarser level's iterate carried to the requested grid without iterating (a solve stopped
/// on a coarse level: cancelled or out of time), evaluated as a plan, with `termination` and the
/// reason `said` (StepTooLarge if the boundary data admit no step at this N); no plan if the stop
/// came before any level held an iterate (`coarse_steps` empty).
GridOutcome carryToGrid(const PlanningProblem& problem,
                        const ReducedProblem::StepVectors& coarse_steps, Termination termination,
                        const std::vector<MessageClause>& said);

}  // namespace attitude_planner
