// Every iteration a request reports names the attempt it belongs to (SolveContext::Scope): its
// stage and homotopy class as the trail (PlanResult::attempts) names them, so that a convergence
// plot (the action's feedback) tells one attempt from the next and the kept one from the others.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/worker_threads.hpp"
#include "support/pointing_requests.hpp"
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

TEST(AttemptTags, BranchesRunAtOnceReportInOneSequenceAndJoinTheTrailInTheirOrder) {
  // Four branches, two at a time on two threads: every report reaches the caller once, numbered
  // 1, 2, ... in the order the caller sees them; attempts are numbered once across branches; the
  // trail holds each branch's attempt in the branches' order, and the iterations all of them.
  std::vector<int> numbers;
  std::set<int> attempt_numbers;
  ap::SolverOptions options;
  options.threads = 2;
  options.on_iteration = [&](const ap::IterationInfo& info) {
    numbers.push_back(info.iteration);
    attempt_numbers.insert(info.attempt.number);
    return true;
  };
  ap::SolveContext context(options);
  constexpr int kBranches = 4, kIterations = 50;
  ap::runBranches(context, kBranches, [&](int i, ap::SolveContext& branch) {
    const ap::SolveContext::Scope scope(branch, ap::AttemptStage::MinimumTimeSolve, {false, 0});
    for (int k = 0; k < kIterations; ++k) branch.reportIteration({});
    ap::Attempt a;
    a.iterations = scope.iterations();
    a.cost = i;  // which branch
    branch.record(a);
  });
  ASSERT_EQ(numbers.size(), static_cast<std::size_t>(kBranches * kIterations));
  for (std::size_t k = 0; k < numbers.size(); ++k) EXPECT_EQ(numbers[k], static_cast<int>(k) + 1);
  EXPECT_EQ(attempt_numbers.size(), static_cast<std::size_t>(kBranches));
  EXPECT_EQ(context.iterations(), kBranches * kIterations);
  ASSERT_EQ(context.attempts().size(), static_cast<std::size_t>(kBranches));
  for (int i = 0; i < kBranches; ++i) {
    EXPECT_EQ(context.attempts()[i].cost, i);
    EXPECT_EQ(context.attempts()[i].iterations, kIterations);
  }
}

TEST(AttemptTags, TheConeClearingsTallyCountsOnlyWhileClearingWithTheBranchesJoinedThen) {
  // The request's cone clearings are read from the one numbering (coneClearingIterations): what
  // is reported while a ClearingCones is alive, the branches joined then included; a branch's
  // own clearings join with it; a nested ClearingCones ends without pausing the outer one.
  ap::SolverOptions options;
  options.threads = 2;
  ap::SolveContext context(options);
  const auto report = [](ap::SolveContext& c, int n) {
    for (int k = 0; k < n; ++k) c.reportIteration({});
  };
  report(context, 5);
  EXPECT_EQ(context.coneClearingIterations(), 0);
  {
    const ap::SolveContext::ClearingCones clearing(context);
    report(context, 7);
    ap::runBranches(context, 2, [&](int, ap::SolveContext& branch) { report(branch, 10); });
  }
  EXPECT_EQ(context.coneClearingIterations(), 27);
  report(context, 3);
  ap::runBranches(context, 2, [&](int, ap::SolveContext& branch) {
    {
      const ap::SolveContext::ClearingCones clearing(branch);
      report(branch, 4);
    }
    report(branch, 6);
  });
  EXPECT_EQ(context.coneClearingIterations(), 35);
  {
    const ap::SolveContext::ClearingCones outer(context);
    {
      const ap::SolveContext::ClearingCones inner(context);
      report(context, 1);
    }
    report(context, 1);
  }
  report(context, 2);
  EXPECT_EQ(context.coneClearingIterations(), 37);
  EXPECT_EQ(context.iterations(), 5 + 27 + 3 + 20 + 2 + 2);
}

TEST(AttemptTags, ASlidingWindowBeginsEachWorkAfterTheSameEndsHoweverLongTheWorksTake) {
  // Works of random lengths, some empty (no place taken), on 1, 2 and 3 threads: the ends run in
  // order, at most `threads` works run at once, and what each begin has seen (the ends before
  // it) is the same on every run: with every work non-empty, begin(i) follows ends 0..i − threads.
  std::mt19937 random(52);
  for (const int threads : {1, 2, 3}) {
    std::vector<int> seen_first;
    for (int run = 0; run < 4; ++run) {
      ap::SolverOptions options;
      options.threads = threads;
      ap::SolveContext context(options);
      constexpr int kWorks = 9;
      std::vector<int> ends, seen(kWorks, -1);
      std::atomic<int> running{0}, most{0};
      std::vector<int> pause_us(kWorks);
      for (int& p : pause_us) p = std::uniform_int_distribution<int>(0, 3000)(random);
      const auto begin = [&](int i) -> ap::BranchWork {
        seen[i] = static_cast<int>(ends.size());
        if (i % 4 == 3) return {};  // a repeat: nothing to run
        return [&, i](ap::SolveContext& branch) {
          most = std::max(most.load(), ++running);
          std::this_thread::sleep_for(std::chrono::microseconds(pause_us[i]));
          ap::Attempt a;
          a.cost = i;
          branch.record(a);
          --running;
        };
      };
      ap::runSlidingWindow(context, kWorks, begin, [&](int i) { ends.push_back(i); });
      ASSERT_EQ(ends.size(), static_cast<std::size_t>(kWorks));
      for (int i = 0; i < kWorks; ++i) EXPECT_EQ(ends[i], i);
      EXPECT_LE(most.load(), threads);
      ASSERT_EQ(context.attempts().size(), 7u);  // the non-empty works, in their order
      for (std::size_t k = 1; k < context.attempts().size(); ++k) {
        EXPECT_LT(context.attempts()[k - 1].cost, context.attempts()[k].cost);
      }
      if (run == 0) seen_first = seen;
      EXPECT_EQ(seen, seen_first) << threads << " threads, run " << run;
      for (int i = 0; i < 3; ++i) EXPECT_EQ(seen[i], std::max(0, i - threads + 1));
    }
  }
}

TEST(AttemptTags, ASlidingWindowRethrowsAWorksExceptionAtItsEndAndBeginsNothingAfter) {
  ap::SolverOptions options;
  options.threads = 2;
  ap::SolveContext context(options);
  std::vector<int> begun, ended;
  const auto begin = [&](int i) -> ap::BranchWork {
    begun.push_back(i);
    return [i](ap::SolveContext&) {
      if (i == 2) throw std::runtime_error("work 2 failed");
    };
  };
  EXPECT_THROW(ap::runSlidingWindow(context, 8, begin, [&](int i) { ended.push_back(i); }),
               std::runtime_error);
  EXPECT_EQ(ended, (std::vector<int>{0, 1}));
  EXPECT_LE(begun.size(), 4u);  // work 2 and at most one after it had begun when it ended
}

TEST(AttemptTags, QueuedBranchesRunEachWorkOnceWithoutWaitingForABatchAndJoinInTheirOrder) {
  // Five works of unequal length on two threads, queued: each runs once, and a long first work
  // does not hold the others back (the other thread takes works 1..4 while work 0 runs, which a
  // batch of two would not allow); the trail is still in the works' order.
  ap::SolverOptions options;
  options.threads = 2;
  ap::SolveContext context(options);
  constexpr int kWorks = 5;
  std::vector<int> runs(kWorks, 0);
  std::atomic<bool> first_done{false};
  std::atomic<int> done_during_first{0};
  ap::runBranches(context, kWorks, [&](int i, ap::SolveContext& branch) {
    ++runs[i];
    if (i == 0) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (done_during_first < kWorks - 1 && std::chrono::steady_clock::now() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      first_done = true;
    } else if (!first_done) {
      ++done_during_first;
    }
    branch.reportIteration({});
    ap::Attempt a;
    a.cost = i;
    branch.record(a);
  });
  for (int i = 0; i < kWorks; ++i) EXPECT_EQ(runs[i], 1) << i;
  EXPECT_EQ(done_during_first, kWorks - 1);
  EXPECT_EQ(context.iterations(), kWorks);
  ASSERT_EQ(context.attempts().size(), static_cast<std::size_t>(kWorks));
  for (int i = 0; i < kWorks; ++i) EXPECT_EQ(context.attempts()[i].cost, i);
}

TEST(WorkerThreads, EachWorkRunsOnceWhetherHandedOverInBurstsOrApart) {
  // Bursts of works handed over at once, the bursts from 0 to 3 ms apart (a thread that ended
  // its work may or may not be waiting again): at any speed each work runs exactly once, on a
  // thread or, taken back before any thread began it, on its caller, and what it wrote is
  // visible to its caller after takeBackOrWait.
  ap::WorkerThreads& threads = ap::WorkerThreads::shared();
  constexpr int kBurst = 3, kRounds = 15;
  for (const int pause_us : {0, 100, 300, 800, 3000}) {
    for (int round = 0; round < kRounds; ++round) {
      std::vector<int> runs(kBurst, 0);  // each written by its own work only
      std::vector<std::unique_ptr<ap::HandedWork>> works;
      for (int i = 0; i < kBurst; ++i) {
        works.push_back(std::make_unique<ap::HandedWork>([&runs, i] { ++runs[i]; }));
      }
      for (auto& work : works) threads.handOver(*work);
      for (int i = 0; i < kBurst; ++i) {
        if (!threads.takeBackOrWait(*works[i])) {
          EXPECT_EQ(runs[i], 0) << "a work taken back had begun";
          works[i]->runHere();
        }
        EXPECT_EQ(runs[i], 1) << "pause " << pause_us << " us, round " << round << ", work " << i;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(pause_us));
    }
  }
}

TEST(AttemptTags, ACallerRefusingAReportStopsEveryBranch) {
  // The refusal is the request's: a branch that has not reported yet stops too.
  ap::SolverOptions options;
  options.threads = 2;
  std::atomic<int> calls{0};
  options.on_iteration = [&](const ap::IterationInfo&) { return ++calls < 10; };
  ap::SolveContext context(options);
  std::atomic<int> stopped{0};
  ap::runBranches(context, 2, [&](int, ap::SolveContext& branch) {
    for (int k = 0; k < 1000000 && !branch.stopReason(); ++k) branch.reportIteration({});
    if (branch.stopReason() == ap::Termination::Cancelled) ++stopped;
  });
  EXPECT_EQ(stopped, 2);
  EXPECT_EQ(context.stopReason(), ap::Termination::Cancelled);
  EXPECT_LT(context.iterations(), 1000);
  EXPECT_EQ(calls.load(),
            10);  // the other branch's reports after the refusal never reach the caller
}

TEST(AttemptTags, ACallerThatRefusedHearsNoFurtherReport) {
  // A branch on another thread reports until it next polls; the caller who said stop must not
  // be called again (its last report stays the one it refused).
  ap::SolverOptions options;
  options.threads = 2;
  int calls = 0;
  options.on_iteration = [&](const ap::IterationInfo&) { return ++calls < 3; };
  ap::SolveContext context(options);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(context.reportIteration({}), k < 2);
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(context.reportIteration({}));
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(context.stopReason(), ap::Termination::Cancelled);
}

TEST(AttemptTags, AClassSurveysIterationsAreTaggedWithTheTrailsStagesAndClasses) {
  // Near a half turn the survey solves several classes and refines the cheapest: each report
  // names its attempt, and the reports of each stage and class add up to the trail's count.
  ap::PlanningProblem p = ap::test_support::sceneProblem("rest_to_rest", 64);
  ap::PlanResult r;
  const std::vector<ap::IterationInfo> infos = reported(p, &r);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_FALSE(infos.empty());
  EXPECT_TRUE(std::all_of(infos.begin(), infos.end(),
                          [](const ap::IterationInfo& i) { return i.attempt.number > 0; }));
  EXPECT_EQ(byTag(infos), byTrail(r.attempts));
  EXPECT_EQ(static_cast<int>(infos.size()), r.iterations);
  const auto surveys = std::count_if(infos.begin(), infos.end(), [](const ap::IterationInfo& i) {
    return i.attempt.stage == ap::AttemptStage::ClassSurvey;
  });
  EXPECT_GT(surveys, 0) << r.message();
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
    ASSERT_FALSE(infos.empty()) << r.message();
    EXPECT_TRUE(std::any_of(
        r.attempts.begin(), r.attempts.end(),
        [](const ap::Attempt& a) { return a.formulation != ap::Formulation::Unconstrained; }))
        << "the interior point ran: " << r.message();
    EXPECT_EQ(byTag(infos), byTrail(r.attempts)) << r.message();
    EXPECT_EQ(static_cast<int>(infos.size()), r.iterations);
  }
}

/// The result's trail is what the request's context recorded, attempt for attempt (every field),
/// with one kept attempt in both when `one_kept`.
void expectTheContextsTrail(const ap::PlanResult& r, const ap::SolveContext& context,
                            bool one_kept = true) {
  const std::vector<ap::Attempt>& trail = context.attempts();
  ASSERT_EQ(trail.size(), r.attempts.size()) << r.message();
  for (std::size_t i = 0; i < trail.size(); ++i) {
    SCOPED_TRACE(i);
    const ap::Attempt &a = r.attempts[i], &b = trail[i];
    EXPECT_EQ(a.stage, b.stage);
    EXPECT_EQ(a.start, b.start);
    EXPECT_EQ(a.formulation, b.formulation);
    EXPECT_EQ(a.globalization, b.globalization);
    EXPECT_TRUE(ap::sameHomotopyClass(a.homotopy, b.homotopy));
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.termination, b.termination);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_TRUE(a.cost == b.cost || (std::isnan(a.cost) && std::isnan(b.cost)));
    EXPECT_EQ(a.kept, b.kept);
    EXPECT_EQ(a.start_detail.coarse_steps, b.start_detail.coarse_steps);
    EXPECT_EQ(a.start_detail.origin, b.start_detail.origin);
    const double ta = a.start_detail.twist, tb = b.start_detail.twist;
    EXPECT_TRUE(ta == tb || (std::isnan(ta) && std::isnan(tb)));
    const double da = a.start_detail.duration, db = b.start_detail.duration;
    EXPECT_TRUE(da == db || (std::isnan(da) && std::isnan(db)));
  }
  const auto kept = [](const std::vector<ap::Attempt>& t) {
    return std::count_if(t.begin(), t.end(), [](const ap::Attempt& a) { return a.kept; });
  };
  if (one_kept) EXPECT_EQ(kept(r.attempts), 1) << r.message();
  EXPECT_EQ(kept(trail), kept(r.attempts));
}

TEST(AttemptTags, AConstrainedRequestsTrailIsTheContextsTrail) {
  // Newton's walk, then the interior point from its optimum (at N = 512 through its grid
  // continuation, whose levels' unconstrained starts are parts of its attempt), and the other
  // classes where the first stops: the result's trail is what the request's context recorded.
  for (const int steps : {64, 512}) {
    for (const char* scene :
         {"torque_limited", "rate_limited", "sun_keep_out", "leo_slew_limited"}) {
      SCOPED_TRACE(scene);
      SCOPED_TRACE(steps);
      const ap::PlanningProblem p = ap::test_support::sceneProblem(scene, steps);
      const ap::SolverOptions options;
      ap::SolveContext context(options);
      const ap::PlanResult r = ap::planAtResolution(p, ap::SolveRequest(options), context);
      ASSERT_TRUE(std::any_of(
          r.attempts.begin(), r.attempts.end(),
          [](const ap::Attempt& a) { return a.formulation != ap::Formulation::Unconstrained; }))
          << "the interior point ran: " << r.message();
      expectTheContextsTrail(r, context);
      // The interior point's continuation is one attempt: the Newton solve that starts its
      // coarsest level (which its scope would name `constrained`) is no attempt of the trail.
      EXPECT_TRUE(std::none_of(r.attempts.begin(), r.attempts.end(), [](const ap::Attempt& a) {
        return a.formulation == ap::Formulation::Unconstrained &&
               (a.stage == ap::AttemptStage::Constrained ||
                a.stage == ap::AttemptStage::ConstrainedRetry);
      })) << r.message();
    }
  }
}

TEST(AttemptTags, AFourthOrderRequestsTrailIsTheContextsTrail) {
  // The N and the 2N second_order solves, a solver's own solve named fourth_order_coarse or
  // fourth_order_fine by the scope it runs in (the N solve's class survey keeps its stages; the
  // 2N solve, pinned to the class the N solve chose, is one): the 2N solve's kept attempt kept.
  for (const char* scene : {"rest_to_rest", "torque_limited"}) {
    SCOPED_TRACE(scene);
    ap::PlanningProblem p = ap::test_support::sceneProblem(scene, 32);
    p.scheme = ap::SchemeKind::FourthOrder;
    const ap::SolverOptions options;
    ap::SolveContext context(options);
    const ap::PlanResult r = ap::planAtResolution(p, ap::SolveRequest(options), context);
    ASSERT_TRUE(r.converged()) << r.message();
    expectTheContextsTrail(r, context);
    const auto named = [&](ap::AttemptStage stage) {
      return std::any_of(r.attempts.begin(), r.attempts.end(),
                         [&](const ap::Attempt& a) { return a.stage == stage; });
    };
    EXPECT_TRUE(named(ap::AttemptStage::FourthOrderFine));
    EXPECT_FALSE(named(ap::AttemptStage::Solve));
    EXPECT_TRUE(std::any_of(r.attempts.begin(), r.attempts.end(),
                            [](const ap::Attempt& a) { return a.steps == 32; }));
    const auto kept = std::find_if(r.attempts.begin(), r.attempts.end(),
                                   [](const ap::Attempt& a) { return a.kept; });
    ASSERT_NE(kept, r.attempts.end());
    EXPECT_EQ(kept->steps, 64);
  }
}

TEST(AttemptTags, AMinimumTimeRequestsTrailIsTheContextsTrail) {
  // The free-time solves (their starts' helper solves left out), the search where they fail,
  // the probes below T* with spinning ends, the plan at the margin: rest to rest, spinning, and
  // with a time margin, the trail is what the context recorded, the answer's attempt kept.
  ap::PlanningProblem rest = ap::test_support::sceneProblem("min_time_bilimoria_wie", 32);
  ap::PlanningProblem spinning = ap::test_support::sceneProblem("min_time_sphere", 32);
  spinning.initial_velocity = ap::Vector3(0.2, 0.0, 0.0);
  ap::PlanningProblem margin = rest;
  margin.time_margin = 0.05;
  ap::PlanningProblem keep_out = ap::test_support::sceneProblem("min_time_keep_out", 32);
  const std::pair<const char*, const ap::PlanningProblem*> requests[] = {
      {"rest to rest", &rest},
      {"spinning", &spinning},
      {"margin", &margin},
      {"keep-out cone", &keep_out}};
  for (const auto& [name, problem] : requests) {
    SCOPED_TRACE(name);
    ap::PlanningProblem p = *problem;
    p.objective = ap::Objective::MinimumTime;
    const ap::SolverOptions options;
    ap::SolveContext context(options);
    const ap::PlanResult r = ap::planMinimumTime(p, context);
    ASSERT_TRUE(r.converged()) << r.message();
    ASSERT_FALSE(r.attempts.empty());
    expectTheContextsTrail(r, context);
  }
}

/// Minimum effort for `p` (a minimum-time request) at 0.9 of its T*, planned in `context`.
ap::PlanResult boundedBelowItsMinimumTime(ap::PlanningProblem p, ap::SolveContext& context) {
  const ap::PlanResult fastest = ap::planManeuver(p, ap::SolverOptions());
  EXPECT_TRUE(fastest.converged()) << fastest.message();
  p.objective = ap::Objective::MinimumEffort;
  p.duration = 0.9 * fastest.minimum_duration;
  return ap::planBoundedMinimumEffort(p, context);
}

TEST(AttemptTags, ABoundedRequestsTrailIsTheContextsTrail) {
  // Minimum effort at 0.9 T*: the interior point ends infeasible, the minimum-time phase backs
  // the verdict; the trail holds both, as the context recorded them.
  ap::PlanningProblem p = ap::test_support::sceneProblem("min_time_bilimoria_wie", 32);
  p.objective = ap::Objective::MinimumTime;
  const ap::SolverOptions options;
  ap::SolveContext context(options);
  const ap::PlanResult r = boundedBelowItsMinimumTime(p, context);
  EXPECT_EQ(r.termination, ap::Termination::Infeasible) << r.message();
  const bool minimum_time_phase = std::any_of(
      r.attempts.begin(), r.attempts.end(),
      [](const ap::Attempt& a) { return a.stage == ap::AttemptStage::MinimumTimeSolve; });
  EXPECT_TRUE(minimum_time_phase) << r.message();
  expectTheContextsTrail(r, context, false);
}

TEST(AttemptTags, APointingRequestsTrailIsTheContextsTrail) {
  // A pointing request under a keep-out cone: its twist runs and the fixed-twist solves they
  // start from, as the context recorded them.
  const ap::PlanningProblem p = ap::test_support::randomConstrainedPointingRequest(
      7, 32, false, ap::SchemeKind::SecondOrder, ap::test_support::PointingBinding::KeepOut);
  const ap::SolverOptions options;
  ap::SolveContext context(options);
  const ap::PlanResult r = ap::planAtResolution(p, ap::SolveRequest(options), context);
  ASSERT_FALSE(r.attempts.empty()) << r.message();
  expectTheContextsTrail(r, context, r.converged());
}

TEST(AttemptTags, APointingMinimumTimeRequestsTrailIsTheContextsTrailTaggedWithItsTwists) {
  // Minimum time to a pointing target: each start twist's fixed-twist solves (on the survey grid,
  // then the best on N), with and without a time margin; the trail is what the context recorded,
  // and every attempt names the start twist it was posed at.
  ap::PlanningProblem p =
      ap::test_support::randomBettsPointingRequest(4303, 32, ap::SchemeKind::SecondOrder);
  for (const double margin : {0.0, 0.05}) {
    SCOPED_TRACE(margin);
    p.time_margin = margin;
    const ap::SolverOptions options;
    ap::SolveContext context(options);
    const ap::PlanResult r = ap::planMinimumTime(p, context);
    ASSERT_TRUE(r.converged()) << r.message();
    ASSERT_FALSE(r.attempts.empty());
    expectTheContextsTrail(r, context);
    std::set<double> twists;
    for (const ap::Attempt& a : r.attempts) {
      EXPECT_TRUE(std::isfinite(a.start_detail.twist)) << ap::attemptStageName(a.stage);
      twists.insert(a.start_detail.twist);
    }
    EXPECT_GT(twists.size(), 1u) << "the start twists are told apart";
  }
}

TEST(AttemptTags, ABoundedPointingRequestsTrailIsTheContextsTrail) {
  // Minimum effort to a pointing target below T* (the twist free): the interior point ends
  // infeasible and the minimum-time phase over the start twists backs the verdict; the trail
  // holds both, as the context recorded them.
  const ap::PlanningProblem p =
      ap::test_support::randomBettsPointingRequest(4303, 32, ap::SchemeKind::SecondOrder);
  const ap::SolverOptions options;
  ap::SolveContext context(options);
  const ap::PlanResult r = boundedBelowItsMinimumTime(p, context);
  EXPECT_FALSE(r.converged()) << r.message();
  EXPECT_TRUE(std::any_of(r.attempts.begin(), r.attempts.end(), [](const ap::Attempt& a) {
    return a.stage == ap::AttemptStage::MinimumTimeSolve && std::isfinite(a.start_detail.twist);
  })) << r.message();
  expectTheContextsTrail(r, context, false);
}

/// The result's levels are what the request's context recorded, level for level.
void expectTheContextsLevels(const ap::PlanResult& r, const ap::SolveContext& context) {
  const std::vector<ap::LevelSummary>& levels = context.levels();
  ASSERT_EQ(levels.size(), r.levels.size()) << r.message();
  for (std::size_t i = 0; i < levels.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(r.levels[i].steps, levels[i].steps);
    EXPECT_EQ(r.levels[i].iterations, levels[i].iterations);
    EXPECT_EQ(r.levels[i].termination, levels[i].termination);
    EXPECT_EQ(r.levels[i].relative_gradient, levels[i].relative_gradient);
    EXPECT_EQ(r.levels[i].newton_decrement, levels[i].newton_decrement);
    EXPECT_EQ(r.levels[i].reason, levels[i].reason);
  }
}

TEST(AttemptTags, AConstrainedRequestsLevelsAreTheContextsLevels) {
  // Newton's kept attempt's levels, then every grid solve of the interior point (at N = 512 its
  // continuation's levels, each from its own unconstrained optimum or the coarser level): the
  // result's levels are the context's, one of them on the requested grid.
  for (const int steps : {64, 512}) {
    for (const char* scene : {"torque_limited", "rate_limited", "sun_keep_out"}) {
      SCOPED_TRACE(scene);
      SCOPED_TRACE(steps);
      ap::PlanningProblem p = ap::test_support::sceneProblem(scene, steps);
      ap::SolverOptions options;
      options.enumerate_classes = false;  // one class: the request's levels alone
      ap::SolveContext context(options);
      const ap::PlanResult r = ap::planAtResolution(p, ap::SolveRequest(options), context);
      ASSERT_FALSE(r.levels.empty()) << r.message();
      expectTheContextsLevels(r, context);
      EXPECT_TRUE(std::any_of(r.levels.begin(), r.levels.end(), [&](const ap::LevelSummary& l) {
        return l.steps == steps;
      })) << r.message();
    }
  }
}

TEST(AttemptTags, TheKeptAttemptOfAConstrainedRequestIsAmongTheTagsReported) {
  // Under a torque bound the interior point follows Newton's optimum: its iterations are tagged
  // `constrained`, and the kept attempt's stage and class were reported.
  const ap::PlanningProblem p = ap::test_support::sceneProblem("torque_limited", 64);
  ap::PlanResult r;
  const std::vector<ap::IterationInfo> infos = reported(p, &r);
  ASSERT_TRUE(r.converged()) << r.message();
  const auto kept = std::find_if(r.attempts.begin(), r.attempts.end(),
                                 [](const ap::Attempt& a) { return a.kept; });
  ASSERT_NE(kept, r.attempts.end());
  const std::map<StageAndClass, int> tags = byTag(infos);
  EXPECT_EQ(tags.count(keyOf(kept->stage, kept->homotopy)), 1u) << r.message();
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
  ASSERT_TRUE(r.converged()) << r.message();
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
  EXPECT_EQ(cancelled.termination, ap::Termination::Cancelled) << cancelled.message();
  ASSERT_FALSE(until_cancel.empty());
  EXPECT_EQ(until_cancel.front().attempt.stage, ap::AttemptStage::MinimumTimeSolve);
  EXPECT_EQ(until_cancel.size(), 1u);
}
