// The wording of an answer's message and the recording of its clauses (message_clauses.hpp):
// what happened, on which grid, how the solve it names ended, its figures, and the reason of the
// solve it refers to. Each clause is worded in one place (renderNote, renderFrame,
// renderVerdict) and the message is their fold (renderMessage), so a clause reads the same
// wherever it is recorded; the figures a caller needs are fields of the answer (PlanResult, its
// trail `attempts`, its `levels`, its `clauses`), never parsed from these words.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/planning/message_clauses.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// The clause's words ("; grid continuation from N = 8", ...), each starting with its separator.
std::string renderNote(const Note& note);
/// Adds the clause to the result's clauses (its message says it after what it says already).
void addNote(PlanResult* result, const Note& note);

/// The message `frame` makes of `reason` (the message it is given).
std::string renderFrame(const Frame& frame, const std::string& reason);
/// Adds the frame to the result's clauses (its message is framed by `frame`).
void frameMessage(PlanResult* result, const Frame& frame);

/// The message a driver's `verdict` makes (include/attitude_planner/planning/driver_verdict.hpp):
/// its words, then, for the kinds that judge a solve (LocallyInfeasible, MinimumTimeFoundNone,
/// FeasibleAtMinimumTime, SolverReason; MinimumTimeAnswer: a failed replay), `reason`, the
/// message of that solve; the kinds that
/// answer without one (before any solve, the search's end, no pointing start) do not read it.
std::string renderVerdict(const Verdict& verdict, const std::string& reason);
/// Records `verdict` on the result and adds it to its clauses (the reason it is given is the
/// message the result carried).
void recordVerdict(PlanResult* result, const Verdict& verdict);
/// The same for a solver's own outcome that carries a verdict and its clauses (FreeTimeOutcome).
template <class Outcome>
void recordVerdict(Outcome* outcome, const Verdict& verdict) {
  outcome->verdict = verdict;
  outcome->clauses.push_back(verdict);
}
/// Words no kind, note or frame holds yet (a caught error's text): the result's clauses start
/// again from them.
void recordReason(PlanResult* result, const std::string& words);
/// `to` is given `from`'s reason: its verdict and its clauses (a wrapper then frames it; a
/// driver's result takes its solver's outcome's).
template <class To, class From>
void carryReason(To* to, const From& from) {
  to->verdict = from.verdict;
  to->clauses = from.clauses;
}
/// `to` says `from`'s reason (its clauses) and keeps its own verdict: a plan made of other
/// solves' (a Richardson combination, a probe's plan) framed around one solve's reason.
void takeReason(PlanResult* to, const PlanResult& from);
/// The same from a reason kept as clauses (a level's end, a frame's own).
void takeReason(PlanResult* to, const std::vector<MessageClause>& clauses);

/// The message `clauses` make, folded in order (MessageClause).
std::string renderClauses(const std::vector<MessageClause>& clauses);
/// The message of `result`: renderClauses of its clauses (PlanResult::message).
std::string renderMessage(const PlanResult& result);

}  // namespace attitude_planner
