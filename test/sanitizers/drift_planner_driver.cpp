// Focused ASan + UBSan check of the drift + two-input planner alone (docs/notes/sanitizers.md): both
// drift scenes at N = 60 … 4000, a time-budget stop, a guess, the free drift, multiple shooting and
// a target about e3 (the linearized starts). Not part of the catkin build. From the repository
// root, with F = -fsanitize=address,undefined -fno-sanitize-recover=undefined:
//   g++ -O1 -g -fno-omit-frame-pointer $F -std=c++17 -Iinclude -Isrc -I/usr/include/eigen3
//       test/sanitizers/drift_planner_driver.cpp src/drift_two_input/planner.cpp
//       src/drift_two_input/system.cpp src/lie/so3.cpp -o /tmp/drift_asan
//   ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1 /tmp/drift_asan
#include <cstdio>
#include "attitude_planner/drift_two_input/planner.hpp"
using namespace attitude_planner;
int main() {
  DriftTwoInputRequest a;
  a.g1 = so3::fromAxisAngle(Vector3(1, 1, 0), 1.2);
  a.duration = 3.0;
  a.weights = {1.0, 2.0};
  DriftTwoInputRequest b;
  b.g0 = so3::fromAxisAngle(Vector3(1, 0, 0), 0.3);
  b.g1 = so3::fromAxisAngle(Vector3(2.5, 0.3, -0.7), 2.6);
  b.duration = 12.0;
  b.weights = {2.0, 0.5};
  for (DriftTwoInputRequest* rq : {&a, &b})
    for (int N : {60, 100, 400, 1000, 4000}) {
      rq->steps = N;
      const auto p = planDriftTwoInput(*rq);
      std::printf("N=%d converged=%d cost=%.10f\n", N, p.converged(), p.cost);
    }
  a.time_budget_s = 1e-9;
  std::printf("budget: %s\n", planDriftTwoInput(a).message.c_str());
  a.time_budget_s = 0;
  a.initial_costate = Vector3(2, 1, 0);
  a.g1 = so3::exp(Vector3(0, 0, 3));
  std::printf("guess: %d\n", planDriftTwoInput(a).converged());
  a.initial_costate.reset();
  std::printf("free drift: %d\n", planDriftTwoInput(a).converged());
  a.g1 = so3::fromAxisAngle(Vector3(1, 1, 0), 1.2);
  a.duration = 20;
  a.steps = 100;
  a.shooting_intervals = 8;
  a.initial_costate = Vector3(0.5, 0.5, 0);
  std::printf("multiple shooting: %d\n", planDriftTwoInput(a).converged());
  DriftTwoInputRequest c;
  c.duration = 8;
  c.weights = {0.5, 3.0};
  c.g1 = so3::exp(Vector3(0, 0, 3));
  c.steps = 50;
  std::printf("z-axis target: %d\n", planDriftTwoInput(c).converged());
}
