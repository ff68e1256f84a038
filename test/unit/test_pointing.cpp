// The pointing end condition R_N b = d with the twist ψ about b free: the reference and twist
// conventions (planning/pointing.hpp), the twist's derivatives in the transcription
// (ReducedProblem::evaluateWithTwist) against central differences of the cost for every scheme,
// and the planned answer against a sweep of fixed-attitude solves over ψ refined by golden section.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/newton/least_raise.hpp"
#include "planning/newton/twist_newton.hpp"
#include "planning/strategies/starts.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "support/perturbed_problem.hpp"
#include "support/pointing_requests.hpp"

using namespace attitude_planner;

namespace {

constexpr SchemeKind kDiscretizations[] = {SchemeKind::Paper, SchemeKind::Variational,
                                           SchemeKind::SecondOrder};

Vector3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3(n(rng), n(rng), n(rng)).normalized();
}

EndCondition pointingAt(const Vector3& b, const Vector3& d) {
  EndCondition end;
  end.kind = EndConditionKind::Pointing;
  end.body_axis = b;
  end.world_direction = d;
  return end;
}

using test_support::randomPointingRequest;

TEST(PointingConventions, ReferenceTakesTheAxisToTheDirection) {
  std::mt19937 rng(3);
  for (int i = 0; i < 50; ++i) {
    const Vector3 b = randomUnit(rng), d = randomUnit(rng);
    EXPECT_LT((pointingReference(b, d) * b - d).norm(), 1e-14);
    EXPECT_LT((pointingReference(2.0 * b, 0.5 * d) * b - d).norm(), 1e-14);  // lengths free
    EXPECT_LT((pointingReference(b, -b) * b + b).norm(), 1e-14);             // b = −d
    EXPECT_LT((pointingReference(b, b) - Matrix3::Identity()).norm(), 1e-15);
  }
  // b = −d: a half turn about b × e_i, e_i along b's smallest component (here e_y).
  const Matrix3 R = pointingReference(Vector3(1, 0.1, 0.3), Vector3(-1, -0.1, -0.3));
  const Vector3 axis = Vector3(1, 0.1, 0.3).cross(Vector3::UnitY()).normalized();
  EXPECT_LT((R - so3::exp(Vector3(M_PI * axis))).norm(), 1e-14);
}

TEST(PointingConventions, TwistOfInvertsPointingAttitude) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-M_PI + 1e-9, M_PI);
  for (int i = 0; i < 50; ++i) {
    const EndCondition end = pointingAt(randomUnit(rng), randomUnit(rng));
    const double psi = u(rng);
    const Matrix3 R = pointingAttitude(end, psi);
    EXPECT_NEAR(twistOf(R, end), psi, 1e-13);
    EXPECT_LT(pointingError(R, end), 1e-14);
  }
}

// The summary every driver fills: ψ and the residual of the plan's own R_N, an R_N off the end
// condition by a tilt about an axis perpendicular to b reported as that tilt, and the solver's
// fields left alone.
TEST(PointingConventions, AnInfeasibleAnswerSaysWhatItRestsOn) {
  PlanResult r;
  r.termination = Termination::Converged;
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::None);
  r.termination = Termination::Infeasible;  // a solver's own local verdict at its starts
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::LocalToStarts);
  r.verdict = verdicts::NoPointingStartConverged{8};
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::LocalToStarts);
  r.verdict = verdicts::LocallyInfeasible{10.0, 12.0, "minimum time", 0.0, "", false};
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::MinimumTimeOverTwist);
  r.verdict = verdicts::MinimumTimeFoundNone{Termination::NotConverged};
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::MinimumTimeOverTwist);
  r.duration_verdict.proven_infeasible = true;
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::Proven);
  r.termination = Termination::NotConverged;
  EXPECT_EQ(pointingInfeasibleBasis(r), PointingInfeasibleBasis::None);
}

TEST(PointingPlan, ARateLimitBelowTheAngleToTurnIsProvenInfeasibleOverEveryTwist) {
  // Rest to rest, |Omega| <= w: every R_N(psi) turns R_0 b onto d, so T >= angle / w (proven);
  // planned through planManeuver, the field says so.
  PlanningProblem p = randomPointingRequest(47, 32, false, SchemeKind::Paper);
  const Vector3 from = p.initial_attitude * p.end_condition.body_axis;
  const double angle = std::atan2(from.cross(p.end_condition.world_direction).norm(),
                                  from.dot(p.end_condition.world_direction));
  p.constraints.push_back(PlanningConstraint::maxAngularRate(0.5 * angle / p.duration));
  const PlanResult r = planManeuver(p);
  EXPECT_EQ(r.termination, Termination::Infeasible) << r.message();
  EXPECT_EQ(r.pointing.infeasible_basis, PointingInfeasibleBasis::Proven) << r.message();
}

TEST(PointingConventions, SummaryOfAnEndReportsItsTwistAndResidual) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-M_PI + 1e-9, M_PI), tilt(1e-6, 0.5);
  for (int i = 0; i < 20; ++i) {
    const EndCondition end = pointingAt(randomUnit(rng), randomUnit(rng));
    const double psi = u(rng), angle = tilt(rng);
    PointingSummary s;
    s.twist_gradient = 0.25;
    s.twist_stationarity = 0.5;
    s.starts = 3;
    summarizePointingEnd(pointingAttitude(end, psi), end, &s);
    EXPECT_TRUE(s.active);
    EXPECT_NEAR(s.final_twist, psi, 1e-13);
    EXPECT_LT(s.error, 1e-14);
    EXPECT_EQ(s.twist_gradient, 0.25);
    EXPECT_EQ(s.twist_stationarity, 0.5);
    EXPECT_EQ(s.starts, 3);
    // Tilted in the world about an axis perpendicular to d: R b leaves d by exactly that angle.
    const Vector3 d = end.world_direction.normalized();
    const Vector3 across = d.cross(randomUnit(rng)).normalized();
    summarizePointingEnd(so3::exp(Vector3(angle * across)) * pointingAttitude(end, psi), end, &s);
    EXPECT_NEAR(s.error, angle, 1e-12);
  }
}

TEST(PointingConventions, NearestTwistHasTheLeastRotationAngle) {
  std::mt19937 rng(5);
  for (int i = 0; i < 20; ++i) {
    const EndCondition end = pointingAt(randomUnit(rng), randomUnit(rng));
    const Matrix3 from = so3::exp(Vector3(2.0 * randomUnit(rng)));
    const auto angle = [&](double psi) {
      return so3::log(Matrix3(from.transpose() * pointingAttitude(end, psi))).norm();
    };
    const double best = angle(nearestTwist(from, end));
    for (int k = 0; k < 720; ++k) EXPECT_LE(best, angle(2.0 * M_PI * k / 720) + 1e-12);
  }
}

/// C at the free attitudes of `rp` (δ = 0) with R_N moved by exp(Δψ b^): a problem built anew for
/// the rotated end and given the same free attitudes, its cost from the torques themselves (not
/// from the stencils or the retraction the derivatives use).
double costAtTwist(const PlanningProblem& problem, const ReducedProblem& rp, double dpsi) {
  PlanningProblem moved = problem;
  moved.final_attitude = problem.final_attitude *
                         so3::exp(Vector3(dpsi * problem.end_condition.body_axis.normalized()));
  ReducedProblem q(moved);
  q.setInteriorFromAttitudes(rp.attitudes(rp.current()));
  return q.cost(q.current());
}

TEST(TwistUnknown, DerivativesMatchCentralDifferencesForEveryScheme) {
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    PlanningProblem p = randomPointingRequest(11, 24, true, scheme);
    p.final_attitude = pointingAttitude(p.end_condition, 0.7);
    const ReducedProblem rp = test_support::perturbedReducedProblem(p, 12);
    const int n = rp.unknowns();
    Eigen::VectorXd g, border;
    BandedSymmetricMatrix band(n, ReducedProblem::kHalfBandwidth);
    double corner = 0.0, scale = 0.0;
    const double C = rp.evaluateWithTwist(&g, &band, &border, &corner, &scale);
    EXPECT_DOUBLE_EQ(C, rp.cost(rp.current()));
    const double e = 1e-4;
    const double cp = costAtTwist(p, rp, e), cm = costAtTwist(p, rp, -e);
    EXPECT_NEAR(g(n), (cp - cm) / (2 * e), 1e-6 * (std::abs(g(n)) + C));
    EXPECT_NEAR(corner, (cp - 2 * C + cm) / (e * e), 1e-4 * (std::abs(corner) + C));
    // The border: ∂/∂ψ of the node gradient, by central differences of evaluate() at ±Δψ.
    Eigen::VectorXd gp, gm, unused_border;
    double unused_corner, unused_scale;
    const auto movedBy = [&](double dpsi) {
      ReducedProblem q = rp;
      q.setCurrentWithTwist(q.retractWithTwist(Eigen::VectorXd::Zero(n), dpsi, 1.0), dpsi);
      return q;
    };
    movedBy(e).evaluateWithTwist(&gp, nullptr, &unused_border, &unused_corner, &unused_scale);
    movedBy(-e).evaluateWithTwist(&gm, nullptr, &unused_border, &unused_corner, &unused_scale);
    const Eigen::VectorXd fd = (gp - gm).head(n) / (2 * e);
    EXPECT_LT((fd - border).cwiseAbs().maxCoeff(), 1e-5 * (border.cwiseAbs().maxCoeff() + 1.0));
    // A mixed direction (v, s): the second derivative of C along the retraction is the bordered
    // Hessian's quadratic form (the motion is linear in the coordinates: no curvature term).
    std::mt19937 rng(13);
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v(i) = normal(rng);
    const double s = 0.8;
    const auto along = [&](double t) { return rp.cost(rp.retractWithTwist(v, s, t)); };
    const double quadratic = v.dot(band.toDense() * v) + 2 * s * border.dot(v) + s * s * corner;
    EXPECT_NEAR(quadratic, (along(e) - 2 * C + along(-e)) / (e * e), 1e-4 * (quadratic + C));
    const double slope = g.head(n).dot(v) + s * g(n);
    EXPECT_NEAR(slope, (along(e) - along(-e)) / (2 * e), 1e-6 * (std::abs(slope) + C));
  }
}

TEST(TwistUnknown, FixedEndProblemHasNoTwist) {
  PlanningProblem p = randomPointingRequest(21, 16, false, SchemeKind::Paper);
  p.end_condition = EndCondition();
  const ReducedProblem rp(p);
  EXPECT_FALSE(rp.hasTwist());
  EXPECT_EQ(rp.twistMotion(p.steps), Vector3::Zero());
}

/// The twist Newton on `p` from the Hermite curve at ψ = 0 (R_N posed there), watched by `watch`.
TwistSolve twistNewtonFromHermite(const PlanningProblem& p, const TwistWatch* watch) {
  PlanningProblem at = p;
  at.final_attitude = pointingAttitude(p.end_condition, 0.0);
  ReducedProblem np(at);
  startOnHermiteCurve(at, &np);
  SolveContext context{SolverOptions()};
  return solveTwistNewton(np, 0.0, context, 1e-10, 200, NewtonParameters{}, nullptr, watch);
}

TEST(TwistUnknown, AWatchSeesTheModelsMinimumAndEndsTheSolveWhereItSaysSo) {
  for (unsigned seed : {111u, 112u, 113u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanningProblem p = randomPointingRequest(seed, 16, seed % 2 == 0, SchemeKind::Paper);
    const TwistSolve plain = twistNewtonFromHermite(p, nullptr);
    ASSERT_EQ(plain.termination, Termination::Converged) << plain.reason;
    // A watch that never stops changes nothing; the model's minimum it is shown converges to the
    // answer (cost and ψ) as the decrement falls.
    double last_gap = INFINITY;
    const TwistWatch silent = [&](double cost, double twist, double decrement) {
      if (decrement < 1e-3) {
        last_gap = std::max(std::abs(cost - plain.cost) / plain.cost,
                            std::abs(std::remainder(twist - plain.twist, 2.0 * M_PI)));
      }
      return std::string();
    };
    const TwistSolve watched = twistNewtonFromHermite(p, &silent);
    EXPECT_EQ(watched.termination, Termination::Converged);
    EXPECT_EQ(watched.iterations, plain.iterations);
    EXPECT_EQ(watched.cost, plain.cost);
    EXPECT_LT(last_gap, 1e-5);
    // A watch that stops when first asked (at the first unshifted step) ends the solve there, not
    // converged, with its reason.
    const TwistWatch stop = [](double, double, double) { return std::string("stopped"); };
    const TwistSolve stopped = twistNewtonFromHermite(p, &stop);
    EXPECT_EQ(stopped.termination, Termination::NotConverged);
    EXPECT_EQ(stopped.reason, "stopped");
    EXPECT_LT(stopped.iterations, plain.iterations);
  }
}

TEST(TwistUnknown, TheLeastDefiniteShiftIsTheOneByOneScansWithFewerFactorizations) {
  // Success from a least raise on (definiteness above the least definite shift): the search ends
  // where a scan 0, 1, 2, … does, or reports none within `most`, from any guess, in tests
  // logarithmic in the guess's distance (3 where the guess is the least raise: 0 is tried first).
  const auto log2Of = [](int n) { return static_cast<int>(std::floor(std::log2(n + 1.0))); };
  for (int most = 0; most <= 48; ++most) {
    for (int least = 0; least <= most + 1; ++least) {
      for (int guess = 0; guess <= most; ++guess) {
        SCOPED_TRACE("most " + std::to_string(most) + ", least " + std::to_string(least) +
                     ", guess " + std::to_string(guess));
        int tests = 0;
        const int found = leastSucceedingRaise(
            most,
            [&](int r) {
              ++tests;
              return r >= least;
            },
            guess);
        ASSERT_EQ(found, least <= most ? least : -1);
        ASSERT_LE(tests, 2 * log2Of(std::abs(least - std::max(guess, 1))) + 4);
        if (guess <= 1 && least >= 8 && least <= most) ASSERT_LT(tests, least + 1);  // the scan's
        if (guess == least && least > 1) ASSERT_EQ(tests, 3);  // 0, the guess, one below it
        if (least == 0) ASSERT_EQ(tests, 1);
      }
    }
  }
}

TEST(PointingPlan, AtMostTheSweepsBestTwistOnSeededRandomRequests) {
  for (unsigned seed : {101u, 102u, 103u, 104u}) {
    const bool spinning = seed % 2 == 0;
    const PlanningProblem p = randomPointingRequest(seed, 32, spinning, SchemeKind::Paper);
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    ASSERT_TRUE(r.pointing.active);
    const test_support::TwistSweep sweep = test_support::sweepTwist(p);
    EXPECT_LE(r.cost, sweep.best * (1.0 + 1e-6)) << "swept best at twist " << sweep.best_twist;
    EXPECT_LT(r.pointing.error, 1e-12);
    EXPECT_LT(pointingError(r.maneuver.attitude.back(), p.end_condition), 1e-12);
    EXPECT_LT(r.pointing.twist_stationarity, 1e-8);
    EXPECT_NEAR(twistOf(r.maneuver.attitude.back(), p.end_condition), r.pointing.final_twist, 1e-9);
    EXPECT_EQ(r.pointing.starts, 8);
    EXPECT_GE(r.attempts.size(), 8u);
    EXPECT_TRUE(std::isfinite(r.attempts.front().start_detail.twist));
  }
}

TEST(PointingPlan, EverySchemeMeetsTheEndCondition) {
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    const PlanningProblem p = randomPointingRequest(31, 48, true, scheme);
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    EXPECT_LT(r.pointing.error, 1e-12);
    EXPECT_LT(r.pointing.twist_stationarity, 1e-8);
    const std::string json = planResultJson(p, r);
    EXPECT_NE(json.find("\"final_twist\": "), std::string::npos);
    EXPECT_NE(json.find("\"pointing\": {\"body_axis\""), std::string::npos);
  }
}

TEST(PointingPlan, WithoutConvergenceTheStartsOnTheRequestedGridAreTriedAndNamed) {
  // One iteration per start: no survey answer to refine, so the starts run on the requested grid
  // too; the answer is not converged, carries an iterate there and lists all 16 starts.
  const PlanningProblem p = randomPointingRequest(51, 64, false, SchemeKind::Paper);
  SolverOptions options;
  options.max_iterations = 1;
  const PlanResult r = planManeuver(p, options);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.maneuver.steps(), 64);
  ASSERT_EQ(r.attempts.size(), 16u);
  EXPECT_EQ(r.attempts.front().stage, AttemptStage::ClassSurvey);
  EXPECT_EQ(r.attempts.back().stage, AttemptStage::Solve);
  EXPECT_EQ(r.attempts.back().steps, 64);
}

TEST(PointingPlan, RequestsItCannotServeAreRefusedByName) {
  PlanningProblem p = randomPointingRequest(41, 32, false, SchemeKind::Paper);
  const auto refusal = [&](const PlanningProblem& q) {
    try {
      planManeuver(q);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("not refused");
  };
  PlanningProblem effected = p;
  auto effects = std::make_shared<EffectModel>();
  effects->add(std::make_unique<DisturbanceTorque>(Vector3(0.0, 0.0, 1e-3), TorqueFrame::Body));
  effected.effects = effects;
  EXPECT_NE(refusal(effected).find("final.pointing: not supported with effects"), std::string::npos)
      << refusal(effected);
  PlanningProblem fourth = p;
  fourth.scheme = SchemeKind::FourthOrder;
  EXPECT_NE(refusal(fourth).find("scheme fourth_order"), std::string::npos);
  PlanningProblem zero = p;
  zero.end_condition.world_direction = Vector3::Zero();
  EXPECT_NE(refusal(zero).find("final.pointing.world_direction"), std::string::npos);
}

const char* const kPointingScene = R"(
inertia: [2, 3, 4]
duration: 10
steps: 32
initial: {attitude: {axis: [1, 0, 0], angle: 0}, angular_velocity: [0, 0, 0]}
final: {pointing: {body_axis: [0, 0, 1], world_direction: [1, 0, 0]}, angular_velocity: [0, 0, 0]}
)";

TEST(PointingScene, ParsesFormatsAndRefusesBadKeys) {
  const Scene scene = parseScene(kPointingScene);
  EXPECT_TRUE(scene.problem.end_condition.pointing());
  EXPECT_EQ(scene.problem.end_condition.world_direction, Vector3(1, 0, 0));
  const Scene again = parseScene(formatScene(scene));
  EXPECT_TRUE(again.problem.end_condition.pointing());
  EXPECT_EQ(again.problem.end_condition.body_axis, Vector3(0, 0, 1));
  const auto error = [](const std::string& text) {
    try {
      parseScene(text);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  std::string both = kPointingScene;
  both.replace(both.find("final: {"), 8, "final: {attitude: {quaternion: [1, 0, 0, 0]}, ");
  EXPECT_NE(error(both).find("not both"), std::string::npos) << error(both);
  std::string zero = kPointingScene;
  zero.replace(zero.find("world_direction: [1, 0, 0]"), 26, "world_direction: [0, 0, 0]");
  EXPECT_NE(error(zero).find("final.pointing.world_direction"), std::string::npos) << error(zero);
  std::string neither = kPointingScene;
  neither.replace(neither.find("pointing: {body_axis: [0, 0, 1], world_direction: [1, 0, 0]}, "),
                  62, "");
  EXPECT_NE(error(neither).find("final.pointing"), std::string::npos) << error(neither);
}

TEST(PointingScene, ExampleSceneAimsTheBoresight) {
  const Scene scene = loadScene(AP_SOURCE_DIR "/scenes/point_boresight.yaml");
  const PlanResult r = planManeuver(scene.problem);
  ASSERT_TRUE(r.converged()) << r.message();
  const Vector3 aimed = r.maneuver.attitude.back() * Vector3::UnitZ();
  EXPECT_LT((aimed - Vector3(1, 1, 0).normalized()).norm(), 1e-12);
  EXPECT_NEAR(r.pointing.final_twist,
              twistOf(r.maneuver.attitude.back(), scene.problem.end_condition), 1e-9);
}

}  // namespace
