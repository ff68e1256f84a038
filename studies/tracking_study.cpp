// Terminal error and torque effort of the tracker's modes (docs/ros_tracker.md): each scene is
// planned once (planManeuver, as the tracker's ~plan_in_process does) and driven open loop
// (replayPlan, mode replay), with the tracking law (simulateTracking, mode feedback) and with the
// law and receding-horizon re-planning (RecedingHorizonRun, mode replan: every period the rest of
// the maneuver is planned by planManeuver from the body's state, warm-started with the rest of the
// plan in force — the request the node sends to the service — and flown from `delay` nodes later)
// under the scene's effects; with torque noise over several noise seeds (median and worst). The
// same core calls as attitude_tracker_node, without ROS.
//
//   tracking_study [--seeds K] [--noise STD] [--cycles C] [--replan-period P] [--replan-delay D]
//                  SCENE.yaml...
//     --seeds K          noise seeds 1..K for scenes with torque noise (default 10)
//     --noise STD        add torque_noise {std: [STD, STD, STD]} [N m] to every scene (default:
//     none)
//     --cycles C         the law's natural frequency ω_n = C / T (default
//     kTrackingCyclesPerManeuver)
//     --replan-period P  maneuver time between re-plans, as a fraction of T (default 0.1), rounded
//                        to whole steps
//     --replan-delay D   plan steps between a re-plan's node and the node it is flown from (default
//                        1: the node's answer arrives within one step)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "attitude_planner/analysis/constraint_health.hpp"
#include "attitude_planner/analysis/replanning.hpp"
#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

using namespace attitude_planner;

namespace {

/// One mode's figures over the noise seeds.
struct ModeFigures {
  std::vector<double> attitude, rate, effort;  // terminal [rad], [rad/s], ½∫|τ|²dt [N²m²s]
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double worst(const std::vector<double>& v) {
  return *std::max_element(v.begin(), v.end());
}

/// The effects with every torque_noise seed replaced by `seed`; whether any noise is present.
std::vector<EffectSpec> withNoiseSeed(std::vector<EffectSpec> effects, std::uint64_t seed,
                                      bool* noisy) {
  *noisy = false;
  for (EffectSpec& e : effects) {
    if (auto* noise = std::get_if<TorqueNoiseSpec>(&e)) {
      noise->seed = seed;
      *noisy = true;
    }
  }
  return effects;
}

/// Re-planning settings (mode replan).
struct ReplanSettings {
  double period_fraction = 0.1;  ///< of T
  int delay_steps = 1;
};

/// The replan mode's closed loop: re-plans from nodes period, 2 period, ... up to
/// lastReplanNode, each flown from `delay` nodes later. Adds the terminal errors against
/// `reference`'s end and the effort to `figures`; returns the re-plans that failed.
int flyReplanned(const PlanningProblem& problem, const ManeuverInterpolation& reference,
                 SchemeKind scheme, const std::shared_ptr<const EffectModel>& effects,
                 const Actuation& actuation, const TrackingOptions& options,
                 const ReplanSettings& settings, ModeFigures* figures) {
  const Maneuver& nodes = reference.nodes();
  const int N = nodes.steps();
  RecedingHorizonRun run(nodes, scheme, problem.inertia, effects, actuation, options);
  const int period = std::max(1, static_cast<int>(std::lround(settings.period_fraction * N)));
  int failures = 0;
  const int last = lastReplanNode(N, nodes.time_step, run.naturalFrequency());
  for (int k = period; k <= last; k += period) {
    const ManeuverSample at_node = run.bodyAtNode(k);
    const RigidBodyState node_state{at_node.attitude, at_node.angular_velocity};
    // The start the tracker sends: the scheme's boundary data, then onto the constraints.
    const double t_k = k * nodes.time_step;
    const RigidBodyState scheme_start =
        schemeStartOf(scheme, problem.inertia, effects.get(), node_state,
                      run.commandAt(node_state, t_k), t_k, nodes.time_step);
    const ProjectedStart body =
        projectOntoConstraints(scheme_start, problem.constraints, ProjectionTolerance(),
                               firstStepFixedByStart(scheme) ? nodes.time_step : 0.0);
    if (!body.feasible) {
      ++failures;
      continue;
    }
    const PlanningProblem rest =
        remainderProblem(problem, k, body.state.attitude, body.state.angular_velocity);
    const Maneuver guess = run.planRemainderAt(k);
    SolverOptions solver;
    solver.warm_start = &guess;
    const PlanResult plan = planManeuver(rest, solver);
    if (!plan.converged()) {
      ++failures;
      continue;  // the node keeps the plan in force too
    }
    run.adopt(plan.maneuver, k, std::min(k + settings.delay_steps, N - 1));
  }
  const ManeuverSample end = run.bodyAt(reference.duration());
  const ManeuverSample target = reference.at(reference.duration());
  figures->attitude.push_back(so3::angleBetween(end.attitude, target.attitude));
  figures->rate.push_back((end.angular_velocity - target.angular_velocity).norm());
  figures->effort.push_back(run.effort());
  return failures;
}

void printRow(const std::string& scene, const std::string& mode, const ModeFigures& f) {
  std::printf("| %s | %s | %.3g | %.3g | %.3g | %.3g | %.6g |\n", scene.c_str(), mode.c_str(),
              median(f.attitude), worst(f.attitude), median(f.rate), worst(f.rate),
              median(f.effort));
}

void study(const std::string& path, int seeds, double extra_noise, double cycles,
           const ReplanSettings& settings) {
  Scene scene = loadScene(path);
  if (extra_noise > 0.0) {
    TorqueNoiseSpec noise;
    noise.std = Vector3::Constant(extra_noise);
    scene.effects.push_back(noise);
  }
  const PlanResult plan = planManeuver(scene.problem);
  if (!plan.converged()) {
    std::fprintf(stderr, "%s: not planned: %s\n", path.c_str(), plan.message().c_str());
    std::exit(1);
  }
  const Matrix3& J = scene.problem.inertia;
  const SchemeKind scheme = scene.problem.scheme;
  const Maneuver& nodes = plan.maneuver;
  const std::shared_ptr<const EffectModel> effects = plannableEffects(scene.effects, J);
  const ManeuverInterpolation reference(nodes, scheme, J, effects.get());
  ModeFigures replay, feedback, replan;
  int failures = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    bool noisy = false;
    const std::vector<EffectSpec> specs = withNoiseSeed(scene.effects, seed, &noisy);
    Actuation open_loop = actuationOf(specs);
    SimulationInput input;
    input.initial_attitude = nodes.attitude[0];
    input.initial_velocity = nodes.angular_velocity[0];
    input.torque = nodes.torque;
    input.effects = effects.get();
    input.actuation = &open_loop;
    const Maneuver replayed = replayPlan(scheme, J, nodes.time_step, input);
    replay.attitude.push_back(so3::angleBetween(replayed.attitude.back(), nodes.attitude.back()));
    replay.rate.push_back(
        (replayed.angular_velocity.back() - nodes.angular_velocity.back()).norm());
    replay.effort.push_back(openLoopEffort(scheme, replayed));

    Actuation closed_loop = actuationOf(specs);
    TrackingOptions options;
    options.natural_frequency = cycles / reference.duration();
    const TrackingRun run =
        simulateTracking(reference, nodes.attitude[0], nodes.angular_velocity[0], effects.get(),
                         &closed_loop, options);
    feedback.attitude.push_back(run.terminal_attitude_error);
    feedback.rate.push_back(run.terminal_velocity_error);
    feedback.effort.push_back(run.effort);

    failures += flyReplanned(scene.problem, reference, scheme, effects, actuationOf(specs), options,
                             settings, &replan);
    if (!noisy) break;  // deterministic: one run says it all
  }
  std::string name = path.substr(path.find_last_of('/') + 1);
  if (extra_noise > 0.0) name += " + noise " + std::to_string(extra_noise).substr(0, 6) + " N m";
  printRow(name, "replay", replay);
  printRow(name, "feedback", feedback);
  printRow(name, "replan", replan);
  if (failures > 0) std::fprintf(stderr, "%s: %d re-plans failed\n", name.c_str(), failures);
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 10;
  double noise = 0.0;
  double cycles = kTrackingCyclesPerManeuver;
  ReplanSettings replan;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seeds" && i + 1 < argc) {
      seeds = std::atoi(argv[++i]);
    } else if (arg == "--cycles" && i + 1 < argc) {
      cycles = std::atof(argv[++i]);
    } else if (arg == "--replan-period" && i + 1 < argc) {
      replan.period_fraction = std::atof(argv[++i]);
    } else if (arg == "--replan-delay" && i + 1 < argc) {
      replan.delay_steps = std::atoi(argv[++i]);
    } else if (arg == "--noise" && i + 1 < argc) {
      noise = std::atof(argv[++i]);
    } else {
      scenes.push_back(arg);
    }
  }
  if (scenes.empty() || seeds < 1 || !(noise >= 0.0) || !(cycles > 0.0) ||
      !(replan.period_fraction > 0.0 && replan.period_fraction <= 1.0) || replan.delay_steps < 0) {
    std::fprintf(stderr,
                 "usage: tracking_study [--seeds K >= 1] [--noise STD >= 0] [--cycles C > 0] "
                 "[--replan-period P in (0, 1]] [--replan-delay D >= 0] SCENE.yaml...\n");
    return 2;
  }
  std::printf(
      "| scene | mode | terminal attitude error, median [rad] | worst [rad] | terminal "
      "rate error, median [rad/s] | worst [rad/s] | effort ½∫\\|τ\\|²dt, median "
      "[N²·m²·s] |\n|---|---|---|---|---|---|---|\n");
  try {
    for (const std::string& s : scenes) study(s, seeds, noise, cycles, replan);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tracking_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
