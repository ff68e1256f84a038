// Which plan a Newton walk keeps, with each plan's check (planInconsistency) run only where the
// choice depends on it. The rule is the walk's, in the order the attempts ended: the first plan on
// the requested grid, replaced by each later converged plan that is cheaper by more than `tie`
// (relative), or by any converged plan while the one kept has not converged. A plan converges
// when its solver's test and its check both pass; the check (a step-by-step replay of the plan,
// as dear as the open-loop replay) is deferred: the plan the rule would keep if every unchecked
// plan passed is checked, and if every other converged plan before it is costlier by more than
// `tie`, it is the rule's answer whatever their checks say, so theirs are never run.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

namespace attitude_planner {

/// Where a plan stands in the walk's choice.
enum class PlanStanding {
  NotConverged,  ///< its solver did not converge, or its check failed
  Unchecked,     ///< its solver converged; its check has not run
  Checked,       ///< its solver converged and its check passed
};

/// The walk's rule over `standing` (an Unchecked plan counted as converged): the index kept.
/// `cost` and `standing` have one entry per plan, in attempt order, at least one.
inline std::size_t keptByTheWalksRule(const std::vector<double>& cost,
                                      const std::vector<PlanStanding>& standing, double tie) {
  const auto converged = [&](std::size_t i) { return standing[i] != PlanStanding::NotConverged; };
  std::size_t kept = 0;
  for (std::size_t i = 1; i < cost.size(); ++i) {
    if (converged(i) && (!converged(kept) || cost[i] < cost[kept] * (1 - tie))) kept = i;
  }
  return kept;
}

/// The walk's rule with the checks run on demand: `check(i)` runs plan i's check (once per plan)
/// and says whether it passed; `standing` is updated (a failed check: NotConverged). The answer
/// is keptByTheWalksRule over the standings every check would give, and the plan it names is
/// Checked unless no plan converged (then the first plan, as the rule keeps it).
inline std::size_t keptWithChecksOnDemand(const std::vector<double>& cost,
                                          std::vector<PlanStanding>* standing, double tie,
                                          const std::function<bool(std::size_t)>& check) {
  std::vector<PlanStanding>& s = *standing;
  const auto run = [&](std::size_t i) {
    s[i] = check(i) ? PlanStanding::Checked : PlanStanding::NotConverged;
  };
  for (;;) {
    const std::size_t kept = keptByTheWalksRule(cost, s, tie);
    if (s[kept] == PlanStanding::NotConverged) return kept;  // no plan converged
    if (s[kept] == PlanStanding::Unchecked) run(kept);
    if (s[kept] == PlanStanding::NotConverged) continue;  // failed: the rule chooses again
    // Every converged plan before it costlier by more than the tie: whatever their checks say,
    // the rule reaches it and nothing after it is cheaper (those the rule would take are before).
    bool beats_every_earlier = true;
    for (std::size_t j = 0; j < kept; ++j) {
      if (s[j] != PlanStanding::NotConverged && !(cost[kept] < cost[j] * (1 - tie))) {
        beats_every_earlier = false;
      }
    }
    if (beats_every_earlier) return kept;
    // Costs within the tie of one another (rare): every check decides, as in the walk itself.
    for (std::size_t j = 0; j < s.size(); ++j) {
      if (s[j] == PlanStanding::Unchecked) run(j);
    }
    return keptByTheWalksRule(cost, s, tie);
  }
}

}  // namespace attitude_planner
