// Runs the package's command-line tools from gtests (test_plan_maneuver_cli, test_hostile_inputs):
// one place for the path of the built tools and for capturing their output and exit status.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace attitude_planner_test {

/// Where catkin puts the package's executables (AP_BINARY_DIR is the package's build dir).
inline const std::string kToolDir = AP_BINARY_DIR "/../../devel/lib/attitude_planner/";

struct ToolRun {
  int status = -1;     ///< exit status (−1: did not exit normally)
  std::string output;  ///< stdout and stderr together
};

/// Runs `command` through the shell, capturing stdout and stderr together.
inline ToolRun runCommand(const std::string& command) {
  ToolRun r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
  const int raw = pclose(pipe);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

/// Runs `directory/program args` (both streams captured); `timeout_s` > 0 wraps it in
/// coreutils' timeout, so a hang fails the test instead of CI.
inline ToolRun runProgram(const std::string& directory, const std::string& program,
                          const std::string& args, int timeout_s = 0) {
  const std::string prefix = timeout_s > 0 ? "timeout " + std::to_string(timeout_s) + " " : "";
  return runCommand(prefix + "'" + directory + program + "' " + args);
}

/// runProgram for one of the installed tools (kToolDir).
inline ToolRun runTool(const std::string& tool, const std::string& args, int timeout_s = 0) {
  return runProgram(kToolDir, tool, args, timeout_s);
}

}  // namespace attitude_planner_test
