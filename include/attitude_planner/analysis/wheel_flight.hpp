// A plan flown with reaction wheels (the tracker's ~mode replay of a maneuver with wheels): the
// plan's wheel torques u_k drive body + wheels through the plan's own discrete scheme
// (replayWithWheelsOnTheScheme: the Lie group integrator of the plan, derived independently of
// the planner's wheel quantities, so the plan comes back to round-off, as replayPlan does without
// wheels), or for fourth_order (not a discretization) the continuous body + wheels
// (replayWithWheels: RK4, u held linearly between nodes); the flown path's wheel peaks are
// measured against the array's limits (WheelPeaks).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/analysis/wheel_peaks.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/reaction_wheels.hpp"

namespace attitude_planner {

/// RK4 steps per plan step of the wheel flight (the replay's default).
inline constexpr int kWheelFlightSubsteps = 16;

/// Node rows (k = 0..N on t_k = k h) at time t ∈ [0, T], linear between the nodes (clamped to the
/// ends): how wheel torques are held between nodes.
Eigen::VectorXd heldLinearly(const std::vector<Eigen::VectorXd>& rows, double time_step, double t);

/// The body and wheels flown from a plan's wheel torques.
struct WheelFlight {
  /// The body at the nodes t_k: R, Ω and, in the torque column, the torque the array exerts on
  /// it, τ_k = −A u_k − Ω_k × A h_w,k [N m] (what `torque` shows for a wheel-driven body).
  Maneuver body;
  std::vector<Eigen::VectorXd> torque;    ///< u_k [N m], the wheel torques flown
  std::vector<Eigen::VectorXd> momentum;  ///< h_w(t_k) [N m s] of the flight
  /// Peaks along the flight: |h_w,i| at the nodes (and at every RK4 substep of a continuous
  /// flight), |A h_w| at the nodes, |u_i| at every node (all are flown; a linear hold between
  /// nodes never exceeds its ends).
  WheelPeaks peaks;

  /// u(t), h_w(t) at t ∈ [0, T]: linear between the nodes (u exactly as flown; h_w to O(h²)).
  Eigen::VectorXd torqueAt(double t) const;
  Eigen::VectorXd momentumAt(double t) const;
};

/// What a wheel flight integrates.
enum class WheelFlightModel {
  /// The plan's discrete scheme (paper, variational, second_order; replayWithWheelsOnTheScheme):
  /// the plan's own wheel torques reproduce its nodes to round-off. fourth_order, not a
  /// discretization, is flown Continuous.
  PlanScheme,
  /// The continuous body + wheels (replayWithWheels, kWheelFlightSubsteps RK4 steps per plan
  /// step, u held linearly between the nodes): follows a plan to O(h²).
  Continuous,
};

/// Flies `plan` (scheme `scheme`, inertia J) with the array `wheels` from `start` (the plan's
/// R_0, Ω_0 unless a running body takes it over; with PlanScheme the start velocity is the
/// scheme's boundary velocity Ω(0), as replayPlan takes it) and the wheels at their
/// initial_momentum: `wheel_torque` (one vector of n per node; empty: the plan's own,
/// wheelStates) through `model`. The body's rows are in the scheme's convention (paper,
/// variational: each step's reported velocity, row N repeating N − 1; second_order: the node
/// velocities J⁻¹Π_k), so ManeuverInterpolation reads them as a plan of `scheme`. The array must
/// be valid (validateReactionWheels). Throws StepTooLarge when a step solve of the scheme fails.
WheelFlight flyWithWheels(const Matrix3& inertia, SchemeKind scheme, const ReactionWheels& wheels,
                          const Maneuver& plan, std::vector<Eigen::VectorXd> wheel_torque,
                          const RigidBodyState& start,
                          WheelFlightModel model = WheelFlightModel::PlanScheme);

/// A closed loop flown by the wheels (the tracker's ~mode feedback with wheels).
struct WheelTracking {
  /// The body and wheels on the control grid t_j = j Δt (body.time_step = Δt), `torque` the
  /// wheel torques delivered over [t_j, t_{j+1}) (row M: the last one, held).
  WheelFlight flight;
  int substeps = 1;                ///< control samples per plan step
  double natural_frequency = 0.0;  ///< ω_n of the law [rad/s]
  /// ½∫|τ|² dt of the body torque the array delivered (the left sum on the control grid)
  /// [N²·m²·s]: what the feedback mode's `effort` is without wheels.
  double effort = 0.0;
  /// Control samples at which a wheel's command was cut: by its torque limit U_i, or to 0 because
  /// its momentum was at its limit H_i and the command would drive it further.
  int saturated_samples = 0;
  int samples = 0;  ///< control samples flown (M)
};

/// Tracks `reference` with the geometric law (TrackingLaw, its ω_n and control grid as
/// simulateTracking) through the wheels: at every control sample the law's body torque τ_c is
/// distributed over the wheels by the array's minimum-norm law, A u = −(τ_c + Ω × A h_w),
/// u = A⁺(A u) (docs/reaction_wheels.md); each u_i is then cut to ±U_i, and to 0 in the
/// direction that drives a wheel already at ±H_i further. The cut u is held over the period and
/// flies the continuous body + wheels (replayWithWheels, kWheelFlightSubsteps RK4 steps): the body
/// gets τ = −A u − Ω × A h_w, the array's reaction. No effects (the tracker refuses them with
/// wheels). Throws InvalidInput for bad options (naming them).
WheelTracking trackWithWheels(const ManeuverInterpolation& reference, const Matrix3& inertia,
                              const ReactionWheels& wheels, const RigidBodyState& start,
                              const TrackingOptions& options);

}  // namespace attitude_planner
