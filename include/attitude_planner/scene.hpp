// Scene files (YAML, DESIGN.md "Scene file"): what to plan and which effects are present.
#pragma once

#include <string>

#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// A parsed scene. Unknown keys and bad values throw InvalidInput naming the key and the value.
struct Scene {
  PlanningProblem problem;
  std::string source;  ///< file name (for messages)
};

/// Parses YAML text; `source` names it in error messages.
Scene parseScene(const std::string& yaml_text, const std::string& source = "<scene>");
/// Reads and parses a scene file.
Scene loadScene(const std::string& path);

}  // namespace attitude_planner
