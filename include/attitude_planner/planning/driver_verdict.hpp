// A driver's verdict on a request as data: which kind of answer it is and the figures it rests
// on (PlanResult::verdict, JSON `verdict`). The words of the message are rendered from it in one
// place (renderVerdict, src/planning/problem/message_notes); a caller reads the figures here,
// never from the words.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "attitude_planner/termination.hpp"

namespace attitude_planner {

/// One figure of a verdict by name (JSON `verdict.figures`), in the unit its field states.
struct VerdictFigure {
  std::string name;
  double value = 0.0;
};

namespace verdicts {

/// What the bounds alone prove about the durations of a request's plans on its grid (N =
/// `steps`), said with a verdict that found no plan (the search's): no plan below `least` (the
/// proven lower bound on the grid, `least_basis` its proof; 0: none applies), and none from
/// `no_plan_from` on (the paper scheme's last free step into a final rate on the rate limit has
/// no room up to `no_plan_to`, NoRoomBeforeTheEnd; above `no_plan_to` a step at the boundary
/// rates turns π or more, which no step of the scheme does; 0, 0: none proven). Where both are
/// proven a plan can lie only in [least, no_plan_from) (DurationVerdict holds the same figures:
/// lower_bound's grid value, no_plan_from, no_plan_to).
struct ProvenDurations {
  int steps = 0;
  double least = 0.0;  ///< [s]
  std::string least_basis;
  double no_plan_from = 0.0;  ///< [s]
  double no_plan_to = 0.0;    ///< [s]
  bool rangeProven() const { return no_plan_to > no_plan_from; }
  std::vector<VerdictFigure> figures() const {
    return {
        {"grid_lower_bound", least}, {"no_plan_from", no_plan_from}, {"no_plan_to", no_plan_to}};
  }
};

/// `figures` followed by `proven`'s.
inline std::vector<VerdictFigure> withProven(std::vector<VerdictFigure> figures,
                                             const ProvenDurations& proven) {
  for (const VerdictFigure& f : proven.figures()) figures.push_back(f);
  return figures;
}

/// No driver's verdict: the message is the solver's own reason (and the notes after it).
struct SolverReason {
  static constexpr const char* kKind = "solver_reason";
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// Minimum time between identical rest states: T* = 0 s, the body is there (no solve).
struct AlreadyAtRest {
  static constexpr const char* kKind = "already_at_rest";
  std::vector<VerdictFigure> figures() const { return {{"minimum_duration", 0.0}}; }
};
/// The requested duration lies below the proven lower bound on its grid: infeasible, answered
/// before any solve (DurationVerdict::proven_infeasible).
struct BelowProvenBound {
  static constexpr const char* kKind = "below_proven_bound";
  double lower_bound = 0.0;  ///< T_c [s], the continuous problem's (DurationVerdict::lower_bound)
  std::string basis;         ///< how it is proven (DurationVerdict::lower_bound_basis)
  std::string bounds;        ///< the bounds in force, in the scene's words
  int steps = 0;             ///< N
  double grid_lower_bound = 0.0;  ///< the bound on N steps [s] (≥ lower_bound)
  double requested = 0.0;         ///< the request's T [s] (minimum time: its upper limit)
  bool upper_limit = false;       ///< minimum time: the request asked for T ≤ `requested`
  std::vector<VerdictFigure> figures() const {
    return {{"lower_bound", lower_bound},
            {"steps", double(steps)},
            {"grid_lower_bound", grid_lower_bound},
            {"requested_duration", requested}};
  }
};
/// A phase run on a problem the planner built (a fallback, a probe, a restart) threw an input
/// error: about that problem, not the request (runInternalPhase), so NotConverged.
struct InternalPhaseFailed {
  static constexpr const char* kKind = "internal_phase_failed";
  std::string phase;  ///< "the minimum-time phase", ...
  std::string what;   ///< the error's message
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// Minimum time: no duration admits a plan (`why`: what rules every duration out).
struct InfeasibleAtEveryDuration {
  static constexpr const char* kKind = "infeasible_at_every_duration";
  std::string why;
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// Bounded minimum effort: the requested T lies in a range of durations proven to hold no plan on
/// its grid (DurationVerdict::no_plan_from, no_plan_to; `why`: what has no room there), answered
/// before any solve.
struct NoRoomAtDuration {
  static constexpr const char* kKind = "no_room_at_duration";
  double requested = 0.0;  ///< T [s]
  double from = 0.0;       ///< the range proven without a plan [s]
  double to = 0.0;
  int steps = 0;  ///< N
  std::string why;
  std::vector<VerdictFigure> figures() const {
    return {{"requested_duration", requested},
            {"no_plan_from", from},
            {"no_plan_to", to},
            {"steps", double(steps)}};
  }
};
/// A local "infeasible" at the requested T: no plan was found at T; the least duration at which
/// one was found (a local minimum-time plan, not a requirement) and the proven bound where one
/// applies. The reason it is given follows: the minimum-time solve's (minimum time with T as
/// its upper limit), or in parentheses the minimum-effort solve's at T (`solved_at_requested`).
struct LocallyInfeasible {
  static constexpr const char* kKind = "locally_infeasible";
  double requested = 0.0;    ///< T [s]
  double least_found = 0.0;  ///< T* [s] (DurationVerdict::least_duration_found)
  std::string what_found;    ///< what T* is ("minimum time, a KKT point of ...")
  double lower_bound = 0.0;  ///< T_c [s]; 0: none applies
  std::string basis;         ///< its proof's name (empty with none)
  bool solved_at_requested = false;
  std::vector<VerdictFigure> figures() const {
    return {{"requested_duration", requested},
            {"least_duration_found", least_found},
            {"lower_bound", lower_bound}};
  }
};
/// A bounded minimum-effort request ended infeasible at T, and the minimum-time problem under
/// the same bounds found no feasible duration either (it ended `minimum_time`): a local verdict.
struct MinimumTimeFoundNone {
  static constexpr const char* kKind = "minimum_time_found_none";
  Termination minimum_time = Termination::NotConverged;
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// The minimum-time search was stopped (`stop`: timed out, cancelled; not converged where it
/// spent its own work allowance, `work_allowance` node-iterations, figure "work_allowance")
/// before any duration was found feasible; what the bounds prove about the durations (`proven`).
/// Local: durations the search did not try are not judged.
struct SearchStopped {
  static constexpr const char* kKind = "search_stopped";
  Termination stop = Termination::TimedOut;
  ProvenDurations proven;
  double work_allowance = 0.0;  ///< > 0: the search's own allowance stopped it, not the caller
  std::vector<VerdictFigure> figures() const {
    std::vector<VerdictFigure> f = proven.figures();
    if (work_allowance > 0.0) f.push_back({"work_allowance", work_allowance});
    return f;
  }
};
/// The minimum-time search found no plan below T = `from` (it tried durations down to
/// `least_tried`), and from there on one step at the boundary rates has no solution on N steps;
/// `coarse`: even at the proven least duration a boundary step turns more than 1 rad
/// (StepTooLarge), else NotConverged; what the bounds prove about the durations (`proven`).
struct SearchUnrepresentable {
  static constexpr const char* kKind = "search_unrepresentable";
  double from = 0.0;  ///< [s]
  int steps = 0;      ///< N
  bool coarse = false;
  double least_tried = 0.0;  ///< [s] the least duration a solve was tried at (0: none)
  ProvenDurations proven;
  std::vector<VerdictFigure> figures() const {
    return withProven({{"unrepresentable_from", from},
                       {"steps", double(steps)},
                       {"least_duration_tried", least_tried}},
                      proven);
  }
};
/// The minimum-time search doubled its first guess `doublings` times and found no duration that
/// admits a plan (a local search: every start's solves ended infeasible or unconverged); what the
/// bounds prove about the durations (`proven`).
struct SearchInfeasible {
  static constexpr const char* kKind = "search_infeasible";
  int doublings = 0;
  double first_guess = 0.0;  ///< [s]
  ProvenDurations proven;
  std::vector<VerdictFigure> figures() const {
    return withProven({{"doublings", double(doublings)}, {"first_guess", first_guess}}, proven);
  }
};
/// The search's plan at T* meets every bound while its minimum-effort solve stopped short of
/// optimality: feasible at T*, which is what T* rests on (its reason follows in parentheses).
/// `free_time_iterate`: the plan is a free-time solve's iterate strictly inside every bound (a plan
/// at its T by construction), not a minimum-effort solve's.
struct FeasibleAtMinimumTime {
  static constexpr const char* kKind = "feasible_at_minimum_time";
  double minimum_duration = 0.0;  ///< T* [s]
  bool free_time_iterate = false;
  std::vector<VerdictFigure> figures() const {
    return {{"minimum_duration", minimum_duration},
            {"free_time_iterate", free_time_iterate ? 1.0 : 0.0}};
  }
};
/// A pointing request where no start converged (`starts` twist and way-round starts tried).
struct NoPointingStartConverged {
  static constexpr const char* kKind = "no_pointing_start_converged";
  int starts = 0;
  std::vector<VerdictFigure> figures() const { return {{"starts", double(starts)}}; }
};

/// The NLopt SLSQP cross-check ended (its first reason, crosscheck/nlopt_solver.cpp): NLopt's
/// result, the callbacks' stop reason, and the figures of the replayed plan.
struct NloptEnded {
  static constexpr const char* kKind = "nlopt_ended";
  std::string code;            ///< NLopt's result ("XTOL_REACHED", ...)
  std::string stop_reason;     ///< the callbacks' ("cancelled", ...); empty: none
  std::string exception_text;  ///< what NLopt threw; empty: nothing
  bool converged = false;
  /// NLopt reported success, but the replayed plan misses the terminal constraints.
  bool terminal_unmet = false;
  double violation = 0.0;     ///< the constraint violation of its last iterate
  double stationarity = 0.0;  ///< its relative stationarity residual
  std::vector<VerdictFigure> figures() const {
    return {{"constraint_violation", violation}, {"relative_stationarity", stationarity}};
  }
};

/// A Newton solve on one grid ended (newton/grid_solve): how, after how many iterations, and its
/// first-order figures there.
struct NewtonEnded {
  static constexpr const char* kKind = "newton_ended";
  std::string how;  ///< "converged", "iteration limit reached", ...
  int iterations = 0;
  double relative_gradient = 0.0;
  double relative_decrement = 0.0;  ///< the relative Newton decrement
  std::vector<VerdictFigure> figures() const {
    return {{"iterations", double(iterations)},
            {"relative_gradient", relative_gradient},
            {"relative_newton_decrement", relative_decrement}};
  }
};
/// The interior point on one grid ended (interior_point/grid_solve): how (an infeasible end: the
/// constraint whose violation stopped decreasing and where), after how many iterations, and its
/// figures there.
struct InteriorPointEnded {
  static constexpr const char* kKind = "interior_point_ended";
  std::string how;  ///< "converged", "line search failed ...", "infeasible: ...", ...
  int iterations = 0;
  double relative_decrement = 0.0;  ///< the relative Newton decrement
  double barrier = 0.0;             ///< μ relative to the cost scale
  double max_elastic_violation = 0.0;
  std::vector<VerdictFigure> figures() const {
    return {{"iterations", double(iterations)},
            {"relative_newton_decrement", relative_decrement},
            {"barrier_over_cost", barrier},
            {"max_elastic_violation", max_elastic_violation}};
  }
};
/// A boundary velocity has no step at this h (no reduced problem on this grid): StepTooLarge,
/// before any iteration (Newton or the interior point), or the free-time solve's end before any
/// iteration (`free_time`).
struct NoBoundaryStep {
  static constexpr const char* kKind = "no_boundary_step";
  std::string what;  ///< which velocity and why
  bool free_time = false;
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// A keep-out or keep-in cone is violated at a node the boundary velocities fix (R_1, R_{N−1}):
/// infeasible on this grid before any iteration (the interior point).
struct ConeAtFixedNode {
  static constexpr const char* kKind = "cone_at_fixed_node";
  std::string violation;  ///< the cone, the node and by how much
  std::vector<VerdictFigure> figures() const { return {}; }
};

/// A free-time solve (interior_point/free_time_solver) ended: how, after how many iterations,
/// and the KKT figures of the discrete minimum-time problem there.
struct FreeTimeEnded {
  static constexpr const char* kKind = "free_time_ended";
  std::string how;  ///< "converged", "iteration limit", a watch's or a stop's reason, ...
  int iterations = 0;
  double duration = 0.0;         ///< T = N h [s] at the end
  double stationarity = 0.0;     ///< max |∇L| of the minimum-time Lagrangian
  double time_row = 0.0;         ///< |∂L/∂h|, its h row
  double complementarity = 0.0;  ///< Σ z c
  double smallest_value = 0.0;   ///< min c over the constraint rows
  std::vector<VerdictFigure> figures() const {
    return {{"iterations", double(iterations)},   {"duration", duration},
            {"stationarity", stationarity},       {"time_row", time_row},
            {"complementarity", complementarity}, {"min_constraint_value", smallest_value}};
  }
};
/// A free-time solve's start violates a cone at a node the boundary data fix (R_0, R_N and, where
/// they fix them, R_1, R_{N−1}): no iterate moves it, so no solve (NotConverged).
struct FreeTimeConeAtFixedNode {
  static constexpr const char* kKind = "free_time_cone_at_fixed_node";
  std::string violation;  ///< the cone, the node and by how much
  std::vector<VerdictFigure> figures() const { return {}; }
};
/// A free-time solve found no strictly feasible start (raising h, or the elastic phase where it
/// is not allowed): `why`, no solve (NotConverged).
struct NoStrictlyFeasibleStart {
  static constexpr const char* kKind = "no_strictly_feasible_start";
  std::string why;
  std::vector<VerdictFigure> figures() const { return {}; }
};

/// The minimum-time answer: T* from one free-time solve that ended at a KKT point of the discrete
/// minimum-time problem, second-order sufficient there (a strict local minimum) or not, from
/// `start`; its residuals, and every start solved (each with its T* or how it ended). Not a KKT
/// point (`kkt_point` false): the solve on the requested grid ended short of one at a plan inside
/// every bound, so T* is that plan's T, an upper bound. A failed replay of the plan is the reason
/// it is given, said after it.
struct MinimumTimeAnswer {
  static constexpr const char* kKind = "minimum_time_answer";
  /// One start solved: its name, the earlier start it repeats (empty: none), how it ended and,
  /// converged, its T* and whether that is second-order sufficient (else a saddle).
  struct Start {
    std::string name;
    std::string same_as;
    Termination termination = Termination::NotConverged;
    double duration = 0.0;
    bool second_order_sufficient = false;
  };
  double minimum_duration = 0.0;  ///< T* [s]
  bool kkt_point = true;
  bool second_order_sufficient = false;  ///< only at a KKT point
  std::string start;                     ///< the start the answering solve came from
  int iterations = 0;
  double stationarity = 0.0;
  double time_row = 0.0;
  double complementarity = 0.0;
  std::vector<Start> starts;
  int solves = 0;  ///< free-time solves run
  std::vector<VerdictFigure> figures() const {
    return {{"minimum_duration", minimum_duration},
            {"kkt_point", kkt_point ? 1.0 : 0.0},
            {"second_order_sufficient", second_order_sufficient ? 1.0 : 0.0},
            {"iterations", double(iterations)},
            {"stationarity", stationarity},
            {"time_row", time_row},
            {"complementarity", complementarity},
            {"solves", double(solves)}};
  }
};

}  // namespace verdicts

/// What a driver answered, as data (PlanResult::verdict): the kind and its figures. A solver's
/// first reason is a kind too (NloptEnded, NewtonEnded, InteriorPointEnded, NoBoundaryStep,
/// ConeAtFixedNode, FreeTimeEnded, FreeTimeConeAtFixedNode, NoStrictlyFeasibleStart), and so is
/// the minimum-time answer's account of T* (MinimumTimeAnswer);
/// SolverReason where a solver's reason is still words only.
using Verdict = std::variant<
    verdicts::SolverReason, verdicts::AlreadyAtRest, verdicts::BelowProvenBound,
    verdicts::InternalPhaseFailed, verdicts::InfeasibleAtEveryDuration, verdicts::LocallyInfeasible,
    verdicts::MinimumTimeFoundNone, verdicts::SearchStopped, verdicts::SearchUnrepresentable,
    verdicts::SearchInfeasible, verdicts::FeasibleAtMinimumTime, verdicts::NoPointingStartConverged,
    verdicts::NloptEnded, verdicts::NewtonEnded, verdicts::InteriorPointEnded,
    verdicts::NoBoundaryStep, verdicts::ConeAtFixedNode, verdicts::FreeTimeEnded,
    verdicts::FreeTimeConeAtFixedNode, verdicts::NoStrictlyFeasibleStart,
    verdicts::MinimumTimeAnswer, verdicts::NoRoomAtDuration>;

/// "solver_reason", "below_proven_bound", ... (JSON `verdict.kind`).
inline std::string verdictKindName(const Verdict& verdict) {
  return std::visit([](const auto& v) { return std::string(v.kKind); }, verdict);
}
/// The verdict's figures by name (JSON `verdict.figures`); the words say them, not more.
inline std::vector<VerdictFigure> verdictFigures(const Verdict& verdict) {
  return std::visit([](const auto& v) { return v.figures(); }, verdict);
}

}  // namespace attitude_planner
