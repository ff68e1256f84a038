// plan_maneuver: plan the minimum-effort maneuver of a scene file (command-line entry point).
// Reads the scene, applies flag overrides, calls planManeuver(), prints a summary and writes the
// trajectory CSV / JSON summary. Exit status: 0 converged, 1 not converged or invalid input,
// 2 usage error.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/report.hpp"
#include "attitude_planner/scene.hpp"

namespace ap = attitude_planner;

namespace {

const char* const kUsage =
    "usage: plan_maneuver SCENE.yaml [options]\n"
    "\n"
    "Plans the minimum-effort attitude maneuver of a scene (seed 000, Problem 3.2).\n"
    "\n"
    "options (override the scene):\n"
    "  --steps N                 number of time steps (h = T/N)\n"
    "  --scheme paper|variational  discretization\n"
    "  --solver newton|nlopt     newton (default) or the NLopt SLSQP cross-check\n"
    "  --tolerance TOL           optimality tolerance (default 1e-10)\n"
    "  --max-iterations K        iteration limit (nlopt: function evaluations; default 200)\n"
    "  --time-budget S           wall-time limit [s] (default: none)\n"
    "  --csv OUT.csv             write the trajectory (k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz)\n"
    "  --summary OUT.json        write the result figures as JSON\n"
    "  --help                    show this help\n"
    "\n"
    "exit status: 0 converged, 1 not converged or invalid input, 2 usage error\n";

/// A command-line mistake: reported with the usage text, exit status 2.
struct UsageError {
  std::string message;
};

int parseInt(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || v > 2147483647L ||
      v < -2147483647L) {
    throw UsageError{flag + ": expected an integer, got '" + text + "'"};
  }
  return static_cast<int>(v);
}

double parseDouble(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v)) {
    throw UsageError{flag + ": expected a finite number, got '" + text + "'"};
  }
  return v;
}

struct Arguments {
  std::string scene;
  int steps = 0;  ///< 0: the scene's
  std::string scheme;
  std::string solver = "newton";
  double tolerance = -1.0;  ///< < 0: the default
  int max_iterations = -1;  ///< < 0: the default
  double time_budget = 0.0;
  std::string csv;
  std::string summary;
  bool help = false;
};

Arguments parseArguments(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      a.help = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) {
      if (!a.scene.empty()) {
        throw UsageError{"unexpected argument '" + arg + "' (one scene file only)"};
      }
      a.scene = arg;
      continue;
    }
    std::string value;
    bool has_value = false;
    const std::size_t eq = arg.find('=');
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      has_value = true;
    }
    const auto next = [&]() -> std::string {
      if (has_value) return value;
      if (i + 1 >= argc) throw UsageError{arg + ": missing value"};
      return argv[++i];
    };
    if (arg == "--steps") {
      a.steps = parseInt(arg, next());
      if (a.steps < 1) throw UsageError{"--steps: must be >= 4, got " + std::to_string(a.steps)};
    } else if (arg == "--scheme") {
      a.scheme = next();
      if (a.scheme != "paper" && a.scheme != "variational") {
        throw UsageError{"--scheme: unknown value '" + a.scheme + "' (paper or variational)"};
      }
    } else if (arg == "--solver") {
      a.solver = next();
      if (a.solver != "newton" && a.solver != "nlopt") {
        throw UsageError{"--solver: unknown value '" + a.solver + "' (newton or nlopt)"};
      }
    } else if (arg == "--tolerance") {
      a.tolerance = parseDouble(arg, next());
      if (!(a.tolerance > 0.0)) throw UsageError{"--tolerance: must be > 0"};
    } else if (arg == "--max-iterations") {
      a.max_iterations = parseInt(arg, next());
      if (a.max_iterations < 1) throw UsageError{"--max-iterations: must be >= 1"};
    } else if (arg == "--time-budget") {
      a.time_budget = parseDouble(arg, next());
      if (!(a.time_budget > 0.0)) throw UsageError{"--time-budget: must be > 0 s"};
    } else if (arg == "--csv") {
      a.csv = next();
    } else if (arg == "--summary") {
      a.summary = next();
    } else {
      throw UsageError{"unknown option '" + arg + "'"};
    }
  }
  if (!a.help && a.scene.empty()) throw UsageError{"missing SCENE.yaml"};
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  try {
    args = parseArguments(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "plan_maneuver: " << e.message << "\n\n" << kUsage;
    return 2;
  }
  if (args.help) {
    std::cout << kUsage;
    return 0;
  }

  try {
    ap::Scene scene = ap::loadScene(args.scene);
    ap::requirePlannable(scene);  // effects / other systems: refuse, never ignore
    ap::PlanningProblem& problem = scene.problem;
    if (args.steps > 0) problem.steps = args.steps;
    if (!args.scheme.empty()) problem.scheme = ap::parseSchemeName(args.scheme);

    ap::SolverOptions options;
    options.solver = args.solver;
    if (args.tolerance > 0.0) options.tolerance = args.tolerance;
    if (args.max_iterations > 0) options.max_iterations = args.max_iterations;
    options.time_budget_s = args.time_budget;

    const ap::PlanResult result = ap::planManeuver(problem, options);
    std::cout << "scene                    " << args.scene << "\n"
              << ap::planResultText(problem, result);
    if (!args.csv.empty() && !result.maneuver.attitude.empty()) {
      ap::writeManeuverCsv(result.maneuver, args.csv);
    }
    if (!args.summary.empty()) {
      std::ofstream out(args.summary);
      out << ap::planResultJson(problem, result);
      if (!out) throw ap::InvalidInput("--summary: cannot write '" + args.summary + "'");
    }
    if (!result.converged) {
      std::cerr << "plan_maneuver: not converged: " << result.message << "\n";
      return 1;
    }
    return 0;
  } catch (const ap::InvalidInput& e) {
    std::cerr << "plan_maneuver: invalid input: " << e.what() << "\n";
    return 1;
  } catch (const ap::StepTooLarge& e) {
    std::cerr << "plan_maneuver: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "plan_maneuver: error: " << e.what() << "\n";
    return 1;
  }
}
