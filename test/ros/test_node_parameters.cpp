// rostest: a private parameter the node cannot use stops it at start-up with exit status 78
// (kExitInvalidParameter) and an error naming the parameter and the value, instead of a
// fallback to the default. Scene paths: package://, relative to the caller's directory (a
// missing one names that directory). /use_sim_time is read through the node's remappings
// (replay.launch gives rviz alone simulated time that way) and the tracker says once that it
// waits for /clock. Each case runs the node binary itself against the rostest master.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <regex>
#include <sstream>
#include <string>

namespace {

const std::string kPlanner = AP_TOOL_DIR "attitude_planner_node";
const std::string kTracker = AP_TOOL_DIR "attitude_tracker_node";
const std::string kPlant = AP_TOOL_DIR "attitude_plant_node";
constexpr int kExitInvalidParameter = 78;  // parameters.hpp: EX_CONFIG
constexpr int kTimeoutExit = 124;          // timeout(1): the node was still running

struct NodeRun {
  int status = -1;  ///< exit status (-1: did not exit normally)
  std::string output;
};

/// Runs `command` in `directory` (also its $PWD) with stderr merged; at most `seconds` long, then
/// SIGINT (status kTimeoutExit).
NodeRun runNode(const std::string& command, int seconds, const std::string& directory = "/tmp") {
  const std::string line = "cd '" + directory + "' && PWD='" + directory + "' timeout -s INT " +
                           std::to_string(seconds) + " " + command + " 2>&1";
  NodeRun run;
  FILE* pipe = popen(line.c_str(), "r");
  if (!pipe) return run;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    run.output.append(buffer.data(), n);
  const int raw = pclose(pipe);
  if (WIFEXITED(raw)) run.status = WEXITSTATUS(raw);
  return run;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(NodeParameters, OutOfRangeValueStopsThePlannerNamingIt) {
  const NodeRun run = runNode(kPlanner + " __name:=bad_tolerance _tolerance:=-1.0", 60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "/bad_tolerance/tolerance = -1 is invalid: must be > 0"))
      << run.output;
}

TEST(NodeParameters, UnknownNameStopsThePlannerListingTheNames) {
  const NodeRun run = runNode(kPlanner + " __name:=bad_solver _solver:=ipopt", 60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "/bad_solver/solver = ipopt is invalid")) << run.output;
  EXPECT_TRUE(contains(run.output, "newton")) << run.output;
}

TEST(NodeParameters, WrongTypeStopsThePlannerNamingTheType) {
  const NodeRun run = runNode(kPlanner + " __name:=bad_threads _threads:=many", 60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "/bad_threads/threads = many is not an integer")) << run.output;
}

TEST(NodeParameters, ValidValuesKeepThePlannerServing) {
  const NodeRun run =
      runNode(kPlanner + " __name:=good_planner _tolerance:=1e-9 _solver:=nlopt _threads:=2", 5);
  EXPECT_EQ(run.status, kTimeoutExit) << "the planner should still run:\n" << run.output;
}

TEST(NodeParameters, OutOfRangeValueStopsTheTrackerNamingIt) {
  const NodeRun run = runNode(kTracker + " __name:=bad_rate _rate_factor:=0", 60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "/bad_rate/rate_factor = 0 is invalid: must be > 0"))
      << run.output;
}

/// Runs `command`; expects it to stop with exit 78 and every one of `parts` in its output.
void expectStopped(const std::string& command, std::initializer_list<std::string> parts) {
  const NodeRun run = runNode(command, 60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << command << ":\n" << run.output;
  for (const std::string& part : parts) EXPECT_TRUE(contains(run.output, part)) << run.output;
}

TEST(NodeParameters, UnknownPlantOrModeStopsTheTrackerListingTheNames) {
  expectStopped(kTracker + " __name:=bad_plant _plant:=outside",
                {"/bad_plant/plant = outside is invalid", "external"});
  // Before, a bad ~mode printed FATAL and exited 0.
  expectStopped(kTracker + " __name:=bad_mode _mode:=autopilot",
                {"/bad_mode/mode = autopilot is invalid", "feedback"});
}

TEST(NodeParameters, PlantNodeNeedsASceneAndRunsWithOne) {
  const std::string scene = " _scene:=" AP_SOURCE_DIR "/scenes/leo_slew.yaml";
  expectStopped(kPlant + " __name:=sceneless_plant", {"/sceneless_plant/scene is required"});
  expectStopped(kPlant + " __name:=bad_plant_rate _rate:=0" + scene,
                {"/bad_plant_rate/rate = 0 is invalid"});
  // ~replay_scene (tracker.launch's plant:=node passes it on): a scene whose effects act instead.
  expectStopped(kPlant + " __name:=bad_replay_plant _replay_scene:=/no/such/scene.yaml" + scene,
                {"/bad_replay_plant/replay_scene = /no/such/scene.yaml", "no readable file"});
  expectStopped(
      kPlant + " __name:=wrong_replay_plant _replay_scene:=" AP_SOURCE_DIR "/launch/plant.launch" +
          scene,
      {"/wrong_replay_plant/replay_scene = "});
  const NodeRun good = runNode(kPlant + " __name:=good_plant" + scene, 5);
  EXPECT_EQ(good.status, kTimeoutExit) << "the plant should still run:\n" << good.output;
  const NodeRun replayed =
      runNode(kPlant + " __name:=replay_plant" + scene +
                  " _replay_scene:=" AP_SOURCE_DIR "/scenes/disturbed_replay.yaml",
              5);
  EXPECT_EQ(replayed.status, kTimeoutExit) << "the plant should still run:\n" << replayed.output;
}

TEST(NodeParameters, PlantNodeWithWheelsNeedsSpinInertiasAndNoActuatorEffects) {
  const std::string dir = " _scene:=" AP_SOURCE_DIR "/test/ros/";
  expectStopped(kPlant + " __name:=nospin_plant" + dir + "wheel_pyramid.yaml",
                {"actuators.reaction_wheels.spin_inertia", "spin rates"});
  expectStopped(kPlant + " __name:=noisy_wheel_plant" + dir + "wheel_pyramid_noisy.yaml",
                {"actuators.reaction_wheels: torque_noise acts on a body torque"});
  for (const char* scene : {"wheel_pyramid_spin.yaml", "wheel_pyramid_disturbed.yaml"}) {
    const NodeRun good = runNode(kPlant + " __name:=wheel_plant" + dir + scene, 5);
    EXPECT_EQ(good.status, kTimeoutExit) << scene << ": the plant should run:\n" << good.output;
  }
}

TEST(NodeParameters, MissingRelativeSceneNamesTheCallersDirectory) {
  const NodeRun run =
      runNode(kTracker + " __name:=bad_scene _scene:=scenes/no_such_scene.yaml", 60, AP_SOURCE_DIR);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "/bad_scene/scene = scenes/no_such_scene.yaml")) << run.output;
  EXPECT_TRUE(contains(run.output,
                       "resolved against the directory roslaunch or rosrun was "
                       "started in, " AP_SOURCE_DIR))
      << run.output;
}

TEST(NodeParameters, MissingPackageSceneStopsTheTracker) {
  const NodeRun run = runNode(
      kTracker + " __name:=bad_package_scene _scene:=package://attitude_planner/scenes/none.yaml",
      60);
  EXPECT_EQ(run.status, kExitInvalidParameter) << run.output;
  EXPECT_TRUE(contains(run.output, "no readable file")) << run.output;
}

TEST(NodeParameters, RelativeSceneIsPlannedFromTheCallersDirectory) {
  // In-process planning, 10x real time, then exit_when_done: the tracker ends by itself (0).
  const NodeRun run = runNode(kTracker +
                                  " __name:=relative_scene _scene:=scenes/rest_to_rest.yaml"
                                  " _plan_in_process:=true _rate_factor:=10.0 _start_delay:=0.0"
                                  " _exit_when_done:=true",
                              120, AP_SOURCE_DIR);
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_TRUE(contains(run.output, "planning " AP_SOURCE_DIR "/scenes/rest_to_rest.yaml"))
      << run.output;
}

TEST(NodeParameters, AnUnknownPrivateParameterIsWarnedAndTheNodeRuns) {
  // `~rat` (meant: `~rate`) would leave the rate at its default without a word: warned, named,
  // with the node's parameters listed; the node runs on (a warning, not a stop).
  const NodeRun run = runNode(kTracker + " __name:=misspelt _rat:=30.0 _rate:=20.0", 5);
  EXPECT_EQ(run.status, kTimeoutExit) << run.output;
  EXPECT_TRUE(contains(run.output, "parameter /misspelt/rat is not one of this node's"))
      << run.output;
  EXPECT_TRUE(contains(run.output, "measurement_timeout")) << run.output;  // the list
  EXPECT_FALSE(contains(run.output, "parameter /misspelt/rate is not")) << run.output;
  const NodeRun planner = runNode(kPlanner + " __name:=misspelt_planner _thread:=3", 5);
  EXPECT_EQ(planner.status, kTimeoutExit) << planner.output;
  EXPECT_TRUE(contains(planner.output, "parameter /misspelt_planner/thread is not one of"))
      << planner.output;
}

TEST(NodeParameters, SimTimeThroughARemapAndOneWarningWhileClockIsSilent) {
  // As replay.launch does for rviz: /use_sim_time remapped to a private parameter. Nothing
  // publishes /clock here, so the replay waits and the tracker says so, once.
  const NodeRun run = runNode(kTracker +
                                  " __name:=silent_clock /use_sim_time:=silent_clock/use_sim_time"
                                  " _use_sim_time:=true _plan_in_process:=true"
                                  " _scene:=package://attitude_planner/scenes/rest_to_rest.yaml",
                              15);
  EXPECT_EQ(run.status, kTimeoutExit) << run.output;
  const std::string warning = "no /clock is published: waiting for /clock";
  const size_t first = run.output.find(warning);
  EXPECT_NE(first, std::string::npos) << run.output;
  EXPECT_EQ(run.output.find(warning, first + 1), std::string::npos) << "warned twice:\n"
                                                                    << run.output;
}

TEST(NodeParameters, RosArgsListsEveryLaunchArgAndSaysWhichListedAsRequiredAreOptional) {
  // `roslaunch --ros-args` lists every arg of each shipped launch file; an arg whose default is
  // empty it lists under "Required Arguments" (roslaunch's arg_dump reads "" as no default), so
  // the doc of each such arg says whether it is optional, required, or derived.
  NodeRun found = runNode("rospack find attitude_planner", 60);
  ASSERT_EQ(found.status, 0) << found.output;
  const std::string package = found.output.substr(0, found.output.find('\n'));
  for (const std::string name : {"planner", "tracker", "plant", "demo", "replay"}) {
    const NodeRun run = runNode("roslaunch --ros-args attitude_planner " + name + ".launch", 120);
    ASSERT_EQ(run.status, 0) << name << ":\n" << run.output;
    std::ifstream file(package + "/launch/" + name + ".launch");
    std::stringstream text;
    text << file.rdbuf();
    const std::string launch = text.str();
    // Declared args (a default or a doc); an include's <arg name= value=> only passes one on.
    const std::regex arg_name("<arg name=\"([a-z_]+)\"[^>]*(default|doc)=");
    int args = 0;
    for (auto it = std::sregex_iterator(launch.begin(), launch.end(), arg_name);
         it != std::sregex_iterator(); ++it, ++args) {
      EXPECT_TRUE(contains(run.output, "  " + (*it)[1].str())) << name << ": " << (*it)[1];
    }
    EXPECT_GT(args, 0) << name;
    const std::size_t required = run.output.find("Required Arguments:");
    if (required == std::string::npos) continue;
    std::istringstream lines(
        run.output.substr(required, run.output.find("Optional Arguments:") - required));
    std::string line;
    std::getline(lines, line);  // the heading
    while (std::getline(lines, line)) {
      if (line.empty()) continue;
      EXPECT_TRUE(contains(line, "optional") || contains(line, "(required)") ||
                  contains(line, "(derived)"))
          << name << ".launch lists an arg as required without saying which it is: " << line;
    }
  }
}
