// The clauses of an answer's message, as data (PlanResult::clauses): a solver's own words
// (`clauses::Reason`), a verdict (driver_verdict.hpp), the notes that follow a reason, and the
// frames said around it. The message is their fold, worded in one place
// (src/planning/problem/message_notes: renderMessage); a caller reads the figures from the
// answer's fields and from these structs, never from the words.
#pragma once

#include <cstddef>
#include <string>
#include <variant>
#include <vector>

#include "attitude_planner/planning/driver_verdict.hpp"
#include "attitude_planner/termination.hpp"

namespace attitude_planner {

/// One clause of a message (defined below); a note or a frame that says another solve's reason
/// holds that solve's clauses, rendered where the message it is part of is rendered.
struct MessageClause;
/// A message as data: its clauses in the order they were recorded.
using MessageClauses = std::vector<MessageClause>;

namespace notes {

/// The interior point's other formulation tried from the same start after the first stopped
/// (drivers/constrained_recipe.cpp: the formulation recipe). `solved`: its answer is returned, else
/// the first's is, and `reason` is the other solve's message. `within_bounds`: the retry is
/// returned though it stopped too, its plan within the bounds where the first's was not.
struct FormulationRetry {
  std::string retry;  ///< the retry's formulation ("elastic", ...)
  std::string first;  ///< the first one's
  bool solved = false;
  MessageClauses reason;  ///< the other solve's clauses
  bool within_bounds = false;
};
/// A 4x refinement that stopped, reached once more through the level in between (N = `steps`).
struct ReachedThroughMiddle {
  int steps = 0;
  MessageClauses reason;  ///< the direct refinement's clauses
};
/// The interior point's levels: the coarsest one's N.
struct GridContinuation {
  int steps = 0;
};
/// Cones with other limits, from a start inside a cone: the cones alone, then every constraint.
struct RetriedInTwoStages {
  MessageClauses reason;  ///< the first solve's clauses
};
/// The interior point from the caller's plan of this N, its multipliers re-derived.
struct FromInitialGuess {};
/// Newton's grid continuation: the level below the requested grid (N = `steps`) and how it ended:
/// converged, its plan started the requested grid, else the geodesic did.
struct CoarserLevel {
  int steps = 0;
  Termination termination = Termination::Converged;
};
/// Newton's class survey on a coarser grid (N = `steps`), its chosen class refined.
struct RefinedFromSurvey {
  int steps = 0;
};
/// The unconstrained optimum met every node constraint: it is the answer.
struct ConstraintsInactive {};
/// The unconstrained optimum (cost `cost`) violates `worst` at `where` (empty `worst`: only a
/// cone's margin) and started the interior point after `newton_iterations`.
struct UnconstrainedStart {
  double cost = 0.0;
  std::string worst;
  std::string where;
  int newton_iterations = 0;
};
/// The interior point from the caller's guess stopped; the answer is the usual start's.
struct AfterGuessStopped {
  MessageClauses reason;  ///< the solve from the guess's clauses
};
/// An answer that is no plan (infeasible, stopped) whose torques also fail the replay.
struct LastIterateDoesNotReplay {
  std::string reason;  ///< the replay's failure
};
/// A converged plan that replays step by step from its own states (within `step_angle` rad)
/// whose torques replayed open-loop parted from it until a step had no root (`what`): an
/// unstable motion's sensitivity, replay_miss +inf.
struct OpenLoopReplayParted {
  std::string what;
  double step_angle = 0.0;
};
/// A request with its class left free: another class under the constraints is cheaper.
struct CheapestClass {
  MessageClauses reason;  ///< the first class's (the unconstrained optimum's) clauses
};
/// A class's plan that cut a cone between nodes (by `cut` rad past its half angle), solved again
/// from itself with every cone's node bound tightened by up to `margin` rad: the margin its
/// longest step needs (PlanningConstraint::margin, requiredConeMargin), so the motion between
/// the nodes keeps the cones too.
struct ConesTightenedBetweenNodes {
  double cut = 0.0;
  double margin = 0.0;
};
/// A pointing request where no start converged: the last start's reason.
struct LastPointingStart {
  std::string reason;
};
/// A constrained pointing request whose free-twist solves did not converge, answered with the
/// cheapest converged fixed-attitude plan at one twist (the twist not optimized).
struct FixedTwistFallback {
  double twist = 0.0;  ///< ψ [rad] of the plan returned
  std::string reason;  ///< the free-twist solve's message there
};
/// A bounded pointing request not converged at T where minimum time with the twist free found
/// T* <= T: plans exist, the restart from the minimum-time plan is not served for pointing yet.
struct PointingRestartNotServed {
  double minimum_duration = 0.0;  ///< T* [s]
};
/// The minimum-time search's summary (drivers/minimum_time_search.cpp renders its bracket, the
/// starts' least durations and the solves from its outcomes).
struct SearchSummary {
  std::string summary;
};
/// Spinning ends: a probe below T* = `previous` found a plan at T = `duration`, and the free-time
/// solve from it descended to a lower KKT point.
struct DescendedFromProbe {
  double duration = 0.0;
  double previous = 0.0;
};
/// Spinning ends: the probes below T* stopped at their work allowance (`work_allowance`
/// node-iterations, AdvancedParameters::search_work_allowance) before they ran out of durations to
/// try: a lower T* may exist.
struct ProbesStopped {
  double work_allowance = 0.0;
};
/// Minimum time searched on T instead of solved free-time, and `why`.
struct SearchedOnT {
  std::string why;
};
/// The search's plan (T = `duration`) started the free-time solve that answers.
struct SharpenedFromSearch {
  std::string why;  ///< why the structured starts did not answer
  double duration = 0.0;
};
/// The plan at (1 + `margin`) T* (T = `duration`) from the T* plan.
struct PlannedAtMargin {
  double margin = 0.0;
  double duration = 0.0;
  double minimum_duration = 0.0;  ///< T*
};
/// A bounded minimum-effort request restarted from the minimum-time plan at T* after its first
/// solve `why`: directly, else through a ladder of durations from T*.
struct MinimumTimeRestart {
  double minimum_duration = 0.0;  ///< T*
  std::string why;
  bool ladder_reached = false;                     ///< the ladder reached T (its plan answers)
  Termination direct = Termination::NotConverged;  ///< the direct start's end
  bool ladder_tried = false;
  double ladder_longest = 0.0;  ///< the longest T it found a plan at (0: none)
};
/// How a restart that did not beat the first answer ended (after MinimumTimeRestart).
struct RestartEnded {
  Termination termination = Termination::NotConverged;
  MessageClauses reason;  ///< the restart's clauses
};
/// The first solve `why` and the minimum-time problem under the same bounds ended `termination`.
struct MinimumTimeUnsolved {
  std::string why;
  Termination termination = Termination::NotConverged;
};
/// A bounded answer that stopped short of optimality whose plan still meets the dynamics, the ends
/// and every bound at T = `duration` (DurationVerdict::plan_within_bounds).
struct PlanWithinBounds {
  double duration = 0.0;
};

/// A pointing answer's twist ψ [rad] and the stationarity in ψ: with constraints or bounds
/// (`lagrangian`) ∂L/∂ψ and its relative size, else ∂C/∂ψ.
struct PointingTwist {
  double twist = 0.0;
  double gradient = 0.0;
  bool lagrangian = false;
  double relative = 0.0;  ///< with `lagrangian`
};

/// A requested accuracy reached: the `measure`'s estimate `error` <= `target` at N = `steps`
/// with `scheme` (planToAccuracy).
struct AccuracyReached {
  std::string measure;
  double error = 0.0;
  double target = 0.0;
  int steps = 0;
  std::string scheme;
};

}  // namespace notes

using Note =
    std::variant<notes::FormulationRetry, notes::ReachedThroughMiddle, notes::GridContinuation,
                 notes::RetriedInTwoStages, notes::FromInitialGuess, notes::CoarserLevel,
                 notes::RefinedFromSurvey, notes::ConstraintsInactive, notes::UnconstrainedStart,
                 notes::AfterGuessStopped, notes::LastIterateDoesNotReplay,
                 notes::OpenLoopReplayParted, notes::CheapestClass,
                 notes::ConesTightenedBetweenNodes, notes::LastPointingStart,
                 notes::FixedTwistFallback, notes::PointingRestartNotServed, notes::SearchSummary,
                 notes::SearchedOnT, notes::SharpenedFromSearch, notes::PlannedAtMargin,
                 notes::MinimumTimeRestart, notes::RestartEnded, notes::MinimumTimeUnsolved,
                 notes::DescendedFromProbe, notes::ProbesStopped, notes::PlanWithinBounds,
                 notes::PointingTwist, notes::AccuracyReached>;

// The clauses that frame a message instead of following it: said before the reason they are
// given (and around it), worded here as the notes are (renderFrame).
namespace frames {

/// fourth_order's pair of second_order solves at N = `steps` and 2N; `from_plans_at_minimum_time`:
/// each solve started from its own plan at T* (minimum_time.cpp), else from the usual starts.
struct RichardsonPair {
  int steps = 0;
  bool from_plans_at_minimum_time = false;
};
/// A solve of the pair did not converge (the one at N = `stopped_steps`): its plan is returned,
/// the reason it is given is that solve's message.
struct PairSolveStopped {
  RichardsonPair pair;
  int stopped_steps = 0;
};
/// Both solves converged and were combined; the reason it is given is the N solve's message.
/// `replaced`: the plan is the N solve's (the combination left a bound both meet).
struct PairCombined {
  RichardsonPair pair;
  bool replaced = false;
  MessageClauses fine_reason;  ///< the 2N solve's clauses
};
/// fourth_order minimum time: a solve of its pair of second_order problems (N = `steps` and 2N)
/// did not converge, the one at 2N (`at_fine`) or at N: its minimum-time problem, or
/// (`effort_at_minimum_time`) the other one's minimum-effort plan at the binding T*; its plan is
/// returned, the reason it is given is that solve's message.
struct MinimumTimePairStopped {
  int steps = 0;
  bool at_fine = false;
  bool effort_at_minimum_time = false;
};
/// fourth_order minimum time from its pair: T* = max(T* at N, T* at 2N), the one at 2N binds
/// (`fine_binds`) or the one at N; `replaced`: the plan is the N plan at T* (see PairCombined).
/// The reason it is given is the N solve's message, said last.
struct MinimumTimePairCombined {
  int steps = 0;
  double minimum_duration = 0.0;  ///< T*
  double at_coarse = 0.0;         ///< T* at N
  double at_fine = 0.0;           ///< T* at 2N
  bool fine_binds = false;
  bool replaced = false;
  MessageClauses fine_reason;  ///< the 2N solve's clauses
};
/// Spinning ends: a probe below T* = `previous` found a plan at T = `duration` from which the
/// free-time solve did not descend: T* ≤ `duration`, an upper bound; the reason it is given is the
/// probe's message.
struct UpperBoundFromProbe {
  double duration = 0.0;
  double previous = 0.0;
};
/// A bounded minimum-effort request at T (`requested`) ≥ T* = `minimum_duration` whose solves
/// from the minimum-time plan ended at infeasible points: rest to rest, feasible but not
/// converged; else, where the ladder of durations found plans up to `ladder_reached` (> 0), a
/// local "infeasible from here"; else not converged. The reason it is given is the last solve's.
struct StuckAtMinimumTimePlan {
  bool rest_to_rest = false;
  double minimum_duration = 0.0;
  double requested = 0.0;
  double ladder_reached = 0.0;
};
/// A converged plan outside the class the request named: `why` (classInconsistency), around the
/// plan's own message.
struct OutsideRequestedClass {
  std::string why;
};
/// The replay of a converged plan's torques failed (`what`), and its step `step` replayed from
/// the plan's own state lands `angle` rad from the plan's (+inf: no root), around the plan's own
/// message.
struct ReplayFailed {
  std::string what;
  int step = -1;
  double angle = 0.0;
};
/// Minimum time to a pointing end: the start twists solved (none: no start was solved), each
/// with its T* or its termination, and the one kept (-1: none); the reason it is given is the
/// kept answer's message, said last.
struct PointingStarts {
  struct Start {
    double twist = 0.0;  ///< ψ [rad]
    Termination termination = Termination::NotConverged;
    double minimum_duration = 0.0;  ///< T* [s] where converged
  };
  std::vector<Start> starts;
  int kept = -1;
};

/// A staged continuation (a rate continuation, an inertia homotopy: `what`) stopped at s =
/// `reached` of 1 after `stages` stages: no plan for the request; the reason it is given is its
/// last stage's message.
struct StagedUnfinished {
  std::string what;
  double reached = 0.0;
  int stages = 0;
};
/// Newton's walk: none of its `tried` attempts produced a plan on the requested grid; the reason
/// it is given is the last one's message.
struct NoAttemptPlanned {
  std::size_t tried = 0;
};
/// The interior point's continuation: a finer level ended "infeasible" after the level at N =
/// `feasible_steps` met every constraint, so not converged (its solver stopped at a local minimum
/// of the violation, no certificate); the reason it is given is the finer level's message.
struct FinerLevelStopped {
  int feasible_steps = 0;
};

/// A level of a continuation that stopped answers for the finer ones: its reason, said on the
/// level (N = `steps`) it was reached on.
struct OnContinuationLevel {
  int steps = 0;
};
/// A continuation cancelled or out of time (`stop`) on a coarser grid (N = `steps`: a level, or
/// Newton's class survey with `class_survey`): its iterate carried over to N = `requested` is the
/// plan. It replaces the reason it is given (the carried iterate's).
struct CarriedOverAfterStop {
  Termination stop = Termination::Cancelled;
  int steps = 0;
  int requested = 0;
  bool class_survey = false;
};
/// Newton's walk: the attempt kept (`kept_at`, 0-based, of `tried`; its stage and start), and,
/// where the walk was stopped (`stopped`: cancelled or out of time, `stop`) during an attempt
/// (its stage `during`) that is not the one kept, that stop first; the reason it is given is the
/// kept attempt's message.
struct WalkKept {
  bool stopped = false;
  Termination stop = Termination::Cancelled;
  std::string during;
  std::size_t kept_at = 0;
  std::size_t tried = 0;
  std::string kept_stage;
  std::string kept_start;
};
/// A pointing request's starts: the attempt kept (`kept_at`, 0-based, of `attempts`), whether no
/// start converged (`none_converged`, of `starts`), and how the starts were drawn (`survey`:
/// none, the interior point from the plan given; `constrained`: the constrained survey, else
/// start twists x ways round); the reason it is given is the kept run's message, said first.
struct PointingWalk {
  bool none_converged = false;
  std::size_t starts = 0;
  std::size_t kept_at = 0;
  std::size_t attempts = 0;
  bool survey = true;
  bool constrained = false;
  int start_twists = 0;
  std::size_t ways_round = 0;
};

/// A requested accuracy: the N/2 = `half_steps` solve of the Richardson estimate did not
/// converge; the reason it is given is that solve's.
struct RichardsonHalfStopped {
  int half_steps = 0;
};
/// A requested accuracy: the coarse resolution (N = 64) with `scheme` did not converge; the
/// reason it is given is that solve's.
struct CoarseResolutionStopped {
  std::string scheme;
};
/// A requested accuracy `target` of `measure` needs N = `steps` > max_steps: the finest plan
/// solved is returned. It replaces the reason it is given.
struct AccuracyNeedsSteps {
  double target = 0.0;
  std::string measure;
  int steps = 0;
  int max_steps = 0;
};
/// A requested accuracy not reached after 4 refinements: the `measure`'s estimate `error` >
/// `target` at N = `steps`. It replaces the reason it is given.
struct AccuracyNotReached {
  std::string measure;
  double error = 0.0;
  double target = 0.0;
  int steps = 0;
};

}  // namespace frames

using Frame =
    std::variant<frames::PairSolveStopped, frames::PairCombined, frames::MinimumTimePairStopped,
                 frames::MinimumTimePairCombined, frames::UpperBoundFromProbe,
                 frames::StuckAtMinimumTimePlan, frames::OutsideRequestedClass,
                 frames::ReplayFailed, frames::PointingStarts, frames::StagedUnfinished,
                 frames::NoAttemptPlanned, frames::FinerLevelStopped, frames::OnContinuationLevel,
                 frames::CarriedOverAfterStop, frames::WalkKept, frames::PointingWalk,
                 frames::RichardsonHalfStopped, frames::CoarseResolutionStopped,
                 frames::AccuracyNeedsSteps, frames::AccuracyNotReached>;

namespace clauses {

/// Words a solver or a driver says that no kind, note or frame holds yet (a caught error's text):
/// they replace what the message said before.
struct Reason {
  std::string words;
};

}  // namespace clauses

/// One clause of a message: folded in order, a Reason sets the message, a Verdict words it with
/// the message so far as its reason, a Note is appended, a Frame words its clause around it. A
/// class (not an alias) so that notes and frames can hold clauses (MessageClauses).
struct MessageClause : std::variant<clauses::Reason, Verdict, Note, Frame> {
  using variant::variant;
};

}  // namespace attitude_planner
