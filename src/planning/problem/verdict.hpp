// How every solver's plan is judged: its figures measured the same way for every solver, and the
// one convergence rule beside each solver's own first-order test.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "attitude_planner/planning/verdict.hpp"

namespace attitude_planner {

/// Fills result->maneuver with `planned` (the solver's own trajectory; `planned` may be
/// &result->maneuver itself, built in place, then nothing is copied) and its cost and
/// step_residual; without `planned`, with the replay of `torque` (replayFigures), which is then
/// also the plan. Every solver finishes through here, so every figure is measured the same way.
/// The replay of a planned trajectory is left to replayFigures, which planAtResolution calls once
/// for the plan it returns (not for every grid level and start: at N = 512 with torque limits
/// those replays were a fifth of the solve). Throws StepTooLarge if a replay's implicit step
/// fails. `residual` (optional) receives the step residual measured, for planInconsistency.
void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result, const Maneuver* planned = nullptr,
                  StepResidual* residual = nullptr);

/// Replays the plan's torques τ_k (k = 0..N, τ_0 = τ_N = 0 but with end torques) through the
/// problem's scheme from R_0, Ω_0 and sets dynamics_residual, the terminal errors and replay_miss
/// (`replay`: where to keep the replayed maneuver, or null). Throws StepTooLarge if the replay's
/// implicit step fails.
void replayFigures(const PlanningProblem& problem, PlanResult* result, Maneuver* replay = nullptr);

/// Measures the result's plan against the problem's node constraints and sets the four figures a
/// user reads of them (constraints, max_constraint_violation, max_violation_between_nodes,
/// active_constraints): one place for every plan that is answered.
void recordConstraintFigures(const PlanningProblem& problem, PlanResult* result);

struct StepwiseReplay;

/// The one convergence rule beside first-order optimality (which each solver tests on its own
/// iterate): the plan satisfies the discrete equations of motion step by step
/// (measureStepResidual within its tolerance), each of its steps is the one the scheme's own
/// step solve finds from the plan's state (replayStepByStep: not a step on another root of its
/// momentum map) and, with `constraints`, its node constraints
/// (ConstraintCheck::max_relative_violation ≤ kNodeConstraintTolerance). Returns why not, or "" if
/// it does. The open-loop replay (replay_miss) is not part of it. `measured`: the plan's step
/// residual if evaluatePlan measured it already (measureStepResidual of the same plan).
/// `stepwise`: the plan's stepwise replay if measured already (replayStepByStep of the same plan,
/// e.g. joined from pieces measured at once: stepReplayAngles, worstStepReplay).
std::string planInconsistency(const PlanningProblem& problem, const PlanResult& result,
                              bool constraints, const StepResidual* measured = nullptr,
                              const StepwiseReplay* stepwise = nullptr);

/// Whether `r` holds a plan at the problem's T within every bound: the one judgement of "a plan
/// at T exists" (a stopped solve that answers the interior point's formulation retry, the
/// minimum-time search's and probes' feasible durations, a bounded answer's plan_within_bounds).
/// A converged answer holds one by its verdict. A solve that stopped short of optimality
/// (NotConverged: the iteration limit, a stalled line search) holds one when its iterate is a plan
/// on the problem's own grid that meets the discrete equations step by step, its ends and every
/// node constraint (planInconsistency with constraints, within kStepResidualTolerance and
/// kNodeConstraintTolerance): a plan at T, not shown optimal. Nothing else does: an infeasible
/// end, a stop by the clock or a cancel, or a scheme without discrete equations of its own
/// (fourth_order's unconverged answer is the second_order sub-plan that stopped).
bool provesFeasible(const PlanningProblem& problem, const PlanResult& r);

/// Why a plan is not in the homotopy class its extremal names (empty: nothing says it is not).
/// The class is the lift φ of R_1ᵀR_{N−1} its solve started on (ExtremalSummary::angle = |φ|);
/// along a continuous lift of the plan's path, |φ| grows at most as fast as the body turns, so a
/// plan ending on that lift turns at least |φ| between R_1 and R_{N−1}. A path more than half a
/// turn shorter is in another class (e.g. the nearest one, after a solve labelled with extra
/// turns slid back); within half a turn it counts as its class (see the definition).
std::string classInconsistency(const PlanResult& result);

/// A plan replayed step by step: each step k solved by the open-loop replay's own implicit-step
/// solve (DiscreteScheme::solveStep) from the plan's state, the momentum c_k it carries and, as
/// the replay warm-starts, the plan's step k − 1. A consistent plan (measureStepResidual) has
/// each F_k a root of its momentum map; this says whether it is the root the replay finds: a
/// step on another root (past a fold) lands O(1) rad away, a consistent one within round-off
/// of its step residual. Unlike the open-loop replay, round-off does not grow along the plan.
struct StepwiseReplay {
  double worst_angle = 0.0;  ///< max_k ∠(F_k solved, F_k planned) [rad]; +inf: no root found
  int worst_step = -1;       ///< its k (−1: no step)
  /// Every step lands on the plan's own (1e-6 rad: far above a consistent plan's round-off,
  /// far below another root's distance).
  bool reproduces() const { return worst_angle <= 1e-6; }
};
StepwiseReplay replayStepByStep(const PlanningProblem& problem, const Maneuver& plan);
/// replayStepByStep's angle at each step k in [first, last) into (*apart)[k] (sized N): each
/// step's solve starts from the plan alone, so pieces of the plan may be measured apart (at
/// once, on other threads) and folded by worstStepReplay to replayStepByStep's result.
void stepReplayAngles(const PlanningProblem& problem, const Maneuver& plan, int first, int last,
                      std::vector<double>* apart);
/// The worst of the steps' angles, the first of equals, as replayStepByStep folds them.
StepwiseReplay worstStepReplay(const std::vector<double>& apart);

/// The open-loop replay of the plan's torques found no implicit step (`what`). An iterate that
/// is no answer (infeasible, stopped) keeps its verdict, the failure said after it. A converged
/// plan whose every step the replay's solve reproduces from the plan's own state
/// (replayStepByStep) is a plan: the open-loop replay has parted from it (round-off grows along
/// an unstable motion until a step has no root), a sensitivity, so replay_miss is +inf and the
/// verdict stands. One with a step the replay does not reproduce is not converged (never the
/// user's step count: the request's own N holds a consistent plan).
void judgeFailedReplay(const PlanningProblem& problem, const std::string& what, PlanResult* result);

/// Sets the terminal errors of an open-loop replay and replay_miss, the larger of the attitude
/// miss and T × the velocity miss (one rule for every scheme's replay).
void setReplayMiss(const PlanningProblem& problem, const Maneuver& replayed, PlanResult* result);

}  // namespace attitude_planner
