// Every file in test/hostile/scenes/ (first line "# expect: <text>") is
// refused by the scene parser with InvalidInput naming the file, the field and the value, and by
// plan_maneuver with exit status 1 and the same message, never a crash or a hang. Solver options
// and the time budget are checked at the core. The same files seed the fuzz corpus (scripts/fuzz)
// and the bad-input table of docs/results/robustness.md (scripts/robustness).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "support/robustness_cases.hpp"
#include "tool_runner.hpp"

namespace ap = attitude_planner;
namespace fs = std::filesystem;

namespace {

const std::string kHostile = AP_SOURCE_DIR "/test/hostile/scenes/";
using attitude_planner_test::runTool;
using attitude_planner_test::ToolRun;
const std::string& kBin = attitude_planner_test::kToolDir;

struct HostileScene {
  std::string path;
  std::string expected;  ///< the "# expect:" text the error must contain
};

std::vector<HostileScene> hostileScenes() {
  std::vector<HostileScene> out;
  for (const auto& entry : fs::directory_iterator(kHostile)) {
    if (entry.path().extension() != ".yaml") continue;
    std::ifstream in(entry.path());
    std::string first;
    std::getline(in, first);
    const std::string tag = "# expect: ";
    if (first.rfind(tag, 0) != 0) continue;
    out.push_back({entry.path().string(), first.substr(tag.size())});
  }
  std::sort(out.begin(), out.end(),
            [](const HostileScene& a, const HostileScene& b) { return a.path < b.path; });
  return out;
}

ToolRun run(const std::string& args) {
  return runTool("plan_maneuver", args, 60);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ap::InvalidInput& e) {
    return e.what();
  }
  return "(no InvalidInput)";
}

ap::PlanningProblem seedRestToRest(int steps) {
  ap::PlanningProblem p;
  p.inertia = ap::robustness::seedInertia();
  p.allow_nonphysical_inertia = true;
  p.duration = 12.8;
  p.steps = steps;
  p.final_attitude = ap::so3::fromAxisAngle(ap::Vector3::UnitX(), M_PI / 3);
  return p;
}

}  // namespace

TEST(HostileScenes, CorpusIsThere) {
  EXPECT_GE(hostileScenes().size(), 30u);
}

TEST(HostileScenes, EachIsRefusedNamingFileFieldAndValue) {
  for (const HostileScene& h : hostileScenes()) {
    const std::string message = errorOf([&] { ap::loadScene(h.path); });
    EXPECT_NE(message.find(h.expected), std::string::npos)
        << h.path << ": '" << message << "' lacks '" << h.expected << "'";
    EXPECT_NE(message.find(fs::path(h.path).filename().string()), std::string::npos) << message;
  }
}

TEST(HostileScenes, PlanManeuverExitsOneWithTheSameMessage) {
  ASSERT_EQ(access((kBin + "plan_maneuver").c_str(), X_OK), 0) << kBin;
  for (const HostileScene& h : hostileScenes()) {
    const ToolRun r = run("'" + h.path + "'");
    EXPECT_EQ(r.status, 1) << h.path << "\n" << r.output;
    EXPECT_NE(r.output.find("plan_maneuver: invalid input: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(h.expected), std::string::npos) << h.path << "\n" << r.output;
  }
}

TEST(HostileScenes, NearUnitAndNegativeWQuaternionsAreAccepted) {
  const std::string base =
      "inertia: [2, 3, 4]\nduration: 10\nsteps: 16\n"
      "initial: {attitude: {quaternion: [-1, 0, 0, 0]}, angular_velocity: [0, 0, 0]}\n"
      "final: {attitude: {quaternion: [0.7071, 0.7071, 0, 0]}, angular_velocity: [0, 0, 0]}\n"
      "effects: []\n";
  const ap::Scene s = ap::parseScene(base);
  EXPECT_LT(ap::so3::angleBetween(s.problem.initial_attitude, ap::Matrix3::Identity()), 1e-15);
  EXPECT_LT(ap::so3::orthogonalityError(s.problem.final_attitude), 1e-15);
  EXPECT_NEAR(ap::so3::log(s.problem.final_attitude).x(), M_PI / 2, 1e-4);
}

TEST(HostileScenes, DirectionAndExtraRevolutionsAreReadAndWrittenBack) {
  const std::string text =
      "inertia: [2, 3, 4]\nduration: 10\nsteps: 16\ndirection: long_way\nextra_revolutions: 2\n"
      "initial: {attitude: {axis: [1, 0, 0], angle: 0}, angular_velocity: [0, 0, 0]}\n"
      "final: {attitude: {axis: [1, 0, 0], angle: 1}, angular_velocity: [0, 0, 0]}\n"
      "effects: []\n";
  const ap::Scene s = ap::parseScene(text);
  EXPECT_EQ(s.problem.direction, ap::RotationDirection::LongWay);
  EXPECT_EQ(s.problem.extra_revolutions, 2);
  const ap::Scene back = ap::parseScene(ap::formatScene(s));
  EXPECT_EQ(back.problem.direction, ap::RotationDirection::LongWay);
  EXPECT_EQ(back.problem.extra_revolutions, 2);
}

TEST(HostileOptions, BadSolverOptionsNameTheOptionAndTheValue) {
  const ap::PlanningProblem p = seedRestToRest(16);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    ap::SolverOptions options;
    std::string expected;
  };
  std::vector<Case> cases(7);
  cases[0].options.tolerance = -1e-12;
  cases[0].expected = "tolerance: must be a finite number > 0, got -9.9999999999999998e-13";
  cases[1].options.tolerance = nan;
  cases[1].expected = "tolerance: must be a finite number > 0, got nan";
  cases[2].options.tolerance = 0.0;
  cases[2].expected = "tolerance: must be a finite number > 0, got 0";
  cases[3].options.max_iterations = -3;
  cases[3].expected = "max_iterations: must be >= 0, got -3";
  cases[4].options.time_budget_s = -1.0;
  cases[4].expected = "time_budget: must be a finite number >= 0 s (0 = none), got -1";
  cases[5].options.time_budget_s = std::numeric_limits<double>::infinity();
  cases[5].expected = "time_budget: must be a finite number >= 0 s (0 = none), got inf";
  cases[6].options.threads = -2;
  cases[6].expected = "threads: must be >= 0 (0 = the machine's cores), got -2";
  for (const Case& c : cases) {
    EXPECT_EQ(errorOf([&] { ap::planManeuver(p, c.options); }), c.expected);
  }
}

TEST(HostileOptions, FlagValuesAreInvalidInputNamingTheValue) {
  // A bad flag value is invalid input like a bad scene value: exit status 1, naming flag and value
  // (2 stays for a malformed command line: unknown option, missing value).
  const std::string scene = "'" AP_SOURCE_DIR "/scenes/rest_to_rest.yaml'";
  const ToolRun tol = run(scene + " --tolerance -1e-3");
  EXPECT_EQ(tol.status, 1) << tol.output;
  EXPECT_NE(tol.output.find("--tolerance: must be > 0, got -1e-3"), std::string::npos)
      << tol.output;
  const ToolRun nan = run(scene + " --tolerance nan");
  EXPECT_EQ(nan.status, 1) << nan.output;
  EXPECT_NE(nan.output.find("--tolerance: expected a finite number, got 'nan'"), std::string::npos)
      << nan.output;
  const ToolRun budget = run(scene + " --time-budget -5");
  EXPECT_EQ(budget.status, 1) << budget.output;
  EXPECT_NE(budget.output.find("--time-budget: must be > 0 s, got -5"), std::string::npos)
      << budget.output;
  const ToolRun threads = run(scene + " --threads 0");
  EXPECT_EQ(threads.status, 1) << threads.output;
  EXPECT_NE(threads.output.find("--threads: must be >= 1, got 0"), std::string::npos)
      << threads.output;
  const ToolRun turns = run(scene + " --extra-revolutions -1");
  EXPECT_EQ(turns.status, 1) << turns.output;
  EXPECT_NE(turns.output.find("--extra-revolutions: must be >= 0, got -1"), std::string::npos)
      << turns.output;
  const ToolRun way = run(scene + " --direction sideways");
  EXPECT_EQ(way.status, 1) << way.output;
  EXPECT_NE(way.output.find("--direction: unknown value 'sideways'"), std::string::npos)
      << way.output;
}

TEST(HostileOptions, StepTooLargeIsExitOneSayingIncreaseSteps) {
  const std::string text =
      "inertia: [2, 3, 4]\nduration: 1\nsteps: 8\n"
      "initial: {attitude: {axis: [1, 0, 0], angle: 0}, angular_velocity: [0, 0, 40]}\n"
      "final: {attitude: {axis: [1, 0, 0], angle: 1}, angular_velocity: [0, 0, 0]}\n"
      "effects: []\n";
  const std::string path = ::testing::TempDir() + "/ap_step_too_large.yaml";
  std::ofstream(path) << text;
  const ToolRun r = run("'" + path + "'");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("initial.angular_velocity: step too large, increase steps"),
            std::string::npos)
      << r.output;
  const ToolRun fine = run("'" + path + "' --steps 64");
  EXPECT_EQ(fine.status, 0) << fine.output;
}

TEST(HostileOptions, TimeBudgetStopsALongSolveCleanly) {
  // N = 1e5 takes ~1 s unbounded (its coarse levels alone ~0.3 s); a 0.01 s budget stops it at
  // the next iteration boundary, on any machine, with a not-converged result on the requested grid
  // (no exception, finite figures).
  const ap::PlanningProblem p = seedRestToRest(100000);
  ap::SolverOptions options;
  options.time_budget_s = 0.01;
  const auto start = std::chrono::steady_clock::now();
  const ap::PlanResult r = ap::planManeuver(p, options);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_FALSE(r.converged());
  EXPECT_NE(r.message().find("time budget"), std::string::npos) << r.message();
  EXPECT_LT(elapsed, 0.01 + 5.0) << r.message();
  EXPECT_EQ(r.maneuver.steps(), 100000);
  EXPECT_TRUE(std::isfinite(r.cost));
  std::printf("budget 0.01 s: returned after %.2f s: %s\n", elapsed, r.message().c_str());
}

TEST(HostileOptions, PlanManeuverTimeBudgetFlagStopsTheCli) {
  const std::string scene = "'" AP_SOURCE_DIR "/scenes/rest_to_rest.yaml'";
  const auto start = std::chrono::steady_clock::now();
  const ToolRun r = run(scene + " --steps 100000 --time-budget 0.01");
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("time budget"), std::string::npos) << r.output;
  EXPECT_LT(elapsed, 10.0) << r.output;
}

TEST(Determinism, PlanManeuverWritesByteIdenticalFilesTwice) {
  const std::string scene = "'" AP_SOURCE_DIR "/scenes/slew_up.yaml'";
  const std::string a = ::testing::TempDir() + "/ap_det_a.csv",
                    b = ::testing::TempDir() + "/ap_det_b.csv";
  ASSERT_EQ(run(scene + " --steps 512 --csv '" + a + "'").status, 0);
  ASSERT_EQ(run(scene + " --steps 512 --csv '" + b + "'").status, 0);
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  std::stringstream sa, sb;
  sa << fa.rdbuf();
  sb << fb.rdbuf();
  EXPECT_GT(sa.str().size(), 512u * 50u);
  EXPECT_TRUE(sa.str() == sb.str()) << "the two CSVs differ";
}

TEST(FuzzRegressions, HugeBoundaryVelocityIsStepTooLargeNotSolved) {
  // test/fuzz/regressions/request/huge_initial_velocity_variational.bin: Ω_0 = (−5.2e153, 0, 0)
  // rad/s, variational scheme. |JΩ| overflowed the norms in the implicit step's tolerance (+inf),
  // so the step "converged", the planner went on with infinite coasting and cast it to int (UB;
  // in a Release build an empty list of lifts was indexed). Now: StepTooLarge, naming the field.
  const ap::DiscreteScheme scheme(ap::SchemeKind::Variational, ap::robustness::seedInertia(), 0.4);
  EXPECT_THROW(scheme.stepFromVelocity(ap::Vector3(-5.237424972633827e153, 0, 0)),
               ap::StepTooLarge);
  ap::PlanningProblem p = seedRestToRest(32);
  p.scheme = ap::SchemeKind::Variational;
  p.initial_velocity = ap::Vector3(-5.237424972633827e153, 2.002885e-317, 0.0);
  try {
    ap::planManeuver(p);
    FAIL() << "expected StepTooLarge";
  } catch (const ap::StepTooLarge& e) {
    EXPECT_NE(std::string(e.what()).find("initial.angular_velocity: step too large"),
              std::string::npos)
        << e.what();
  }
}
