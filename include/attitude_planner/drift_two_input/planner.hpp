// Boundary value problem of seed 001, (3.8)–(3.10): find the initial costate p(0) whose normal
// extremal steers g0 to g1 in the fixed time T. Single shooting on the terminal error
// log(g1ᵀ g(T)) with exact sensitivities (forward-mode dual numbers through the same
// structure-preserving scheme), Newton with a backtracking line search, and continuation on the
// target attitude along the geodesic from the guess's endpoint to g1 when a direct solve fails;
// optionally multiple shooting (shooting_intervals > 1) for long horizons.
//
// Extremals are not unique (e.g. ones that wind once more about the drift axis): the plan says
// which one was found through p(0) and its cost; a request's guess selects among them.
#pragma once

#include <optional>
#include <string>

#include "attitude_planner/drift_two_input/system.hpp"

namespace attitude_planner {

/// Everything a CLI or a ROS node needs to ask for a drift + two-input maneuver.
struct DriftTwoInputRequest {
  Matrix3 g0 = Matrix3::Identity();        ///< initial attitude g(0) (body → world)
  Matrix3 g1 = Matrix3::Identity();        ///< required final attitude g(T) (body → world)
  double duration = 1.0;                   ///< T [s]
  int steps = 100;                         ///< output intervals N: samples k = 0..N at t_k = k T/N
  DriftTwoInputWeights weights;            ///< cost weights (c1, c2)
  std::optional<Vector3> initial_costate;  ///< guess for p(0) [c·rad/s]; default 0 (u ≡ 0)
  double max_step = 0.01;                  ///< bound on the internal step [s] (4th-order scheme)
  double tolerance = 1e-11;                ///< required terminal error |log(g1ᵀ g(T))| [rad]
  int max_iterations = 200;                ///< Newton iterations over all continuation stages
  int max_continuation_stages = 64;        ///< bound on the number of intermediate targets
  int shooting_intervals = 1;  ///< 1: single shooting; M > 1: multiple shooting on M intervals
};

/// Result of planDriftTwoInput: the extremal found (or the best attempt) and how it went.
struct DriftTwoInputPlan {
  bool converged = false;  ///< terminal_error ≤ tolerance
  std::string message;     ///< what happened, including which extremal (p(0), cost) was found
  Vector3 initial_costate = Vector3::Zero();  ///< p(0) of the extremal [c·rad/s]
  double cost = 0.0;                          ///< ½∫(c1 u1² + c2 u2²) dt [cost]
  double terminal_error = 0.0;         ///< |log(g1ᵀ g(T))| of the returned trajectory [rad]
  int iterations = 0;                  ///< Newton iterations, all stages
  int continuation_stages = 0;         ///< targets solved (1: direct solve)
  int substeps = 1;                    ///< internal steps per output interval
  DriftTwoInputTrajectory trajectory;  ///< t, u1/u2, p, g on the N+1 output samples
};

/// Terminal error r(p0) = log(g1ᵀ g(T; p0)) [rad] and its Jacobian ∂r/∂p0 (exact, dual numbers),
/// for n_steps steps of the given order; throws StepTooLarge if an implicit step fails.
void driftTwoInputShootingResidual(const Matrix3& g0, const Matrix3& g1, double T, int n_steps,
                                   int order, const DriftTwoInputWeights& w, const Vector3& p0,
                                   Vector3* residual, Matrix3* jacobian);

/// Solves the BVP (3.8)–(3.10); throws InvalidInput on a malformed request (names the field).
/// Never throws for a non-converged solve: converged = false and message says why.
DriftTwoInputPlan planDriftTwoInput(const DriftTwoInputRequest& request);

}  // namespace attitude_planner
