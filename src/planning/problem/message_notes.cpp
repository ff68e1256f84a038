// The wording of every clause of message_notes.hpp, in one place.
#include "planning/problem/message_notes.hpp"

#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {
namespace {

using namespace notes;

std::string grid(int steps) {
  return "N = " + std::to_string(steps);
}

std::string words(const FormulationRetry& n) {
  return (n.solved ? "; solved with " + n.retry + " after " + n.first + " stopped: "
                   : "; retried with " + n.retry + ": ") +
         n.reason;
}
std::string words(const ReachedThroughMiddle& n) {
  return "; reached through " + grid(n.steps) + " after the direct refinement stopped: " + n.reason;
}
std::string words(const GridContinuation& n) {
  return "; grid continuation from " + grid(n.steps);
}
std::string words(const RetriedInTwoStages& n) {
  return "; retried in two stages (the cones alone, then every constraint from that path) "
         "after: " +
         n.reason;
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
  return "; after the start from the initial guess stopped: " + n.reason;
}
std::string words(const LastIterateDoesNotReplay& n) {
  return "; its last iterate's torques do not replay: " + n.reason;
}
std::string words(const CheapestClass& n) {
  return "; the cheapest homotopy class under the constraints (after the unconstrained "
         "optimum's class: " +
         n.reason + ")";
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
  return ": " + terminationName(n.termination) + " (" + n.reason + ")";
}
std::string words(const MinimumTimeUnsolved& n) {
  return "; the first solve " + n.why +
         " and the minimum-time problem under the same bounds did not converge (" +
         terminationName(n.termination) + ")";
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
         ": N: " + reason + " | 2N: " + f.fine_reason;
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
    << " | 2N: " << f.fine_reason << " | N: " << reason;
  return s.str();
}
std::string framed(const frames::UpperBoundFromProbe& f, const std::string& reason) {
  return "minimum time T* <= " + exactNumber(f.duration) +
         " s, the least duration found feasible (an upper bound)" +
         foundBelow(f.duration, f.previous) + " (its minimum-effort plan is returned): " + reason;
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
  return "replay of the planned torques failed: " + f.what + " (" + reason + ")";
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

}  // namespace

std::string renderNote(const Note& note) {
  return std::visit([](const auto& n) { return words(n); }, note);
}

void addNote(PlanResult* result, const Note& note) {
  result->message.append(renderNote(note));
}

std::string renderFrame(const Frame& frame, const std::string& reason) {
  return std::visit([&](const auto& f) { return framed(f, reason); }, frame);
}

void frameMessage(PlanResult* result, const Frame& frame) {
  result->message = renderFrame(frame, result->message);
}

}  // namespace attitude_planner
