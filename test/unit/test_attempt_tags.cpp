// Every iteration a request reports names the attempt it belongs to (SolveContext::Scope): its
// stage and homotopy class as the trail (PlanResult::attempts) names them, so that a convergence
// plot (the action's feedback) tells one attempt from the next and the kept one from the others.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/solve_context.hpp"
#include "support/scene_problem.hpp"

namespace ap = attitude_planner;

namespace {

/// The iterations a request reported, in order.
std::vector<ap::IterationInfo> reported(const ap::PlanningProblem& problem, ap::PlanResult* r) {
  std::vector<ap::IterationInfo> infos;
  ap::SolverOptions options;
  options.on_iteration = [&](const ap::IterationInfo& info) {
    infos.push_back(info);
    return true;
  };
  *r = ap::planManeuver(problem, options);
  return infos;
}

using StageAndClass = std::pair<ap::AttemptStage, std::pair<bool, int>>;

StageAndClass keyOf(ap::AttemptStage stage, const ap::HomotopyClass& c) {
  return {stage, {c.long_way, c.extra_revolutions}};
}

/// Iterations per (stage, class), as the reports tag them and as the trail counts them.
std::map<StageAndClass, int> byTag(const std::vector<ap::IterationInfo>& infos) {
  std::map<StageAndClass, int> out;
  for (const ap::IterationInfo& i : infos) ++out[keyOf(i.attempt.stage, i.attempt.homotopy)];
  return out;
}
std::map<StageAndClass, int> byTrail(const std::vector<ap::Attempt>& trail) {
  std::map<StageAndClass, int> out;
  for (const ap::Attempt& a : trail) out[keyOf(a.stage, a.homotopy)] += a.iterations;
  return out;
}

}  // namespace

TEST(AttemptTags, ScopesNumberAttemptsAndNameNestedSolvesByTheirDriversStage) {
  // The rules themselves, on a bare context: numbers in the order attempts begin, the enclosing
  // tag back when a scope ends, a nested Solve renamed by its driver's stage, every nested
  // attempt renamed inside a ScopeStage scope, and the iterations a scope saw.
  ap::SolveContext context{ap::SolverOptions{}};
  EXPECT_EQ(context.currentAttempt().number, 0);
  const ap::HomotopyClass nearest{false, 0}, other{true, 1};
  {
    const ap::SolveContext::Scope probe(context, ap::AttemptStage::MinimumTimeProbe, nearest);
    EXPECT_EQ(context.currentAttempt().number, 1);
    {
      const ap::SolveContext::Scope solve(context, ap::AttemptStage::Solve, other);
      EXPECT_EQ(context.currentAttempt().number, 2);
      EXPECT_EQ(context.currentAttempt().stage, ap::AttemptStage::MinimumTimeProbe);
      EXPECT_TRUE(context.currentAttempt().homotopy.long_way);
      context.reportIteration({});
      EXPECT_EQ(solve.iterations(), 1);
    }
    {
      const ap::SolveContext::Scope own(context, ap::AttemptStage::Constrained, nearest);
      EXPECT_EQ(context.currentAttempt().number, 3);
      EXPECT_EQ(context.currentAttempt().stage, ap::AttemptStage::Constrained);
    }
    EXPECT_EQ(context.currentAttempt().number, 1);
    EXPECT_EQ(probe.iterations(), 1);
  }
  {
    const ap::SolveContext::Scope margin(context, ap::AttemptStage::MinimumTimeMargin, nearest,
                                         ap::SolveContext::Nested::ScopeStage);
    const ap::SolveContext::Scope inner(context, ap::AttemptStage::ClassSurvey, other);
    const ap::SolveContext::Scope deeper(context, ap::AttemptStage::Constrained, other);
    EXPECT_EQ(context.currentAttempt().number, 6);
    EXPECT_EQ(context.currentAttempt().stage, ap::AttemptStage::MinimumTimeMargin);
  }
  // Outside every scope a Solve is the request's own, and ScopeStage no longer holds.
  const ap::SolveContext::Scope top(context, ap::AttemptStage::ClassRefine, nearest);
  EXPECT_EQ(context.currentAttempt().stage, ap::AttemptStage::ClassRefine);
  EXPECT_EQ(context.iterations(), 1);
}

TEST(AttemptTags, AClassSurveysIterationsAreTaggedWithTheTrailsStagesAndClasses) {
  // Near a half turn the survey solves several classes and refines the cheapest: each report
  // names its attempt, and the reports of each stage and class add up to the trail's count.
  ap::PlanningProblem p = ap::test_support::sceneProblem("rest_to_rest", 64);
  ap::PlanResult r;
  const std::vector<ap::IterationInfo> infos = reported(p, &r);
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_FALSE(infos.empty());
  EXPECT_TRUE(std::all_of(infos.begin(), infos.end(),
                          [](const ap::IterationInfo& i) { return i.attempt.number > 0; }));
  EXPECT_EQ(byTag(infos), byTrail(r.attempts));
  EXPECT_EQ(static_cast<int>(infos.size()), r.iterations);
  const auto surveys = std::count_if(infos.begin(), infos.end(), [](const ap::IterationInfo& i) {
    return i.attempt.stage == ap::AttemptStage::ClassSurvey;
  });
  EXPECT_GT(surveys, 0) << r.message;
}

TEST(AttemptTags, AConstrainedRequestsAttemptsCountTheIterationsTheyReported) {
  // Under node constraints the trail's per-attempt counts (the interior point's levels,
  // formulation retries and two-stage retry, read from the context) are the reports of each
  // stage and class, and they add up to the request's count: every iteration a solver counts is
  // reported (the elastic penalty raise included), none is summed from results.
  for (const char* scene : {"torque_limited", "rate_limited", "sun_keep_out", "leo_slew_limited"}) {
    SCOPED_TRACE(scene);
    const ap::PlanningProblem p = ap::test_support::sceneProblem(scene, 64);
    ap::PlanResult r;
    const std::vector<ap::IterationInfo> infos = reported(p, &r);
    ASSERT_FALSE(infos.empty()) << r.message;
    EXPECT_TRUE(std::any_of(
        r.attempts.begin(), r.attempts.end(),
        [](const ap::Attempt& a) { return a.formulation != ap::Formulation::Unconstrained; }))
        << "the interior point ran: " << r.message;
    EXPECT_EQ(byTag(infos), byTrail(r.attempts)) << r.message;
    EXPECT_EQ(static_cast<int>(infos.size()), r.iterations);
  }
}

TEST(AttemptTags, AConstrainedRequestsTrailIsTheContextsTrail) {
  // Newton's walk, then the interior point from its optimum: the result's trail is what the
  // request's context recorded, attempt for attempt, with one kept attempt in both (the context
  // names an attempt as its scopes do and keeps one mark).
  for (const char* scene : {"torque_limited", "rate_limited", "sun_keep_out", "leo_slew_limited"}) {
    SCOPED_TRACE(scene);
    const ap::PlanningProblem p = ap::test_support::sceneProblem(scene, 64);
    const ap::SolverOptions options;
    ap::SolveContext context(options);
    const ap::PlanResult r = ap::planAtResolution(p, options, context);
    ASSERT_TRUE(std::any_of(
        r.attempts.begin(), r.attempts.end(),
        [](const ap::Attempt& a) { return a.formulation != ap::Formulation::Unconstrained; }))
        << "the interior point ran: " << r.message;
    const std::vector<ap::Attempt>& trail = context.attempts();
    ASSERT_EQ(trail.size(), r.attempts.size()) << r.message;
    for (std::size_t i = 0; i < trail.size(); ++i) {
      SCOPED_TRACE(i);
      const ap::Attempt &a = r.attempts[i], &b = trail[i];
      EXPECT_EQ(a.stage, b.stage);
      EXPECT_EQ(a.start, b.start);
      EXPECT_EQ(a.formulation, b.formulation);
      EXPECT_TRUE(ap::sameHomotopyClass(a.homotopy, b.homotopy));
      EXPECT_EQ(a.steps, b.steps);
      EXPECT_EQ(a.termination, b.termination);
      EXPECT_EQ(a.iterations, b.iterations);
      EXPECT_EQ(a.kept, b.kept);
    }
    const auto kept = [](const std::vector<ap::Attempt>& t) {
      return std::count_if(t.begin(), t.end(), [](const ap::Attempt& a) { return a.kept; });
    };
    EXPECT_EQ(kept(r.attempts), 1);
    EXPECT_EQ(kept(trail), 1);
  }
}

TEST(AttemptTags, TheKeptAttemptOfAConstrainedRequestIsAmongTheTagsReported) {
  // Under a torque bound the interior point follows Newton's optimum: its iterations are tagged
  // `constrained`, and the kept attempt's stage and class were reported.
  const ap::PlanningProblem p = ap::test_support::sceneProblem("torque_limited", 64);
  ap::PlanResult r;
  const std::vector<ap::IterationInfo> infos = reported(p, &r);
  ASSERT_TRUE(r.converged()) << r.message;
  const auto kept = std::find_if(r.attempts.begin(), r.attempts.end(),
                                 [](const ap::Attempt& a) { return a.kept; });
  ASSERT_NE(kept, r.attempts.end());
  const std::map<StageAndClass, int> tags = byTag(infos);
  EXPECT_EQ(tags.count(keyOf(kept->stage, kept->homotopy)), 1u) << r.message;
  EXPECT_TRUE(std::any_of(infos.begin(), infos.end(), [](const ap::IterationInfo& i) {
    return i.attempt.stage == ap::AttemptStage::Constrained;
  }));
}

TEST(AttemptTags, ASpinningMinimumTimeRequestsClassOptimaRunInTheRequestsContext) {
  // The unconstrained optima of the four start classes that start a spinning minimum-time request
  // are solved in the request's context: their iterations are reported (tagged as the start of a
  // minimum_time_solve, in their class; the free-time solves themselves are all in the request's
  // class), and a cancel at the first report stops the request there instead of after four
  // Newton solves nobody could stop.
  ap::PlanningProblem p = ap::test_support::sceneProblem("min_time_sphere", 32);
  p.initial_velocity = ap::Vector3(0.2, 0.0, 0.0);
  ap::PlanResult r;
  const std::vector<ap::IterationInfo> infos = reported(p, &r);
  ASSERT_TRUE(r.converged()) << r.message;
  std::set<std::pair<bool, int>> classes;
  for (const ap::IterationInfo& i : infos) {
    if (i.attempt.stage == ap::AttemptStage::MinimumTimeSolve) {
      classes.insert({i.attempt.homotopy.long_way, i.attempt.homotopy.extra_revolutions});
    }
  }
  const std::set<std::pair<bool, int>> four = {{false, 0}, {true, 0}, {false, 1}, {true, 1}};
  EXPECT_EQ(classes, four);
  // The request's count is the context's: every iteration reported, the class optima's too
  // (before, the drivers' sums counted 30 of 1,542 on a seeded minimum-time case).
  EXPECT_EQ(static_cast<int>(infos.size()), r.iterations);
  int in_trail = 0;
  for (const ap::Attempt& a : r.attempts) in_trail += a.iterations;
  EXPECT_GT(r.iterations, in_trail) << "the class optima are counted, not in the trail";

  std::vector<ap::IterationInfo> until_cancel;
  ap::SolverOptions options;
  options.on_iteration = [&](const ap::IterationInfo& info) {
    until_cancel.push_back(info);
    return false;  // cancel at once
  };
  const ap::PlanResult cancelled = ap::planManeuver(p, options);
  EXPECT_EQ(cancelled.termination, ap::Termination::Cancelled) << cancelled.message;
  ASSERT_FALSE(until_cancel.empty());
  EXPECT_EQ(until_cancel.front().attempt.stage, ap::AttemptStage::MinimumTimeSolve);
  EXPECT_EQ(until_cancel.size(), 1u);
}
