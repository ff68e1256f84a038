// libFuzzer target: arbitrary bytes as a planning request, decoded the way the node
// decodes PlanAttitudeManeuver (float64[9] inertia, quaternions checked for finiteness and unit
// norm within 1e-3, then the core's validateProblem / validateOptions) and, if valid and small,
// planned with a bounded budget. Only InvalidInput / StepTooLarge may escape validation; a
// crash, sanitizer report, hang or broken invariant is a bug. Layout of the input (little-endian
// doubles, missing bytes read as 0): J[9], T, q0[4], Ω0[3], qN[4], ΩN[3], tolerance,
// time_budget, then int32 steps, int32 max_iterations, int32 extra_revolutions, byte flags
// (bit 0 scheme variational, bit 1 allow_nonphysical_inertia, bit 2 long way).
#include <cmath>
#include <cstdint>
#include <cstring>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "fuzz_common.hpp"

namespace ap_fuzz {

struct Reader {
  const std::uint8_t* data;
  std::size_t size, at = 0;
  template <class T>
  T next() {
    T v{};
    std::uint8_t bytes[sizeof(T)] = {};
    for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = at < size ? data[at++] : 0;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
};

/// The node's quaternion check (ros_conversions::attitudeFromMsg: attitudeFromQuaternion), without
/// ROS types.
inline attitude_planner::Matrix3 attitudeOf(Reader& r) {
  Eigen::Vector4d wxyz;
  for (int i = 0; i < 4; ++i) wxyz(i) = r.next<double>();
  return attitude_planner::attitudeFromQuaternion(wxyz, "quaternion");
}

inline int fuzzRequest(const std::uint8_t* data, std::size_t size) {
  namespace ap = attitude_planner;
  Reader r{data, size};
  ap::PlanningProblem p;
  ap::SolverOptions o;
  try {
    for (int i = 0; i < 9; ++i) p.inertia(i / 3, i % 3) = r.next<double>();
    p.duration = r.next<double>();
    p.initial_attitude = attitudeOf(r);
    for (int i = 0; i < 3; ++i) p.initial_velocity(i) = r.next<double>();
    p.final_attitude = attitudeOf(r);
    for (int i = 0; i < 3; ++i) p.final_velocity(i) = r.next<double>();
    o.tolerance = r.next<double>();
    o.time_budget_s = r.next<double>();
    p.steps = r.next<std::int32_t>();
    o.max_iterations = r.next<std::int32_t>();
    p.extra_revolutions = r.next<std::int32_t>() % 4;
    const std::uint8_t flags = r.next<std::uint8_t>();
    p.scheme = (flags & 1) ? ap::SchemeKind::Variational : ap::SchemeKind::Paper;
    p.allow_nonphysical_inertia = (flags & 2) != 0;
    p.direction = (flags & 4) ? ap::RotationDirection::LongWay : ap::RotationDirection::Shortest;
    ap::validateProblem(p);
    ap::validateOptions(o);
  } catch (const ap::InvalidInput&) {
    return 0;
  }
  boundedPlan(p);
  return 0;
}

}  // namespace ap_fuzz

#ifndef AP_FUZZ_NO_ENTRY
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ap_fuzz::fuzzRequest(data, size);
}
#endif
