// Between nodes: how far a constraint met at the nodes can be violated by the motion between two
// nodes, R_k exp(s ω_k^), s ∈ [0, 1] (docs/notes/constraints_notes.md "Between nodes"), checked by
// sampling that motion; and the cone `margin`, which keeps the continuous motion within the
// stated limit where the unmargined plan leaves it.
#include <gtest/gtest.h>

#include <random>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "scene_errors.hpp"

namespace ap = attitude_planner;
using ap::Matrix3;
using ap::Vector3;

namespace {

constexpr int kSamples = 400;  // per step

/// The smallest cone margin [rad] over `kSamples` + 1 points of step R_k → R_next, by brute force.
double sampledMarginOverStep(const ap::PlanningConstraint& cone, const Matrix3& R_k,
                             const Matrix3& R_next) {
  const Vector3 omega = ap::so3::log(Matrix3(R_k.transpose() * R_next));
  double worst = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kSamples; ++i) {
    const double s = double(i) / kSamples;
    worst = std::min(worst, ap::coneMargin(cone, R_k * ap::so3::exp(Vector3(s * omega))));
  }
  return worst;
}

/// What a keep_out cone's angle can lose within a step of angle φ whose end nodes meet it:
/// a − acos(cos a + φ²/8) (the pointing cosine exceeds its chord by at most φ²/8).
double keepOutDipBound(double half_angle, double phi) {
  return half_angle - std::acos(std::min(1.0, std::cos(half_angle) + phi * phi / 8.0));
}

Vector3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vector3(normal(rng), normal(rng), normal(rng)).normalized();
}

struct Sampled {
  double worst_margin = std::numeric_limits<double>::infinity();  // over all steps and samples
  double largest_step = 0.0;                                      // max |ω_k| [rad]
};

Sampled sampleCone(const ap::PlanningConstraint& cone, const ap::Maneuver& m) {
  Sampled out;
  for (int k = 0; k < m.steps(); ++k) {
    out.worst_margin =
        std::min(out.worst_margin, sampledMarginOverStep(cone, m.attitude[k], m.attitude[k + 1]));
    const Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
    out.largest_step = std::max(out.largest_step, ap::so3::log(F).norm());
  }
  return out;
}

/// scenes/sun_keep_out.yaml at N = 16 (h = 3.75 s): coarse enough that the dip matters.
ap::PlanningProblem coarseSunKeepOut() {
  ap::PlanningProblem p = ap::loadScene(AP_SOURCE_DIR "/scenes/sun_keep_out.yaml").problem;
  p.steps = 16;
  return p;
}

}  // namespace

TEST(BetweenNodes, PointingCosineStaysWithinItsChordPlusStepSquaredOverEight) {
  // The bound behind the margin, at random steps up to 1 rad and random cones: the cosine
  // p(s) = sᵀR_k exp(s ω^) b exceeds the chord (1 − s) p(0) + s p(1) by at most |ω|²/8; and the
  // closed-form coneMarginOverStep equals the sampled minimum (never above it).
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  double tightest = 0.0;  // largest observed excess / bound
  for (int trial = 0; trial < 300; ++trial) {
    const Matrix3 R = ap::so3::exp(Vector3(3.0 * randomUnit(rng) * uniform(rng)));
    const Vector3 omega = randomUnit(rng) * (0.01 + uniform(rng));
    const ap::PlanningConstraint cone =
        trial % 2 ? ap::PlanningConstraint::keepOut(randomUnit(rng), randomUnit(rng), 0.5)
                  : ap::PlanningConstraint::keepIn(randomUnit(rng), randomUnit(rng), 1.5);
    const auto cosine = [&](double s) {
      return cone.world_direction.dot(R * ap::so3::exp(Vector3(s * omega)) * cone.body_axis);
    };
    const double bound = omega.squaredNorm() / 8.0;
    double excess = 0.0;
    for (int i = 0; i <= kSamples; ++i) {
      const double s = double(i) / kSamples;
      const double chord = (1 - s) * cosine(0.0) + s * cosine(1.0);
      excess = std::max(excess, std::abs(cosine(s) - chord));
    }
    EXPECT_LE(excess, bound * (1 + 1e-12)) << "trial " << trial;
    tightest = std::max(tightest, excess / bound);
    const Matrix3 R_next = R * ap::so3::exp(omega);
    const double exact = ap::coneMarginOverStep(cone, R, R_next);
    const double sampled = sampledMarginOverStep(cone, R, R_next);
    EXPECT_LE(exact, sampled + 1e-12) << "trial " << trial;
    EXPECT_GE(exact, sampled - 1e-4) << "trial " << trial;  // sampling resolution
  }
  // Not vacuous: some random step comes close to the bound (|p''| = |ω|² sin β |…| ≤ |ω|²).
  EXPECT_GT(tightest, 0.5);
  std::printf("largest |p - chord| / (|w|^2/8) over 300 random steps: %.3f\n", tightest);
}

TEST(BetweenNodes, RequiredMarginClosesTheDipBound) {
  // m = requiredConeMargin(φ) is exactly what keeps cos(a + m) + φ²/8 = cos a (keep_out) and
  // cos(a − m) − φ²/8 = cos a (keep_in); no margin exists where the offset leaves [−1, 1].
  for (double a : {0.1, 0.5, 1.5, 2.5}) {
    for (double phi : {0.01, 0.1, 0.4}) {
      const auto out = ap::PlanningConstraint::keepOut(Vector3::UnitX(), Vector3::UnitY(), a);
      const auto in = ap::PlanningConstraint::keepIn(Vector3::UnitX(), Vector3::UnitY(), a);
      const double m_out = ap::requiredConeMargin(out, phi);
      const double m_in = ap::requiredConeMargin(in, phi);
      if (std::isinf(m_in)) {  // a narrow keep_in cone that a step this long can cross
        EXPECT_GT(std::cos(a) + phi * phi / 8, 1.0) << a << " " << phi;
        continue;
      }
      EXPECT_NEAR(std::cos(a + m_out) + phi * phi / 8, std::cos(a), 1e-13) << a << " " << phi;
      EXPECT_NEAR(std::cos(a - m_in) - phi * phi / 8, std::cos(a), 1e-13) << a << " " << phi;
      EXPECT_GT(m_out, 0.0);
      EXPECT_GT(m_in, 0.0);
      EXPECT_NEAR(keepOutDipBound(a, phi), m_in, 1e-15);  // the same arc, mirrored
    }
  }
  const auto narrow = ap::PlanningConstraint::keepIn(Vector3::UnitX(), Vector3::UnitY(), 0.1);
  EXPECT_TRUE(std::isinf(ap::requiredConeMargin(narrow, 0.4)));
}

TEST(BetweenNodes, PlannedSunKeepOutDipsBetweenNodesWithinTheBound) {
  // At N = 16 the plan meets the cone at every node, the sampled motion between nodes enters it
  // (a scene where the margin matters), by no more than the bound of each step, and the result's
  // max_violation_between_nodes is what the sampling finds.
  const ap::PlanningProblem p = coarseSunKeepOut();
  const ap::PlanResult r = ap::planManeuver(p, ap::SolverOptions());
  ASSERT_TRUE(r.converged()) << r.message();
  const ap::PlanningConstraint& cone = p.constraints[0];
  EXPECT_LE(r.max_constraint_violation, 1e-9);
  double worst = std::numeric_limits<double>::infinity();
  double tightest = 0.0;  // largest (dip below the lower end) / bound over the steps
  for (int k = 0; k < p.steps; ++k) {
    const Matrix3& A = r.maneuver.attitude[k];
    const Matrix3& B = r.maneuver.attitude[k + 1];
    const double ends = std::min(ap::coneMargin(cone, A), ap::coneMargin(cone, B));
    ASSERT_GE(ends, -1e-9) << "node constraint violated at k = " << k;
    const double phi = ap::so3::log(Matrix3(A.transpose() * B)).norm();
    const double sampled = sampledMarginOverStep(cone, A, B);
    EXPECT_GE(sampled, -keepOutDipBound(cone.half_angle, phi) - 1e-9) << "k = " << k;
    worst = std::min(worst, sampled);
    tightest = std::max(tightest, (ends - sampled) / keepOutDipBound(cone.half_angle, phi));
  }
  EXPECT_LT(worst, -1e-4) << "the continuous motion never enters the cone: no test of the margin";
  EXPECT_NEAR(r.max_violation_between_nodes, -worst, 1e-6);
  std::printf(
      "N = 16 without margin: sampled worst margin between nodes %.3g rad; largest dip / bound "
      "%.2f\n",
      worst, tightest);
}

TEST(BetweenNodes, MarginKeepsTheContinuousMotionOutOfTheCone) {
  ap::PlanningProblem p = coarseSunKeepOut();
  const ap::PlanResult plain = ap::planManeuver(p, ap::SolverOptions());
  ASSERT_TRUE(plain.converged()) << plain.message();
  const Sampled before = sampleCone(p.constraints[0], plain.maneuver);
  ASSERT_LT(before.worst_margin, -1e-4);
  // The margin for steps 25 % longer than the plain plan's longest (the detour lengthens them).
  const double margin = ap::requiredConeMargin(p.constraints[0], 1.25 * before.largest_step);
  p.constraints[0].margin = margin;
  const ap::PlanResult r = ap::planManeuver(p, ap::SolverOptions());
  ASSERT_TRUE(r.converged()) << r.message();
  const Sampled after = sampleCone(p.constraints[0], r.maneuver);
  // The guarantee needs the margin to cover the margined plan's own steps: checked, not assumed.
  ASSERT_LE(ap::requiredConeMargin(p.constraints[0], after.largest_step), margin);
  EXPECT_GE(after.worst_margin, -1e-9);
  EXPECT_LE(r.max_violation_between_nodes, 1e-9);
  EXPECT_LE(r.max_constraint_violation, 1e-9);
  EXPECT_GT(r.active_constraints, 0);  // active at the tightened node bound
  EXPECT_GT(r.cost, plain.cost);
  std::printf("margin %.4g rad: sampled worst margin %.3g rad (without: %.3g), cost %.6g (%.6g)\n",
              margin, after.worst_margin, before.worst_margin, r.cost, plain.cost);
}

TEST(BetweenNodes, MarginIsParsedRoundTripsAndBadValuesAreNamed) {
  const std::string head = R"(inertia: [20, 25, 30]
duration: 60.0
steps: 16
initial: {attitude: {axis: [0, 0, 1], angle: 0.0}, angular_velocity: [0, 0, 0]}
final: {attitude: {axis: [0, 0, 1], angle: 1.5707963267948966}, angular_velocity: [0, 0, 0]}
constraints:
)";
  const ap::Scene s = ap::parseScene(
      head +
      "  - keep_out: {body_axis: [1, 0, 0], world_direction: [0, 0, 1], half_angle: 0.5, "
      "margin: 0.02}\n");
  ASSERT_EQ(s.problem.constraints.size(), 1u);
  EXPECT_EQ(s.problem.constraints[0].margin, 0.02);
  EXPECT_EQ(s.problem.constraints[0].nodeHalfAngle(), 0.52);
  EXPECT_EQ(ap::parseScene(ap::formatScene(s)).problem.constraints[0].margin, 0.02);
  EXPECT_NE(attitude_planner_test::sceneErrorOf(
                head + "  - keep_out: {body_axis: [1, 0, 0], world_direction: [0, 0, 1], "
                       "half_angle: 0.5, margin: -0.1}\n")
                .find("constraints[0].keep_out.margin: must be >= 0 rad and leave a cone "
                      "(half_angle + margin < pi), got -0.1"),
            std::string::npos);
  EXPECT_NE(attitude_planner_test::sceneErrorOf(
                head + "  - keep_in: {body_axis: [1, 0, 0], world_direction: [1, 0, 0], "
                       "half_angle: 0.5, margin: 0.5}\n")
                .find("constraints[0].keep_in.margin: must be >= 0 rad and leave a cone "
                      "(half_angle - margin > 0), got 0.5"),
            std::string::npos);
}
