// Reaction-wheel peaks (analysis/wheel_peaks.hpp) against a brute-force scan, and a plan flown
// with its wheel torques (analysis/wheel_flight.hpp: the tracker's body + wheels) against the
// plan: on the plan's scheme the flight reproduces it to round-off, continuously (RK4) it follows
// it to O(h²); its wheel torques are exactly the plan's at the nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "attitude_planner/analysis/wheel_flight.hpp"
#include "attitude_planner/analysis/wheel_peaks.hpp"
#include "attitude_planner/analysis/wheel_plant.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

namespace ap = attitude_planner;

namespace {

ap::ReactionWheels pyramidWheels() {
  const double s = std::sqrt(2.0 / 3.0), c = std::sqrt(1.0 / 3.0);
  ap::ReactionWheels w;
  w.spin_axes = {ap::Vector3(s, 0, c), ap::Vector3(0, s, c), ap::Vector3(-s, 0, c),
                 ap::Vector3(0, -s, c)};
  w.max_torque = {0.3};
  w.max_momentum = {3.0, 3.0, 2.0, 3.0};
  w.initial_momentum = {0.3, -0.2, 0.5, 0.1};
  w.max_momentum_norm = 4.0;
  return w;
}

ap::PlanningProblem pyramidSlew(int steps) {
  ap::PlanningProblem p;
  p.inertia << 13.0, -2.0, 1.0, -2.0, 16.0, 0.5, 1.0, 0.5, 18.0;
  p.duration = 20.0;
  p.steps = steps;
  p.scheme = ap::SchemeKind::SecondOrder;
  p.final_attitude = ap::so3::exp(ap::Vector3(0.4, -0.7, 0.9));
  p.reaction_wheels = pyramidWheels();
  return p;
}

}  // namespace

TEST(WheelPeaks, MatchABruteForceScanAndNameTheWorstExcess) {
  const ap::ReactionWheels wheels = pyramidWheels();
  const ap::WheelArray array = ap::wheelArray(wheels);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-2.5, 2.5);
  ap::WheelStates states;
  for (int k = 0; k <= 10; ++k) {
    Eigen::VectorXd h(4), u(4);
    for (int i = 0; i < 4; ++i) {
      h(i) = uniform(rng);
      u(i) = 0.1 * uniform(rng);
    }
    states.momentum.push_back(h);
    states.torque.push_back(u);
  }
  states.torque[0](1) = 5.0;  // an end torque: counted only with end torques
  for (const bool end_torques : {false, true}) {
    const ap::WheelPeaks peaks = ap::planWheelPeaks(wheels, states, end_torques);
    for (int i = 0; i < 4; ++i) {
      double h = 0.0, u = 0.0;
      for (int k = 0; k <= 10; ++k) {
        h = std::max(h, std::abs(states.momentum[k](i)));
        if (end_torques || (k > 0 && k < 10)) u = std::max(u, std::abs(states.torque[k](i)));
      }
      EXPECT_EQ(peaks.peak_momentum(i), h) << "wheel " << i;
      EXPECT_EQ(peaks.peak_torque(i), u) << "wheel " << i;
    }
    double norm = 0.0;
    for (const Eigen::VectorXd& h : states.momentum) norm = std::max(norm, (array.axes * h).norm());
    EXPECT_NEAR(peaks.peak_momentum_norm, norm, 1e-15 * norm);
  }
  ap::WheelPeaks peaks(4);
  peaks.peak_momentum << 1.0, 1.0, 2.5, 1.0;  // wheel_3: 0.5 past its 2 N m s
  peaks.peak_torque << 0.1, 0.2, 0.1, 0.1;
  peaks.peak_momentum_norm = 3.0;
  std::string which;
  EXPECT_DOUBLE_EQ(peaks.worstExcess(wheels, &which), 0.5);
  EXPECT_EQ(which, "wheel_3 momentum");
  peaks.peak_momentum_norm = 4.75;
  EXPECT_DOUBLE_EQ(peaks.worstExcess(wheels, &which), 0.75);
  EXPECT_EQ(which, "max_momentum_norm");
  peaks.peak_momentum_norm = 1.0;
  peaks.peak_momentum(2) = 1.0;
  EXPECT_LT(peaks.worstExcess(wheels, &which), 0.0) << "every limit holds";
}

/// ~mode replay's flight (the plan's scheme, the default model): the plan's wheel torques,
/// flown from its start through the scheme's own body + wheels, reproduce every node of the plan
/// to round-off (attitude, reported velocity, body torque, wheel momenta) on paper, variational
/// and second_order, so every wheel limit the plan meets holds in the flight to 1e-9; one wheel
/// torque off by 1e-3 of its limit at one node departs by orders of magnitude more.
TEST(WheelFlight, ReplayOnThePlansSchemeReproducesThePlanToRoundOff) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    ap::PlanningProblem p = pyramidSlew(32);
    p.scheme = scheme;
    p.reaction_wheels.max_momentum = {0.9};  // binding on some wheel (checked below)
    const std::string name = ap::schemeName(scheme);
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << name << ": " << r.message();
    ASSERT_GT(r.active_constraints, 0) << name;
    const ap::WheelStates planned =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    const ap::RigidBodyState start{r.maneuver.attitude[0], r.maneuver.angular_velocity[0]};
    const ap::WheelFlight flight =
        ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r.maneuver, {}, start);
    ASSERT_EQ(flight.body.steps(), 32);
    const double h = r.maneuver.time_step;
    double attitude = 0.0, rate = 0.0, torque = 0.0, momentum = 0.0;
    for (int k = 0; k <= 32; ++k) {
      EXPECT_EQ(flight.torqueAt(k * h), planned.torque[k]) << name << " k = " << k;
      attitude = std::max(attitude,
                          ap::so3::angleBetween(flight.body.attitude[k], r.maneuver.attitude[k]));
      rate =
          std::max(rate, (flight.body.angular_velocity[k] - r.maneuver.angular_velocity[k]).norm());
      momentum = std::max(momentum, (flight.momentum[k] - planned.momentum[k]).norm());
      if (ap::schemeHasEndTorques(scheme) || (k > 0 && k < 32)) {
        torque = std::max(torque, (flight.body.torque[k] - r.maneuver.torque[k]).norm());
      }
    }
    std::printf("%s: departure %.3g rad, %.3g rad/s, %.3g N m, %.3g N m s\n", name.c_str(),
                attitude, rate, torque, momentum);
    EXPECT_LT(attitude, 1e-12) << name;
    EXPECT_LT(rate, 1e-12) << name;
    EXPECT_LT(torque, 1e-10) << name;
    EXPECT_LT(momentum, 1e-12) << name;
    std::string which;
    EXPECT_LT(flight.peaks.worstExcess(p.reaction_wheels, &which), 1e-9 * 0.9) << which;
    EXPECT_GT(flight.peaks.worstExcess(p.reaction_wheels), -1e-6) << name << ": a limit binds";

    std::vector<Eigen::VectorXd> nudged = planned.torque;
    nudged[16](1) += 1e-3 * p.reaction_wheels.max_torque[0];
    const ap::WheelFlight off =
        ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r.maneuver, nudged, start);
    const double miss = ap::so3::angleBetween(off.body.attitude.back(), r.maneuver.attitude.back());
    EXPECT_GT(miss, 1e3 * std::max(attitude, 1e-15)) << name << ": a wrong torque departs";
  }
}

/// The continuous flight (WheelFlightModel::Continuous, what fourth_order plans get): the
/// flight's wheel torques are the plan's (held linearly); its body and wheel momenta follow the
/// plan to O(h²) (the planner's discrete algebra against the continuous body + wheels).
TEST(WheelFlight, ContinuousFlightFollowsThePlanToSecondOrder) {
  std::vector<double> misses, momentum_gaps;
  for (const int N : {32, 64, 128}) {
    const ap::PlanningProblem p = pyramidSlew(N);
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    const ap::WheelStates planned =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    const ap::WheelFlight flight =
        ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r.maneuver, {},
                          ap::RigidBodyState{p.initial_attitude, p.initial_velocity},
                          ap::WheelFlightModel::Continuous);
    ASSERT_EQ(flight.body.steps(), N);
    const double h = r.maneuver.time_step;
    double gap = 0.0;
    for (int k = 0; k <= N; ++k) {
      EXPECT_EQ(flight.torqueAt(k * h), planned.torque[k]) << "k = " << k;
      gap = std::max(gap, (flight.momentum[k] - planned.momentum[k]).cwiseAbs().maxCoeff());
    }
    const Eigen::VectorXd middle = 0.5 * (planned.torque[3] + planned.torque[4]);
    EXPECT_LT((flight.torqueAt(3.5 * h) - middle).norm(), 1e-15);
    misses.push_back(ap::so3::angleBetween(flight.body.attitude.back(), p.final_attitude));
    momentum_gaps.push_back(gap);
    std::printf("N = %d: terminal miss %.3g rad, max |h_flown - h_planned| %.3g N m s\n", N,
                misses.back(), gap);
  }
  EXPECT_LT(misses[0], 1e-2);
  EXPECT_GT(misses[0] / misses[1], 3.0);
  EXPECT_GT(misses[1] / misses[2], 3.0);
  EXPECT_GT(momentum_gaps[0] / momentum_gaps[1], 3.0);
  EXPECT_GT(momentum_gaps[1] / momentum_gaps[2], 3.0);
}

/// Plans `p` (which must converge) and flies the plan's own wheel torques from its start.
void planAndFly(const ap::PlanningProblem& p, ap::PlanResult* r, ap::WheelFlight* flight) {
  *r = ap::planManeuver(p);
  ASSERT_TRUE(r->converged()) << r->message();
  *flight = ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r->maneuver, {},
                              ap::RigidBodyState{p.initial_attitude, p.initial_velocity});
}

/// The body torque of the flight is the array's reaction, τ = −A u − Ω × A h_w, at every node.
TEST(WheelFlight, BodyTorqueIsTheArraysReaction) {
  const ap::PlanningProblem p = pyramidSlew(32);
  ap::PlanResult r;
  ap::WheelFlight flight;
  ASSERT_NO_FATAL_FAILURE(planAndFly(p, &r, &flight));
  const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
  for (int k = 0; k <= 32; ++k) {
    const ap::Vector3 Omega = flight.body.angular_velocity[k];
    ap::Vector3 expected = ap::Vector3::Zero();
    for (int i = 0; i < 4; ++i) {  // wheel by wheel, not the matrix product
      const ap::Vector3 a = array.axes.col(i);
      expected -= a * flight.torque[k](i) + Omega.cross(a * flight.momentum[k](i));
    }
    EXPECT_LT((flight.body.torque[k] - expected).norm(), 1e-13) << "k = " << k;
    // and the plan's body torque: the array makes the torque the plan asked for
    EXPECT_LT((flight.body.torque[k] - r.maneuver.torque[k]).norm(), 1e-10) << "k = " << k;
  }
}

/// A wheel's spin rate relative to the body (wheelSpinRates) against the gyrostat written with
/// relative rates: the body with its wheels locked has the inertia J_total = J + Σ J_s,i a_i a_iᵀ
/// (J excludes the wheels' axial inertia), and the wheels add Σ a_i J_s,i w_i. Its momentum must
/// be the package's J Ω + A h_w at every node of a flight; a wheel turning with the body (w = 0)
/// carries h = J_s a·Ω.
TEST(WheelSpinRates, GyrostatWithRelativeRatesHasTheArraysMomentum) {
  ap::PlanningProblem p = pyramidSlew(32);
  p.reaction_wheels.spin_inertia = {0.02, 0.03, 0.025, 0.04};
  ap::PlanResult r;
  ap::WheelFlight flight;
  ASSERT_NO_FATAL_FAILURE(planAndFly(p, &r, &flight));
  const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
  ap::Matrix3 locked = p.inertia;
  for (int i = 0; i < 4; ++i) {
    const ap::Vector3 a = array.axes.col(i);
    locked += p.reaction_wheels.spin_inertia[i] * a * a.transpose();
  }
  double largest_rate = 0.0;
  for (int k = 0; k <= 32; ++k) {
    const ap::Vector3 Omega = flight.body.angular_velocity[k];
    const Eigen::VectorXd w = ap::wheelSpinRates(p.reaction_wheels, flight.momentum[k], Omega);
    ap::Vector3 gyrostat = locked * Omega;
    for (int i = 0; i < 4; ++i)
      gyrostat += array.axes.col(i) * p.reaction_wheels.spin_inertia[i] * w(i);
    const ap::Vector3 package = p.inertia * Omega + array.axes * flight.momentum[k];
    EXPECT_LT((gyrostat - package).norm(), 1e-13 * package.norm()) << "k = " << k;
    largest_rate = std::max(largest_rate, w.cwiseAbs().maxCoeff());
    // A tachometer's reading back to the momenta (the external plant's measurement): the inverse.
    const Eigen::VectorXd back = ap::wheelMomentaFromSpinRates(p.reaction_wheels, w, Omega);
    EXPECT_LT((back - flight.momentum[k]).norm(), 1e-14 * (1 + flight.momentum[k].norm()));
  }
  EXPECT_GT(largest_rate, 1.0);  // [rad/s]: the wheels spin (biased), so the check has teeth
  // Locked wheels: h_i = J_s,i a_i·Ω gives w = 0 (the scalar spin inertia for every wheel).
  p.reaction_wheels.spin_inertia = {0.05};
  const ap::Vector3 Omega(0.3, -0.2, 0.1);
  Eigen::VectorXd locked_momenta(4);
  for (int i = 0; i < 4; ++i) locked_momenta(i) = 0.05 * array.axes.col(i).dot(Omega);
  EXPECT_LT(ap::wheelSpinRates(p.reaction_wheels, locked_momenta, Omega).norm(), 1e-15);
}

/// spin_inertia: one value or one per wheel, each finite and > 0 [kg m^2], checked once by the
/// core (validateProblem), named by its scene key; a scene writes and reads it back.
TEST(WheelSpinRates, SpinInertiaIsValidatedByNameAndRoundTrips) {
  const std::string base = std::string(AP_SOURCE_DIR) + "/test/ros/wheel_pyramid.yaml";
  ap::Scene scene = ap::loadScene(base);
  const auto refused = [&](std::vector<double> spin, const std::string& expected) {
    ap::PlanningProblem p = scene.problem;
    p.reaction_wheels.spin_inertia = std::move(spin);
    try {
      ap::validateProblem(p);
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const ap::InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("actuators.reaction_wheels.spin_inertia"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused({0.01, 0.02}, "got 2 values [0.01, 0.02]");
  refused({0.01, -0.02, 0.01, 0.01}, "got -0.02 at index 1");
  refused({std::nan("")}, "got nan at index 0");
  refused({0.0}, "got 0 at index 0");
  scene.problem.reaction_wheels.spin_inertia = {0.01, 0.02, 0.03, 0.04};
  EXPECT_NO_THROW(ap::validateProblem(scene.problem));
  const ap::Scene back = ap::parseScene(ap::formatScene(scene));
  EXPECT_EQ(back.problem.reaction_wheels.spin_inertia, scene.problem.reaction_wheels.spin_inertia);
  // The scene key itself, as a scalar.
  std::string text = ap::formatScene(scene);
  const std::size_t at = text.find(", spin_inertia:");
  ASSERT_NE(at, std::string::npos) << text;
  text = text.substr(0, at) + ", spin_inertia: 0.015}}" + text.substr(text.find("}}", at) + 2);
  EXPECT_EQ(ap::parseScene(text).problem.reaction_wheels.spin_inertia, std::vector<double>{0.015});
}

/// The feedback mode with wheels (trackWithWheels): from a start off the plan the wheels fly the
/// law's torque (delivered body torque = the law's command, recomputed here, at every sample no
/// wheel was cut; the wheel torques carry no null-space part), the loop lands on the target, and
/// with a torque limit below what the law asks the commands are cut to exactly ±U.
TEST(WheelTracking, WheelsDeliverTheLawsTorqueAndAreCutAtTheirLimits) {
  ap::PlanningProblem p = pyramidSlew(64);
  p.reaction_wheels.max_momentum = {3.0};  // room for the correction
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  const ap::ManeuverInterpolation reference(r.maneuver, p.scheme, p.inertia, nullptr);
  const ap::RigidBodyState start{ap::so3::exp(ap::Vector3(0.02, -0.01, 0.015)),
                                 ap::Vector3(0.002, 0.0, -0.001)};
  const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
  const auto check = [&](const ap::ReactionWheels& wheels, bool expect_cut) {
    const ap::WheelTracking run =
        ap::trackWithWheels(reference, p.inertia, wheels, start, ap::TrackingOptions());
    const ap::TrackingLaw law(reference, nullptr, ap::TrackingOptions());
    ASSERT_EQ(run.samples, 64 * run.substeps);
    ASSERT_EQ(static_cast<int>(run.flight.torque.size()), run.samples + 1);
    int delivered_as_commanded = 0;
    double peak_u = 0.0;
    for (int j = 0; j < run.samples; ++j) {
      const ap::Maneuver& body = run.flight.body;
      const Eigen::VectorXd& u = run.flight.torque[j];
      peak_u = std::max(peak_u, u.cwiseAbs().maxCoeff());
      const ap::Vector3 commanded =
          law.command(body.attitude[j], body.angular_velocity[j], j * body.time_step);
      if ((body.torque[j] - commanded).norm() < 1e-12 * (1.0 + commanded.norm())) {
        ++delivered_as_commanded;
        // minimum norm: u = A⁺A u (no part in A's null space)
        EXPECT_LT((u - array.pseudo_inverse * (array.axes * u)).norm(), 1e-14) << j;
      }
    }
    if (expect_cut) {
      EXPECT_GT(run.saturated_samples, 0);
      EXPECT_DOUBLE_EQ(peak_u, wheels.max_torque[0]);
    } else {
      EXPECT_EQ(run.saturated_samples, 0);
      EXPECT_EQ(delivered_as_commanded, run.samples);
      const ap::Matrix3 end = run.flight.body.attitude.back();
      EXPECT_LT(ap::so3::angleBetween(end, p.final_attitude), 1e-3);
    }
    EXPECT_LE(peak_u, wheels.max_torque[0]);
    std::printf("U = %g N m: %d of %d samples cut, %d delivered as commanded, terminal %.3g rad\n",
                wheels.max_torque[0], run.saturated_samples, run.samples, delivered_as_commanded,
                ap::so3::angleBetween(run.flight.body.attitude.back(), p.final_attitude));
  };
  ap::ReactionWheels roomy = p.reaction_wheels;
  roomy.max_torque = {5.0};  // above the law's first correction of the 0.027 rad offset
  check(roomy, false);
  ap::ReactionWheels tight = p.reaction_wheels;
  tight.max_torque = {0.05};
  check(tight, true);
}

/// WheelPlant (attitude_plant_node with wheels) against closed forms: three orthogonal wheels on
/// a principal-axis body at rest, wheel_1 (along x) commanded a constant u: the body turns about
/// x alone with J_x Ω̇ = −u, so Ω_x = −u t / J_x, the angle −u t² / (2 J_x), and h_1 = u t; a
/// command past its limit is cut to ±U; torque-free, R (J Ω + A h_w) stays put.
TEST(WheelPlant, MatchesClosedFormsAndConservesTheTotalMomentum) {
  ap::ReactionWheels wheels;
  wheels.spin_axes = {ap::Vector3::UnitX(), ap::Vector3::UnitY(), ap::Vector3::UnitZ()};
  wheels.max_torque = {0.2};
  wheels.max_momentum = {5.0};
  const ap::Matrix3 J = ap::Vector3(10.0, 12.0, 14.0).asDiagonal();
  ap::WheelPlant plant(J, wheels, {ap::Matrix3::Identity(), ap::Vector3::Zero()}, 0.05);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3);
  u(0) = 0.5;  // past U = 0.2: delivered 0.2
  EXPECT_EQ(plant.command(u)(0), 0.2);
  plant.advanceTo(3.0);
  const double t = 3.0, delivered = 0.2;
  EXPECT_NEAR(plant.angularVelocity().x(), -delivered * t / 10.0, 1e-14);
  EXPECT_LT(plant.angularVelocity().tail<2>().norm(), 1e-15);
  EXPECT_NEAR(plant.momentum()(0), delivered * t, 1e-14);
  const ap::Vector3 turned = ap::so3::log(plant.attitude());
  EXPECT_NEAR(turned.x(), -delivered * t * t / 20.0, 1e-12);
  EXPECT_THROW(plant.command(Eigen::VectorXd::Zero(2)), ap::InvalidInput);

  // Torque-free tumbling with a biased pyramid: the total momentum is conserved to RK4's error.
  ap::WheelPlant free(ap::Matrix3(pyramidSlew(8).inertia), pyramidWheels(),
                      {ap::so3::exp(ap::Vector3(0.3, -0.2, 0.1)), ap::Vector3(0.2, -0.1, 0.15)},
                      0.01);
  const ap::WheelArray array = ap::wheelArray(pyramidWheels());
  const auto total = [&](const ap::WheelPlant& p) {
    return ap::Vector3(p.attitude() *
                       (pyramidSlew(8).inertia * p.angularVelocity() + array.axes * p.momentum()));
  };
  const ap::Vector3 before = total(free);
  free.advanceTo(20.0);
  EXPECT_LT((total(free) - before).norm(), 1e-9 * before.norm());
  EXPECT_GT(ap::so3::angleBetween(free.attitude(), ap::Matrix3::Identity()), 0.5) << "it moved";
}

/// A wheel that reaches its momentum limit stops there: the closed form of a saturated wheel on a
/// principal axis (J_x Ω̇_x = −ḣ, ḣ = u until h = H at t_s = H/u, then ḣ = 0 and Ω_x holds
/// −H/J_x), whether the plant is advanced in one call or in many; the torque it can no longer
/// absorb is not delivered, the total momentum stays zero, and a torque back off the limit is
/// delivered again.
TEST(WheelPlant, AWheelAtItsMomentumLimitStopsThereAndTheBodyKeepsItsMomentum) {
  ap::ReactionWheels wheels;
  wheels.spin_axes = {ap::Vector3::UnitX(), ap::Vector3::UnitY(), ap::Vector3::UnitZ()};
  wheels.max_torque = {0.2};
  wheels.max_momentum = {0.5};
  const ap::Matrix3 J = ap::Vector3(10.0, 12.0, 14.0).asDiagonal();
  const double u = 0.2, H = 0.5, Jx = 10.0, t_s = H / u, t = 4.0;
  Eigen::VectorXd command = Eigen::VectorXd::Zero(3);
  command(0) = u;
  for (int calls : {1, 7, 64}) {
    ap::WheelPlant plant(J, wheels, {ap::Matrix3::Identity(), ap::Vector3::Zero()}, 0.05);
    plant.command(command);
    for (int c = 1; c <= calls; ++c) plant.advanceTo(t * c / calls);
    EXPECT_NEAR(plant.saturatedAt()[0], t_s, 1e-12) << calls;
    EXPECT_TRUE(std::isnan(plant.saturatedAt()[1])) << "the other wheels never moved";
    EXPECT_EQ(plant.momentum()(0), H) << calls;
    EXPECT_EQ(plant.deliveredTorque()(0), 0.0) << "the wheel cannot absorb more";
    EXPECT_NEAR(plant.angularVelocity().x(), -H / Jx, 1e-14) << calls;
    EXPECT_LT(plant.angularVelocity().tail<2>().norm(), 1e-15);
    const double angle = -u * t_s * t_s / (2 * Jx) - H / Jx * (t - t_s);
    EXPECT_NEAR(ap::so3::log(plant.attitude()).x(), angle, 1e-12) << calls;
    // The total momentum R (J Ω + A h_w) stays what it was: zero.
    EXPECT_LT((J * plant.angularVelocity() + plant.momentum()).norm(), 1e-14) << calls;
    // Back off the limit: delivered again, the momentum leaves H linearly.
    EXPECT_EQ(plant.command(-command)(0), -u);
    plant.advanceTo(t + 1.0);
    EXPECT_NEAR(plant.momentum()(0), H - u, 1e-14);
    EXPECT_NEAR(plant.angularVelocity().x(), -(H - u) / Jx, 1e-14);
  }
  // Without the stop, the unsaturated closed form would have gone on: the difference is visible.
  EXPECT_GT(u * t - H, 0.1);
}

/// Effects act on the body, and the wheels only move momentum between body and wheels: under a
/// constant world-frame disturbance τ_d the total angular momentum R (J Ω + A h_w) grows by
/// exactly its impulse t τ_d (closed form), whatever the wheels are commanded, in one call or many.
TEST(WheelPlant, AWorldDisturbanceChangesTheTotalMomentumByItsImpulse) {
  const ap::ReactionWheels wheels = pyramidWheels();
  const ap::Matrix3 J = pyramidSlew(8).inertia;
  const ap::WheelArray array = ap::wheelArray(wheels);
  const ap::Vector3 tau_d(0.02, -0.015, 0.01);
  auto effects = std::make_shared<ap::EffectModel>();
  effects->add(std::make_unique<ap::DisturbanceTorque>(tau_d, ap::TorqueFrame::World));
  const ap::RigidBodyState start{ap::so3::exp(ap::Vector3(0.3, -0.2, 0.1)),
                                 ap::Vector3(0.05, -0.04, 0.03)};
  const auto total = [&](const ap::WheelPlant& p) {
    return ap::Vector3(p.attitude() * (J * p.angularVelocity() + array.axes * p.momentum()));
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> torque(-0.1, 0.1);
  for (int calls : {1, 5, 40}) {
    ap::WheelPlant plant(J, wheels, start, 0.01, effects);
    ap::WheelPlant undisturbed(J, wheels, start, 0.01);
    const ap::Vector3 before = total(plant);
    const double T = 20.0;
    for (int c = 1; c <= calls; ++c) {
      Eigen::VectorXd u(4);
      for (int i = 0; i < 4; ++i) u(i) = torque(rng);
      plant.command(u);
      undisturbed.command(u);
      plant.advanceTo(T * c / calls);
      undisturbed.advanceTo(T * c / calls);
    }
    EXPECT_LT((total(plant) - (before + T * tau_d)).norm(), 1e-9 * (T * tau_d).norm()) << calls;
    // It acted: without it the total stays where it was and the body ends elsewhere.
    EXPECT_LT((total(undisturbed) - before).norm(), 1e-9 * before.norm()) << calls;
    EXPECT_GT(ap::so3::angleBetween(plant.attitude(), undisturbed.attitude()), 1e-2) << calls;
  }
}

/// With the wheels at rest (no momentum, no command) the body is a rigid body: under a gravity
/// gradient (a fast orbit, so its clock matters) and a body-frame disturbance the plant moves as
/// RigidBodyPlant does (an independent integrator, RKMK4 on the rotation group), advanced in one
/// call or many: the effects see the attitude, the body frame and the plant's time.
TEST(WheelPlant, EffectsActOnTheBodyAsOnARigidBodyWhenTheWheelsRest) {
  ap::ReactionWheels wheels = pyramidWheels();
  wheels.initial_momentum = {0.0, 0.0, 0.0, 0.0};
  const ap::Matrix3 J = pyramidSlew(8).inertia;
  const double r = 7.0e6, n = 0.05;  // mean motion [rad/s]: an orbit in about 2 minutes
  auto effects = std::make_shared<ap::EffectModel>();
  effects->add(std::make_unique<ap::GravityGradient>(n * n * r * r * r, r, J));
  effects->add(std::make_unique<ap::DisturbanceTorque>(ap::Vector3(1e-3, 0.0, -2e-3),
                                                       ap::TorqueFrame::Body));
  const ap::Matrix3 R0 = ap::so3::exp(ap::Vector3(0.4, 0.1, -0.3));
  const ap::Vector3 W0(0.02, -0.03, 0.01);
  for (int calls : {1, 9}) {
    ap::WheelPlant plant(J, wheels, {R0, W0}, 0.005, effects);
    ap::RigidBodyPlant body(J, R0, W0, effects, ap::Actuation(), 0.005);
    ap::RigidBodyPlant free(J, R0, W0, nullptr, ap::Actuation(), 0.005);
    const double T = 60.0;
    for (int c = 1; c <= calls; ++c) {
      plant.advanceTo(T * c / calls);
      body.advanceTo(T * c / calls);
      free.advanceTo(T * c / calls);
    }
    EXPECT_LT(ap::so3::angleBetween(plant.attitude(), body.attitude()), 1e-8) << calls;
    EXPECT_LT((plant.angularVelocity() - body.angularVelocity()).norm(), 1e-9) << calls;
    EXPECT_LT(plant.momentum().norm(), 1e-15) << "the wheels stay at rest";
    EXPECT_GT(ap::so3::angleBetween(body.attitude(), free.attitude()), 0.05) << "the effects acted";
  }
}

/// predictWheelState moves a state as the plant does: the same equations under the held torques.
TEST(WheelPlant, PredictionIsThePlantsMotion) {
  const ap::ReactionWheels wheels = pyramidWheels();
  const ap::Matrix3 J = pyramidSlew(8).inertia;
  const ap::RigidBodyState start{ap::so3::exp(ap::Vector3(0.1, 0.2, -0.3)),
                                 ap::Vector3(0.05, -0.02, 0.03)};
  ap::WheelPlant plant(J, wheels, start, 0.0125);
  Eigen::VectorXd u(4);
  u << 0.1, -0.05, 0.02, 0.15;
  plant.command(u);
  plant.advanceTo(0.2);
  ap::WheelBodyState state{start, Eigen::VectorXd(4)};
  state.momentum << 0.3, -0.2, 0.5, 0.1;
  const ap::WheelBodyState predicted =
      ap::predictWheelState(J, ap::wheelArray(wheels), state, u, 0.2);
  EXPECT_LT(ap::so3::angleBetween(predicted.body.attitude, plant.attitude()), 1e-13);
  EXPECT_LT((predicted.body.angular_velocity - plant.angularVelocity()).norm(), 1e-13);
  EXPECT_LT((predicted.momentum - plant.momentum()).norm(), 1e-13);
  EXPECT_GT((predicted.momentum - state.momentum).norm(), 1e-3) << "the wheels moved";
}
