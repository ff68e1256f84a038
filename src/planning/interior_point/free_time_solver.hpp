// Minimum time as one interior-point problem: the time step h (T = N h) an unknown next to the
// node unknowns δ of the reduced problem, objective T, the torque constraints, pointing cones and
// rate limits in force (the stage constraints, transcription/stage_constraints.hpp;
// free_time_solver.cpp derives the method).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/local_lower_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// What one free-time solve leaves: the plan's steps at its h, and the KKT residuals of the
/// discrete minimum-time problem at the end.
struct FreeTimeOutcome {
  Termination termination = Termination::NotConverged;
  Verdict verdict;                     ///< how it ended, as data (driver_verdict.hpp)
  std::vector<MessageClause> clauses;  ///< its words as data (recordVerdict)
  std::string message() const { return renderClauses(clauses); }  ///< their fold
  ReducedProblem::StepVectors steps;  ///< the iterate's steps (every iterate meets the constraints)
  double time_step = 0.0;             ///< h at the end
  double start_time_step = 0.0;  ///< h₀: the start's h once strictly feasible (T₀ = N h₀)
  /// The start was brought inside by the elastic phase (c + θ ≥ 0, θ driven to 0) at its own T,
  /// not by raising h (h₀ is then the start's h).
  bool elastic_start = false;
  double duration = 0.0;  ///< T = N h
  int iterations = 0;
  /// max-norm of ∇T − Σ zᵢ∇cᵢ over (δ, h/h₀, and a pointing end's twist ψ) relative to
  /// ∂T/∂(h/h₀) = T₀ (h₀ the start's h): the stationarity of the minimum-time Lagrangian, its h
  /// row (and ψ row) included.
  double stationarity = 0.0;
  double time_row = 0.0;  ///< the h row of that residual alone, same scale
  /// A pointing end's ψ row of that residual, signed (∂L/∂ψ per rad, same scale; 0 without):
  /// the stationarity in the free twist.
  double twist_gradient = 0.0;
  double complementarity = 0.0;             ///< Σ zᵢcᵢ: the duality gap, relative to T₀
  double smallest_value = 0.0;              ///< min cᵢ (> 0: strictly feasible)
  double effort_weight = 0.0;               ///< ε of T + ε C at the end (→ 0 with the barrier)
  Maneuver maneuver;                        ///< the plan at the end (N + 1 nodes on t = k h)
  std::vector<Vector3> torque_multipliers;  ///< z⁺ − z⁻ per node and axis (box bounds)
  /// σ_k = (z⁺ − z⁻)/(a w_k) per axis (box bounds; empty without): minus the τ_k-gradient of
  /// Σ zc per unit weight, the discrete PMP switching function of minimum time (the costate's
  /// projection): τ_k = +a where σ_k > 0, −a where σ_k < 0 (complementarity), crossing zero at
  /// a switch (PlanResult::switching_function).
  std::vector<Vector3> switching_function;
  /// Converged only: the second-order check at the KKT point. The condensed Hessian of the last
  /// barrier problem, W + Σ (zᵢ/cᵢ) gᵢgᵢᵀ over (δ, η) (W the Lagrangian's), factors without a
  /// shift (positive definite): at μ → 0 the barrier terms of the active bounds grow like zᵢ²/μ,
  /// so this is the reduced Hessian on the tangent of the active constraints being positive
  /// definite, the second-order sufficient condition (a strict local minimum). False: a saddle
  /// (or a degenerate point) of the discrete minimum-time problem, not a local minimum.
  bool second_order_sufficient = false;
  /// Where second_order_sufficient is false: the eigenvector of that matrix's least eigenvalue
  /// over δ (n entries, the reduced problem's unknowns), scaled to max |δ_j| = 1 rad; a
  /// direction of negative curvature (displacedAlongNegativeCurvature).
  Eigen::VectorXd negative_curvature;
  /// That least eigenvalue relative to the matrix's mean |diagonal| (0 where sufficient).
  double least_curvature = 0.0;
  /// NotConverged because the caller's BarrierWatch stopped it at a solved barrier problem (the
  /// message says why).
  bool stopped_by_watch = false;
};

/// Where an elastic start (FreeTimeOutcome::elastic_start) begins its barrier: at μ₀, as every
/// free-time solve does, or at a μ on the scale of the start's violations (FromViolations:
/// InteriorPointParameters::elastic_kink_width). The two reach different KKT points from one start.
enum class ElasticBarrier { Initial, FromViolations };

/// Where a start strictly inside (or raised inside) begins its barrier: at μ₀, or (NearKktPoint)
/// at near_kkt_barrier × μ₀ for a start that is already a KKT plan of a neighbouring problem (a
/// fixed-twist minimum-time plan started with the twist free): begun at μ₀ the barrier re-centres
/// such a start and may carry it to another local minimum (free_time_solver.cpp).
enum class StartBarrier { Initial, NearKktPoint };

/// How far a start outside the bounds that move with h is raised before its elastic phase takes
/// over. Bounded: at most InteriorPointParameters::largest_start_raise, for a start whose T is near
/// its answer's (a coarser grid's T*, a plan's own T), whose local violations a raise would trade
/// for a start far from T*. UntilInside: as far as needed where a raise scales every such row
/// down (rest to rest, no wheel momentum; elsewhere Bounded), for a start whose T is a guess (the
/// structured starts: the eigenaxis slew's profile).
enum class StartRaise { Bounded, UntilInside };

/// The scale of a free-time solve's objective T/T₀ + εC (ε = ε₀ μ/μ₀, ε₀ C₀ a fixed share): T₀
/// and C₀. Unset (0), a solve takes its own start's (the raised start's T and effort). Starts on
/// one grid that share one scale solve one family of barrier problems: two of them at the same μ
/// near one local solution are at one point of one central path, which the watch recognizes
/// (sameCentralPath); on their own scales they follow different central paths to the same KKT
/// point, and a start that joins another's basin runs to its end.
struct FreeTimeScale {
  double duration = 0.0;  ///< T₀ [s]
  double cost = 0.0;      ///< C₀ [N² m²], the effort at T₀
  bool set() const { return duration > 0.0 && cost > 0.0; }
};

/// The scale of the start through `attitudes` at T = duration (its T and effort before any raise),
/// for other starts on the same grid to share; unset where the start admits no step.
FreeTimeScale freeTimeScaleOf(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double duration);

/// A solved barrier problem of a free-time solve: its point on the central path at μ.
struct BarrierPoint {
  double mu = 0.0;
  double duration = 0.0;  ///< T [s] of the iterate
  /// T − T₀ (Σ zc + εC) [s]: what the solve can still reach, locally (the local minimum of
  /// T/T₀ + εC lies at most the duality gap below the iterate's value on the central path).
  double lower_bound = 0.0;
  std::vector<Matrix3> attitudes;  ///< R_0 … R_N of the iterate
  int iterations = 0;
  /// The condensed barrier Hessian over (δ, η) factors without a shift at the iterate: a strict
  /// local minimum of this barrier problem, where lower_bound holds locally. (Where it does not,
  /// the solve may still slide to a lower point: measured on Bilimoria–Wie N = 32, a bound of
  /// 3.27871 s at μ = 2.7e-6, then 68 iterations at that μ, the end 3.27774 s.)
  bool locally_convex = false;
  /// Its T [s] and lower bound, which holds where it is locally convex.
  LocalLowerBound bound() const { return {duration, lower_bound, locally_convex}; }
};

/// Called at every solved barrier problem of a feasible free-time solve (not while elastic);
/// a non-empty answer stops the solve there, NotConverged with that message and
/// FreeTimeOutcome::stopped_by_watch.
using BarrierWatch = std::function<std::string(const BarrierPoint&)>;

/// Why `problem` cannot be solved free-time here (empty: it can; minimum_time.cpp falls back to
/// the search otherwise). Every request can today: effects are written in h (their time
/// t_k = k h moves with h: ReducedProblem::forEachStencilWithTimeStep), and fourth_order, which
/// has no single transcription, is the pair of its second_order problems at N and 2N
/// (minimum_time.cpp, fourthOrderMinimumTime). Kept as the one place a future case names itself.
std::string freeTimeUnsupported(const PlanningProblem& problem);

/// One free-time interior-point solve from the plan through `attitudes` (N + 1 of them, R_0 and
/// R_N the problem's) at T = start_duration, raised until every torque constraint holds strictly
/// (a cone must hold strictly at the start's attitudes already, and at the attitudes the boundary
/// data fix: raising T does not move them). If a raise by 2× does not suffice (spinning ends: an
/// end torque carries the boundary momentum, which a slower interior no longer meets), the start
/// stays at its T and is brought inside by an elastic phase instead: the constraints that move
/// with h relaxed to c + θ ≥ 0, θ ≥ 0 one more unknown penalized in the objective, dropped at the
/// first iterate strictly inside every constraint; from then on every iterate is strictly
/// feasible (if that solve fails, it is retried raising h alone). Boundary rates are held at
/// every h. Ends Converged at a KKT point of the discrete minimum-time problem
/// (complementarity within `tolerance`, stationarity within it × max(1, (N/256)²): round-off),
/// NotConverged at the iteration limit or a failed line search (its last iterate still feasible),
/// Cancelled or TimedOut when `context` asks (SolveContext::stopReason every iteration, polled
/// inside the assembly too), and NotConverged (stopped_by_watch) where `watch` stops it. Every
/// iteration (an accepted step, or a barrier update at the same iterate: step length 0) is
/// reported to `context` (SolveContext::reportIteration: the request's iteration callback, and so
/// an action's feedback); a refusal ends the solve Cancelled. FreeTimeOutcome::iterations counts
/// the last run's (the raised one's after an elastic start failed); the solve's are the context's
/// (SolveContext::IterationTally). `scale`: the objective's (FreeTimeScale), the start's own
/// where unset.
FreeTimeOutcome solveFreeTime(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double start_duration, double tolerance, int max_iterations,
                              SolveContext& context, const BarrierWatch& watch = {},
                              ElasticBarrier elastic_barrier = ElasticBarrier::Initial,
                              StartBarrier start_barrier = StartBarrier::Initial,
                              StartRaise start_raise = StartRaise::Bounded,
                              const FreeTimeScale& scale = {});
/// The same in a context of its own with default options (no budget, no callback): for tests and
/// studies that run one free-time solve outside a request. Its iterations: every run's.
FreeTimeOutcome solveFreeTime(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double start_duration, double tolerance, int max_iterations);

}  // namespace attitude_planner
