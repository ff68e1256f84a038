// The free-time recipe: one minimum-time solve on one grid by the free-time interior point
// (interior_point/free_time_solver.hpp), its start placed, its retry and the second-order check
// of its end (free_time_recipe.cpp). Minimum time's drivers (minimum_time_free_time.hpp) call it
// once per start and level.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "planning/interior_point/free_time_solver.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// How far a start outside the bounds that move with h is raised before its elastic phase takes
/// over. Bounded: at most InteriorPointParameters::largest_start_raise, for a start whose T is near
/// its answer's (a coarser grid's T*, a plan's own T), whose local violations a raise would trade
/// for a start far from T*. UntilInside: as far as needed where a raise scales every such row
/// down (rest to rest, no wheel momentum; elsewhere Bounded), for a start whose T is a guess (the
/// structured starts: the eigenaxis slew's profile).
enum class StartRaise { Bounded, UntilInside };

/// The scale of the start through `attitudes` at T = duration (its T and effort before any raise),
/// for other starts on the same grid to share; unset where the start admits no step.
FreeTimeScale freeTimeScaleOf(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double duration);

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
