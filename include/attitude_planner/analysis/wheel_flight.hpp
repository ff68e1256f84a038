// A plan flown with reaction wheels (the tracker's ~mode replay of a maneuver with wheels): the
// plan's wheel torques u_k drive the continuous body + wheels (replayWithWheels: RK4, u held
// linearly between nodes, independent of the planner's algebra), and the flown path's wheel
// peaks are measured against the array's limits (WheelPeaks).
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

/// The body and wheels flown from a plan's wheel torques.
struct WheelFlight {
  /// The body at the nodes t_k: R, Ω and, in the torque column, the torque the array exerts on
  /// it, τ_k = −A u_k − Ω_k × A h_w,k [N m] (what `torque` shows for a wheel-driven body).
  Maneuver body;
  std::vector<Eigen::VectorXd> torque;    ///< u_k [N m], the wheel torques flown
  std::vector<Eigen::VectorXd> momentum;  ///< h_w(t_k) [N m s] of the flight
  /// Peaks along the flight: |h_w,i| at every RK4 substep, |A h_w| at the nodes, |u_i| at every
  /// node (all are flown; a linear hold between nodes never exceeds its ends).
  WheelPeaks peaks;

  /// u(t), h_w(t) at t ∈ [0, T]: linear between the nodes (u exactly as flown; h_w to O(h²)).
  Eigen::VectorXd torqueAt(double t) const;
  Eigen::VectorXd momentumAt(double t) const;
};

/// Flies `plan` (scheme `scheme`, inertia J) with the array `wheels` from `start` (the plan's
/// R_0, Ω_0 unless a running body takes it over) and the wheels at their initial_momentum:
/// `wheel_torque` (one vector of n per node; empty: the plan's own, wheelStates) through
/// replayWithWheels. The array must be valid (validateReactionWheels).
WheelFlight flyWithWheels(const Matrix3& inertia, SchemeKind scheme, const ReactionWheels& wheels,
                          const Maneuver& plan, std::vector<Eigen::VectorXd> wheel_torque,
                          const RigidBodyState& start);

}  // namespace attitude_planner
