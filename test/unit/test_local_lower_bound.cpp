// The one rule every watch of a start against the least answer held stops by (cannotEndBelow):
// a start is stopped only where its local lower bound holds and lies above the least answer.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "planning/interior_point/free_time_solver.hpp"
#include "planning/interior_point/grid_solve.hpp"
#include "planning/interior_point/local_lower_bound.hpp"

namespace ap = attitude_planner;

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}

TEST(LocalLowerBound, AStartIsStoppedOnlyWhereItsBoundHoldsAndLiesAboveTheLeastAnswer) {
  const ap::LocalLowerBound above{12.0, 11.0, true};
  EXPECT_FALSE(ap::cannotEndBelow(above, 10.0, "the least T").empty());
  EXPECT_TRUE(ap::cannotEndBelow(above, 11.0, "the least T").empty());  // at the bound: may tie
  EXPECT_TRUE(ap::cannotEndBelow(above, 11.5, "the least T").empty());
  EXPECT_TRUE(ap::cannotEndBelow({12.0, 11.0, false}, 10.0, "the least T").empty());
  EXPECT_TRUE(ap::cannotEndBelow(above, kInfinity, "the least T").empty());
  EXPECT_TRUE(ap::cannotEndBelow(above, std::nan(""), "the least T").empty());
  EXPECT_TRUE(ap::cannotEndBelow({12.0, std::nan(""), true}, 10.0, "the least T").empty());
}

TEST(LocalLowerBound, TheRuleAndItsReasonAgreeEverywhere) {
  // cannotEndBelowLeast is the rule and cannotEndBelow its words: a reason exactly where the rule
  // stops, over bounds that hold or not and least answers below, at, above, +∞ and NaN.
  const double leasts[] = {-kInfinity, -1.0, 10.0, 11.0, 11.5, 12.0, kInfinity, std::nan("")};
  for (const bool holds : {true, false}) {
    for (const double bound : {-kInfinity, 0.0, 11.0, kInfinity}) {
      for (const double least : leasts) {
        const ap::LocalLowerBound at{12.0, bound, holds};
        EXPECT_EQ(ap::cannotEndBelowLeast(at, least), !ap::cannotEndBelow(at, least, "x").empty())
            << holds << " " << bound << " " << least;
      }
    }
  }
  EXPECT_TRUE(ap::cannotEndBelowLeast({12.0, 11.0, true}, 10.0));
  EXPECT_FALSE(ap::cannotEndBelowLeast({12.0, 11.0, true}, 11.0));
}

TEST(LocalLowerBound, FreeTimesBarrierPointsHoldWhereLocallyConvexAndFixedStepIteratesAlways) {
  ap::BarrierPoint point;
  point.duration = 5.0;
  point.lower_bound = 4.0;
  EXPECT_FALSE(point.bound().holds);
  point.locally_convex = true;
  EXPECT_TRUE(point.bound().holds);
  EXPECT_EQ(point.bound().value, 5.0);
  EXPECT_EQ(point.bound().lower_bound, 4.0);
  const ap::FeasibleIterate at{3.0, 2.5, 0.01, 7};
  EXPECT_TRUE(at.bound().holds);
  EXPECT_EQ(at.bound().value, 3.0);
  EXPECT_EQ(at.bound().lower_bound, 2.5);
}
