// Test helper shared by the scene tests: the message a bad scene is refused with.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"

namespace attitude_planner_test {

/// The message of the InvalidInput parseScene throws; fails the test if none is thrown.
inline std::string sceneErrorOf(const std::string& text) {
  try {
    attitude_planner::parseScene(text, "bad.yaml");
  } catch (const attitude_planner::InvalidInput& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InvalidInput for:\n" << text;
  return "";
}

}  // namespace attitude_planner_test
