// The verdicts of bounded requests as data (issue "honest verdicts"): what is answered before
// any solve (identical rest states; a duration below the proven lower bound), how an internal
// phase's failure is kept from reaching the user as an input error, and what a local
// "infeasible" records next to the proven bound (verdicts worded by renderVerdict).
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/duration_bound.hpp"

namespace attitude_planner {

/// The answer to `problem` that needs no solve, if any: minimum time between identical rest
/// states without effects (T* = 0: the body is there), a bounded request whose duration lies
/// below the proven lower bound on its grid (Infeasible, DurationVerdict::proven_infeasible), or a
/// bounded minimum-effort request whose duration lies in a range noRoomBeforeTheEnd proves without
/// a plan (Infeasible, proven, the range in DurationVerdict::no_plan_from/to).
std::optional<PlanResult> answerBeforeSolving(const PlanningProblem& problem,
                                              const DurationLowerBound& bound);

/// `solve()` for a problem the planner built itself (a fallback, a probe, a restart): an
/// InvalidInput or StepTooLarge it throws is about that internal problem, not the user's
/// request, so it ends the phase NotConverged with the reason, "<phase> failed: ...".
PlanResult runInternalPhase(const std::string& phase, const std::function<PlanResult()>& solve);

/// Sets `result->duration_verdict`'s bound from `bound`.
void recordLowerBound(const DurationLowerBound& bound, PlanResult* result);

/// The verdict of a local "infeasible" at the requested T (its words: renderVerdict): no plan
/// found at T, the least duration at which one was found (`least_found`, a local minimum-time
/// plan, not a requirement), and the proven bound where one applies; `solved_at_requested`: the
/// reason it is given is the minimum-effort solve's at T.
verdicts::LocallyInfeasible localInfeasibility(double requested, double least_found,
                                               const std::string& what_found,
                                               const DurationLowerBound& bound,
                                               bool solved_at_requested);

/// Why no plan exists at any duration, where that follows from the bounds alone (empty: not
/// shown; the problem may still be infeasible). Shown for a constant body-frame disturbance whose
/// component about a body axis exceeds that axis's torque bound, on a body whose gyroscopic
/// torque about that axis vanishes (the axis principal, the other two moments equal: J = I, an
/// axisymmetric body about it): there J_i ω̇_i = u_i + d_i has the sign of d_i at every
/// instant, so the rate about the axis must move that way by at least (|d_i| − a_i) T / J_i,
/// which boundary rates with no such change (rest to rest) forbid at every T. A start from the
/// free-time solver's raise never gets inside there, and the search ends "infeasible" only after
/// every start has failed (about 16 000 iterations at N = 64).
///
/// Also shown for the paper scheme's last free step into a final rate on the rate limit
/// (noRoomBeforeTheEnd below): where that step has no room at any step h the planner takes.
std::string infeasibleAtEveryDuration(const PlanningProblem& problem);

/// The paper scheme's last free step Ω_{N−2} into the final rate Ω_{N−1} (boundary data) at
/// h = T/N: J Ω_{N−2} = exp(hΩ̂_{N−1}) J Ω_{N−1} − h τ_{N−1} (the scheme's equation at k = N − 1),
/// τ_{N−1} within the torque bounds. A lower bound on the least |Ω_{N−2}| any plan at T has: the
/// least over the ball |τ| ≤ a, a the largest torque magnitude the bounds allow (the norm bound,
/// or a box's corner: a ball that holds every allowed torque), by weak duality (exact to the
/// bisection's round-off for a norm bound). A plan at T needs it at most the rate limit, and at a
/// final rate on the limit the torque-free step leaves the ball by O(h²) while the torque brings
/// it back by O(h): above some T the step has no room (docs/design/planner_behaviour.md,
/// "Spinning ends: a final rate on the rate limit"). +∞ where it does not apply (another scheme,
/// no torque bound, effects).
double leastRateBeforeTheEnd(const PlanningProblem& problem, double duration);

/// Where the last free step has no room (leastRateBeforeTheEnd above every rate limit in force),
/// proven over a range of durations: [from, to] [s] with no plan on the request's grid (0, 0:
/// none proven). Proven over intervals of h: leastRateBeforeTheEnd is Lipschitz in h with
/// constant λ_max(J⁻¹)(|Ω_{N−1}| |J Ω_{N−1}| + a), so its values at the ends of an interval bound
/// it inside; intervals are split until that holds or a duration with room is found. The range
/// searched: from the proven least duration on the grid (discreteDurationLowerBound) up to the
/// largest step the planner takes at the boundary rates (h |Ω| < π), from its top down.
struct NoRoomBeforeTheEnd {
  double from = 0.0;
  double to = 0.0;
  bool everywhere = false;  ///< the whole range searched: no plan at any duration on this grid
};
NoRoomBeforeTheEnd noRoomBeforeTheEnd(const PlanningProblem& problem);

/// What the bounds prove about `problem`'s durations on its grid, for a verdict that found no
/// plan: no plan below its proven lower bound on the grid (discreteDurationLowerBound) and none in
/// `none`'s range or above it.
verdicts::ProvenDurations provenDurations(const PlanningProblem& problem,
                                          const NoRoomBeforeTheEnd& none);

/// Sets `result->duration_verdict`'s range without a plan (no_plan_from, no_plan_to) from `none`
/// where it proves one.
void recordNoRoom(const NoRoomBeforeTheEnd& none, PlanResult* result);

}  // namespace attitude_planner
