// The world-rotation invariance of minimum time, one check for every test that states it.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "attitude_planner/planner.hpp"

namespace attitude_planner::test_support {

/// The request in a world turned by Q: both boundary attitudes and every cone's world direction
/// (world-frame effects are the caller's: their torque turns too).
inline PlanningProblem inATurnedWorld(PlanningProblem p, const Matrix3& Q) {
  p.initial_attitude = Q * p.initial_attitude;
  p.final_attitude = Q * p.final_attitude;
  for (PlanningConstraint& c : p.constraints) c.world_direction = Q * c.world_direction;
  return p;
}

/// `turned` (a request in a turned world) answered by a KKT point with the T* of `answer` to
/// `relative`; returns its answer.
inline PlanResult expectSameTStarWhenTurned(const PlanningProblem& turned, const PlanResult& answer,
                                            double relative, const std::string& label) {
  const PlanResult in_turned = planManeuver(turned);
  EXPECT_TRUE(in_turned.converged()) << label << ": " << in_turned.message();
  EXPECT_TRUE(in_turned.minimum_time.kkt_point) << label << ": " << in_turned.message();
  EXPECT_NEAR(in_turned.minimum_duration, answer.minimum_duration,
              relative * answer.minimum_duration)
      << label;
  return in_turned;
}

}  // namespace attitude_planner::test_support
