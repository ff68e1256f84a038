// plan_maneuver: plan the optimal maneuver of a scene file (command-line entry point).
// Reads the scene, applies flag overrides, calls planManeuver() (system: rigid_body, seed 000) or
// planDriftTwoInput() (system: drift_two_input, seed 001), prints a summary and writes the
// trajectory CSV / JSON summary. Exit status: 0 converged, 1 not converged or invalid input,
// 2 usage error.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/csv.hpp"
#include "attitude_planner/io/plan_flags.hpp"
#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "command_line.hpp"

namespace ap = attitude_planner;

namespace {

using ap::tools::InvalidFlagValue;
using ap::tools::UsageError;

const char* const kUsage =
    "usage: plan_maneuver SCENE.yaml [options]\n"
    "\n"
    "Plans the optimal attitude maneuver of a scene: the minimum-effort rigid-body transfer\n"
    "(seed 000, Problem 3.2; system: rigid_body, the default) or the drift + two-input\n"
    "extremal g' = g(E3 + u1 E1 + u2 E2), min 1/2 int c1 u1^2 + c2 u2^2 dt (seed 001;\n"
    "system: drift_two_input).\n"
    "\n"
    "options (override the scene):\n"
    "  --steps N                 number of time steps (h = T/N)\n"
    "  --scheme paper|variational|second_order|fourth_order|auto\n"
    "                            discretization (rigid_body only; auto: the planner chooses,\n"
    "                            with a --target-* flag only)\n"
    "  --target-miss RAD         instead of --steps: choose N so that the terminal attitude miss\n"
    "                            of the torques held over the steps on the continuous body is\n"
    "                            <= RAD (rigid_body; docs/results/accuracy.md)\n"
    "  --target-cost-error E     instead of --steps: choose N so that |h cost - continuous cost|\n"
    "                            <= E [N^2 m^2 s] (Richardson estimate; rigid_body)\n"
    "  --solver newton|nlopt     newton (default) or the NLopt SLSQP cross-check (rigid_body)\n"
    "  --precision auto|double|extended|double_double\n"
    "                            arithmetic of the interior point's Newton system (rigid_body\n"
    "                            with constraints; auto: double to N = 1024, extended to 8192,\n"
    "                            double_double above)\n"
    "  --objective minimum_effort|minimum_time\n"
    "                            minimum_time: the least duration T* under the torque bounds\n"
    "                            and constraints in force (rigid_body; the scene's duration\n"
    "                            becomes an upper bound and first guess)\n"
    "  --time-margin M           with minimum_time: plan the minimum-effort maneuver at\n"
    "                            (1 + M) T* instead of the bang-bang one at T* (M >= 0)\n"
    "  --tolerance TOL           rigid_body: optimality tolerance (default 1e-10);\n"
    "                            drift_two_input: terminal attitude error [rad] (default 1e-11)\n"
    "  --max-iterations K        iteration limit, default 200 (newton: per grid level and\n"
    "                            start; the coasting start of a spinning solve may take 25x;\n"
    "                            nlopt: function evaluations)\n"
    "  --time-budget S           wall-time limit [s] (default: none)\n"
    "  --threads K               independent solves run at once, K >= 1 (minimum time's\n"
    "                            starts, the homotopy classes; default: the machine's cores)\n"
    "  --direction shortest|long_way  which way round (rigid_body; overrides the scene);\n"
    "                            shortest with no extra turns (the default): the cheapest of\n"
    "                            the homotopy classes (both ways, 0 or 1 extra turn)\n"
    "  --extra-revolutions K     K >= 0 extra full turns (rigid_body; overrides the scene)\n"
    "  --point-body-axis BX,BY,BZ  with --point-world-direction DX,DY,DZ: aim the body axis b\n"
    "                            at the world direction d instead of the scene's final attitude,\n"
    "                            the twist about b chosen by the planner (JSON final_twist;\n"
    "                            rigid_body, minimum effort, constraints allowed)\n"
    "  --point-world-direction DX,DY,DZ  the world direction d of --point-body-axis\n"
    "  --advanced NAME=VALUE     set one of the solvers' tuning constants (repeatable; e.g.\n"
    "                            interior_point.free_time.theta_mu=1.2, newton.armijo=1e-3;\n"
    "                            names and defaults: include/attitude_planner/planning/\n"
    "                            {newton,interior_point}_parameters.hpp; a value out of its\n"
    "                            range is refused, the range named)\n"
    "  --initial-costate P1,P2,P3  drift_two_input: guess for p(0) (overrides initial_costate)\n"
    "  --warm-start PLAN.csv     start from a previous plan (a CSV this tool wrote with --csv,\n"
    "                            e.g. the remainder of the plan being flown): resampled to N\n"
    "                            if its N differs; need not match the boundary data. The\n"
    "                            solve stays in its homotopy class (no other starts); with\n"
    "                            constraints the interior point starts from it (rigid_body)\n"
    "  --csv OUT.csv             write the trajectory: rigid_body "
    "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz\n"
    "                            (+ u1..un,h1..hn with reaction wheels);\n"
    "                            drift_two_input k,t,qw,qx,qy,qz,u1,u2,p1,p2,p3\n"
    "  --summary OUT.json        write the result figures as JSON\n"
    "  --help                    show this help\n"
    "\n"
    "exit status: 0 converged, 1 not converged or invalid input (a bad scene or a bad flag\n"
    "value), 2 usage error (unknown option, missing value or scene file)\n";

/// "p1,p2,p3" → the three finite numbers.
ap::Vector3 parseCostate(const std::string& text) {
  ap::Vector3 p;
  std::size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = text.find(',', start);
    if ((i < 2) != (comma != std::string::npos)) {
      throw InvalidFlagValue{"--initial-costate: expected P1,P2,P3 (three numbers), got '" + text +
                             "'"};
    }
    const std::string number = text.substr(start, comma - start);
    char* end = nullptr;
    p(i) = std::strtod(number.c_str(), &end);
    if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(p(i))) {
      throw InvalidFlagValue{"--initial-costate: expected a finite number, got '" + number + "'"};
    }
    start = comma + 1;
  }
  return p;
}

struct Arguments {
  std::string scene;
  ap::PlanFlags flags;          ///< the planning flags (io/plan_flags.hpp)
  std::string initial_costate;  ///< --initial-costate text, "" if absent
  std::string warm_start;       ///< --warm-start PLAN.csv, "" if absent
  std::string csv;
  std::string summary;
  bool help = false;
};

/// Applies one option (its name without "=value") to *a; next() yields its value.
template <class NextValue>
void applyOption(const std::string& arg, const NextValue& next, Arguments* out) {
  Arguments& a = *out;
  if (ap::isPlanFlag(arg)) {
    if ((arg == "--target-miss" || arg == "--target-cost-error") && !a.flags.target_flag.empty()) {
      throw UsageError{arg + ": only one target (" + a.flags.target_flag + " was given)"};
    }
    const std::string value = next();
    try {
      ap::applyPlanFlag(arg, value, &a.flags);
    } catch (const ap::InvalidInput& e) {
      throw InvalidFlagValue{e.what()};
    }
  } else if (arg == "--initial-costate") {
    a.initial_costate = next();
    parseCostate(a.initial_costate);  // checked here: a bad value, exit status 1
  } else if (arg == "--warm-start") {
    a.warm_start = next();
  } else if (arg == "--csv") {
    a.csv = next();
  } else if (arg == "--summary") {
    a.summary = next();
  } else {
    throw UsageError{"unknown option '" + arg + "'"};
  }
}

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
    applyOption(arg, next, &a);
  }
  if (!a.help && a.scene.empty()) throw UsageError{"missing SCENE.yaml"};
  try {
    ap::checkPlanFlagCombination(a.flags);
  } catch (const ap::InvalidInput& e) {
    throw UsageError{e.what()};
  }
  return a;
}

/// The drift + two-input path of main (seed 001): same flags where they apply, same exit codes.
int runDriftTwoInput(const Arguments& args, const ap::Scene& scene) {
  const ap::PlanFlags& flags = args.flags;
  if (!flags.scheme.empty() || flags.solver_given || !flags.target_flag.empty() ||
      !flags.direction.empty() || flags.extra_revolutions >= 0 || !args.warm_start.empty() ||
      flags.point_body_axis) {
    std::cerr << "plan_maneuver: --scheme, --solver, --direction, "
                 "--extra-revolutions, --warm-start, --point-* and --target-* apply to system: "
                 "rigid_body "
                 "only (this "
                 "scene is drift_two_input)\n\n"
              << kUsage;
    return 2;
  }
  ap::DriftTwoInputRequest request = ap::driftTwoInputRequest(scene);
  if (flags.steps) request.steps = *flags.steps;
  if (flags.tolerance > 0.0) request.tolerance = flags.tolerance;
  if (flags.max_iterations > 0) request.max_iterations = flags.max_iterations;
  request.time_budget_s = flags.time_budget;
  if (!args.initial_costate.empty()) request.initial_costate = parseCostate(args.initial_costate);

  const auto start = std::chrono::steady_clock::now();
  const ap::DriftTwoInputPlan plan = ap::planDriftTwoInput(request);
  const double solve_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "scene                    " << args.scene << "\n"
            << ap::driftTwoInputPlanText(request, plan, solve_time);
  if (!args.csv.empty() && !plan.trajectory.g.empty()) {
    ap::writeDriftTwoInputCsv(plan.trajectory, args.csv);
  }
  if (!args.summary.empty()) {
    std::ofstream out(args.summary);
    out << ap::driftTwoInputPlanJson(request, plan, solve_time);
    if (!out) throw ap::InvalidInput("--summary: cannot write '" + args.summary + "'");
  }
  if (!plan.converged()) {
    std::cerr << "plan_maneuver: not converged: " << plan.message << "\n";
    return 1;
  }
  return 0;
}

/// Plans the scene of `args` and writes what they ask for; the exit status.
int run(const Arguments& args) {
  ap::Scene scene = ap::loadScene(args.scene);
  if (scene.system == ap::SystemKind::DriftTwoInput) return runDriftTwoInput(args, scene);
  if (!args.initial_costate.empty()) {
    std::cerr << "plan_maneuver: --initial-costate applies to system: drift_two_input only\n\n"
              << kUsage;
    return 2;
  }
  ap::requirePlannable(scene);  // effects / other systems: refuse, never ignore
  ap::PlanningProblem& problem = scene.problem;
  ap::SolverOptions options;
  ap::applyPlanFlags(args.flags, &problem, &options);
  ap::Maneuver guess;
  if (!args.warm_start.empty()) {
    try {
      guess = ap::readManeuverCsv(args.warm_start);
    } catch (const ap::InvalidInput& e) {
      throw ap::InvalidInput(std::string("--warm-start: ") + e.what());
    }
    ap::validateInitialGuess(guess, "--warm-start");
    options.warm_start = &guess;
  }

  const ap::PlanResult result = ap::planManeuver(problem, options);
  std::cout << "scene                    " << args.scene << "\n"
            << ap::planResultText(problem, result);
  if (!args.csv.empty() && !result.maneuver.attitude.empty()) {
    if (problem.reaction_wheels.present()) {
      ap::writeManeuverCsv(result.maneuver,
                           ap::wheelStates(problem.scheme, problem.inertia, problem.reaction_wheels,
                                           result.maneuver, problem.worldDisturbance()),
                           args.csv);
    } else {
      ap::writeManeuverCsv(result.maneuver, args.csv);
    }
  }
  if (!args.summary.empty()) {
    std::ofstream out(args.summary);
    out << ap::planResultJson(problem, result);
    if (!out) throw ap::InvalidInput("--summary: cannot write '" + args.summary + "'");
  }
  if (!result.converged()) {
    std::cerr << "plan_maneuver: not converged: " << result.message() << " (termination "
              << ap::terminationName(result.termination) << ")\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return ap::tools::runTool("plan_maneuver", kUsage, argc, argv, parseArguments, run);
}
