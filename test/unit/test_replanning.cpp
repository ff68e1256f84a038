// Receding-horizon re-planning (analysis/replanning.hpp), the tracker's `replan` mode without ROS:
// the effects' clock moved on, the remainder problem, the closed loop continued across an
// adoption (state and noise stream), and re-planning under scenes/disturbed_replay.yaml.
#include <gtest/gtest.h>

#include <cmath>

#include "attitude_planner/analysis/replanning.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

using namespace attitude_planner;

namespace {

Scene disturbedScene() {
  return loadScene(std::string(AP_SOURCE_DIR) + "/scenes/disturbed_replay.yaml");
}

/// scenes/disturbed_replay.yaml and its plan (the gravity gradient and the disturbance planned
/// for, the torque noise not).
struct DisturbedPlan {
  Scene scene = loadScene(std::string(AP_SOURCE_DIR) + "/scenes/disturbed_replay.yaml");
  PlanResult plan = planManeuver(scene.problem);
  Matrix3 J = scene.problem.inertia;
  std::shared_ptr<const EffectModel> effects = plannableEffects(scene.effects, J);
};

}  // namespace

TEST(EffectModelTimeShifted, ReadsTheEffectsLaterByTheOffsetWithTheirNames) {
  const Scene scene = disturbedScene();
  const std::shared_ptr<const EffectModel> model =
      plannableEffects(scene.effects, scene.problem.inertia);
  const EffectModel shifted = model->timeShifted(123.0);
  EXPECT_EQ(shifted.names(), model->names());
  const Matrix3 R = so3::fromAxisAngle(Vector3(1.0, 2.0, -0.5).normalized(), 0.7);
  for (double t : {0.0, 10.0, 400.0}) {
    EXPECT_LT((shifted.torque(R, t) - model->torque(R, t + 123.0)).norm(), 1e-18);
    EXPECT_LT((shifted.jacobian(R, t) - model->jacobian(R, t + 123.0)).norm(), 1e-18);
  }
  // The gravity gradient's orbit moves: the shift changes the torque (else this test is void).
  EXPECT_GT((shifted.torque(R, 0.0) - model->torque(R, 0.0)).norm(), 1e-6);
}

TEST(RemainderProblem, KeepsTheGridTargetAndConstraintsFromTheState) {
  Scene scene = disturbedScene();
  const PlanningProblem& p = scene.problem;  // N = 300, T = 600 s
  const Matrix3 R = so3::fromAxisAngle(Vector3::UnitZ(), 0.4);
  const Vector3 W(1e-4, -2e-4, 3e-3);
  const PlanningProblem rest = remainderProblem(p, 100, R, W);
  EXPECT_EQ(rest.steps, 200);
  EXPECT_DOUBLE_EQ(rest.duration, 400.0);
  EXPECT_TRUE(rest.initial_attitude.isApprox(R));
  EXPECT_TRUE(rest.initial_velocity.isApprox(W));
  EXPECT_TRUE(rest.final_attitude.isApprox(p.final_attitude));
  EXPECT_EQ(rest.scheme, p.scheme);
  ASSERT_TRUE(rest.effects);
  EXPECT_LT((rest.effects->torque(R, 5.0) - p.effects->torque(R, 205.0)).norm(), 1e-18);
  EXPECT_NO_THROW(remainderProblem(p, 300 - kMinSteps, R, W));
  EXPECT_THROW(remainderProblem(p, 300 - kMinSteps + 1, R, W), InvalidInput);
}

// Adopting the plan's own rest at node k changes nothing: the body continues from its state at
// t_k with the noise stream where it was, under the effects at the right time. So the segmented
// run is the single closed-loop run (to round-off), which is what makes re-plans comparable.
TEST(RecedingHorizonRun, AdoptingThePlansOwnRestContinuesTheSameClosedLoop) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const auto& [scene, plan, J, effects] = disturbed;
  const SchemeKind scheme = scene.problem.scheme;
  const Maneuver& nodes = plan.maneuver;
  const ManeuverInterpolation reference(nodes, scheme, J, effects.get());
  Actuation actuation = actuationOf(scene.effects);  // with noise: the stream must continue
  const TrackingRun single = simulateTracking(
      reference, nodes.attitude[0], nodes.angular_velocity[0], effects.get(), &actuation, {});

  RecedingHorizonRun run(nodes, scheme, J, effects, actuationOf(scene.effects), {});
  for (int k : {90, 200}) run.adopt(run.planRemainderAt(k), k, k);
  EXPECT_EQ(run.adoptions(), 2);
  const ManeuverInterpolation single_body(single.actual, scheme, J, nullptr, TorqueHold::StepStart);
  const double T = reference.duration();
  for (double t : {0.0, 101.0, 250.0, 453.0, T}) {
    const ManeuverSample body = run.bodyAt(t);
    const ManeuverSample expected = single_body.at(t);
    EXPECT_LT(so3::angleBetween(body.attitude, expected.attitude), 1e-9) << "t = " << t;
    EXPECT_LT((body.angular_velocity - expected.angular_velocity).norm(), 1e-11) << "t = " << t;
  }
  const ManeuverSample at_node = run.bodyAtNode(200);  // the adopted segment's own first row
  EXPECT_LT(so3::angleBetween(at_node.attitude, single.actual.attitude[200 * single.substeps]),
            1e-9);
  EXPECT_NEAR(run.effort(), single.effort, 1e-9 * single.effort);
  EXPECT_NEAR(run.maxAttitudeError(), single.max_attitude_error, 1e-9);
  EXPECT_THROW(run.adopt(run.planRemainderAt(100), 100, 99), InvalidInput);  // before its node
  EXPECT_THROW(run.adopt(remainderOf(nodes, 100), 50, 60), InvalidInput);    // wrong grid
}

// Re-planned every 100 s under the scene's noise (the plan cannot know it), each re-plan from
// the body's state by planManeuver warm-started with the rest of the plan in force and flown
// one node later (what the tracker does through the service): every re-plan converges, and the
// body lands far better than open loop, as the law alone does.
TEST(RecedingHorizonRun, ReplannedUnderNoiseLandsAsTheLawDoes) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const auto& [scene, plan, J, effects] = disturbed;
  const SchemeKind scheme = scene.problem.scheme;
  const Maneuver& nodes = plan.maneuver;
  const int N = nodes.steps();

  Actuation open_loop = actuationOf(scene.effects);
  SimulationInput input;
  input.initial_attitude = nodes.attitude[0];
  input.initial_velocity = nodes.angular_velocity[0];
  input.torque = nodes.torque;
  input.effects = effects.get();
  input.actuation = &open_loop;
  const Maneuver replayed = replayPlan(scheme, J, nodes.time_step, input);
  const double replay_miss = so3::angleBetween(replayed.attitude.back(), nodes.attitude.back());

  RecedingHorizonRun run(nodes, scheme, J, effects, actuationOf(scene.effects), {});
  for (int k = 50; N - k >= kMinSteps; k += 50) {
    const ManeuverSample body = run.bodyAtNode(k);
    const PlanningProblem rest =
        remainderProblem(scene.problem, k, body.attitude, body.angular_velocity);
    const Maneuver guess = run.planRemainderAt(k);
    SolverOptions options;
    options.warm_start = &guess;
    const PlanResult replan = planManeuver(rest, options);
    ASSERT_TRUE(replan.converged()) << "from node " << k << ": " << replan.message();
    // The body is near the plan: the rest re-planned from it starts where the body is.
    EXPECT_TRUE(replan.maneuver.attitude.front().isApprox(body.attitude, 1e-12));
    run.adopt(replan.maneuver, k, k + 1);
  }
  EXPECT_EQ(run.adoptions(), 5);
  const ManeuverSample end = run.bodyAt(N * nodes.time_step);
  const double miss = so3::angleBetween(end.attitude, nodes.attitude.back());
  EXPECT_GT(replay_miss, 1e-3);
  EXPECT_LT(miss, 0.1 * replay_miss) << "replan " << miss << " rad, replay " << replay_miss;
}

// A run that takes over from another (a new maneuver mid-run, the tracker) starts at the given
// state, not at the plan's R_0: exactly simulateTracking's run from that state.
TEST(RecedingHorizonRun, StartsFromTheGivenStateAsSimulateTrackingDoes) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const auto& [scene, plan, J, effects] = disturbed;
  const SchemeKind scheme = scene.problem.scheme;
  const Maneuver& nodes = plan.maneuver;
  const RigidBodyState start{nodes.attitude[0] * so3::exp(Vector3(0.05, -0.1, 0.02)),
                             Vector3(1e-3, 0.0, -2e-3)};
  const ManeuverInterpolation reference(nodes, scheme, J, effects.get());
  Actuation actuation = actuationOf(scene.effects);
  const TrackingRun single = simulateTracking(reference, start.attitude, start.angular_velocity,
                                              effects.get(), &actuation, {});
  const RecedingHorizonRun run(nodes, scheme, J, effects, actuationOf(scene.effects), {}, start);
  EXPECT_LT(so3::angleBetween(run.bodyAt(0.0).attitude, start.attitude), 1e-15);
  EXPECT_LT((run.bodyAt(0.0).angular_velocity - start.angular_velocity).norm(), 1e-15);
  const double T = reference.duration();
  EXPECT_LT(so3::angleBetween(run.bodyAt(T).attitude, single.actual.attitude.back()), 1e-12);
  EXPECT_GT(so3::angleBetween(start.attitude, nodes.attitude[0]), 0.1);  // a real offset ...
  EXPECT_LT(single.terminal_attitude_error, 1e-3);                       // ... pulled in
}

// ~replan_period in plan steps: a period rounds to whole steps (at least one); 0, the default,
// is T / 10 whatever the step (the old default of 1 s re-planned at every node of h = 2 s).
TEST(ReplanPeriodSteps, RoundsAPeriodAndDerivesTheDefaultFromThePlan) {
  EXPECT_EQ(replanPeriodSteps(60.0, 300, 2.0), 30);
  EXPECT_EQ(replanPeriodSteps(1.0, 300, 2.0), 1);   // shorter than a step: every node
  EXPECT_EQ(replanPeriodSteps(3.1, 300, 2.0), 2);   // rounded
  EXPECT_EQ(replanPeriodSteps(0.0, 300, 2.0), 30);  // T / 10
  EXPECT_EQ(replanPeriodSteps(0.0, 1200, 0.5), 120);
  EXPECT_EQ(replanPeriodSteps(0.0, 8, 0.1), 1);  // at least one step
  EXPECT_THROW(replanPeriodSteps(-1.0, 300, 2.0), InvalidInput);
  EXPECT_THROW(replanPeriodSteps(std::nan(""), 300, 2.0), InvalidInput);
}

// commandAt is the law on the plan in force: before an adoption the first plan's TrackingLaw; after
// one, the law on the adopted rows at the segment's own clock, which for the plan's own rest is
// the same command again (the same reference, the effects' clock shifted by t_k).
TEST(RecedingHorizonRun, CommandAtIsTheLawOnThePlanInForce) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const Maneuver& nodes = disturbed.plan.maneuver;
  const SchemeKind scheme = disturbed.scene.problem.scheme;
  const ManeuverInterpolation reference(nodes, scheme, disturbed.J, disturbed.effects.get());
  const TrackingLaw law(reference, disturbed.effects.get(), {});
  RecedingHorizonRun run(nodes, scheme, disturbed.J, disturbed.effects, Actuation(), {});
  const RigidBodyState off{nodes.attitude[0] * so3::exp(Vector3(0.01, -0.02, 0.005)),
                           Vector3(1e-4, 0.0, 2e-4)};
  for (double t : {0.0, 33.0, 301.0}) {
    EXPECT_LT((run.commandAt(off, t) - law.command(off.attitude, off.angular_velocity, t)).norm(),
              1e-15)
        << "t = " << t;
  }
  run.adopt(run.planRemainderAt(100), 100, 100);
  for (double t : {201.0, 450.0}) {
    const Vector3 expected = law.command(off.attitude, off.angular_velocity, t);
    EXPECT_LT((run.commandAt(off, t) - expected).norm(), 1e-9 * expected.norm()) << "t = " << t;
  }
}

// schemeStartOf against the body's own first step (one RKMK4 step of the continuous body under
// the held torque: independent of the midpoint prediction): the paper scheme's Ω_0 is that step's
// rate log(R(t)ᵀR(t + h))/h. The midpoint rate matches it to second order in h (the error falls
// ~4x when h halves), the rate at the node only to first order (~2x) — the (h/2)Ω̇ offset that made
// re-plans under active torque limits infeasible. second_order's Ω_0 is the node's rate itself.
TEST(SchemeStartOf, IsTheFirstStepsRateToSecondOrderForThePaperScheme) {
  const Matrix3 J =
      (Matrix3() << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37).finished();
  const RigidBodyState body{so3::exp(Vector3(0.3, -0.2, 0.5)), Vector3(0.05, -0.12, 0.08)};
  const Vector3 torque(0.26, -0.33, 0.41);
  double start_error[2], node_error[2];
  for (int i = 0; i < 2; ++i) {
    const double h = 0.2 / (1 << i);
    const RigidBodyState next = predictState(J, nullptr, body, torque, 1.0, h);
    const Vector3 step_rate = so3::log(Matrix3(body.attitude.transpose() * next.attitude)) / h;
    const RigidBodyState start = schemeStartOf(SchemeKind::Paper, J, nullptr, body, torque, 1.0, h);
    EXPECT_TRUE(start.attitude.isApprox(body.attitude, 1e-15));  // R_0 is the node's
    start_error[i] = (start.angular_velocity - step_rate).norm();
    node_error[i] = (body.angular_velocity - step_rate).norm();
  }
  EXPECT_GT(start_error[0] / start_error[1], 3.5);
  EXPECT_LT(node_error[0] / node_error[1], 2.5);
  EXPECT_LT(start_error[0], 0.05 * node_error[0]);
  const RigidBodyState same =
      schemeStartOf(SchemeKind::SecondOrder, J, nullptr, body, torque, 1.0, 0.2);
  EXPECT_EQ(same.angular_velocity, body.angular_velocity);
}
