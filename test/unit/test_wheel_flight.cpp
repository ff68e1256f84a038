// Reaction-wheel peaks (analysis/wheel_peaks.hpp) against a brute-force scan, and a plan flown
// with its wheel torques (analysis/wheel_flight.hpp: the tracker's body + wheels) against the
// plan: the flight follows it to O(h²), its wheel torques are exactly the plan's at the nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "attitude_planner/analysis/wheel_flight.hpp"
#include "attitude_planner/analysis/wheel_peaks.hpp"
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

/// The flight's wheel torques are the plan's (held linearly); its body and wheel momenta follow
/// the plan to O(h²) (the planner's discrete algebra against the continuous body + wheels).
TEST(WheelFlight, FliesThePlansWheelTorquesAndFollowsThePlanToSecondOrder) {
  std::vector<double> misses, momentum_gaps;
  for (const int N : {32, 64, 128}) {
    const ap::PlanningProblem p = pyramidSlew(N);
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message;
    const ap::WheelStates planned =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    const ap::WheelFlight flight =
        ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r.maneuver, {},
                          ap::RigidBodyState{p.initial_attitude, p.initial_velocity});
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

/// The body torque of the flight is the array's reaction, τ = −A u − Ω × A h_w, at every node.
TEST(WheelFlight, BodyTorqueIsTheArraysReaction) {
  const ap::PlanningProblem p = pyramidSlew(32);
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message;
  const ap::WheelFlight flight =
      ap::flyWithWheels(p.inertia, p.scheme, p.reaction_wheels, r.maneuver, {},
                        ap::RigidBodyState{p.initial_attitude, p.initial_velocity});
  const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
  for (int k = 0; k <= 32; ++k) {
    const ap::Vector3 Omega = flight.body.angular_velocity[k];
    ap::Vector3 expected = ap::Vector3::Zero();
    for (int i = 0; i < 4; ++i) {  // wheel by wheel, not the matrix product
      const ap::Vector3 a = array.axes.col(i);
      expected -= a * flight.torque[k](i) + Omega.cross(a * flight.momentum[k](i));
    }
    EXPECT_LT((flight.body.torque[k] - expected).norm(), 1e-13) << "k = " << k;
    // and the plan's body torque to O(h): the array makes the torque the plan asked for
    EXPECT_LT((flight.body.torque[k] - r.maneuver.torque[k]).norm(), 0.05) << "k = " << k;
  }
}
