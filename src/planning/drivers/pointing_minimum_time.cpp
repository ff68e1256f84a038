#include "planning/drivers/pointing_minimum_time.hpp"

#include <cmath>
#include <vector>

#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/termination.hpp"
#include "planning/drivers/pointing.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

namespace {

/// One start twist's answer.
struct TwistStart {
  double twist = 0.0;
  PlanResult result;
};

/// The index of the converged start with the least T* (−1: none converged).
int leastDuration(const std::vector<TwistStart>& starts) {
  int kept = -1;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const PlanResult& r = starts[i].result;
    if (r.converged() && (kept < 0 || r.minimum_duration < starts[kept].result.minimum_duration)) {
      kept = static_cast<int>(i);
    }
  }
  return kept;
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

}  // namespace

PlanResult pointingMinimumTime(const PlanningProblem& problem, SolveContext& context,
                               const MinimumTimeRecipe& recipe) {
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  std::vector<TwistStart> starts;
  for (int i = 0; i < kPointingStartTwists && !context.stopReason(); ++i) {
    const double twist = std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI);
    TwistStart s{twist, recipe(endingAt(problem, pointingAttitude(problem.end_condition, twist)))};
    for (Attempt& a : s.result.attempts) a.start_detail.twist = twist;
    starts.push_back(std::move(s));
  }
  if (starts.empty()) {
    PlanResult none;
    none.termination = context.stopReason().value_or(Termination::NotConverged);
    frameMessage(&none, frames::PointingStarts{});
    return none;
  }
  const int kept = leastDuration(starts);
  PlanResult result = starts[kept >= 0 ? kept : static_cast<int>(starts.size()) - 1].result;
  result.attempts.clear();
  result.minimum_time.solves = 0;  // every start's free-time solves
  for (std::size_t i = 0; i < starts.size(); ++i) {
    result.minimum_time.solves += starts[i].result.minimum_time.solves;
    for (Attempt a : starts[i].result.attempts) {
      a.kept = a.kept && static_cast<int>(i) == kept;
      result.attempts.push_back(a);
    }
  }
  summarizePointing(problem, static_cast<int>(starts.size()), &result);
  frameMessage(&result, startsFrame(starts, kept));
  return result;
}

}  // namespace attitude_planner
