// accuracy_study: what accuracy costs in time. For each scene and scheme, solves the
// continuous reference, then plans at N = 16, 32, ..., max and records the three accuracy
// measures (accuracy.hpp) and the median solve time; then plans to requested accuracies and
// compares the planner's estimate with the actual error. Writes one JSON object (raw data for
// scripts/plot_accuracy.py, which writes docs/results/accuracy.md and the plots).
//
// usage: accuracy_study OUT.json SCENE.yaml... [--max-steps N] [--repeats K]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "attitude_planner/analysis/accuracy.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "support/study_tools.hpp"

using namespace attitude_planner;

namespace {

using attitude_planner::study::loadAverage;
using attitude_planner::study::median;
using attitude_planner::study::seconds;

/// max_k |τ_k| [N m]: the scale of the relative torque error.
double maxTorque(const Maneuver& m) {
  double largest = 0.0;
  for (const Vector3& t : m.torque) largest = std::max(largest, t.norm());
  return largest;
}

std::string sceneName(const std::string& path) {
  std::string base = path.substr(path.find_last_of('/') + 1);
  return base.substr(0, base.find('.'));
}

/// The continuous reference of a scene and its self-check at twice the segments and macro steps.
struct CheckedReference {
  ContinuousReference ref;
  double solve_time_s = 0.0;
  double cost_vs_finer = 0.0, attitude_vs_finer = 0.0, torque_vs_finer = 0.0;
};

CheckedReference checkedReference(const PlanningProblem& problem) {
  const auto t0 = std::chrono::steady_clock::now();
  CheckedReference out{solveContinuousReference(problem), 0.0, 0.0, 0.0, 0.0};
  out.solve_time_s = seconds(t0);
  ReferenceOptions fine_options;
  fine_options.segments = 16;
  fine_options.macro_steps_per_segment = 32;
  const ContinuousReference fine = solveContinuousReference(problem, fine_options);
  const ContinuousState mid = out.ref.stateAt(0.37 * problem.duration);
  const ContinuousState mid_fine = fine.stateAt(0.37 * problem.duration);
  out.cost_vs_finer = std::abs(out.ref.cost - fine.cost);
  out.attitude_vs_finer = so3::angleBetween(mid.attitude, mid_fine.attitude);
  out.torque_vs_finer = (mid.torque() - mid_fine.torque()).norm();
  return out;
}

/// The plan of `problem` solved `repeats` times (the last) and the median solve time.
PlanResult timedPlan(const PlanningProblem& problem, int repeats, double* median_time) {
  std::vector<double> times;
  PlanResult plan;
  for (int r = 0; r < repeats; ++r) {
    plan = planManeuver(problem);
    times.push_back(plan.solve_time_s);
  }
  *median_time = median(times);
  return plan;
}

/// The sweep N = 16, 32, ..., max_steps: the three accuracy measures and the solve time.
void writeSweep(FILE* out, PlanningProblem& problem, const ContinuousReference& ref, int max_steps,
                int repeats) {
  for (int N = 16; N <= max_steps; N *= 2) {
    problem.steps = N;
    double time = 0.0;
    const PlanResult plan = timedPlan(problem, repeats, &time);
    const AccuracyMeasures m = measureAccuracy(problem, plan.maneuver, ref);
    std::fprintf(out,
                 "  %s{\"N\": %d, \"converged\": %s, \"solve_time_s\": %.6g, \"cost\": %.17g, "
                 "\"cost_integral\": %.17g, \"cost_error\": %.6e, \"trajectory_error\": %.6e, "
                 "\"torque_error\": %.6e, \"max_torque\": %.6e, \"attitude_miss\": %.6e, "
                 "\"velocity_miss\": %.6e, "
                 "\"attitude_miss_step_start\": %.6e, \"velocity_miss_step_start\": %.6e}\n",
                 N == 16 ? "" : ",", N, plan.converged() ? "true" : "false", time, plan.cost,
                 m.cost_integral, m.cost_error, m.trajectory_error, m.torque_error,
                 maxTorque(plan.maneuver), m.miss.attitude_miss, m.miss.velocity_miss,
                 m.miss_step_start.attitude_miss, m.miss_step_start.velocity_miss);
    std::fprintf(stderr, "  %s N=%d %.3g s cost_err %.3e traj %.3e miss %.3e\n",
                 schemeName(problem.scheme).c_str(), N, time, m.cost_error, m.trajectory_error,
                 m.miss.attitude_miss);
  }
}

/// Coarse grids, every N = 4 … 32: which N (and time) reaches a given loose accuracy, e.g. the
/// seed's default plan's (README, "Which scheme reaches the seed's default accuracy").
void writeCoarse(FILE* out, PlanningProblem& problem, const ContinuousReference& ref, int repeats) {
  for (int N = 4; N <= 32; ++N) {
    problem.steps = N;
    double time = 0.0;
    const PlanResult plan = timedPlan(problem, 5 * repeats, &time);
    if (!plan.converged() || plan.maneuver.steps() != N) {  // e.g. a step too large
      std::fprintf(out, "  %s{\"N\": %d, \"converged\": false}\n", N == 4 ? "" : ",", N);
      continue;
    }
    const AccuracyMeasures m = measureAccuracy(problem, plan.maneuver, ref);
    std::fprintf(out,
                 "  %s{\"N\": %d, \"converged\": %s, \"solve_time_s\": %.6g, "
                 "\"relative_torque_error\": %.6e, \"trajectory_error\": %.6e, "
                 "\"attitude_miss\": %.6e}\n",
                 N == 4 ? "" : ",", N, plan.converged() ? "true" : "false", time,
                 m.torque_error / maxTorque(plan.maneuver), m.trajectory_error,
                 m.miss.attitude_miss);
  }
}

/// Plans to a requested accuracy: the planner's estimate against the actual error.
void writeTargets(FILE* out, const PlanningProblem& problem, const ContinuousReference& ref,
                  int repeats) {
  struct Request {
    AccuracyMeasure measure;
    double value;
  };
  const Request requests[] = {
      {AccuracyMeasure::TerminalMiss, 1e-4}, {AccuracyMeasure::TerminalMiss, 1e-6},
      {AccuracyMeasure::TerminalMiss, 1e-8}, {AccuracyMeasure::CostError, 1e-2},
      {AccuracyMeasure::CostError, 1e-3},    {AccuracyMeasure::CostError, 1e-4}};
  bool first_target = true;
  for (const Request& q : requests) {
    PlanningProblem wanted = problem;
    wanted.accuracy.measure = q.measure;
    wanted.accuracy.value = q.value;
    double time = 0.0;
    const PlanResult plan = timedPlan(wanted, repeats, &time);
    const int N = plan.maneuver.steps();
    double actual = 0.0;
    double plain_time = 0.0;
    if (plan.converged()) {
      PlanningProblem at_N = problem;
      at_N.steps = N;
      const AccuracyMeasures m = measureAccuracy(at_N, plan.maneuver, ref);
      actual = q.measure == AccuracyMeasure::TerminalMiss ? m.miss.attitude_miss : m.cost_error;
      std::vector<double> plain;
      for (int r = 0; r < repeats; ++r) plain.push_back(planManeuver(at_N).solve_time_s);
      plain_time = median(plain);
    }
    std::string tried;
    for (size_t i = 0; i < plan.accuracy.steps_tried.size(); ++i) {
      tried += (i ? "," : "") + std::to_string(plan.accuracy.steps_tried[i]);
    }
    std::fprintf(out,
                 "  %s{\"measure\": \"%s\", \"target\": %.3g, \"converged\": %s, \"N\": %d, "
                 "\"estimated\": %.6e, \"predicted\": %.6e, \"actual\": %.6e, "
                 "\"solve_time_s\": %.6g, \"plain_solve_time_s\": %.6g, \"tried\": \"%s\"}\n",
                 first_target ? "" : ",", accuracyMeasureName(q.measure).c_str(), q.value,
                 plan.converged() ? "true" : "false", N, plan.accuracy.estimated_error,
                 plan.accuracy.predicted_error, actual, time, plain_time, tried.c_str());
    first_target = false;
  }
}

/// One scene in every scheme: the reference, the sweep, the coarse grids and the targets.
void runScene(FILE* out, const std::string& path, int max_steps, int repeats, bool* first_case) {
  PlanningProblem problem = loadScene(path).problem;
  const CheckedReference checked = checkedReference(problem);
  const ContinuousReference& ref = checked.ref;
  std::fprintf(stderr, "%s: reference %s (%.2f s), cost %.15g\n", path.c_str(), ref.message.c_str(),
               checked.solve_time_s, ref.cost);
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder,
                            SchemeKind::FourthOrder}) {
    problem.scheme = scheme;
    std::fprintf(out,
                 "%s{\"scene\": \"%s\", \"scheme\": \"%s\", \"duration\": %.17g,\n"
                 " \"reference\": {\"converged\": %s, \"cost\": %.17g, \"iterations\": %d, "
                 "\"max_defect\": %.3e, \"integration_error\": %.3e, \"hamiltonian_drift\": %.3e, "
                 "\"solve_time_s\": %.4g, \"cost_vs_finer\": %.3e, \"attitude_vs_finer\": %.3e, "
                 "\"torque_vs_finer\": %.3e},\n \"sweep\": [\n",
                 *first_case ? "" : ",\n", sceneName(path).c_str(), schemeName(scheme).c_str(),
                 problem.duration, ref.converged ? "true" : "false", ref.cost, ref.iterations,
                 ref.max_defect, ref.integration_error, ref.hamiltonian_drift, checked.solve_time_s,
                 checked.cost_vs_finer, checked.attitude_vs_finer, checked.torque_vs_finer);
    *first_case = false;
    writeSweep(out, problem, ref, max_steps, repeats);
    std::fprintf(out, " ],\n \"coarse\": [\n");
    writeCoarse(out, problem, ref, repeats);
    std::fprintf(out, " ],\n \"targets\": [\n");
    writeTargets(out, problem, ref, repeats);
    std::fprintf(out, " ]}");
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: accuracy_study OUT.json SCENE.yaml... [--max-steps N] [--repeats K]\n");
    return 2;
  }
  const std::string out_path = argv[1];
  std::vector<std::string> scenes;
  int max_steps = 8192;
  int repeats = 3;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--max-steps" && i + 1 < argc) {
      max_steps = std::atoi(argv[++i]);
    } else if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else {
      scenes.push_back(a);
    }
  }
  FILE* out = std::fopen(out_path.c_str(), "w");
  if (!out) {
    std::fprintf(stderr, "accuracy_study: cannot write %s\n", out_path.c_str());
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  std::fprintf(out, "{\n\"load_average_start\": \"%s\",\n\"repeats\": %d,\n\"cases\": [\n",
               loadAverage().c_str(), repeats);
  bool first_case = true;
  for (const std::string& path : scenes) runScene(out, path, max_steps, repeats, &first_case);
  std::fprintf(out, "\n],\n\"load_average_end\": \"%s\",\n\"wall_time_s\": %.1f\n}\n",
               loadAverage().c_str(), seconds(start));
  std::fclose(out);
  return 0;
}
