// The clauses drivers add to a message are recorded as notes and worded in one place
// (problem/message_notes.hpp): each is one line after the message it extends, begins with its
// separator, and says the figures and the nested reason it was given, in the branch its fields
// choose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <variant>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/solve_context.hpp"
#include "support/bounded_requests.hpp"
#include "support/pointing_requests.hpp"
#include "support/random_problems.hpp"
#include "support/scene_problem.hpp"

namespace ap = attitude_planner;
namespace notes = attitude_planner::notes;

namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Another solve's reason as the clauses a note or a frame holds: its bare words.
ap::MessageClauses said(const std::string& words) {
  return {ap::clauses::Reason{words}};
}

}  // namespace

TEST(MessageNotes, EveryKindIsOneClauseThatBeginsWithItsSeparator) {
  const std::vector<ap::Note> all = {
      notes::FormulationRetry{"elastic", "free slacks", true, said("r")},
      notes::ReachedThroughMiddle{64, said("r")},
      notes::GridContinuation{8},
      notes::RetriedInTwoStages{said("r")},
      notes::FromInitialGuess{},
      notes::CoarserLevel{32, ap::Termination::Converged},
      notes::RefinedFromSurvey{16},
      notes::ConstraintsInactive{},
      notes::UnconstrainedStart{1.5, "w", "at k = 3", 7},
      notes::AfterGuessStopped{said("r")},
      notes::LastIterateDoesNotReplay{"r"},
      notes::OpenLoopReplayParted{"r", 1e-12},
      notes::CheapestClass{said("r")},
      notes::ConesTightenedBetweenNodes{0.004, 0.006},
      notes::LastPointingStart{"r"},
      notes::FixedTwistFallback{0.5, "r"},
      notes::PointingRestartNotServed{3.5},
      notes::SearchedOnT{"why"},
      notes::SharpenedFromSearch{"why", 2.5},
      notes::PlannedAtMargin{0.1, 3.3, 3.0},
      notes::MinimumTimeRestart{3.0, "why", false, ap::Termination::Infeasible, false, 0.0},
      notes::MinimumTimeUnsolved{"why", ap::Termination::NotConverged},
      notes::DescendedFromProbe{2.5, 3.0},
  };
  for (const ap::Note& note : all) {
    const std::string words = ap::renderNote(note);
    SCOPED_TRACE(words);
    EXPECT_EQ(words.rfind("; ", 0), 0u);
    EXPECT_GT(words.size(), 4u);
    EXPECT_EQ(words.find('\n'), std::string::npos);
  }
  EXPECT_EQ(
      ap::renderNote(notes::RestartEnded{ap::Termination::Infeasible, said("r")}).rfind(": ", 0),
      0u);
  // The search's summary is its own rendering (minimum_time_search.cpp), kept as given.
  EXPECT_EQ(ap::renderNote(notes::SearchSummary{"; minimum time T* = 1 s"}),
            "; minimum time T* = 1 s");
}

TEST(MessageNotes, AddNoteExtendsTheMessageWithTheNotesFiguresAndReason) {
  ap::PlanResult r;
  ap::recordReason(&r, "converged after 12 interior-point iterations");
  ap::addNote(&r, notes::GridContinuation{8});
  ap::addNote(
      &r, notes::FormulationRetry{"elastic", "free slacks", false, said("infeasible at N = 8")});
  EXPECT_EQ(r.message(),
            "converged after 12 interior-point iterations; grid continuation from N = 8; retried "
            "with elastic: infeasible at N = 8");
}

TEST(MessageNotes, TheFieldsChooseTheBranchOfTheWording) {
  // A converged coarser level started the grid; another ending names it and the geodesic.
  EXPECT_TRUE(contains(ap::renderNote(notes::CoarserLevel{32, ap::Termination::Converged}),
                       "started from the N = 32 solution"));
  const std::string stopped =
      ap::renderNote(notes::CoarserLevel{32, ap::Termination::NotConverged});
  EXPECT_TRUE(contains(stopped,
                       "N = 32 level ended " + ap::terminationName(ap::Termination::NotConverged)));
  EXPECT_TRUE(contains(stopped, "geodesic"));
  // A retry that answers names both formulations; one that did not, the retry's.
  EXPECT_TRUE(contains(ap::renderNote(notes::FormulationRetry{"elastic", "free slacks", true, {}}),
                       "solved with elastic after free slacks stopped"));
  EXPECT_TRUE(contains(ap::renderNote(notes::FormulationRetry{"elastic", "free slacks", false, {}}),
                       "retried with elastic: "));
  // Only the cone's margin is violated when no stated limit is.
  EXPECT_TRUE(contains(ap::renderNote(notes::UnconstrainedStart{2.0, "", "", 5}),
                       "violates a cone's margin and started it (5 Newton iterations)"));
  EXPECT_TRUE(contains(ap::renderNote(notes::UnconstrainedStart{2.0, "|tau_x| <= 1", "by 0.1", 5}),
                       "(cost 2) violates |tau_x| <= 1 by 0.1"));
  // The restart from the minimum-time plan: T* exactly, and what the ladder of durations did.
  const double T_star = 3.0 + 1.0 / 3.0;
  const std::string direct = ap::renderNote(notes::MinimumTimeRestart{
      T_star, "ended infeasible", false, ap::Termination::Converged, false, 0.0});
  EXPECT_TRUE(contains(direct, "(T* = " + ap::exactNumber(T_star) + " s)"));
  EXPECT_FALSE(contains(direct, "ladder"));
  EXPECT_TRUE(contains(ap::renderNote(notes::MinimumTimeRestart{
                           T_star, "w", true, ap::Termination::Infeasible, true, T_star}),
                       "reached by a ladder of durations from T* (the direct start ended " +
                           ap::terminationName(ap::Termination::Infeasible) + ")"));
  EXPECT_TRUE(contains(ap::renderNote(notes::MinimumTimeRestart{
                           T_star, "w", false, ap::Termination::Infeasible, true, 4.5}),
                       "up to T = " + ap::exactNumber(4.5) + " s, not at T"));
  EXPECT_TRUE(contains(ap::renderNote(notes::MinimumTimeRestart{
                           T_star, "w", false, ap::Termination::Infeasible, true, 0.0}),
                       "found no plan within the bounds above T*"));
}

TEST(MessageFrames, EachFrameSaysItsFiguresBeforeTheReasonItIsGiven) {
  const std::string reason = "converged after 3 iterations";
  const ap::frames::RichardsonPair pair{32};
  const ap::frames::RichardsonPair from_t_star{32, true};
  const std::vector<ap::Frame> all = {
      ap::frames::PairSolveStopped{pair, 64},
      ap::frames::PairCombined{pair, false, said("2N's")},
      ap::frames::PairCombined{from_t_star, true, said("2N's")},
      ap::frames::MinimumTimePairStopped{32, true, false},
      ap::frames::MinimumTimePairStopped{32, false, true},
      ap::frames::MinimumTimePairCombined{32, 2.5, 2.25, 2.5, true, false, said("2N's")},
      ap::frames::UpperBoundFromProbe{2.5, 3.0},
      ap::frames::StuckAtMinimumTimePlan{true, 2.0, 3.0, 0.0},
      ap::frames::StuckAtMinimumTimePlan{false, 2.0, 3.0, 2.5},
      ap::frames::StuckAtMinimumTimePlan{false, 2.0, 3.0, 0.0},
      ap::frames::OutsideRequestedClass{"it turns 0.3 rad"},
      ap::frames::ReplayFailed{"step 7 too large"},
      ap::frames::PointingStarts{{{0.5, ap::Termination::Converged, 21.8363}}, 0},
      ap::frames::StagedUnfinished{"rate continuation", 0.375, 4},
      ap::frames::NoAttemptPlanned{3},
      ap::frames::FinerLevelStopped{64},
  };
  for (const ap::Frame& frame : all) {
    const std::string words = ap::renderFrame(frame, reason);
    SCOPED_TRACE(words);
    const std::size_t at = words.find(reason);
    ASSERT_NE(at, std::string::npos);
    EXPECT_GT(at, 0u);  // the frame's words come first
    EXPECT_EQ(words.find(reason, at + 1), std::string::npos);
    EXPECT_EQ(words.find('\n'), std::string::npos);
  }
  // Pointing starts: each start's twist with its T* or termination, the kept one, then the reason
  // (the words of the former hand-built expression).
  const ap::frames::PointingStarts starts{
      {{0.5, ap::Termination::Converged, 21.8363}, {2.1, ap::Termination::NotConverged, 0.0}}, 0};
  EXPECT_EQ(ap::renderFrame(starts, reason),
            "pointing: 2 start twists (T* per start: 0.5 rad 21.8363 s; 2.1 rad not_converged;), "
            "the start from 0.5 rad kept; " +
                reason);
  EXPECT_EQ(ap::renderFrame(ap::frames::PointingStarts{}, reason),
            "pointing: no start twist was solved");
  // The pair names N and 2N, where each solve started, and which one stopped.
  const std::string stopped = ap::renderFrame(ap::frames::PairSolveStopped{pair, 64}, reason);
  EXPECT_TRUE(contains(stopped, "second_order at N = 32 and 2N = 64)"));
  EXPECT_TRUE(contains(stopped, "the second_order solve at N = 64 did not converge"));
  const std::string combined =
      ap::renderFrame(ap::frames::PairCombined{from_t_star, true, said("2N's")}, reason);
  EXPECT_TRUE(contains(combined, "2N = 64, each from its plan at T*)"));
  EXPECT_TRUE(contains(combined, "the plan is the second_order plan at N"));
  EXPECT_TRUE(contains(combined, ": N: " + reason + " | 2N: 2N's"));
  EXPECT_FALSE(contains(ap::renderFrame(ap::frames::PairCombined{pair, false, said("x")}, reason),
                        "the plan is"));
  // fourth_order minimum time: which solve stopped, and T* with the two it is the larger of.
  EXPECT_TRUE(contains(
      ap::renderFrame(ap::frames::MinimumTimePairStopped{32, false, true}, reason),
      "problems at N = 32 and 2N = 64): the minimum-effort plan at T* at N did not converge"));
  EXPECT_TRUE(contains(ap::renderFrame(ap::frames::MinimumTimePairStopped{32, true, false}, reason),
                       "): the one at 2N did not converge (its plan is returned): " + reason));
  const double T_star = 2.0 + 1.0 / 3.0;
  const std::string pair_t_star = ap::renderFrame(
      ap::frames::MinimumTimePairCombined{32, T_star, 2.0, T_star, true, true, said("2N's")},
      reason);
  EXPECT_TRUE(contains(pair_t_star, "T* = " + ap::exactNumber(T_star) + " s, the one at 2N binds"));
  EXPECT_TRUE(contains(pair_t_star, "(T* at N = " + ap::exactNumber(2.0) + " s"));
  EXPECT_TRUE(contains(pair_t_star, "the plan is the second_order plan at N at T*"));
  EXPECT_TRUE(contains(pair_t_star, " | 2N: 2N's | N: " + reason));
  // The class and replay frames put the plan's own message in parentheses after their reason.
  EXPECT_EQ(ap::renderFrame(ap::frames::OutsideRequestedClass{"w"}, reason),
            "not converged in the requested class: w (" + reason + ")");
  ap::PlanResult r;
  ap::recordReason(&r, reason);
  ap::frameMessage(&r, ap::frames::ReplayFailed{"e", 3, HUGE_VAL});
  EXPECT_EQ(r.message(),
            "not converged: the plan's step k = 3 is not the step the replay solves from the "
            "plan's own state there (no root found), and its torques replayed open-loop fail: e (" +
                reason + ")");
}

TEST(MessageFrames, ProbesAndTheLadderSayTheirDurationsExactly) {
  // Spinning ends: a probe below T* found a plan; the free-time solve descended from it, or not.
  const double below = 2.0 + 1.0 / 3.0, previous = 2.5;
  const std::string found = "; a plan was found at " + ap::exactNumber(below) +
                            " s, below the T* = " + ap::exactNumber(previous) + " s reached before";
  EXPECT_EQ(ap::renderNote(notes::DescendedFromProbe{below, previous}),
            found + ", and the free-time solve from it descended");
  EXPECT_EQ(ap::renderFrame(ap::frames::UpperBoundFromProbe{below, previous}, "r"),
            "minimum time T* <= " + ap::exactNumber(below) +
                " s, the least duration found feasible (an upper bound)" + found +
                " (the plan found there is returned): r");
  // Stuck at the minimum-time plan: the branch its fields choose, the durations exact.
  const std::string rest =
      ap::renderFrame(ap::frames::StuckAtMinimumTimePlan{true, below, 3, 2.9}, "r");
  EXPECT_EQ(rest.rfind("not converged (feasible: T* = " + ap::exactNumber(below) + " s <= ", 0),
            0u);
  EXPECT_FALSE(contains(rest, "ladder"));
  const std::string ladder =
      ap::renderFrame(ap::frames::StuckAtMinimumTimePlan{false, below, 3.0, 2.75}, "r");
  EXPECT_EQ(ladder.rfind("infeasible from here (a local verdict): no plan within the bounds was "
                         "found at T = " +
                             ap::exactNumber(3.0) + " s",
                         0),
            0u);
  EXPECT_TRUE(
      contains(ladder, "found up to T = " + ap::exactNumber(2.75) + " s, where the ladder"));
  const std::string none =
      ap::renderFrame(ap::frames::StuckAtMinimumTimePlan{false, below, 3, 0}, "r");
  EXPECT_EQ(none.rfind("not converged (a plan within the bounds exists at T* = " +
                           ap::exactNumber(below) + " s < T",
                       0),
            0u);
  for (const std::string& s : {rest, ladder, none}) EXPECT_EQ(s.substr(s.size() - 4), "): r");
}

// A driver's verdict is data on the result (kind and figures); its words are rendered in one
// place and are, kind by kind, the words the drivers wrote by hand before (their former
// expressions, copied here with figures that print differently in every digit).
TEST(DriverVerdicts, EachKindSaysTheWordsOfItsFormerExpression) {
  namespace v = ap::verdicts;
  const std::string reason = "converged after 3 iterations";
  const double T = 2.0 + 1.0 / 3.0, least = 2.5 + 1.0 / 7.0, bound = 1.0 + 1.0 / 9.0;
  EXPECT_EQ(ap::renderVerdict(v::SolverReason{}, reason), reason);
  EXPECT_EQ(ap::renderVerdict(v::AlreadyAtRest{}, ""),
            "converged: the initial and final states are the same state at rest, so T* = 0 s (no "
            "motion is needed; the plan holds the body at rest, zero torques)");
  for (const bool minimum_time : {false, true}) {
    EXPECT_EQ(ap::renderVerdict(v::BelowProvenBound{bound, "proven: b", "max_angular_rate 0.05", 32,
                                                    least, T, minimum_time},
                                ""),
              "infeasible: any plan needs T >= " + ap::exactNumber(bound) +
                  " s under max_angular_rate 0.05 (proven: b; on 32 steps at least " +
                  ap::exactNumber(least) + " s), requested " +
                  (minimum_time ? "duration <= " : "T = ") + ap::exactNumber(T) +
                  " s; answered before any solve");
  }
  EXPECT_EQ(ap::renderVerdict(v::InternalPhaseFailed{"the minimum-time phase", "e"}, ""),
            "the minimum-time phase failed on a problem the planner built (not the request): e");
  EXPECT_EQ(ap::renderVerdict(v::InfeasibleAtEveryDuration{"why"}, ""), "infeasible: why");
  const std::string local =
      "infeasible from here (a local verdict): no plan within the bounds was found at T = " +
      ap::exactNumber(T) + " s; the least duration at which one was found is " +
      ap::exactNumber(least) + " s (what, not a requirement)";
  const std::string proven = "; any plan needs T >= " + ap::exactNumber(bound) + " s (b)";
  EXPECT_EQ(ap::renderVerdict(v::LocallyInfeasible{T, least, "what", bound, "b", false}, reason),
            local + proven + "; " + reason);
  EXPECT_EQ(ap::renderVerdict(v::LocallyInfeasible{T, least, "what", bound, "b", true}, reason),
            local + proven + " (" + ap::terminationName(ap::Termination::Infeasible) +
                " at T: " + reason + ")");
  EXPECT_EQ(ap::renderVerdict(v::LocallyInfeasible{T, least, "what", 0.0, "", false}, reason),
            local + "; " + reason);  // no proven bound applies
  EXPECT_EQ(ap::renderVerdict(v::MinimumTimeFoundNone{ap::Termination::TimedOut}, reason),
            "infeasible (a local verdict: the minimum-time problem under the same bounds found no "
            "feasible duration either, " +
                ap::terminationName(ap::Termination::TimedOut) + "): " + reason);
  EXPECT_EQ(
      ap::renderVerdict(v::SearchStopped{ap::Termination::Cancelled}, ""),
      ap::terminationName(ap::Termination::Cancelled) + " before any duration was found feasible");
  EXPECT_EQ(ap::renderVerdict(v::SearchUnrepresentable{T, 48, false, 0.25 * T}, ""),
            "not converged: no plan was found below T = " + ap::exactNumber(T) +
                " s (tried down to T = " + ap::exactNumber(0.25 * T) +
                " s), and from there on one step of " + ap::exactNumber(T / 48) +
                " s at the boundary rates has no solution (N = 48)");
  for (const bool coarse : {false, true}) {
    EXPECT_EQ(ap::renderVerdict(v::SearchUnrepresentable{T, 48, coarse}, ""),
              std::string(coarse ? "step too large, increase steps" : "not converged") +
                  ": no plan was found below T = " + ap::exactNumber(T) +
                  " s, and from there on one step of " + ap::exactNumber(T / 48) +
                  " s at the boundary rates has no solution (N = 48)" +
                  (coarse ? "; even at the proven least duration a boundary step turns more "
                            "than 1 rad"
                          : ""));
  }
  EXPECT_EQ(ap::renderVerdict(v::SearchInfeasible{12, T}, ""),
            "infeasible: no duration up to 2^12 times the first guess " + ap::exactNumber(T) +
                " s admits a plan under the bounds and constraints in force (a local search: "
                "every start's solves ended infeasible or unconverged)");
  EXPECT_EQ(
      ap::renderVerdict(v::FeasibleAtMinimumTime{T}, reason),
      "feasible at T* (its minimum-effort solve stopped short of optimality: " + reason + ")");
  EXPECT_EQ(ap::renderVerdict(v::NoPointingStartConverged{16}, ""),
            "no start converged (16 twist and way-round starts tried)");
}

TEST(DriverVerdicts, TheSearchsVerdictsSayTheProvenDurationsFromTheirFigures) {
  // A search that found no plan says what the bounds prove about the durations, from the
  // verdict's data: none below the grid's lower bound, none from the range without room on, and
  // the window left between them; each part only where its figures prove it.
  namespace v = ap::verdicts;
  const double least = 10.084716, from = 13.8437, to = 164.0412, T = 186.08;
  const v::ProvenDurations both{256, least, "momentum", from, to};
  const std::string below = "no plan below " + ap::exactNumber(least) + " s (momentum)";
  const std::string range =
      "from " + ap::exactNumber(from) + " s on (to " + ap::exactNumber(to) +
      " s the paper scheme's last free step into the final rate on the rate limit has no room; "
      "above it a step at the boundary rates would turn pi or more, no step of the scheme)";
  const std::string window =
      ": a plan can lie only in [" + ap::exactNumber(least) + ", " + ap::exactNumber(from) + ") s";
  const std::string unrepresentable = ap::renderVerdict(v::SearchUnrepresentable{T, 256}, "");
  EXPECT_EQ(ap::renderVerdict(v::SearchUnrepresentable{T, 256, false, 0.0, both}, ""),
            unrepresentable + "; proven on 256 steps: " + below + ", none " + range + window);
  const v::ProvenDurations floor_only{256, least, "momentum"};
  EXPECT_EQ(ap::renderVerdict(v::SearchInfeasible{12, T, floor_only}, ""),
            ap::renderVerdict(v::SearchInfeasible{12, T}, "") + "; proven on 256 steps: " + below);
  const v::ProvenDurations range_only{256, 0.0, "", from, to};
  EXPECT_EQ(ap::renderVerdict(v::SearchStopped{ap::Termination::TimedOut, range_only}, ""),
            ap::renderVerdict(v::SearchStopped{ap::Termination::TimedOut}, "") +
                "; proven on 256 steps: no plan " + range);
  // Nothing proven, nothing said; the figures carry the same values the words say.
  EXPECT_EQ(ap::renderVerdict(v::SearchStopped{ap::Termination::TimedOut, {256}}, ""),
            ap::renderVerdict(v::SearchStopped{ap::Termination::TimedOut}, ""));
  const std::vector<ap::VerdictFigure> figures =
      ap::verdictFigures(v::SearchUnrepresentable{T, 256, false, 0.0, both});
  const auto figure = [&](const std::string& name) {
    for (const ap::VerdictFigure& f : figures)
      if (f.name == name) return f.value;
    return -1.0;
  };
  EXPECT_EQ(figure("grid_lower_bound"), least);
  EXPECT_EQ(figure("no_plan_from"), from);
  EXPECT_EQ(figure("no_plan_to"), to);
}

TEST(DriverVerdicts, RecordingKeepsTheVerdictAndItsFiguresAsData) {
  namespace v = ap::verdicts;
  ap::PlanResult r;
  EXPECT_EQ(ap::verdictKindName(r.verdict), "solver_reason");  // a solver's reason stands
  EXPECT_TRUE(ap::verdictFigures(r.verdict).empty());
  ap::recordReason(&r, "infeasible at N = 32");
  ap::recordVerdict(&r, v::LocallyInfeasible{3.0, 3.25, "what", 2.75, "b", true});
  EXPECT_EQ(ap::verdictKindName(r.verdict), "locally_infeasible");
  ASSERT_TRUE(std::holds_alternative<v::LocallyInfeasible>(r.verdict));
  EXPECT_EQ(std::get<v::LocallyInfeasible>(r.verdict).least_found, 3.25);
  EXPECT_EQ(r.message().rfind("infeasible from here", 0), 0u);
  EXPECT_NE(r.message().find("(infeasible at T: infeasible at N = 32)"), std::string::npos);
  // The figures by name carry the fields' values, each name once.
  const std::vector<ap::VerdictFigure> figures = ap::verdictFigures(r.verdict);
  ASSERT_EQ(figures.size(), 3u);
  EXPECT_EQ(figures[0].name, "requested_duration");
  EXPECT_EQ(figures[0].value, 3.0);
  EXPECT_EQ(figures[1].name, "least_duration_found");
  EXPECT_EQ(figures[1].value, 3.25);
  EXPECT_EQ(figures[2].name, "lower_bound");
  EXPECT_EQ(figures[2].value, 2.75);
  const std::vector<ap::Verdict> all = {v::SolverReason{},
                                        v::AlreadyAtRest{},
                                        v::BelowProvenBound{},
                                        v::InternalPhaseFailed{},
                                        v::InfeasibleAtEveryDuration{},
                                        v::NoRoomAtDuration{},
                                        v::LocallyInfeasible{},
                                        v::MinimumTimeFoundNone{},
                                        v::SearchStopped{},
                                        v::SearchUnrepresentable{},
                                        v::SearchInfeasible{},
                                        v::FeasibleAtMinimumTime{},
                                        v::NoPointingStartConverged{},
                                        v::NloptEnded{},
                                        v::NewtonEnded{},
                                        v::InteriorPointEnded{},
                                        v::NoBoundaryStep{},
                                        v::ConeAtFixedNode{},
                                        v::FreeTimeEnded{},
                                        v::FreeTimeConeAtFixedNode{},
                                        v::NoStrictlyFeasibleStart{},
                                        v::MinimumTimeAnswer{}};
  std::vector<std::string> kinds;
  for (const ap::Verdict& verdict : all) {
    const std::string kind = ap::verdictKindName(verdict);
    EXPECT_EQ(std::count(kinds.begin(), kinds.end(), kind), 0) << kind;
    kinds.push_back(kind);
    std::vector<std::string> names;
    for (const ap::VerdictFigure& f : ap::verdictFigures(verdict)) {
      EXPECT_EQ(std::count(names.begin(), names.end(), f.name), 0) << kind << " " << f.name;
      names.push_back(f.name);
    }
  }
  EXPECT_EQ(kinds.size(), std::variant_size_v<ap::Verdict>);
}

TEST(DriverVerdicts, TheSolversFirstReasonsSayTheWordsOfTheirFormerExpressions) {
  // Newton's and the interior point's endings on one grid, as data: the words the solvers wrote
  // themselves before (their ostringstream expressions, repeated here), and the figures by name.
  namespace v = ap::verdicts;
  const double g = 1.0 / 3.0 * 1e-9, d = 2.0 / 7.0 * 1e-11, mu = 1.0 / 9.0 * 1e-12, e = 0.125;
  std::ostringstream newton;
  newton << "converged"
         << " after " << 7 << " iterations (relative gradient " << g
         << ", relative Newton decrement " << d << ")";
  EXPECT_EQ(ap::renderVerdict(v::NewtonEnded{"converged", 7, g, d}, "ignored"), newton.str());
  std::ostringstream interior;
  interior << "line search failed"
           << " after " << 41 << " interior-point iterations (relative Newton decrement " << d
           << ", barrier " << mu << " x cost, max elastic violation " << e << ")";
  EXPECT_EQ(ap::renderVerdict(v::InteriorPointEnded{"line search failed", 41, d, mu, e}, ""),
            interior.str());
  EXPECT_EQ(ap::renderVerdict(v::NoBoundaryStep{"no step from 9 rad/s"}, ""),
            std::string("boundary velocity: ") + "no step from 9 rad/s");
  EXPECT_EQ(ap::renderVerdict(v::ConeAtFixedNode{"keep_out at R_1 by 0.1 rad"}, ""),
            "infeasible: " + std::string("keep_out at R_1 by 0.1 rad") +
                ", an attitude the boundary velocities fix (increase steps or move the "
                "boundary)");
  const std::vector<ap::VerdictFigure> figures =
      ap::verdictFigures(v::InteriorPointEnded{"converged", 41, d, mu, e});
  ASSERT_EQ(figures.size(), 4u);
  EXPECT_EQ(figures[0].name, "iterations");
  EXPECT_EQ(figures[0].value, 41.0);
  EXPECT_EQ(figures[2].name, "barrier_over_cost");
  EXPECT_EQ(figures[2].value, mu);
}

TEST(DriverVerdicts, TheFreeTimeSolversReasonsSayTheWordsOfTheirFormerExpressions) {
  // The free-time solve's endings as data: the words free_time_solver wrote itself before (its
  // expressions, repeated here), and the figures by name.
  namespace v = ap::verdicts;
  const double T = 12.0 + 1.0 / 3.0, g = 2.0 / 7.0 * 1e-9, h = 1.0 / 9.0 * 1e-10,
               gap = 3.0 / 11.0 * 1e-12, c = 1.0 / 13.0;
  std::ostringstream ended;
  ended << "converged"
        << " after " << 23 << " iterations: T = " << T << " s, stationarity " << g << " (h row "
        << h << "), complementarity " << gap << ", min c " << c;
  const v::FreeTimeEnded free_time{"converged", 23, T, g, h, gap, c};
  EXPECT_EQ(ap::renderVerdict(free_time, "ignored"), ended.str());
  EXPECT_EQ(ap::renderVerdict(v::FreeTimeConeAtFixedNode{"keep_out at R_1 by 0.1 rad"}, ""),
            std::string("keep_out at R_1 by 0.1 rad") + ", an attitude the boundary data fix");
  EXPECT_EQ(ap::renderVerdict(v::NoStrictlyFeasibleStart{"no strictly feasible start: x"}, ""),
            "no strictly feasible start: x");
  EXPECT_EQ(ap::renderVerdict(v::NoBoundaryStep{"9 rad/s", true}, ""),
            std::string("the boundary rates admit no step: ") + "9 rad/s");
  const std::vector<ap::VerdictFigure> figures = ap::verdictFigures(free_time);
  ASSERT_EQ(figures.size(), 6u);
  EXPECT_EQ(figures[1].name, "duration");
  EXPECT_EQ(figures[1].value, T);
  EXPECT_EQ(figures[5].name, "min_constraint_value");
  EXPECT_EQ(figures[5].value, c);
}

TEST(MessageFrames, TheSolversWrappersSayTheWordsOfTheirFormerExpressions) {
  // Newton's staged continuation that stopped, its walk with no plan on the requested grid, and
  // the interior point's finer level that stopped: the former hand-built expressions.
  const std::string reason = "line search failed after 3 iterations";
  std::ostringstream staged;
  staged << "inertia homotopy"
         << " reached s = " << std::max(-0.5, 0.0) << " of 1 (" << 2 << " stages): " << reason;
  EXPECT_EQ(ap::renderFrame(ap::frames::StagedUnfinished{"inertia homotopy", -0.5, 2}, reason),
            staged.str());
  EXPECT_EQ(ap::renderFrame(ap::frames::StagedUnfinished{"x", 0.625, 5}, reason),
            "x reached s = 0.625 of 1 (5 stages): " + reason);
  EXPECT_EQ(ap::renderFrame(ap::frames::NoAttemptPlanned{4}, reason),
            "no attempt produced a plan on the requested grid (" + std::to_string(4) +
                " tried); the last: " + reason);
  EXPECT_EQ(ap::renderFrame(ap::frames::FinerLevelStopped{128}, reason),
            "not converged: the N = " + std::to_string(128) +
                " level met every constraint, but a finer level stopped (" + reason + ")");
}

TEST(DriverVerdicts, AReasonCarriedTakesItsVerdictAlong) {
  // A result given another's reason (a wrapper's, a driver's from its solver's outcome) carries
  // the verdict with the words, so a frame around it keeps the kind.
  ap::PlanResult solved;
  ap::recordVerdict(&solved, ap::verdicts::NewtonEnded{"iteration limit reached", 50, 1e-3, 0.5});
  ap::PlanResult wrapper;
  ap::carryReason(&wrapper, solved);
  ap::frameMessage(&wrapper, ap::frames::StagedUnfinished{"rate continuation", 0.5, 3});
  EXPECT_EQ(ap::verdictKindName(wrapper.verdict), "newton_ended");
  EXPECT_EQ(
      wrapper.message(),
      ap::renderFrame(ap::frames::StagedUnfinished{"rate continuation", 0.5, 3}, solved.message()));
}

TEST(DriverVerdicts, NloptsEndingSaysItsResultAndFiguresAsBefore) {
  // The cross-check's first reason as data: the words of its former expression, %.3g figures.
  namespace v = ap::verdicts;
  EXPECT_EQ(ap::renderVerdict(
                v::NloptEnded{"XTOL_REACHED", "", "", true, false, 1.234567e-9, 4.5e-7}, ""),
            "converged; nlopt SLSQP: XTOL_REACHED; constraint violation 1.23e-09, relative "
            "stationarity residual 4.5e-07");
  EXPECT_EQ(
      ap::renderVerdict(v::NloptEnded{"FORCED_STOP", "cancelled", "", false, false, 0.5, 0.25}, ""),
      "not converged; cancelled; nlopt SLSQP: FORCED_STOP (cancelled); constraint violation 0.5, "
      "relative stationarity residual 0.25");
  EXPECT_EQ(ap::renderVerdict(v::NloptEnded{"FAILURE", "", "roundoff", false, true, 2.0, 3.0}, ""),
            "not converged; nlopt SLSQP: FAILURE (roundoff); constraint violation 2, relative "
            "stationarity residual 3; terminal constraints not met");
  const v::NloptEnded ended{"XTOL_REACHED", "", "", true, false, 0.125, 0.0625};
  const std::vector<ap::VerdictFigure> figures = ap::verdictFigures(ended);
  ASSERT_EQ(figures.size(), 2u);
  EXPECT_EQ(figures[0].name, "constraint_violation");
  EXPECT_EQ(figures[0].value, 0.125);
  EXPECT_EQ(figures[1].name, "relative_stationarity");
  EXPECT_EQ(figures[1].value, 0.0625);
}

namespace {

/// A request planned as planManeuver plans it: the drivers' own answer (their context overloads).
ap::PlanResult plannedByTheDrivers(const ap::PlanningProblem& problem,
                                   const ap::SolverOptions& options = {}) {
  ap::SolveContext context(options);
  return problem.objective == ap::Objective::MinimumTime
             ? ap::planMinimumTime(problem, context)
             : ap::planBoundedMinimumEffort(problem, context);
}

/// The clauses a note or a frame holds (another solve's reason: `reason` or `fine_reason`).
template <class T, class = void>
struct HoldsReason : std::false_type {};
template <class T>
struct HoldsReason<T, std::void_t<decltype(T::reason)>>
    : std::is_same<decltype(T::reason), ap::MessageClauses> {};
template <class T, class = void>
struct HoldsFineReason : std::false_type {};
template <class T>
struct HoldsFineReason<T, std::void_t<decltype(T::fine_reason)>>
    : std::is_same<decltype(T::fine_reason), ap::MessageClauses> {};

/// Every reason held inside `clauses`, however deep: each is the clauses of a solve that said
/// something (none empty). Returns how many there were.
int expectNestedReasonsSaid(const ap::MessageClauses& clauses) {
  int nested = 0;
  const auto inner = [&](const auto& held) {
    using T = std::decay_t<decltype(held)>;
    const ap::MessageClauses* reason = nullptr;
    if constexpr (HoldsReason<T>::value) reason = &held.reason;
    if constexpr (HoldsFineReason<T>::value) reason = &held.fine_reason;
    if (!reason) return;
    EXPECT_FALSE(reason->empty()) << typeid(T).name() << " holds no reason";
    nested += 1 + expectNestedReasonsSaid(*reason);
  };
  for (const ap::MessageClause& clause : clauses) {
    if (const auto* note = std::get_if<ap::Note>(&clause)) std::visit(inner, *note);
    if (const auto* frame = std::get_if<ap::Frame>(&clause)) std::visit(inner, *frame);
  }
  return nested;
}

/// Every path records what it says: the answer's clauses, and every solve's reason they hold,
/// are not empty, and they say a message of one line.
void expectItsClausesSaid(const ap::PlanResult& r, const std::string& label, int* checked,
                          int* nested) {
  SCOPED_TRACE(label + ": " + r.message());
  EXPECT_FALSE(r.clauses.empty());
  EXPECT_FALSE(r.message().empty());
  EXPECT_EQ(r.message().find('\n'), std::string::npos);
  *nested += expectNestedReasonsSaid(r.clauses);
  ++*checked;
}

}  // namespace

TEST(MessageClauses, EveryKindOfRequestRecordsClausesThatSayItsMessage) {
  namespace rb = ap::robustness;
  namespace ts = ap::test_support;
  int checked = 0;
  int nested = 0;
  // Minimum effort, unconstrained: seeded random bodies, ends, horizons and N; those up to N = 256
  // as fourth_order too (a Richardson pair at N and 2N, framed around its N solve's reason).
  for (int i = 0; i < 4; ++i) {
    rb::RandomCase c = rb::randomCase(4601, i);
    expectItsClausesSaid(plannedByTheDrivers(c.problem), c.label, &checked, &nested);
    if (c.problem.steps > 256) continue;
    c.problem.scheme = ap::SchemeKind::FourthOrder;
    expectItsClausesSaid(plannedByTheDrivers(c.problem), c.label + " fourth_order", &checked,
                         &nested);
  }
  // Bounded: a torque norm, per-axis torques, a norm with a rate limit and a replan, each a
  // minimum-effort request (the minimum-time phase where it ends infeasible), and two asked as
  // minimum time.
  for (int i : {0, 1, 2, 3, 4, 5, 12, 13}) {
    const std::optional<rb::BoundedRequest> request = rb::boundedRequest(4602, i);
    if (!request) continue;
    expectItsClausesSaid(plannedByTheDrivers(request->problem), request->label, &checked, &nested);
  }
  // Constrained scenes (a keep-out cone, a rate limit, torque bounds; classes enumerated) and the
  // minimum-time scenes at two grids each.
  for (const char* scene : {"sun_keep_out", "rate_limited", "torque_limited", "min_time_keep_out",
                            "min_time_bilimoria_wie"}) {
    for (int steps : {32, 64}) {
      expectItsClausesSaid(plannedByTheDrivers(ts::sceneProblem(scene, steps)),
                           std::string(scene) + " N = " + std::to_string(steps), &checked, &nested);
    }
  }
  // Pointing: unconstrained, under a cone and under torque bounds, and minimum time on Betts's
  // body (its start twists framed around the kept answer).
  for (unsigned seed : {4603u, 4604u}) {
    const std::string at = " seed " + std::to_string(seed);
    expectItsClausesSaid(plannedByTheDrivers(ts::randomPointingRequest(
                             seed, 32, seed % 2 == 1, ap::SchemeKind::SecondOrder)),
                         "pointing" + at, &checked, &nested);
    for (ts::PointingBinding binding :
         {ts::PointingBinding::KeepOut, ts::PointingBinding::TorqueBox}) {
      expectItsClausesSaid(plannedByTheDrivers(ts::randomConstrainedPointingRequest(
                               seed, 32, false, ap::SchemeKind::SecondOrder, binding)),
                           "constrained pointing" + at, &checked, &nested);
    }
    expectItsClausesSaid(
        plannedByTheDrivers(ts::randomBettsPointingRequest(seed, 32, ap::SchemeKind::SecondOrder)),
        "pointing minimum time" + at, &checked, &nested);
  }
  // The NLopt cross-check, and a request stopped by its iteration limit.
  ap::SolverOptions nlopt;
  nlopt.solver = ap::SolverKind::Nlopt;
  expectItsClausesSaid(plannedByTheDrivers(ts::sceneProblem("rest_to_rest", 32), nlopt), "nlopt",
                       &checked, &nested);
  ap::SolverOptions capped;
  capped.max_iterations = 3;
  expectItsClausesSaid(plannedByTheDrivers(ts::sceneProblem("sun_keep_out", 64), capped),
                       "sun_keep_out capped", &checked, &nested);
  EXPECT_GE(checked, 30) << "the requests were planned";
  EXPECT_GT(nested, 0) << "some answer says another solve's reason";
}

TEST(MessageClauses, AFoldSaysWhatTheRecordingSaid) {
  // A reason, a verdict that judges it, a note and a frame, in that order: the fold is the
  // message recorded clause by clause, and a taken reason carries the clauses, not the verdict.
  ap::PlanResult r;
  ap::recordReason(&r, "replay failed");
  ap::recordVerdict(&r, ap::verdicts::MinimumTimeFoundNone{ap::Termination::Infeasible});
  ap::addNote(&r, notes::GridContinuation{8});
  ap::frameMessage(&r, ap::frames::OnContinuationLevel{16});
  ASSERT_EQ(r.clauses.size(), 4u);
  EXPECT_EQ(ap::renderMessage(r), r.message());
  EXPECT_EQ(r.message(),
            ap::renderVerdict(ap::verdicts::MinimumTimeFoundNone{ap::Termination::Infeasible},
                              "replay failed") +
                "; grid continuation from N = 8 (on the N = 16 level of the grid "
                "continuation)");
  ap::PlanResult combined;
  ap::takeReason(&combined, r);
  EXPECT_EQ(combined.message(), r.message());
  EXPECT_EQ(ap::verdictKindName(combined.verdict), "solver_reason");
  ap::recordReason(&combined, "other words");
  EXPECT_EQ(combined.clauses.size(), 1u);
  EXPECT_EQ(ap::renderMessage(combined), "other words");
}

TEST(MessageClauses, TheMessageIsOnlyTheRenderingOfItsClauses) {
  // No copy of the words to write: the message is a function of the clauses alone.
  static_assert(std::is_member_function_pointer_v<decltype(&ap::PlanResult::message)>,
                "PlanResult::message renders the clauses; it stores nothing");
  // Another solve's reason is held as its clauses and rendered where the outer message is.
  ap::PlanResult first;
  ap::recordReason(&first, "replay failed");
  ap::recordVerdict(&first, ap::verdicts::MinimumTimeFoundNone{ap::Termination::Infeasible});
  ap::PlanResult r;
  ap::recordReason(&r, "converged after 3 iterations");
  ap::addNote(&r, notes::CheapestClass{first.clauses});
  EXPECT_EQ(r.message(),
            "converged after 3 iterations; the cheapest homotopy class under the constraints "
            "(after the unconstrained optimum's class: " +
                first.message() + ")");
  ap::PlanResult same;
  same.clauses = r.clauses;
  EXPECT_EQ(same.message(), r.message());
  r.clauses.clear();
  EXPECT_EQ(r.message(), "");
}

TEST(MessageFrames, TheBriefsAndTheStopsSayTheWordsOfTheirFormerExpressions) {
  // The walks' briefs, the continuations' stops, the pointing and the accuracy clauses, once
  // built by hand around a message, are frames and notes: the words of those expressions.
  namespace f = ap::frames;
  const std::string reason = "converged after 3 iterations";
  EXPECT_EQ(ap::renderFrame(f::OnContinuationLevel{16}, reason),
            reason + " (on the N = 16 level of the grid continuation)");
  EXPECT_EQ(
      ap::renderFrame(f::CarriedOverAfterStop{ap::Termination::Cancelled, 16, 64, false}, reason),
      "cancelled on the N = 16 level; the plan is its iterate carried over to N = 64");
  EXPECT_EQ(
      ap::renderFrame(f::CarriedOverAfterStop{ap::Termination::TimedOut, 16, 64, true}, reason),
      "time budget exceeded; the plan is the N = 16 class survey's iterate carried over to N = 64");
  EXPECT_EQ(ap::renderFrame(f::WalkKept{true, ap::Termination::TimedOut, "constrained_retry", 0, 3,
                                        "solve", "hermite"},
                            reason),
            "time budget exceeded during the constrained_retry attempt; the plan returned: " +
                reason + "; attempt 1 of 3 kept (solve from hermite)");
  EXPECT_EQ(ap::renderFrame(
                f::WalkKept{false, ap::Termination::Cancelled, "solve", 0, 1, "solve", "hermite"},
                reason),
            reason);
  f::PointingWalk walk{true, 8, 2, 9, true, false, 4, 2};
  EXPECT_EQ(ap::renderFrame(walk, reason),
            reason +
                "; no twist start converged (8 starts; each verdict is local to its start "
                "twist); attempt 3 of 9 kept (4 start twists x 2 ways round)");
  walk.none_converged = false;
  walk.survey = false;
  EXPECT_EQ(ap::renderFrame(walk, reason),
            reason +
                "; attempt 3 of 9 kept (the interior point with the twist free from the plan "
                "given, strictly inside every bound)");
  walk.survey = true;
  walk.constrained = true;
  EXPECT_TRUE(contains(ap::renderFrame(walk, reason),
                       "; attempt 3 of 9 kept (4 start twists x 2 ways round unconstrained, each "
                       "distinct optimum below the cheapest constrained answer"));
  EXPECT_EQ(ap::renderNote(notes::PointingTwist{0.25, -1.5, true, 2e-9}),
            "; pointing: twist 0.25 rad, d L/d twist -1.5 (relative 2e-09)");
  EXPECT_EQ(ap::renderNote(notes::PointingTwist{0.25, -1.5}),
            "; pointing: twist 0.25 rad, d cost/d twist -1.5");
  EXPECT_EQ(ap::renderNote(notes::AccuracyReached{"cost_error", 1.23456e-5, 1e-4, 128, "paper"}),
            "; cost_error 1.23e-05 <= target 0.0001 at N = 128 (paper)");
  EXPECT_EQ(ap::renderFrame(f::RichardsonHalfStopped{32}, reason),
            "N/2 = 32 for the Richardson estimate: " + reason);
  EXPECT_EQ(ap::renderFrame(f::CoarseResolutionStopped{"second_order"}, reason),
            "coarse resolution N = 64 (second_order) did not converge: " + reason);
  EXPECT_EQ(ap::renderFrame(f::AccuracyNeedsSteps{1e-6, "terminal_miss", 70000, 65536}, reason),
            "accuracy_target 1e-06 (terminal_miss) needs N = 70000 > max_steps = 65536");
  EXPECT_EQ(ap::renderFrame(f::AccuracyNotReached{"cost_error", 2.5e-3, 1e-3, 512}, reason),
            "accuracy_target not reached: cost_error 0.0025 > target 0.001 at N = 512 after 4 "
            "refinements (round-off floor?)");
}
