// Boundary value problem of seed 001, (3.8)–(3.10): find the initial costate p(0) whose normal
// extremal steers g0 to g1 in the fixed time T.
//
// Shooting on the three unknowns p(0) with a Taylor-series integrator of the continuous extremal
// flow (order 20, step from the series' own convergence radius, local error ~1e-16): the step
// sequence depends on p(0) only, never on the output sampling N, so the extremal found and its
// cost are the same for every N; N only sets where the extremal is sampled (dense output of the
// same series). Sensitivities are exact (forward-mode dual numbers through the same series).
//
// Extremals are not unique (they differ in how often the controls wind about the drift axis).
// Without a guess the planner starts from every extremal of the symmetric problem c1 = c2 = c̄
// (closed form, docs/design/drift_two_input.md) up to a cost bound, carries each to the requested
// weights (Levenberg–Marquardt, then continuation in the weights if needed), keeps the cheapest
// and reports the others' costs in `extremal`. A guess selects among extremals instead.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/drift_two_input/system.hpp"
#include "attitude_planner/termination.hpp"

namespace attitude_planner {

/// Everything a CLI or a ROS node needs to ask for a drift + two-input maneuver.
struct DriftTwoInputRequest {
  Matrix3 g0 = Matrix3::Identity();        ///< initial attitude g(0) (body → world)
  Matrix3 g1 = Matrix3::Identity();        ///< required final attitude g(T) (body → world)
  double duration = 1.0;                   ///< T [s]
  int steps = 100;                         ///< output intervals N: samples k = 0..N at t_k = k T/N
  DriftTwoInputWeights weights;            ///< cost weights (c1, c2)
  std::optional<Vector3> initial_costate;  ///< guess for p(0) [c·rad/s]; none: structured starts
  double max_step = 0.0;     ///< optional bound on the integrator's step [s]; 0 = adaptive only
  double tolerance = 1e-11;  ///< required terminal error |log(g1ᵀ g(T))| [rad]
  int max_iterations = 200;  ///< Newton (Levenberg–Marquardt) iterations per start, all stages
  int max_continuation_stages = 64;  ///< bound on the weight-continuation stages per start
  int shooting_intervals = 1;  ///< 1: single shooting; M > 1: multiple shooting on M intervals
  double time_budget_s = 0.0;  ///< wall-time limit of the whole solve [s]; 0 = none
};

/// Result of planDriftTwoInput: the extremal found (or the best attempt) and how it went.
struct DriftTwoInputPlan {
  /// Converged (terminal_error ≤ tolerance), NotConverged, TimedOut (the time budget stopped
  /// the search) or StepTooLarge (the extremal could not be integrated); the message says why.
  Termination termination = Termination::NotConverged;
  bool converged() const { return termination == Termination::Converged; }
  std::string message;  ///< what happened, including which extremal (p(0), cost) was found
  /// Which extremal was returned among those found, e.g. "least cost of 5 distinct extremals
  /// found from 8 starts; the others cost 12.4, 31.0, ...".
  std::string extremal;
  std::vector<double> other_costs;            ///< costs of the other extremals found, ascending
  Vector3 initial_costate = Vector3::Zero();  ///< p(0) of the extremal [c·rad/s]
  double cost = 0.0;                          ///< ½∫(c1 u1² + c2 u2²) dt [cost]
  double terminal_error = 0.0;  ///< |log(g1ᵀ g(T))| of the returned trajectory [rad]
  int iterations = 0;           ///< Newton iterations, all starts and stages
  int continuation_stages = 0;  ///< weight-continuation stages of the returned extremal (1: none)
  int starts = 0;               ///< starts tried
  int converged_starts = 0;     ///< starts that reached g1
  int integration_steps = 0;    ///< Taylor steps over [0, T] (independent of N)
  DriftTwoInputTrajectory trajectory;  ///< t, u1/u2, p, g on the N+1 output samples
};

/// Terminal error r(p0) = log(g1ᵀ g(T; p0)) [rad] of the extremal from (g0, p0) and its Jacobian
/// ∂r/∂p0 (exact, dual numbers; pass nullptr for the value only), by the planner's Taylor
/// integrator (max_step > 0 bounds its step). Throws StepTooLarge if p0 is so large that the
/// integration would take more than a million steps.
void driftTwoInputShootingResidual(const Matrix3& g0, const Matrix3& g1, double T,
                                   const DriftTwoInputWeights& w, const Vector3& p0,
                                   Vector3* residual, Matrix3* jacobian, double max_step = 0.0);

/// Samples the extremal from (g0, p0) at t_k = k T/N, k = 0..N, by the planner's Taylor
/// integrator (dense output: the step sequence does not depend on N), with the cost
/// ½∫(c1 u1² + c2 u2²) dt integrated along. Throws InvalidInput on bad arguments and
/// StepTooLarge as driftTwoInputShootingResidual.
DriftTwoInputTrajectory sampleDriftTwoInputExtremal(const Matrix3& g0, const Vector3& p0, double T,
                                                    int steps, const DriftTwoInputWeights& w,
                                                    double max_step = 0.0,
                                                    int* integration_steps = nullptr);

/// Solves the BVP (3.8)–(3.10); throws InvalidInput on a malformed request (names the field).
/// Never throws for a non-converged solve: `termination` says how it ended and `message` why.
DriftTwoInputPlan planDriftTwoInput(const DriftTwoInputRequest& request);

}  // namespace attitude_planner
