// How every solver's plan is judged: its figures measured the same way for every solver, and the
// one convergence rule beside each solver's own first-order test.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Fills result->maneuver with `planned` (the solver's own trajectory; `planned` may be
/// &result->maneuver itself, built in place, then nothing is copied) and its cost and
/// step_residual; without `planned`, with the replay of `torque` (replayFigures), which is then
/// also the plan. Every solver finishes through here, so every figure is measured the same way.
/// The replay of a planned trajectory is left to replayFigures, which planAtResolution calls once
/// for the plan it returns (not for every grid level and start: at N = 512 with torque limits
/// those replays were a fifth of the solve). Throws StepTooLarge if a replay's implicit step
/// fails.
void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result, const Maneuver* planned = nullptr);

/// Replays the plan's torques τ_k (k = 0..N, τ_0 = τ_N = 0 but with end torques) through the
/// problem's scheme from R_0, Ω_0 and sets dynamics_residual, the terminal errors and replay_miss
/// (`replay`: where to keep the replayed maneuver, or null). Throws StepTooLarge if the replay's
/// implicit step fails.
void replayFigures(const PlanningProblem& problem, PlanResult* result, Maneuver* replay = nullptr);

/// The one convergence rule beside first-order optimality (which each solver tests on its own
/// iterate): the plan satisfies the discrete equations of motion step by step
/// (measureStepResidual within its tolerance) and, with `constraints`, its node constraints
/// (ConstraintCheck::max_relative_violation ≤ kNodeConstraintTolerance). Returns why not, or "" if
/// it does. The open-loop replay (replay_miss) is not part of it.
std::string planInconsistency(const PlanningProblem& problem, const PlanResult& result,
                              bool constraints);

/// Why a plan is not in the homotopy class its extremal names (empty: nothing says it is not).
/// The class is the lift φ of R_1ᵀR_{N−1} its solve started on (ExtremalSummary::angle = |φ|);
/// along a continuous lift of the plan's path, |φ| grows at most as fast as the body turns, so a
/// plan ending on that lift turns at least |φ| between R_1 and R_{N−1}. A path more than half a
/// turn shorter is in another class (e.g. the nearest one, after a solve labelled with extra
/// turns slid back); within half a turn it counts as its class (see the definition).
std::string classInconsistency(const PlanResult& result);

/// Sets the terminal errors of an open-loop replay and replay_miss, the larger of the attitude
/// miss and T × the velocity miss (one rule for every scheme's replay).
void setReplayMiss(const PlanningProblem& problem, const Maneuver& replayed, PlanResult* result);

}  // namespace attitude_planner
