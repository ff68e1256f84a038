// The C++ example of README.md ("Planning from C++"): the seed's rest-to-rest slew planned through
// planManeuver(). README.md holds the lines between the two markers verbatim, and
// test/unit/test_docs.cpp checks that it does and runs this program, so the example cannot rot.
// Built by CMake (target plan_rest_to_rest, not installed).
// BEGIN README EXAMPLE
#include <cmath>
#include <cstdio>

#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planner.hpp"

int main() {
  using namespace attitude_planner;
  PlanningProblem problem;
  problem.inertia << 13.25, -7.80, -11.40,  // J [kg m²], body frame (the seed's example)
      -7.80, 16.25, 4.71,                   //
      -11.40, 4.71, 18.37;
  problem.allow_nonphysical_inertia = true;  // the seed's J violates J1 + J2 >= J3
  problem.duration = 12.8;                   // T [s]
  problem.steps = 128;                       // N, h = T/N
  problem.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3);  // R_N; R_0 = I
  // Ω_0 = Ω_{N−1} = 0 (rest to rest); scheme paper; no effects, no constraints.

  SolverOptions options;                                   // Newton, relative tolerance 1e-10
  options.time_budget_s = 5;                               // wall-time limit [s]
  const PlanResult plan = planManeuver(problem, options);  // throws InvalidInput on bad input

  std::printf("%s in %d iterations: cost %.8f N^2 m^2, replay miss %.1e rad\n",
              terminationName(plan.termination).c_str(), plan.iterations, plan.cost,
              plan.replay_miss);
  if (!plan.converged()) {
    std::fprintf(stderr, "%s\n", plan.message().c_str());  // why, in words
    return 1;
  }
  const Vector3& tau = plan.maneuver.torque[1];  // τ_k [N m], body, k = 0..N
  std::printf("tau_1 = [%.6f, %.6f, %.6f] N m\n", tau.x(), tau.y(), tau.z());
  return 0;
}
// END README EXAMPLE
