// fourth_order minimum time (drivers/minimum_time.cpp, fourthOrderMinimumTime;
// docs/design/fourth_order.md "Minimum time"): a fourth_order plan at T exists exactly when the
// second_order plans at N and 2N both do, so T* is the larger of the two second_order T*, a KKT
// point of the pair where that one is; the plan meets the bounds (the Richardson combination, or
// the N plan where that leaves them). Checked against second_order solved independently, the
// former search on T over fourth_order minimum-effort solves, and a world rotation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "attitude_planner/planner.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "support/scene_problem.hpp"
#include "support/searched_minimum_time.hpp"
#include "support/turned_world.hpp"

namespace ap = attitude_planner;

namespace {

ap::PlanningProblem fourthOrder(const char* name, int steps) {
  ap::PlanningProblem p = ap::test_support::sceneProblem(name, steps);
  p.scheme = ap::SchemeKind::FourthOrder;
  return p;
}

/// second_order's own minimum-time answer to `p` at `steps`.
ap::PlanResult secondOrder(ap::PlanningProblem p, int steps) {
  p.scheme = ap::SchemeKind::SecondOrder;
  p.steps = steps;
  return ap::planManeuver(p);
}

}  // namespace

TEST(FourthOrderMinimumTime, IsTheLargerSecondOrderTStarAKktPointNoSlowerThanTheSearch) {
  const ap::Matrix3 Q = ap::so3::exp(ap::Vector3(0.4, -1.1, 0.7));
  for (const char* name : {"min_time_bilimoria_wie", "min_time_betts"}) {
    for (const int N : {32, 64}) {
      const ap::PlanningProblem p = fourthOrder(name, N);
      EXPECT_EQ(ap::freeTimeUnsupported(p), "");
      const ap::PlanResult r = ap::planManeuver(p);
      ASSERT_TRUE(r.converged()) << name << " N = " << N << ": " << r.message();
      EXPECT_EQ(r.scheme, ap::SchemeKind::FourthOrder);
      ASSERT_TRUE(r.minimum_time.kkt_point) << r.message();
      EXPECT_LE(r.minimum_time.stationarity, 1e-8) << name << " N = " << N;
      EXPECT_LE(r.minimum_time.complementarity, 1e-8) << name << " N = " << N;
      EXPECT_NEAR(r.duration, r.minimum_duration, 1e-12 * r.duration);
      ASSERT_EQ(r.maneuver.steps(), N);
      // At T* the 2N plan is bang–bang and the N plan is not: their Richardson combination
      // would leave the bounds (by 0.15–0.26 of them, measured), so the plan is the N plan at T*,
      // which meets them; the trail keeps its solve.
      EXPECT_LE(r.max_constraint_violation, 1e-8) << name << " N = " << N;
      int kept = 0;
      for (const ap::Attempt& a : r.attempts) {
        if (!a.kept) continue;
        ++kept;
        EXPECT_EQ(a.steps, N) << name << " N = " << N;
      }
      EXPECT_EQ(kept, 1) << name << " N = " << N;

      // T* is the larger of second_order's T* at N and at 2N, each solved on its own.
      const ap::PlanResult at_N = secondOrder(p, N);
      const ap::PlanResult at_2N = secondOrder(p, 2 * N);
      ASSERT_TRUE(at_N.converged() && at_2N.converged()) << at_N.message() << at_2N.message();
      const double larger = std::max(at_N.minimum_duration, at_2N.minimum_duration);
      EXPECT_NEAR(r.minimum_duration, larger, 1e-9 * larger) << name << " N = " << N;
      // The other one is feasible there: its minimum-effort plan at T* meets the bounds.
      ap::PlanningProblem other = p;
      other.scheme = ap::SchemeKind::SecondOrder;
      other.steps = at_N.minimum_duration < at_2N.minimum_duration ? N : 2 * N;
      other.objective = ap::Objective::MinimumEffort;
      other.duration = r.minimum_duration;
      const ap::PlanResult other_at_T = ap::planManeuver(other);
      ASSERT_TRUE(other_at_T.converged()) << other_at_T.message();
      EXPECT_LE(other_at_T.max_constraint_violation, 1e-8);

      // The search's T is an upper bound on T* (bracketed to 1e-9 relative).
      const ap::PlanResult search = ap::test_support::searchedMinimumTime(p);
      ASSERT_TRUE(search.converged()) << search.message();
      EXPECT_FALSE(search.minimum_time.kkt_point);
      EXPECT_LE(r.minimum_duration, search.minimum_duration * (1 + 1e-8)) << name << " N = " << N;
      std::printf(
          "%s N = %d: T* = %.9f (second_order N: %.9f, 2N: %.9f), max_constraint_violation "
          "%.3e, replay miss %.3e; search T = %.9f, max_constraint_violation %.3e, replay miss "
          "%.3e\n",
          name, N, r.minimum_duration, at_N.minimum_duration, at_2N.minimum_duration,
          r.max_constraint_violation, r.replay_miss, search.minimum_duration,
          search.max_constraint_violation, search.replay_miss);

      ap::test_support::expectSameTStarWhenTurned(ap::test_support::inATurnedWorld(p, Q), r, 1e-8,
                                                  std::string(name) + " N = " + std::to_string(N));
    }
  }
}

TEST(FourthOrderMinimumTime, MarginAndABoundedRequestBelowTStarUseThePair) {
  // time_margin: each second_order sub-solve starts from its own plan at T*, time-scaled inside
  // the bounds (from the combination, the 2N solve started cold and ended a false "infeasible"
  // at 1.005, 1.02 and 1.1 T*). At 1.005 T* the combination leaves a bound (0.19 N m): the plan
  // is the N one there.
  const ap::PlanningProblem p = fourthOrder("min_time_betts", 64);
  const ap::PlanResult tight = ap::planManeuver(p);
  ASSERT_TRUE(tight.converged()) << tight.message();
  for (const double margin : {0.005, 0.02, 0.1}) {
    ap::PlanningProblem relaxed = p;
    relaxed.time_margin = margin;
    const ap::PlanResult r = ap::planManeuver(relaxed);
    ASSERT_TRUE(r.converged()) << "margin " << margin << ": " << r.message();
    EXPECT_EQ(r.scheme, ap::SchemeKind::FourthOrder);
    EXPECT_NEAR(r.minimum_duration, tight.minimum_duration, 1e-12 * tight.minimum_duration);
    EXPECT_NEAR(r.duration, (1 + margin) * tight.minimum_duration, 1e-12 * r.duration);
    EXPECT_LE(r.max_constraint_violation, 1e-8) << "margin " << margin;
    EXPECT_LT(r.effort, tight.effort) << "margin " << margin;
  }
  // A bounded minimum-effort request below T* is answered infeasible, naming T* (structured).
  ap::PlanningProblem below = p;
  below.objective = ap::Objective::MinimumEffort;
  below.duration = 0.999 * tight.minimum_duration;
  const ap::PlanResult refused = ap::planManeuver(below);
  EXPECT_EQ(refused.termination, ap::Termination::Infeasible) << refused.message();
  EXPECT_NEAR(refused.minimum_duration, tight.minimum_duration, 1e-12 * tight.minimum_duration);
}
