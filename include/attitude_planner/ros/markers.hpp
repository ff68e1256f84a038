// The tracker's rviz vocabulary: one colour per meaning (MarkerMeaning), the legend drawn from the
// same table, and the markers that must not depend on the order in which tf and markers reach
// rviz (the constrained body axes and the boresight, drawn in the world frame from the attitude).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <ros/time.h>
#include <std_msgs/ColorRGBA.h>
#include <visualization_msgs/MarkerArray.h>

#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// One meaning of a colour on the canvas: the legend's words, the colour (RGB; each marker keeps
/// its own alpha) and the marker namespaces drawn in it. No two meanings share a colour.
struct MarkerMeaning {
  std::string legend;                   ///< what the colour means, as the legend says it
  float r, g, b;                        ///< the colour
  std::vector<std::string> namespaces;  ///< marker ns drawn in it
};

/// Every colour the tracker draws with, in the legend's order.
const std::vector<MarkerMeaning>& markerMeanings();

/// The colour of the markers of namespace `ns`, with alpha `alpha`; throws std::out_of_range for
/// a namespace no meaning lists (every marker the tracker draws is in the legend).
std_msgs::ColorRGBA meaningColour(const std::string& ns, float alpha = 1.0f);

/// The legend: one TEXT_VIEW_FACING line per meaning, in its colour, stacked in `world_frame`
/// beside the body (x = 0.4, y = −0.7 `path_radius`, from z = 0.95 `path_radius` down), ns
/// "legend", ids 0.. (published latched once).
visualization_msgs::MarkerArray legendMarkers(const std::string& world_frame, double path_radius);

/// Arrows from the origin to `length` · R b in `world_frame` at `stamp`, drawn from the attitude
/// R (body → world) itself so that they need no tf: each cone's body axis b (ns
/// "keep_out_body_axis" / "keep_in_body_axis", id = the cone's place among the cones) and, for a
/// pointing end condition, the boresight b (ns "pointing_boresight", id 0).
visualization_msgs::MarkerArray bodyAxisMarkers(const std::vector<PlanningConstraint>& constraints,
                                                const std::optional<EndCondition>& pointing,
                                                const Matrix3& attitude, double length,
                                                const std::string& world_frame,
                                                const ros::Time& stamp);

/// The world directions the maneuver refers to, in `world_frame` (latched once per maneuver):
/// each cone's direction s from the origin to 1.5 `length` s (the Sun or target: ns
/// "keep_out_direction" / "keep_in_direction") and a pointing target d (ns "pointing_target").
visualization_msgs::MarkerArray worldDirectionMarkers(
    const std::vector<PlanningConstraint>& constraints, const std::optional<EndCondition>& pointing,
    double length, const std::string& world_frame);

/// Where the wheel-momentum bars stand, in units of `path_radius` (world frame): beside the body
/// in the shipped view, behind it (x −1.3), clear of the legend (x 0.4, y −0.7) and the traced
/// path (radius 1).
inline constexpr double kWheelBarsX = -1.3, kWheelBarsY = 0.2, kWheelBarsZ = -0.4;
inline constexpr double kWheelBarWidth = 0.1;         ///< bar edge
inline constexpr double kWheelBarHeight = 0.8;        ///< a bar at its limit H_i
inline constexpr double kWheelBarMostFraction = 1.5;  ///< taller bars (past 1.5 H_i) are cut

/// The wheel momenta as bars (`wheel_momentum_markers`, per sample): wheel i (0-based) a CUBE of
/// height |h_i| / H_i · kWheelBarHeight · path_radius standing on the base (ns "wheel_momentum",
/// id i) and a flat slab at the limit's height (ns "wheel_momentum_limit", id i), left to right
/// in `world_frame`, coloured by markerMeanings(): a bar reaching its slab is at its limit.
visualization_msgs::MarkerArray wheelMomentumMarkers(const ReactionWheels& wheels,
                                                     const Eigen::VectorXd& momentum,
                                                     double path_radius,
                                                     const std::string& world_frame,
                                                     const ros::Time& stamp);

}  // namespace attitude_planner
