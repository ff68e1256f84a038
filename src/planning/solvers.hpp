// The solvers behind planManeuver(). Call planManeuver() rather than these directly: it
// validates the problem, times the solve and fills the common figures.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Newton's method on the first-order optimality conditions, O(N) per iteration
/// (newton_solver.cpp). Fills everything but solve_time_s.
PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options);

/// Primal–dual interior point on the reduced problem with the node constraints (per-axis torque
/// bounds, PlanningProblem::constraints), O(N) per iteration (interior_point_solver.cpp). Starts
/// from options.warm_start if given. Sets PlanResult::infeasible when the constraints cannot be
/// met. Fills everything but solve_time_s and the constraint figures.
PlanResult solveWithInteriorPoint(const PlanningProblem& problem, const SolverOptions& options);

/// The interior point on the requested grid directly, from options.warm_start (a plan given as
/// the initial guess, with the problem's N: initialGuessOnGrid) with its multipliers re-derived
/// from stationarity at the guess (multiplier_estimate.hpp) and the small barrier of a warm
/// level; free slacks with the predictor–corrector first, the elastic form as the retry.
PlanResult solveWithInteriorPointFromGuess(const PlanningProblem& problem,
                                           const SolverOptions& options);

/// The steps ω_k, k = 0..N−1, of the Newton solver's first guess on the requested grid (the
/// rate-honouring Hermite curve to the nearest lift, or the other way round for LongWay), before
/// any continuation level: the start a peer solver gets in a like-for-like comparison
/// (benchmark_solvers --random-suite). Throws StepTooLarge like ReducedProblem.
std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem);

/// Independent cross-check: NLopt on the direct method (τ_1..τ_{N−1} as variables, equality
/// constraints on the terminal state, exact gradients) (nlopt_solver.cpp).
PlanResult solveWithNlopt(const PlanningProblem& problem, const SolverOptions& options);

/// Fills result->maneuver with `planned` (the solver's own trajectory) and its cost and
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

}  // namespace attitude_planner
