// step_roots_study: how many converged plans have a step on another root of the implicit step,
// and what checking it costs. Each plan is replayed step by step (replayStepByStep: each step
// solved by the open-loop replay's own solve from the plan's state): a step on another root lands
// O(1) rad from the plan's. Seeded problems of two families: the random suite
// (test/support/random_problems.hpp) and unstable spins near the intermediate axis
// (unstableSpin), each planned in every scheme with discrete equations (paper, variational,
// second_order) by every solver: Newton (unconstrained), the interior point (a torque-norm bound
// at 0.8 of the Newton plan's peak) and NLopt SLSQP (the first --nlopt-count problems of each
// family, at N = 32). One line per plan on stderr; the tally on stdout. Since the acceptance
// (planInconsistency) replays each step too, a structured solver's converged plan has no step on
// another root by construction; run against an older core library (LD_LIBRARY_PATH) it counts
// what the acceptance now refuses, and what the check costs beside the solves
// (docs/design/planner_behaviour.md, "Every step on the scheme's principal branch").
//
//   step_roots_study [--count K] [--spins S] [--seed SEED] [--nlopt-count M] [--time-budget S]
//                    [--scheme NAME]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "planning/problem/verdict.hpp"
#include "support/random_problems.hpp"
#include "support/study_tools.hpp"

namespace ap = attitude_planner;
namespace rb = attitude_planner::robustness;
namespace st = attitude_planner::study;

namespace {

struct Options {
  int count = 200;
  int spins = 40;
  int nlopt_count = 10;
  std::uint64_t seed = 19;
  int time_budget = 30;  ///< per solve [s]: a plan stopped by it is not converged
  std::string scheme;    ///< one scheme only ("": paper, variational and second_order)
};

Options parse(int argc, char** argv) {
  Options o;
  st::FlagReader flags;
  flags.add("--count", &o.count)
      .add("--spins", &o.spins)
      .add("--seed", &o.seed)
      .add("--nlopt-count", &o.nlopt_count)
      .add("--time-budget", &o.time_budget)
      .add("--scheme", &o.scheme);
  st::readFlagsOrExit(flags, argc, argv, "step_roots_study",
                      "[--count K] [--spins S] [--seed SEED] [--nlopt-count M] [--time-budget S] "
                      "[--scheme NAME]");
  return o;
}

/// The tally of one solver in one scheme.
struct Tally {
  int plans = 0, converged = 0, other_root = 0, parted = 0;
  double worst_reproduced = 0.0;         ///< the largest step gap of a reproduced plan [rad]
  std::vector<double> check_over_solve;  ///< replayStepByStep's wall time / the solve's
  double check_seconds = 0.0, solve_seconds = 0.0;
};

double peakNorm(const std::vector<ap::Vector3>& torque) {
  double peak = 0.0;
  for (const ap::Vector3& t : torque) peak = std::max(peak, t.norm());
  return peak;
}

/// Plans `p` with `options`, replays a converged plan step by step, adds it to `tally`.
ap::PlanResult judge(const std::string& label, const ap::PlanningProblem& p,
                     const ap::SolverOptions& options, Tally* tally) {
  ++tally->plans;
  const auto solve_start = std::chrono::steady_clock::now();
  ap::PlanResult r;
  try {
    r = ap::planManeuver(p, options);
  } catch (const std::exception& e) {
    std::cerr << label << ": refused: " << e.what() << "\n";
    return r;
  }
  const double solve_s = st::seconds(solve_start);
  std::cerr << label << ": " << ap::terminationName(r.termination);
  if (r.converged()) {
    ++tally->converged;
    const auto check_start = std::chrono::steady_clock::now();
    const ap::StepwiseReplay stepwise = ap::replayStepByStep(p, r.maneuver);
    const double check_s = st::seconds(check_start);
    tally->check_seconds += check_s;
    tally->solve_seconds += solve_s;
    tally->check_over_solve.push_back(check_s / solve_s);
    if (!std::isfinite(r.replay_miss)) ++tally->parted;
    if (stepwise.reproduces()) {
      tally->worst_reproduced = std::max(tally->worst_reproduced, stepwise.worst_angle);
    } else {
      ++tally->other_root;
    }
    std::cerr << ", step gap " << stepwise.worst_angle << " rad at k = " << stepwise.worst_step
              << " (" << (stepwise.reproduces() ? "reproduced" : "ANOTHER ROOT")
              << "), replay miss " << r.replay_miss << ", check " << check_s << " s of " << solve_s
              << " s";
  }
  std::cerr << "\n";
  return r;
}

/// Seeded: a spin near the intermediate axis of a random anisotropic body, spun up over 40-60 s
/// (the family of test_plan_verdict's unstable spins).
ap::PlanningProblem unstableSpin(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ap::PlanningProblem p;
  p.inertia = ap::Vector3(0.2 + 0.3 * u(*rng), 2.0 + u(*rng), 3.0 + 2.0 * u(*rng)).asDiagonal();
  p.allow_nonphysical_inertia = true;
  p.duration = 40.0 + 20.0 * u(*rng);
  p.steps = 400;
  const double w = 1.0 + u(*rng);
  p.initial_velocity = ap::Vector3(0.0, w, 0.0);
  p.final_velocity = ap::Vector3(0.0, 3.0 * w, 0.1);
  p.final_attitude = ap::so3::exp(ap::Vector3(0.3 * u(*rng), 1.0, 0.2));
  return p;
}

const ap::SchemeKind kSchemes[] = {ap::SchemeKind::Paper, ap::SchemeKind::Variational,
                                   ap::SchemeKind::SecondOrder};

/// Every scheme and solver on one problem of family `family`, index `i`.
void planEverywhere(const std::string& family, int i, ap::PlanningProblem p, bool nlopt,
                    int time_budget, const std::string& only_scheme,
                    std::map<std::string, Tally>* tallies) {
  ap::SolverOptions structured;
  structured.time_budget_s = time_budget;
  for (ap::SchemeKind scheme : kSchemes) {
    if (!only_scheme.empty() && ap::schemeName(scheme) != only_scheme) continue;
    p.scheme = scheme;
    p.constraints.clear();
    const std::string name = ap::schemeName(scheme);
    const std::string label = family + " #" + std::to_string(i) + " " + name;
    const ap::PlanResult free =
        judge(label + " newton", p, structured, &(*tallies)[name + " newton"]);
    if (free.converged()) {
      ap::PlanningProblem bounded = p;
      bounded.constraints = {
          ap::PlanningConstraint::maxTorqueNorm(0.8 * peakNorm(free.maneuver.torque))};
      judge(label + " interior point", bounded, structured, &(*tallies)[name + " interior point"]);
    }
    // SLSQP's dense steps: at N = 32 (64 and above ran to its limit in tens of seconds), and
    // only the schemes it transcribes.
    if (nlopt && scheme != ap::SchemeKind::SecondOrder) {
      ap::SolverOptions options = structured;
      options.solver = ap::SolverKind::Nlopt;
      ap::PlanningProblem coarse = p;
      coarse.steps = 32;
      judge(label + " nlopt N = 32", coarse, options, &(*tallies)[name + " nlopt"]);
    }
  }
}

void print(const std::map<std::string, Tally>& tallies) {
  std::printf(
      "| scheme, solver | plans | converged | a step on another root | open-loop replay "
      "parted | worst reproduced step gap [rad] | check / solve, median (max) | check, "
      "total [s] | solves, total [s] |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, t] : tallies) {
    const double worst = t.check_over_solve.empty() ? 0.0
                                                    : *std::max_element(t.check_over_solve.begin(),
                                                                        t.check_over_solve.end());
    std::printf("| %s | %d | %d | %d | %d | %.2g | %.2g (%.2g) | %.3g | %.3g |\n", name.c_str(),
                t.plans, t.converged, t.other_root, t.parted, t.worst_reproduced,
                st::median(t.check_over_solve), worst, t.check_seconds, t.solve_seconds);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  const auto start = std::chrono::steady_clock::now();
  std::printf(
      "step_roots_study --count %d --spins %d --seed %llu --nlopt-count %d --time-budget %d; "
      "load %s\n\n",
      o.count, o.spins, static_cast<unsigned long long>(o.seed), o.nlopt_count, o.time_budget,
      st::loadAverage().c_str());
  std::map<std::string, Tally> random, spins;
  for (const rb::RandomCase& c : rb::randomSuite(o.seed, o.count)) {
    planEverywhere("random", c.index, c.problem, c.index < o.nlopt_count, o.time_budget, o.scheme,
                   &random);
  }
  std::mt19937_64 rng(o.seed);
  for (int i = 0; i < o.spins; ++i) {
    planEverywhere("spin", i, unstableSpin(&rng), i < o.nlopt_count, o.time_budget, o.scheme,
                   &spins);
  }
  std::printf("Random suite (seed %llu, %d problems)\n\n", static_cast<unsigned long long>(o.seed),
              o.count);
  print(random);
  std::printf("\nUnstable spins (seed %llu, %d problems, N = 400, 40-60 s)\n\n",
              static_cast<unsigned long long>(o.seed), o.spins);
  print(spins);
  std::printf("\nwall %.0f s; load %s\n", st::seconds(start), st::loadAverage().c_str());
  return 0;
}
