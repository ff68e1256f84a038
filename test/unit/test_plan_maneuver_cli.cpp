// End-to-end tests of the command-line tools plan_maneuver and simulate_torques: run the built
// binaries on the shipped scenes and on bad inputs; check exit status, messages and outputs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/io/csv.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "tool_runner.hpp"

namespace ap = attitude_planner;

namespace {

using attitude_planner_test::runTool;
using attitude_planner_test::ToolRun;
const std::string& kBin = attitude_planner_test::kToolDir;
const std::string kScenes = AP_SOURCE_DIR "/scenes/";

ToolRun run(const std::string& tool, const std::string& args) {
  return runTool(tool, args);
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The number after `"key": ` in a JSON summary (the first occurrence).
double jsonNumber(const std::string& summary, const std::string& key) {
  const std::string field = "\"" + key + "\": ";
  const std::size_t at = summary.find(field);
  EXPECT_NE(at, std::string::npos) << key << " missing in " << summary;
  return at == std::string::npos ? std::nan("") : std::stod(summary.substr(at + field.size()));
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/ap_cli_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    ASSERT_EQ(access((kBin + "plan_maneuver").c_str(), X_OK), 0)
        << "plan_maneuver not built at " << kBin;
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }

  /// Writes a scene file into the test directory and returns its path.
  std::string writeScene(const std::string& name, const std::string& text) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }

  std::string dir_;
};

/// `text` with its first occurrence of `from` replaced by `to`.
std::string withReplaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << "output:\n" << (haystack)

}  // namespace

TEST_F(CliTest, NloptPlanWritesCsvAndSummaryAndExitsZero) {
  const std::string csv = dir_ + "/plan.csv", json = dir_ + "/plan.json";
  const ToolRun r =
      run("plan_maneuver", kScenes + "rest_to_rest.yaml --solver nlopt --steps 16 --csv " + csv +
                               " --summary=" + json);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_CONTAINS(r.output, "converged                yes");
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"converged\": true");
  EXPECT_CONTAINS(summary, "\"solver\": \"nlopt\"");
  EXPECT_CONTAINS(summary, "\"scheme\": \"paper\"");
  EXPECT_CONTAINS(summary, "\"steps\": 16");
  for (const char* key : {"iterations", "cost", "terminal_attitude_error",
                          "terminal_velocity_error", "max_residual", "solve_time_s", "duration",
                          "dynamics_residual", "step_residual", "replay_miss", "message"}) {
    EXPECT_CONTAINS(summary, std::string("\"") + key + "\": ");
  }
  const ap::Maneuver m = ap::readManeuverCsv(csv);
  ASSERT_EQ(m.steps(), 16);
  EXPECT_NEAR(m.time.back(), 12.8, 1e-12);
  EXPECT_TRUE(m.torque.back().isZero(0.0));
  EXPECT_GT(m.torque[1].norm(), 0.0);
  // Full precision: the cost in the summary is the cost of the CSV's torques to round-off.
  double cost = 0.0;
  for (const auto& t : m.torque) cost += 0.5 * t.squaredNorm();
  const std::size_t at = summary.find("\"cost\": ") + 8;
  EXPECT_NEAR(std::stod(summary.substr(at)), cost, 1e-14 * cost);

  // The simulation entry point replays the CSV onto the scene's final state.
  const ToolRun replay =
      run("simulate_torques", kScenes + "rest_to_rest.yaml " + csv + " --max-miss 1e-9");
  EXPECT_EQ(replay.status, 0) << replay.output;
  EXPECT_CONTAINS(replay.output, "terminal attitude error");
  // Against another scene the same torques miss, and --max-miss says so.
  const ToolRun miss =
      run("simulate_torques", kScenes + "slew_up.yaml " + csv + " --max-miss 1e-9");
  EXPECT_EQ(miss.status, 1) << miss.output;
  EXPECT_CONTAINS(miss.output, "exceeds --max-miss");
}

TEST_F(CliTest, DefaultSolverPlansBothShippedScenesAtTheirOwnSteps) {
  for (const std::string scene : {"rest_to_rest", "slew_up"}) {
    const std::string json = dir_ + "/" + scene + ".json";
    const ToolRun r = run("plan_maneuver", kScenes + scene + ".yaml --summary " + json);
    EXPECT_EQ(r.status, 0) << r.output;
    const std::string summary = readFile(json);
    EXPECT_CONTAINS(summary, "\"converged\": true");
    EXPECT_CONTAINS(summary, "\"solver\": \"newton\"");
    EXPECT_CONTAINS(summary, "\"steps\": 128");
    const std::size_t at = summary.find("\"terminal_attitude_error\": ") + 27;
    EXPECT_LT(std::stod(summary.substr(at)), 1e-10) << summary;
  }
}

// --scheme second_order end to end: the summary names the scheme and reports effort = h·cost,
// the CSV holds node torques at the ends too, and simulate_torques replays it to round-off.
TEST_F(CliTest, SecondOrderPlanReportsEffortAndReplaysThroughSimulateTorques) {
  const std::string csv = dir_ + "/second.csv", json = dir_ + "/second.json";
  const ToolRun r = run("plan_maneuver", kScenes + "slew_up.yaml --scheme second_order --steps 64" +
                                             " --csv " + csv + " --summary " + json);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"scheme\": \"second_order\"");
  EXPECT_CONTAINS(summary, "\"converged\": true");
  const double cost = jsonNumber(summary, "cost");
  const double effort = jsonNumber(summary, "effort");
  const double duration = jsonNumber(summary, "duration");
  EXPECT_NEAR(effort, duration / 64 * cost, 1e-9 * effort) << summary;
  const ap::Maneuver plan = ap::readManeuverCsv(csv);
  EXPECT_GT(plan.torque.front().norm(), 0.0);  // end torques are part of the plan
  EXPECT_GT(plan.torque.back().norm(), 0.0);
  const ToolRun replay = run("simulate_torques", kScenes + "slew_up.yaml " + csv +
                                                     " --scheme second_order --max-miss 1e-9");
  EXPECT_EQ(replay.status, 0) << replay.output;
  // The seed's paper scheme has no end torques: replaying this plan with it is refused by name.
  const ToolRun wrong = run("simulate_torques", kScenes + "slew_up.yaml " + csv);
  EXPECT_NE(wrong.status, 0) << wrong.output;
  EXPECT_CONTAINS(wrong.output, "tau_0 and tau_N must be zero with scheme paper");
}

// --scheme fourth_order end to end: the summary names the scheme, the message says it extrapolates
// second_order at N and 2N, the CSV holds N + 1 node rows with end torques, and simulate_torques
// replays it with the cubic hold (RKMK4) to the plan's own O(h⁴) accuracy.
TEST_F(CliTest, FourthOrderPlanExtrapolatesAndReplaysThroughSimulateTorques) {
  const std::string csv = dir_ + "/fourth.csv", json = dir_ + "/fourth.json";
  const ToolRun r = run("plan_maneuver", kScenes + "slew_up.yaml --scheme fourth_order --steps 64" +
                                             " --csv " + csv + " --summary " + json);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"scheme\": \"fourth_order\"");
  EXPECT_CONTAINS(summary, "\"converged\": true");
  EXPECT_CONTAINS(summary, "Richardson extrapolation of second_order at N = 64 and 2N = 128");
  const double cost = jsonNumber(summary, "cost");
  const double effort = jsonNumber(summary, "effort");
  const double duration = jsonNumber(summary, "duration");
  EXPECT_NEAR(effort, duration / 64 * cost, 1e-9 * effort) << summary;
  const ap::Maneuver plan = ap::readManeuverCsv(csv);
  EXPECT_EQ(plan.steps(), 64);
  EXPECT_GT(plan.torque.front().norm(), 0.0);
  EXPECT_GT(plan.torque.back().norm(), 0.0);
  const ToolRun replay = run("simulate_torques", kScenes + "slew_up.yaml " + csv +
                                                     " --scheme fourth_order --max-miss 1e-5");
  EXPECT_EQ(replay.status, 0) << replay.output;
  const ToolRun nlopt =
      run("plan_maneuver", kScenes + "slew_up.yaml --scheme fourth_order --solver nlopt");
  EXPECT_EQ(nlopt.status, 1) << nlopt.output;
  EXPECT_CONTAINS(nlopt.output, "scheme: 'fourth_order' is not available with solver nlopt");
}

// --objective minimum_time on the closed-form scene: T* in the summary, the plan at (1 + M) T*
// with --time-margin M; a minimum-time request without any torque bound is refused by name.
TEST_F(CliTest, MinimumTimeReportsTStarAndHonoursTheMargin) {
  const std::string json = dir_ + "/min.json";
  const ToolRun r =
      run("plan_maneuver",
          kScenes + "min_time_sphere.yaml --steps 32 --time-margin " + "0.25 --summary " + json);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"objective\": \"minimum_time\"");
  const double t_star = jsonNumber(summary, "minimum_duration");
  const double duration = jsonNumber(summary, "duration");
  EXPECT_NEAR(t_star, 2 * std::sqrt(10.0), 2e-3 * t_star);  // closed form, N = 32
  EXPECT_NEAR(duration, 1.25 * t_star, 1e-9 * duration);
  EXPECT_CONTAINS(r.output, "minimum duration T*");
  const ToolRun unbounded =
      run("plan_maneuver", kScenes + "rest_to_rest.yaml --objective minimum_time");
  EXPECT_EQ(unbounded.status, 1) << unbounded.output;
  EXPECT_CONTAINS(unbounded.output, "objective: 'minimum_time' needs a torque bound");
}

TEST_F(CliTest, ExitStatusAgreesWithConvergedForEverySolver) {
  for (const std::string solver : {"newton", "nlopt"}) {
    const std::string json = dir_ + "/" + solver + ".json";
    const ToolRun r = run("plan_maneuver", kScenes + "slew_up.yaml --steps 16 --solver " + solver +
                                               " --summary " + json);
    const bool converged = readFile(json).find("\"converged\": true") != std::string::npos;
    EXPECT_EQ(r.status == 0, converged) << solver << "\n" << r.output;
    if (!converged) EXPECT_CONTAINS(r.output, "not converged");
  }
}

TEST_F(CliTest, IterationLimitGivesNonConvergedExitOne) {
  const ToolRun r = run("plan_maneuver", kScenes +
                                             "slew_up.yaml --solver nlopt --steps 16 "
                                             "--max-iterations 2 --scheme variational");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_CONTAINS(r.output, "plan_maneuver: not converged: ");
  EXPECT_CONTAINS(r.output, "NLOPT_MAXEVAL_REACHED");
  EXPECT_CONTAINS(r.output, "nlopt / variational");
}

TEST_F(CliTest, InvalidSceneExitsOneNamingTheKey) {
  std::string text = readFile(kScenes + "rest_to_rest.yaml");
  text.replace(text.find("duration: 12.8"), 14, "duration: -3");
  const ToolRun r = run("plan_maneuver", writeScene("bad.yaml", text));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_CONTAINS(r.output, "invalid input");
  EXPECT_CONTAINS(r.output, "duration: must be a finite number > 0 s, got -3");

  const ToolRun missing = run("plan_maneuver", dir_ + "/nope.yaml");
  EXPECT_EQ(missing.status, 1);
  EXPECT_CONTAINS(missing.output, "nope.yaml");

  const ToolRun steps = run("plan_maneuver", kScenes + "rest_to_rest.yaml --steps 2");
  EXPECT_EQ(steps.status, 1);
  EXPECT_CONTAINS(steps.output, "steps: must be >= 4, got 2");
}

TEST_F(CliTest, StepsAreCheckedByThePlannersRuleOnly) {
  // The CLI keeps no copy of the steps rule: --steps 0 is refused with each planner's own bound
  // (the bound a copy would get wrong for one of the two systems).
  for (const char* bad : {"0", "-5", "3"}) {
    const ToolRun r = run("plan_maneuver", kScenes + "rest_to_rest.yaml --steps " + bad);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_CONTAINS(r.output, std::string("invalid input: steps: must be >= 4, got ") + bad);
    EXPECT_EQ(r.output.find("--steps: must be"), std::string::npos) << r.output;
  }
  // The drift + two-input system needs N >= 1 only: --steps 0 is refused with that bound.
  const ToolRun drift = run("plan_maneuver", kScenes + "drift_two_input.yaml --steps 0");
  EXPECT_EQ(drift.status, 1) << drift.output;
  EXPECT_CONTAINS(drift.output, "steps must be >= 1, got 0");
}

TEST_F(CliTest, EffectsArePlannedByNewtonAndRefusedWhereUnsupported) {
  std::string text = readFile(kScenes + "rest_to_rest.yaml");
  text.replace(text.find("effects: []"), 11,
               "effects: [{gravity_gradient: {mu: 3.986004418e14, orbit_radius: 7.0e6}}]");
  const std::string scene = writeScene("gg.yaml", text);
  const ToolRun planned = run("plan_maneuver", scene + " --steps 32");
  EXPECT_EQ(planned.status, 0) << planned.output;
  const ToolRun r = run("plan_maneuver", scene + " --solver nlopt --steps 16");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_CONTAINS(r.output, "effects is implemented in the newton solver only");
  std::string limited = readFile(kScenes + "rest_to_rest.yaml");
  limited.replace(limited.find("effects: []"), 11,
                  "effects: [{actuator_limits: {max_torque: [1, 1, 1]}},\n"
                  "          {gravity_gradient: {mu: 3.986004418e14, orbit_radius: 7.0e6}}]");
  // Limits with effect torques: planned by the interior point (bounds inactive here: 1 N m).
  const ToolRun bounds = run("plan_maneuver", writeScene("limits.yaml", limited) + " --steps 16");
  EXPECT_EQ(bounds.status, 0) << bounds.output;
  EXPECT_CONTAINS(bounds.output, "actuator_limits");
}

TEST_F(CliTest, ReplayAppliesExactlyTheScenesEffects) {
  // leo_slew is planned with its gravity gradient and disturbance: replayed under the same scene
  // it lands; under rest_to_rest-like "no effects" and under disturbed_replay (+ torque noise) it
  // misses, and simulate_torques says which effects acted.
  const std::string csv = dir_ + "/leo.csv";
  const ToolRun plan = run("plan_maneuver", kScenes + "leo_slew.yaml --csv " + csv);
  ASSERT_EQ(plan.status, 0) << plan.output;
  const ToolRun same =
      run("simulate_torques", kScenes + "leo_slew.yaml " + csv + " --max-miss 1e-8");
  EXPECT_EQ(same.status, 0) << same.output;
  EXPECT_CONTAINS(same.output, "replay effects           gravity_gradient, disturbance_torque\n");
  std::string bare = readFile(kScenes + "leo_slew.yaml");
  bare = bare.substr(0, bare.find("effects:")) + "effects: []\n";
  const ToolRun none =
      run("simulate_torques", writeScene("bare.yaml", bare) + " " + csv + " --max-miss 1e-3");
  EXPECT_EQ(none.status, 1) << none.output;  // the effects moved the body by more than 1e-3 rad
  EXPECT_CONTAINS(none.output, "replay effects           none\n");
  const ToolRun noisy =
      run("simulate_torques", kScenes + "disturbed_replay.yaml " + csv + " --max-miss 1e-4");
  EXPECT_EQ(noisy.status, 1) << noisy.output;
  EXPECT_CONTAINS(noisy.output, "gravity_gradient, disturbance_torque, torque_noise");
}

TEST_F(CliTest, DriftTwoInputSceneWritesCsvAndSummaryAndReachesTheTarget) {
  // scenes/drift_two_input.yaml: the worked example of docs/design/drift_two_input.md (no guess).
  const std::string csv = dir_ + "/drift.csv", json = dir_ + "/drift.json";
  const ToolRun r =
      run("plan_maneuver", kScenes + "drift_two_input.yaml --csv " + csv + " --summary " + json);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_CONTAINS(r.output, "drift_two_input");
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"converged\": true");
  EXPECT_CONTAINS(summary, "\"system\": \"drift_two_input\"");
  EXPECT_CONTAINS(summary, "\"steps\": 60");
  EXPECT_CONTAINS(summary, "\"control_weights\": [1, 2]");
  EXPECT_CONTAINS(summary, "\"initial_costate_guess\": null");
  EXPECT_CONTAINS(summary, "extremal with p(0) = ");  // the message names the extremal found
  for (const char* key : {"iterations", "cost", "solve_time_s", "initial_costate", "message"}) {
    EXPECT_CONTAINS(summary, std::string("\"") + key + "\": ");
  }
  const std::size_t at = summary.find("\"terminal_attitude_error\": ") + 27;
  EXPECT_LE(std::stod(summary.substr(at)), 1e-10) << summary;

  std::istringstream lines(readFile(csv));
  std::string line;
  ASSERT_TRUE(std::getline(lines, line));
  EXPECT_EQ(line, "k,t,qw,qx,qy,qz,u1,u2,p1,p2,p3");
  int rows = 0;
  std::string last;
  while (std::getline(lines, line)) {
    EXPECT_EQ(line.rfind(std::to_string(rows) + ",", 0), 0u) << line;
    last = line;
    ++rows;
  }
  EXPECT_EQ(rows, 61);  // k = 0..N
  // Last row: t = T, g(T) = g1 = exp(1.2 (1, 1, 0)/√2) to the solver tolerance; u_i = p_i / c_i.
  std::vector<double> v;
  std::istringstream fields(last);
  for (std::string f; std::getline(fields, f, ',');) v.push_back(std::stod(f));
  ASSERT_EQ(v.size(), 11u);
  EXPECT_NEAR(v[1], 3.0, 1e-12);
  const ap::Matrix3 g = ap::so3::fromQuaternion(Eigen::Quaterniond(v[2], v[3], v[4], v[5]));
  const ap::Matrix3 g1 = ap::so3::fromAxisAngle(ap::Vector3(1, 1, 0), 1.2);
  EXPECT_LT(ap::so3::angleBetween(g, g1), 1e-10);
  EXPECT_DOUBLE_EQ(v[6], v[8] / 1.0);
  EXPECT_DOUBLE_EQ(v[7], v[9] / 2.0);

  // A guess from the command line is reported and selects the same extremal here.
  const ToolRun guessed =
      run("plan_maneuver", kScenes +
                               "drift_two_input.yaml --initial-costate=-1.6,-0.9,-1.3 "
                               "--summary " +
                               json);
  EXPECT_EQ(guessed.status, 0) << guessed.output;
  EXPECT_CONTAINS(readFile(json),
                  "\"initial_costate_guess\": [-1.6000000000000001, -0.90000000000000002, -1.3]");
}

TEST_F(CliTest, BadDriftTwoInputScenesExitOneNamingTheKey) {
  const std::string base = readFile(kScenes + "drift_two_input.yaml");
  std::string velocity = base;
  velocity.replace(
      velocity.find("final:   {attitude: {axis: [1, 1, 0], angle: 1.2}}"), 51,
      "final:   {attitude: {axis: [1, 1, 0], angle: 1.2}, angular_velocity: [0, 0, 1]}");
  const ToolRun v = run("plan_maneuver", writeScene("velocity.yaml", velocity));
  EXPECT_EQ(v.status, 1) << v.output;
  EXPECT_CONTAINS(v.output, "final.angular_velocity: not allowed with system: drift_two_input");

  const ToolRun weights = run(
      "plan_maneuver", writeScene("weights.yaml", withReplaced(base, "control_weights: [1.0, 2.0]",
                                                               "control_weights: [1.0, 0]")));
  EXPECT_EQ(weights.status, 1) << weights.output;
  EXPECT_CONTAINS(weights.output, "control_weights[1]: must be > 0, got '0'");

  const ToolRun costate =
      run("plan_maneuver", writeScene("costate.yaml", base + "initial_costate: [1, .nan, 0]\n"));
  EXPECT_EQ(costate.status, 1) << costate.output;
  EXPECT_CONTAINS(costate.output, "initial_costate[1]: not finite");

  const ToolRun effects =
      run("plan_maneuver",
          writeScene("effects.yaml",
                     base + "effects: [{disturbance_torque: {frame: body, value: [0, 0, 1]}}]\n"));
  EXPECT_EQ(effects.status, 1) << effects.output;
  EXPECT_CONTAINS(effects.output, "effects: not modelled for system: drift_two_input");

  // Too few iterations: not converged, exit 1, and the summary says so.
  const std::string json = dir_ + "/short.json";
  const ToolRun short_run =
      run("plan_maneuver", kScenes + "drift_two_input.yaml --max-iterations 1 --summary " + json);
  EXPECT_EQ(short_run.status, 1) << short_run.output;
  EXPECT_CONTAINS(short_run.output, "not converged");
  EXPECT_CONTAINS(readFile(json), "\"converged\": false");

  // Rigid-body-only flags are usage errors for this system, and vice versa.
  const ToolRun scheme =
      run("plan_maneuver", kScenes + "drift_two_input.yaml --scheme variational");
  EXPECT_EQ(scheme.status, 2) << scheme.output;
  EXPECT_CONTAINS(scheme.output, "apply to system: rigid_body only");
  const ToolRun rigid_guess =
      run("plan_maneuver", kScenes + "rest_to_rest.yaml --initial-costate 0,0,0");
  EXPECT_EQ(rigid_guess.status, 2) << rigid_guess.output;
  const ToolRun bad_guess =
      run("plan_maneuver", kScenes + "drift_two_input.yaml --initial-costate 1,2");
  EXPECT_EQ(bad_guess.status, 1) << bad_guess.output;  // a bad value: invalid input
  EXPECT_CONTAINS(bad_guess.output, "--initial-costate: expected P1,P2,P3");
}

TEST_F(CliTest, TargetMissChoosesStepsAndReportsTheEstimate) {
  const std::string csv = dir_ + "/target.csv", json = dir_ + "/target.json";
  const ToolRun r =
      run("plan_maneuver", kScenes + "rest_to_rest.yaml --target-miss 1e-6 --scheme auto --csv " +
                               csv + " --summary " + json);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_CONTAINS(r.output, "accuracy target          terminal_miss <= 1e-06");
  const std::string summary = readFile(json);
  EXPECT_CONTAINS(summary, "\"accuracy\": {\"measure\": \"terminal_miss\"");
  // auto: fourth_order (order-4 miss) needs the least work (3N = 240 against N = 1634 for
  // variational, the best order-2 miss; paper would need N ≈ 1.3 million)
  EXPECT_CONTAINS(summary, "\"scheme\": \"fourth_order\"");
  EXPECT_CONTAINS(
      summary,
      "\"schemes_tried\": [\"paper\", \"variational\", \"second_order\", \"fourth_order\"");
  const std::size_t at = summary.find("\"estimated_error\": ");
  ASSERT_NE(at, std::string::npos) << summary;
  EXPECT_LE(std::stod(summary.substr(at + 19)), 1e-6) << summary;
  // The CSV has the N the planner chose, the one the summary reports (not the scene's 128).
  const ap::Maneuver m = ap::readManeuverCsv(csv);
  EXPECT_CONTAINS(summary, "\"steps\": " + std::to_string(m.steps()) + ",");
  EXPECT_NE(m.steps(), 128);

  for (const char* bad : {"0", "-1e-6", "nan"}) {
    const ToolRun b = run("plan_maneuver", kScenes + "rest_to_rest.yaml --target-miss " + bad);
    EXPECT_EQ(b.status, 1) << b.output;  // a bad value: invalid input
    EXPECT_CONTAINS(b.output, std::string("--target-miss: "));
    EXPECT_CONTAINS(b.output, bad);
  }
  const ToolRun both =
      run("plan_maneuver", kScenes + "rest_to_rest.yaml --target-cost-error 1e-3 --steps 64");
  EXPECT_EQ(both.status, 2) << both.output;
  EXPECT_CONTAINS(both.output, "--target-cost-error chooses N");
}

TEST_F(CliTest, UsageErrorsNameTheFlag) {
  const ToolRun unknown = run("plan_maneuver", kScenes + "rest_to_rest.yaml --stepz 4");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_CONTAINS(unknown.output, "unknown option '--stepz'");
  EXPECT_CONTAINS(unknown.output, "usage: plan_maneuver");

  const ToolRun missing = run("plan_maneuver", kScenes + "rest_to_rest.yaml --steps");
  EXPECT_EQ(missing.status, 2);
  EXPECT_CONTAINS(missing.output, "--steps: missing value");

  const ToolRun not_number = run("plan_maneuver", kScenes + "rest_to_rest.yaml --tolerance abc");
  EXPECT_EQ(not_number.status, 1);  // a bad value is invalid input (1), not a usage error
  EXPECT_CONTAINS(not_number.output, "--tolerance: expected a finite number, got 'abc'");

  const ToolRun scheme = run("plan_maneuver", kScenes + "rest_to_rest.yaml --scheme rk4");
  EXPECT_EQ(scheme.status, 1);
  EXPECT_CONTAINS(scheme.output, "--scheme: unknown value 'rk4'");

  const ToolRun no_scene = run("plan_maneuver", "");
  EXPECT_EQ(no_scene.status, 2);
  EXPECT_CONTAINS(no_scene.output, "missing SCENE.yaml");

  const ToolRun help = run("plan_maneuver", "--help");
  EXPECT_EQ(help.status, 0);
  EXPECT_CONTAINS(help.output, "--max-iterations");

  const ToolRun sim = run("simulate_torques", kScenes + "rest_to_rest.yaml");
  EXPECT_EQ(sim.status, 2);
  EXPECT_CONTAINS(sim.output, "expected SCENE.yaml and MANEUVER.csv");
}

TEST_F(CliTest, AdvancedParametersReachTheSolverAndABadOneIsNamed) {
  // A set value moves the minimum-time iterations, not T* (the flag reaches the free-time solver).
  const std::string scene = kScenes + "min_time_bilimoria_wie.yaml --steps 32 --summary ";
  const ToolRun base = run("plan_maneuver", scene + dir_ + "/base.json");
  const ToolRun set = run("plan_maneuver", scene + dir_ + "/set.json" +
                                               " --advanced interior_point.free_time.theta_mu=1.2");
  ASSERT_EQ(base.status, 0) << base.output;
  ASSERT_EQ(set.status, 0) << set.output;
  const std::string b = readFile(dir_ + "/base.json"), a = readFile(dir_ + "/set.json");
  EXPECT_NE(jsonNumber(a, "iterations"), jsonNumber(b, "iterations"));
  EXPECT_NEAR(jsonNumber(a, "minimum_duration"), jsonNumber(b, "minimum_duration"), 1e-8);

  const ToolRun range = run("plan_maneuver", kScenes +
                                                 "torque_limited.yaml --advanced "
                                                 "interior_point.armijo=0.5");
  EXPECT_EQ(range.status, 1) << range.output;
  EXPECT_CONTAINS(range.output,
                  "--advanced: advanced.interior_point.armijo: must be a finite number in (0, "
                  "0.5), got 0.5");
  const ToolRun unknown = run("plan_maneuver", kScenes +
                                                   "torque_limited.yaml --advanced "
                                                   "interior_point.armijo_typo=0.1");
  EXPECT_EQ(unknown.status, 1) << unknown.output;
  EXPECT_CONTAINS(unknown.output, "advanced.interior_point.armijo_typo: not an advanced parameter");
  const ToolRun shape = run("plan_maneuver", kScenes + "torque_limited.yaml --advanced armijo");
  EXPECT_EQ(shape.status, 1) << shape.output;
  EXPECT_CONTAINS(shape.output, "--advanced: expected NAME=VALUE");
}

TEST_F(CliTest, SimulateTorquesRejectsABadCsvNamingTheLine) {
  const std::string csv = dir_ + "/bad.csv";
  std::ofstream(csv) << "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz\n0,0,1,0,0,0,0,0,0,0,0,0\n"
                        "1,0.1,1,0,0,0,0,0,0,x,0,0\n";
  const ToolRun r = run("simulate_torques", kScenes + "rest_to_rest.yaml " + csv);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_CONTAINS(r.output, "line 3");
}

// --warm-start PLAN.csv: the re-plan from node k of a plan (a scene written from its
// row k) warm-started with the plan's remainder CSV returns the remainder (cost to 1e-8, ≤ 2
// iterations); a plan of another N is resampled; a broken CSV is named with the flag; the
// drift + two-input system refuses the flag.
TEST_F(CliTest, WarmStartFromAPlanCsvRecoversTheRemainder) {
  const std::string csv = dir_ + "/plan.csv", rest_csv = dir_ + "/rest.csv";
  ASSERT_EQ(run("plan_maneuver", kScenes + "rest_to_rest.yaml --steps 64 --csv " + csv).status, 0);
  const ap::Maneuver plan = ap::readManeuverCsv(csv);
  const int k = 16;
  ap::writeManeuverCsv(ap::remainderOfPlan(plan, k), rest_csv);
  const Eigen::Quaterniond q = ap::so3::toQuaternion(plan.attitude[k]);
  const ap::Vector3& w = plan.angular_velocity[k];
  const std::string n = ", ";
  const std::string scene =
      writeScene("rest.yaml",
                 "inertia: [[13.25, -7.80, -11.40], [-7.80, 16.25, 4.71], [-11.40, 4.71, 18.37]]\n"
                 "allow_nonphysical_inertia: true\nduration: " +
                     ap::exactNumber(12.8 * 48 / 64) + "\nsteps: 48\nscheme: paper\n" +
                     "initial: {attitude: {quaternion: [" + ap::exactNumber(q.w()) + n +
                     ap::exactNumber(q.x()) + n + ap::exactNumber(q.y()) + n +
                     ap::exactNumber(q.z()) + "]}, angular_velocity: [" + ap::exactNumber(w.x()) +
                     n + ap::exactNumber(w.y()) + n + ap::exactNumber(w.z()) + "]}\n" +
                     "final: {attitude: {axis: [1, 0, 0], angle: 1.0471975511965976}, "
                     "angular_velocity: [0, 0, 0]}\n");
  double remainder = 0.0;
  for (int j = k + 1; j < 64; ++j) remainder += 0.5 * plan.torque[j].squaredNorm();
  const std::string json = dir_ + "/warm.json";
  const ToolRun warm =
      run("plan_maneuver", scene + " --warm-start " + rest_csv + " --summary " + json);
  ASSERT_EQ(warm.status, 0) << warm.output;
  const std::string summary = readFile(json);
  EXPECT_NEAR(jsonNumber(summary, "cost"), remainder, 1e-8 * remainder) << summary;
  EXPECT_LE(jsonNumber(summary, "iterations"), 2) << summary;

  // The full plan (N = 64) as the guess at N = 128: resampled, the cold solve's cost.
  const std::string cold_json = dir_ + "/cold.json", fine_json = dir_ + "/fine.json";
  ASSERT_EQ(run("plan_maneuver", kScenes + "rest_to_rest.yaml --summary " + cold_json).status, 0);
  const ToolRun fine = run("plan_maneuver", kScenes + "rest_to_rest.yaml --warm-start=" + csv +
                                                " --summary " + fine_json);
  ASSERT_EQ(fine.status, 0) << fine.output;
  EXPECT_NEAR(jsonNumber(readFile(fine_json), "cost"), jsonNumber(readFile(cold_json), "cost"),
              1e-8 * jsonNumber(readFile(cold_json), "cost"));

  // A row whose quaternion is not unit, and a missing file: exit 1, the flag and the value named.
  std::string text = readFile(rest_csv);
  const std::size_t row3 = text.find("\n3,");
  ASSERT_NE(row3, std::string::npos);
  const std::size_t qw = text.find(',', text.find(',', row3 + 1) + 1) + 1;
  text.replace(qw, text.find(',', qw) - qw, "2");
  const std::string broken = dir_ + "/broken.csv";
  std::ofstream(broken) << text;
  const ToolRun bad = run("plan_maneuver", scene + " --warm-start " + broken);
  EXPECT_EQ(bad.status, 1) << bad.output;
  EXPECT_CONTAINS(bad.output, "--warm-start: maneuver CSV '" + broken + "' line 5 (qw,qx,qy,qz)");
  EXPECT_CONTAINS(bad.output, "not a unit quaternion");
  const ToolRun missing = run("plan_maneuver", scene + " --warm-start " + dir_ + "/none.csv");
  EXPECT_EQ(missing.status, 1) << missing.output;
  EXPECT_CONTAINS(missing.output, "--warm-start: maneuver CSV: cannot read");
  const ToolRun drift =
      run("plan_maneuver", kScenes + "drift_two_input.yaml --warm-start " + rest_csv);
  EXPECT_EQ(drift.status, 2) << drift.output;
  EXPECT_CONTAINS(drift.output, "--warm-start");
  EXPECT_CONTAINS(run("plan_maneuver", "--help").output, "--warm-start PLAN.csv");
}

// Reaction wheels through the tools: the CSV's wheel columns, and simulate_torques replaying body
// + wheels from them (docs/reaction_wheels.md).
TEST_F(CliTest, WheelScenePlansAndReplaysBodyAndWheels) {
  const std::string csv = dir_ + "/wheels.csv";
  const ToolRun plan = run("plan_maneuver", kScenes + "reaction_wheels_min_time.yaml --csv " + csv);
  EXPECT_EQ(plan.status, 0) << plan.output;
  EXPECT_CONTAINS(plan.output, "reaction_wheels");
  const ToolRun replay = run("simulate_torques", kScenes + "reaction_wheels_min_time.yaml " + csv);
  EXPECT_EQ(replay.status, 0) << replay.output;
  EXPECT_CONTAINS(replay.output, "wheel replay (RK4)       terminal attitude error");
  EXPECT_CONTAINS(replay.output, "wheel_3");
  // The replay on the plan's scheme from u1..un alone reproduces the plan's nodes to round-off.
  const std::string on_scheme = "wheel replay on second_order     departure from CSV ";
  const std::size_t at = replay.output.find(on_scheme);
  ASSERT_NE(at, std::string::npos) << replay.output;
  EXPECT_LT(std::stod(replay.output.substr(at + on_scheme.size())), 1e-10) << replay.output;
  EXPECT_CONTAINS(replay.output, "wheel_3 at the nodes peak |h|");
}
