// The reaction wheels' peaks (per wheel |h_w,i| and |u_i|, the array's |A h_w|) over a plan's nodes
// or a flown path, against the array's limits: what the JSON summary's `reaction_wheels`, the
// services' ReactionWheelsSummary and the tracker's `done` report (one place for the rule).
#pragma once

#include <string>

#include <Eigen/Core>

#include "attitude_planner/planning/reaction_wheels.hpp"

namespace attitude_planner {

/// The name of wheel i (0-based) in every output: "wheel_1", "wheel_2", ...
inline std::string wheelName(int i) {
  return "wheel_" + std::to_string(i + 1);
}

/// Peaks seen so far (all 0 before any observation).
struct WheelPeaks {
  Eigen::VectorXd peak_momentum;    ///< max |h_w,i| [N m s], per wheel
  Eigen::VectorXd peak_torque;      ///< max |u_i| [N m], per wheel
  double peak_momentum_norm = 0.0;  ///< max |A h_w| [N m s]

  explicit WheelPeaks(int wheels = 0)
      : peak_momentum(Eigen::VectorXd::Zero(wheels)), peak_torque(Eigen::VectorXd::Zero(wheels)) {}
  /// Takes wheel momenta h_w (n entries; `axes` = A of the array).
  void observeMomentum(const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                       const Eigen::VectorXd& momentum);
  /// Takes wheel torques u (n entries).
  void observeTorque(const Eigen::VectorXd& torque);
  /// The largest excess of a peak over its limit (per-wheel momentum and torque, the envelope)
  /// [N m s or N m], ≤ 0 when every limit holds; `which` (if not null) names it, e.g.
  /// "wheel_2 momentum".
  double worstExcess(const ReactionWheels& wheels, std::string* which = nullptr) const;
};

/// The peaks over a plan's wheel states: momenta at every node k = 0..N, torques at the nodes the
/// plan carries torques at (1..N−1; 0..N when `end_torques`, schemeHasEndTorques).
WheelPeaks planWheelPeaks(const ReactionWheels& wheels, const WheelStates& states,
                          bool end_torques);

}  // namespace attitude_planner
