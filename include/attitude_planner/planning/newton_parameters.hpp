// Every tuning constant of the Newton solver and its strategies, one field per idea, with its
// symbol where the literature has one, its default and why. How the values were chosen (the
// random-suite measurements) is in docs/notes/newton_tuning.md. A user sets them as
// SolverOptions::advanced.newton (advanced_parameters.hpp), which bounds every field.
#pragma once

#include <algorithm>
#include <limits>

namespace attitude_planner {

struct NewtonParameters {
  // --- The Newton step -------------------------------------------------------------------------
  /// Above this N the normal equations (condition ~N⁴, λ_max/λ_min = 7e10 at N = 256) risk losing
  /// the Cholesky factorization to round-off; the augmented system has condition ~N².
  int normal_equations_max_steps = 256;

  // --- Stopping test -----------------------------------------------------------------------------
  /// Least relative torque accuracy (decrement / |τ|₂) a round-off stall counts as converged at.
  double round_off_acceptance_min = 1e-6;
  /// The round-off floor of the decrement is ≈ this × eps·N² (torques are second differences).
  double round_off_floor_factor = 0.5;
  /// A final step is taken when the decrement predicted after it is below this × tolerance.
  double final_step_prediction_margin = 0.1;
  /// −gᵀδ ≤ this × C: the predicted decrease is below the cost's round-off, take the step.
  double negligible_decrease = 1e-13;
  /// A stall at round-off: a decrement that falls by less than this factor ...
  double stall_decrement_ratio = 0.5;
  /// ... for this many consecutive iterations.
  int stall_iterations = 2;
  /// Guard of √(2C) in the relative decrement (a zero-cost iterate).
  double cost_floor = 1e-300;
  /// A predicted decrement below this is reported as "at round-off" (message only).
  double round_off_report = 1e-16;

  // --- Step control: trust region through the Levenberg–Marquardt shift λ (Nielsen) ------------
  /// Most trial steps within one iteration (shift raises and recomputations).
  int max_step_attempts = 80;
  /// λ_min: the first shift tried when H is indefinite (below it λ counts as 0).
  double smallest_shift = 1e-14;
  /// Below this λ a well-predicted step is followed by pure Newton (quadratic convergence).
  double negligible_shift = 1e-7;
  /// λ growth while H + λI is indefinite: fine steps stay near the least definite shift.
  double indefinite_shift_growth = 4;
  /// λ after a rejected pure Newton step.
  double first_rejection_shift = 1e-8;
  /// η: least ratio ρ of actual to predicted decrease accepted.
  double accept_ratio = 1e-4;
  /// Most λ falls after one accepted step (Nielsen: λ·max(1/3, 1 − (2ρ − 1)³); here 1/10).
  double shift_min_factor = 0.1;
  /// ν₀: the first growth of λ after a rejection (Nielsen), doubled after each further one.
  double initial_shift_growth = 2;
  /// ν's own growth factor after each rejection (Nielsen: 2).
  double shift_growth_growth = 2;

  // --- Step control: backtracking line search (one of the more starts) -------------------------
  /// c₁: Armijo's sufficient-decrease constant.
  double armijo = 1e-4;
  /// Most halvings of the step before the shift is raised instead.
  int max_halvings = 40;
  /// The step's contraction per backtrack.
  double backtrack_factor = 0.5;
  /// The next iteration's shift is this × the last (IPOPT's inertia correction uses 1/3).
  double line_search_shift_carry = 0.25;

  // --- Grid continuation -------------------------------------------------------------------------
  /// Coarsest grid of the continuation: below it a solve is already cheap and robust.
  int coarsest_steps = 16;
  /// N of a level ÷ N of the next coarser one.
  int coarsening_factor = 4;
  /// h·|Ω| above this [rad] makes the coarse problem a different, harder one: no coarse level.
  double coarse_max_step_angle = 1.0;
  /// A coarse level only starts the next: it is solved to max(tolerance, this).
  double coarse_tolerance_floor = 1e-6;

  // --- Starts and their order --------------------------------------------------------------------
  /// The class survey (a request that leaves its homotopy class free): every class is solved on
  /// the coarsest level of the request's grid continuation with at least this many steps (the
  /// requested grid if none is coarser). Coarser grids rank the classes' costs too poorly to
  /// choose among them (docs/notes/newton_tuning.md).
  int class_survey_min_steps = 16;
  /// Classes whose survey cost is within this relative margin of the cheapest are all refined to
  /// the requested grid: coarse costs reorder on refinement (docs/notes/newton_tuning.md).
  double class_refine_margin = 0.5;
  /// Where no caller reads the refined classes' plans (a request without node constraints: a
  /// constrained one starts each class's solve from its refined plan and keeps
  /// class_refine_margin), a class other than the request's own is refined only within this
  /// margin of the cheapest survey cost. Measured over 660 seeded requests (rest to rest and
  /// spinning, N = 64–256, docs/notes/newton_tuning.md): the class cheapest on the requested grid
  /// was the request's own or within 1.253× the cheapest survey cost; 0.35 keeps 0.1 above that.
  double unconstrained_refine_margin = 0.35;
  /// Two surveyed classes whose costs agree to this relative difference reached the same extremal
  /// from different starts (a survey is solved to a 1e-6 relative decrement, its cost to ~1e-12):
  /// only the first is refined.
  double same_extremal_cost = 1e-9;
  /// Two converged costs within this relative difference tie (the first start keeps it).
  double cheaper_tie = 1e-12;
  /// Continuation in the boundary rates: most stages (0: not tried; the probes below a
  /// minimum-time T* ask that), the first increment of the rate scale s, its largest, and the
  /// smallest before giving up.
  int rate_continuation_max_stages = 24;
  double rate_continuation_first_increment = 0.25;
  double rate_continuation_max_increment = 0.5;
  double rate_continuation_min_increment = 1.0 / 64;
  /// The coasting start's solve creeps along valleys of negative curvature: it may take this
  /// many times the per-level iteration limit.
  int coasting_iteration_factor = 25;
  /// Stages of the inertia homotopy from the sphere J̄ = tr(J)/3·I to J.
  int inertia_homotopy_stages = 8;
  /// A spinning solve whose kept class took more iterations than this (survey and refinement)
  /// wandered far from its start: that class is solved from more starts and the cheapest kept.
  int more_starts_above_iterations = 40;

  /// Relative decrement accepted as converged when the solve stalls at round-off at N steps.
  double roundOffAcceptance(int steps) const {
    return std::max(round_off_acceptance_min,
                    std::numeric_limits<double>::epsilon() * double(steps) * steps);
  }
  /// Below this relative decrement no iteration can improve the torques at N steps.
  double roundOffFloor(int steps) const {
    return round_off_floor_factor * std::numeric_limits<double>::epsilon() * double(steps) * steps;
  }
};

}  // namespace attitude_planner
