// call_overhead: the C++ side of the Python call-overhead benchmark
// (scripts/python_benchmark, docs/results/python.md). Loads a scene, applies planning flags as
// plan_maneuver does and times planManeuver R times in this process; prints one wall time [s] per
// line. The Python side times attitude_planner.plan on the same scene and flags in its own process,
// in interleaved rounds.
//
//   call_overhead SCENE.yaml --repeats R [--steps N ...]   (any plan_maneuver planning flag)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/plan_flags.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

namespace ap = attitude_planner;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: call_overhead SCENE.yaml --repeats R [planning flags]\n";
    return 2;
  }
  try {
    ap::Scene scene = ap::loadScene(argv[1]);
    ap::PlanFlags flags;
    int repeats = 1;
    for (int i = 2; i + 1 < argc; i += 2) {
      const std::string flag = argv[i];
      if (flag == "--repeats") {
        repeats = std::atoi(argv[i + 1]);
      } else {
        ap::applyPlanFlag(flag, argv[i + 1], &flags);
      }
    }
    ap::SolverOptions options;
    ap::applyPlanFlags(flags, &scene.problem, &options);
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      const ap::PlanResult result = ap::planManeuver(scene.problem, options);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (!result.converged()) {
        std::cerr << "call_overhead: not converged: " << result.message() << "\n";
        return 1;
      }
      std::printf("%.9f\n", seconds);
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "call_overhead: " << e.what() << "\n";
    return 1;
  }
}
