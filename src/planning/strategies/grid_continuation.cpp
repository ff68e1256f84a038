#include "planning/strategies/grid_continuation.hpp"

#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

PlanningProblem coarserLevel(const PlanningProblem& problem, const GridLevelRule& rule) {
  PlanningProblem coarse = problem;
  coarse.steps = std::max(rule.coarsest_steps, problem.steps / rule.coarsening_factor);
  return coarse;
}

bool usesCoarserLevel(const PlanningProblem& problem, const GridLevelRule& rule) {
  return problem.steps > rule.coarsest_steps && problem.steps > rule.direct_up_to &&
         (!rule.level_helps || rule.level_helps(coarserLevel(problem, rule)));
}

std::vector<PlanningProblem> gridLevels(const PlanningProblem& problem, const GridLevelRule& rule) {
  std::vector<PlanningProblem> levels{problem};
  while (usesCoarserLevel(levels.back(), rule)) levels.push_back(coarserLevel(levels.back(), rule));
  std::reverse(levels.begin(), levels.end());
  return levels;
}

void describeContinuation(const ContinuationRecord& record, PlanResult* finest) {
  const std::size_t count = record.levels.size();
  if (count < 2) return;
  const LevelEnd& below = record.levels[count - 2];
  if (record.stop) {
    frameMessage(finest,
                 frames::CarriedOverAfterStop{record.stop->termination, record.stop->level.steps,
                                              record.levels.back().steps, false});
  } else {
    addNote(finest, notes::CoarserLevel{below.steps, below.termination});
  }
}

}  // namespace attitude_planner
