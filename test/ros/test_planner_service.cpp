// rostest: drives attitude_planner_node through its service plan_attitude_maneuver.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanErrorCode.h"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/scene.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

/// Calls the service (fresh persistent-free client: safe from any thread).
PlanAttitudeManeuver::Response call(const PlanAttitudeManeuver::Request& req) {
  PlanAttitudeManeuver srv;
  srv.request = req;
  EXPECT_TRUE(ros::service::call("plan_attitude_maneuver", srv));
  return srv.response;
}

PlanAttitudeManeuver::Request seed(int steps = 32, double angle = M_PI / 3) {
  PlanAttitudeManeuver::Request r;
  ros_testing::fillSeedRequest(&r, steps, angle);
  return r;
}

}  // namespace

class PlannerService : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_TRUE(ros::service::waitForService("plan_attitude_maneuver", ros::Duration(30.0)));
  }
};

TEST_F(PlannerService, SeedSlewMeetsTheBoundaryData) {
  const int N = 32;
  const ros::WallTime start = ros::WallTime::now();
  const PlanAttitudeManeuver::Response res = call(seed(N));
  const double latency = (ros::WallTime::now() - start).toSec();
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.error_code.val, PlanErrorCode::SUCCESS);
  const AttitudeManeuver& m = res.maneuver;
  EXPECT_EQ(m.header.frame_id, "world");
  EXPECT_EQ(m.child_frame_id, "body");
  EXPECT_EQ(m.scheme, "paper");
  ASSERT_EQ(m.attitude.size(), size_t(N + 1));
  ASSERT_EQ(m.time.size(), size_t(N + 1));
  ASSERT_EQ(m.angular_velocity.size(), size_t(N + 1));
  ASSERT_EQ(m.torque.size(), size_t(N + 1));
  EXPECT_DOUBLE_EQ(m.time_step, 12.8 / N);                          // h [s]
  EXPECT_NEAR(m.time.back(), 12.8, 1e-12);                          // t_N = T [s]
  EXPECT_EQ(rc::vectorFromMsg(m.torque.front()), Vector3::Zero());  // τ_0 = 0
  EXPECT_EQ(rc::vectorFromMsg(m.torque.back()), Vector3::Zero());   // τ_N = 0
  const Matrix3 target = so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3);
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(m.attitude.back(), "R_N"), target), 1e-8);
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(m.attitude.front(), "R_0"), Matrix3::Identity()),
            1e-15);
  EXPECT_LT(res.terminal_attitude_error, 1e-8);                          // [rad]
  EXPECT_LT(res.terminal_velocity_error, 1e-8);                          // [rad/s]
  EXPECT_LT(rc::vectorFromMsg(m.angular_velocity[N - 1]).norm(), 1e-8);  // rest at the end
  EXPECT_GT(res.cost, 0.0);
  EXPECT_GT(res.iterations, 0);
  EXPECT_GT(res.solve_time, 0.0);
  RecordProperty("latency_s", std::to_string(latency));
  std::printf("seed N = %d: service latency %.4f s (solve %.4f s, %d iterations, cost %.6g)\n", N,
              latency, res.solve_time, res.iterations, res.cost);
}

TEST_F(PlannerService, NanosecondHorizonIsJudgedByThePlanAndReportsItsReplayMiss) {
  // T = 1e-9 s, π about x (rates ~3e9 rad/s): relative thresholds judge the replay like the same
  // shape at T = 12.8 s (an absolute miss would refuse it NOT_CONVERGED).
  PlanAttitudeManeuver::Request req = seed(64, M_PI);
  req.duration = 1e-9;
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.error_code.val, PlanErrorCode::SUCCESS);
  EXPECT_LE(res.step_residual, 1e-8);
  EXPECT_GE(res.replay_miss, 0.0);
  EXPECT_LE(res.replay_miss, 1e-6);  // [rad]; this motion is stable
  req.duration = 12.8;
  const PlanAttitudeManeuver::Response slow = call(req);
  ASSERT_TRUE(slow.success) << slow.message;
  EXPECT_EQ(res.iterations, slow.iterations);
}

TEST_F(PlannerService, SeedExampleAtFullResolutionForLatency) {
  const ros::WallTime start = ros::WallTime::now();
  const PlanAttitudeManeuver::Response res = call(seed(128));  // the seed example, N = 128
  const double latency = (ros::WallTime::now() - start).toSec();
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_LT(res.terminal_attitude_error, 1e-8);
  RecordProperty("latency_s", std::to_string(latency));
  std::printf("seed N = 128: service latency %.4f s (solve %.4f s, %d iterations, cost %.8g)\n",
              latency, res.solve_time, res.iterations, res.cost);
}

TEST_F(PlannerService, BadRequestsNameTheFieldAndTheNodeKeepsServing) {
  struct Case {
    const char* what;
    PlanAttitudeManeuver::Request req;
    const char* expected;
  };
  std::vector<Case> cases;
  cases.push_back({"zero quaternion", seed(), "final_attitude: zero quaternion"});
  cases.back().req.final_attitude = geometry_msgs::Quaternion();
  cases.push_back({"NaN inertia", seed(), "inertia"});
  cases.back().req.inertia[4] = std::numeric_limits<double>::quiet_NaN();
  cases.push_back({"steps = 2", seed(), "steps: must be >= 4, got 2"});
  cases.back().req.steps = 2;
  cases.push_back(
      {"non-unit quaternion", seed(), "initial_attitude: not a unit quaternion: [2, 0, 0, 0]"});
  cases.back().req.initial_attitude.w = 2.0;
  cases.push_back({"unknown scheme", seed(), "scheme: unknown value 'rk4'"});
  cases.back().req.scheme = "rk4";
  cases.push_back({"negative duration", seed(), "duration"});
  cases.back().req.duration = -1.0;
  cases.push_back({"indefinite inertia", seed(), "inertia"});
  cases.back().req.inertia[0] = -1.0;
  for (const Case& c : cases) {
    const PlanAttitudeManeuver::Response res = call(c.req);
    EXPECT_FALSE(res.success) << c.what;
    EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << c.what << ": " << res.message;
    EXPECT_NE(res.message.find(c.expected), std::string::npos)
        << c.what << ": message '" << res.message << "' lacks '" << c.expected << "'";
    EXPECT_TRUE(res.maneuver.attitude.empty()) << c.what;
  }
  // The node survived all of them and still plans.
  const PlanAttitudeManeuver::Response good = call(seed());
  EXPECT_TRUE(good.success) << good.message;
  EXPECT_LT(good.terminal_attitude_error, 1e-8);
}

TEST_F(PlannerService, StepsLeftAtZeroTakeTheNodesDefaultSteps) {
  // Empty/0 fields take the node's defaults (README), steps included; the
  // node here runs with ~default_steps = 128 (launch/planner.launch).
  const PlanAttitudeManeuver::Response res = call(seed(0));
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.steps, 128);
  EXPECT_EQ(res.maneuver.attitude.size(), size_t(129));
}

TEST_F(PlannerService, StepTooLargeIsItsOwnErrorAndTheNodeKeepsServing) {
  PlanAttitudeManeuver::Request req = seed(8);
  req.duration = 1.0;
  req.initial_angular_velocity.z = 40.0;  // h|Ω_0| = 5 rad > π: no paper step exists
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::STEP_TOO_LARGE) << res.message;
  EXPECT_NE(res.message.find("initial_angular_velocity: step too large, increase steps"),
            std::string::npos)
      << res.message;
  req.steps = 64;  // h|Ω_0| = 0.625
  const PlanAttitudeManeuver::Response fine = call(req);
  EXPECT_TRUE(fine.success) << fine.message;
}

TEST_F(PlannerService, RunawaySolveIsStoppedByMaxSolveTimeAndTheNextRequestIsServed) {
  // The node in the `capped` namespace runs with ~max_solve_time 0.1 s (planner_service.test).
  // This request asks for a 1e6 s budget at N = 1e5 (seconds of work on any machine): the cap
  // stops it, and the same node then serves a small request.
  ASSERT_TRUE(ros::service::waitForService("capped/plan_attitude_maneuver", ros::Duration(30.0)));
  const auto capped = [](const PlanAttitudeManeuver::Request& req) {
    PlanAttitudeManeuver srv;
    srv.request = req;
    EXPECT_TRUE(ros::service::call("capped/plan_attitude_maneuver", srv));
    return srv.response;
  };
  PlanAttitudeManeuver::Request req = seed(100000);
  req.tolerance = 1e-300;
  req.max_iterations = 1000000;
  req.time_budget = 1e6;
  const ros::WallTime start = ros::WallTime::now();
  const PlanAttitudeManeuver::Response res = capped(req);
  const double elapsed = (ros::WallTime::now() - start).toSec();
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::TIMED_OUT) << res.message;
  EXPECT_NE(res.message.find("time budget"), std::string::npos) << res.message;
  EXPECT_LT(elapsed, 0.1 + 15.0) << res.message;  // the budget, one fine iteration, transport
  std::printf("runaway request stopped after %.2f s: %s\n", elapsed, res.message.c_str());
  const PlanAttitudeManeuver::Response next = capped(seed(16));
  EXPECT_TRUE(next.success) << next.message;
}

TEST_F(PlannerService, LongWayAndExtraTurnsAreHonoured) {
  // 1 rad about x (seed J, N = 64): the other way round and one extra turn cost more than the
  // short way and still land.
  const PlanAttitudeManeuver::Response short_way = call(seed(64, 1.0));
  PlanAttitudeManeuver::Request req = seed(64, 1.0);
  req.direction = "long_way";
  const PlanAttitudeManeuver::Response long_way = call(req);
  req.direction = "";
  req.extra_revolutions = 1;
  const PlanAttitudeManeuver::Response extra = call(req);
  for (const auto* r : {&short_way, &long_way, &extra}) {
    ASSERT_TRUE(r->success) << r->message;
    EXPECT_LT(r->terminal_attitude_error, 1e-9);
  }
  EXPECT_GT(long_way.cost, short_way.cost);
  EXPECT_GT(extra.cost, short_way.cost);
}

TEST_F(PlannerService, EffectsArePlannedListedAndLandWhenReplayedUnderThem) {
  // scenes/leo_slew.yaml as a request: gravity gradient + world disturbance in the planning model.
  PlanAttitudeManeuver::Request r;
  r.inertia = {800, 0, 0, 0, 1200, 0, 0, 0, 1500};
  r.initial_attitude.w = 1.0;
  r.final_attitude = rc::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitZ(), M_PI / 2));
  r.duration = 600.0;
  r.steps = 300;
  r.scheme = "variational";
  const std::vector<EffectSpec> effects = {
      GravityGradientSpec{3.986004418e14, 6.778e6},
      DisturbanceTorqueSpec{TorqueFrame::World, Vector3(2e-4, 0.0, -1e-4)}};
  for (const EffectSpec& e : effects) r.effects.push_back(rc::effectToMsg(e));
  const PlanAttitudeManeuver::Response res = call(r);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.effects, (std::vector<std::string>{"gravity_gradient", "disturbance_torque"}));
  // Replayed under the same effects, the plan lands; without them it misses (they matter).
  const Maneuver plan = rc::maneuverFromMsg(res.maneuver);
  const Matrix3 J = rc::inertiaFromMsg(r.inertia);
  const DiscreteScheme scheme(SchemeKind::Variational, J, plan.time_step);
  SimulationInput input;
  input.torque = plan.torque;
  const auto model = plannableEffects(effects, J);
  input.effects = model.get();
  const Matrix3 target = rc::attitudeFromMsg(r.final_attitude, "final_attitude");
  EXPECT_LT(so3::angleBetween(simulate(scheme, input).attitude.back(), target), 1e-8);
  input.effects = nullptr;
  EXPECT_GT(so3::angleBetween(simulate(scheme, input).attitude.back(), target), 1e-3);

  PlanAttitudeManeuver::Request noisy = r;
  noisy.effects.push_back(rc::effectToMsg(TorqueNoiseSpec{Vector3(1e-4, 1e-4, 1e-4), 7}));
  const PlanAttitudeManeuver::Response refused = call(noisy);
  EXPECT_FALSE(refused.success);
  EXPECT_EQ(refused.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(refused.message.find("effects[2].type: 'torque_noise' is not plannable"),
            std::string::npos)
      << refused.message;
}

TEST_F(PlannerService, SchemeAndSolverFieldsAreHonoured) {
  PlanAttitudeManeuver::Request req = seed();
  req.scheme = "variational";
  const PlanAttitudeManeuver::Response variational = call(req);
  ASSERT_TRUE(variational.success) << variational.message;
  EXPECT_EQ(variational.maneuver.scheme, "variational");
  EXPECT_LT(variational.terminal_attitude_error, 1e-8);

  const PlanAttitudeManeuver::Response newton = call(seed());
  req = seed();
  req.solver = "nlopt";  // the independent cross-check reaches the same optimum
  const PlanAttitudeManeuver::Response nlopt = call(req);
  ASSERT_TRUE(newton.success) << newton.message;
  ASSERT_TRUE(nlopt.success) << nlopt.message;
  EXPECT_NEAR(nlopt.cost, newton.cost, 1e-6 * newton.cost);

  // second_order: end torques in the plan, effort = h·cost, lower effort error than paper's
  // (the seed's cost is ≈ 3h/T too high); with solver nlopt it is refused by name.
  req = seed();
  req.scheme = "second_order";
  const PlanAttitudeManeuver::Response second = call(req);
  ASSERT_TRUE(second.success) << second.message;
  EXPECT_EQ(second.scheme, "second_order");
  EXPECT_EQ(second.maneuver.scheme, "second_order");
  EXPECT_LT(second.terminal_attitude_error, 1e-8);
  EXPECT_LT(second.terminal_velocity_error, 1e-8);
  const double h = req.duration / second.steps;
  EXPECT_NEAR(second.effort, h * second.cost, 1e-12 * second.effort);
  EXPECT_NEAR(newton.effort, h * newton.cost, 1e-12 * newton.effort);
  EXPECT_GT(std::abs(second.maneuver.torque.front().x) +
                std::abs(second.maneuver.torque.front().y) +
                std::abs(second.maneuver.torque.front().z),
            0.0);
  req.solver = "nlopt";
  const PlanAttitudeManeuver::Response refused = call(req);
  EXPECT_FALSE(refused.success);
  EXPECT_EQ(refused.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(refused.message.find("scheme: 'second_order'"), std::string::npos) << refused.message;

  // fourth_order: Richardson extrapolation of second_order at N and 2N; node values with end
  // torques, effort = h·cost (Gregory weights), replayed with the cubic hold to O(h⁴).
  req = seed();
  req.scheme = "fourth_order";
  const PlanAttitudeManeuver::Response fourth = call(req);
  ASSERT_TRUE(fourth.success) << fourth.message;
  EXPECT_EQ(fourth.scheme, "fourth_order");
  EXPECT_EQ(fourth.maneuver.scheme, "fourth_order");
  EXPECT_NE(fourth.message.find("Richardson extrapolation of second_order"), std::string::npos)
      << fourth.message;
  EXPECT_EQ(fourth.maneuver.torque.size(), second.maneuver.torque.size());
  EXPECT_NEAR(fourth.effort, req.duration / fourth.steps * fourth.cost, 1e-12 * fourth.effort);
  EXPECT_LT(fourth.terminal_attitude_error, 1e-3);
  // closer to the continuous optimum's effort than second_order's at the same N
  EXPECT_LT(std::abs(fourth.effort - second.effort), 0.1 * std::abs(second.effort - newton.effort));
  req.solver = "nlopt";
  const PlanAttitudeManeuver::Response refused4 = call(req);
  EXPECT_FALSE(refused4.success);
  EXPECT_EQ(refused4.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(refused4.message.find("scheme: 'fourth_order'"), std::string::npos) << refused4.message;
  EXPECT_TRUE(call(seed()).success);  // and the node keeps serving
}

TEST_F(PlannerService, IterationLimitIsNotConverged) {
  PlanAttitudeManeuver::Request req = seed();
  req.max_iterations = 1;
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::NOT_CONVERGED) << res.message;
  EXPECT_EQ(res.maneuver.attitude.size(), 33u);  // the last iterate is still returned
}

TEST_F(PlannerService, ConcurrentRequestsEachGetTheirOwnAnswer) {
  // Several threads, each slewing by its own angle: no answer may be another request's.
  const int kThreads = 6;
  std::vector<std::thread> threads;
  std::vector<PlanAttitudeManeuver::Response> responses(kThreads);
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&responses, i]() {
      PlanAttitudeManeuver srv;
      srv.request = seed(32 + 8 * i, 0.2 + 0.25 * i);
      if (ros::service::call("plan_attitude_maneuver", srv)) responses[i] = srv.response;
    });
  }
  for (std::thread& t : threads) t.join();
  for (int i = 0; i < kThreads; ++i) {
    const PlanAttitudeManeuver::Response& res = responses[i];
    ASSERT_TRUE(res.success) << "request " << i << ": " << res.message;
    ASSERT_EQ(res.maneuver.attitude.size(), size_t(32 + 8 * i + 1)) << "request " << i;
    const Matrix3 target = so3::fromAxisAngle(Vector3::UnitX(), 0.2 + 0.25 * i);
    EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(res.maneuver.attitude.back(), "R_N"), target),
              1e-8)
        << "request " << i;
  }
}

TEST_F(PlannerService, ConstraintsArePlannedReportedAndABadOneIsNamed) {
  // The seed slew (N = 32) with |tau_k| <= 0.45 N m (the unconstrained peak is ~0.6 N m): the
  // bound binds, the response lists it and its figures; then a keep-out cone with a non-unit
  // axis is refused naming the field, and the node keeps serving.
  PlanAttitudeManeuver::Request req = seed(32);
  Constraint norm;
  norm.type = Constraint::MAX_TORQUE_NORM;
  norm.limit = 0.45;
  req.constraints.push_back(norm);
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  ASSERT_EQ(res.constraints.size(), 1u);
  EXPECT_EQ(res.constraints[0], "max_torque_norm");
  EXPECT_GT(res.active_constraints, 0);
  EXPECT_LE(res.max_constraint_violation, 1e-9);
  for (const geometry_msgs::Vector3& t : res.maneuver.torque) {
    EXPECT_LE(std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z), 0.45 * (1 + 1e-9));
  }
  Constraint cone;
  cone.type = Constraint::KEEP_OUT;
  cone.body_axis.z = 2.0;
  cone.world_direction.y = 1.0;
  cone.half_angle = 0.3;
  req.constraints = {cone};
  const PlanAttitudeManeuver::Response bad = call(req);
  EXPECT_FALSE(bad.success);
  EXPECT_EQ(bad.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(bad.message.find("constraints[0].body_axis: not a unit vector"), std::string::npos)
      << bad.message;
  EXPECT_TRUE(call(seed(16)).success);
}

TEST_F(PlannerService, KeepOutAndTorqueNormBindAreEchoedAndMetAtEveryNode) {
  PlanAttitudeManeuver::Request req;
  ros_testing::fillConstrainedRequest(&req, 32);
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.constraints, (std::vector<std::string>{"max_torque_norm", "keep_out"}));
  EXPECT_GT(res.active_constraints, 0);
  EXPECT_LE(res.max_constraint_violation, 1e-9);
  // Both met at every node and both at their bound (checked here from the returned rows).
  const ros_testing::ConstrainedSlacks slack = ros_testing::constrainedRequestSlacks(res.maneuver);
  EXPECT_GE(slack.torque, -1e-9);
  EXPECT_GE(slack.cone, -1e-9);
  EXPECT_LT(slack.torque, 1e-6);
  EXPECT_LT(slack.cone, 1e-6);
  EXPECT_LT(res.terminal_attitude_error, 1e-8);
  // Both bind: the plan costs more than the same slew without them.
  req.constraints.clear();
  const PlanAttitudeManeuver::Response free = call(req);
  ASSERT_TRUE(free.success) << free.message;
  EXPECT_LT(ros_testing::constrainedRequestSlacks(free.maneuver).cone, -1e-3);
  EXPECT_GT(res.cost, free.cost);
}

TEST_F(PlannerService, ReactionWheelsArePlannedWithTheirStatesAndPeaksPerWheel) {
  // The biased pyramid slew with a binding momentum limit: the answer carries each row's wheel
  // torques and momenta and the per-wheel peaks and margins (checked from the rows).
  PlanAttitudeManeuver::Request req;
  ros_testing::fillWheelRequest(&req, 128);
  const PlanAttitudeManeuver::Response res = call(req);
  ros_testing::expectWheelAnswer(res, 128);
  EXPECT_LE(res.max_constraint_violation, 1e-9);
  // The same request decimated to 9 rows: the wheel rows of the kept nodes k = 0, 16, ..., 128.
  req.output_steps = 9;
  const PlanAttitudeManeuver::Response few = call(req);
  ASSERT_TRUE(few.success) << few.message;
  ASSERT_EQ(few.maneuver.wheel_momentum.size(), 9u * 4u);
  ASSERT_EQ(few.maneuver.wheel_torque.size(), 9u * 4u);
  for (std::size_t j = 0; j < 9; ++j) {
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_NEAR(few.maneuver.wheel_momentum[j * 4 + i],
                  res.maneuver.wheel_momentum[16 * j * 4 + i], 1e-9)
          << "row " << j;
      EXPECT_NEAR(few.maneuver.wheel_torque[j * 4 + i], res.maneuver.wheel_torque[16 * j * 4 + i],
                  1e-9)
          << "row " << j;
    }
  }
  // Without wheels: no wheel rows, no summary.
  const PlanAttitudeManeuver::Response plain = call(seed(16));
  ASSERT_TRUE(plain.success) << plain.message;
  EXPECT_TRUE(plain.maneuver.wheel_torque.empty());
  EXPECT_TRUE(plain.maneuver.reaction_wheels.spin_axes.empty());
  EXPECT_TRUE(plain.reaction_wheels.wheels.empty());
}

TEST_F(PlannerService, BadReactionWheelsAreNamedByTheRequestsField) {
  const auto refusal = [](const std::function<void(PlanAttitudeManeuver::Request*)>& spoil) {
    PlanAttitudeManeuver::Request req;
    ros_testing::fillWheelRequest(&req, 32);
    spoil(&req);
    const PlanAttitudeManeuver::Response res = call(req);
    EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << res.message;
    return res.message;
  };
  const auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  std::string m = refusal([](auto* r) { r->reaction_wheels.spin_axes.resize(2); });
  EXPECT_TRUE(has(m, "reaction_wheels.spin_axes: need at least 3 wheels")) << m;
  EXPECT_FALSE(has(m, "actuators.")) << "the request's own spelling: " << m;
  m = refusal([](auto* r) {
    r->reaction_wheels.spin_axes[3] = r->reaction_wheels.spin_axes[1];
    r->reaction_wheels.spin_axes[2] = r->reaction_wheels.spin_axes[0];
  });
  EXPECT_TRUE(has(m, "reaction_wheels.spin_axes: the axes do not span R^3")) << m;
  m = refusal([](auto* r) { r->reaction_wheels.max_momentum = {-1.0}; });
  EXPECT_TRUE(has(m, "reaction_wheels.max_momentum")) << m;
  EXPECT_TRUE(has(m, "-1")) << m;
  m = refusal([](auto* r) { r->reaction_wheels.max_torque = {0.3, 0.3}; });
  EXPECT_TRUE(has(m, "reaction_wheels.max_torque")) << m;
  m = refusal([](auto* r) { r->reaction_wheels.initial_momentum = {0.3, -0.2, 1.5, 0.1}; });
  EXPECT_TRUE(has(m, "reaction_wheels.initial_momentum")) << m;
  m = refusal([](auto* r) { r->reaction_wheels.max_momentum_norm = -2.0; });
  EXPECT_TRUE(has(m, "reaction_wheels.max_momentum_norm")) << m;
  m = refusal([](auto* r) { r->reaction_wheels.spin_axes[1].y = std::nan(""); });
  EXPECT_TRUE(has(m, "reaction_wheels.spin_axes[1]")) << m;
  m = refusal([](auto* r) {
    r->reaction_wheels.spin_axes.clear();  // no wheels, yet limits given
  });
  EXPECT_TRUE(has(m, "reaction_wheels.spin_axes: empty")) << m;
  m = refusal([](auto* r) {
    Effect limits;
    limits.type = Effect::ACTUATOR_LIMITS;
    limits.value.x = limits.value.y = limits.value.z = 1.0;
    r->effects.push_back(limits);
  });
  EXPECT_TRUE(has(m, "actuator_limits")) << m;
  EXPECT_TRUE(call(seed(16)).success) << "the node keeps serving";
}

TEST_F(PlannerService, BadConstraintValuesAreNamedAndTheNodeKeepsServing) {
  struct Case {
    const char* what;
    PlanAttitudeManeuver::Request req;
    const char* expected;
  };
  std::vector<Case> cases;
  PlanAttitudeManeuver::Request base;
  ros_testing::fillConstrainedRequest(&base, 16);
  cases.push_back(
      {"zero body axis", base, "constraints[1].body_axis: zero vector [0, 0, 0] has no direction"});
  cases.back().req.constraints[1].body_axis = geometry_msgs::Vector3();
  cases.push_back(
      {"half angle above pi", base, "constraints[1].half_angle: must be in (0, pi) rad, got 3.5"});
  cases.back().req.constraints[1].half_angle = 3.5;
  cases.push_back(
      {"keep_in half angle 0", base, "constraints[1].half_angle: must be in (0, pi) rad, got 0"});
  cases.back().req.constraints[1].type = Constraint::KEEP_IN;
  cases.back().req.constraints[1].half_angle = 0.0;
  cases.push_back({"negative torque norm", base,
                   "constraints[0].limit: must be a finite number > 0 N m, got -0.095"});
  cases.back().req.constraints[0].limit = -0.095;
  cases.push_back({"unknown type", base, "constraints[0].type: unknown value 'max_torque'"});
  cases.back().req.constraints[0].type = "max_torque";
  for (const Case& c : cases) {
    const PlanAttitudeManeuver::Response res = call(c.req);
    EXPECT_FALSE(res.success) << c.what;
    EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << c.what << ": " << res.message;
    EXPECT_NE(res.message.find(c.expected), std::string::npos)
        << c.what << ": message '" << res.message << "' lacks '" << c.expected << "'";
    EXPECT_TRUE(res.maneuver.attitude.empty()) << c.what;
  }
  const PlanAttitudeManeuver::Response good = call(base);
  EXPECT_TRUE(good.success) << good.message;
  EXPECT_GE(ros_testing::constrainedRequestSlacks(good.maneuver).cone, -1e-9);
}

TEST_F(PlannerService, MinimumTimeReturnsTStarAndTheMarginPlan) {
  // A sphere J = 10 I, 1 rad about x, |τ|₂ ≤ 1 N m: T* = 2√10 s (eigenaxis bang–bang). No
  // duration given; the plan at 1.1 T*. Then a minimum-time request without a bound is named.
  PlanAttitudeManeuver::Request req = seed(32);
  req.inertia = {10, 0, 0, 0, 10, 0, 0, 0, 10};
  req.allow_nonphysical_inertia = false;
  req.duration = 0.0;
  req.scheme = "second_order";
  req.objective = "minimum_time";
  req.time_margin = 0.1;
  Constraint norm;
  norm.type = Constraint::MAX_TORQUE_NORM;
  norm.limit = 1.0;
  req.constraints.push_back(norm);
  req.final_attitude = ros_conversions::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitX(), 1.0));
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_NEAR(res.minimum_duration, 2 * std::sqrt(10.0), 2e-3 * res.minimum_duration);
  EXPECT_NEAR(res.duration, 1.1 * res.minimum_duration, 1e-9 * res.duration);
  EXPECT_LE(res.max_constraint_violation, 1e-9);
  req.constraints.clear();
  const PlanAttitudeManeuver::Response bad = call(req);
  EXPECT_FALSE(bad.success);
  EXPECT_EQ(bad.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(bad.message.find("objective: 'minimum_time' needs a torque bound"), std::string::npos)
      << bad.message;
  EXPECT_TRUE(call(seed(16)).success);
}

// ---- a service for people and programs --------------------------------------------

TEST_F(PlannerService, OutputStepsDecimatesToTheAskedSizeWithBothEnds) {
  // N = 1000, at most 11 nodes: stride ceil(1000 / 10) = 100, k = 0, 100, ..., 1000.
  PlanAttitudeManeuver::Request req = seed(1000);
  req.output_steps = 11;
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_EQ(res.steps, 1000);  // the plan's N, not the rows returned
  const AttitudeManeuver& m = res.maneuver;
  ASSERT_EQ(m.attitude.size(), 11u);
  ASSERT_EQ(m.time.size(), 11u);
  ASSERT_EQ(m.angular_velocity.size(), 11u);
  ASSERT_EQ(m.torque.size(), 11u);
  EXPECT_DOUBLE_EQ(m.time_step, 12.8 / 1000);  // the plan's h
  EXPECT_EQ(m.time.front(), 0.0);
  EXPECT_NEAR(m.time[1], 100 * 12.8 / 1000, 1e-12);
  EXPECT_NEAR(m.time.back(), 12.8, 1e-12);
  const Matrix3 target = so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3);
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(m.attitude.back(), "R_N"), target), 1e-8);
  // The same rows as the full answer's.
  const PlanAttitudeManeuver::Response full = call(seed(1000));
  ASSERT_EQ(full.maneuver.attitude.size(), 1001u);
  for (std::size_t i = 0; i < m.attitude.size(); ++i) {
    const std::size_t k = std::min<std::size_t>(100 * i, 1000);
    EXPECT_EQ(m.time[i], full.maneuver.time[k]) << "row " << i;
    EXPECT_EQ(m.torque[i].x, full.maneuver.torque[k].x) << "row " << i;
  }
  // N = 32 at most 7 nodes: stride ceil(32 / 6) = 6, k = 0, 6, ..., 30 and 32 (7 rows).
  req = seed(32);
  req.output_steps = 7;
  const PlanAttitudeManeuver::Response small = call(req);
  ASSERT_TRUE(small.success) << small.message;
  ASSERT_EQ(small.maneuver.time.size(), 7u);
  EXPECT_NEAR(small.maneuver.time[5], 30 * 12.8 / 32, 1e-12);
  EXPECT_NEAR(small.maneuver.time[6], 12.8, 1e-12);
  // More nodes than the plan has: all of them.
  req.output_steps = 1000;
  EXPECT_EQ(call(req).maneuver.attitude.size(), 33u);
}

TEST_F(PlannerService, SummaryOnlyAnswerHasTheFiguresAndNoManeuver) {
  PlanAttitudeManeuver::Request req = seed(128);
  req.return_maneuver = "none";
  const PlanAttitudeManeuver::Response res = call(req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_TRUE(res.maneuver.attitude.empty());
  EXPECT_TRUE(res.maneuver.time.empty());
  EXPECT_TRUE(res.maneuver.torque.empty());
  EXPECT_EQ(res.steps, 128);
  EXPECT_GT(res.cost, 0.0);
  EXPECT_LT(res.terminal_attitude_error, 1e-8);
  req.return_maneuver = "nodes";  // the default spelt out
  EXPECT_EQ(call(req).maneuver.attitude.size(), 129u);
}

TEST_F(PlannerService, BadOutputFieldsAreNamed) {
  struct Case {
    const char* what;
    PlanAttitudeManeuver::Request req;
    const char* expected;
  };
  std::vector<Case> cases;
  cases.push_back({"output_steps 1", seed(), "output_steps: must be 0 (every node) or >= 2"});
  cases.back().req.output_steps = 1;
  cases.push_back({"output_steps -1", seed(), "output_steps: must be 0 (every node) or >= 2"});
  cases.back().req.output_steps = -1;
  cases.push_back({"unknown return_maneuver", seed(), "return_maneuver: unknown value 'all'"});
  cases.back().req.return_maneuver = "all";
  cases.push_back(
      {"output_steps with none", seed(), "output_steps: 10 given with return_maneuver"});
  cases.back().req.return_maneuver = "none";
  cases.back().req.output_steps = 10;
  for (const Case& c : cases) {
    const PlanAttitudeManeuver::Response res = call(c.req);
    EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << c.what << ": " << res.message;
    EXPECT_EQ(res.message.rfind(c.expected, 0), 0u)
        << c.what << ": message '" << res.message << "' does not start with '" << c.expected << "'";
  }
}

TEST_F(PlannerService, ErrorsNameTheRequestsOwnFields) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* what;
    PlanAttitudeManeuver::Request req;
    const char* expected;  // the message starts with it
  };
  std::vector<Case> cases;
  cases.push_back({"NaN initial rate", seed(), "initial_angular_velocity: not finite"});
  cases.back().req.initial_angular_velocity.y = nan;
  cases.push_back({"NaN final rate", seed(), "final_angular_velocity: not finite"});
  cases.back().req.final_angular_velocity.z = nan;
  Constraint rate;
  rate.type = Constraint::MAX_ANGULAR_RATE;
  rate.limit = 0.2;
  cases.push_back({"initial rate above a rate limit", seed(),
                   "initial_angular_velocity: already violates constraints[0] (max_angular_rate)"});
  cases.back().req.initial_angular_velocity.z = 0.5;
  cases.back().req.constraints = {rate};
  cases.push_back({"negative rate limit", seed(),
                   "constraints[0].limit: must be a finite number > 0 rad/s, got -0.2"});
  cases.back().req.constraints = {rate};
  cases.back().req.constraints[0].limit = -0.2;
  PlanAttitudeManeuver::Request constrained;
  ros_testing::fillConstrainedRequest(&constrained, 16);
  cases.push_back({"cone margin", constrained, "constraints[1].margin: must be >= 0 rad"});
  cases.back().req.constraints[1].margin = -0.1;
  cases.push_back({"limit on a cone", constrained, "constraints[1].limit: not used by keep_out"});
  cases.back().req.constraints[1].limit = 1.0;
  cases.push_back({"actuator limit", seed(), "effects[0].value.z: must be > 0 N m, got -1"});
  cases.back().req.effects = {rc::effectToMsg(ActuatorLimitsSpec{Vector3(1.0, 1.0, 1.0)})};
  cases.back().req.effects[0].value.z = -1.0;
  for (const Case& c : cases) {
    const PlanAttitudeManeuver::Response res = call(c.req);
    EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << c.what << ": " << res.message;
    EXPECT_EQ(res.message.rfind(c.expected, 0), 0u)
        << c.what << ": message '" << res.message << "' does not start with '" << c.expected << "'";
    // No scene key leaks into a request's error.
    for (const char* scene_key : {"initial.", "final.", ".max_torque_norm",
                                  ".max_angular_rate:", ".keep_out.", ".actuator_limits."}) {
      EXPECT_EQ(res.message.find(scene_key), std::string::npos)
          << c.what << ": '" << res.message << "' names the scene key '" << scene_key << "'";
    }
  }
  EXPECT_TRUE(call(seed(16)).success);
}

TEST_F(PlannerService, NloptAboveItsLimitIsInvalidInputNamingSteps) {
  PlanAttitudeManeuver::Request req = seed(2048);
  req.solver = "nlopt";
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::INVALID_INPUT) << res.message;
  EXPECT_EQ(res.message.rfind("steps: 2048 > 1024 is refused by solver nlopt", 0), 0u)
      << res.message;
  EXPECT_TRUE(res.maneuver.attitude.empty());
}

TEST_F(PlannerService, InfeasibleAnswerIsOneLineWithTheAccountInDetails) {
  // 1.047 rad in 12.8 s needs a mean rate of 0.082 rad/s: |Omega| <= 0.05 rad/s cannot be met.
  PlanAttitudeManeuver::Request req = seed(32);
  Constraint rate;
  rate.type = Constraint::MAX_ANGULAR_RATE;
  rate.limit = 0.05;
  req.constraints = {rate};
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_FALSE(res.success);
  ASSERT_EQ(res.error_code.val, PlanErrorCode::INFEASIBLE) << res.message;
  EXPECT_EQ(res.message.rfind("infeasible: ", 0), 0u) << res.message;
  EXPECT_EQ(res.message.find('\n'), std::string::npos) << res.message;
  // The binding limit, as the proof's figure (the message is worded from it).
  EXPECT_TRUE(res.duration_verdict.proven_infeasible);
  EXPECT_EQ(res.duration_verdict.rate_limit, 0.05) << res.message;
  EXPECT_EQ(res.duration_verdict.torque_limit, 0.0) << res.message;  // no torque bound
  EXPECT_NEAR(res.duration_verdict.lower_bound, M_PI / 3 / 0.05, 1e-9);
  EXPECT_LE(res.message.size(), 200u) << res.message;
  EXPECT_GT(res.details.size(), res.message.size()) << res.details;
  // Below the proven bound θ/w = 20.9 s the answer needs no solve, and says it is proven.
  EXPECT_TRUE(res.duration_verdict.proven_infeasible) << res.details;
  EXPECT_NEAR(res.duration_verdict.lower_bound, M_PI / 3 / 0.05, 1e-9);
}

TEST_F(PlannerService, BudgetFarBelowTheSolveIsTimedOut) {
  // N = 1e5 needs seconds here; 10 ms is a deadline the answer cannot meet. The status is
  // asserted, never the wall time (docs/ros_planner.md records the times).
  PlanAttitudeManeuver::Request req = seed(100000);
  req.time_budget = 0.01;
  req.return_maneuver = "none";
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_FALSE(res.success);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::TIMED_OUT) << res.message;
  std::printf("N = 1e5, time_budget 0.01 s: solve_time %.3f s: %s\n", res.solve_time,
              res.message.c_str());
}

TEST_F(PlannerService, BudgetTooSmallToConvergeAnswersWithThePlanReached) {
  // An anytime plan: a budget spent before the first iteration stops the solve at its start, a
  // plan of the dynamics with the request's boundary data. The answer is TIMED_OUT with that plan,
  // flagged unconverged, with its residuals (before: no plan, the deadline at B (1 + 2 %) came
  // before the stopped solve had measured it).
  const int N = 512;
  PlanAttitudeManeuver::Request req = seed(N);
  req.tolerance = 1e-300;
  req.max_iterations = 1000000;
  req.time_budget = 1e-6;
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::TIMED_OUT) << res.message;
  ros_testing::expectSeedAnytimePlan(res, N, req.tolerance);
}

TEST_F(PlannerService, LargeRequestTimedOutAtItsDeadlineCarriesThePlanReached) {
  // N = 1e5 with a budget of 1 s, where the stopped solve's hand-over (carrying
  // the iterate to N = 1e5, building and judging the rows) takes longer than the answer's slack
  // after B. The core stops a hand-over's time before the deadline (solveBudget), so the
  // answer is TIMED_OUT with the plan reached, flagged unconverged, with its residuals. States
  // only: no time is asserted.
  const int N = 100000;
  PlanAttitudeManeuver::Request req = seed(N);
  req.tolerance = 1e-300;  // only the budget ends it
  req.max_iterations = 1000000;
  req.time_budget = 1.0;
  const PlanAttitudeManeuver::Response res = call(req);
  EXPECT_EQ(res.error_code.val, PlanErrorCode::TIMED_OUT) << res.message;
  ros_testing::expectSeedAnytimePlan(res, N, req.tolerance);
}

TEST_F(PlannerService, InitialGuessWarmStartsTheReplanFromAStateOnThePlan) {
  // The seed's slew, then the re-plan from its node k (spinning) to the same end with
  // the plan's remainder as initial_guess: the remainder comes back, cost to 1e-8, in <= 2
  // iterations. A guess of another N is resampled; malformed guesses are named by row.
  const int N = 32, k = 8;
  const PlanAttitudeManeuver::Response full = call(seed(N));
  ASSERT_TRUE(full.success) << full.message;
  const AttitudeManeuver& m = full.maneuver;
  PlanAttitudeManeuver::Request req = seed(N - k);
  req.duration = 12.8 * (N - k) / N;
  req.initial_attitude = m.attitude[k];
  req.initial_angular_velocity = m.angular_velocity[k];
  AttitudeManeuver& guess = req.initial_guess;
  guess = m;
  guess.time.clear();
  guess.attitude.assign(m.attitude.begin() + k, m.attitude.end());
  guess.angular_velocity.assign(m.angular_velocity.begin() + k, m.angular_velocity.end());
  guess.torque.assign(m.torque.begin() + k, m.torque.end());
  double remainder = 0.0;
  for (int j = k + 1; j < N; ++j) remainder += 0.5 * rc::vectorFromMsg(m.torque[j]).squaredNorm();
  const PlanAttitudeManeuver::Response warm = call(req);
  ASSERT_TRUE(warm.success) << warm.message;
  EXPECT_NEAR(warm.cost, remainder, 1e-8 * remainder);
  EXPECT_LE(warm.iterations, 2);

  PlanAttitudeManeuver::Request finer = seed(2 * N);
  finer.initial_guess = m;  // N = 32 for a request at 64: resampled
  const PlanAttitudeManeuver::Response resampled = call(finer);
  EXPECT_TRUE(resampled.success) << resampled.message;
  EXPECT_NEAR(resampled.cost, call(seed(2 * N)).cost, 1e-8 * resampled.cost);

  PlanAttitudeManeuver::Request bad = req;
  bad.initial_guess.attitude[3] = geometry_msgs::Quaternion();
  const PlanAttitudeManeuver::Response zero = call(bad);
  EXPECT_EQ(zero.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(zero.message.find("initial_guess.attitude[3]: zero quaternion"), std::string::npos)
      << zero.message;
  bad = req;
  bad.initial_guess.attitude.resize(1);
  bad.initial_guess.angular_velocity.clear();
  bad.initial_guess.torque.clear();
  const PlanAttitudeManeuver::Response one_row = call(bad);
  EXPECT_EQ(one_row.error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(one_row.message.find("initial_guess: needs at least 2 rows (N >= 1), got 1"),
            std::string::npos)
      << one_row.message;
  EXPECT_TRUE(call(seed(16)).success);
}

TEST_F(PlannerService, DiagnosticsCountTheAnswersByErrorCode) {
  // Each planner node publishes its status on /diagnostics every second; a bad request shows up
  // as one more INVALID_INPUT answer of this node (not of the /capped one).
  ros_testing::StatusWatch watch("/attitude_planner: planner");
  const auto any = [](const std::string&) { return true; };
  const std::string before = watch.waitFor("answered", any, 5.0);
  ASSERT_NE(before, "(not seen)") << "no status named '/attitude_planner: planner' on /diagnostics";
  const int answered = std::stoi(before);
  const std::string failed = watch.waitFor("failed INVALID_INPUT", any, 0.0);
  const int invalid = failed == "(not seen)" ? 0 : std::stoi(failed);
  PlanAttitudeManeuver::Request bad = seed();
  bad.steps = 2;
  EXPECT_EQ(call(bad).error_code.val, PlanErrorCode::INVALID_INPUT);
  EXPECT_NE(watch.waitFor(
                "failed INVALID_INPUT",
                [&](const std::string& v) { return std::stoi(v) == invalid + 1; }, 5.0),
            "(not seen)");
  EXPECT_NE(
      watch.waitFor(
          "answered", [&](const std::string& v) { return std::stoi(v) >= answered + 1; }, 5.0),
      "(not seen)");
  EXPECT_EQ(watch.waitFor("last answer", any, 5.0), "INVALID_INPUT");
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_planner_service");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
