// Anytime plans: a solve stopped by its time budget or by its caller (TimedOut, Cancelled) returns
// the plan it had reached, on the requested grid, with the figures that judge it. Every iterate of
// the reduced formulation is a maneuver of the discrete dynamics with the boundary data, so the
// stopped plan must meet both (to round-off) while its optimality residual says it is no answer.
// The dynamics are checked here against the seed's equations (18) written out, not through the
// package's own residual (measureStepResidual), which is compared with them.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/verdict.hpp"
#include "support/paper_equations.hpp"

using namespace attitude_planner;

namespace {

PlanningProblem sceneProblem(const std::string& name, int N) {
  PlanningProblem p = loadScene(std::string(AP_SOURCE_DIR) + "/scenes/" + name).problem;
  p.steps = N;
  return p;
}

/// What every anytime plan of a paper-scheme attitude problem must be: N + 1 rows on SO(3), the
/// boundary data R_0, Ω_0, R_N, Ω_{N−1} of the request, the discrete dynamics to round-off, and the
/// figures that say how far it is from an answer (its optimality residual, measured, above the
/// tolerance; a stopped interior point's too).
void expectAnytimePlan(const PlanningProblem& p, const PlanResult& r, double tolerance) {
  const int N = p.steps;
  ASSERT_EQ(r.maneuver.steps(), N) << r.message();
  ASSERT_EQ(static_cast<int>(r.maneuver.attitude.size()), N + 1);
  for (int k = 0; k <= N; ++k) {
    ASSERT_LT(so3::orthogonalityError(r.maneuver.attitude[k]), 1e-12) << "R_" << k;
    ASSERT_NEAR(r.maneuver.attitude[k].determinant(), 1.0, 1e-12) << "R_" << k;
  }
  EXPECT_LT(so3::angleBetween(r.maneuver.attitude[0], p.initial_attitude), 1e-12);
  EXPECT_LT(so3::angleBetween(r.maneuver.attitude[N], p.final_attitude), 1e-12);
  EXPECT_LT((r.maneuver.angular_velocity[0] - p.initial_velocity).norm(), 1e-12);
  EXPECT_LT((r.maneuver.angular_velocity[N - 1] - p.final_velocity).norm(), 1e-12);
  EXPECT_LT(test_support::paperEquationMiss(p.inertia, r.maneuver), 1e-11) << r.message();
  // The package's own step residual, reported with the plan, agrees with the equations above.
  const StepResidual own = measureStepResidual(p, r.maneuver);
  EXPECT_LE(own.relative, own.tolerance);
  EXPECT_NEAR(r.step_residual, own.relative, 1e-15);
  // Not an answer, and its figures say so.
  EXPECT_FALSE(r.converged());
  EXPECT_TRUE(std::isfinite(r.max_residual)) << r.message();
  EXPECT_GT(r.max_residual, tolerance) << r.message();
  EXPECT_TRUE(std::isfinite(r.cost));
  EXPECT_GT(r.cost, 0.0);
  // Handed over without its open-loop replay (N implicit steps), and said so as data.
  EXPECT_FALSE(r.replay_measured);
  EXPECT_TRUE(std::isnan(r.replay_miss));
  EXPECT_TRUE(std::isnan(r.terminal_attitude_error));
  EXPECT_TRUE(std::isnan(r.terminal_velocity_error));
  EXPECT_TRUE(std::isnan(r.dynamics_residual));
}

/// Options whose callback stops the solve at its `stop_at`-th reported iteration: by refusing to go
/// on (Cancelled) or, with a budget, by outliving it (TimedOut at the next poll).
SolverOptions stoppedAt(int stop_at, double budget_s) {
  SolverOptions options;
  options.tolerance = 1e-300;  // never met: only the stop ends the solve
  options.max_iterations = 100000;
  options.time_budget_s = budget_s;
  options.on_iteration = [stop_at, budget_s](const IterationInfo& info) {
    if (info.iteration < stop_at) return true;
    if (budget_s <= 0.0) return false;  // cancelled by its caller
    std::this_thread::sleep_for(std::chrono::duration<double>(budget_s));
    return true;  // the budget is spent: the solve ends TimedOut
  };
  return options;
}

}  // namespace

TEST(AnytimePlan, TimedOutBeforeTheFirstIterationReturnsTheStartWithItsResiduals) {
  const PlanningProblem p = sceneProblem("rest_to_rest.yaml", 1024);
  SolverOptions options;
  options.time_budget_s = 1e-9;
  const PlanResult r = planManeuver(p, options);
  EXPECT_EQ(r.termination, Termination::TimedOut) << r.message();
  expectAnytimePlan(p, r, options.tolerance);
}

TEST(AnytimePlan, TimedOutAfterSomeIterationsReturnsTheIterateOnTheGroup) {
  for (int N : {32, 512}) {  // one grid; several levels (stopped on a coarser one at N = 512)
    const PlanningProblem p = sceneProblem("rest_to_rest.yaml", N);
    const SolverOptions options = stoppedAt(3, 0.2);
    const PlanResult r = planManeuver(p, options);
    EXPECT_EQ(r.termination, Termination::TimedOut) << N << ": " << r.message();
    expectAnytimePlan(p, r, 1e-10);
  }
}

TEST(AnytimePlan, CancelledReturnsTheIterateOnTheGroup) {
  for (int N : {32, 512}) {
    const PlanningProblem p = sceneProblem("rest_to_rest.yaml", N);
    const PlanResult r = planManeuver(p, stoppedAt(2, 0.0));
    EXPECT_EQ(r.termination, Termination::Cancelled) << N << ": " << r.message();
    expectAnytimePlan(p, r, 1e-10);
  }
}

TEST(AnytimePlan, StoppedUnderConstraintsReturnsTheIterateWithItsViolations) {
  // Stopped in the interior point (after the unconstrained optimum, which violates the cone, has
  // started it), and before it: either way a plan of the dynamics with the boundary data, its
  // constraint figures measured on it.
  const PlanningProblem p = sceneProblem("sun_keep_out.yaml", 128);
  SolverOptions probe;
  int newton_iterations = 0;
  probe.on_iteration = [&](const IterationInfo& info) {
    if (info.attempt.stage != AttemptStage::Constrained) newton_iterations = info.iteration;
    return info.attempt.stage != AttemptStage::Constrained;
  };
  ASSERT_EQ(planManeuver(p, probe).termination, Termination::Cancelled);
  ASSERT_GT(newton_iterations, 2);
  for (int stop_at : {2, newton_iterations + 3}) {
    const PlanResult r = planManeuver(p, stoppedAt(stop_at, 0.0));
    EXPECT_EQ(r.termination, Termination::Cancelled) << stop_at << ": " << r.message();
    expectAnytimePlan(p, r, 1e-10);
    ASSERT_EQ(r.constraints.size(), 1u) << stop_at;
    EXPECT_TRUE(std::isfinite(r.max_constraint_violation));
    EXPECT_GE(r.max_constraint_violation, 0.0);
    EXPECT_NEAR(r.max_constraint_violation, checkConstraints(p, r.maneuver).max_violation, 1e-15);
  }
}

TEST(AnytimePlan, OnlyAStoppedPlanIsHandedOverWithoutItsReplay) {
  // A converged plan (and one stopped short of its tolerance by the iteration limit) keeps its
  // replay figures, measured: only TimedOut and Cancelled skip the replay.
  const PlanningProblem p = sceneProblem("rest_to_rest.yaml", 64);
  const PlanResult converged = planManeuver(p, SolverOptions());
  ASSERT_TRUE(converged.converged()) << converged.message();
  EXPECT_TRUE(converged.replay_measured);
  EXPECT_TRUE(std::isfinite(converged.replay_miss));
  EXPECT_LT(converged.replay_miss, 1e-8);
  SolverOptions limited;
  limited.tolerance = 1e-300;
  limited.max_iterations = 2;
  const PlanResult not_converged = planManeuver(p, limited);
  ASSERT_EQ(not_converged.termination, Termination::NotConverged) << not_converged.message();
  EXPECT_TRUE(not_converged.replay_measured);
  EXPECT_TRUE(std::isfinite(not_converged.replay_miss));
}

TEST(AnytimePlan, ARefinementStoppedOnACoarseLevelHandsOverItsOwnIterate) {
  // The class survey ranks the classes on N = 16; the kept class is refined through 64, 256,
  // 1024 to 4096. Stopped inside a coarse level of that refinement (by its cancel or its budget),
  // the refinement's iterate is carried to the requested grid and is the plan: no other attempt
  // runs after the stop (before, the stopped refinement ended with no plan and the request's
  // class was carried through every level again, a second pass over the requested grid).
  const int N = 4096;
  const PlanningProblem p = sceneProblem("rest_to_rest.yaml", N);
  for (const double budget : {0.0, 0.2}) {
    SolverOptions options;
    options.tolerance = 1e-300;  // never met: only the stop ends the solve
    options.max_iterations = 100000;
    options.on_iteration = [budget](const IterationInfo& info) {
      const bool coarse_refinement =
          info.attempt.stage == AttemptStage::ClassRefine && info.steps > 16 && info.steps < N;
      if (!coarse_refinement) return true;
      if (budget <= 0.0) return false;  // cancelled by its caller
      std::this_thread::sleep_for(std::chrono::duration<double>(budget));
      return true;  // the budget is spent: the solve ends TimedOut at its next poll
    };
    options.time_budget_s = budget;
    const PlanResult r = planManeuver(p, options);
    EXPECT_EQ(r.termination, budget > 0.0 ? Termination::TimedOut : Termination::Cancelled)
        << r.message();
    expectAnytimePlan(p, r, 1e-10);
    ASSERT_FALSE(r.attempts.empty());
    // The kept attempt is a refinement the stop ended; the refinements run at once on the
    // machine's cores, so others the stop ended too may follow it in the trail, and nothing else.
    const auto kept =
        std::find_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; });
    ASSERT_NE(kept, r.attempts.end()) << r.message();
    for (auto a = kept; a != r.attempts.end(); ++a) {
      EXPECT_EQ(a->stage, AttemptStage::ClassRefine) << r.message();
      EXPECT_EQ(a->termination, r.termination) << r.message();
    }
    for (const Attempt& a : r.attempts) {
      EXPECT_NE(a.stage, AttemptStage::Solve)
          << "a second attempt ran after the stop: " << r.message();
    }
  }
}
