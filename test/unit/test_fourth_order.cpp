// fourth_order: one Richardson extrapolation step of the time-symmetric second_order scheme
// (docs/design/fourth_order.md). Orders against the continuous reference on small sweeps, the
// isotropic closed form, equivariance, the cubic hold and its RKMK4 replay, and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "attitude_planner/analysis/accuracy.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "support/robustness_cases.hpp"
#include "support/seed_examples.hpp"

using namespace attitude_planner;

namespace {

using test_support::fittedOrder;

PlanningProblem seedProblem(bool slew_up, SchemeKind scheme = SchemeKind::FourthOrder) {
  return test_support::seedProblem(slew_up, scheme);
}

double maxTorque(const Maneuver& m) {
  double largest = 0;
  for (const Vector3& t : m.torque) largest = std::max(largest, t.norm());
  return largest;
}

}  // namespace

// The orders on N = 32 … 256 (below the torque's round-off floor eps·(2N)², which the
// extrapolation reaches at N ≈ 512: docs/design/fourth_order.md). The documented order is 4.
TEST(FourthOrder, SmallSweepMeasuresOrderFourInEveryMeasure) {
  for (bool slew_up : {false, true}) {
    PlanningProblem p = seedProblem(slew_up);
    const ContinuousReference ref = solveContinuousReference(p);
    ASSERT_TRUE(ref.converged) << ref.message;
    std::vector<int> Ns;
    std::vector<double> cost, trajectory, torque, miss, velocity_miss;
    for (int N = 32; N <= 256; N *= 2) {
      p.steps = N;
      const PlanResult plan = planManeuver(p);
      ASSERT_TRUE(plan.converged()) << plan.message();
      EXPECT_EQ(plan.scheme, SchemeKind::FourthOrder);
      EXPECT_EQ(plan.maneuver.steps(), N);
      const AccuracyMeasures m = measureAccuracy(p, plan.maneuver, ref);
      EXPECT_NEAR(m.cost_integral, plan.effort, 1e-14 * plan.effort);
      Ns.push_back(N);
      cost.push_back(m.cost_error);
      trajectory.push_back(m.trajectory_error);
      torque.push_back(m.torque_error);
      miss.push_back(m.miss.attitude_miss);
      velocity_miss.push_back(m.miss.velocity_miss);
      std::printf("%s N=%d cost %.3e traj %.3e torque %.3e miss %.3e vmiss %.3e\n",
                  slew_up ? "slew_up" : "rest_to_rest", N, m.cost_error, m.trajectory_error,
                  m.torque_error, m.miss.attitude_miss, m.miss.velocity_miss);
    }
    const std::string what = slew_up ? "slew_up" : "rest_to_rest";
    const double orders[] = {fittedOrder(Ns, cost), fittedOrder(Ns, trajectory),
                             fittedOrder(Ns, torque), fittedOrder(Ns, miss),
                             fittedOrder(Ns, velocity_miss)};
    std::printf("%s orders: cost %.2f traj %.2f torque %.2f miss %.2f vmiss %.2f\n", what.c_str(),
                orders[0], orders[1], orders[2], orders[3], orders[4]);
    for (double order : orders) EXPECT_GE(order, 3.5) << what;
    EXPECT_NEAR(orders[1], measuredOrder(SchemeKind::FourthOrder, AccuracyMeasure::CostError), 0.3)
        << what;
    EXPECT_NEAR(orders[3], measuredOrder(SchemeKind::FourthOrder, AccuracyMeasure::TerminalMiss),
                0.3)
        << what;
  }
}

// The target: relative torque error ≤ 1e-6 against the continuous optimum on the seed's
// rest-to-rest example, at a resolution that solves in milliseconds (N = 64: second_order at 64
// and 128).
TEST(FourthOrder, SeedRestToRestTorqueWithinOnePpmAtSixtyFourSteps) {
  PlanningProblem p = seedProblem(false);
  const ContinuousReference ref = solveContinuousReference(p);
  ASSERT_TRUE(ref.converged) << ref.message;
  p.steps = 64;
  const PlanResult plan = planManeuver(p);
  ASSERT_TRUE(plan.converged()) << plan.message();
  const AccuracyMeasures m = measureAccuracy(p, plan.maneuver, ref);
  EXPECT_LE(m.torque_error / maxTorque(plan.maneuver), 1e-6);
  // and the effort converges to the continuous optimum's
  EXPECT_LE(std::abs(plan.effort - ref.cost), 1e-6 * ref.cost);
}

// J = jI, rest to rest, rotation θ about a: τ(t) = jθ(6/T² − 12t/T³)a, effort 6j²θ²/T³.
TEST(FourthOrder, IsotropicRestToRestClosedForm) {
  const double j = 2.5, theta = 1.2, T = 10.0;
  const Vector3 a = Vector3(1, 2, 3).normalized();
  const double exact_effort = 6 * j * j * theta * theta / (T * T * T);
  std::vector<int> Ns;
  std::vector<double> effort_error, torque_error, trajectory_error;
  for (int N : {8, 16, 32, 64}) {
    PlanningProblem p;
    p.inertia = j * Matrix3::Identity();
    p.duration = T;
    p.steps = N;
    p.final_attitude = so3::fromAxisAngle(a, theta);
    p.scheme = SchemeKind::FourthOrder;
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    const double h = T / N;
    double te = 0, re = 0;
    for (int k = 0; k <= N; ++k) {
      const double t = k * h, s = t / T;
      const Vector3 exact = j * theta * (6 / (T * T) - 12 * t / (T * T * T)) * a;
      EXPECT_LE(r.maneuver.torque[k].cross(a).norm(), 1e-10 * exact_effort);
      te = std::max(te, (r.maneuver.torque[k] - exact).norm());
      const Matrix3 R = so3::fromAxisAngle(a, theta * (3 * s * s - 2 * s * s * s));
      re = std::max(re, so3::angleBetween(R, r.maneuver.attitude[k]));
    }
    Ns.push_back(N);
    effort_error.push_back(std::abs(r.effort - exact_effort));
    torque_error.push_back(te);
    trajectory_error.push_back(re);
    std::printf("isotropic N=%d effort %.3e torque %.3e traj %.3e\n", N, effort_error.back(), te,
                re);
  }
  EXPECT_GE(fittedOrder(Ns, effort_error), 3.7);
  EXPECT_GE(fittedOrder(Ns, torque_error), 3.7);
  EXPECT_GE(fittedOrder(Ns, trajectory_error), 3.7);
  EXPECT_LE(effort_error.back(), 1e-6 * exact_effort);
}

TEST(FourthOrder, EquivarianceUnderWorldRotation) {
  const Matrix3 Q = so3::exp(Vector3(0.7, -1.9, 0.4));
  PlanningProblem p = seedProblem(true);
  p.steps = 64;
  const PlanResult a = planManeuver(p);
  p.initial_attitude = Q * p.initial_attitude;
  p.final_attitude = Q * p.final_attitude;
  const PlanResult b = planManeuver(p);
  ASSERT_TRUE(a.converged() && b.converged()) << a.message() << " / " << b.message();
  double torque = 0, attitude = 0, velocity = 0;
  for (int k = 0; k <= 64; ++k) {
    torque = std::max(torque, (a.maneuver.torque[k] - b.maneuver.torque[k]).norm());
    velocity = std::max(velocity,
                        (a.maneuver.angular_velocity[k] - b.maneuver.angular_velocity[k]).norm());
    attitude =
        std::max(attitude, so3::angleBetween(Q * a.maneuver.attitude[k], b.maneuver.attitude[k]));
  }
  EXPECT_LE(torque, 1e-10);
  EXPECT_LE(velocity, 1e-10);
  EXPECT_LE(attitude, 1e-10);
  EXPECT_NEAR(a.effort, b.effort, 1e-12 * a.effort);
}

// The combination rule itself: fourth_order's node values are X_{2N} + (X_{2N} − X_N)/3 of the
// two second_order plans (on the group for the attitudes), its ends the boundary data.
TEST(FourthOrder, IsTheRichardsonCombinationOfSecondOrderAtNAndTwoN) {
  PlanningProblem p = seedProblem(true);
  p.steps = 32;
  const PlanResult four = planManeuver(p);
  p.scheme = SchemeKind::SecondOrder;
  const PlanResult coarse = planManeuver(p);
  p.steps = 64;
  const PlanResult fine = planManeuver(p);
  ASSERT_TRUE(four.converged() && coarse.converged() && fine.converged());
  // The pair, read from the trail: the N solve's attempts, then the 2N solve's, whose kept one is
  // the only one kept.
  int kept = 0;
  bool coarse_converged_before = false;
  for (const Attempt& a : four.attempts) {
    EXPECT_NE(a.stage, AttemptStage::Solve) << attemptStageName(a.stage);
    if (a.kept) {
      ++kept;
      EXPECT_EQ(a.stage, AttemptStage::FourthOrderFine);
      EXPECT_EQ(a.steps, 64);
      EXPECT_EQ(a.termination, Termination::Converged);
      EXPECT_TRUE(coarse_converged_before);
    } else if (a.steps == 32 && a.termination == Termination::Converged) {
      coarse_converged_before = true;
    }
  }
  EXPECT_EQ(kept, 1) << four.message();
  for (int k = 0; k <= 32; ++k) {
    const Vector3 tau = fine.maneuver.torque[2 * k] +
                        (fine.maneuver.torque[2 * k] - coarse.maneuver.torque[k]) / 3.0;
    EXPECT_LE((four.maneuver.torque[k] - tau).norm(), 1e-9 * maxTorque(four.maneuver)) << k;
    const Matrix3& R2 = fine.maneuver.attitude[2 * k];
    const Matrix3 R =
        R2 *
        so3::exp(Vector3(so3::log(Matrix3(coarse.maneuver.attitude[k].transpose() * R2)) / 3.0));
    EXPECT_LE(so3::angleBetween(R, four.maneuver.attitude[k]), 1e-10) << k;
  }
  EXPECT_NEAR(four.effort,
              p.duration / 32 * schemeCost(SchemeKind::FourthOrder, four.maneuver.torque),
              1e-14 * four.effort);
}

// Gregory's end-corrected trapezoidal rule is exact for cubics (N ≥ 3) and sums to N.
TEST(FourthOrder, EffortWeightsIntegrateCubicsExactly) {
  for (int N : {3, 4, 5, 8, 33}) {
    double sum = 0, cubic = 0;
    for (int k = 0; k <= N; ++k) {
      const double w = schemeTorqueWeight(SchemeKind::FourthOrder, k, N);
      const double x = double(k) / N;
      sum += w;
      cubic += w * (1 + x - 2 * x * x + 5 * x * x * x) / N;
    }
    EXPECT_NEAR(sum, N, 1e-13 * N);
    EXPECT_NEAR(cubic, 1 + 0.5 - 2.0 / 3 + 5.0 / 4, 1e-13) << N;
  }
}

// The cubic hold reproduces cubics exactly and interpolates the node torques.
TEST(FourthOrder, CubicHoldReproducesCubicsAndInterpolates) {
  const int N = 7;
  const double h = 0.3;
  const auto f = [](double t) { return Vector3(1 - t + 2 * t * t * t, 3 * t * t, -0.5 + 4 * t); };
  std::vector<Vector3> torque;
  for (int k = 0; k <= N; ++k) torque.push_back(f(k * h));
  for (int k = 0; k < N; ++k) {
    const std::array<Vector3, 4> c = cubicHoldCoefficients(torque, k, h);
    for (double s : {0.0, 0.1, 0.2, h}) {
      const Vector3 value = c[0] + s * (c[1] + s * (c[2] + s * c[3]));
      EXPECT_LE((value - f(k * h + s)).norm(), 1e-12) << k << " " << s;
    }
  }
  EXPECT_THROW(cubicHoldCoefficients(std::vector<Vector3>(3, Vector3::Zero()), 0, h), InvalidInput);
}

// replayPlan's order-4 hold and integrator: the fourth_order plan's torques replayed on the
// continuous body (cubic hold, RKMK4, one step per plan step) end O(h⁴) from the target; the
// GBS replay of the same hold (accuracy.cpp) agrees to O(h⁴).
TEST(FourthOrder, ReplayWithCubicHoldAndRkmk4IsOrderFour) {
  for (bool slew_up : {false, true}) {
    PlanningProblem p = seedProblem(slew_up);
    std::vector<int> Ns;
    std::vector<double> miss, velocity_miss;
    for (int N = 32; N <= 256; N *= 2) {
      p.steps = N;
      const PlanResult plan = planManeuver(p);
      ASSERT_TRUE(plan.converged()) << plan.message();
      SimulationInput input;
      input.initial_attitude = p.initial_attitude;
      input.initial_velocity = p.initial_velocity;
      input.torque = plan.maneuver.torque;
      const Maneuver replay = replayPlan(SchemeKind::FourthOrder, p.inertia, p.duration / N, input);
      Ns.push_back(N);
      miss.push_back(so3::angleBetween(replay.attitude[N], p.final_attitude));
      velocity_miss.push_back((replay.angular_velocity[N] - p.final_velocity).norm());
      EXPECT_NEAR(plan.terminal_attitude_error, miss.back(), 1e-15);
      const ZeroOrderHoldReplay exact = replayZeroOrderHold(p, plan.maneuver);
      EXPECT_LE(so3::angleBetween(exact.attitude, replay.attitude[N]), 2 * miss.back() + 1e-12);
      std::printf("%s replay N=%d miss %.3e vmiss %.3e (cubic hold, exact: %.3e)\n",
                  slew_up ? "slew_up" : "rest_to_rest", N, miss.back(), velocity_miss.back(),
                  exact.attitude_miss);
    }
    EXPECT_GE(fittedOrder(Ns, miss), 3.5);
    EXPECT_GE(fittedOrder(Ns, velocity_miss), 3.5);
  }
}

// Nothing builds a DiscreteScheme or a step residual for fourth_order, and NLopt has no end
// torques: each refuses by name.
TEST(FourthOrder, RefusalsNameTheScheme) {
  try {
    DiscreteScheme scheme(SchemeKind::FourthOrder, Matrix3::Identity(), 0.1);
    ADD_FAILURE() << "no InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("'fourth_order' has no discrete equations of motion"),
              std::string::npos)
        << e.what();
  }
  PlanningProblem p = seedProblem(false);
  p.steps = 32;
  SolverOptions nlopt;
  nlopt.solver = SolverKind::Nlopt;
  EXPECT_THROW(planManeuver(p, nlopt), InvalidInput);
  const PlanResult plan = planManeuver(p);
  ASSERT_TRUE(plan.converged());
  EXPECT_THROW(measureStepResidual(p, plan.maneuver), InvalidInput);
  p.steps = kMaxSteps / 2 + 1;
  EXPECT_THROW(validateProblem(p), InvalidInput);
}

// A sub-solve that does not converge makes the whole result unconverged, with the reason.
TEST(FourthOrder, UnconvergedSubSolveIsReported) {
  PlanningProblem p = seedProblem(true);
  p.steps = 256;
  SolverOptions options;
  options.max_iterations = 1;
  const PlanResult r = planManeuver(p, options);
  EXPECT_FALSE(r.converged());
  EXPECT_NE(r.message().find("fourth_order (Richardson extrapolation of second_order at N = 256"),
            std::string::npos)
      << r.message();
  EXPECT_NE(r.message().find("did not converge"), std::string::npos) << r.message();
}

TEST(FourthOrder, SceneKeyAndAutoChoice) {
  const Scene scene = parseScene(
      "inertia: [1, 2, 3]\nduration: 10\nsteps: 32\nscheme: fourth_order\n"
      "initial: {attitude: {axis: [1, 0, 0], angle: 0.0}, angular_velocity: [0, 0, 0]}\n"
      "final: {attitude: {axis: [0, 0, 1], angle: 1.0}, angular_velocity: [0, 0, 0]}\n");
  EXPECT_EQ(scene.problem.scheme, SchemeKind::FourthOrder);
  EXPECT_EQ(parseScheme("fourth_order", "scheme"), SchemeKind::FourthOrder);
  EXPECT_EQ(schemeName(SchemeKind::FourthOrder), "fourth_order");
  EXPECT_EQ(naturalHold(SchemeKind::FourthOrder), TorqueHold::PiecewiseCubic);
  // auto with a tight miss target: all four schemes are tried, and the order-4 one needs the
  // least work.
  PlanningProblem p = seedProblem(false);
  p.accuracy.measure = AccuracyMeasure::TerminalMiss;
  p.accuracy.value = 1e-8;
  p.accuracy.choose_scheme = true;
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_GE(r.accuracy.schemes_tried.size(), 4u);
  EXPECT_EQ(r.accuracy.schemes_tried[3], "fourth_order");
  EXPECT_EQ(r.scheme, SchemeKind::FourthOrder);
  EXPECT_LE(replayZeroOrderHold(
                [&] {
                  PlanningProblem at = p;
                  at.scheme = r.scheme;
                  at.steps = r.maneuver.steps();
                  return at;
                }(),
                r.maneuver)
                .attitude_miss,
            1e-8);
}

// With node constraints both second_order solves go through the interior point (exact Hessians,
// the same band): the extrapolated plan meets the bounds, reports them, and its effort is closer
// to the converged one than second_order's at the same N (no order is claimed with active
// constraints: docs/design/fourth_order.md).
TEST(FourthOrder, ConstrainedScenesPlanThroughTheInteriorPoint) {
  struct Case {
    const char* scene;
    double converged_effort;  // second_order at N = 8192 (docs/design/second_order.md)
  };
  for (const Case& c : {Case{"sun_keep_out", 0.0959376}, Case{"torque_limited", 0.8299004},
                        Case{"rate_limited", 0.9637895}}) {
    PlanningProblem p =
        loadScene(std::string(AP_SOURCE_DIR) + "/scenes/" + c.scene + ".yaml").problem;
    p.steps = 64;
    p.scheme = SchemeKind::FourthOrder;
    const PlanResult four = planManeuver(p);
    ASSERT_TRUE(four.converged()) << c.scene << ": " << four.message();
    EXPECT_EQ(four.scheme, SchemeKind::FourthOrder);
    EXPECT_FALSE(four.constraints.empty()) << c.scene;
    EXPECT_LE(four.max_constraint_violation, 1e-8) << c.scene;
    if (p.hasTorqueBounds()) {  // the switching function, combined like the torques
      EXPECT_EQ(four.switching_function.size(), 65u) << c.scene;
    }
    p.scheme = SchemeKind::SecondOrder;
    const PlanResult second = planManeuver(p);
    ASSERT_TRUE(second.converged()) << c.scene << ": " << second.message();
    EXPECT_LT(std::abs(four.effort - c.converged_effort),
              0.3 * std::abs(second.effort - c.converged_effort))
        << c.scene << ": fourth_order " << four.effort << ", second_order " << second.effort;
  }
}

// Minimum time searches the duration over fourth_order minimum-effort solves: the sphere's T* =
// 2√10 s (eigenaxis bang–bang) closer than second_order's at the same N.
TEST(FourthOrder, MinimumTimeOnTheSphere) {
  PlanningProblem p =
      loadScene(std::string(AP_SOURCE_DIR) + "/scenes/min_time_sphere.yaml").problem;
  p.steps = 32;
  p.scheme = SchemeKind::FourthOrder;
  const PlanResult four = planManeuver(p);
  ASSERT_TRUE(four.converged()) << four.message();
  p.scheme = SchemeKind::SecondOrder;
  const PlanResult second = planManeuver(p);
  ASSERT_TRUE(second.converged()) << second.message();
  const double exact = 2 * std::sqrt(10.0);
  EXPECT_NEAR(four.minimum_duration, exact, 1e-3 * exact);
  EXPECT_LT(std::abs(four.minimum_duration - exact), std::abs(second.minimum_duration - exact));
}
