// A shipped scene (scenes/<name>.yaml) as a problem at a chosen N, for the tests that start from
// one; AP_SOURCE_DIR is the test targets' source tree.
#pragma once

#include <string>

#include "attitude_planner/io/scene.hpp"

namespace attitude_planner::test_support {

/// scenes/<name>.yaml's problem with `steps` steps.
inline PlanningProblem sceneProblem(const char* name, int steps) {
  PlanningProblem p = loadScene(std::string(AP_SOURCE_DIR "/scenes/") + name + ".yaml").problem;
  p.steps = steps;
  return p;
}

}  // namespace attitude_planner::test_support
