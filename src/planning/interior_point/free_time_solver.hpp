// Minimum time as one interior-point problem: the time step h (T = N h) an unknown next to the
// node unknowns δ, objective T, the stage constraints in force (the method:
// docs/notes/interior_point_formulation.md). Where a solve begins, its retry and the second-order
// check of its end are its recipe's (drivers/free_time_recipe.hpp: solveFreeTime).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/local_lower_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"

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
  /// The start was brought inside by the elastic phase (the rows that move with h ℓ1-elastic) at
  /// its own T, not by raising h (h₀ is then the start's h).
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
/// such a start and may carry it to another local minimum.
enum class StartBarrier { Initial, NearKktPoint };

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
  /// local minimum of this barrier problem, where lower_bound holds locally (elsewhere the solve
  /// may still slide below it).
  bool locally_convex = false;
  /// Its T [s] and lower bound, which holds where it is locally convex.
  LocalLowerBound bound() const { return {duration, lower_bound, locally_convex}; }
};

/// Called at every solved barrier problem of a feasible free-time solve (not while elastic);
/// a non-empty answer stops the solve there, NotConverged with that message and
/// FreeTimeOutcome::stopped_by_watch.
using BarrierWatch = std::function<std::string(const BarrierPoint&)>;

/// The free-time barrier problem as its recipe sees it (drivers/free_time_recipe.cpp): the rows'
/// values at the iterate, where the solve begins, the solve, and the Newton matrix it ends at.
class FreeTimeProblem {
 public:
  virtual ~FreeTimeProblem() = default;
  /// The least value at the iterate of the constraints that move with h (`moves_with_h`) or of
  /// the others (the cones), never relaxed.
  virtual double smallestValue(bool moves_with_h) const = 0;
  /// Begins at the iterate's h (h₀ = h, T₀ = N h₀): strictly inside every constraint, or
  /// (`elastic`) with the constraints that move with h ℓ1-elastic until the iterate is inside them.
  virtual void beginAt(bool elastic) = 0;
  /// The solve from there (solveFreeTime's contract, without the second-order check's fields).
  virtual FreeTimeOutcome run(double tolerance, int max_iterations, SolveContext& context,
                              const BarrierWatch& watch) = 0;
  /// Whether the condensed barrier Hessian assembled at the iterate factors without a shift.
  virtual bool barrierHessianDefinite() const = 0;
  /// That matrix's least eigenpair (leastEigenpair, kkt_system.hpp).
  virtual std::optional<LeastEigenpair> barrierHessianLeastEigenpair() const = 0;
};

/// The free-time profile of the barrier problem over `np` (which its iterates move), the
/// constraints `constraints` of `problem` in force: where its barrier begins (ElasticBarrier,
/// StartBarrier) and the objective's scale (FreeTimeScale: the start's own where unset).
std::unique_ptr<FreeTimeProblem> makeFreeTimeProblem(
    const PlanningProblem& problem, ReducedProblem* np, const StageConstraints& constraints,
    const InteriorPointParameters& parameters, ElasticBarrier elastic_barrier,
    StartBarrier start_barrier, const FreeTimeScale& scale);

}  // namespace attitude_planner
