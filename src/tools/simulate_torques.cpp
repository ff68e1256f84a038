// simulate_torques: replay a maneuver CSV's torques through the discrete dynamics from a scene's
// initial state (the simulation entry point on the command line). Prints the terminal state, the
// miss against the scene's final state and how far the replay departs from the CSV's attitudes.
// Exit status: 0 replayed (and within --max-miss if given), 1 invalid input / failed replay /
// miss too large, 2 usage error.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "attitude_planner/dynamics/discrete_wheel_replay.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/dynamics/wheel_replay.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/csv.hpp"
#include "attitude_planner/io/scene.hpp"
#include "command_line.hpp"

namespace ap = attitude_planner;

namespace {

const char* const kUsage =
    "usage: simulate_torques SCENE.yaml MANEUVER.csv [options]\n"
    "\n"
    "Replays the torques tau_k of MANEUVER.csv (as written by plan_maneuver --csv) through the\n"
    "discrete rigid body of SCENE.yaml (inertia, scheme, initial state; N and h from the CSV;\n"
    "fourth_order: the continuous body under a cubic hold of the torques, RKMK4)\n"
    "under exactly the scene's effects: gravity gradient and disturbances act on the body,\n"
    "actuator_limits saturate and torque_noise perturbs the applied torques. Replaying a plan\n"
    "under a scene with more effects than it was planned for shows their terminal miss.\n"
    "With reaction wheels also body + wheels from the CSV's wheel torques u1..un alone: on the\n"
    "plan's discrete scheme (reproduces a plan's nodes to round-off) and continuously (RK4),\n"
    "each wheel's peaks against its limits.\n"
    "\n"
    "options:\n"
    "  --scheme paper|variational|second_order|fourth_order  override the scene's scheme\n"
    "  --csv OUT.csv             write the replayed trajectory\n"
    "  --max-miss TOL            exit 1 unless both terminal errors are <= TOL\n"
    "  --help                    show this help\n";

using ap::tools::UsageError;

struct Arguments {
  std::string scene_path, csv_path, scheme, out_csv;
  double max_miss = -1.0;  ///< < 0: no bound
  bool help = false;
};

Arguments parseArguments(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      a.help = true;
      return a;
    }
    if (arg.rfind("--", 0) == 0) {
      std::string value;
      const std::size_t eq = arg.find('=');
      if (eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
      } else {
        if (i + 1 >= argc) throw UsageError{arg + ": missing value"};
        value = argv[++i];
      }
      if (arg == "--scheme") {
        a.scheme = value;
      } else if (arg == "--csv") {
        a.out_csv = value;
      } else if (arg == "--max-miss") {
        char* end = nullptr;
        a.max_miss = std::strtod(value.c_str(), &end);
        if (value.empty() || end != value.c_str() + value.size() || !(a.max_miss >= 0.0)) {
          throw UsageError{"--max-miss: expected a number >= 0, got '" + value + "'"};
        }
      } else {
        throw UsageError{"unknown option '" + arg + "'"};
      }
    } else if (a.scene_path.empty()) {
      a.scene_path = arg;
    } else if (a.csv_path.empty()) {
      a.csv_path = arg;
    } else {
      throw UsageError{"unexpected argument '" + arg + "'"};
    }
  }
  if (a.csv_path.empty()) throw UsageError{"expected SCENE.yaml and MANEUVER.csv"};
  return a;
}

/// The replay's figures against the plan and the scene.
struct Miss {
  double attitude_departure = 0.0;  ///< max_k angle(R_k from CSV, R_k replayed) [rad]
  double attitude_error = 0.0;      ///< terminal, against the scene's final attitude [rad]
  double velocity_error = 0.0;      ///< terminal, against the scene's final velocity [rad/s]
};

Miss missOf(const ap::PlanningProblem& p, const ap::Maneuver& planned, const ap::Maneuver& replay) {
  const int N = planned.steps();
  Miss m;
  for (int k = 0; k <= N; ++k) {
    m.attitude_departure = std::max(m.attitude_departure,
                                    ap::so3::angleBetween(planned.attitude[k], replay.attitude[k]));
  }
  m.attitude_error = ap::so3::angleBetween(p.final_attitude, replay.attitude[N]);
  m.velocity_error = (replay.angular_velocity[N] - p.final_velocity).norm();
  return m;
}

void printReport(const ap::Scene& scene, ap::SchemeKind kind, int N, double h,
                 const ap::Maneuver& replay, const ap::SimulationReport& report, const Miss& m) {
  std::string effect_names;
  for (const ap::EffectSpec& e : scene.effects) {
    effect_names += (effect_names.empty() ? "" : ", ") + ap::effectName(e);
  }
  if (effect_names.empty()) effect_names = "none";
  const Eigen::Quaterniond q = ap::so3::toQuaternion(replay.attitude[N]);
  const ap::Vector3& w = replay.angular_velocity[N];  // = Ω_{N−1} for paper, variational
  std::printf(
      "steps N, h               %d, %.6g s (scheme %s)\n"
      "terminal attitude R_N    q = [%.17g, %.17g, %.17g, %.17g] (w, x, y, z)\n"
      "terminal velocity        Omega_N = [%.17g, %.17g, %.17g] rad/s\n"
      "terminal attitude error  %.3g rad\n"
      "terminal velocity error  %.3g rad/s\n"
      "departure from CSV       %.3g rad (max over k of the attitude difference)\n"
      "dynamics residual        %.3g N m s\n"
      "replay effects           %s\n",
      N, h, ap::schemeName(kind).c_str(), q.w(), q.x(), q.y(), q.z(), w.x(), w.y(), w.z(),
      m.attitude_error, m.velocity_error, m.attitude_departure, report.max_step_residual,
      effect_names.c_str());
}

/// Each wheel's peak |h_w,i| over `momentum` and |u_i| over `torque`, printed against the
/// limits, `label` naming the replay in each line.
void printWheelPeaks(const ap::ReactionWheels& wheels, const char* label,
                     const Eigen::VectorXd& peak_momentum, const std::vector<Eigen::VectorXd>& u) {
  for (int i = 0; i < wheels.count(); ++i) {
    double peak_u = 0.0;
    for (const Eigen::VectorXd& row : u) peak_u = std::max(peak_u, std::abs(row(i)));
    std::printf("  wheel_%d%s peak |h| %.17g of %.17g N m s, peak |u| %.17g of %.17g N m\n", i + 1,
                label, peak_momentum(i), wheels.momentumLimit(i), peak_u, wheels.torqueLimit(i));
  }
}

/// The discrete replay on the plan's scheme (replayWithWheelsOnTheScheme): reproduces the plan's
/// nodes to round-off if u1..un are the plan's; its wheel peaks at the nodes against the limits.
void replayWheelsOnTheScheme(const ap::PlanningProblem& p, ap::SchemeKind kind,
                             const ap::Maneuver& planned, const std::vector<Eigen::VectorXd>& u,
                             const Eigen::VectorXd& h0, double h) {
  const ap::ReactionWheels& wheels = p.reaction_wheels;
  const ap::WheelArray array = ap::wheelArray(wheels);
  const ap::DiscreteWheelReplay replay =
      ap::replayWithWheelsOnTheScheme(kind, p.inertia, array.axes, p.initial_attitude,
                                      p.initial_velocity, h0, h, u, p.worldDisturbance());
  double departure = 0.0, envelope = 0.0;
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(wheels.count());
  for (std::size_t k = 0; k < replay.attitude.size(); ++k) {
    departure = std::max(departure, ap::so3::angleBetween(replay.attitude[k], planned.attitude[k]));
    peak = peak.cwiseMax(replay.momentum[k].cwiseAbs());
    envelope = std::max(envelope, (array.axes * replay.momentum[k]).norm());
  }
  std::printf(
      "wheel replay on %s     departure from CSV %.3g rad, terminal attitude error %.3g rad, "
      "velocity error %.3g rad/s, peak |A h_w| %.17g of %.17g N m s\n",
      ap::schemeName(kind).c_str(), departure,
      ap::so3::angleBetween(replay.attitude.back(), p.final_attitude),
      (replay.node_velocity.back() - p.final_velocity).norm(), envelope, wheels.max_momentum_norm);
  printWheelPeaks(wheels, " at the nodes", peak, u);
}

/// With reaction wheels: body + wheels replayed from the CSV's wheel torques alone, on the plan's
/// discrete scheme (the nodes, to round-off) and continuously (RK4 between the nodes: the
/// momentum between them, O(h²)); each wheel's peaks against its limits.
void replayWheels(const ap::PlanningProblem& p, ap::SchemeKind kind, const ap::Maneuver& planned,
                  const std::string& csv_path, double h) {
  const std::vector<Eigen::VectorXd> u = ap::readWheelTorquesCsv(csv_path);
  const ap::ReactionWheels& wheels = p.reaction_wheels;
  if (static_cast<int>(u.empty() ? 0 : u[0].size()) != wheels.count()) {
    throw ap::InvalidInput("maneuver CSV '" + csv_path + "': the scene has " +
                           std::to_string(wheels.count()) +
                           " reaction wheels; the CSV needs their columns u1..un, h1..hn "
                           "(plan_maneuver --csv writes them)");
  }
  Eigen::VectorXd h0(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) h0(i) = wheels.initialMomentum(i);
  if (ap::schemeIsDiscretization(kind)) {
    replayWheelsOnTheScheme(p, kind, planned, u, h0, h);
  } else {
    std::printf("wheel replay on %s     none: %s is not a discretization (RK4 below only)\n",
                ap::schemeName(kind).c_str(), ap::schemeName(kind).c_str());
  }
  const ap::WheelReplay replay =
      ap::replayWithWheels(p.inertia, ap::wheelArray(wheels).axes, p.initial_attitude,
                           p.initial_velocity, h0, h, u, p.worldDisturbance());
  std::printf(
      "wheel replay (RK4)       terminal attitude error %.3g rad, velocity error %.3g rad/s\n",
      ap::so3::angleBetween(replay.attitude.back(), p.final_attitude),
      (replay.angular_velocity.back() - p.final_velocity).norm());
  printWheelPeaks(wheels, "               ", replay.peak_momentum, u);
}

/// Loads, replays and reports; the exit status.
int run(const Arguments& args) {
  const ap::Scene scene = ap::loadScene(args.scene_path);
  ap::requirePlannable(scene);  // rigid_body scenes only (drift_two_input has no torques)
  const ap::PlanningProblem& p = scene.problem;
  const ap::SchemeKind kind =
      args.scheme.empty() ? p.scheme : ap::parseScheme(args.scheme, "--scheme");
  const ap::Maneuver planned = ap::readManeuverCsv(args.csv_path);
  const int N = planned.steps();
  const double h = planned.time.back() / N;  // the CSV's time base
  if (!(h > 0.0) || !std::isfinite(h)) {
    throw ap::InvalidInput("maneuver CSV '" + args.csv_path + "': time step is not positive");
  }
  if (std::abs(N * h - p.duration) > 1e-9 * p.duration) {
    std::cerr << "simulate_torques: note: CSV duration " << N * h << " s differs from the scene's "
              << p.duration << " s; using the CSV's\n";
  }
  ap::SimulationInput input;
  input.initial_attitude = p.initial_attitude;
  input.initial_velocity = p.initial_velocity;
  input.torque = planned.torque;
  const std::shared_ptr<const ap::EffectModel> effects =
      ap::plannableEffects(scene.effects, p.inertia);
  ap::Actuation actuation = ap::actuationOf(scene.effects);
  input.effects = effects.get();
  input.actuation = &actuation;
  ap::SimulationReport report;
  const ap::Maneuver replay = ap::replayPlan(kind, p.inertia, h, input, &report);
  const Miss m = missOf(p, planned, replay);
  printReport(scene, kind, N, h, replay, report, m);
  if (p.reaction_wheels.present()) replayWheels(p, kind, planned, args.csv_path, h);
  if (!args.out_csv.empty()) ap::writeManeuverCsv(replay, args.out_csv);
  if (args.max_miss >= 0.0 &&
      (m.attitude_error > args.max_miss || m.velocity_error > args.max_miss)) {
    std::cerr << "simulate_torques: terminal miss exceeds --max-miss " << args.max_miss << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return ap::tools::runTool("simulate_torques", kUsage, argc, argv, parseArguments, run);
}
