// The interior point's tuning constants, each with its symbol in the paper it follows (IPOPT:
// Wächter & Biegler, Math. Program. 106 (2006); LOQO: Vanderbei & Shanno, Comput. Optim. Appl. 13
// (1999); Mehrotra, SIAM J. Optim. 2 (1992)), its default and why. How the defaults were chosen
// (the measurements behind them) is in docs/notes/interior_point_tuning.md. One struct: the
// constants once, and where the two problems the interior point solves (fixed h, free time) take
// different values of one idea, two named profiles of InteriorPointProfile. A user sets them as
// SolverOptions::advanced.interior_point (advanced_parameters.hpp), which bounds every field.
#pragma once

namespace attitude_planner {

/// A plan meets its node constraints when no violation exceeds this fraction of the constraint's
/// scale (ConstraintCheck::max_relative_violation); the interior-point solver stops on the same
/// figure for its elastic violations.
constexpr double kNodeConstraintTolerance = 1e-8;

/// The values of one idea that differ between the interior point's two problems: fixed h (the
/// constrained minimum effort: objective C, scale f_scale = the start's cost) and free time
/// (minimum time: objective T/T₀ + εC, scale 1). Each field's unit is its problem's scale.
struct InteriorPointProfile {
  /// μ₀ × f_scale/m (m constraints): fixed h starts the barrier terms as large as the cost, free
  /// time at a tenth of the objective T/T₀ = 1.
  double initial_barrier;
  /// Monotone μ rule (IPOPT θ_μ): superlinear decrease μ ← μ^θ_μ (scaled). Free time below
  /// IPOPT's 1.5: a steeper fall sent the next steps halving their way into the active bounds for
  /// ~6 iterations per barrier level (one solve, Bilimoria–Wie N = 256: 50 → 38 iterations; Betts
  /// N = 64: 85 → 53).
  double theta_mu;
  /// Most halvings of the line search (free time fewer: a step of 1e-12 in η is no progress in
  /// T) ...
  int max_halvings;
  /// ... and at the round-off floor (fixed h: where a 32× shortened step is no progress; free
  /// time: max_halvings' value, its floor's round-off steps are not tried at all).
  int floor_halvings;
  /// First shift of the inertia correction (IPOPT δ_w⁰): fixed h relative to each row's diagonal,
  /// a round-off nudge; free time relative to the mean |diagonal|, which the border's corner and
  /// the barrier terms dominate.
  double first_shift;
  /// Elastic ρ₀ × f_scale: far above the multipliers met in practice (fixed h: a binding z is ~
  /// f/N; free time: the relaxed problem's minimum has v = 0 above every multiplier).
  double initial_penalty;
  /// ρ ← this × ρ: fixed h once before a request is called infeasible, free time whenever a
  /// barrier problem is solved with the iterate still outside.
  double penalty_growth;
};

/// Fixed h (grid_solve.cpp, drivers/constrained_recipe.cpp).
constexpr InteriorPointProfile kFixedStepProfile{1.0, 1.5, 60, 5, 1e-14, 1e4, 1e4};
/// Free time (free_time_solver.cpp).
constexpr InteriorPointProfile kFreeTimeProfile{0.1, 1.3, 40, 40, 1e-10, 100.0, 10.0};

/// Every constant of the interior point (grid_solve.cpp, free_time_solver.cpp). Scales:
/// μ and ρ relative to f_scale/m (the start's cost over the number of constraints), decrements
/// relative to √(2 f_scale).
struct InteriorPointParameters {
  InteriorPointProfile fixed_step = kFixedStepProfile;  ///< the constrained minimum effort
  InteriorPointProfile free_time = kFreeTimeProfile;    ///< minimum time

  // --- barrier μ -------------------------------------------------------------------------------
  /// μ₀ × f_scale/m on a grid started from a coarser grid's solution: its active set is nearly
  /// right and a small barrier keeps the iterate near it.
  double warm_barrier = 1e-3;
  /// μ_final = this × tolerance × f_scale/m: the barrier's cost gap (the duality gap Σ zc ≈ m μ)
  /// stays below the tolerance.
  double final_barrier_fraction = 0.1;
  /// Above this N μ_final grows like N: a torque constraint's value carries round-off ~ N.
  int final_barrier_round_off_steps = 2048;
  /// μ within this factor of μ_final is snapped to it (complementarity there is round-off).
  double barrier_snap_factor = 10.0;
  /// Mehrotra: σ = (μ_aff / mean s z)^this (Mehrotra's cube).
  double mehrotra_exponent = 3.0;
  /// Mehrotra: μ ≥ this × d² × f_scale/m (d the last relative decrement) at N ≤ 1024; a μ far
  /// below the iterate's distance to the barrier problem leaves Newton an ill-conditioned system.
  double barrier_progress_floor = 0.01;
  /// The progress floor grows like (N / this)² above this N.
  int barrier_progress_floor_steps = 1024;
  /// Monotone (IPOPT κ_ε): the barrier problem counts as solved once its decrement and slack
  /// residual are ≤ κ_ε μ (scaled).
  double monotone_kappa_epsilon = 10.0;
  /// Monotone (IPOPT κ_μ): linear decrease μ ← κ_μ μ.
  double monotone_kappa_mu = 0.2;
  /// (Monotone θ_μ is a profile's: the smaller of the two decreases.)
  /// Monotone: full steps in a row that no longer halve the decrement after which a barrier
  /// problem counts as solved as far as round-off allows.
  int monotone_stalled_steps = 2;
  /// LOQO: σ = loqo_scale · min(loqo_centrality (1 − ξ)/ξ, loqo_cap)³ (Vanderbei–Shanno's 0.1,
  /// 0.05, 2).
  double loqo_scale = 0.1;
  double loqo_centrality = 0.05;
  double loqo_cap = 2.0;

  // --- primal–dual safeguards ------------------------------------------------------------------
  /// Fraction to the boundary (IPOPT τ_min): s and z keep at least 1 − τ of their values.
  double fraction_to_boundary = 0.99;
  /// Dual safeguard (IPOPT κ_Σ): z stays within [μ/(κ_Σ s), κ_Σ μ/s].
  double dual_safeguard = 1e10;
  /// Elastic form: u = ρ − z ≥ this × ρ (u → 0 would make D and q infinite).
  double elastic_dual_floor = 1e-12;
  /// Free slacks start at c pushed inside s > 0 by this (IPOPT κ₁).
  double slack_push = 1e-2;
  /// From a coarser level's duals a binding constraint's slack is pushed at most this far inside.
  double warm_slack_push = 1e-6;
  /// Initial multipliers are capped at this × f_scale/m (a violated constraint's primal
  /// multiplier ≈ ρ would swamp the Hessian).
  double initial_multiplier_cap = 10.0;

  // --- penalty (elastic ρ: a profile's; free-slack merit ν) ------------------------------------
  /// A violation above this is not a penalty below a multiplier: no raise, infeasible.
  double penalty_raise_violation = 1e-3;
  /// ν ≥ this × the largest multiplier after the step (the ℓ1 merit is exact above it).
  double merit_multiplier_margin = 1.1;
  /// ν large enough that the step decreases the merit by this fraction of its predicted
  /// infeasibility reduction (IPOPT's ρ in the penalty update).
  double merit_infeasibility_fraction = 0.1;

  // --- inertia correction ----------------------------------------------------------------------
  /// Factorizations tried with growing shifts before the system counts as not positive definite.
  int max_inertia_corrections = 40;
  /// δ_w ← this × δ_w after a failed factorization (IPOPT's κ̄_w⁺, the first growth).
  double shift_growth = 100.0;
  /// The shift's floor per row: this × the largest diagonal (rows of zero scale still move).
  double shift_row_floor = 1e-8;
  /// After a failed line search the shift floor rises to max(this, 100 × floor) ...
  double line_search_shift = 1e-8;
  /// ... while it is below this; a direction rejected once it is not ends the solve. (1e-8 × 100³
  /// rounds to just below 1e-2, so with these defaults the last raise takes the floor to about 1:
  /// test_kkt_system measures the schedule.)
  double max_shift_floor = 1e-2;
  /// A shift this small is round-off, not a change of the step.
  double negligible_shift = 1e-12;

  // --- line search -----------------------------------------------------------------------------
  /// Armijo's sufficient-decrease constant (IPOPT η_φ).
  double armijo = 1e-4;
  /// A predicted merit decrease below this × |φ| is round-off: the step is taken (fixed h), or
  /// searched, and not tried at the round-off floor (free time).
  double merit_round_off = 1e-14;

  // --- stopping test ---------------------------------------------------------------------------
  /// Relative decrement below which a stall at μ_final counts as converged (at N ≤ 1024) ...
  double stall_acceptance = 1e-6;
  /// ... growing like N above this N (measured round-off floors).
  int stall_acceptance_steps = 1024;
  /// A full step that leaves the decrement above this × the previous one does not progress.
  double stall_ratio = 0.5;
  /// Stalled iterations at μ_final that end the solve.
  int stalled_iterations = 2;
  /// Quadratic finish: the last step was at least this long ...
  double quadratic_step = 0.9;
  /// ... and the predicted next decrement is ≤ this × the stall acceptance.
  double quadratic_margin = 0.1;
  /// Mehrotra: decrements ≤ this × stall acceptance are the round-off floor (the last step).
  double reachable_fraction = 0.01;
  /// At μ_final, feasible, decrement ≤ this × stall acceptance: the round-off floor.
  double floor_factor = 10.0;
  /// Iterations without reducing a nonzero violation after which it counts as stalled (elastic,
  /// free slacks: whose iterates may violate more for a while on their way).
  int violation_stall = 8;
  int free_slack_violation_stall = 40;
  /// A violation counts as reduced when it falls by more than this fraction.
  double violation_progress = 1e-6;
  /// Violation (constraint units) that counts as infeasible.
  double feasibility_tolerance = kNodeConstraintTolerance;
  /// A slack residual |c − s| below this is round-off: not in the free-slack decrement.
  double round_off_slack_residual = 1e-10;

  // --- scales ----------------------------------------------------------------------------------
  /// f_scale ≥ this × ½ N |J θ/T²|² so that a free coast still has a scale ...
  double cost_scale_floor = 1e-6;
  /// ... with θ at least this [rad].
  double angle_floor = 1e-3;

  // --- minimum time's own strategies (free_time_solver.cpp, inertia_correction.cpp; the start --
  // raise: drivers/free_time_recipe.cpp) -------------------------------------------------------
  /// The start's h grows by this factor until every constraint that moves with h holds with the
  /// start margin (torques scale like 1/h²: a few percent per growth keeps T₀ near the least
  /// feasible T of the start's path).
  double start_growth = 1.05;
  /// ... with c ≥ this: a start on its bounds would begin with infinite barrier terms.
  double start_margin = 0.05;
  /// ... at most this many growths (1.05⁴⁰⁰ ≈ 3e8: a start no slower plan makes feasible).
  int max_start_growths = 400;
  /// A bounded raise (StartRaise::Bounded) stops at this factor and the elastic start takes over:
  /// with spinning ends a raise at fixed attitudes does not scale every torque down (an end torque
  /// carries the boundary momentum, 2√w JΩ/h, which a slower interior no longer meets), so a start
  /// a little outside its bounds at T was raised to 52 T before every bound held (a prolonged
  /// N = 128 answer on N = 256, docs/results/minimum_time.md "Spinning ends") and the solve,
  /// started that far from T*, stopped at the iteration limit. Rest to rest every such
  /// constraint falls with h and a raise of a few percent suffices.
  double largest_start_raise = 2.0;
  /// A start that is a neighbouring problem's KKT plan (StartBarrier::NearKktPoint) begins its
  /// barrier at this × μ₀.
  double near_kkt_barrier = 1e-2;
  /// ElasticBarrier::FromViolations: the elastic phase's first μ puts the width μ/ρ of an elastic
  /// row's kink (where its merit turns from ρ|c| to −μ ln c) at this fraction of the largest
  /// violation. At μ₀ (about 0.1/m) the kink is far narrower than the violations of a spinning
  /// start (c down to −50), the merit is ℓ1 in all but name and its Newton model sees no curvature
  /// there (measured: 500 iterations of steps α ≈ 1e-4–1e-2); at the wider kink the starts reach
  /// KKT points more often, in other basins (docs/design/planner_behaviour.md).
  double elastic_kink_width = 0.1;
  /// After a system that needed a shift the next one resumes at that shift ÷ this (1/IPOPT κ_w⁻)
  /// ...
  double resumed_shift_divisor = 3.0;
  /// ... and grows by this (IPOPT κ_w⁺) instead of shift_growth ...
  double resumed_shift_growth = 8.0;
  /// ... down to this (IPOPT's δ_w^min): a floor at the first shift swamped the soft directions'
  /// curvature once the barrier terms of active bounds make the mean diagonal ~1e11 (N ≥ 1024)
  /// and stalled the refinement.
  double smallest_resumed_shift = 1e-20;
  /// The largest shift (relative to the mean |diagonal|) before the step counts as failed.
  double max_uniform_shift = 1e10;
  /// Steps the line search cut below this length ...
  double damping_cut_step = 1.0 / 16;
  /// ... this many times in a row damp the next Newton steps (a shift from the first shift up,
  /// PerturbationHandler::afterStep): where minimum time is flat along an arc the undamped step
  /// runs into the constraints' curvature (0.96 N m about body x against |u_x| ≤ 1, N = 64: 500
  /// iterations without converging; damped, a KKT point in 380). Two: one damped after a single
  /// cut step, common on the way. Measured (N = 64, plan_maneuver): T* the same to the last digit
  /// on Bilimoria–Wie, Betts, the cone and the cone + rate rows, iterations 397 → 292, 188 → 188,
  /// 1123 → 1129, 1117 → 1127.
  int damping_cut_steps = 2;
  /// ... once the barrier μ is at most this × its start μ₀ (the end game: where the basin is
  /// chosen, at the first barrier levels, damped steps took paper on min_time_keep_out.yaml
  /// N = 32 to a higher KKT point, 29.7404 s instead of 29.7113 s). In the end game too each
  /// rejected trial step, the full one and every halving, is retried with its second-order
  /// correction (line_search.cpp correctedTrial, free_time_solver.cpp correctedStep): there the
  /// torque bounds' curvature, not the basin, cuts the steps (every halving too, not the full
  /// step alone: docs/results/minimum_time_step.md). Measured with the full step alone:
  /// plan_maneuver, free-time iterations of all starts: 0.96 N m about body x
  /// against |u_x| ≤ 1, N = 64: 1188 → 520, N = 128: a KKT point in 867 (before: the iteration
  /// limit, the search's answer); 0.99 N m, N = 64: a KKT point in 673 (before: the search). At
  /// every μ the correction changed the basin: paper around the keep-out cone took 310 → 529
  /// iterations at N = 64 (the eigenaxis start left its saddle), the same T*.
  double damped_barrier = 1e-2;
  /// The damping grows by this factor per further cut step and falls by it per full step ...
  double damping_growth = 10.0;
  /// ... down to this, then none.
  double smallest_damping = 1e-14;

  // --- grids -----------------------------------------------------------------------------------
  /// Above this N the constrained problem is first solved on coarser grids (down to 16 steps).
  int coarsest_grid = 256;
  /// N of a level ÷ N of the next coarser one.
  int coarsening_factor = 4;
};

}  // namespace attitude_planner
