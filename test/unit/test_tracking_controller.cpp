// The geometric tracking law (dynamics/tracking_controller.hpp) and the closed loop around a plan
// (analysis/tracking.hpp): the law's output at zero error, exponential convergence of the
// continuous closed loop from a perturbed start, the interpolation's exactness at the nodes, and
// feedback against open-loop replay under the disturbed scene.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <utility>
#include <vector>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/dynamics/tracking_controller.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

using namespace attitude_planner;

namespace {

const Matrix3 kInertia =
    (Matrix3() << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37).finished();

/// A reference spinning at a constant rate about a non-principal axis: R_d(t) = R_d0 exp(t Ω_d^),
/// Ω̇_d = 0, so the feed-forward is the gyroscopic Ω_d × JΩ_d ≠ 0.
struct ConstantSpin {
  Matrix3 start = so3::exp(Vector3(0.2, -0.4, 0.1));
  Vector3 rate = Vector3(0.3, -0.2, 0.25);  // [rad/s]
  AttitudeReference at(double t) const {
    AttitudeReference r;
    r.attitude = start * so3::exp(Vector3(t * rate));
    r.angular_velocity = rate;
    return r;
  }
};

/// |e_R| + |e_Ω| / ω_n: the error in one number (both parts decay at the same rate).
double errorSize(const Matrix3& R, const Vector3& W, const AttitudeReference& ref, double w_n) {
  const TrackingErrors e = trackingErrors(R, W, ref);
  return e.attitude.norm() + e.rate.norm() / w_n;
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

TEST(TrackingController, ZeroErrorGivesExactlyTheFeedForwardTorque) {
  const TrackingGains gains = trackingGains(kInertia, 2.0, 0.8);
  AttitudeReference ref;
  ref.angular_velocity = Vector3(0.3, -1.2, 0.7);
  ref.angular_acceleration = Vector3(-0.05, 0.4, 0.2);
  // At R = R_d = I every error term is exactly zero: the output is the feed-forward, bit for bit.
  const Vector3 ff = feedForwardTorque(kInertia, ref);
  EXPECT_EQ(trackingTorque(kInertia, gains, ref.attitude, ref.angular_velocity, ref), ff);
  // J Ω̇_d + Ω_d × JΩ_d: the torque Euler's equation needs for Ω̇_d.
  EXPECT_LT((ff - (kInertia * ref.angular_acceleration +
                   ref.angular_velocity.cross(kInertia * ref.angular_velocity)))
                .norm(),
            1e-15);
  // Anywhere else on SO(3): the same to round-off (Rᵀ R is I only to round-off).
  ref.attitude = so3::exp(Vector3(1.1, -2.0, 0.4));
  const Vector3 tau = trackingTorque(kInertia, gains, ref.attitude, ref.angular_velocity, ref);
  EXPECT_LT((tau - feedForwardTorque(kInertia, ref)).norm(), 1e-13 * ff.norm());
  const TrackingErrors e = trackingErrors(ref.attitude, ref.angular_velocity, ref);
  EXPECT_EQ(e.attitude.norm(), 0.0);
  EXPECT_LT(e.rate.norm(), 1e-15);
  EXPECT_LT(e.angle, 1e-7);  // ‖log(≈I)‖: the square root of round-off at worst
}

TEST(TrackingController, AttitudeErrorIsSineOfTheAngleAboutTheAxis) {
  const Matrix3 R_d = so3::exp(Vector3(0.3, 0.1, -0.2));
  const Vector3 axis = Vector3(1.0, -2.0, 0.5).normalized();
  AttitudeReference ref;
  ref.attitude = R_d;
  for (double angle : {1e-6, 0.3, 1.5, 3.0}) {
    const TrackingErrors e =
        trackingErrors(R_d * so3::fromAxisAngle(axis, angle), Vector3::Zero(), ref);
    EXPECT_LT((e.attitude - std::sin(angle) * axis).norm(), 1e-14) << angle;
    EXPECT_NEAR(e.angle, angle, 1e-12) << angle;
  }
}

TEST(TrackingController, GainsAreRefusedByName) {
  EXPECT_THROW(trackingGains(kInertia, 0.0, 1.0), InvalidInput);
  EXPECT_THROW(trackingGains(kInertia, 1.0, -1.0), InvalidInput);
  try {
    trackingGains(kInertia, std::nan(""), 1.0);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("natural_frequency"), std::string::npos) << e.what();
  }
}

// The continuous closed loop (the law evaluated at every Runge–Kutta stage) from 1 rad and a rate
// error away converges exponentially: critically damped, the error envelope is (1 + ω_n t)
// e^{−ω_n t}, so each 10/ω_n divides it by far more than 100.
TEST(TrackingController, ConvergesExponentiallyFromAPerturbedStart) {
  const double w_n = 1.5;
  const TrackingGains gains = trackingGains(kInertia, w_n, 1.0);
  const ConstantSpin spin;
  Matrix3 R = spin.at(0.0).attitude * so3::fromAxisAngle(Vector3(0.2, 1.0, -0.4).normalized(), 1.0);
  Vector3 W = spin.rate + Vector3(0.1, 0.2, -0.3);
  const Matrix3 J_inverse = kInertia.inverse();
  const auto derivative = [&](const Matrix3& R_s, const Vector3& w, double t) {
    const Vector3 tau = trackingTorque(kInertia, gains, R_s, w, spin.at(t));
    return Vector3(J_inverse * ((kInertia * w).cross(w) + tau));
  };
  const double dt = 0.002 / w_n;
  std::vector<double> size_at;  // at t = 0, 10/ω_n, 20/ω_n
  size_at.push_back(errorSize(R, W, spin.at(0.0), w_n));
  const int per_block = static_cast<int>(std::lround(10.0 / w_n / dt));
  for (int i = 1; i <= 2 * per_block; ++i) {
    const double t = (i - 1) * dt;
    // RKMK4 on R exp(u^), u̇ = J_r(u)⁻¹ Ω (the integrator of analysis/tracking.cpp).
    const auto du = [&](const Vector3& u, const Vector3& w) {
      return Vector3(so3::rightJacobianInverse(u) * w);
    };
    const Vector3 u1 = du(Vector3::Zero(), W), w1 = derivative(R, W, t);
    const Vector3 a2 = 0.5 * dt * u1, W2 = W + 0.5 * dt * w1;
    const Vector3 u2 = du(a2, W2), w2 = derivative(R * so3::exp(a2), W2, t + 0.5 * dt);
    const Vector3 a3 = 0.5 * dt * u2, W3 = W + 0.5 * dt * w2;
    const Vector3 u3 = du(a3, W3), w3 = derivative(R * so3::exp(a3), W3, t + 0.5 * dt);
    const Vector3 a4 = dt * u3, W4 = W + dt * w3;
    const Vector3 u4 = du(a4, W4), w4 = derivative(R * so3::exp(a4), W4, t + dt);
    R = reorthonormalize(R * so3::exp(Vector3(dt / 6.0 * (u1 + 2.0 * u2 + 2.0 * u3 + u4))));
    W += dt / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
    if (i % per_block == 0) size_at.push_back(errorSize(R, W, spin.at(i * dt), w_n));
  }
  ASSERT_EQ(size_at.size(), 3u);
  EXPECT_GT(size_at[0], 0.5);
  EXPECT_LT(size_at[1], 1e-2 * size_at[0]) << size_at[1];
  EXPECT_LT(size_at[2], 1e-2 * size_at[1]) << size_at[2];  // the same factor again: exponential
}

TEST(ManeuverInterpolation, IsExactAtTheNodesAndOnThePaperSchemesGeodesic) {
  const int N = 16;
  const double h = 0.25;
  SimulationInput input;
  input.initial_velocity = Vector3(0.1, 0.0, -0.05);
  input.torque.assign(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) input.torque[k] = Vector3(std::sin(0.4 * k), 0.3, -0.2);
  const Maneuver plan = simulate(DiscreteScheme(SchemeKind::Paper, kInertia, h), input);
  const ManeuverInterpolation interp(plan, SchemeKind::Paper, kInertia, nullptr);
  EXPECT_DOUBLE_EQ(interp.duration(), N * h);
  for (int k = 0; k <= N; ++k) {
    const ManeuverSample s = interp.at(k * h);
    EXPECT_EQ(s.attitude, plan.attitude[k]) << k;
    EXPECT_EQ(s.torque, plan.torque[k]) << k;
    // paper's rates are the steps' (midpoint) rates: at an interior node their mean.
    if (k > 0 && k < N) {
      EXPECT_LT(
          (s.angular_velocity - 0.5 * (plan.angular_velocity[k - 1] + plan.angular_velocity[k]))
              .norm(),
          1e-15)
          << k;
    }
  }
  EXPECT_EQ(interp.at(0.25 * h).angular_velocity, plan.angular_velocity[0]);
  EXPECT_LT((interp.at((N - 0.5) * h).angular_velocity - plan.angular_velocity[N - 1]).norm(),
            1e-15);
  // paper: constant body rate Ω_k over step k, so R(t_k + s) = R_k exp(s Ω_k^).
  const int k = 5;
  const double s = 0.37 * h;
  const ManeuverSample mid = interp.at(k * h + s);
  EXPECT_LT(so3::angleBetween(mid.attitude,
                              plan.attitude[k] * so3::exp(Vector3(s * plan.angular_velocity[k]))),
            1e-12);
  // The node-centred hold: τ_k on [t_k − h/2, t_k + h/2).
  EXPECT_EQ(interp.at(k * h + 0.4 * h).torque, plan.torque[k]);
  EXPECT_EQ(interp.at(k * h + 0.6 * h).torque, plan.torque[k + 1]);
}

/// meanTorque is the exact mean of the hold: against each hold's closed form over a whole step,
/// and against a fine midpoint sum over intervals that straddle nodes and midpoints, for every
/// hold; meanOverHold itself is exact for a cubic between half-steps.
TEST(ManeuverInterpolation, MeanTorqueIsTheHoldsMeanOverTheInterval) {
  const int N = 8;
  const double h = 0.5;
  Maneuver m;
  m.time_step = h;
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int k = 0; k <= N; ++k) {
    m.time.push_back(k * h);
    m.attitude.push_back(so3::exp(Vector3(0.1 * k, 0.0, 0.0)));
    m.angular_velocity.push_back(Vector3(0.2, 0.0, 0.0));
    m.torque.push_back(Vector3(unit(rng), unit(rng), unit(rng)));
  }
  const Matrix3 J = Vector3(2.0, 3.0, 4.0).asDiagonal();
  const int k = 3;
  const auto& tau = m.torque;
  const std::vector<std::pair<TorqueHold, Vector3>> step_means = {
      {TorqueHold::NodeCentred, 0.5 * (tau[k] + tau[k + 1])},
      {TorqueHold::StepStart, tau[k]},
      {TorqueHold::PiecewiseLinear, 0.5 * (tau[k] + tau[k + 1])},
  };
  for (const auto& [hold, mean] : step_means) {
    const ManeuverInterpolation plan(m, SchemeKind::Paper, J, nullptr, hold);
    EXPECT_LT((plan.meanTorque(k * h, (k + 1) * h) - mean).norm(), 1e-14);
  }
  for (TorqueHold hold : {TorqueHold::NodeCentred, TorqueHold::StepStart,
                          TorqueHold::PiecewiseLinear, TorqueHold::PiecewiseCubic}) {
    const ManeuverInterpolation plan(m, SchemeKind::Paper, J, nullptr, hold);
    for (const auto& [t0, t1] : std::vector<std::pair<double, double>>{
             {0.1, 0.37}, {0.6, 1.9}, {1.23, 3.77}, {0.0, N * h}}) {
      const int pieces = 200000;
      Vector3 sum = Vector3::Zero();
      for (int i = 0; i < pieces; ++i) {
        const double t = t0 + (i + 0.5) * (t1 - t0) / pieces;
        sum += plan.torqueOnStep(std::min(N - 1, static_cast<int>(std::floor(t / h))), t);
      }
      EXPECT_LT((plan.meanTorque(t0, t1) - sum / pieces).norm(), 1e-4) << t0 << " " << t1;
    }
    EXPECT_EQ(plan.meanTorque(1.0, 1.0), plan.at(1.0).torque) << "an empty hold: the value";
  }
  // A cubic between half-steps (breaks at j h/2): exact to round-off.
  const auto cubic = [](double t) { return t < 0.75 ? t * t * t : 2.0 - t; };
  const double exact = (std::pow(0.75, 4) / 4 - std::pow(0.1, 4) / 4 + (2.0 * 1.3 - 0.5 * 1.69) -
                        (2.0 * 0.75 - 0.5 * 0.5625)) /
                       (1.3 - 0.1);
  EXPECT_NEAR(meanOverHold<double>(cubic, 0.1, 1.3, 0.5), exact, 1e-15);
}

/// The external plant's open-loop replay in-process: scenes/leo_slew.yaml's plan commanded at
/// every node (the tracker's sample spacing in tracker_external.test) to the continuous body
/// under the plan's own effects. Holding each sample's mean of the plan's torque lands closer
/// than holding τ(t_j), which lags the plan by half a sample (measured: 1.17e-4 against 2.20e-4
/// rad; what is left is the continuous body against the discrete plan).
TEST(RigidBodyPlant, OpenLoopCommandsOfTheHoldsMeanDoNotLagThePlan) {
  Scene scene = loadScene(std::string(AP_SOURCE_DIR) + "/scenes/leo_slew.yaml");
  const PlanResult plan = planManeuver(scene.problem);
  ASSERT_TRUE(plan.converged()) << plan.message();
  const Matrix3 J = scene.problem.inertia;
  const std::shared_ptr<const EffectModel> effects = plannableEffects(scene.effects, J);
  const Maneuver& nodes = plan.maneuver;
  const ManeuverInterpolation reference(nodes, scene.problem.scheme, J, effects.get());
  const double h = nodes.time_step;
  const auto openLoopMiss = [&](bool mean) {
    RigidBodyPlant plant(J, nodes.attitude[0], nodes.angular_velocity[0], effects, Actuation(),
                         h / 8);
    for (int j = 0; j < nodes.steps(); ++j) {
      plant.command(mean ? reference.meanTorque(j * h, (j + 1) * h) : reference.at(j * h).torque);
      plant.advanceTo((j + 1) * h);
    }
    return so3::angleBetween(plant.attitude(), nodes.attitude.back());
  };
  const double held_sample = openLoopMiss(false), held_mean = openLoopMiss(true);
  std::printf("open loop: %.3g rad holding tau(t_j), %.3g rad holding its mean over the sample\n",
              held_sample, held_mean);
  EXPECT_LT(held_mean, 0.6 * held_sample);
}

TEST(ManeuverInterpolation, NonUniformTimesAreRefusedNamingTheRow) {
  Maneuver m;
  m.time_step = 0.5;
  m.time = {0.0, 0.5, 1.2};
  m.attitude.assign(3, Matrix3::Identity());
  m.angular_velocity.assign(3, Vector3::Zero());
  m.torque.assign(3, Vector3::Zero());
  try {
    requireUniformTimeGrid(m);
    FAIL() << "accepted time[2] = 1.2 with time_step 0.5";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("maneuver.time[2]"), std::string::npos) << e.what();
  }
  m.time[2] = 1.0;
  EXPECT_NO_THROW(requireUniformTimeGrid(m));
}

// Without effects, from the plan's own start, the loop reproduces the plan (the law only adds
// the discretization's small corrections); from a perturbed start it lands anyway.
TEST(SimulateTracking, TracksAPlanFromAPerturbedStart) {
  const int N = 64;
  const double h = 0.2;
  SimulationInput input;
  input.torque.assign(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) input.torque[k] = 0.2 * Vector3(std::sin(0.1 * k), 0.5, -0.3);
  const Maneuver plan = simulate(DiscreteScheme(SchemeKind::Variational, kInertia, h), input);
  const ManeuverInterpolation reference(plan, SchemeKind::Variational, kInertia, nullptr);
  const TrackingRun exact =
      simulateTracking(reference, plan.attitude[0], plan.angular_velocity[0], nullptr, nullptr, {});
  EXPECT_LT(exact.terminal_attitude_error, 1e-3);
  const TrackingRun perturbed =
      simulateTracking(reference, plan.attitude[0] * so3::exp(Vector3(0.3, -0.2, 0.1)),
                       Vector3(0.05, 0.0, 0.02), nullptr, nullptr, {});
  EXPECT_GT(perturbed.max_attitude_error, 0.3);
  EXPECT_LT(perturbed.terminal_attitude_error, 1e-2 * perturbed.max_attitude_error);
  EXPECT_EQ(perturbed.actual.steps(), N * perturbed.substeps);
  EXPECT_GT(perturbed.effort, exact.effort);
}

// scenes/disturbed_replay.yaml: the plan knows the gravity gradient and the disturbance, not the
// actuator noise. Open loop misses by the noise's random walk; closed loop by far less.
TEST(SimulateTracking, FeedbackBeatsOpenLoopReplayUnderNoiseByAnOrderOfMagnitude) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const auto& [scene, plan, J, effects] = disturbed;
  const Maneuver& nodes = plan.maneuver;

  Actuation open_loop_actuation = actuationOf(scene.effects);
  SimulationInput input;
  input.initial_attitude = nodes.attitude[0];
  input.initial_velocity = nodes.angular_velocity[0];
  input.torque = nodes.torque;
  input.effects = effects.get();
  input.actuation = &open_loop_actuation;
  const Maneuver replayed = replayPlan(scene.problem.scheme, J, nodes.time_step, input);
  const double replay_miss = so3::angleBetween(replayed.attitude.back(), nodes.attitude.back());

  Actuation closed_loop_actuation = actuationOf(scene.effects);
  const ManeuverInterpolation reference(nodes, scene.problem.scheme, J, effects.get());
  const TrackingRun run = simulateTracking(reference, nodes.attitude[0], nodes.angular_velocity[0],
                                           effects.get(), &closed_loop_actuation, {});
  EXPECT_GT(replay_miss, 1e-3);  // the noise matters open loop (~1.5e-3 rad, docs/ros_tracker.md)
  EXPECT_LT(run.terminal_attitude_error, 0.1 * replay_miss)
      << "feedback " << run.terminal_attitude_error << " rad, replay " << replay_miss << " rad";
}

// The plant (attitude_plant_node's core) against closed forms: a torque-free spin about a
// principal axis keeps Ω and turns R by exp(t Ω^); a constant torque about a principal axis from
// rest turns the body by ½ (τ/J) t² about it (Euler's equation decouples on that axis).
TEST(RigidBodyPlant, MatchesTheClosedFormsOfASpinAndAConstantTorque) {
  const Matrix3 J = Vector3(800.0, 1200.0, 1500.0).asDiagonal();
  const Vector3 spin(0.0, 0.03, 0.0);  // about the middle principal axis: an equilibrium
  RigidBodyPlant spinning(J, Matrix3::Identity(), spin, nullptr, Actuation(), 0.5);
  spinning.advanceTo(40.0);
  EXPECT_NEAR(so3::angleBetween(spinning.attitude(), so3::exp(Vector3(40.0 * spin))), 0.0, 1e-12);
  EXPECT_NEAR((spinning.angularVelocity() - spin).norm(), 0.0, 1e-15);

  RigidBodyPlant pushed(J, Matrix3::Identity(), Vector3::Zero(), nullptr, Actuation(), 0.25);
  const Vector3 torque(0.0, 0.0, 0.3);  // [N m] about the largest moment
  EXPECT_EQ(pushed.command(torque), torque);
  pushed.advanceTo(7.0);
  pushed.advanceTo(20.0);
  pushed.advanceTo(19.0);  // the past: nothing happens
  EXPECT_DOUBLE_EQ(pushed.time(), 20.0);
  const double angle = 0.5 * 0.3 / 1500.0 * 20.0 * 20.0;
  EXPECT_NEAR(so3::angleBetween(pushed.attitude(), so3::fromAxisAngle(Vector3::UnitZ(), angle)),
              0.0, 1e-13);
  EXPECT_NEAR(pushed.angularVelocity().z(), 0.3 / 1500.0 * 20.0, 1e-15);
  EXPECT_THROW(RigidBodyPlant(J, Matrix3::Identity(), spin, nullptr, Actuation(), 0.0),
               InvalidInput);
}

// predictState (a measurement moved to the time of the command) is the body's motion: forward
// and back again by the same dt is the identity to RKMK4's error; on a principal-axis spin under
// a torque about that axis it is the closed form (R = exp(θ e_z), θ = Ω_0 dt + ½ (τ/J) dt²); and
// it agrees with the plant (the same integrator) over one step, effects included.
TEST(RigidBodyPlant, PredictStateIsTheBodysMotion) {
  const Matrix3 J = Vector3(800.0, 1200.0, 1500.0).asDiagonal();
  const RigidBodyState spin{Matrix3::Identity(), Vector3(0.0, 0.0, 0.02)};
  const Vector3 torque(0.0, 0.0, 0.15);
  const double dt = 3.0;
  const RigidBodyState ahead = predictState(J, nullptr, spin, torque, 0.0, dt);
  const double angle = 0.02 * dt + 0.5 * 0.15 / 1500.0 * dt * dt;
  EXPECT_LT(so3::angleBetween(ahead.attitude, so3::fromAxisAngle(Vector3::UnitZ(), angle)), 1e-14);
  EXPECT_NEAR(ahead.angular_velocity.z(), 0.02 + 0.15 / 1500.0 * dt, 1e-15);

  const DisturbedPlan disturbed;
  const RigidBodyState tumbling{so3::exp(Vector3(0.3, -0.1, 0.7)), Vector3(0.002, -0.005, 0.001)};
  const Vector3 u(0.01, -0.02, 0.005);
  const RigidBodyState there =
      predictState(disturbed.J, disturbed.effects.get(), tumbling, u, 100.0, 0.5);
  const RigidBodyState back =
      predictState(disturbed.J, disturbed.effects.get(), there, u, 100.5, -0.5);
  EXPECT_LT(so3::angleBetween(back.attitude, tumbling.attitude), 1e-12);
  EXPECT_LT((back.angular_velocity - tumbling.angular_velocity).norm(), 1e-12);
  // The plant's clock starts at 0: its effects shifted by 100 s are those at t = 100.
  RigidBodyPlant at_100(disturbed.J, tumbling.attitude, tumbling.angular_velocity,
                        std::make_shared<const EffectModel>(disturbed.effects->timeShifted(100.0)),
                        Actuation(), 1.0);
  at_100.command(u);
  at_100.advanceTo(0.5);
  EXPECT_LT(so3::angleBetween(at_100.attitude(), there.attitude), 1e-15);
  EXPECT_LT((at_100.angularVelocity() - there.angular_velocity).norm(), 1e-15);
}

// The plant driven by the law's command at simulateTracking's control samples, on its clock, with
// the same effects and actuation (noise stream), is the internal feedback mode's run: what
// ~plant external with attitude_plant_node reproduces over ROS topics.
TEST(RigidBodyPlant, DrivenByTheLawAtTheControlSamplesReproducesSimulateTracking) {
  const DisturbedPlan disturbed;
  ASSERT_TRUE(disturbed.plan.converged()) << disturbed.plan.message();
  const auto& [scene, plan, J, effects] = disturbed;
  const Maneuver& nodes = plan.maneuver;
  const ManeuverInterpolation reference(nodes, scene.problem.scheme, J, effects.get());
  Actuation internal_actuation = actuationOf(scene.effects);
  const TrackingRun internal =
      simulateTracking(reference, nodes.attitude[0], nodes.angular_velocity[0], effects.get(),
                       &internal_actuation, {});

  const TrackingLaw law(reference, effects.get(), {});
  EXPECT_EQ(law.substepsPerPlanStep(), internal.substeps);
  const double dt = internal.actual.time_step;
  RigidBodyPlant plant(J, nodes.attitude[0], nodes.angular_velocity[0], effects,
                       actuationOf(scene.effects), dt);
  const int M = internal.actual.steps();
  for (int j = 0; j < M; ++j) {
    const Vector3 delivered =
        plant.command(law.command(plant.attitude(), plant.angularVelocity(), j * dt));
    EXPECT_NEAR((delivered - internal.actual.torque[j]).norm(), 0.0, 1e-12) << "sample " << j;
    plant.advanceTo((j + 1) * dt);
  }
  EXPECT_NEAR(so3::angleBetween(plant.attitude(), internal.actual.attitude[M]), 0.0, 1e-10);
  const double miss = so3::angleBetween(plant.attitude(), nodes.attitude.back());
  EXPECT_NEAR(miss, internal.terminal_attitude_error, 1e-10);
}
