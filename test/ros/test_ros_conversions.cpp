// Unit tests of the ROS adapters that need no ROS master: conversions, request parsing, the box.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <regex>
#include <set>
#include <thread>
#include <tuple>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanAttitudeManeuverAction.h"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "attitude_planner/ros/diagnostics.hpp"
#include "attitude_planner/ros/markers.hpp"
#include "attitude_planner/ros/planner_node.hpp"
#include "attitude_planner/ros/tracker_node.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

PlanAttitudeManeuver::Request seedRequest() {
  PlanAttitudeManeuver::Request r;
  const double J[9] = {13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37};
  for (int i = 0; i < 9; ++i) r.inertia[i] = J[i];
  r.allow_nonphysical_inertia = true;  // the seed J violates J1 + J2 >= J3
  r.initial_attitude.w = 1.0;
  r.final_attitude = rc::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3));
  r.duration = 12.8;
  r.steps = 32;
  return r;
}

std::string invalidMessage(const PlanAttitudeManeuver::Request& r) {
  const PlanOutcome out = planRequest(r, rc::PlannerDefaults(), nullptr);
  EXPECT_EQ(out.error_code, PlanErrorCode::INVALID_INPUT) << out.message;
  EXPECT_FALSE(out.solver_ran);
  return out.message;
}

}  // namespace

TEST(RosConversions, QuaternionRoundTripIsExact) {
  const Matrix3 R = so3::fromAxisAngle(Vector3(1, -2, 0.5), 2.3);
  const Matrix3 back = rc::attitudeFromMsg(rc::attitudeToMsg(R), "q");
  EXPECT_LT(so3::angleBetween(R, back), 1e-15);
}

TEST(RosConversions, InertiaIsRowMajor) {
  boost::array<double, 9> j = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  const Matrix3 J = rc::inertiaFromMsg(j);
  EXPECT_EQ(J(0, 1), 2.0);
  EXPECT_EQ(J(1, 0), 4.0);
  EXPECT_EQ(rc::inertiaToMsg(J), j);
}

TEST(RosConversions, ZeroQuaternionNamesTheField) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.final_attitude = geometry_msgs::Quaternion();  // (0, 0, 0, 0): a forgotten field
  const std::string m = invalidMessage(r);
  EXPECT_NE(m.find("final_attitude"), std::string::npos) << m;
  EXPECT_NE(m.find("zero quaternion"), std::string::npos) << m;
}

TEST(RosConversions, NonUnitAndNanQuaternionsAreRejected) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.initial_attitude.w = 1.1;
  EXPECT_NE(invalidMessage(r).find("initial_attitude: not a unit quaternion"), std::string::npos);
  r.initial_attitude.w = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(invalidMessage(r).find("initial_attitude: quaternion not finite"), std::string::npos);
}

TEST(RosConversions, BadFieldsAreNamedWithTheirValue) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.inertia[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(invalidMessage(r).find("inertia"), std::string::npos);
  r = seedRequest();
  r.steps = 2;
  EXPECT_NE(invalidMessage(r).find("steps: must be >= 4, got 2"), std::string::npos);
  r = seedRequest();
  r.steps = 1000000;
  EXPECT_NE(invalidMessage(r).find("steps: 1000000 exceeds"), std::string::npos);
  r = seedRequest();
  r.scheme = "euler";
  EXPECT_NE(invalidMessage(r).find("scheme: unknown value 'euler'"), std::string::npos);
  r = seedRequest();
  r.solver = "magic";
  EXPECT_NE(invalidMessage(r).find("solver: unknown value 'magic'"), std::string::npos);
  r = seedRequest();
  r.duration = -1.0;
  EXPECT_NE(invalidMessage(r).find("duration"), std::string::npos);
  r = seedRequest();
  r.time_budget = -3.0;
  EXPECT_NE(invalidMessage(r).find("time_budget"), std::string::npos);
}

TEST(RosConversions, HostileRequestsGetTheirErrorCodeNamingFieldAndValue) {
  // Every bad request is refused with a specific message and code, never a crash. With
  // AP_BAD_INPUT_TABLE=<file> the rows are also written as markdown (docs/results/robustness.md).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    std::string what;
    std::function<void(PlanAttitudeManeuver::Request*)> edit;
    int code;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"inertia[4] = NaN", [&](auto* r) { r->inertia[4] = nan; }, PlanErrorCode::INVALID_INPUT,
       "inertia: not finite"},
      {"duration = Inf", [&](auto* r) { r->duration = inf; }, PlanErrorCode::INVALID_INPUT,
       "duration: must be a finite number > 0 s, got inf"},
      {"initial_angular_velocity.y = NaN", [&](auto* r) { r->initial_angular_velocity.y = nan; },
       PlanErrorCode::INVALID_INPUT, "initial_angular_velocity: not finite"},
      {"final_angular_velocity.z = -Inf", [&](auto* r) { r->final_angular_velocity.z = -inf; },
       PlanErrorCode::INVALID_INPUT, "final_angular_velocity: not finite"},
      {"final_attitude.x = NaN", [&](auto* r) { r->final_attitude.x = nan; },
       PlanErrorCode::INVALID_INPUT, "final_attitude: quaternion not finite"},
      {"inertia not symmetric (J01 = 0)", [&](auto* r) { r->inertia[1] = 0.0; },
       PlanErrorCode::INVALID_INPUT, "inertia: not symmetric"},
      {"inertia not positive definite (J00 = -1)", [&](auto* r) { r->inertia[0] = -1.0; },
       PlanErrorCode::INVALID_INPUT, "inertia: not positive definite"},
      {"seed J without allow_nonphysical_inertia",
       [&](auto* r) { r->allow_nonphysical_inertia = false; }, PlanErrorCode::INVALID_INPUT,
       "violate the triangle inequality J1 + J2 >= J3"},
      {"inertia diag(1, 1e13, 1e13) (condition 1e13)",
       [&](auto* r) {
         r->inertia = {1, 0, 0, 0, 1e13, 0, 0, 0, 1e13};
         r->allow_nonphysical_inertia = false;
       },
       PlanErrorCode::INVALID_INPUT, "inertia: condition number 10000000000000"},
      {"final_attitude = (0, 0, 0, 0)",
       [&](auto* r) { r->final_attitude = geometry_msgs::Quaternion(); },
       PlanErrorCode::INVALID_INPUT, "final_attitude: zero quaternion"},
      {"initial_attitude = (2, 0, 0, 0)", [&](auto* r) { r->initial_attitude.w = 2.0; },
       PlanErrorCode::INVALID_INPUT,
       "initial_attitude: not a unit quaternion: [2, 0, 0, 0] has norm 2 (must be within 0.001 of "
       "1"},
      {"duration = 0", [&](auto* r) { r->duration = 0.0; }, PlanErrorCode::INVALID_INPUT,
       "duration: must be a finite number > 0 s, got 0"},
      {"duration = -12.8", [&](auto* r) { r->duration = -12.8; }, PlanErrorCode::INVALID_INPUT,
       "duration: must be a finite number > 0 s, got -12.8"},
      {"steps = 3", [&](auto* r) { r->steps = 3; }, PlanErrorCode::INVALID_INPUT,
       "steps: must be >= 4, got 3"},
      {"steps = -2147483648", [&](auto* r) { r->steps = std::numeric_limits<int>::min(); },
       PlanErrorCode::INVALID_INPUT, "steps: must be >= 4, got -2147483648"},
      {"steps = 2147483647 (> ~max_steps)",
       [&](auto* r) { r->steps = std::numeric_limits<int>::max(); }, PlanErrorCode::INVALID_INPUT,
       "steps: 2147483647 exceeds the node's ~max_steps = 100000"},
      {"tolerance = -1e-12", [&](auto* r) { r->tolerance = -1e-12; }, PlanErrorCode::INVALID_INPUT,
       "tolerance: must be a finite number >= 0 (0 = default), got -9.9999999999999998e-13"},
      {"tolerance = NaN", [&](auto* r) { r->tolerance = nan; }, PlanErrorCode::INVALID_INPUT,
       "tolerance: must be a finite number >= 0 (0 = default), got nan"},
      {"max_iterations = -1", [&](auto* r) { r->max_iterations = -1; },
       PlanErrorCode::INVALID_INPUT, "max_iterations: must be >= 0 (0 = default), got -1"},
      {"time_budget = -3", [&](auto* r) { r->time_budget = -3.0; }, PlanErrorCode::INVALID_INPUT,
       "time_budget: must be a finite number >= 0 s (0 = default), got -3"},
      {"scheme = \"rk4\"", [&](auto* r) { r->scheme = "rk4"; }, PlanErrorCode::INVALID_INPUT,
       "scheme: unknown value 'rk4'"},
      {"direction = \"sideways\"", [&](auto* r) { r->direction = "sideways"; },
       PlanErrorCode::INVALID_INPUT, "direction: unknown value 'sideways'"},
      {"extra_revolutions = -1", [&](auto* r) { r->extra_revolutions = -1; },
       PlanErrorCode::INVALID_INPUT, "extra_revolutions: must be >= 0"},
      {"effects[0].type = \"torque_noise\"",
       [&](auto* r) {
         r->effects = {rc::effectToMsg(TorqueNoiseSpec{Vector3(1e-4, 0, 0), 1})};
       },
       PlanErrorCode::INVALID_INPUT, "torque_noise"},
      {"initial_angular_velocity.z = 40, duration 1, steps 8 (h|Ω| = 5)",
       [&](auto* r) {
         r->initial_angular_velocity.z = 40.0;
         r->duration = 1.0;
         r->steps = 8;
       },
       PlanErrorCode::STEP_TOO_LARGE, "initial_angular_velocity: step too large, increase steps"},
  };
  std::ofstream table;
  if (const char* path = std::getenv("AP_BAD_INPUT_TABLE")) table.open(path);
  for (const Case& c : cases) {
    PlanAttitudeManeuver::Request r = seedRequest();
    c.edit(&r);
    const PlanOutcome out = planRequest(r, rc::PlannerDefaults(), nullptr);
    EXPECT_EQ(out.error_code, c.code) << c.what << ": " << out.message;
    EXPECT_NE(out.message.find(c.expected), std::string::npos)
        << c.what << ": '" << out.message << "' lacks '" << c.expected << "'";
    PlanAttitudeManeuver::Response res;
    fillResponse(out, "world", "body", &res);
    EXPECT_FALSE(res.success) << c.what;
    EXPECT_TRUE(res.maneuver.attitude.empty()) << c.what;
    if (table) {
      std::string message = out.message;
      for (char& ch : message) ch = ch == '|' ? '/' : ch;
      table << "| " << c.what << " | " << out.error_code << " | `" << message << "` |\n";
    }
  }
  // Accepted: a near-unit quaternion (normalized) and w < 0.
  PlanAttitudeManeuver::Request near = seedRequest();
  near.initial_attitude.w = -1.0005;
  SolverOptions options;
  const PlanningProblem p = rc::problemFromRequest(near, rc::PlannerDefaults(), &options);
  EXPECT_LT(so3::angleBetween(p.initial_attitude, Matrix3::Identity()), 1e-15);
}

TEST(RosConversions, TheTrailAndTheMinimumTimeSummaryReachTheResponseNamedAsInTheJson) {
  // A minimum-time request (a torque bound, rest to rest): its trail has free-time solves, a
  // polish and one kept attempt; every field of every attempt and of the summary is copied.
  ros::Time::init();  // fillResponse stamps the maneuver; no master is needed
  PlanAttitudeManeuver::Request r = seedRequest();
  r.objective = "minimum_time";
  r.duration = 0.0;
  r.effects = {rc::effectToMsg(ActuatorLimitsSpec{Vector3(0.3, 0.4, 0.5)})};
  const PlanOutcome out = planRequest(r, rc::PlannerDefaults(), nullptr);
  ASSERT_EQ(out.error_code, PlanErrorCode::SUCCESS) << out.message;
  PlanAttitudeManeuver::Response res;
  fillResponse(out, "world", "body", &res);
  const std::vector<Attempt>& trail = out.result.attempts;
  ASSERT_FALSE(trail.empty());
  ASSERT_EQ(res.attempts.size(), trail.size());
  int kept = 0;
  for (std::size_t i = 0; i < trail.size(); ++i) {
    const PlanAttempt& m = res.attempts[i];
    EXPECT_EQ(m.stage, attemptStageName(trail[i].stage)) << i;
    EXPECT_EQ(m.start, attemptStartName(trail[i].start)) << i;
    EXPECT_EQ(m.formulation, formulationName(trail[i].formulation)) << i;
    EXPECT_EQ(m.long_way, trail[i].homotopy.long_way) << i;
    EXPECT_EQ(m.extra_revolutions, trail[i].homotopy.extra_revolutions) << i;
    EXPECT_EQ(m.steps, trail[i].steps) << i;
    EXPECT_EQ(m.termination, terminationName(trail[i].termination)) << i;
    EXPECT_EQ(m.iterations, trail[i].iterations) << i;
    EXPECT_TRUE(m.cost == trail[i].cost || (std::isnan(m.cost) && std::isnan(trail[i].cost))) << i;
    EXPECT_EQ(m.kept, trail[i].kept) << i;
    kept += m.kept ? 1 : 0;
    const StartDetail& d = trail[i].start_detail;
    const PlanAttemptStart& ms = m.start_detail;
    EXPECT_TRUE(ms.duration == d.duration || (std::isnan(ms.duration) && std::isnan(d.duration)))
        << i;
    EXPECT_EQ(ms.eigenaxis.x, d.eigenaxis.x()) << i;
    EXPECT_EQ(ms.eigenaxis.y, d.eigenaxis.y()) << i;
    EXPECT_EQ(ms.eigenaxis.z, d.eigenaxis.z()) << i;
    EXPECT_EQ(ms.excursion_axis.x, d.excursion_axis.x()) << i;
    EXPECT_EQ(ms.excursion_axis.y, d.excursion_axis.y()) << i;
    EXPECT_EQ(ms.excursion_axis.z, d.excursion_axis.z()) << i;
    EXPECT_EQ(ms.excursion, d.excursion) << i;
    EXPECT_EQ(ms.excursion_peak, d.excursion_peak) << i;
    EXPECT_EQ(ms.cleared_of_cones, d.cleared_of_cones) << i;
    EXPECT_EQ(ms.coarse_steps, d.coarse_steps) << i;
    EXPECT_EQ(ms.elastic_from_violations, d.elastic_from_violations) << i;
    EXPECT_EQ(ms.origin, attemptStartName(originOf(trail[i]))) << i;
  }
  EXPECT_EQ(kept, 1);
  // The structured starts carry their parameters: an excursion names its axis and size.
  EXPECT_TRUE(std::any_of(res.attempts.begin(), res.attempts.end(), [](const PlanAttempt& m) {
    return m.start == "excursion" && m.start_detail.excursion > 0 && m.start_detail.duration > 0;
  }));
  EXPECT_TRUE(std::any_of(res.attempts.begin(), res.attempts.end(),
                          [](const PlanAttempt& m) { return m.stage == "minimum_time_solve"; }));
  EXPECT_EQ(res.minimum_time.kkt_point, out.result.minimum_time.kkt_point);
  EXPECT_TRUE(res.minimum_time.kkt_point) << out.details;
  EXPECT_EQ(res.minimum_time.stationarity, out.result.minimum_time.stationarity);
  EXPECT_EQ(res.minimum_time.time_stationarity, out.result.minimum_time.time_stationarity);
  EXPECT_EQ(res.minimum_time.complementarity, out.result.minimum_time.complementarity);
  EXPECT_EQ(res.minimum_time.solves, out.result.minimum_time.solves);
  EXPECT_EQ(res.minimum_time.second_order_sufficient,
            out.result.minimum_time.second_order_sufficient);
  EXPECT_GT(res.minimum_duration, 0.0);
}

TEST(RosConversions, DirectionAndExtraRevolutionsReachTheProblem) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.direction = "long_way";
  r.extra_revolutions = 2;
  SolverOptions options;
  const PlanningProblem p = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  EXPECT_EQ(p.direction, RotationDirection::LongWay);
  EXPECT_EQ(p.extra_revolutions, 2);
  r.direction = "";
  EXPECT_EQ(rc::problemFromRequest(r, rc::PlannerDefaults(), &options).direction,
            RotationDirection::Shortest);
}

TEST(RosConversions, MaxSolveTimeCapsEveryRequestsBudget) {
  rc::PlannerDefaults d;
  d.time_budget = 0.0;  // "none" by default ...
  d.max_solve_time = 7.0;
  SolverOptions options;
  PlanAttitudeManeuver::Request r = seedRequest();
  rc::problemFromRequest(r, d, &options);
  EXPECT_EQ(options.time_budget_s, 7.0);  // ... is still bounded
  r.time_budget = 1e9;
  rc::problemFromRequest(r, d, &options);
  EXPECT_EQ(options.time_budget_s, 7.0);
  r.time_budget = 2.0;
  rc::problemFromRequest(r, d, &options);
  EXPECT_EQ(options.time_budget_s, 2.0);
}

TEST(RosConversions, EffectMessagesRoundTrip) {
  const std::vector<EffectSpec> specs = {
      GravityGradientSpec{3.986004418e14, 6.778e6},
      DisturbanceTorqueSpec{TorqueFrame::World, Vector3(2e-4, 0.0, -1e-4)},
      ActuatorLimitsSpec{Vector3(0.3, 0.4, 0.5)},
      TorqueNoiseSpec{Vector3(1e-4, 2e-4, 0.0), 7},
  };
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const Effect msg = rc::effectToMsg(specs[i]);
    EXPECT_EQ(msg.type, effectName(specs[i]));
    const EffectSpec back = rc::effectFromMsg(msg, "effects[0]");
    ASSERT_EQ(back.index(), specs[i].index());
    EXPECT_EQ(rc::effectToMsg(back), msg) << msg.type;
  }
}

TEST(RosConversions, ConstraintMessagesRoundTrip) {
  const std::vector<PlanningConstraint> constraints = {
      PlanningConstraint::maxTorqueNorm(0.5), PlanningConstraint::maxAngularRate(0.2),
      PlanningConstraint::keepOut(Vector3(0, 0, 1), Vector3(0.6, 0.8, 0), 0.5, 0.01),
      PlanningConstraint::keepIn(Vector3(1, 0, 0), Vector3(0, 0, -1), 1.2)};
  for (const PlanningConstraint& c : constraints) {
    const Constraint msg = rc::constraintToMsg(c);
    EXPECT_EQ(msg.type, constraintKindName(c.kind));
    const PlanningConstraint back = rc::constraintFromMsg(msg, "constraints[0]");
    EXPECT_EQ(back.kind, c.kind);
    EXPECT_EQ(back.limit, c.isCone() ? 0.0 : c.limit);
    if (c.isCone()) {
      EXPECT_EQ(back.body_axis, c.body_axis);
      EXPECT_EQ(back.world_direction, c.world_direction);
      EXPECT_EQ(back.half_angle, c.half_angle);
      EXPECT_EQ(back.margin, c.margin);
    }
    EXPECT_EQ(rc::constraintToMsg(back), msg) << msg.type;
  }
  // A margin on a kind that has none is named.
  Constraint bad = rc::constraintToMsg(constraints[0]);
  bad.margin = 0.1;
  try {
    rc::constraintFromMsg(bad, "constraints[3]");
    ADD_FAILURE() << "margin on max_torque_norm accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("constraints[3]: body_axis, "
                                         "world_direction, half_angle and margin are not used"),
              std::string::npos)
        << e.what();
  }
}

TEST(RosConversions, BadEffectsNameTheFieldAndTheValue) {
  auto message = [](const std::vector<Effect>& effects) {
    PlanAttitudeManeuver::Request r = seedRequest();
    r.effects = effects;
    return invalidMessage(r);
  };
  Effect unknown;
  unknown.type = "solar_pressure";
  EXPECT_NE(message({unknown}).find("effects[0].type: unknown value 'solar_pressure'"),
            std::string::npos);
  Effect gravity = rc::effectToMsg(GravityGradientSpec{3.986004418e14, 6.778e6});
  gravity.mu = -1.0;
  EXPECT_NE(message({gravity}).find("effects[0].mu: must be finite and > 0"), std::string::npos);
  Effect stray = rc::effectToMsg(GravityGradientSpec{3.986004418e14, 6.778e6});
  stray.value.x = 1.0;  // not read by gravity_gradient: a mistake, not a default
  EXPECT_NE(message({stray}).find("effects[0].value: not used by type 'gravity_gradient'"),
            std::string::npos);
  Effect frame = rc::effectToMsg(DisturbanceTorqueSpec{TorqueFrame::Body, Vector3(1e-3, 0, 0)});
  frame.frame = "orbit";
  EXPECT_NE(message({frame}).find("effects[0].frame: unknown value 'orbit'"), std::string::npos);
  Effect limits = rc::effectToMsg(ActuatorLimitsSpec{Vector3(1.0, 1.0, 1.0)});
  limits.value.y = 0.0;
  EXPECT_NE(message({limits}).find("effects[0].value.y: must be > 0 N m, got 0"),
            std::string::npos);
  const Effect good = rc::effectToMsg(GravityGradientSpec{3.986004418e14, 6.778e6});
  EXPECT_NE(message({good, good}).find("effects[1]: duplicate effect"), std::string::npos);
  const Effect noise = rc::effectToMsg(TorqueNoiseSpec{Vector3(1e-4, 1e-4, 1e-4), 3});
  EXPECT_NE(message({noise}).find("effects[0].type: 'torque_noise' is not plannable"),
            std::string::npos);
}

TEST(RosConversions, RequestEffectsEnterThePlanningModel) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.effects.push_back(
      rc::effectToMsg(DisturbanceTorqueSpec{TorqueFrame::Body, Vector3(1e-3, 0.0, 0.0)}));
  SolverOptions options;
  PlanningProblem p = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  ASSERT_TRUE(p.effects);
  EXPECT_EQ(p.effects->names(), std::vector<std::string>{"disturbance_torque"});
  EXPECT_EQ(p.effects->torque(Matrix3::Identity(), 0.0), Vector3(1e-3, 0.0, 0.0));
  EXPECT_FALSE(p.hasTorqueBounds());

  r = seedRequest();
  r.effects.push_back(rc::effectToMsg(ActuatorLimitsSpec{Vector3(0.3, 0.4, 0.5)}));
  p = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  EXPECT_FALSE(p.effects);
  EXPECT_EQ(p.max_torque, Vector3(0.3, 0.4, 0.5));
}

// start_time moves the effects' clock (the tracker's re-plan of the rest of a maneuver from t_r):
// the gravity gradient at t is the unshifted one at start_time + t; a bad value is named.
TEST(RosConversions, StartTimeShiftsTheEffectsClock) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.effects.push_back(rc::effectToMsg(GravityGradientSpec{3.986004418e14, 6.778e6}));
  SolverOptions options;
  const PlanningProblem unshifted = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  r.start_time = 250.0;
  const PlanningProblem shifted = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  ASSERT_TRUE(shifted.effects);
  EXPECT_EQ(shifted.effects->names(), std::vector<std::string>{"gravity_gradient"});
  const Matrix3 R = so3::fromAxisAngle(Vector3(0.3, -1.0, 0.4).normalized(), 0.9);
  EXPECT_LT((shifted.effects->torque(R, 10.0) - unshifted.effects->torque(R, 260.0)).norm(), 1e-18);
  EXPECT_GT((shifted.effects->torque(R, 10.0) - unshifted.effects->torque(R, 10.0)).norm(), 1e-6);
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
    r.start_time = bad;
    try {
      rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
      ADD_FAILURE() << "start_time " << bad << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()).rfind("start_time: must be a finite number >= 0 s", 0), 0u)
          << e.what();
    }
  }
}

TEST(RosConversions, DefaultsFillEmptyFields) {
  rc::PlannerDefaults d;
  d.scheme = SchemeKind::Variational;
  d.tolerance = 1e-7;
  d.max_iterations = 17;
  d.time_budget = 3.0;
  SolverOptions options;
  const PlanningProblem p = rc::problemFromRequest(seedRequest(), d, &options);
  EXPECT_EQ(p.scheme, SchemeKind::Variational);
  EXPECT_EQ(options.solver, SolverKind::Structured);
  EXPECT_EQ(options.tolerance, 1e-7);
  EXPECT_EQ(options.max_iterations, 17);
  EXPECT_EQ(options.time_budget_s, 3.0);
  EXPECT_EQ(p.steps, 32);
  EXPECT_LT(so3::angleBetween(p.final_attitude, so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3)),
            1e-15);
}

TEST(RosConversions, StepsLeftAtZeroTakeTheNodesDefaultSteps) {
  // A request that leaves steps at 0 takes the node's default (empty/0 fields do), not a refusal
  // ("steps: must be >= 4, got 0").
  rc::PlannerDefaults d;
  EXPECT_EQ(d.steps, 128);
  PlanAttitudeManeuver::Request r = seedRequest();
  r.steps = 0;
  SolverOptions options;
  EXPECT_EQ(rc::problemFromRequest(r, d, &options).steps, 128);
  d.steps = 64;
  EXPECT_EQ(rc::problemFromRequest(r, d, &options).steps, 64);
  PlanDriftTwoInput::Request drift;
  drift.initial_attitude.w = 1.0;
  drift.final_attitude.w = 1.0;
  drift.duration = 1.0;
  drift.control_weights = {1.0, 1.0};
  EXPECT_EQ(rc::driftRequestFromMsg(drift, d).steps, 64);
  // A negative N is still refused by the planner's own rule, naming the value.
  r.steps = -1;
  EXPECT_NE(invalidMessage(r).find("steps: must be >= 4, got -1"), std::string::npos);
}

TEST(RosConversions, EffectTypeConstantsAreTheEffectNames) {
  // Effect.msg spells the types as constants; the core's name table must agree with them.
  EXPECT_EQ(Effect::GRAVITY_GRADIENT, effectKindName(EffectKind::GravityGradient));
  EXPECT_EQ(Effect::DISTURBANCE_TORQUE, effectKindName(EffectKind::DisturbanceTorque));
  EXPECT_EQ(Effect::ACTUATOR_LIMITS, effectKindName(EffectKind::ActuatorLimits));
  EXPECT_EQ(Effect::TORQUE_NOISE, effectKindName(EffectKind::TorqueNoise));
}

TEST(RosConversions, ManeuverMessageRoundTrip) {
  const Matrix3 J = rc::inertiaFromMsg(seedRequest().inertia);
  const DiscreteScheme scheme(SchemeKind::Paper, J, 0.1);
  SimulationInput input;
  input.torque.assign(9, Vector3::Zero());
  for (int k = 1; k < 8; ++k) input.torque[k] = Vector3(0.1 * k, -0.2, 0.05);
  const Maneuver m = simulate(scheme, input);
  PlanningProblem p;
  p.inertia = J;
  const AttitudeManeuver msg = rc::maneuverToMsg(m, p, "world", "body", ros::Time(0));
  EXPECT_EQ(msg.attitude.size(), 9u);
  EXPECT_EQ(msg.header.frame_id, "world");
  EXPECT_EQ(msg.child_frame_id, "body");
  EXPECT_EQ(msg.scheme, "paper");
  const Maneuver back = rc::maneuverFromMsg(msg);
  for (int k = 0; k <= 8; ++k) {
    EXPECT_LT(so3::angleBetween(back.attitude[k], m.attitude[k]), 1e-15);
    EXPECT_EQ(back.torque[k], m.torque[k]);
  }
  AttitudeManeuver bad = msg;
  bad.torque.pop_back();
  EXPECT_THROW(rc::maneuverFromMsg(bad), InvalidInput);
}

TEST(RosConversions, DriftManeuverMessageRoundTrip) {
  const DriftTwoInputWeights w{1.0, 2.0};
  const DriftTwoInputTrajectory tr = integrateDriftTwoInputExtremal(
      so3::fromAxisAngle(Vector3(0, 1, 1), 0.3), Vector3(-1.5, 0.5, 1.0), 2.0, 20, w);
  const DriftTwoInputManeuver m = rc::driftManeuverToMsg(tr, w, "world", "body", ros::Time(12.0));
  EXPECT_EQ(m.header.frame_id, "world");
  EXPECT_EQ(m.child_frame_id, "body");
  EXPECT_DOUBLE_EQ(m.time_step, 0.1);
  ASSERT_EQ(m.control.size(), 21u);
  DriftTwoInputWeights back_w;
  const DriftTwoInputTrajectory back = rc::driftManeuverFromMsg(m, &back_w);
  EXPECT_EQ(back_w.c1, 1.0);
  EXPECT_EQ(back_w.c2, 2.0);
  ASSERT_EQ(back.g.size(), 21u);
  for (int k = 0; k <= 20; ++k) {
    EXPECT_EQ(back.t[k], tr.t[k]);
    EXPECT_EQ(back.u[k], tr.u[k]);
    EXPECT_EQ(back.p[k], tr.p[k]);
    EXPECT_LT(so3::angleBetween(back.g[k], tr.g[k]), 1e-15);
    EXPECT_EQ(m.control[k].z, 0.0);
  }
  DriftTwoInputManeuver bad = m;
  bad.control[3].z = 1.0;
  EXPECT_THROW(rc::driftManeuverFromMsg(bad, &back_w), InvalidInput);
  bad = m;
  bad.costate.pop_back();
  EXPECT_THROW(rc::driftManeuverFromMsg(bad, &back_w), InvalidInput);
  bad = m;
  bad.control_weights[0] = -1.0;
  EXPECT_THROW(rc::driftManeuverFromMsg(bad, &back_w), InvalidInput);
}

TEST(RosConversions, DriftRequestFieldsAreNamed) {
  PlanDriftTwoInput::Request r;
  r.initial_attitude.w = 1.0;
  r.final_attitude.w = 1.0;
  r.duration = 3.0;
  r.steps = 60;
  r.control_weights = {1.0, 2.0};
  const rc::PlannerDefaults d;
  DriftTwoInputRequest req = rc::driftRequestFromMsg(r, d);
  EXPECT_FALSE(req.initial_costate.has_value());
  EXPECT_EQ(req.tolerance, 1e-11);  // 0 = the core's default
  EXPECT_EQ(req.max_iterations, 200);
  EXPECT_EQ(req.shooting_intervals, 1);
  r.use_initial_costate = true;
  r.initial_costate.x = 0.5;
  req = rc::driftRequestFromMsg(r, d);
  ASSERT_TRUE(req.initial_costate.has_value());
  EXPECT_EQ(*req.initial_costate, Vector3(0.5, 0, 0));
  auto message = [&](PlanDriftTwoInput::Request bad) {
    try {
      rc::driftRequestFromMsg(bad, d);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  PlanDriftTwoInput::Request bad = r;
  bad.duration = 0.0;
  EXPECT_EQ(message(bad).rfind("duration:", 0), 0u) << message(bad);
  bad = r;
  bad.steps = d.max_steps + 1;
  EXPECT_EQ(message(bad).rfind("steps:", 0), 0u) << message(bad);
  bad = r;
  bad.control_weights[0] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message(bad).rfind("control_weights[0]:", 0), 0u) << message(bad);
  bad = r;
  bad.shooting_intervals = -1;
  EXPECT_EQ(message(bad).rfind("shooting_intervals:", 0), 0u) << message(bad);
}

TEST(RosConversions, EveryTerminationHasItsOwnErrorCode) {
  // One switch maps the core's status to the interface's: each termination gets a distinct code,
  // SUCCESS only for Converged, and none falls through to INTERNAL_ERROR.
  const std::pair<Termination, int> expected[] = {
      {Termination::Converged, PlanErrorCode::SUCCESS},
      {Termination::NotConverged, PlanErrorCode::NOT_CONVERGED},
      {Termination::Infeasible, PlanErrorCode::INFEASIBLE},
      {Termination::StepTooLarge, PlanErrorCode::STEP_TOO_LARGE},
      {Termination::TimedOut, PlanErrorCode::TIMED_OUT},
      {Termination::Cancelled, PlanErrorCode::CANCELLED},
      {Termination::InvalidInput, PlanErrorCode::INVALID_INPUT}};
  std::set<int> codes;
  for (const auto& [termination, code] : expected) {
    EXPECT_EQ(errorCodeOf(termination), code) << terminationName(termination);
    codes.insert(errorCodeOf(termination));
  }
  EXPECT_EQ(codes.size(), std::size(expected));
}

TEST(RosConversions, ExceptionsMapThroughTheSameSwitch) {
  int code = 0;
  std::string message;
  try {
    throw InvalidInput("steps: must be >= 4, got 2");
  } catch (...) {
    describeCurrentException(&code, &message);
  }
  EXPECT_EQ(code, PlanErrorCode::INVALID_INPUT);
  EXPECT_EQ(message, "steps: must be >= 4, got 2");
  try {
    throw StepTooLarge("increase steps");
  } catch (...) {
    describeCurrentException(&code, &message);
  }
  EXPECT_EQ(code, PlanErrorCode::STEP_TOO_LARGE);
  try {
    throw std::runtime_error("boom");
  } catch (...) {
    describeCurrentException(&code, &message);
  }
  EXPECT_EQ(code, PlanErrorCode::INTERNAL_ERROR);
  EXPECT_EQ(message, "internal error: boom");
}

TEST(PrincipalBox, UniformBoxMomentsAreRecovered) {
  // A uniform box 1 × 2 × 3 m (mass 12 kg): J = diag(b²+c², a²+c², a²+b²) = diag(13, 10, 5).
  const Matrix3 R = so3::fromAxisAngle(Vector3(0.3, 1, -0.2), 0.9);
  const Matrix3 J = R * Vector3(13, 10, 5).asDiagonal() * R.transpose();
  const PrincipalBox box = principalBox(J, 3.0);
  EXPECT_NEAR(box.moments(0), 5.0, 1e-12);
  EXPECT_NEAR(box.dimensions(0), 3.0, 1e-12);  // smallest moment ↔ longest edge
  EXPECT_NEAR(box.dimensions(1), 2.0, 1e-12);
  EXPECT_NEAR(box.dimensions(2), 1.0, 1e-12);
  EXPECT_NEAR(box.axes.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(box.axes.col(0).dot(R.col(2))), 1.0, 1e-12);
}

TEST(PrincipalBox, MarkersAreTheBoxThreeAxesAndTheTracedAxisInTheBodyFrame) {
  const PrincipalBox box = principalBox(Vector3(5, 10, 13).asDiagonal().toDenseMatrix(), 1.0);
  const visualization_msgs::MarkerArray a = bodyMarkers(box, 0.9, 1.2, "body", ros::Time(3.0));
  ASSERT_EQ(a.markers.size(), 5u);
  EXPECT_EQ(a.markers[0].type, visualization_msgs::Marker::CUBE);
  for (const visualization_msgs::Marker& m : a.markers) {
    EXPECT_EQ(m.header.frame_id, "body");
    EXPECT_EQ(m.header.stamp, ros::Time(3.0));
  }
  for (int i = 1; i <= 4; ++i) EXPECT_EQ(a.markers[i].type, visualization_msgs::Marker::ARROW);
  EXPECT_DOUBLE_EQ(a.markers[4].points[1].x, 1.2);  // tip of body x at path_radius [m]
}

namespace {

/// A keep_out and a keep_in cone and a pointing end condition, all with unnormalized vectors.
std::vector<PlanningConstraint> twoCones() {
  PlanningConstraint out;
  out.kind = ConstraintKind::KeepOut;
  out.body_axis = Vector3(2, 0, 0);
  out.world_direction = Vector3(0.7, 0.7, 0.1);
  out.half_angle = 0.5;
  PlanningConstraint in = out;
  in.kind = ConstraintKind::KeepIn;
  in.body_axis = Vector3(0, 0, 1);
  in.world_direction = Vector3(0, 0, -3);
  in.half_angle = 1.2;
  return {out, in};
}

EndCondition pointingAt() {
  EndCondition end;
  end.kind = EndConditionKind::Pointing;
  end.body_axis = Vector3(0, 1, 1);
  end.world_direction = Vector3(1, -2, 0.5);
  return end;
}

/// Three orthogonal wheels, H = (1, 2, 1) N m s, U = (0.2, 0.3, 0.4) N m, a small bias.
ReactionWheels threeWheels() {
  ReactionWheels w;
  w.spin_axes = {Vector3::UnitX(), Vector3::UnitY(), Vector3::UnitZ()};
  w.max_torque = {0.2, 0.3, 0.4};
  w.max_momentum = {1.0, 2.0, 1.0};
  w.initial_momentum = {0.1, -0.2, 0.0};
  return w;
}

Vector3 tipOf(const visualization_msgs::Marker& arrow) {
  return Vector3(arrow.points[1].x, arrow.points[1].y, arrow.points[1].z);
}

}  // namespace

TEST(WheelMarkers, BarsStandInProportionToTheMomentumWithTheLimitSlabAtFullHeight) {
  const ReactionWheels wheels = threeWheels();  // H = 1, 2, 1 N m s
  const visualization_msgs::MarkerArray bars =
      wheelMomentumMarkers(wheels, Eigen::Vector3d(0.5, -1.0, 2.0), 1.0, "world", ros::Time(2.0));
  ASSERT_EQ(bars.markers.size(), 6u);
  const double full = kWheelBarHeight;
  const double expected[3] = {0.5 * full, 0.5 * full, kWheelBarMostFraction * full};  // 2 > 1.5 H
  double previous_y = -1e9;
  for (int i = 0; i < 3; ++i) {
    const visualization_msgs::Marker& bar = bars.markers[2 * i];
    const visualization_msgs::Marker& slab = bars.markers[2 * i + 1];
    EXPECT_EQ(bar.ns, "wheel_momentum");
    EXPECT_EQ(slab.ns, "wheel_momentum_limit");
    EXPECT_EQ(bar.id, i);
    EXPECT_NEAR(bar.scale.z, expected[i], 1e-12) << "wheel " << i;
    EXPECT_NEAR(bar.pose.position.z - kWheelBarsZ, 0.5 * bar.scale.z, 1e-12);  // on the base
    EXPECT_NEAR(slab.pose.position.z - kWheelBarsZ, full, 1e-12);              // at the limit
    EXPECT_GT(bar.pose.position.y, previous_y);  // left to right in wheel order
    previous_y = bar.pose.position.y;
  }
}

TEST(ReactionWheelMessages, RoundTripAndEncodingErrorsAreNamed) {
  const ReactionWheels wheels = threeWheels();
  const ReactionWheelArray msg = rc::reactionWheelsToMsg(wheels);
  EXPECT_EQ(msg.max_momentum_norm, 0.0) << "no envelope: 0";
  const ReactionWheels back = rc::reactionWheelsFromMsg(msg, "reaction_wheels");
  ASSERT_EQ(back.count(), 3);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(back.spin_axes[i], wheels.spin_axes[i]);
  EXPECT_EQ(back.max_torque, wheels.max_torque);
  EXPECT_EQ(back.max_momentum, wheels.max_momentum);
  EXPECT_EQ(back.initial_momentum, wheels.initial_momentum);
  EXPECT_TRUE(std::isinf(back.max_momentum_norm));
  ReactionWheels enveloped = wheels;
  enveloped.max_momentum_norm = 2.5;
  EXPECT_EQ(rc::reactionWheelsFromMsg(rc::reactionWheelsToMsg(enveloped), "w").max_momentum_norm,
            2.5);
  EXPECT_FALSE(rc::reactionWheelsFromMsg(ReactionWheelArray(), "reaction_wheels").present());
  const auto refusal = [](const ReactionWheelArray& m) {
    try {
      rc::reactionWheelsFromMsg(m, "reaction_wheels");
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  ReactionWheelArray limits_only;
  limits_only.max_torque = {0.1};
  EXPECT_NE(refusal(limits_only).find("reaction_wheels.spin_axes: empty"), std::string::npos)
      << refusal(limits_only);
  ReactionWheelArray nan_axis = msg;
  nan_axis.spin_axes[2].z = std::nan("");
  EXPECT_NE(refusal(nan_axis).find("reaction_wheels.spin_axes[2]"), std::string::npos)
      << refusal(nan_axis);
  // The core names the scene's path; the request says reaction_wheels.
  EXPECT_EQ(rc::requestFieldName("actuators.reaction_wheels.max_momentum"),
            "reaction_wheels.max_momentum");
  EXPECT_EQ(rc::requestFieldName("actuators.reaction_wheels"), "reaction_wheels");
  // Wheel rows: (N + 1) * n values, finite.
  EXPECT_EQ(rc::wheelRowsFromMsg({1, 2, 3, 4, 5, 6}, 2, 3, "maneuver.wheel_torque")[1](2), 6.0);
  try {
    rc::wheelRowsFromMsg({1, 2, 3, 4, 5}, 2, 3, "maneuver.wheel_torque");
    ADD_FAILURE() << "a short array was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("maneuver.wheel_torque: needs (N + 1) * n = 2 * 3"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(rc::wheelRowsFromMsg({1, 2, std::nan(""), 4, 5, 6}, 2, 3, "maneuver.wheel_torque"),
               InvalidInput);
}

TEST(ReactionWheelMessages, SummaryCarriesEachWheelsPeaksLimitsAndMargins) {
  ReactionWheels wheels = threeWheels();
  WheelPeaks peaks(3);
  peaks.peak_momentum << 0.5, 2.5, 0.25;
  peaks.peak_torque << 0.1, 0.2, 0.3;
  peaks.peak_momentum_norm = 2.6;
  ReactionWheelsSummary s = rc::wheelSummaryToMsg(wheels, peaks);
  ASSERT_EQ(s.wheels.size(), 3u);
  EXPECT_EQ(s.wheels[1].name, "wheel_2");
  EXPECT_EQ(s.wheels[1].max_momentum, 2.0);
  EXPECT_EQ(s.wheels[1].momentum_margin, -0.5);  // past its limit
  EXPECT_EQ(s.wheels[2].torque_margin, wheels.torqueLimit(2) - 0.3);
  EXPECT_FALSE(s.has_momentum_norm_limit);
  EXPECT_EQ(s.max_momentum_norm, 0.0);
  EXPECT_EQ(s.effort_minimized, "") << "a flown path (no plan's objective) leaves it empty";
  wheels.max_momentum_norm = 3.0;
  s = rc::wheelSummaryToMsg(wheels, peaks, MinimizedEffort::BodyTorque);
  EXPECT_TRUE(s.has_momentum_norm_limit);
  EXPECT_NEAR(s.momentum_norm_margin, 0.4, 1e-15);
  EXPECT_EQ(s.effort_minimized, "body_torque");
  EXPECT_EQ(rc::wheelSummaryToMsg(wheels, peaks, MinimizedEffort::WheelTorque).effort_minimized,
            "wheel_torque");
}

TEST(MarkerColours, OneColourPerMeaningAndEveryMarkerDrawnInItsMeaningsColour) {
  // Before: red, green and blue meant both the principal axes and the TF display's frame axes,
  // and the colours were literals scattered over the node; now one table, read by every marker.
  const std::vector<MarkerMeaning>& meanings = markerMeanings();
  std::set<std::string> namespaces;
  for (std::size_t i = 0; i < meanings.size(); ++i) {
    for (std::size_t j = i + 1; j < meanings.size(); ++j) {
      const double distance = std::abs(meanings[i].r - meanings[j].r) +
                              std::abs(meanings[i].g - meanings[j].g) +
                              std::abs(meanings[i].b - meanings[j].b);
      EXPECT_GT(distance, 0.15) << meanings[i].legend << " / " << meanings[j].legend;
    }
    for (const std::string& ns : meanings[i].namespaces) {
      EXPECT_TRUE(namespaces.insert(ns).second) << ns << " has two meanings";
    }
  }
  // Every marker the node builds is in its meaning's colour.
  const PrincipalBox box = principalBox(Vector3(5, 10, 13).asDiagonal().toDenseMatrix(), 1.0);
  const Matrix3 R = so3::fromAxisAngle(Vector3(1, 2, 3).normalized(), 0.7);
  std::vector<visualization_msgs::Marker> drawn;
  for (const visualization_msgs::MarkerArray& a :
       {bodyMarkers(box, 0.9, 1.2, "body", ros::Time(3.0)),
        constraintMarkers(twoCones(), 1.2, "world", ros::Time()),
        worldDirectionMarkers(twoCones(), pointingAt(), 1.2, "world"),
        bodyAxisMarkers(twoCones(), pointingAt(), R, 1.2, "world", ros::Time(3.0)),
        wheelMomentumMarkers(threeWheels(), Eigen::Vector3d(0.1, -0.5, 2.0), 1.2, "world",
                             ros::Time(3.0))}) {
    drawn.insert(drawn.end(), a.markers.begin(), a.markers.end());
  }
  ASSERT_EQ(drawn.size(), 5u + 2u + 3u + 3u + 6u);
  std::set<std::string> seen;
  for (const visualization_msgs::Marker& m : drawn) {
    ASSERT_EQ(namespaces.count(m.ns), 1u) << m.ns << " is in no meaning (not in the legend)";
    const std_msgs::ColorRGBA c = meaningColour(m.ns);
    EXPECT_EQ(std::make_tuple(m.color.r, m.color.g, m.color.b), std::make_tuple(c.r, c.g, c.b))
        << m.ns;
    seen.insert(m.ns);
  }
  EXPECT_GE(seen.size(), 14u);
  EXPECT_THROW(meaningColour("no_such_marker"), std::out_of_range);
  // The legend: one line per meaning, in order, in its colour, saying it.
  const visualization_msgs::MarkerArray legend = legendMarkers("world", 1.2);
  ASSERT_EQ(legend.markers.size(), meanings.size());
  for (std::size_t i = 0; i < meanings.size(); ++i) {
    const visualization_msgs::Marker& line = legend.markers[i];
    EXPECT_EQ(line.type, visualization_msgs::Marker::TEXT_VIEW_FACING);
    EXPECT_EQ(line.header.frame_id, "world");
    EXPECT_EQ(line.text, meanings[i].legend);
    EXPECT_EQ(line.color.r, meanings[i].r);
    EXPECT_EQ(line.color.g, meanings[i].g);
    EXPECT_EQ(line.color.b, meanings[i].b);
    if (i > 0) EXPECT_LT(line.pose.position.z, legend.markers[i - 1].pose.position.z);
  }
}

TEST(MarkerColours, TheShippedRvizConfigHidesTheTfAxesAndShowsTheLegend) {
  // The TF display's own red-green-blue frame axes would give the principal axes' colours a
  // second meaning: the shipped config shows frame names instead, and displays `legend`.
  std::ifstream file(std::string(AP_SOURCE_DIR) + "/rviz/maneuver.rviz");
  ASSERT_TRUE(file) << "rviz/maneuver.rviz";
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::size_t tf = text.find("Class: rviz/TF");
  ASSERT_NE(tf, std::string::npos);
  const std::size_t next = text.find("- Class:", tf);
  const std::string tf_display = text.substr(tf, next - tf);
  EXPECT_NE(tf_display.find("Show Axes: false"), std::string::npos) << tf_display;
  EXPECT_NE(tf_display.find("Show Names: true"), std::string::npos) << tf_display;
  // The wheel-momentum bars are displayed (a maneuver with reaction wheels publishes them).
  EXPECT_NE(text.find("Marker Topic: wheel_momentum_markers"), std::string::npos);
  EXPECT_NE(text.find("Marker Topic: legend"), std::string::npos);
  // The torque display draws in the colour the legend gives it.
  const std_msgs::ColorRGBA torque = meaningColour("torque_display");
  char expected[64];
  std::snprintf(expected, sizeof expected, "Torque Color: %d; %d; %d",
                static_cast<int>(std::lround(255 * torque.r)),
                static_cast<int>(std::lround(255 * torque.g)),
                static_cast<int>(std::lround(255 * torque.b)));
  EXPECT_NE(text.find(expected), std::string::npos) << expected;
}

TEST(LaunchFiles, EveryPrivateParameterOfANodeIsAnArgumentOfItsLaunchFile) {
  // Every name a node reads with readParam / readNamedParam is set from an <arg> by its launch
  // file (before: planner.launch had no action_workers).
  const auto text = [](const std::string& path) {
    std::ifstream file(std::string(AP_SOURCE_DIR) + "/" + path);
    EXPECT_TRUE(file) << path;
    return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  };
  const std::regex read(R"re(read(?:Named)?Param(?:<[^>]*>)?\(\s*\w+,\s*"([a-z_]+)")re");
  const std::pair<const char*, const char*> nodes[] = {
      {"src/ros/planner_node.cpp", "launch/planner.launch"},
      {"src/ros/tracker_node.cpp", "launch/tracker.launch"},
      {"src/ros/plant_node.cpp", "launch/plant.launch"}};
  for (const auto& [source, launch] : nodes) {
    const std::string code = text(source);
    const std::string xml = text(launch);
    int names = 0;
    for (std::sregex_iterator it(code.begin(), code.end(), read), end; it != end; ++it) {
      const std::string name = (*it)[1];
      ++names;
      EXPECT_NE(xml.find("<param name=\"" + name + "\""), std::string::npos)
          << launch << " does not set ~" << name;
      EXPECT_NE(xml.find("<arg name=\"" + name + "\""), std::string::npos)
          << launch << " has no arg " << name;
    }
    EXPECT_GE(names, 5) << source;  // the pattern still finds the node's parameters
  }
}

TEST(BodyAxisMarkers, DrawnInTheWorldFrameFromTheAttitudeNeedingNoTf) {
  // The constrained body axes and the boresight: R b in the world frame at the sample's stamp
  // (before: a frame-locked arrow in the body frame, latched before tf had the body frame).
  const Matrix3 R = so3::fromAxisAngle(Vector3(-1, 2, 0.5).normalized(), 2.1);
  const std::vector<PlanningConstraint> cones = twoCones();
  const EndCondition end = pointingAt();
  const visualization_msgs::MarkerArray a =
      bodyAxisMarkers(cones, end, R, 1.2, "map", ros::Time(7.0));
  ASSERT_EQ(a.markers.size(), 3u);
  const Vector3 axes[3] = {cones[0].body_axis, cones[1].body_axis, end.body_axis};
  const char* ns[3] = {"keep_out_body_axis", "keep_in_body_axis", "pointing_boresight"};
  for (int i = 0; i < 3; ++i) {
    const visualization_msgs::Marker& m = a.markers[i];
    EXPECT_EQ(m.ns, ns[i]);
    EXPECT_EQ(m.header.frame_id, "map");
    EXPECT_EQ(m.header.stamp, ros::Time(7.0));
    EXPECT_FALSE(m.frame_locked);
    EXPECT_LT((tipOf(m) - 1.2 * R * axes[i].normalized()).norm(), 1e-12) << ns[i];
  }
  // The world directions (the Sun arrow, the pointing target), once per maneuver.
  const visualization_msgs::MarkerArray d = worldDirectionMarkers(cones, end, 1.2, "map");
  ASSERT_EQ(d.markers.size(), 3u);
  const Vector3 directions[3] = {cones[0].world_direction, cones[1].world_direction,
                                 end.world_direction};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(d.markers[i].header.frame_id, "map");
    EXPECT_LT((tipOf(d.markers[i]) - 1.8 * directions[i].normalized()).norm(), 1e-12);
  }
  // Without cones or a pointing end condition: nothing.
  EXPECT_TRUE(bodyAxisMarkers({}, std::nullopt, R, 1.2, "map", ros::Time()).markers.empty());
  EXPECT_TRUE(worldDirectionMarkers({}, EndCondition(), 1.2, "map").markers.empty());
}

TEST(PrincipalBox, NonPhysicalInertiaStillGetsAVisibleBox) {
  // The seed's J violates J1 + J2 >= J3: the third edge would be imaginary; it is clamped.
  const PrincipalBox box = principalBox(rc::inertiaFromMsg(seedRequest().inertia), 1.0);
  EXPECT_NEAR(box.dimensions.maxCoeff(), 1.0, 1e-12);
  EXPECT_NEAR(box.dimensions.minCoeff(), 0.1, 1e-12);
}

// ---- errors in the request's fields, decimated answers, the deadline -----------------

TEST(RequestFieldNames, SceneKeysMapToTheRequestsFields) {
  const std::pair<const char*, const char*> cases[] = {
      {"initial.angular_velocity", "initial_angular_velocity"},
      {"final.angular_velocity", "final_angular_velocity"},
      {"initial.attitude", "initial_attitude"},
      {"final.attitude", "final_attitude"},
      {"constraints[0].max_torque_norm", "constraints[0].limit"},
      {"constraints[12].max_angular_rate", "constraints[12].limit"},
      {"constraints[1].keep_out.body_axis", "constraints[1].body_axis"},
      {"constraints[2].keep_in.half_angle", "constraints[2].half_angle"},
      {"constraints[2].keep_in", "constraints[2]"},
      {"effects[0].actuator_limits.max_torque[2]", "effects[0].value.z"},
      {"effects[1].disturbance_torque.value[0]", "effects[1].value.x"},
      {"effects[0].gravity_gradient.mu", "effects[0].mu"},
      {"effects[3].gravity_gradient", "effects[3]"},
      {"steps", "steps"},
      {"duration", "duration"},
      {"accuracy_target", "accuracy_target"},
  };
  for (const auto& [core, request] : cases) EXPECT_EQ(rc::requestFieldName(core), request) << core;
  // The structured field is mapped; the detail is kept as it is.
  EXPECT_EQ(rc::requestErrorMessage(InvalidInput("constraints[0].max_torque_norm", "must be > 0")),
            "constraints[0].limit: must be > 0");
  EXPECT_EQ(rc::requestErrorMessage(InvalidInput("initial_attitude: zero quaternion")),
            "initial_attitude: zero quaternion");  // no separate field: unchanged
}

TEST(DecimatedManeuver, KeepsBothEndsAndAtMostTheAskedNodes) {
  for (const int N : {4, 31, 32, 100, 1000, 100000}) {
    Maneuver plan;
    plan.time_step = 0.5;
    for (int k = 0; k <= N; ++k) {
      plan.time.push_back(0.5 * k);
      plan.attitude.push_back(Matrix3::Identity());
      plan.angular_velocity.push_back(Vector3(k, 0, 0));
      plan.torque.push_back(Vector3(0, k, 0));
    }
    for (const int M : {2, 3, 7, 11, 1000, 200000}) {
      const Maneuver d = rc::decimatedManeuver(plan, M);
      const std::size_t rows = d.attitude.size();
      EXPECT_LE(rows, static_cast<std::size_t>(std::min(M, N + 1))) << N << ", " << M;
      EXPECT_GE(rows, 2u);
      if (M >= N + 1) EXPECT_EQ(rows, static_cast<std::size_t>(N + 1)) << N << ", " << M;
      ASSERT_EQ(d.time.size(), rows);
      ASSERT_EQ(d.torque.size(), rows);
      ASSERT_EQ(d.angular_velocity.size(), rows);
      EXPECT_EQ(d.time.front(), 0.0);
      EXPECT_EQ(d.time.back(), 0.5 * N);        // both ends
      EXPECT_EQ(d.time_step, 0.5);              // the plan's h
      for (std::size_t i = 0; i < rows; ++i) {  // each row is the plan's own row
        EXPECT_EQ(d.torque[i].y(), d.time[i] / 0.5);
        EXPECT_EQ(d.angular_velocity[i].x(), d.time[i] / 0.5);
      }
    }
  }
  EXPECT_EQ(rc::decimatedManeuver(Maneuver(), 0).attitude.size(), 0u);
}

TEST(OutputSelection, AllZeroKeepsEveryNodeAndBadValuesAreNamed) {
  const rc::OutputSelection none = rc::outputSelectionFromRequest("", 0);
  EXPECT_EQ(none.output, rc::ManeuverOutput::Nodes);
  EXPECT_EQ(none.max_nodes, 0);
  EXPECT_EQ(rc::outputSelectionFromRequest("none", 0).output, rc::ManeuverOutput::None);
  EXPECT_EQ(rc::outputSelectionFromRequest("nodes", 5).max_nodes, 5);
  EXPECT_THROW(rc::outputSelectionFromRequest("", 1), InvalidInput);
  EXPECT_THROW(rc::outputSelectionFromRequest("", -1), InvalidInput);
  EXPECT_THROW(rc::outputSelectionFromRequest("none", 3), InvalidInput);
  EXPECT_THROW(rc::outputSelectionFromRequest("summary", 0), InvalidInput);
}

TEST(Deadline, APlanThatConvergedAfterItsBudgetIsTimedOut) {
  PlanOutcome late;
  late.error_code = PlanErrorCode::SUCCESS;
  late.time_budget_s = 0.3;
  late.wall_time_s = 0.75;  // well past its 0.3 s budget, though the solve converged
  enforceDeadline(&late);
  EXPECT_EQ(late.error_code, PlanErrorCode::TIMED_OUT);
  // The figures stay in their fields (the message is worded from them).
  EXPECT_EQ(late.wall_time_s, 0.75);
  EXPECT_EQ(late.time_budget_s, 0.3);
  EXPECT_EQ(late.message.rfind("timed out: the plan converged after", 0), 0u) << late.message;
  PlanOutcome in_time = late;
  in_time.error_code = PlanErrorCode::SUCCESS;
  in_time.message = "converged";
  in_time.wall_time_s = 0.29;
  enforceDeadline(&in_time);
  EXPECT_EQ(in_time.error_code, PlanErrorCode::SUCCESS);
  PlanOutcome unbounded = late;
  unbounded.error_code = PlanErrorCode::SUCCESS;
  unbounded.time_budget_s = 0.0;  // none
  enforceDeadline(&unbounded);
  EXPECT_EQ(unbounded.error_code, PlanErrorCode::SUCCESS);
}

TEST(Deadline, TheAnswerLeavesTheStoppedSolveTimeWithinTheContract) {
  // The bound for a deadline answer, 1.1 B + 0.05 s, holds for every budget, and a stopped
  // solve has at least kHandoverFloor after B to hand over the plan it reached.
  for (double budget : {1e-6, 0.01, 0.1, 0.5, 1.0, 30.0, 300.0}) {
    EXPECT_LE(answerDeadline(budget), 1.1 * budget + 0.05) << budget;
    EXPECT_GE(answerDeadline(budget) - budget, kHandoverFloor) << budget;
  }
}

TEST(Deadline, ACancelWaitsForTheHandOverOfTheLargestGridTheGoalMayBePlannedOn) {
  // The wait grows with the goal's N (the hand-over is a few passes over the grid) and is
  // kCancelGrace at no steps; the N is the goal's, its default, or ~max_steps when the planner
  // chooses it (an accuracy target).
  ros_conversions::PlannerDefaults defaults;
  defaults.steps = 128;
  defaults.max_steps = 100000;
  PlanAttitudeManeuverGoal goal;
  EXPECT_EQ(largestPlannedSteps(goal, defaults), 128);
  goal.steps = 4096;
  EXPECT_EQ(largestPlannedSteps(goal, defaults), 4096);
  goal.steps = 200000;  // refused by the planner; the wait is still bounded by ~max_steps
  EXPECT_EQ(largestPlannedSteps(goal, defaults), 100000);
  goal.steps = 64;
  goal.accuracy_measure = "terminal_miss";
  EXPECT_EQ(largestPlannedSteps(goal, defaults), 100000);
  EXPECT_EQ(cancelGrace(0), kCancelGrace);
  double previous = cancelGrace(0);
  for (int steps : {4, 128, 4096, 100000}) {
    EXPECT_GT(cancelGrace(steps), previous) << steps;
    previous = cancelGrace(steps);
  }
  EXPECT_NEAR(cancelGrace(100000) - cancelGrace(50000), 50000 * kHandoverPerNode, 1e-15);
}

TEST(Deadline, TheSolveStopsAHandOversTimeBeforeTheAnswersDeadline) {
  // The core's own budget leaves the hand-over estimate of the request's N before the answer's
  // deadline (where the budget allows any solve at all), never exceeds the request's budget, is
  // never "none", and takes nothing where the hand-over fits in the answer's slack (small N).
  for (int steps : {4, 128, 4096, 20000, 100000}) {
    for (double budget : {1e-6, 0.01, 0.1, 0.3, 0.5, 1.0, 2.0, 5.0, 30.0, 300.0}) {
      const double solve = solveBudget(budget, steps);
      EXPECT_GT(solve, 0.0) << steps << " " << budget;
      EXPECT_LE(solve, budget) << steps << " " << budget;
      if (solve > kLeastSolveBudget) {
        EXPECT_GE(answerDeadline(budget) - solve, handoverEstimate(steps) - 1e-12)
            << steps << " " << budget;
      }
      if (handoverEstimate(steps) <= answerDeadline(budget) - budget) {
        EXPECT_EQ(solve, budget) << steps << " " << budget;
      }
    }
  }
  EXPECT_EQ(solveBudget(0.0, 100000), 0.0) << "no budget stays none";
  EXPECT_EQ(solveBudget(0.3, 100000), kLeastSolveBudget) << "the hand-over takes all of it";
  EXPECT_NEAR(solveBudget(1.0, 100000), answerDeadline(1.0) - handoverEstimate(100000), 1e-12);
  EXPECT_NEAR(solveBudget(5.0, 100000), answerDeadline(5.0) - handoverEstimate(100000), 1e-12);
  EXPECT_EQ(cancelGrace(100000) - kCancelGrace, handoverEstimate(100000)) << "one estimate";
  // The service request's N the same way as a goal's.
  ros_conversions::PlannerDefaults defaults;
  PlanAttitudeManeuver::Request request;
  request.steps = 100000;
  EXPECT_EQ(largestPlannedSteps(request, defaults), 100000);
  request.steps = 0;
  EXPECT_EQ(largestPlannedSteps(request, defaults), defaults.steps);
}

TEST(AnytimePlan, AStoppedSolveFillsTheResponseWithItsPlanFlaggedUnconverged) {
  // The adapter carries the core's stopped plan: cancelled at the second iteration (no master
  // needed), the response has the plan's N + 1 rows, unconverged_plan and its residuals; a
  // converged answer is not flagged.
  ros::Time::init();  // the response's stamps, without a master
  PlanAttitudeManeuver::Request req = seedRequest();
  req.steps = 64;
  req.tolerance = 1e-300;
  const PlanOutcome stopped =
      planRequest(req, rc::PlannerDefaults(),
                  [](const IterationInfo& info, double) { return info.iteration < 2; });
  ASSERT_TRUE(stopped.solver_ran) << stopped.message;
  EXPECT_EQ(stopped.error_code, PlanErrorCode::CANCELLED) << stopped.message;
  PlanAttitudeManeuver::Response res;
  fillResponse(stopped, "world", "body", &res);
  EXPECT_FALSE(res.success);
  EXPECT_TRUE(res.unconverged_plan);
  EXPECT_EQ(res.maneuver.attitude.size(), 65u);
  EXPECT_GT(res.max_residual, req.tolerance);
  EXPECT_LE(res.step_residual, 1e-8);
  req.tolerance = 0.0;  // the node's default
  PlanAttitudeManeuver::Response converged;
  fillResponse(planRequest(req, rc::PlannerDefaults(), nullptr), "world", "body", &converged);
  EXPECT_TRUE(converged.success) << converged.message;
  EXPECT_FALSE(converged.unconverged_plan);
}

TEST(RosConversions, TheVerdictIsInTheResponseAndTheActionResultAsInTheJsonSummary) {
  // verdict_kind and verdict_figures carry the result's verdict as data, by the JSON summary's
  // names: the seed request's (the Newton solver's ending) and a local infeasibility's, in the
  // service's response and the action's result alike.
  ros::Time::init();  // the response's stamps, without a master
  PlanOutcome outcome = planRequest(seedRequest(), rc::PlannerDefaults(), nullptr);
  ASSERT_TRUE(outcome.solver_ran) << outcome.message;
  const auto expectTheVerdict = [&](const std::string& kind,
                                    const std::vector<NamedFigure>& figures) {
    const Verdict& verdict = outcome.result.verdict;
    EXPECT_EQ(kind, verdictKindName(verdict));
    const std::string json = planResultJson(outcome.problem, outcome.result);
    EXPECT_NE(json.find("\"verdict\": {\"kind\": \"" + kind + "\""), std::string::npos) << json;
    const std::vector<VerdictFigure> expected = verdictFigures(verdict);
    ASSERT_EQ(figures.size(), expected.size());
    for (std::size_t i = 0; i < figures.size(); ++i) {
      EXPECT_EQ(figures[i].name, expected[i].name);
      EXPECT_EQ(figures[i].value, expected[i].value);
      EXPECT_NE(json.find("\"" + figures[i].name + "\": " + exactNumber(figures[i].value)),
                std::string::npos)
          << figures[i].name << " in " << json;
    }
  };
  PlanAttitudeManeuver::Response res;
  fillResponse(outcome, "world", "body", &res);
  EXPECT_EQ(res.verdict_kind, "newton_ended");
  expectTheVerdict(res.verdict_kind, res.verdict_figures);
  outcome.result.verdict =
      verdicts::LocallyInfeasible{12.8, 13.0 + 1.0 / 3.0, "what", 11.5, "", true};
  PlanAttitudeManeuverResult result;
  fillResponse(outcome, "world", "body", &result);
  EXPECT_EQ(result.verdict_kind, "locally_infeasible");
  ASSERT_EQ(result.verdict_figures.size(), 3u);
  EXPECT_EQ(result.verdict_figures[1].name, "least_duration_found");
  EXPECT_EQ(result.verdict_figures[1].value, 13.0 + 1.0 / 3.0);
  expectTheVerdict(result.verdict_kind, result.verdict_figures);
}

TEST(NloptRefusal, AboveItsLimitIsInvalidInputNamingSteps) {
  PlanAttitudeManeuver::Request r = seedRequest();
  r.steps = 1025;
  r.solver = "nlopt";
  EXPECT_EQ(invalidMessage(r).rfind("steps: 1025 > 1024 is refused by solver nlopt", 0), 0u)
      << invalidMessage(r);
}

// The tracker's default body frame: one per namespace, "body" in the root one.
TEST(TrackerFrames, DefaultBodyFrameComesFromTheNamespace) {
  EXPECT_EQ(defaultBodyFrame("/"), "body");
  EXPECT_EQ(defaultBodyFrame(""), "body");
  EXPECT_EQ(defaultBodyFrame("/sat1"), "sat1/body");
  EXPECT_EQ(defaultBodyFrame("/fleet/sat2/"), "fleet/sat2/body");
}

// Odometry (the external plant's measured state): attitude and body rate round-trip; a quaternion
// that is not unit and a non-finite rate are refused naming the field.
TEST(Odometry, RoundTripsTheStateAndNamesABadField) {
  const Matrix3 R = so3::exp(Vector3(0.3, -0.2, 0.9));
  const Vector3 W(0.01, -0.02, 0.03);
  const nav_msgs::Odometry m = rc::odometryToMsg(R, W, ros::Time(4.0), "world", "sat1/body");
  EXPECT_EQ(m.header.frame_id, "world");
  EXPECT_EQ(m.child_frame_id, "sat1/body");
  EXPECT_EQ(m.header.stamp, ros::Time(4.0));
  const rc::MeasuredState s = rc::measuredStateFromMsg(m);
  EXPECT_LT(so3::angleBetween(s.attitude, R), 1e-15);
  EXPECT_EQ(s.angular_velocity, W);
  const auto expectRefusedNaming = [](const nav_msgs::Odometry& bad, const std::string& field) {
    try {
      rc::measuredStateFromMsg(bad);
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  nav_msgs::Odometry bad = m;
  bad.pose.pose.orientation.w = 3.0;  // not a unit quaternion
  expectRefusedNaming(bad, "odometry.pose.pose.orientation");
  bad = m;
  bad.twist.twist.angular.y = std::nan("");
  expectRefusedNaming(bad, "odometry.twist.twist.angular");
}

// /diagnostics: the answer counts and wall-time figures, and the level rules of both nodes'
// statuses (docs/ros_tracker.md, "Diagnostics").
namespace {
std::string valueOf(const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
  for (const diagnostic_msgs::KeyValue& pair : status.values) {
    if (pair.key == key) return pair.value;
  }
  return "(missing)";
}
}  // namespace

TEST(Diagnostics, AnswerStatisticsCountByCodeAndTakeTheMedianOfTheRecentAnswers) {
  AnswerStatistics answers;
  EXPECT_EQ(answers.summary().answered, 0);
  for (int i = 1; i <= 5; ++i) answers.record(PlanErrorCode::SUCCESS, 0.1 * i);
  answers.record(PlanErrorCode::INVALID_INPUT, 0.001);
  answers.record(PlanErrorCode::TIMED_OUT, 2.0);
  const AnswerStatistics::Summary s = answers.summary();
  EXPECT_EQ(s.answered, 7);
  EXPECT_EQ(s.succeeded, 5);
  EXPECT_EQ(s.failed.at(PlanErrorCode::INVALID_INPUT), 1);
  EXPECT_EQ(s.failed.at(PlanErrorCode::TIMED_OUT), 1);
  EXPECT_EQ(s.last_code, PlanErrorCode::TIMED_OUT);
  EXPECT_DOUBLE_EQ(s.median_s, 0.3);  // of {0.001, 0.1, ..., 0.5, 2}
  EXPECT_DOUBLE_EQ(s.max_s, 2.0);
  // Only the last kRecent answers count for the wall times; the counts keep every answer.
  for (std::size_t i = 0; i < AnswerStatistics::kRecent; ++i) answers.record(1, 1.0);
  EXPECT_DOUBLE_EQ(answers.summary().max_s, 1.0);
  EXPECT_EQ(answers.summary().answered, 7 + static_cast<int>(AnswerStatistics::kRecent));
}

TEST(Diagnostics, PlannerStatusWarnsWhenGoalsWouldBeRejectedAndErrsOnAnInternalError) {
  AnswerStatistics answers;
  answers.record(PlanErrorCode::SUCCESS, 0.2);
  PlannerLoad load{2, 1, 0};
  diagnostic_msgs::DiagnosticStatus status = plannerStatus("/p: planner", answers.summary(), load);
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::OK) << status.message;
  EXPECT_EQ(status.name, "/p: planner");
  EXPECT_EQ(valueOf(status, "answered"), "1");
  EXPECT_EQ(valueOf(status, "busy action workers"), "1");
  load.busy_workers = 2;
  status = plannerStatus("/p: planner", answers.summary(), load);
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::WARN);
  load = PlannerLoad{2, 0, 1};
  EXPECT_EQ(plannerStatus("/p", answers.summary(), load).level,
            diagnostic_msgs::DiagnosticStatus::WARN);
  answers.record(PlanErrorCode::INTERNAL_ERROR, 0.01);
  status = plannerStatus("/p", answers.summary(), PlannerLoad{2, 0, 0});
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_EQ(valueOf(status, "failed INTERNAL_ERROR"), "1");
  EXPECT_EQ(valueOf(status, "last answer"), "INTERNAL_ERROR");
  // The next good answer clears the error: the level says how the node is now.
  answers.record(PlanErrorCode::SUCCESS, 0.2);
  EXPECT_EQ(plannerStatus("/p", answers.summary(), PlannerLoad{2, 0, 0}).level,
            diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(Diagnostics, TrackerStatusWarnsOnAStaleMeasurementOrAFailedReplanAndErrsOnAFrameConflict) {
  TrackerHealth health;
  health.mode = "feedback";
  health.plant = "external";
  health.running = true;
  health.attitude_error = 0.25;
  EXPECT_EQ(trackerStatus("/t", health).level, diagnostic_msgs::DiagnosticStatus::OK);
  EXPECT_EQ(valueOf(trackerStatus("/t", health), "attitude error [rad]"), "0.25");
  // Each measurement's age under its own key: the body's odometry and the wheels' spin rates.
  EXPECT_EQ(valueOf(trackerStatus("/t", health), "wheel measurement age [s]"), "-1");
  health.measurement_age = 0.01;
  health.wheel_measurement_age = 1.5;
  EXPECT_EQ(valueOf(trackerStatus("/t", health), "measurement age [s]"), "0.01");
  EXPECT_EQ(valueOf(trackerStatus("/t", health), "wheel measurement age [s]"), "1.5");
  health.measurement_problem = "newest odometry is 0.9 s old (~measurement_timeout 0.5 s)";
  diagnostic_msgs::DiagnosticStatus status = trackerStatus("/t", health);
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_NE(status.message.find(health.measurement_problem), std::string::npos) << status.message;
  health.running = false;  // idle: no measurement is expected
  EXPECT_EQ(trackerStatus("/t", health).level, diagnostic_msgs::DiagnosticStatus::OK);
  health.replan_failures = 1;
  EXPECT_EQ(trackerStatus("/t", health).level, diagnostic_msgs::DiagnosticStatus::WARN);
  health.frame_conflict = "node /other also publishes the transform world -> body";
  EXPECT_EQ(trackerStatus("/t", health).level, diagnostic_msgs::DiagnosticStatus::ERROR);
}

TEST(RosConversions, PointingRequestIsPlannedAndReportsItsTwist) {
  ros::Time::init();  // fillResponse stamps the maneuver; no master is needed
  PlanAttitudeManeuver::Request r = seedRequest();
  r.end_condition = "pointing";
  r.pointing_body_axis = rc::vectorToMsg(Vector3(0, 0, 1));
  r.pointing_world_direction = rc::vectorToMsg(Vector3(1, 1, 0));
  SolverOptions options;
  const PlanningProblem p = rc::problemFromRequest(r, rc::PlannerDefaults(), &options);
  EXPECT_TRUE(p.end_condition.pointing());
  const PlanOutcome out = planRequest(r, rc::PlannerDefaults(), nullptr);
  ASSERT_EQ(out.error_code, PlanErrorCode::SUCCESS) << out.message;
  PlanAttitudeManeuver::Response res;
  fillResponse(out, "world", "body", &res);
  EXPECT_EQ(res.final_twist, out.result.pointing.final_twist);
  EXPECT_LT(res.pointing_error, 1e-12);
  EXPECT_LT(res.twist_stationarity, 1e-8);
  const Vector3 aimed =
      rc::attitudeFromMsg(res.maneuver.attitude.back(), "attitude") * Vector3::UnitZ();
  EXPECT_LT((aimed - Vector3(1, 1, 0).normalized()).norm(), 1e-9);
  EXPECT_TRUE(std::isfinite(res.attempts.front().start_detail.twist));
  EXPECT_EQ(res.pointing_infeasible_basis, "none");
  // A rate limit below the angle from R_0 b to d over T: no twist admits a plan (proven), and the
  // response carries what the verdict rests on as the JSON summary does.
  PlanAttitudeManeuver::Request slow = r;
  slow.constraints.push_back(
      rc::constraintToMsg(PlanningConstraint::maxAngularRate(0.5 * (M_PI / 2) / r.duration)));
  const PlanOutcome none = planRequest(slow, rc::PlannerDefaults(), nullptr);
  ASSERT_EQ(none.error_code, PlanErrorCode::INFEASIBLE) << none.message;
  PlanAttitudeManeuver::Response slow_res;
  fillResponse(none, "world", "body", &slow_res);
  EXPECT_EQ(slow_res.pointing_infeasible_basis,
            pointingInfeasibleBasisName(none.result.pointing.infeasible_basis));
  EXPECT_EQ(slow_res.pointing_infeasible_basis, "proven");
  // An attitude end condition has no pointing verdict.
  const PlanOutcome attitude_end = planRequest(seedRequest(), rc::PlannerDefaults(), nullptr);
  PlanAttitudeManeuver::Response attitude_res;
  fillResponse(attitude_end, "world", "body", &attitude_res);
  EXPECT_EQ(attitude_res.pointing_infeasible_basis, "");
  // A name it does not know, a zero vector and an unserved combination are named.
  r.end_condition = "aim";
  EXPECT_NE(invalidMessage(r).find("end_condition"), std::string::npos);
  r.end_condition = "pointing";
  r.pointing_world_direction = rc::vectorToMsg(Vector3::Zero());
  EXPECT_NE(invalidMessage(r).find("pointing_world_direction"), std::string::npos)
      << invalidMessage(r);
  r.pointing_world_direction = rc::vectorToMsg(Vector3(1, 0, 0));
  r.objective = "minimum_time";
  EXPECT_NE(invalidMessage(r).find("minimum_time"), std::string::npos) << invalidMessage(r);
}

TEST(ActionFeedback, IterationsNameTheirAttemptAndTheLastMessageIsTheKeptAttempts) {
  // The feedback must not end on a discarded attempt's iterate (its effort can be far above the
  // result's). Each iteration's message carries its attempt's number, stage and class; the last
  // one is the returned plan's, tagged with the kept attempt.
  PlanAttitudeManeuver::Request r = seedRequest();
  r.final_attitude = rc::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitX(), M_PI - 0.05));
  std::vector<PlanAttitudeManeuverFeedback> feedback;
  const PlanOutcome out =
      planRequest(r, rc::PlannerDefaults(), [&](const IterationInfo& info, double elapsed) {
        feedback.push_back(iterationFeedback(info, elapsed));
        return true;
      });
  ASSERT_EQ(out.error_code, PlanErrorCode::SUCCESS) << out.message;
  ASSERT_FALSE(feedback.empty());
  std::set<int> attempts;
  for (const PlanAttitudeManeuverFeedback& f : feedback) {
    EXPECT_GT(f.attempt, 0);
    EXPECT_FALSE(f.kept);
    EXPECT_TRUE(findByName(kAttemptStageNames, f.stage).has_value()) << f.stage;
    attempts.insert(f.attempt);
  }
  EXPECT_GT(attempts.size(), 1u) << "near a half turn the survey solves more than one class";
  const auto kept = keptAttemptFeedback(out, feedback.back().iteration);
  ASSERT_TRUE(kept.has_value());
  EXPECT_TRUE(kept->kept);
  EXPECT_EQ(kept->iteration, feedback.back().iteration);
  EXPECT_EQ(kept->cost, out.result.cost);
  EXPECT_EQ(kept->effort, out.result.effort);
  EXPECT_EQ(kept->steps, 32);
  const std::vector<Attempt>& trail = out.result.attempts;
  ASSERT_GE(kept->attempt, 1);
  ASSERT_LE(kept->attempt, static_cast<int>(trail.size()));
  const Attempt& a = trail[kept->attempt - 1];
  EXPECT_TRUE(a.kept);
  EXPECT_EQ(kept->stage, attemptStageName(a.stage));
  EXPECT_EQ(kept->long_way, a.homotopy.long_way);
  EXPECT_EQ(kept->extra_revolutions, a.homotopy.extra_revolutions);
  // A request refused before solving has no kept attempt to report.
  r.steps = -1;
  EXPECT_FALSE(keptAttemptFeedback(planRequest(r, rc::PlannerDefaults(), nullptr), 0));
}
