#include "attitude_planner/ros/markers.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {

namespace {

/// An ARROW from the origin to `tip` in `frame`, coloured by its namespace's meaning.
visualization_msgs::Marker worldArrow(const std::string& frame, const ros::Time& stamp,
                                      const std::string& ns, int id, const Vector3& tip,
                                      double length, float alpha) {
  visualization_msgs::Marker a;
  a.header.frame_id = frame;
  a.header.stamp = stamp;
  a.ns = ns;
  a.id = id;
  a.type = visualization_msgs::Marker::ARROW;
  a.action = visualization_msgs::Marker::ADD;
  a.pose.orientation.w = 1.0;
  a.points.push_back(ros_conversions::xyzToMsg<geometry_msgs::Point>(Vector3::Zero()));
  a.points.push_back(ros_conversions::xyzToMsg<geometry_msgs::Point>(tip));
  a.scale.x = 0.03 * length;  // shaft diameter [m]
  a.scale.y = 0.05 * length;  // head diameter [m]
  a.scale.z = 0.08 * length;  // head length [m]
  a.color = meaningColour(ns, alpha);
  return a;
}

}  // namespace

const std::vector<MarkerMeaning>& markerMeanings() {
  // The principal axes keep red, green, blue; the shipped rviz config hides the TF display's own
  // red-green-blue frame axes (it shows frame names), so the three colours mean one thing each.
  static const std::vector<MarkerMeaning> meanings = {
      {"body (box of its principal moments)", 0.55f, 0.7f, 0.95f, {"body"}},
      {"principal axis, smallest moment", 0.9f, 0.1f, 0.1f, {"principal_axis_smallest"}},
      {"principal axis, middle moment", 0.1f, 0.8f, 0.1f, {"principal_axis_middle"}},
      {"principal axis, largest moment", 0.1f, 0.3f, 1.0f, {"principal_axis_largest"}},
      {"traced body axis: planned path, start and target",
       1.0f,
       0.6f,
       0.0f,
       {"traced_axis", "attitude_path", "start_ghost_axis", "target_ghost_axis"}},
      {"traced body axis: flown trail", 1.0f, 0.9f, 0.2f, {"attitude_trail"}},
      {"start attitude (ghost)", 0.35f, 0.35f, 0.35f, {"start_ghost"}},
      {"target attitude (ghost)", 0.8f, 0.8f, 0.8f, {"target_ghost"}},
      {"keep-out cone, its direction (Sun) and body axis",
       0.9f,
       0.1f,
       0.85f,
       {"keep_out", "keep_out_direction", "keep_out_body_axis"}},
      {"keep-in cone, its direction (target) and body axis",
       0.1f,
       0.8f,
       0.9f,
       {"keep_in", "keep_in_direction", "keep_in_body_axis"}},
      {"pointing: boresight and target direction",
       0.6f,
       0.35f,
       1.0f,
       {"pointing_boresight", "pointing_target"}},
      {"status (t / T, angle to go, |tau|, pointing error)", 0.75f, 0.95f, 0.75f, {"status_text"}},
      {"wheel momentum |h_i| / H_i (bars: wheel_1, wheel_2, ... left to right)",
       0.8f,
       0.55f,
       0.3f,
       {"wheel_momentum"}},
      {"wheel momentum limit H_i (slab over each bar)",
       1.0f,
       0.35f,
       0.45f,
       {"wheel_momentum_limit"}},
      // Not a marker: rviz's WrenchStamped display of `torque` (rviz/maneuver.rviz's Torque Color).
      {"delivered torque (body)", 240.0f / 255, 240.0f / 255, 240.0f / 255, {"torque_display"}},
  };
  return meanings;
}

std_msgs::ColorRGBA meaningColour(const std::string& ns, float alpha) {
  for (const MarkerMeaning& m : markerMeanings()) {
    for (const std::string& n : m.namespaces) {
      if (n != ns) continue;
      std_msgs::ColorRGBA c;
      c.r = m.r;
      c.g = m.g;
      c.b = m.b;
      c.a = alpha;
      return c;
    }
  }
  throw std::out_of_range("meaningColour: no meaning lists the marker namespace '" + ns + "'");
}

visualization_msgs::MarkerArray legendMarkers(const std::string& world_frame, double path_radius) {
  visualization_msgs::MarkerArray array;
  const std::vector<MarkerMeaning>& meanings = markerMeanings();
  for (std::size_t i = 0; i < meanings.size(); ++i) {
    visualization_msgs::Marker line;
    line.header.frame_id = world_frame;
    line.ns = "legend";
    line.id = static_cast<int>(i);
    line.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    line.action = visualization_msgs::Marker::ADD;
    line.pose.orientation.w = 1.0;
    // To the left of the body in the shipped view (rviz/maneuver.rviz: yaw 0.4, pitch 0.8),
    // below the status text.
    line.pose.position.x = 0.4 * path_radius;
    line.pose.position.y = -0.7 * path_radius;
    line.pose.position.z = (0.95 - 0.085 * static_cast<double>(i)) * path_radius;
    line.scale.z = 0.05 * path_radius;  // text height [m]
    line.color.r = meanings[i].r;
    line.color.g = meanings[i].g;
    line.color.b = meanings[i].b;
    line.color.a = 1.0f;
    line.text = meanings[i].legend;
    array.markers.push_back(line);
  }
  return array;
}

visualization_msgs::MarkerArray bodyAxisMarkers(const std::vector<PlanningConstraint>& constraints,
                                                const std::optional<EndCondition>& pointing,
                                                const Matrix3& attitude, double length,
                                                const std::string& world_frame,
                                                const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  int cone = 0;
  for (const PlanningConstraint& c : constraints) {
    if (!c.isCone()) continue;
    const std::string ns =
        c.kind == ConstraintKind::KeepOut ? "keep_out_body_axis" : "keep_in_body_axis";
    array.markers.push_back(worldArrow(world_frame, stamp, ns, cone++,
                                       length * (attitude * c.body_axis.normalized()), length,
                                       1.0f));
  }
  if (pointing && pointing->pointing()) {
    array.markers.push_back(worldArrow(world_frame, stamp, "pointing_boresight", 0,
                                       length * (attitude * pointing->body_axis.normalized()),
                                       length, 1.0f));
  }
  return array;
}

visualization_msgs::MarkerArray worldDirectionMarkers(
    const std::vector<PlanningConstraint>& constraints, const std::optional<EndCondition>& pointing,
    double length, const std::string& world_frame) {
  visualization_msgs::MarkerArray array;
  constexpr double kBeyondTheCone = 1.5;  // the direction sticks out of its cone (slant `length`)
  int cone = 0;
  for (const PlanningConstraint& c : constraints) {
    if (!c.isCone()) continue;
    const std::string ns =
        c.kind == ConstraintKind::KeepOut ? "keep_out_direction" : "keep_in_direction";
    array.markers.push_back(worldArrow(world_frame, ros::Time(), ns, cone++,
                                       kBeyondTheCone * length * c.world_direction.normalized(),
                                       0.6 * length, 0.8f));
  }
  if (pointing && pointing->pointing()) {
    array.markers.push_back(worldArrow(
        world_frame, ros::Time(), "pointing_target", 0,
        kBeyondTheCone * length * pointing->world_direction.normalized(), 0.6 * length, 0.6f));
  }
  return array;
}

visualization_msgs::MarkerArray wheelMomentumMarkers(const ReactionWheels& wheels,
                                                     const Eigen::VectorXd& momentum,
                                                     double path_radius,
                                                     const std::string& world_frame,
                                                     const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  const double width = kWheelBarWidth * path_radius, full = kWheelBarHeight * path_radius;
  for (int i = 0; i < wheels.count(); ++i) {
    const double fraction =
        std::min(std::abs(momentum(i)) / wheels.momentumLimit(i), kWheelBarMostFraction);
    const Vector3 base(kWheelBarsX * path_radius,
                       (kWheelBarsY + 1.5 * kWheelBarWidth * i) * path_radius,
                       kWheelBarsZ * path_radius);
    for (const bool limit : {false, true}) {
      visualization_msgs::Marker bar;
      bar.header.frame_id = world_frame;
      bar.header.stamp = stamp;
      bar.ns = limit ? "wheel_momentum_limit" : "wheel_momentum";
      bar.id = i;
      bar.type = visualization_msgs::Marker::CUBE;
      bar.action = visualization_msgs::Marker::ADD;
      bar.pose.orientation.w = 1.0;
      const double height = limit ? 0.04 * full : std::max(fraction * full, 1e-3 * full);
      const double centre = limit ? full : 0.5 * height;
      bar.pose.position =
          ros_conversions::xyzToMsg<geometry_msgs::Point>(base + Vector3(0.0, 0.0, centre));
      bar.scale.x = width;
      bar.scale.y = width;
      bar.scale.z = height;
      bar.color = meaningColour(bar.ns, limit ? 0.9f : 1.0f);
      array.markers.push_back(bar);
    }
  }
  return array;
}

}  // namespace attitude_planner
