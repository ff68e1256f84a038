// The planner node's memory after stopped solves, in a process of its own: the node configures its
// allocator when it starts, before anything is allocated, and so does this binary. Run after other
// tests in one process (test_ros_conversions, where it was), the same solves kept 32 MB more,
// reproducibly: the earlier tests' long-lived blocks, allocated under glibc's dynamic threshold,
// fragment the arenas the later solves reuse, which is not the node's situation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "attitude_planner/ros/planner_node.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

/// This process's resident size [MB] (/proc/self/status VmRSS).
double residentMegabytes() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

TEST(Memory, StoppedSolvesLeaveNothingBehindOnceJoined) {
  // The service's way with a request answered at its deadline: its solve on a thread of its own,
  // stopped by the budget inside its Newton iterations (N = 20,000, 0.3 s: the core's share,
  // solveBudget, is 0.14 s), joined, then returnFreedMemory. Four such solves at a time (each
  // thread its own malloc arena), three times: the resident size comes back to within 24 MB of
  // what one solve left (one stopped solve's Newton system alone is 40 MB at this N). What the
  // arenas keep before the trims is printed: the allocator's. Without configureAllocator (glibc's
  // dynamic mmap threshold) the same run kept 38 MB after the trims (28 -> 66 MB); with one arena
  // (MALLOC_ARENA_MAX=1) nothing: no leak.
  ros::Time::init();
  configureAllocator();  // as the node does at start
  PlanAttitudeManeuver::Request req;
  ros_testing::fillSeedRequest(&req);
  req.steps = 20000;
  req.tolerance = 1e-300;
  req.time_budget = 0.3;
  const auto stoppedSolves = [&](int count) {
    std::vector<std::thread> solves;
    for (int i = 0; i < count; ++i) {
      solves.emplace_back([&req] {
        const PlanOutcome out = planRequest(req, rc::PlannerDefaults(), nullptr);
        EXPECT_EQ(out.error_code, PlanErrorCode::TIMED_OUT) << out.message;
        EXPECT_EQ(out.result.maneuver.attitude.size(), 20001u) << "the plan reached";
      });
    }
    for (std::thread& t : solves) t.join();
  };
  stoppedSolves(1);
  returnFreedMemory();
  const double after_one = residentMegabytes();
  double untrimmed = 0.0;
  for (int round = 0; round < 3; ++round) {
    stoppedSolves(4);
    untrimmed = std::max(untrimmed, residentMegabytes());
    returnFreedMemory();
  }
  const double after_all = residentMegabytes();
  std::printf(
      "resident: %.1f MB after 1 stopped solve, %.1f MB after 13 (up to %.1f MB before "
      "the trims)\n",
      after_one, after_all, untrimmed);
  EXPECT_LT(after_all - after_one, 24.0);
}
