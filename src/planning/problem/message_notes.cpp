// The wording of every clause of message_notes.hpp, in one place.
#include "planning/problem/message_notes.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {
namespace {

using namespace notes;

std::string grid(int steps) {
  return "N = " + std::to_string(steps);
}

std::string words(const FormulationRetry& n) {
  if (n.within_bounds) {
    return "; answered with " + n.retry + "'s plan, within the bounds, after " + n.first +
           " ended outside them: " + renderClauses(n.reason);
  }
  return (n.solved ? "; solved with " + n.retry + " after " + n.first + " stopped: "
                   : "; retried with " + n.retry + ": ") +
         renderClauses(n.reason);
}
std::string words(const ReachedThroughMiddle& n) {
  return "; reached through " + grid(n.steps) +
         " after the direct refinement stopped: " + renderClauses(n.reason);
}
std::string words(const GridContinuation& n) {
  return "; grid continuation from " + grid(n.steps);
}
std::string words(const RetriedInTwoStages& n) {
  return "; retried in two stages (the cones alone, then every constraint from that path) "
         "after: " +
         renderClauses(n.reason);
}
std::string words(const FromInitialGuess&) {
  return "; from the initial guess, its multipliers re-derived";
}
std::string words(const CoarserLevel& n) {
  if (n.termination == Termination::Converged)
    return "; started from the " + grid(n.steps) + " solution";
  return "; the " + grid(n.steps) + " level ended " + terminationName(n.termination) +
         ", started from the geodesic";
}
std::string words(const RefinedFromSurvey& n) {
  return "; refined from the " + grid(n.steps) + " class survey";
}
std::string words(const ConstraintsInactive&) {
  return "; constraints inactive at the unconstrained optimum";
}
std::string words(const UnconstrainedStart& n) {
  std::ostringstream s;
  s << "; the unconstrained optimum (cost " << n.cost << ") violates ";
  if (n.worst.empty()) {
    s << "a cone's margin";  // the stated limits hold, a tightened node bound does not
  } else {
    s << n.worst << " " << n.where;
  }
  s << " and started it (" << n.newton_iterations << " Newton iterations)";
  return s.str();
}
std::string words(const AfterGuessStopped& n) {
  return "; after the start from the initial guess stopped: " + renderClauses(n.reason);
}
std::string words(const LastIterateDoesNotReplay& n) {
  return "; its last iterate's torques do not replay: " + n.reason;
}
std::string words(const OpenLoopReplayParted& n) {
  std::ostringstream s;
  s << "; its torques replayed open-loop from R_0, Omega_0 part from it until a step has no root ("
    << n.what << "): round-off grows along this unstable motion, so replay_miss is infinite (a "
    << "sensitivity: a tracker needs feedback), while every step replayed from the plan's own "
    << "state lands on its step (within " << n.step_angle << " rad)";
  return s.str();
}
std::string words(const CheapestClass& n) {
  return "; the cheapest homotopy class under the constraints (after the unconstrained "
         "optimum's class: " +
         renderClauses(n.reason) + ")";
}
std::string words(const ConesTightenedBetweenNodes& n) {
  return "; the cones' node bounds tightened by up to " + exactNumber(n.margin) +
         " rad (the class's plan at the nodes' bounds cut a cone by " + exactNumber(n.cut) +
         " rad between two nodes; this margin keeps the motion between the nodes outside it)";
}
std::string words(const LastPointingStart& n) {
  return "; the last: " + n.reason;
}
std::string words(const FixedTwistFallback& n) {
  return "; answered with the fixed-attitude plan at twist " + exactNumber(n.twist) +
         " rad (converged there; the twist is not optimized: the free-twist solves did not "
         "converge, the last: " +
         n.reason + ")";
}
std::string words(const PointingRestartNotServed& n) {
  return "; not infeasible: minimum time with the twist free reaches T* = " +
         exactNumber(n.minimum_duration) +
         " s <= T, but the restart from its plan (a warm-started pointing solve) is not served yet";
}
std::string words(const SearchSummary& n) {
  return n.summary;
}
std::string foundBelow(double duration, double previous) {
  return "; a plan was found at " + exactNumber(duration) +
         " s, below the T* = " + exactNumber(previous) + " s reached before";
}
std::string words(const DescendedFromProbe& n) {
  return foundBelow(n.duration, n.previous) + ", and the free-time solve from it descended";
}
std::string words(const ProbesStopped& n) {
  return "; the probes below T* stopped at their work allowance (" + exactNumber(n.work_allowance) +
         " node-iterations): a lower T* may exist";
}
std::string words(const SearchedOnT& n) {
  return "; searched on T (" + n.why + ")";
}
std::string words(const SharpenedFromSearch& n) {
  return "; the structured starts did not converge (" + n.why +
         "), the search found T = " + exactNumber(n.duration) + " s";
}
std::string words(const PlannedAtMargin& n) {
  std::ostringstream s;
  s << "; planned at (1 + " << n.margin << ") T* = " << n.duration
    << " s from the T* plan (minimum time T* = " << n.minimum_duration << " s)";
  return s.str();
}
std::string words(const MinimumTimeRestart& n) {
  std::string s = "; started from the minimum-time plan (T* = " + exactNumber(n.minimum_duration) +
                  " s) after the first solve " + n.why;
  if (n.ladder_reached) {
    s += ", reached by a ladder of durations from T* (the direct start ended " +
         terminationName(n.direct) + ")";
  } else if (n.ladder_tried) {
    s += "; a ladder of durations from T* " +
         (n.ladder_longest > 0.0 ? "found plans within the bounds up to T = " +
                                       exactNumber(n.ladder_longest) + " s, not at T"
                                 : std::string("found no plan within the bounds above T*"));
  }
  return s;
}
std::string words(const RestartEnded& n) {
  return ": " + terminationName(n.termination) + " (" + renderClauses(n.reason) + ")";
}
std::string words(const MinimumTimeUnsolved& n) {
  return "; the first solve " + n.why +
         " and the minimum-time problem under the same bounds did not converge (" +
         terminationName(n.termination) + ")";
}

std::string words(const PlanWithinBounds& n) {
  return "; its plan meets the dynamics, the ends and every bound at T = " +
         exactNumber(n.duration) + " s: a plan at T, not shown optimal";
}

std::string words(const PointingTwist& n) {
  std::ostringstream s;
  s << "; pointing: twist " << n.twist << " rad, ";
  if (n.lagrangian) {
    s << "d L/d twist " << n.gradient << " (relative " << n.relative << ")";
  } else {
    s << "d cost/d twist " << n.gradient;
  }
  return s.str();
}

/// printf's %.3g (the accuracy clauses' figures).
std::string threeDigits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}
std::string words(const AccuracyReached& n) {
  return "; " + n.measure + " " + threeDigits(n.error) + " <= target " + threeDigits(n.target) +
         " at " + grid(n.steps) + " (" + n.scheme + ")";
}

std::string words(const frames::RichardsonPair& p) {
  return "fourth_order (Richardson extrapolation of second_order at " + grid(p.steps) +
         " and 2N = " + std::to_string(2 * p.steps) +
         (p.from_plans_at_minimum_time ? ", each from its plan at T*)" : ")");
}
std::string framed(const frames::PairSolveStopped& f, const std::string& reason) {
  return words(f.pair) + ": the second_order solve at " + grid(f.stopped_steps) +
         " did not converge (its plan is returned): " + reason;
}
std::string framed(const frames::PairCombined& f, const std::string& reason) {
  return words(f.pair) +
         (f.replaced ? ": the plan is the second_order plan at N (the Richardson combination left "
                       "a bound both meet)"
                     : "") +
         ": N: " + reason + " | 2N: " + renderClauses(f.fine_reason);
}
std::string minimumTimePair(int steps) {
  return "fourth_order minimum time (the second_order minimum-time problems at " + grid(steps) +
         " and 2N = " + std::to_string(2 * steps) + ")";
}
std::string framed(const frames::MinimumTimePairStopped& f, const std::string& reason) {
  const std::string at = f.at_fine ? "2N" : "N";
  return minimumTimePair(f.steps) + ": " +
         (f.effort_at_minimum_time ? "the minimum-effort plan at T* at " + at
                                   : "the one at " + at) +
         " did not converge (its plan is returned): " + reason;
}
std::string framed(const frames::MinimumTimePairCombined& f, const std::string& reason) {
  std::ostringstream s;
  s << minimumTimePair(f.steps) << ": T* = " << exactNumber(f.minimum_duration) << " s, the one at "
    << (f.fine_binds ? "2N" : "N") << " binds (T* at N = " << exactNumber(f.at_coarse)
    << " s, at 2N = " << exactNumber(f.at_fine) << " s); "
    << (f.replaced ? "the plan is the second_order plan at N at T*: the Richardson combination "
                     "with the 2N plan left a bound both meet"
                   : "the plan combines the binding plan and the other's minimum-effort plan "
                     "at T*")
    << " | 2N: " << renderClauses(f.fine_reason) << " | N: " << reason;
  return s.str();
}
std::string framed(const frames::UpperBoundFromProbe& f, const std::string& reason) {
  return "minimum time T* <= " + exactNumber(f.duration) +
         " s, the least duration found feasible (an upper bound)" +
         foundBelow(f.duration, f.previous) + " (the plan found there is returned): " + reason;
}
std::string framed(const frames::StuckAtMinimumTimePlan& f, const std::string& reason) {
  std::ostringstream why;
  if (f.rest_to_rest) {
    why << "not converged (feasible: T* = " << exactNumber(f.minimum_duration)
        << " s <= the requested duration and the ends are at rest, but the minimum-effort solve "
           "from the minimum-time plan ended at an infeasible point): ";
  } else if (f.ladder_reached > 0.0) {
    why << "infeasible from here (a local verdict): no plan within the bounds was found at T = "
        << exactNumber(f.requested)
        << " s; from the minimum-time plan (T* = " << exactNumber(f.minimum_duration)
        << " s) plans within the bounds were found up to T = " << exactNumber(f.ladder_reached)
        << " s, where the ladder of durations stopped (spinning ends: not a limit, other classes "
           "may hold plans at T): ";
  } else {
    why << "not converged (a plan within the bounds exists at T* = "
        << exactNumber(f.minimum_duration)
        << " s < T, but with spinning ends a longer duration need not be feasible in its class; "
           "the solves from it ended at infeasible points): ";
  }
  return why.str() + reason;
}
std::string framed(const frames::OutsideRequestedClass& f, const std::string& reason) {
  return "not converged in the requested class: " + f.why + " (" + reason + ")";
}
std::string framed(const frames::ReplayFailed& f, const std::string& reason) {
  std::ostringstream s;
  s << "not converged: the plan's step k = " << f.step
    << " is not the step the replay solves from the plan's own state there (";
  if (std::isfinite(f.angle)) {
    s << f.angle << " rad apart: another root of the step's momentum map";
  } else {
    s << "no root found";
  }
  s << "), and its torques replayed open-loop fail: " << f.what << " (" << reason << ")";
  return s.str();
}
std::string framed(const frames::PointingStarts& f, const std::string& reason) {
  if (f.starts.empty()) return "pointing: no start twist was solved";
  std::ostringstream note;
  note << "pointing: " << f.starts.size() << " start twists (T* per start:";
  for (const frames::PointingStarts::Start& s : f.starts) {
    note << " " << s.twist << " rad ";
    if (s.termination == Termination::Converged) {
      note << s.minimum_duration << " s;";
    } else {
      note << terminationName(s.termination) << ";";
    }
  }
  note << ")";
  if (f.kept >= 0) note << ", the start from " << f.starts[f.kept].twist << " rad kept";
  return note.str() + "; " + reason;
}
std::string framed(const frames::StagedUnfinished& f, const std::string& reason) {
  std::ostringstream note;
  note << f.what << " reached s = " << std::max(f.reached, 0.0) << " of 1 (" << f.stages
       << " stages): " << reason;
  return note.str();
}
std::string framed(const frames::NoAttemptPlanned& f, const std::string& reason) {
  return "no attempt produced a plan on the requested grid (" + std::to_string(f.tried) +
         " tried); the last: " + reason;
}
std::string framed(const frames::FinerLevelStopped& f, const std::string& reason) {
  return "not converged: the N = " + std::to_string(f.feasible_steps) +
         " level met every constraint, but a finer level stopped (" + reason + ")";
}

std::string framed(const frames::OnContinuationLevel& f, const std::string& reason) {
  return reason + " (on the " + grid(f.steps) + " level of the grid continuation)";
}
std::string stopped(Termination stop) {
  return stop == Termination::Cancelled ? "cancelled" : "time budget exceeded";
}
std::string framed(const frames::CarriedOverAfterStop& f, const std::string&) {
  if (f.class_survey) {
    return stopped(f.stop) + "; the plan is the " + grid(f.steps) +
           " class survey's iterate carried over to " + grid(f.requested);
  }
  return stopped(f.stop) + " on the " + grid(f.steps) +
         " level; the plan is its iterate carried over to " + grid(f.requested);
}
std::string framed(const frames::WalkKept& f, const std::string& reason) {
  std::ostringstream brief;
  if (f.stopped) {
    brief << stopped(f.stop) << " during the " << f.during << " attempt; the plan returned: ";
  }
  brief << reason;
  if (f.tried > 1) {
    brief << "; attempt " << f.kept_at + 1 << " of " << f.tried << " kept (" << f.kept_stage
          << " from " << f.kept_start << ")";
  }
  return brief.str();
}
std::string framed(const frames::PointingWalk& f, const std::string& reason) {
  std::ostringstream brief;
  brief << reason;
  // Each start's verdict is local (its ψ and way round): no start converged, which is not a
  // proof that no twist admits a plan.
  if (f.none_converged) {
    brief << "; no twist start converged (" << f.starts
          << " starts; each verdict is local to its start twist)";
  }
  brief << "; attempt " << f.kept_at + 1 << " of " << f.attempts << " kept";
  if (!f.survey) {
    brief << " (the interior point with the twist free from the plan given, strictly inside "
             "every bound)";
  } else if (f.constrained) {
    brief << " (" << f.start_twists << " start twists x " << f.ways_round
          << " ways round unconstrained, each distinct optimum below the cheapest constrained "
             "answer starting the interior point with the twist free; where none converged, "
             "each the other way round and the fixed-twist unconstrained optima; then, unless "
             "those were each certified locally infeasible from at least as many starts as "
             "start twists, each twist's fixed-twist constrained optimum)";
  } else {
    brief << " (" << f.start_twists << " start twists x " << f.ways_round << " ways round)";
  }
  return brief.str();
}

std::string framed(const frames::RichardsonHalfStopped& f, const std::string& reason) {
  return "N/2 = " + std::to_string(f.half_steps) + " for the Richardson estimate: " + reason;
}
std::string framed(const frames::CoarseResolutionStopped& f, const std::string& reason) {
  return "coarse resolution N = 64 (" + f.scheme + ") did not converge: " + reason;
}
std::string framed(const frames::AccuracyNeedsSteps& f, const std::string&) {
  return "accuracy_target " + threeDigits(f.target) + " (" + f.measure + ") needs " +
         grid(f.steps) + " > max_steps = " + std::to_string(f.max_steps);
}
std::string framed(const frames::AccuracyNotReached& f, const std::string&) {
  return "accuracy_target not reached: " + f.measure + " " + threeDigits(f.error) + " > target " +
         threeDigits(f.target) + " at " + grid(f.steps) + " after 4 refinements (round-off floor?)";
}

// The words of the drivers' verdicts (driver_verdict.hpp).
std::string judged(const verdicts::SolverReason&, const std::string& reason) {
  return reason;
}
std::string judged(const verdicts::AlreadyAtRest&, const std::string&) {
  return "converged: the initial and final states are the same state at rest, so T* = 0 s (no "
         "motion is needed; the plan holds the body at rest, zero torques)";
}
std::string judged(const verdicts::BelowProvenBound& v, const std::string&) {
  std::ostringstream why;
  why << "infeasible: any plan needs T >= " << exactNumber(v.lower_bound) << " s under " << v.bounds
      << " (" << v.basis << "; on " << v.steps << " steps at least "
      << exactNumber(v.grid_lower_bound) << " s), requested "
      << (v.upper_limit ? "duration <= " : "T = ") << exactNumber(v.requested)
      << " s; answered before any solve";
  return why.str();
}
std::string judged(const verdicts::InternalPhaseFailed& v, const std::string&) {
  return v.phase + " failed on a problem the planner built (not the request): " + v.what;
}
std::string judged(const verdicts::InfeasibleAtEveryDuration& v, const std::string&) {
  return "infeasible: " + v.why;
}
std::string judged(const verdicts::NoRoomAtDuration& v, const std::string&) {
  std::ostringstream why;
  why << "infeasible: no plan exists at T = " << exactNumber(v.requested) << " s on " << v.steps
      << " steps (proven: " << v.why << ", at every duration from " << exactNumber(v.from)
      << " s to " << exactNumber(v.to) << " s); answered before any solve";
  return why.str();
}
std::string judged(const verdicts::LocallyInfeasible& v, const std::string& reason) {
  std::ostringstream why;
  why << "infeasible from here (a local verdict): no plan within the bounds was found at T = "
      << exactNumber(v.requested) << " s; the least duration at which one was found is "
      << exactNumber(v.least_found) << " s (" << v.what_found << ", not a requirement)";
  if (v.lower_bound > 0.0) {
    why << "; any plan needs T >= " << exactNumber(v.lower_bound) << " s (" << v.basis << ")";
  }
  if (v.solved_at_requested) {
    why << " (" << terminationName(Termination::Infeasible) << " at T: " << reason << ")";
  } else {
    why << "; " << reason;
  }
  return why.str();
}
std::string judged(const verdicts::MinimumTimeFoundNone& v, const std::string& reason) {
  return "infeasible (a local verdict: the minimum-time problem under the same bounds found no "
         "feasible duration either, " +
         terminationName(v.minimum_time) + "): " + reason;
}
/// What the bounds prove about the durations (verdicts::ProvenDurations), said after a verdict
/// that found no plan: "; proven on N = 256 steps: no plan below ... s (...), none from ... s on
/// (...): a plan can lie only in [..., ...) s"; empty where nothing is proven.
std::string provenWords(const verdicts::ProvenDurations& p) {
  const bool least = p.least > 0.0;
  if (!least && !p.rangeProven()) return "";
  std::ostringstream words;
  words << "; proven on " << p.steps << " steps: no plan ";
  if (least) words << "below " << exactNumber(p.least) << " s (" << p.least_basis << ")";
  if (p.rangeProven()) {
    words << (least ? ", none " : "") << "from " << exactNumber(p.no_plan_from) << " s on (to "
          << exactNumber(p.no_plan_to)
          << " s the paper scheme's last free step into the final rate on the rate limit has no "
             "room; above it a step at the boundary rates would turn pi or more, no step of the "
             "scheme)";
  }
  if (least && p.rangeProven()) {
    words << ": a plan can lie only in [" << exactNumber(p.least) << ", "
          << exactNumber(p.no_plan_from) << ") s";
  }
  return words.str();
}
std::string judged(const verdicts::SearchStopped& v, const std::string&) {
  if (v.work_allowance > 0.0) {
    return terminationName(v.stop) + ": the minimum-time search stopped at its work allowance (" +
           exactNumber(v.work_allowance) +
           " node-iterations) before any duration was found feasible; durations it did not try "
           "are not judged" +
           provenWords(v.proven);
  }
  return terminationName(v.stop) + " before any duration was found feasible" +
         provenWords(v.proven);
}
std::string judged(const verdicts::SearchUnrepresentable& v, const std::string&) {
  // Longer plans are not shown infeasible: this grid cannot hold them.
  return std::string(v.coarse ? "step too large, increase steps" : "not converged") +
         ": no plan was found below T = " + exactNumber(v.from) +
         (v.least_tried > 0 ? " s (tried down to T = " + exactNumber(v.least_tried) + " s)"
                            : " s") +
         ", and from there on one step of " + exactNumber(v.from / v.steps) +
         " s at the boundary rates has no solution (N = " + std::to_string(v.steps) + ")" +
         (v.coarse ? "; even at the proven least duration a boundary step turns more than 1 rad"
                   : "") +
         provenWords(v.proven);
}
std::string judged(const verdicts::SearchInfeasible& v, const std::string&) {
  return "infeasible: no duration up to 2^" + std::to_string(v.doublings) +
         " times the first guess " + exactNumber(v.first_guess) +
         " s admits a plan under the bounds and constraints in force (a local search: every "
         "start's solves ended infeasible or unconverged)" +
         provenWords(v.proven);
}
std::string judged(const verdicts::FeasibleAtMinimumTime& v, const std::string& reason) {
  if (v.free_time_iterate) {
    return "feasible at T* (a free-time solve's iterate strictly inside every bound, where that "
           "solve ended short of its KKT point: a plan at its T, not a minimum-effort optimum)";
  }
  return "feasible at T* (its minimum-effort solve stopped short of optimality: " + reason + ")";
}
std::string judged(const verdicts::NoPointingStartConverged& v, const std::string&) {
  return "no start converged (" + std::to_string(v.starts) + " twist and way-round starts tried)";
}
std::string judged(const verdicts::NloptEnded& v, const std::string&) {
  char figures[160];
  std::snprintf(figures, sizeof figures,
                "; constraint violation %.3g, relative stationarity residual %.3g", v.violation,
                v.stationarity);
  std::ostringstream message;
  message << (v.converged ? "converged; " : "not converged; ")
          << (v.stop_reason == "cancelled" ? "cancelled; " : "") << "nlopt SLSQP: " << v.code;
  if (!v.stop_reason.empty()) message << " (" << v.stop_reason << ")";
  if (!v.exception_text.empty()) message << " (" << v.exception_text << ")";
  message << figures;
  if (v.terminal_unmet) message << "; terminal constraints not met";
  return message.str();
}

std::string judged(const verdicts::NewtonEnded& v, const std::string&) {
  std::ostringstream message;
  message << v.how << " after " << v.iterations << " iterations (relative gradient "
          << v.relative_gradient << ", relative Newton decrement " << v.relative_decrement << ")";
  return message.str();
}
std::string judged(const verdicts::InteriorPointEnded& v, const std::string&) {
  std::ostringstream message;
  message << v.how << " after " << v.iterations
          << " interior-point iterations (relative Newton decrement " << v.relative_decrement
          << ", barrier " << v.barrier << " x cost, max elastic violation "
          << v.max_elastic_violation << ")";
  return message.str();
}
std::string judged(const verdicts::NoBoundaryStep& v, const std::string&) {
  return (v.free_time ? "the boundary rates admit no step: " : "boundary velocity: ") + v.what;
}
std::string judged(const verdicts::ConeAtFixedNode& v, const std::string&) {
  return "infeasible: " + v.violation +
         ", an attitude the boundary velocities fix (increase steps or move the boundary)";
}
std::string judged(const verdicts::FreeTimeEnded& v, const std::string&) {
  std::ostringstream message;
  message << v.how << " after " << v.iterations << " iterations: T = " << v.duration
          << " s, stationarity " << v.stationarity << " (h row " << v.time_row
          << "), complementarity " << v.complementarity << ", min c " << v.smallest_value;
  return message.str();
}
std::string judged(const verdicts::FreeTimeConeAtFixedNode& v, const std::string&) {
  return v.violation + ", an attitude the boundary data fix";
}
std::string judged(const verdicts::NoStrictlyFeasibleStart& v, const std::string&) {
  return v.why;
}

std::string judged(const verdicts::MinimumTimeAnswer& v, const std::string& reason) {
  std::ostringstream note;
  note << "minimum time T* = " << v.minimum_duration << " s: ";
  if (v.kkt_point) {
    note << "a KKT point of the discrete minimum-time problem, "
         << (v.second_order_sufficient ? "second-order sufficient (a strict local minimum)"
                                       : "not second-order sufficient (not shown a local "
                                         "minimum)");
  } else {
    note << "an upper bound, not a KKT point: the free-time solve on the requested grid ended "
            "short of its KKT point at a plan inside every bound";
  }
  note << " (one free-time interior-point solve from the " << v.start << " start, " << v.iterations
       << " iterations; stationarity " << v.stationarity << ", h row " << v.time_row
       << ", complementarity " << v.complementarity << "; starts:";
  for (const verdicts::MinimumTimeAnswer::Start& st : v.starts) {
    note << " " << st.name << " ";
    if (!st.same_as.empty()) note << "(as " << st.same_as << ") ";
    if (st.termination == Termination::Converged) {
      note << st.duration << " s" << (st.second_order_sufficient ? "" : " (saddle)") << ";";
    } else {
      note << terminationName(st.termination) << ";";
    }
  }
  note << " " << v.solves << " free-time solves)";
  // A replay that failed says so after the answer's account.
  return note.str() + (reason.empty() ? "" : "; " + reason);
}

/// The fold of a message's clauses (MessageClause): each clause takes the message so far.
struct Fold {
  std::string* message;
  void operator()(const clauses::Reason& r) const { *message = r.words; }
  void operator()(const Verdict& v) const { *message = renderVerdict(v, *message); }
  void operator()(const Note& n) const { message->append(renderNote(n)); }
  void operator()(const Frame& f) const { *message = renderFrame(f, *message); }
};

}  // namespace

std::string renderNote(const Note& note) {
  return std::visit([](const auto& n) { return words(n); }, note);
}

void addNote(PlanResult* result, const Note& note) {
  result->clauses.push_back(note);
}

std::string renderFrame(const Frame& frame, const std::string& reason) {
  return std::visit([&](const auto& f) { return framed(f, reason); }, frame);
}

void frameMessage(PlanResult* result, const Frame& frame) {
  result->clauses.push_back(frame);
}

std::string renderVerdict(const Verdict& verdict, const std::string& reason) {
  return std::visit([&](const auto& v) { return judged(v, reason); }, verdict);
}

void recordVerdict(PlanResult* result, const Verdict& verdict) {
  result->verdict = verdict;
  result->clauses.push_back(verdict);
}

void recordReason(PlanResult* result, const std::string& words) {
  result->clauses.assign(1, clauses::Reason{words});
}

void takeReason(PlanResult* to, const PlanResult& from) {
  takeReason(to, from.clauses);
}

void takeReason(PlanResult* to, const std::vector<MessageClause>& clauses) {
  to->clauses = clauses;
}

std::string renderClauses(const std::vector<MessageClause>& clauses) {
  std::string message;
  for (const MessageClause& clause : clauses) std::visit(Fold{&message}, clause);
  return message;
}

std::string renderMessage(const PlanResult& result) {
  return renderClauses(result.clauses);
}

std::string PlanResult::message() const {
  return renderClauses(clauses);
}

}  // namespace attitude_planner
