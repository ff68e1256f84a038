// Constraint health (analysis/constraint_health.hpp): the violation of each constraint against
// closed forms, the worst along a path, and the projection of a re-plan's start onto the
// constraints — the smallest turn (an independent check: no rotation by less moves R b by that
// much), and a body 2e-4 rad inside a keep-out cone that the planner refuses before and plans
// from after the projection.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "attitude_planner/analysis/constraint_health.hpp"
#include "attitude_planner/analysis/replanning.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

using namespace attitude_planner;

namespace {

/// A keep-out cone of half angle 0.5 rad about world x for body axis x.
PlanningConstraint sunCone() {
  return PlanningConstraint::keepOut(Vector3::UnitX(), Vector3::UnitX(), 0.5);
}

/// The attitude that points body x at `angle` from world x (a turn about world z).
Matrix3 pointingAt(double angle) {
  return so3::fromAxisAngle(Vector3::UnitZ(), angle);
}

}  // namespace

TEST(ConstraintViolation, MatchesClosedFormsForEachKind) {
  const Vector3 none = Vector3::Zero();
  // keep_out: R b at 0.3 rad from s, half angle 0.5: 0.2 rad past; at 0.7 rad: met.
  EXPECT_NEAR(constraintViolation(sunCone(), pointingAt(0.3), none, none), 0.2, 1e-12);
  EXPECT_EQ(constraintViolation(sunCone(), pointingAt(0.7), none, none), 0.0);
  // keep_in mirrors it; the margin does not count (the stated half angle does).
  PlanningConstraint keep_in = PlanningConstraint::keepIn(Vector3::UnitX(), Vector3::UnitX(), 0.5,
                                                          /*margin=*/0.1);
  EXPECT_NEAR(constraintViolation(keep_in, pointingAt(0.7), none, none), 0.2, 1e-12);
  EXPECT_EQ(constraintViolation(keep_in, pointingAt(0.45), none, none), 0.0);
  const PlanningConstraint rate = PlanningConstraint::maxAngularRate(0.1);
  EXPECT_NEAR(constraintViolation(rate, Matrix3::Identity(), Vector3(0.0, 0.3, 0.4), none), 0.4,
              1e-15);
  EXPECT_EQ(constraintViolation(rate, Matrix3::Identity(), Vector3(0.0, 0.06, 0.08), none), 0.0);
  const PlanningConstraint torque = PlanningConstraint::maxTorqueNorm(1.0);
  EXPECT_NEAR(constraintViolation(torque, Matrix3::Identity(), none, Vector3(2.0, 0.0, 0.0)), 1.0,
              1e-15);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NEAR(actuatorLimitViolation(Vector3(0.5, inf, 1.0), Vector3(-0.7, 9.0, 1.05)), 0.2, 1e-15);
  EXPECT_EQ(actuatorLimitViolation(Vector3(0.5, inf, 1.0), Vector3(0.5, 9.0, -1.0)), 0.0);
}

TEST(ConstraintHealth, KeepsTheWorstOfEachInTheDocumentedOrder) {
  ConstraintHealth health(Vector3(1.0, 1.0, 1.0),
                          {sunCone(), PlanningConstraint::maxAngularRate(0.1)});
  ASSERT_EQ(health.names(),
            (std::vector<std::string>{"actuator_limits", "keep_out", "max_angular_rate"}));
  health.observe(pointingAt(0.4), Vector3(0.0, 0.0, 0.05), Vector3(1.5, 0.0, 0.0));
  health.observe(pointingAt(0.45), Vector3(0.0, 0.0, 0.25), Vector3(0.0, 1.2, 0.0));
  health.observe(pointingAt(1.0), Vector3::Zero(), Vector3::Zero());
  EXPECT_EQ(health.observations(), 3);
  EXPECT_NEAR(health.worstViolations()[0], 0.5, 1e-15);
  EXPECT_NEAR(health.worstViolations()[1], 0.1, 1e-12);
  EXPECT_NEAR(health.worstViolations()[2], 0.15, 1e-15);
  // Without limits or constraints there is nothing to report.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(ConstraintHealth(Vector3::Constant(inf), {}).names().empty());
}

TEST(ProjectOntoConstraints, TurnsTheAttitudeByTheLeastAngleThatMeetsEachCone) {
  std::mt19937 rng(43);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 50; ++trial) {
    const Vector3 b = Vector3(normal(rng), normal(rng), normal(rng)).normalized();
    const Vector3 s = Vector3(normal(rng), normal(rng), normal(rng)).normalized();
    const bool keep_out = trial % 2 == 0;
    const double a = 0.3 + 0.02 * trial;
    const PlanningConstraint cone =
        keep_out ? PlanningConstraint::keepOut(b, s, a) : PlanningConstraint::keepIn(b, s, a);
    // A random attitude, then turned so that it is `past` inside (outside) the cone.
    const Matrix3 R0 = so3::exp(Vector3(normal(rng), normal(rng), normal(rng)));
    const double past = 1e-5 * (1 + trial);
    const double angle = std::acos(std::clamp(s.dot(R0 * b), -1.0, 1.0));
    const double target = keep_out ? a - past : a + past;
    const Vector3 axis = s.cross(R0 * b).normalized();
    const Matrix3 R = so3::exp(Vector3((target - angle) * axis)) * R0;
    ASSERT_NEAR(-coneMargin(cone, R), past, 1e-10);
    const ProjectedStart out =
        projectOntoConstraints({R, Vector3(0.01, 0.0, 0.0)}, {cone}, ProjectionTolerance());
    ASSERT_TRUE(out.feasible) << out.refusal;
    EXPECT_GE(coneMargin(cone, out.state.attitude), 0.0);
    EXPECT_LT(coneMargin(cone, out.state.attitude), 1e-8);
    // No smaller turn can do it: a rotation by φ moves the direction R b by at most φ.
    EXPECT_NEAR(out.moved, past + kProjectionClearance, 1e-10);
    EXPECT_EQ(out.state.angular_velocity, Vector3(0.01, 0.0, 0.0));
  }
}

TEST(ProjectOntoConstraints, RefusesAStartFartherThanTheToleranceAndScalesTheRate) {
  const RigidBodyState inside{pointingAt(0.45), Vector3::Zero()};  // 0.05 rad inside
  const ProjectedStart refused = projectOntoConstraints(inside, {sunCone()}, ProjectionTolerance());
  EXPECT_FALSE(refused.feasible);
  EXPECT_NE(refused.refusal.find("constraints[0] (keep_out"), std::string::npos) << refused.refusal;
  EXPECT_NE(refused.refusal.find("0.01 rad"), std::string::npos) << refused.refusal;
  EXPECT_TRUE(refused.state.attitude.isApprox(inside.attitude));
  ProjectionTolerance wide;
  wide.cone_angle = 0.1;
  EXPECT_TRUE(projectOntoConstraints(inside, {sunCone()}, wide).feasible);

  const PlanningConstraint rate = PlanningConstraint::maxAngularRate(0.1);
  const Vector3 fast(0.0, 0.0605, 0.0802);  // |Ω| = 0.10046: 0.46 % past
  const ProjectedStart slowed =
      projectOntoConstraints({Matrix3::Identity(), fast}, {rate}, ProjectionTolerance());
  ASSERT_TRUE(slowed.feasible);
  EXPECT_LE(slowed.state.angular_velocity.norm(), 0.1);
  EXPECT_NEAR(slowed.state.angular_velocity.norm(), 0.1, 1e-9);
  EXPECT_NEAR(slowed.state.angular_velocity.normalized().dot(fast.normalized()), 1.0, 1e-15);
  EXPECT_FALSE(projectOntoConstraints({Matrix3::Identity(), 1.02 * fast / fast.norm() * 0.1},
                                      {rate}, ProjectionTolerance())
                   .feasible);
}

TEST(ProjectOntoConstraints, LetsThePlannerReplanABodyJustInsideAKeepOutCone) {
  // scenes/sun_keep_out.yaml: the plan rides the cone; a tracked body 2e-4 rad inside it at a
  // node where the cone is active is refused as a start, and planned from once projected.
  const Scene scene = loadScene(std::string(AP_SOURCE_DIR) + "/scenes/sun_keep_out.yaml");
  const PlanResult plan = planManeuver(scene.problem);
  ASSERT_TRUE(plan.converged()) << plan.message();
  const PlanningConstraint& cone = scene.problem.constraints.at(0);
  int k = 1;  // the node nearest the cone
  for (int i = 1; i < plan.maneuver.steps() / 2; ++i) {
    if (coneMargin(cone, plan.maneuver.attitude[i]) < coneMargin(cone, plan.maneuver.attitude[k]))
      k = i;
  }
  ASSERT_LT(coneMargin(cone, plan.maneuver.attitude[k]), 1e-3);  // the cone is active there
  const Matrix3& R_k = plan.maneuver.attitude[k];
  const Vector3 pointing = R_k * cone.body_axis;
  const double into = coneMargin(cone, R_k) + 2e-4;  // 2e-4 rad inside
  const Matrix3 R =
      so3::exp(Vector3(-into * cone.world_direction.cross(pointing).normalized())) * R_k;
  ASSERT_NEAR(coneMargin(cone, R), -2e-4, 1e-9);
  const Vector3& W = plan.maneuver.angular_velocity[k];
  EXPECT_THROW(validateProblem(remainderProblem(scene.problem, k, R, W)), InvalidInput);

  // The paper scheme fixes R_1 = R_0 exp(hΩ_0) by the start: projecting R_0 alone leaves the
  // first step inside (the planner: "violated ... at k = 1, an attitude the boundary velocities
  // fix"), so the projection moves Ω_0 too.
  const double h = plan.maneuver.time_step;
  ASSERT_TRUE(firstStepFixedByStart(scene.problem.scheme));
  const ProjectedStart start_only =
      projectOntoConstraints({R, W}, scene.problem.constraints, ProjectionTolerance());
  ASSERT_TRUE(start_only.feasible) << start_only.refusal;
  const Matrix3 R1_only =
      start_only.state.attitude * so3::exp(Vector3(h * start_only.state.angular_velocity));
  EXPECT_LT(coneMargin(cone, R1_only), 0.0);  // else this case does not test the first step
  const ProjectedStart start =
      projectOntoConstraints({R, W}, scene.problem.constraints, ProjectionTolerance(), h);
  ASSERT_TRUE(start.feasible) << start.refusal;
  EXPECT_GE(coneMargin(cone, start.state.attitude), 0.0);
  EXPECT_GE(
      coneMargin(cone, start.state.attitude * so3::exp(Vector3(h * start.state.angular_velocity))),
      0.0);
  const PlanningProblem rest =
      remainderProblem(scene.problem, k, start.state.attitude, start.state.angular_velocity);
  const Maneuver guess = remainderOf(plan.maneuver, k);
  SolverOptions options;
  options.warm_start = &guess;
  const PlanResult replanned = planManeuver(rest, options);
  EXPECT_TRUE(replanned.converged()) << replanned.message();
  EXPECT_LE(replanned.max_constraint_violation, 1e-6);
}
