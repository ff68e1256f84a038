// Trajectory CSV files (docs/DESIGN.md, "Trajectory CSV"): what plan_maneuver writes with --csv,
// simulate_torques reads, and the drift + two-input planner writes for seed 001.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/reaction_wheels.hpp"

namespace attitude_planner {

/// Writes the CSV `k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz` with %.17g; throws InvalidInput if the
/// file cannot be written.
void writeManeuverCsv(const Maneuver& maneuver, const std::string& path);
/// The same with the reaction wheels' columns after tx,ty,tz: u1..un (wheel torques [N m]) and
/// h1..hn (wheel momenta [N m s]) of `wheels` (reaction_wheels.hpp: wheelStates).
void writeManeuverCsv(const Maneuver& maneuver, const WheelStates& wheels, const std::string& path);
/// Reads a CSV written by writeManeuverCsv (header checked; wheel columns are accepted and not
/// read: they follow from the plan and the array); throws InvalidInput naming the line.
Maneuver readManeuverCsv(const std::string& path);
/// The wheel torques u1..un [N m] of each row of a CSV writeManeuverCsv wrote with wheel states
/// (empty if it has no wheel columns); throws InvalidInput naming the line.
std::vector<Eigen::VectorXd> readWheelTorquesCsv(const std::string& path);

/// Header of the drift + two-input trajectory CSV (seed 001).
constexpr const char* kDriftTwoInputCsvHeader = "k,t,qw,qx,qy,qz,u1,u2,p1,p2,p3";

/// Writes the CSV `k,t,qw,qx,qy,qz,u1,u2,p1,p2,p3` (rows k = 0..N, %.17g): t_k [s], g(t_k) as a
/// Hamilton quaternion (body → world, w ≥ 0), controls u [rad/s], costate p [c·rad/s]. Throws
/// InvalidInput if the file cannot be written.
void writeDriftTwoInputCsv(const DriftTwoInputTrajectory& trajectory, const std::string& path);

}  // namespace attitude_planner
