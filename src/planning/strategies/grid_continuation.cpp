#include "planning/strategies/grid_continuation.hpp"

namespace attitude_planner {

PlanningProblem coarserLevel(const PlanningProblem& problem, const GridLevelRule& rule) {
  PlanningProblem coarse = problem;
  coarse.steps = std::max(rule.coarsest_steps, problem.steps / rule.coarsening_factor);
  return coarse;
}

bool usesCoarserLevel(const PlanningProblem& problem, const GridLevelRule& rule) {
  return problem.steps > rule.coarsest_steps &&
         (!rule.level_helps || rule.level_helps(coarserLevel(problem, rule)));
}

std::vector<PlanningProblem> gridLevels(const PlanningProblem& problem, const GridLevelRule& rule) {
  std::vector<PlanningProblem> levels{problem};
  while (usesCoarserLevel(levels.back(), rule)) levels.push_back(coarserLevel(levels.back(), rule));
  std::reverse(levels.begin(), levels.end());
  return levels;
}

}  // namespace attitude_planner
