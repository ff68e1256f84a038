// Measures what the effects cost and what they change. Writes docs/results/effects.md.
// Usage: effects_report [SCENE_DIR=scenes] [OUT_DIR=docs/results]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

using namespace attitude_planner;

namespace {

double medianNanosecondsPerStep(const DiscreteScheme& scheme, const SimulationInput& input) {
  std::vector<double> t;
  for (int r = 0; r < 7; ++r) {
    const auto start = std::chrono::steady_clock::now();
    simulate(scheme, input);
    t.push_back(
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() /
        (input.torque.size() - 1));
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

/// Terminal miss [rad] of `torque` replayed from the problem's initial state under `effects`.
double miss(const PlanningProblem& p, const std::vector<Vector3>& torque,
            const EffectModel* effects, Actuation* actuation = nullptr) {
  SimulationInput input;
  input.initial_attitude = p.initial_attitude;
  input.initial_velocity = p.initial_velocity;
  input.torque = torque;
  input.effects = effects;
  input.actuation = actuation;
  const Maneuver m = simulate(DiscreteScheme(p.scheme, p.inertia, p.duration / p.steps), input);
  return so3::angleBetween(p.final_attitude, m.attitude[p.steps]);
}

/// The page's heading and what the effects model.
void writeIntro(FILE* md) {
  std::fprintf(
      md,
      "# Effects: what they cost and what they change\n\n"
      "Regenerate: `scripts/effects_report`. Only the effects a scene lists are "
      "simulated; a scene with `effects: []` runs the bare integrator (chosen at compile "
      "time, bit-identical: test/unit/test_effects.cpp).\n\n"
      "Model: known torques τ_e(R_k, t_k) force the discrete dynamics at the nodes, "
      "μ(F_k) = F_{k−1}ᵀμ(F_{k−1}) + h(τ_k + τ_e(R_k, t_k)), for both schemes (for "
      "`variational` this is the discrete Lagrange–d'Alembert forcing, not a potential "
      "in the discrete Lagrangian). `actuator_limits` bound the plan's torques (NLopt with "
      "box bounds when they are active) and saturate the tracker's; `torque_noise` is "
      "tracker-only.\n\n"
      "## Per-step integrator cost\n\n"
      "`simulate()`, variational scheme, LEO inertia, 200 000 steps, median of 7 runs "
      "on this machine (other jobs may have shared the 2 cores).\n\n"
      "| effects | ns per step |\n|---|---|\n");
}

/// The per-step cost of simulate() with more and more effects.
void writeIntegratorCost(FILE* md, const PlanningProblem& p) {
  const int steps = 200000;
  SimulationInput input;
  input.torque.assign(steps + 1, Vector3::Zero());
  for (int k = 1; k < steps; ++k) input.torque[k] = Vector3(1e-4, -2e-4, 5e-5);
  const DiscreteScheme scheme(SchemeKind::Variational, p.inertia, 0.5);
  EffectModel models[4];
  models[1].add(std::make_unique<GravityGradient>(3.986004418e14, 6.778e6, p.inertia));
  models[2].add(std::make_unique<GravityGradient>(3.986004418e14, 6.778e6, p.inertia));
  models[2].add(std::make_unique<DisturbanceTorque>(Vector3(2e-4, 0, -1e-4), TorqueFrame::World));
  models[3].add(std::make_unique<GravityGradient>(3.986004418e14, 6.778e6, p.inertia));
  models[3].add(std::make_unique<DisturbanceTorque>(Vector3(2e-4, 0, -1e-4), TorqueFrame::World));
  models[3].add(std::make_unique<DisturbanceTorque>(Vector3(0, 1e-5, 0), TorqueFrame::Body));
  const char* labels[4] = {"none (`effects: []`)", "gravity_gradient",
                           "gravity_gradient + disturbance (world)",
                           "gravity_gradient + disturbance (world) + disturbance (body)"};
  for (int i = 0; i < 4; ++i) {
    input.effects = i == 0 ? nullptr : &models[i];
    std::fprintf(md, "| %s | %.0f |\n", labels[i], medianNanosecondsPerStep(scheme, input));
  }
}

/// The LEO example: which effects matter (the miss each unplanned effect causes).
void writeLeoMisses(FILE* md, const PlanningProblem& p, const std::string& scenes) {
  const PlanResult planned = planManeuver(p);
  PlanningProblem bare_problem = p;
  bare_problem.effects = nullptr;
  const PlanResult ignorant = planManeuver(bare_problem);
  EffectModel gravity_only, disturbance_only;
  gravity_only.add(std::make_unique<GravityGradient>(3.986004418e14, 6.778e6, p.inertia));
  disturbance_only.add(
      std::make_unique<DisturbanceTorque>(Vector3(2e-4, 0, -1e-4), TorqueFrame::World));
  std::fprintf(md,
               "\n## The LEO slew (scenes/leo_slew.yaml): the miss each unplanned effect causes\n\n"
               "90° about z in 600 s, N = 300, J = diag(800, 1200, 1500) kg m², 400 km orbit. "
               "Terminal attitude miss when the plan's torques are replayed open loop.\n\n"
               "| plan made with | replayed under | terminal miss [rad] |\n|---|---|---|\n"
               "| gravity gradient + disturbance | the same | %.2e |\n"
               "| no effects | no effects | %.2e |\n"
               "| no effects | gravity gradient | %.2e |\n"
               "| no effects | disturbance | %.2e |\n"
               "| no effects | gravity gradient + disturbance | %.2e |\n",
               miss(p, planned.maneuver.torque, p.effects.get()),
               miss(p, ignorant.maneuver.torque, nullptr),
               miss(p, ignorant.maneuver.torque, &gravity_only),
               miss(p, ignorant.maneuver.torque, &disturbance_only),
               miss(p, ignorant.maneuver.torque, p.effects.get()));
  const Scene noisy = loadScene(scenes + "/disturbed_replay.yaml");
  Actuation noise = actuationOf(noisy.effects);
  std::fprintf(md,
               "| gravity gradient + disturbance | the same + torque noise (σ = 1e-4 N m, seed 7; "
               "scenes/disturbed_replay.yaml) | %.2e |\n",
               miss(p, planned.maneuver.torque, p.effects.get(), &noise));
  std::fprintf(md,
               "\nPlanning cost with / without the effects: %.6g / %.6g N² m² (%d / %d Newton "
               "iterations).\n",
               planned.cost, ignorant.cost, planned.iterations, ignorant.iterations);
}

/// The torque-limited scene: bounded against unbounded.
void writeTorqueLimits(FILE* md, const std::string& scenes) {
  const Scene limited = loadScene(scenes + "/torque_limited.yaml");
  PlanningProblem unbounded = limited.problem;
  unbounded.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  const PlanResult free = planManeuver(unbounded), bounded = planManeuver(limited.problem);
  int at_bound = 0;
  double over = -1e300;
  for (const Vector3& t : bounded.maneuver.torque) {
    over = std::max(over, (t.cwiseAbs() - limited.problem.max_torque).maxCoeff());
    if ((t.cwiseAbs() - limited.problem.max_torque).maxCoeff() > -1e-9) ++at_bound;
  }
  std::fprintf(md,
               "\n## Torque limits (scenes/torque_limited.yaml)\n\n"
               "Seed rest-to-rest, N = 64, limits at 70 %% of the unbounded peaks.\n\n"
               "| plan | solver | cost [N² m²] | steps at a bound | max(|τ_i| − limit_i) [N m] | "
               "terminal error [rad] |\n|---|---|---|---|---|---|\n"
               "| unbounded | %s | %.10g | – | – | %.1e |\n"
               "| bounded | %s | %.10g | %d of %d | %.1e | %.1e |\n",
               free.solver.c_str(), free.cost, free.terminal_attitude_error, bounded.solver.c_str(),
               bounded.cost, at_bound, limited.problem.steps + 1, over,
               bounded.terminal_attitude_error);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string scenes = argc > 1 ? argv[1] : "scenes";
  const std::string out = argc > 2 ? argv[2] : "docs/results";
  FILE* md = std::fopen((out + "/effects.md").c_str(), "w");
  if (!md) return std::fprintf(stderr, "cannot write %s/effects.md\n", out.c_str()), 1;
  const Scene leo = loadScene(scenes + "/leo_slew.yaml");
  writeIntro(md);
  writeIntegratorCost(md, leo.problem);
  writeLeoMisses(md, leo.problem, scenes);
  writeTorqueLimits(md, scenes);
  std::fclose(md);
  std::printf("wrote %s/effects.md\n", out.c_str());
  return 0;
}
