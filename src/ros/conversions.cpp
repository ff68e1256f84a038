#include "attitude_planner/ros/conversions.hpp"

#include <cmath>
#include <sstream>

namespace attitude_planner {
namespace ros_conversions {

namespace {

std::string quaternionText(const geometry_msgs::Quaternion& q) {
  std::ostringstream s;
  s.precision(17);
  s << "(w, x, y, z) = (" << q.w << ", " << q.x << ", " << q.y << ", " << q.z << ")";
  return s.str();
}

}  // namespace

Matrix3 attitudeFromMsg(const geometry_msgs::Quaternion& q, const std::string& field) {
  if (!std::isfinite(q.w) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) {
    throw InvalidInput(field + ": quaternion not finite: " + quaternionText(q));
  }
  const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (norm == 0.0) {
    throw InvalidInput(field + ": zero quaternion " + quaternionText(q) +
                       " (expected a unit quaternion; identity is w = 1)");
  }
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    std::ostringstream s;
    s << field << ": quaternion norm " << norm << " is not 1 (tolerance "
      << kQuaternionNormTolerance << "): " << quaternionText(q);
    throw InvalidInput(s.str());
  }
  return so3::fromQuaternion(Eigen::Quaterniond(q.w, q.x, q.y, q.z));
}

geometry_msgs::Quaternion attitudeToMsg(const Matrix3& R) {
  const Eigen::Quaterniond q = so3::toQuaternion(R);
  geometry_msgs::Quaternion m;
  m.w = q.w();
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  return m;
}

Vector3 vectorFromMsg(const geometry_msgs::Vector3& v) {
  return Vector3(v.x, v.y, v.z);
}

geometry_msgs::Vector3 vectorToMsg(const Vector3& v) {
  geometry_msgs::Vector3 m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

Matrix3 inertiaFromMsg(const boost::array<double, 9>& j) {
  Matrix3 J;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) J(r, c) = j[3 * r + c];
  }
  return J;
}

boost::array<double, 9> inertiaToMsg(const Matrix3& J) {
  boost::array<double, 9> j;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) j[3 * r + c] = J(r, c);
  }
  return j;
}

AttitudeManeuver maneuverToMsg(const Maneuver& maneuver, const PlanningProblem& problem,
                               const std::string& world_frame, const std::string& body_frame,
                               const ros::Time& stamp) {
  AttitudeManeuver m;
  m.header.stamp = stamp;
  m.header.frame_id = world_frame;
  m.child_frame_id = body_frame;
  m.inertia = inertiaToMsg(problem.inertia);
  m.scheme = schemeName(problem.scheme);
  m.time_step = maneuver.time_step;
  m.time = maneuver.time;
  for (const Matrix3& R : maneuver.attitude) m.attitude.push_back(attitudeToMsg(R));
  for (const Vector3& w : maneuver.angular_velocity) m.angular_velocity.push_back(vectorToMsg(w));
  for (const Vector3& t : maneuver.torque) m.torque.push_back(vectorToMsg(t));
  return m;
}

Maneuver maneuverFromMsg(const AttitudeManeuver& msg) {
  const size_t rows = msg.attitude.size();
  if (rows < 2) {
    throw InvalidInput("maneuver.attitude: needs N + 1 >= 2 rows, got " + std::to_string(rows));
  }
  if (msg.time.size() != rows || msg.angular_velocity.size() != rows || msg.torque.size() != rows) {
    throw InvalidInput("maneuver: arrays disagree in length (time " +
                       std::to_string(msg.time.size()) + ", attitude " + std::to_string(rows) +
                       ", angular_velocity " + std::to_string(msg.angular_velocity.size()) +
                       ", torque " + std::to_string(msg.torque.size()) + ")");
  }
  if (!std::isfinite(msg.time_step) || !(msg.time_step > 0.0)) {
    throw InvalidInput("maneuver.time_step: must be a finite number > 0 s, got " +
                       std::to_string(msg.time_step));
  }
  Maneuver m;
  m.time_step = msg.time_step;
  m.time = msg.time;
  for (size_t k = 0; k < rows; ++k) {
    const std::string row = "[" + std::to_string(k) + "]";
    m.attitude.push_back(attitudeFromMsg(msg.attitude[k], "maneuver.attitude" + row));
    const Vector3 w = vectorFromMsg(msg.angular_velocity[k]);
    const Vector3 t = vectorFromMsg(msg.torque[k]);
    if (!w.allFinite()) throw InvalidInput("maneuver.angular_velocity" + row + ": not finite");
    if (!t.allFinite()) throw InvalidInput("maneuver.torque" + row + ": not finite");
    if (!std::isfinite(msg.time[k])) throw InvalidInput("maneuver.time" + row + ": not finite");
    m.angular_velocity.push_back(w);
    m.torque.push_back(t);
  }
  return m;
}

}  // namespace ros_conversions
}  // namespace attitude_planner
