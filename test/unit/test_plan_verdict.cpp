// A plan is judged by what it is — first-order optimality and the discrete
// equations of motion step by step, relative to the problem's own scales — and the open-loop
// replay of its torques is a reported sensitivity (replay_miss), not a verdict.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <utility>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "planning/problem/verdict.hpp"
#include "support/robustness_cases.hpp"

using namespace attitude_planner;

namespace {

const Matrix3 kSeedInertia = robustness::seedInertia();

/// π about x, rest to rest, with the seed's J (the T = 1e-9 s service request).
PlanningProblem piAboutX(double T, int N) {
  PlanningProblem p;
  p.inertia = kSeedInertia;
  p.allow_nonphysical_inertia = true;
  p.duration = T;
  p.steps = N;
  p.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), M_PI);
  return p;
}

/// A problem with spinning ends, 1.3 rad about (1, 2, 3)/√14: the shape kept while T and J scale.
PlanningProblem spinningShape(double time_scale, double inertia_scale, SchemeKind scheme) {
  PlanningProblem p;
  p.inertia = inertia_scale * kSeedInertia;
  p.allow_nonphysical_inertia = true;
  p.scheme = scheme;
  p.duration = 12.8 * time_scale;
  p.steps = 128;
  p.initial_velocity = Vector3(0.0, 0.2, 0.6) / time_scale;
  p.final_velocity = Vector3(0.4, -0.1, 0.0) / time_scale;
  p.final_attitude = so3::fromAxisAngle(Vector3(1, 2, 3).normalized(), 1.3);
  return p;
}

/// Seeded: a spin near the intermediate axis of a random anisotropic body, spun up over 40-60 s
/// (unstable: its open-loop replay parts from the plan exponentially).
PlanningProblem unstableSpin(std::mt19937_64* rng, SchemeKind scheme) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PlanningProblem p;
  p.inertia = Vector3(0.2 + 0.3 * u(*rng), 2.0 + u(*rng), 3.0 + 2.0 * u(*rng)).asDiagonal();
  p.allow_nonphysical_inertia = true;
  p.scheme = scheme;
  p.duration = 40.0 + 20.0 * u(*rng);
  p.steps = 400;
  const double w = 1.0 + u(*rng);
  p.initial_velocity = Vector3(0.0, w, 0.0);
  p.final_velocity = Vector3(0.0, 3.0 * w, 0.1);
  p.final_attitude = so3::exp(Vector3(0.3 * u(*rng), 1.0, 0.2));
  return p;
}

/// The plan with its step k moved onto another root of the step's momentum map (the same
/// momentum, far from the plan's step; found from the step's angle reflected about pi/2), the
/// attitudes after it carried along. Empty where Newton finds no such root from there.
std::optional<Maneuver> withStepOnAnotherRoot(const PlanningProblem& p, const Maneuver& plan,
                                              int k) {
  const DiscreteScheme scheme(p.scheme, p.inertia, plan.time_step);
  const Matrix3 F = plan.attitude[k].transpose() * plan.attitude[k + 1];
  const Vector3 phi = so3::log(F);
  StepSolveReport report;
  const Matrix3 other =
      scheme.solveStep(scheme.momentum<double>(F),
                       so3::exp(Vector3((M_PI - phi.norm()) * phi.normalized())), &report);
  if (!report.converged || so3::angleBetween(other, F) < 0.1) return std::nullopt;
  Maneuver moved = plan;
  const Matrix3 turn = plan.attitude[k] * other * F.transpose() * plan.attitude[k].transpose();
  for (int j = k + 1; j <= plan.steps(); ++j) moved.attitude[j] = turn * plan.attitude[j];
  return moved;
}

/// A variational plan that meets its discrete equations step by step with step k on another
/// root of its momentum map: the plan up to k, step k moved (withStepOnAnotherRoot), then the
/// scheme's recursion c_{j+1} = F_jᵀ c_j + h τ_{j+1} under the plan's torques with each step
/// solved from the last, and the problem ending where that plan ends. Empty where no other root
/// is found.
std::optional<std::pair<PlanningProblem, Maneuver>> consistentPlanOnAnotherRoot(
    const PlanningProblem& p, const Maneuver& plan, int k) {
  std::optional<Maneuver> moved = withStepOnAnotherRoot(p, plan, k);
  if (!moved) return std::nullopt;
  Maneuver& m = *moved;
  const int N = m.steps();
  const double h = m.time_step;
  const DiscreteScheme scheme(p.scheme, p.inertia, h);
  Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
  Vector3 c = p.inertia * m.angular_velocity[k];  // variational: c_k = J Ω_k
  for (int j = k + 1; j < N; ++j) {
    c = F.transpose() * c + h * m.torque[j];
    m.angular_velocity[j] = p.inertia.ldlt().solve(c);
    StepSolveReport report;
    F = scheme.solveStep(c, F, &report);
    if (!report.converged) return std::nullopt;
    m.attitude[j + 1] = m.attitude[j] * F;
  }
  PlanningProblem q = p;
  q.final_attitude = m.attitude[N];
  q.final_velocity = m.angular_velocity[N - 1];
  return std::make_pair(q, m);
}

}  // namespace

TEST(PlanVerdict, AConvergedPlanWhoseOpenLoopReplayFailsIsJudgedByItsStepsReplayed) {
  // Seeded unstable spins: the open-loop replay of a converged plan parts from it (round-off
  // grows like e^{λt}) and may reach a step with no root: a sensitivity (replay_miss +inf, the
  // verdict kept) where every step replayed from the plan's own state lands on the plan's step.
  std::mt19937_64 rng(4547);
  int parted = 0;
  for (int i = 0; i < 3; ++i) {
    const PlanningProblem p = unstableSpin(&rng, SchemeKind::Paper);
    const PlanResult r = planManeuver(p);
    SCOPED_TRACE("spin " + std::to_string(i) + ": " + r.message());
    if (!r.converged()) continue;
    const StepwiseReplay stepwise = replayStepByStep(p, r.maneuver);
    EXPECT_TRUE(stepwise.reproduces())
        << stepwise.worst_angle << " rad at k = " << stepwise.worst_step;
    if (r.replay_miss > 1.0) ++parted;  // the open-loop replay ends a radian off
    PlanResult judged = r;
    judgeFailedReplay(p, "no implicit step", &judged);
    EXPECT_EQ(judged.termination, Termination::Converged);
    EXPECT_TRUE(std::isinf(judged.replay_miss));
    EXPECT_TRUE(judged.maneuver.attitude == r.maneuver.attitude);
  }
  EXPECT_GE(parted, 2);  // the draw exercises the case (else the assertions say little)
}

TEST(PlanVerdict, AStepOnAnotherRootOfItsMomentumMapIsNotReplayedSoNotConverged) {
  // The variational momentum map folds (sin θ): a step moved onto the other root of its own
  // momentum still meets the step's kinematics, but the replay's solve from the plan's state
  // does not land on it, so a converged plan with such a step whose open-loop replay fails is
  // not converged (never step_too_large: the request's N was not the cause).
  const PlanningProblem p = spinningShape(1.0, 1.0, SchemeKind::Variational);
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_TRUE(replayStepByStep(p, r.maneuver).reproduces());
  int moved_steps = 0;
  for (int k : {1, p.steps / 2, p.steps - 2}) {
    const std::optional<Maneuver> moved = withStepOnAnotherRoot(p, r.maneuver, k);
    if (!moved) continue;
    ++moved_steps;
    const StepwiseReplay off = replayStepByStep(p, *moved);
    EXPECT_FALSE(off.reproduces());
    EXPECT_EQ(off.worst_step, k);
    PlanResult judged = r;
    judged.maneuver = *moved;
    judgeFailedReplay(p, "no implicit step", &judged);
    EXPECT_EQ(judged.termination, Termination::NotConverged);
    EXPECT_TRUE(std::isinf(judged.replay_miss));
  }
  EXPECT_GE(moved_steps, 1);
}

TEST(PlanVerdict, AStoppedPlanProvesItsDurationOnlyWithinItsBoundsAndOnItsEnds) {
  // The one rule for "a plan at T exists" (provesFeasible): a stopped solve's iterate counts when
  // it meets the discrete equations, its ends and every bound within the tolerances
  // planInconsistency names; just inside a bound it counts, just outside or off an end it does
  // not, in every scheme with discrete equations.
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    SCOPED_TRACE(schemeName(scheme));
    const PlanningProblem p = spinningShape(1.0, 1.0, scheme);
    const PlanResult converged = planManeuver(p);
    ASSERT_TRUE(converged.converged()) << converged.message();
    EXPECT_TRUE(provesFeasible(p, converged));
    PlanResult stopped = converged;
    stopped.termination = Termination::NotConverged;
    EXPECT_TRUE(provesFeasible(p, stopped));
    double peak = 0.0;
    for (const Vector3& t : stopped.maneuver.torque) peak = std::max(peak, t.norm());
    const auto bounded = [&](double relative_violation) {
      PlanningProblem b = p;
      b.constraints = {PlanningConstraint::maxTorqueNorm(peak / (1 + relative_violation))};
      return b;
    };
    EXPECT_TRUE(provesFeasible(bounded(0.0), stopped));  // the bound active at the peak
    EXPECT_TRUE(provesFeasible(bounded(0.1 * kNodeConstraintTolerance), stopped));
    EXPECT_FALSE(provesFeasible(bounded(10 * kNodeConstraintTolerance), stopped));
    const double tolerance = measureStepResidual(p, stopped.maneuver).tolerance;
    const auto moved_end = [&](double angle) {
      PlanningProblem m = p;
      m.final_attitude = p.final_attitude * so3::exp(Vector3(angle, 0.0, 0.0));
      return m;
    };
    EXPECT_TRUE(provesFeasible(moved_end(0.1 * tolerance), stopped));
    EXPECT_FALSE(provesFeasible(moved_end(10 * tolerance), stopped));
    PlanningProblem faster_start = p;
    faster_start.initial_velocity *= 1 + 1e3 * tolerance;
    EXPECT_FALSE(provesFeasible(faster_start, stopped));
    // No plan at T: another end, another grid, or a scheme with no discrete equations of its own.
    for (Termination t : {Termination::Infeasible, Termination::TimedOut, Termination::Cancelled}) {
      PlanResult other = stopped;
      other.termination = t;
      EXPECT_FALSE(provesFeasible(p, other)) << terminationName(t);
    }
    PlanningProblem finer = p;
    finer.steps = 2 * p.steps;
    EXPECT_FALSE(provesFeasible(finer, stopped));
    PlanningProblem fourth = p;
    fourth.scheme = SchemeKind::FourthOrder;
    EXPECT_FALSE(provesFeasible(fourth, stopped));
  }
}

TEST(PlanVerdict, TheHardCasesJudgeAPartedReplayByThePlansOwnEndsAndSteps) {
  // The hard cases' rule "converged => terminal error <= 1e-9" reads the open-loop replay's
  // ends. Where that replay parted (judgeFailedReplay: replay_miss +inf, its ends not measured)
  // the plan's own ends and steps are checked instead: a consistent plan passes, the same plan
  // off its end or with a step on another root fails.
  const PlanningProblem p = spinningShape(1.0, 1.0, SchemeKind::Variational);
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  robustness::Recorder measured;
  measured.checkConverged("replayed", p, r, 1e-9);
  EXPECT_EQ(measured.outcome().passed(),
            std::max(r.terminal_attitude_error, r.terminal_velocity_error) <= 1e-9)
      << measured.outcome().failures();
  PlanResult parted = r;
  judgeFailedReplay(p, "no implicit step", &parted);
  ASSERT_EQ(parted.termination, Termination::Converged);
  ASSERT_TRUE(std::isinf(parted.replay_miss));
  ASSERT_TRUE(std::isnan(parted.terminal_attitude_error));
  robustness::Recorder accepted;
  accepted.checkConverged("parted", p, parted, 1e-9);
  EXPECT_TRUE(accepted.outcome().passed()) << accepted.outcome().failures();
  PlanningProblem moved_end = p;
  moved_end.final_attitude = p.final_attitude * so3::exp(Vector3(1e-6, 0.0, 0.0));
  robustness::Recorder off_end;
  off_end.checkConverged("parted", moved_end, parted, 1e-9);
  EXPECT_FALSE(off_end.outcome().passed());
  std::optional<Maneuver> other_root;
  for (int k : {1, p.steps / 2, p.steps - 2}) {
    if (!other_root) other_root = withStepOnAnotherRoot(p, r.maneuver, k);
  }
  ASSERT_TRUE(other_root.has_value());
  PlanResult off_root = parted;
  off_root.maneuver = *other_root;
  robustness::Recorder rejected;
  rejected.checkConverged("parted", p, off_root, 1e-9);
  EXPECT_FALSE(rejected.outcome().passed());
}

TEST(PlanVerdict, APlanWithAStepOnAnotherRootIsNotAccepted) {
  // Newton can converge to a plan that meets the discrete equations with a step on another root
  // of the step's momentum map (past its fold): not the motion the scheme integrates. The
  // acceptance (planInconsistency) replays each step from the plan's own state and refuses it,
  // so it is neither converged nor a plan proving its duration.
  const PlanningProblem p = spinningShape(1.0, 1.0, SchemeKind::Variational);
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_EQ(planInconsistency(p, r, true), "");
  int built = 0;
  for (int k : {1, p.steps / 2, p.steps - 2}) {
    const auto other = consistentPlanOnAnotherRoot(p, r.maneuver, k);
    if (!other) continue;
    ++built;
    const PlanningProblem& q = other->first;
    PlanResult off = r;
    off.maneuver = other->second;
    const StepResidual residual = measureStepResidual(q, off.maneuver);
    EXPECT_LE(residual.relative, residual.tolerance) << "k = " << k;  // its equations hold
    const StepwiseReplay stepwise = replayStepByStep(q, off.maneuver);
    EXPECT_FALSE(stepwise.reproduces());
    EXPECT_EQ(stepwise.worst_step, k);
    EXPECT_NE(planInconsistency(q, off, false), "") << "k = " << k;
    off.termination = Termination::NotConverged;
    EXPECT_FALSE(provesFeasible(q, off)) << "k = " << k;
  }
  EXPECT_GE(built, 1);
}

TEST(PlanVerdict, NanosecondHorizonPiAboutXConverges) {
  // Rates of ~3e9 rad/s: the absolute 1e-9 replay threshold refused this optimum before.
  const PlanningProblem p = piAboutX(1e-9, 64);
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_LE(r.step_residual, measureStepResidual(p, r.maneuver).tolerance);
  EXPECT_LE(r.max_residual, 1e-9);
  EXPECT_TRUE(std::isfinite(r.replay_miss));
  // The same shape at T = 12.8 s costs (12.8/1e-9)⁴ less: τ ∝ 1/T².
  const PlanResult slow = planManeuver(piAboutX(12.8, 64));
  ASSERT_TRUE(slow.converged()) << slow.message();
  EXPECT_NEAR(r.cost * std::pow(1e-9 / 12.8, 4), slow.cost, 1e-9 * slow.cost);
  std::printf("T = 1e-9 s: %d iterations, step residual %.2e, replay miss %.2e rad\n", r.iterations,
              r.step_residual, r.replay_miss);
}

TEST(PlanVerdict, VerdictsAreInvariantUnderTimeAndInertiaScaling) {
  // One class's solve: the further starts of the class survey take iteration counts that differ
  // by round-off in their paths (test_newton_solver's EveryThresholdIsScaleFree).
  SolverOptions one_class;
  one_class.enumerate_classes = false;
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    const PlanResult base = planManeuver(spinningShape(1.0, 1.0, scheme), one_class);
    ASSERT_TRUE(base.converged()) << base.message();
    struct Scaling {
      double time, inertia;
    };
    for (const Scaling s : {Scaling{1e-6, 1.0}, Scaling{1e3, 1.0}, Scaling{1.0, 1e4},
                            Scaling{1e-6, 1e4}, Scaling{1e3, 1e4}}) {
      const PlanningProblem p = spinningShape(s.time, s.inertia, scheme);
      const PlanResult r = planManeuver(p, one_class);
      SCOPED_TRACE(schemeName(scheme) + ", T x " + std::to_string(s.time) + ", J x " +
                   std::to_string(s.inertia));
      EXPECT_EQ(r.termination, base.termination) << r.message();
      EXPECT_EQ(r.iterations, base.iterations);
      // τ ∝ J/T², so the cost ∝ J²/T⁴: equal to round-off once scaled back.
      const double cost_scale = s.inertia * s.inertia / std::pow(s.time, 4);
      EXPECT_NEAR(r.cost / cost_scale, base.cost, 1e-9 * base.cost);
      // The relative figures are the same numbers, up to round-off.
      EXPECT_NEAR(r.max_residual, base.max_residual, 1e-9);
      EXPECT_NEAR(r.newton_decrement, base.newton_decrement, 1e-9);
      EXPECT_NEAR(r.step_residual, base.step_residual, 1e-12);
      EXPECT_LE(r.step_residual, measureStepResidual(p, r.maneuver).tolerance);
      // The replay miss in radians: T·ΔΩ is scale-free too.
      EXPECT_NEAR(r.replay_miss, base.replay_miss, 1e-9);
    }
  }
}

TEST(PlanVerdict, UnstableOptimumConvergesAndReportsItsReplayMiss) {
  // Intermediate-axis spin over 60 s (J = diag(1, 2, 3), λ = 0.577 s⁻¹, e^{λT} ≈ 1e15): the
  // optimum is a consistent plan, but its torques replayed open-loop miss by ~eps·e^{λT}.
  PlanningProblem p;
  p.inertia = Vector3(1, 2, 3).asDiagonal();
  p.duration = 60.0;
  p.steps = 600;
  p.initial_velocity = Vector3(0, 1, 0);
  p.final_velocity = Vector3(0, 1, 0);
  p.final_attitude = so3::exp(Vector3(0, 60.0, 0)) * so3::exp(Vector3(0.2, 0, 0));
  const PlanResult r = planManeuver(p);
  ASSERT_EQ(r.termination, Termination::Converged) << r.message();
  EXPECT_LE(r.max_residual, 1e-9);
  EXPECT_LE(r.step_residual, measureStepResidual(p, r.maneuver).tolerance);
  // The returned plan itself ends on the target; the replay does not.
  EXPECT_LE(so3::angleBetween(r.maneuver.attitude[p.steps], p.final_attitude), 1e-9);
  EXPECT_GT(r.replay_miss, 1e-6);
  EXPECT_DOUBLE_EQ(r.replay_miss,
                   std::max(r.terminal_attitude_error, p.duration * r.terminal_velocity_error));
  std::printf("intermediate-axis spin, T = 60 s: replay miss %.2e rad, step residual %.2e\n",
              r.replay_miss, r.step_residual);
}

TEST(PlanVerdict, StepResidualDetectsAnInconsistentPlan) {
  // The check can fail: a converged plan with one torque (1e-3 of the largest), one velocity
  // (1e-4 rad/s) or the end attitude (1e-6 rad) disturbed no longer satisfies the equations.
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    const PlanningProblem p = spinningShape(1.0, 1.0, scheme);
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    const StepResidual clean = measureStepResidual(p, r.maneuver);
    EXPECT_LE(clean.relative, clean.tolerance);
    double max_torque = 0.0;
    for (const Vector3& t : r.maneuver.torque) max_torque = std::max(max_torque, t.norm());
    Maneuver torque = r.maneuver;
    torque.torque[40].x() += 1e-3 * max_torque;
    EXPECT_GT(measureStepResidual(p, torque).relative, 100 * clean.tolerance);
    Maneuver velocity = r.maneuver;
    velocity.angular_velocity[70].y() += 1e-4;  // rad/s, rates ~0.6 rad/s
    EXPECT_GT(measureStepResidual(p, velocity).relative, 100 * clean.tolerance);
    Maneuver end = r.maneuver;
    end.attitude[p.steps] = end.attitude[p.steps] * so3::exp(Vector3(1e-6, 0, 0));
    EXPECT_GT(measureStepResidual(p, end).relative, 100 * clean.tolerance);
  }
}

TEST(PlanVerdict, ZeroManeuverHasZeroResidual) {
  PlanningProblem p = piAboutX(12.8, 32);
  p.final_attitude = Matrix3::Identity();
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_EQ(r.step_residual, 0.0);
  EXPECT_EQ(r.replay_miss, 0.0);
}
