#include "planning/drivers/pointing_minimum_time.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/termination.hpp"
#include "planning/drivers/pointing.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

namespace {

/// One start twist's answer and its kept attempt in the context's trail (none: no solve, or no
/// attempt of its own kept).
struct TwistStart {
  double twist = 0.0;
  PlanResult result;
  std::optional<std::size_t> kept_attempt;
};

/// The index of the converged start with the least T* (on `steps` steps where given; −1: none).
int leastDuration(const std::vector<TwistStart>& starts, int steps = 0) {
  int kept = -1;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const PlanResult& r = starts[i].result;
    const bool on_grid = steps == 0 || r.maneuver.steps() == steps;
    if (r.converged() && on_grid &&
        (kept < 0 || r.minimum_duration < starts[kept].result.minimum_duration)) {
      kept = static_cast<int>(i);
    }
  }
  return kept;
}

/// The last start with a plan on `steps` steps (else the last start): the answer where none
/// converged.
int lastWithPlan(const std::vector<TwistStart>& starts, int steps) {
  for (int i = static_cast<int>(starts.size()) - 1; i >= 0; --i) {
    if (starts[i].result.maneuver.steps() == steps) return i;
  }
  return static_cast<int>(starts.size()) - 1;
}

/// The pointing summary of a plan that reached R_N by its own twist (kept where the recipe's
/// solver filled it: the free-time answer carries ∂L/∂ψ).
void summarizePointing(const PlanningProblem& problem, int starts, PlanResult* r) {
  if (r->maneuver.attitude.empty()) return;
  summarizePointingEnd(r->maneuver.attitude.back(), problem.end_condition, &r->pointing);
  r->pointing.starts = starts;
}

/// The frame of the message: each start's twist and T* (or termination), the one kept.
frames::PointingStarts startsFrame(const std::vector<TwistStart>& starts, int kept) {
  frames::PointingStarts frame;
  frame.kept = kept;
  for (const TwistStart& s : starts) {
    frame.starts.push_back({s.twist, s.result.termination, s.result.minimum_duration});
  }
  return frame;
}

/// The first cone whose node bound R_N at `twist` violates (empty: none): no plan ends there, so
/// that start twist is not posed (its fixed-attitude request would be refused).
std::string coneAtEnd(const PlanningProblem& problem, double twist) {
  const Matrix3 R_N = pointingAttitude(problem.end_condition, twist);
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.isCone() && coneMargin(c, R_N) - c.margin < 0.0) {
      return "R_N at this start twist violates " + describeConstraint(c);
    }
  }
  return "";
}

/// One start twist's answer: the recipe at R_N there (its attempts in the context tagged with
/// the twist), or, where a cone excludes that R_N, infeasible without a solve.
TwistStart startAt(const PlanningProblem& problem, double twist, SolveContext& context,
                   const MinimumTimeRecipe& recipe) {
  TwistStart s{twist, {}, std::nullopt};
  const std::string excluded = coneAtEnd(problem, twist);
  if (!excluded.empty()) {
    s.result.termination = Termination::Infeasible;  // no solve: the trail shows none
    return s;
  }
  const std::size_t first = context.attempts().size();
  s.result = recipe(endingAt(problem, pointingAttitude(problem.end_condition, twist)));
  context.posedAtTwist(first, twist);
  const std::optional<std::size_t> kept = context.keptAttempt();
  if (kept && *kept >= first) s.kept_attempt = kept;
  return s;
}

/// The survey grid of a minimum-time pointing request: N / kSurveyCoarsening, at least
/// kSurveyLeastSteps; 0 where that is not below N (no survey: the start twists on N).
constexpr int kSurveyCoarsening = 4, kSurveyLeastSteps = 16;
int surveySteps(const PlanningProblem& problem) {
  const int steps = std::max(kSurveyLeastSteps, problem.steps / kSurveyCoarsening);
  return steps < problem.steps ? steps : 0;
}

/// Every start twist (ψ₀ + 2πi/kPointingStartTwists) solved by `solve`; stops at a cancel or the
/// deadline.
template <typename Solve>
std::vector<TwistStart> overStartTwists(const PlanningProblem& problem, SolveContext& context,
                                        const Solve& solve) {
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  std::vector<TwistStart> starts;
  for (int i = 0; i < kPointingStartTwists && !context.stopReason(); ++i) {
    starts.push_back(
        solve(std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI)));
  }
  return starts;
}

}  // namespace

PlanResult pointingMinimumTime(const PlanningProblem& problem, SolveContext& context,
                               const MinimumTimeRecipe& recipe) {
  const auto posedAt = [&context, &recipe](const PlanningProblem& on) {
    return [at = &on, &context, &recipe](double twist) {
      return startAt(*at, twist, context, recipe);
    };
  };
  const std::size_t first = context.attempts().size();
  std::vector<TwistStart> starts;
  if (const int survey = surveySteps(problem)) {
    // The start twists on a coarse grid, then the recipe on N at the least T*'s twist only: the
    // coarse answers rank the basins at a quarter of the cost (measured on the seeded requests
    // of docs/results/pointing_minimum_time.md).
    PlanningProblem coarse = problem;
    coarse.steps = survey;
    starts = overStartTwists(coarse, context, posedAt(coarse));
    const int best = leastDuration(starts);
    if (best >= 0 && !context.stopReason()) {
      const Matrix3& R_N = starts[best].result.maneuver.attitude.back();
      starts.push_back(startAt(problem, twistOf(R_N, problem.end_condition), context, recipe));
    }
  }
  if (leastDuration(starts, problem.steps) < 0 && !context.stopReason()) {
    // No survey, or its answer did not carry to N: every start twist on N.
    std::vector<TwistStart> on_grid = overStartTwists(problem, context, posedAt(problem));
    starts.insert(starts.end(), on_grid.begin(), on_grid.end());
  }
  if (starts.empty()) {
    PlanResult none;
    none.termination = context.stopReason().value_or(Termination::NotConverged);
    frameMessage(&none, frames::PointingStarts{});
    return none;
  }
  const int kept = leastDuration(starts, problem.steps);
  PlanResult result = starts[kept >= 0 ? kept : lastWithPlan(starts, problem.steps)].result;
  result.minimum_time.solves = 0;  // every start's free-time solves
  for (const TwistStart& s : starts) result.minimum_time.solves += s.result.minimum_time.solves;
  context.restoreKept(kept >= 0 ? starts[kept].kept_attempt : std::nullopt);
  result.attempts = context.attemptsFrom(first);
  summarizePointing(problem, static_cast<int>(starts.size()), &result);
  frameMessage(&result, startsFrame(starts, kept));
  return result;
}

}  // namespace attitude_planner
