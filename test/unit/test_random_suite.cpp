// The seeded randomized suite at CI size. Every generated problem
// (test/support/random_problems.hpp: physical and seed-like inertias, random attitudes, boundary
// rates up to 5 rad/s with h|Ω| ≤ 0.5, horizons up to 100 s, both schemes) must converge.
// The full-size run with the IPOPT comparison is `scripts/robustness --random`
// (docs/results/robustness.md).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "support/random_problems.hpp"

using namespace attitude_planner;
using robustness::RandomCase;

namespace {

/// The suite's seed (the full-size study uses the same one) and the CI size: the first
/// kCiCases cases, ~30 s at Release on one core of this machine.
constexpr std::uint64_t kSuiteSeed = 19;
constexpr int kCiCases = 40;

/// Cases of the CI subset that do not converge today (a strict expected failure: if one
/// converges the test fails until it is removed here, so the list cannot go stale). Empty since
/// the Levenberg–Marquardt control of the Newton shift: #1 and #25 (seed-like, variational,
/// T ≈ 65–72 s, ~4 rad/s at both ends) converge by continuation in the boundary rates.
/// docs/results/robustness.md has the full-size figures.
const std::set<int> kKnownStalls = {};

}  // namespace

TEST(RandomSuite, GeneratorIsDeterministicAndMeetsItsBounds) {
  const std::vector<RandomCase> a = robustness::randomSuite(kSuiteSeed, 50);
  const std::vector<RandomCase> b = robustness::randomSuite(kSuiteSeed, 50);
  int physical = 0, paper = 0, spinning = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const PlanningProblem& p = a[i].problem;
    EXPECT_EQ(p.inertia, b[i].problem.inertia);
    EXPECT_EQ(p.final_attitude, b[i].problem.final_attitude);
    EXPECT_EQ(p.initial_velocity, b[i].problem.initial_velocity);
    EXPECT_EQ(p.steps, b[i].problem.steps);
    EXPECT_NO_THROW(validateProblem(p)) << a[i].label;
    const double h = p.duration / p.steps;
    EXPECT_LE(h * p.initial_velocity.norm(), robustness::kMaxBoundaryStepAngle);
    EXPECT_LE(h * p.final_velocity.norm(), robustness::kMaxBoundaryStepAngle);
    EXPECT_LE(p.initial_velocity.norm(), robustness::kMaxBoundaryRate);
    EXPECT_LE(p.duration, robustness::kMaxHorizon);
    if (a[i].family == robustness::InertiaFamily::Physical) {
      ++physical;
      const Vector3 m = Eigen::SelfAdjointEigenSolver<Matrix3>(p.inertia).eigenvalues();
      EXPECT_GE(m(0) + m(1), m(2) * (1 - 1e-12)) << a[i].label;
    }
    paper += p.scheme == SchemeKind::Paper;
    spinning += p.initial_velocity.norm() > 2.5 || p.final_velocity.norm() > 2.5;
  }
  // Both families, both schemes and fast ends are all drawn.
  EXPECT_GT(physical, 10);
  EXPECT_LT(physical, 40);
  EXPECT_EQ(paper, 25);
  EXPECT_GT(spinning, 10);
  // A different seed draws different problems.
  EXPECT_NE(robustness::randomCase(kSuiteSeed + 1, 0).problem.inertia, a[0].problem.inertia);
}
TEST(RandomSuite, EveryCaseConverges) {
  int converged = 0;
  std::vector<int> iterations;
  const auto start = std::chrono::steady_clock::now();
  for (const RandomCase& c : robustness::randomSuite(kSuiteSeed, kCiCases)) {
    const PlanResult r = planManeuver(c.problem);
    if (kKnownStalls.count(c.index)) {
      EXPECT_NE(r.termination, Termination::Converged)
          << c.label << " converges now: remove it from kKnownStalls";
      EXPECT_EQ(r.termination, Termination::NotConverged) << c.label << ": " << r.message();
    } else {
      EXPECT_EQ(r.termination, Termination::Converged) << c.label << ": " << r.message();
    }
    if (r.converged()) {
      ++converged;
      EXPECT_LE(r.step_residual, measureStepResidual(c.problem, r.maneuver).tolerance);
    }
    iterations.push_back(r.iterations);
    std::printf("%-60s %-14s %4d it %8.3f s cost %.10g replay miss %.1e\n", c.label.c_str(),
                terminationName(r.termination).c_str(), r.iterations, r.solve_time_s, r.cost,
                r.replay_miss);
  }
  std::sort(iterations.begin(), iterations.end());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "random suite (seed %llu, %d cases): %d converged, median %d iterations, max %d, "
      "%.1f s\n",
      static_cast<unsigned long long>(kSuiteSeed), kCiCases, converged,
      iterations[iterations.size() / 2], iterations.back(), seconds);
  RecordProperty("converged", converged);
  RecordProperty("cases", kCiCases);
}

// Beyond the CI subset, the suite's one case that IPOPT solved and the Hermite start did not
// (#150: seed-like inertia, T = 92 s, 4.7–5 rad/s at both ends, ~70 revolutions): the direct
// solve and the continuation in the boundary rates stall; the coasting start (the torque-free
// motions from both ends, blended) converges. IPOPT's cost from the Hermite start is 547.642
// (docs/results/robustness_random.md); ours from the coasting start is lower (measured 425.61).
TEST(RandomSuite, StalledSpinningCaseConvergesFromTheCoastingStart) {
  const RandomCase c = robustness::randomCase(kSuiteSeed, 150);
  const PlanResult r = planManeuver(c.problem);
  ASSERT_EQ(r.termination, Termination::Converged) << c.label << ": " << r.message();
  // The trail: every class's solve (the class survey, on the requested grid) and the
  // continuation in the boundary rates stalled, the coasting start converged.
  const auto stage = [&r](AttemptStage s) {
    return std::find_if(r.attempts.begin(), r.attempts.end(),
                        [s](const Attempt& a) { return a.stage == s; });
  };
  const auto continuation = stage(AttemptStage::RateContinuation);
  const auto coasting = stage(AttemptStage::CoastingRetry);
  ASSERT_NE(continuation, r.attempts.end()) << r.extremal;
  ASSERT_NE(coasting, r.attempts.end()) << r.extremal;
  for (auto a = r.attempts.begin(); a != continuation; ++a) {
    EXPECT_EQ(a->stage, AttemptStage::ClassSurvey);
    EXPECT_EQ(a->termination, Termination::NotConverged);
  }
  EXPECT_NE(continuation->termination, Termination::Converged);
  EXPECT_EQ(coasting, continuation + 1);
  EXPECT_EQ(coasting->start, AttemptStart::Coasting);
  EXPECT_EQ(coasting->termination, Termination::Converged) << r.message();
  EXPECT_LE(r.step_residual, measureStepResidual(c.problem, r.maneuver).tolerance);
  EXPECT_LE(r.max_residual, 1e-8) << r.message();  // relative first-order residual at the optimum
  EXPECT_LT(r.cost, 547.642) << c.label;
  std::printf("%s: %d iterations, %.2f s, cost %.10g\n", c.label.c_str(), r.iterations,
              r.solve_time_s, r.cost);
}

// The cheapest extremal (issues 19 and 30): the classes are enumerated, and a spinning class
// that needed more than 40 iterations is solved from more starts in that class, the cheapest
// kept, the others' costs reported in `extremal`. #192 (seed-like, T = 17.6 s, 1.9 / 1.3 rad/s):
// the nearest lift ends at 236.658, the other way round at IPOPT's 199.940
// (docs/results/robustness_random.md).
TEST(RandomSuite, SlowSpinningSolveKeepsTheCheapestOfMoreStarts) {
  const RandomCase c = robustness::randomCase(kSuiteSeed, 192);
  const PlanResult r = planManeuver(c.problem);
  ASSERT_EQ(r.termination, Termination::Converged) << c.label << ": " << r.message();
  const auto more = std::count_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) {
    return a.stage == AttemptStage::MoreStarts;
  });
  EXPECT_GE(more, 4) << r.extremal;
  EXPECT_EQ(
      std::count_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; }),
      1);
  EXPECT_EQ(r.extremal_summary.others.size() + 1, r.attempts.size());
  EXPECT_LE(r.cost, 199.9402466) << c.label << ": " << r.extremal;
  EXPECT_LE(r.step_residual, measureStepResidual(c.problem, r.maneuver).tolerance);
  std::printf("%s: cost %.10g, %d iterations; %s\n", c.label.c_str(), r.cost, r.iterations,
              r.extremal.c_str());
}

// Four cases where the first start's extremal was costlier than IPOPT's and one of the more
// starts reached one at least as cheap (docs/results/robustness_random.md; before the class
// survey: #86 on the requested grid directly, #176 from the coasting start, #80 with the line
// search, #160 by the inertia homotopy, each in the nearest lift's class). With the classes
// enumerated, the more starts search the kept class (and the nearest lift's when it converged
// slowly): the answer must still be at least as cheap as IPOPT's, and come from a more start or
// another class than the nearest lift's own solve.
TEST(RandomSuite, MoreStartsReachExtremalsAsCheapAsIpopts) {
  const struct {
    int index;
    double ipopt_cost;
  } cases[] = {{86, 53926.01728}, {176, 5681.932043}, {80, 1003.148954}, {160, 4224.575025}};
  for (const auto& expected : cases) {
    const RandomCase c = robustness::randomCase(kSuiteSeed, expected.index);
    const PlanResult r = planManeuver(c.problem);
    ASSERT_TRUE(r.converged()) << c.label << ": " << r.message();
    const auto kept =
        std::find_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; });
    ASSERT_NE(kept, r.attempts.end());
    const bool nearest_solve = kept->stage != AttemptStage::MoreStarts &&
                               !kept->homotopy.long_way && kept->homotopy.extra_revolutions == 0;
    EXPECT_FALSE(nearest_solve) << c.label << ": " << r.extremal;
    EXPECT_TRUE(std::any_of(r.attempts.begin(), r.attempts.end(),
                            [](const Attempt& a) { return a.stage == AttemptStage::MoreStarts; }))
        << c.label << ": " << r.extremal;
    EXPECT_LE(r.cost, expected.ipopt_cost * (1 + 1e-8)) << c.label << ": " << r.extremal;
    EXPECT_LE(r.step_residual, measureStepResidual(c.problem, r.maneuver).tolerance);
    EXPECT_LE(r.max_residual, 1e-8) << c.label << ": " << r.message();
    std::printf("%s: cost %.10g, %d iterations, kept %s from %s\n", c.label.c_str(), r.cost,
                r.iterations, attemptStageName(kept->stage).c_str(),
                attemptStartName(kept->start).c_str());
  }
}
