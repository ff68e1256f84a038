// The Newton solver's structured trail: every attempt recorded with its stage, start,
// class, termination, iterations and cost; one kept; iterations numbered across attempts; the
// extremal structured; a cancel from another thread ends a large solve promptly; and the grid
// continuation, which takes any solver as a callable.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <map>
#include <optional>
#include <thread>
#include <tuple>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "planning/strategies/grid_continuation.hpp"
#include "planning/strategies/staged_continuation.hpp"
#include "support/robustness_cases.hpp"
#include "support/scene_problem.hpp"

using namespace attitude_planner;

namespace {

PlanningProblem restToRest(double angle, int N) {
  PlanningProblem p;
  p.inertia = robustness::seedInertia();
  p.duration = 12.8;
  p.steps = N;
  p.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), angle);
  p.allow_nonphysical_inertia = true;  // the seed's J violates J1 + J2 >= J3
  return p;
}

int keptCount(const PlanResult& r) {
  return static_cast<int>(
      std::count_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; }));
}

}  // namespace

TEST(NewtonTrail, OneAttemptForARequestThatNamesItsClass) {
  PlanningProblem p = restToRest(M_PI / 3, 128);
  p.direction = RotationDirection::LongWay;
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_EQ(r.attempts.size(), 1u);
  const Attempt& a = r.attempts[0];
  EXPECT_EQ(a.stage, AttemptStage::Solve);
  EXPECT_EQ(a.start, AttemptStart::CoarseLevel);  // N = 128 goes through N = 32
  EXPECT_EQ(a.formulation, Formulation::Unconstrained);
  EXPECT_EQ(a.globalization, Globalization::TrustRegion);
  EXPECT_TRUE(a.homotopy.long_way);
  EXPECT_EQ(a.homotopy.extra_revolutions, 0);
  EXPECT_EQ(a.steps, 128);
  EXPECT_EQ(a.termination, Termination::Converged);
  EXPECT_EQ(a.iterations, r.iterations);
  EXPECT_DOUBLE_EQ(a.cost, r.cost);
  EXPECT_TRUE(a.kept);
  // The structured extremal, and the string rendered from it as before.
  EXPECT_TRUE(r.extremal_summary.known);
  EXPECT_TRUE(r.extremal_summary.homotopy.long_way);
  EXPECT_NEAR(r.extremal_summary.angle, 2 * M_PI - M_PI / 3, 0.3);  // R_1 to R_{N-1}
  EXPECT_NEAR(std::abs(r.extremal_summary.axis.x()), 1.0, 1e-9);
  EXPECT_TRUE(r.extremal_summary.others.empty());
  EXPECT_EQ(r.extremal.rfind("second-nearest lift", 0), 0u) << r.extremal;
  EXPECT_EQ(r.extremal, describeExtremal(r.extremal_summary));
}

// A request that leaves its class free: every class surveyed on the coarsest grid (N = 16 of
// 16, 32, 128), then its own class and those within 50 % of the cheapest survey cost refined on
// the requested grid; one kept, the others with their costs in the structured extremal.
TEST(NewtonTrail, AFreeClassIsSurveyedThenTheCheapestRefined) {
  const PlanResult r = planManeuver(restToRest(M_PI / 3, 128));
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_GE(r.attempts.size(), 5u) << r.extremal;
  for (int i = 0; i < 4; ++i) {
    const Attempt& a = r.attempts[i];
    EXPECT_EQ(a.stage, AttemptStage::ClassSurvey) << i;
    EXPECT_EQ(a.steps, 16) << i;
    EXPECT_EQ(a.termination, Termination::Converged) << i;
    EXPECT_TRUE(std::isfinite(a.cost) && a.cost > 0) << i;
    EXPECT_FALSE(a.kept) << i;  // a survey is on the coarse grid: never the plan
  }
  // The four classes, each once.
  EXPECT_FALSE(r.attempts[0].homotopy.long_way);
  EXPECT_EQ(r.attempts[0].homotopy.extra_revolutions, 0);
  EXPECT_TRUE(r.attempts[1].homotopy.long_way);
  EXPECT_EQ(r.attempts[1].homotopy.extra_revolutions, 0);
  EXPECT_FALSE(r.attempts[2].homotopy.long_way);
  EXPECT_EQ(r.attempts[2].homotopy.extra_revolutions, 1);
  EXPECT_TRUE(r.attempts[3].homotopy.long_way);
  EXPECT_EQ(r.attempts[3].homotopy.extra_revolutions, 1);
  double cheapest_survey = r.attempts[0].cost;
  for (int i = 1; i < 4; ++i) cheapest_survey = std::min(cheapest_survey, r.attempts[i].cost);
  int total = 0;
  for (const Attempt& a : r.attempts) total += a.iterations;
  EXPECT_EQ(total, r.iterations);
  EXPECT_EQ(keptCount(r), 1);
  for (std::size_t i = 4; i < r.attempts.size(); ++i) {
    const Attempt& a = r.attempts[i];
    EXPECT_EQ(a.stage, AttemptStage::ClassRefine) << i;
    EXPECT_EQ(a.start, AttemptStart::CoarseLevel) << i;
    EXPECT_EQ(a.steps, 128) << i;
    EXPECT_EQ(a.termination, Termination::Converged) << i;
    EXPECT_GE(a.cost, r.cost) << i;
    if (a.kept) EXPECT_DOUBLE_EQ(a.cost, r.cost);
    // Refined: the request's class (the nearest) and the classes near the cheapest survey cost.
    const auto surveyed = std::find_if(r.attempts.begin(), r.attempts.begin() + 4, [&](auto& s) {
      return s.homotopy.long_way == a.homotopy.long_way &&
             s.homotopy.extra_revolutions == a.homotopy.extra_revolutions;
    });
    ASSERT_NE(surveyed, r.attempts.begin() + 4);
    const bool nearest = !a.homotopy.long_way && a.homotopy.extra_revolutions == 0;
    EXPECT_TRUE(nearest || surveyed->cost <= 1.5 * cheapest_survey) << i;
  }
  // π/3 rest to rest: the nearest lift is the cheapest.
  EXPECT_FALSE(r.extremal_summary.homotopy.long_way);
  EXPECT_EQ(r.extremal_summary.homotopy.extra_revolutions, 0);
  EXPECT_EQ(r.extremal_summary.others.size() + 1, r.attempts.size());
  EXPECT_EQ(r.extremal.rfind("nearest lift: ", 0), 0u) << r.extremal;
  EXPECT_NE(r.extremal.find("surveyed at N = 16"), std::string::npos) << r.extremal;
  EXPECT_EQ(r.extremal, describeExtremal(r.extremal_summary));
}

TEST(NewtonTrail, NearPiTheSurveySolvesBothWaysWithTheirCostsAndOneIsKept) {
  const PlanResult r = planManeuver(restToRest(M_PI - 0.05, 64));
  ASSERT_TRUE(r.converged()) << r.message();
  // Surveyed on N = 16; both ways are within the margin of each other: both refined to N = 64.
  ASSERT_GE(r.attempts.size(), 6u) << r.extremal;
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r.attempts[i].stage, AttemptStage::ClassSurvey);
    EXPECT_EQ(r.attempts[i].steps, 16);
    EXPECT_EQ(r.attempts[i].termination, Termination::Converged);
    EXPECT_TRUE(std::isfinite(r.attempts[i].cost) && r.attempts[i].cost > 0);
  }
  EXPECT_FALSE(r.attempts[0].homotopy.long_way);
  EXPECT_TRUE(r.attempts[1].homotopy.long_way);
  const auto refined = [&r](bool long_way) {
    return std::find_if(r.attempts.begin(), r.attempts.end(), [&](const Attempt& a) {
      return a.stage == AttemptStage::ClassRefine && a.homotopy.long_way == long_way &&
             a.homotopy.extra_revolutions == 0;
    });
  };
  ASSERT_NE(refined(false), r.attempts.end()) << r.extremal;
  ASSERT_NE(refined(true), r.attempts.end()) << r.extremal;
  EXPECT_EQ(keptCount(r), 1);
  const Attempt& kept =
      *std::find_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; });
  EXPECT_DOUBLE_EQ(kept.cost, r.cost);
  EXPECT_EQ(kept.steps, 64);
  for (const Attempt& a : r.attempts) {
    if (a.steps == 64 && a.termination == Termination::Converged) EXPECT_LE(kept.cost, a.cost);
  }
  EXPECT_EQ(r.extremal_summary.homotopy.long_way, kept.homotopy.long_way);
  ASSERT_EQ(r.extremal_summary.others.size() + 1, r.attempts.size());
  for (const Attempt& a : r.extremal_summary.others) EXPECT_TRUE(std::isfinite(a.cost));
}

TEST(NewtonTrail, AStalledSpinningRequestRecordsItsRateContinuationAndNumbersIterations) {
  // Spinning at the end, two iterations per level: every class's survey (N = 16) stalls at its
  // limit, so the request's class is solved whole (it stalls too), then the continuation in the
  // boundary rates and the coasting start follow in that class, each recorded.
  PlanningProblem p = restToRest(M_PI / 6, 64);
  p.final_velocity = Vector3(0.3, 0.2, 0.3);
  SolverOptions options;
  options.max_iterations = 2;
  std::vector<int> numbers;
  options.on_iteration = [&](const IterationInfo& info) {
    numbers.push_back(info.iteration);
    return true;
  };
  const PlanResult r = planManeuver(p, options);
  ASSERT_GE(r.attempts.size(), 7u) << r.message();
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r.attempts[i].stage, AttemptStage::ClassSurvey) << i;
    EXPECT_EQ(r.attempts[i].termination, Termination::NotConverged) << i;
  }
  EXPECT_EQ(r.attempts[4].stage, AttemptStage::Solve);
  EXPECT_EQ(r.attempts[4].termination, Termination::NotConverged);
  EXPECT_EQ(r.attempts[5].stage, AttemptStage::RateContinuation);
  EXPECT_EQ(r.attempts[5].start, AttemptStart::PreviousAttempt);
  EXPECT_FALSE(r.attempts[5].homotopy.long_way);  // the request's class
  EXPECT_GT(r.attempts[5].iterations, 0);
  EXPECT_EQ(r.attempts[6].stage, AttemptStage::CoastingRetry);
  EXPECT_EQ(r.attempts[6].start, AttemptStart::Coasting);
  EXPECT_EQ(keptCount(r), 1);
  int total = 0;
  for (const Attempt& a : r.attempts) total += a.iterations;
  EXPECT_EQ(total, r.iterations);
  // Every iteration of every attempt and level is reported, numbered 1..n without a gap.
  ASSERT_EQ(static_cast<int>(numbers.size()), r.iterations);
  for (std::size_t i = 0; i < numbers.size(); ++i) EXPECT_EQ(numbers[i], static_cast<int>(i) + 1);
}

TEST(NewtonTrail, AStalledSpinningRequestAllowedNoRateStagesGoesToTheCoastingStartAtOnce) {
  // The stalled request above with rate_continuation_max_stages = 0 (as the probes below a
  // minimum-time T* ask, drivers/minimum_time.cpp): the continuation in the boundary rates is not
  // tried, no attempt of it is recorded and none of its iterations are counted; the coasting
  // start follows the request's class solve. (A library that rejects 0 throws here.)
  PlanningProblem p = restToRest(M_PI / 6, 64);
  p.final_velocity = Vector3(0.3, 0.2, 0.3);
  SolverOptions options;
  options.max_iterations = 2;
  options.advanced.newton.rate_continuation_max_stages = 0;
  const PlanResult r = planManeuver(p, options);
  ASSERT_GE(r.attempts.size(), 6u) << r.message();
  EXPECT_EQ(r.attempts[4].stage, AttemptStage::Solve);
  EXPECT_EQ(r.attempts[5].stage, AttemptStage::CoastingRetry);
  EXPECT_TRUE(std::none_of(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) {
    return a.stage == AttemptStage::RateContinuation;
  }));
  int total = 0;
  for (const Attempt& a : r.attempts) total += a.iterations;
  EXPECT_EQ(total, r.iterations);
}

TEST(NewtonTrail, ACancelFromAnotherThreadEndsALargeSolveCancelled) {
  const int N = 100000;
  std::atomic<bool> cancel{false};
  std::promise<void> first_iteration, flag_set;
  std::future<void> flag_set_seen = flag_set.get_future();
  std::thread canceller([&, started = first_iteration.get_future()]() mutable {
    started.wait();
    cancel = true;
    flag_set.set_value();
  });
  SolverOptions options;
  options.cancel_requested = &cancel;
  bool first = true;
  options.on_iteration = [&](const IterationInfo&) {
    if (first) {  // hand over to the other thread and wait until it has set the flag
      first = false;
      first_iteration.set_value();
      flag_set_seen.wait();
    }
    return true;
  };
  const PlanResult r = planManeuver(restToRest(M_PI / 3, N), options);
  canceller.join();
  EXPECT_EQ(r.termination, Termination::Cancelled) << r.message();
  EXPECT_EQ(r.maneuver.steps(), N);  // the last iterate, carried over to the requested grid
  ASSERT_FALSE(r.attempts.empty());
  EXPECT_EQ(r.attempts.back().termination, Termination::Cancelled);
}

// The continuation with a stand-in solver: levels coarsest first, each started from the one
// below, a coarse level solved to the floor tolerance, and a stop carried up without iterating.
TEST(GridContinuation, LevelsRunCoarsestFirstAndHandOnTheirIterates) {
  PlanningProblem p = restToRest(1.0, 1024);
  GridLevelRule rule;  // 16, ×4
  SolverOptions options;
  SolveContext context(options);
  std::vector<int> seen;
  const LevelSolver<std::vector<int>> solve = [&](const LevelRequest<std::vector<int>>& r,
                                                  std::vector<int>* out) {
    seen.push_back(r.problem.steps);
    if (seen.size() > 1) {
      EXPECT_NE(r.coarse, nullptr);
      if (r.coarse) {
        EXPECT_EQ(r.coarse->back(), seen[seen.size() - 2]);
      }
    }
    EXPECT_EQ(r.tolerance, r.finest ? 1e-10 : 1e-6);
    EXPECT_EQ(out == nullptr, r.finest);
    if (out) *out = {r.problem.steps};
    PlanResult result;
    result.termination = Termination::Converged;
    result.iterations = 3;
    for (int i = 0; i < 3; ++i) context.reportIteration(IterationInfo{});  // as solvers do
    result.levels.push_back({r.problem.steps, 3, Termination::Converged, 0, 0, "converged"});
    return result;
  };
  const PlanResult r = solveByGridContinuation(p, context, rule, 1e-10, solve);
  EXPECT_EQ(seen, (std::vector<int>{16, 64, 256, 1024}));
  EXPECT_EQ(r.iterations, 12);
  EXPECT_EQ(r.levels.size(), 4u);
  EXPECT_TRUE(r.converged());
  // A level that helps not: no coarser level at all.
  rule.level_helps = [](const PlanningProblem&) { return false; };
  EXPECT_EQ(gridLevels(p, rule).size(), 1u);
}

namespace {

/// A stand-in level solver: each level ends as `ends` says for its N (converged otherwise) after
/// 3 iterations, reported to the request's context as solvers do, and hands on {N}; `seen`
/// records (N, whether it started from a coarse iterate, whether it only replayed).
struct StandIn {
  std::map<int, Termination> ends;
  std::vector<std::tuple<int, bool, bool>> seen;

  LevelSolver<std::vector<int>> solver(SolveContext& context) {
    return [this, &context](const LevelRequest<std::vector<int>>& r, std::vector<int>* out) {
      seen.emplace_back(r.problem.steps, r.coarse != nullptr, r.replay_only);
      if (out) *out = {r.problem.steps};
      PlanResult result;
      const auto end = ends.find(r.problem.steps);
      result.termination = end == ends.end() ? Termination::Converged : end->second;
      result.iterations = r.replay_only ? 0 : 3;
      for (int i = 0; i < result.iterations; ++i) context.reportIteration(IterationInfo{});
      result.clauses = {clauses::Reason{"N = " + std::to_string(r.problem.steps)}};
      result.levels.push_back({r.problem.steps, result.iterations, result.termination, 0, 0, ""});
      return result;
    };
  }
};

}  // namespace

// The interior point's rule: levels 4× coarser only above its coarsest grid (N = 8192: 128, 512,
// 2048, 8192; at or below the coarsest grid no coarser level).
TEST(GridContinuation, ALevelAtOrBelowDirectUpToHasNoCoarserLevel) {
  GridLevelRule rule;
  rule.direct_up_to = 256;
  std::vector<int> steps;
  for (const PlanningProblem& l : gridLevels(restToRest(1.0, 8192), rule)) steps.push_back(l.steps);
  EXPECT_EQ(steps, (std::vector<int>{128, 512, 2048, 8192}));
  EXPECT_EQ(gridLevels(restToRest(1.0, 256), rule).size(), 1u);
  EXPECT_EQ(gridLevels(restToRest(1.0, 300), rule).front().steps, 75);
}

// A level that ends infeasible under infeasible_ends answers for the finer ones: they replay its
// iterate without iterating and the answer is infeasible; the record keeps every level's own end
// for the caller's verdict (a coarser converged level).
TEST(GridContinuation, AnInfeasibleLevelEndsTheContinuationWhenTheRuleSaysSo) {
  SolverOptions options;
  SolveContext context(options);
  GridLevelRule rule;
  rule.infeasible_ends = true;
  StandIn stand_in;
  stand_in.ends[64] = Termination::Infeasible;
  ContinuationRecord seen_record;
  const PlanResult r = solveByGridContinuation<std::vector<int>>(
      restToRest(1.0, 1024), context, rule, 1e-10, stand_in.solver(context),
      [&](const ContinuationRecord& record, PlanResult*) { seen_record = record; });
  using Seen = std::tuple<int, bool, bool>;
  EXPECT_EQ(stand_in.seen,
            (std::vector<Seen>{
                {16, false, false}, {64, true, false}, {256, true, true}, {1024, true, true}}));
  EXPECT_EQ(r.termination, Termination::Infeasible);
  EXPECT_EQ(r.iterations, 6);
  ASSERT_TRUE(seen_record.stop.has_value());
  EXPECT_EQ(seen_record.stop->termination, Termination::Infeasible);
  EXPECT_EQ(seen_record.stop->level.steps, 64);
  EXPECT_EQ(seen_record.stopped_at, 1u);
  EXPECT_EQ(seen_record.levels[0].termination, Termination::Converged);
  ASSERT_EQ(r.levels.size(), 4u);
  EXPECT_EQ(r.levels.back().termination, Termination::Infeasible);
  // Without the rule the next level starts afresh (no coarse iterate) and iterates.
  StandIn afresh;
  afresh.ends[64] = Termination::Infeasible;
  const PlanResult a = solveByGridContinuation<std::vector<int>>(
      restToRest(1.0, 1024), context, GridLevelRule{}, 1e-10, afresh.solver(context));
  EXPECT_EQ(afresh.seen[2], (Seen{256, false, false}));
  EXPECT_TRUE(a.converged());
  EXPECT_EQ(a.iterations, 12);
}

// Resumed from a level the caller solved, the continuation solves only the finer levels, the
// first from that level's iterate; with unconverged_ends a coarse level that does not converge
// ends it there (the result is that level's, not a plan on the requested grid).
TEST(GridContinuation, AResumedContinuationStartsFromTheGivenLevelAndStopsWhereALevelFails) {
  SolverOptions options;
  SolveContext context(options);
  GridLevelRule rule;
  const std::vector<PlanningProblem> levels = gridLevels(restToRest(1.0, 1024), rule);
  ASSERT_EQ(levels.size(), 4u);  // 16, 64, 256, 1024
  SolvedLevel<std::vector<int>> from;
  from.index = 1;
  from.iterate = {64};
  from.below = {16};
  from.below_converged = true;
  StandIn stand_in;
  const LevelSolver<std::vector<int>> inner = stand_in.solver(context);
  const LevelSolver<std::vector<int>> solve = [&](const LevelRequest<std::vector<int>>& r,
                                                  std::vector<int>* out) {
    if (r.problem.steps == 256) {
      EXPECT_EQ(r.coarse != nullptr ? r.coarse->back() : 0, 64);
      EXPECT_EQ(r.coarser != nullptr ? r.coarser->back() : 0, 16);  // extrapolation
    }
    return inner(r, out);
  };
  std::size_t reached = 0;
  const ContinuationFinish finish = [&](const ContinuationRecord& record, PlanResult*) {
    reached = record.reached;
  };
  const PlanResult r = resumeGridContinuation(levels, from, context, rule, 1e-10, solve, finish);
  using Seen = std::tuple<int, bool, bool>;
  EXPECT_EQ(stand_in.seen, (std::vector<Seen>{{256, true, false}, {1024, true, false}}));
  EXPECT_TRUE(r.converged());
  EXPECT_EQ(r.iterations, 6);
  EXPECT_EQ(reached, 4u);

  rule.unconverged_ends = true;
  StandIn failing;
  failing.ends[256] = Termination::NotConverged;
  const PlanResult f =
      resumeGridContinuation(levels, from, context, rule, 1e-10, failing.solver(context), finish);
  EXPECT_EQ(failing.seen, (std::vector<Seen>{{256, true, false}}));
  EXPECT_EQ(f.termination, Termination::NotConverged);
  EXPECT_EQ(reached, 3u);  // the requested level not reached
}

// A cancel before a level: that level and the finer ones replay the last iterate (no
// iterations), the answer is Cancelled and the record names the level it stopped on.
TEST(GridContinuation, ACancelCarriesTheLastIterateUpWithoutIterating) {
  std::atomic<bool> cancel{false};
  SolverOptions options;
  options.cancel_requested = &cancel;
  SolveContext context(options);
  StandIn stand_in;
  const LevelSolver<std::vector<int>> inner = stand_in.solver(context);
  const LevelSolver<std::vector<int>> solve = [&](const LevelRequest<std::vector<int>>& r,
                                                  std::vector<int>* out) {
    PlanResult result = inner(r, out);
    if (r.problem.steps == 64) cancel = true;  // after this level
    return result;
  };
  std::optional<ContinuationStop> stop;
  const PlanResult r = solveByGridContinuation<std::vector<int>>(
      restToRest(1.0, 1024), context, GridLevelRule{}, 1e-10, solve,
      [&](const ContinuationRecord& record, PlanResult*) { stop = record.stop; });
  using Seen = std::tuple<int, bool, bool>;
  EXPECT_EQ(stand_in.seen,
            (std::vector<Seen>{
                {16, false, false}, {64, true, false}, {256, true, true}, {1024, true, true}}));
  EXPECT_EQ(r.termination, Termination::Cancelled);
  EXPECT_EQ(r.iterations, 6);
  ASSERT_TRUE(stop.has_value());
  EXPECT_EQ(stop->termination, Termination::Cancelled);
  EXPECT_EQ(stop->level.steps, 64);
  ASSERT_EQ(r.levels.size(), 4u);
  EXPECT_EQ(r.levels.back().termination, Termination::Cancelled);
}

// One request, one iteration numbering (SolveContext): a constrained request runs Newton (the
// unconstrained optimum, its classes) and then the interior point (whose coarse levels run Newton
// again); every solve reports to the request's one context, so the callback sees 1, 2, ... without
// a restart, and as many reports as the result counts iterations.
TEST(SolveContext, OneRequestNumbersItsIterationsOnce) {
  for (const char* name : {"torque_limited", "sun_keep_out", "rate_limited", "min_time_keep_out"}) {
    const PlanningProblem p = test_support::sceneProblem(name, 64);
    std::vector<int> numbers;
    SolverOptions options;
    options.on_iteration = [&](const IterationInfo& info) {
      numbers.push_back(info.iteration);
      return true;
    };
    const PlanResult r = planManeuver(p, options);
    ASSERT_FALSE(numbers.empty()) << name;
    for (std::size_t i = 0; i < numbers.size(); ++i) {
      ASSERT_EQ(numbers[i], static_cast<int>(i) + 1) << name << ": report " << i;
    }
    if (p.objective == Objective::MinimumEffort) {
      EXPECT_EQ(static_cast<int>(numbers.size()), r.iterations) << name << ": " << r.message();
    }
  }
}

namespace {

/// An adaptive continuation over s in [0, 1] whose stages converge only where s moved by at most
/// `largest` from the last converged stage and s <= `wall` (beyond it, as past a fold, no stage
/// converges): whether each stage solved, and from which converged s to which s each stage was
/// posed (in order).
struct AdaptiveRun {
  StagedOutcome out;
  std::vector<bool> solved;
  std::vector<std::pair<double, double>> posed;
};

AdaptiveRun adaptiveStages(double largest, int hold_after_failure, double first_increment = 0.05,
                           double max_increment = 0.4, double wall = 1.0) {
  SolveContext context{SolverOptions{}};
  AdaptiveSchedule schedule;
  schedule.first_increment = first_increment;
  schedule.max_increment = max_increment;
  schedule.min_increment = 0.01;
  schedule.max_stages = 80;
  schedule.hold_after_failure = hold_after_failure;
  double last = 0.0;
  AdaptiveRun run;
  run.out = solveByAdaptiveStages(
      context,
      [](double s) {
        PlanningProblem p;
        p.duration = 1.0 + s;
        return p;
      },
      schedule,
      [&](const PlanningProblem& stage, const Maneuver* from) {
        const double s = stage.duration - 1.0;
        PlanResult r;
        const bool ok = from == nullptr || (s - last <= largest * (1.0 + 1e-12) && s <= wall);
        r.termination = ok ? Termination::Converged : Termination::Infeasible;
        if (from) {
          run.solved.push_back(ok);
          run.posed.emplace_back(last, s);
        }
        if (ok) last = s;
        return r;
      });
  return run;
}

/// The fewest converged stages between two failed ones (a large number where fewer than two
/// failed).
int fewestConvergedBetweenFailures(const std::vector<bool>& solved) {
  int fewest = 1 << 20;
  int since = -1;  // converged stages since the last failed one (−1: none failed yet)
  for (const bool ok : solved) {
    if (ok) {
      if (since >= 0) ++since;
    } else {
      if (since >= 0) fewest = std::min(fewest, since);
      since = 0;
    }
  }
  return fewest;
}

}  // namespace

// Doubling the increment straight back after a failed stage alternates failed and converged
// stages; held for one converged stage, the continuation reaches s = 1 with fewer failed stages,
// and never two failures with fewer than two converged stages between them.
TEST(StagedContinuation, AHeldIncrementAfterAFailureFailsLessOften) {
  for (const double largest : {0.07, 0.1, 0.13, 0.21}) {
    SCOPED_TRACE(largest);
    const AdaptiveRun doubling = adaptiveStages(largest, 0);
    const AdaptiveRun holding = adaptiveStages(largest, 1);
    const auto failures = [](const std::vector<bool>& v) {
      return std::count(v.begin(), v.end(), false);
    };
    EXPECT_TRUE(doubling.out.complete());
    EXPECT_TRUE(holding.out.complete());
    EXPECT_LT(failures(holding.solved), failures(doubling.solved));
    EXPECT_EQ(fewestConvergedBetweenFailures(doubling.solved), 1);
    EXPECT_GE(fewestConvergedBetweenFailures(holding.solved), 2);
  }
}

// A stage is never posed twice from the same plan (a deterministic solver would fail it again),
// in particular where s + ds was cut at s = 1 and failed there (halving ds, not the increment
// tried, posed s = 1 again from the same plan); the continuation still gets close to the wall.
TEST(StagedContinuation, NoFailedStageIsPosedAgainFromTheSamePlan) {
  int runs = 0;
  for (const double largest : {0.3, 0.6, 1.0}) {
    for (const double first : {0.05, 0.25, 0.5}) {
      for (const double wall : {0.6, 0.95, 0.99}) {
        for (const int hold : {0, 1}) {
          SCOPED_TRACE(std::to_string(largest) + " " + std::to_string(first) + " " +
                       std::to_string(wall) + " " + std::to_string(hold));
          const AdaptiveRun run = adaptiveStages(largest, hold, first, 1.0, wall);
          std::vector<std::pair<double, double>> posed = run.posed;
          std::sort(posed.begin(), posed.end());
          EXPECT_EQ(std::adjacent_find(posed.begin(), posed.end()), posed.end());
          EXPECT_LE(run.out.reached, wall);
          EXPECT_GE(run.out.reached, wall - 0.1);
          ++runs;
        }
      }
    }
  }
  EXPECT_EQ(runs, 54);
}
