// Open-loop replay of sampled drift + two-input controls (seed 001): replayDriftTwoInputControls,
// what attitude_tracker_node integrates for a DriftTwoInputManeuver.
#include <gtest/gtest.h>

#include <cmath>

#include "attitude_planner/drift_two_input/system.hpp"
#include "attitude_planner/errors.hpp"

namespace ap = attitude_planner;

namespace {

/// p(0) of the worked example's extremal (docs/design/drift_two_input.md): g0 = I, T = 3 s, c = (1, 2).
const ap::Vector3 kWorkedP0(-1.606814211891, -0.932477257024, -1.274829991641);
const ap::DriftTwoInputWeights kWeights{1.0, 2.0};

/// Terminal replay error [rad] of the worked extremal sampled at N intervals.
double replayError(int N) {
  ap::DriftTwoInputIntegration opts;
  opts.order = 4;
  opts.substeps = std::max(1, 6000 / N);  // reference flow at h ≤ 0.0005 s
  const ap::DriftTwoInputTrajectory tr = ap::integrateDriftTwoInputExtremal(
      ap::Matrix3::Identity(), kWorkedP0, 3.0, N, kWeights, opts);
  const std::vector<ap::Matrix3> g = ap::replayDriftTwoInputControls(tr.g[0], tr.t, tr.u);
  return ap::so3::angleBetween(g.back(), tr.g.back());
}

}  // namespace

TEST(DriftTwoInputReplay, ConstantControlsGiveTheExactExponential) {
  const std::vector<double> t = {0.0, 0.5, 1.0, 1.5, 2.0};
  const std::vector<Eigen::Vector2d> u(5, Eigen::Vector2d(0.3, -0.7));
  const ap::Matrix3 g0 = ap::so3::fromAxisAngle(ap::Vector3(1, 2, 3), 0.4);
  const std::vector<ap::Matrix3> g = ap::replayDriftTwoInputControls(g0, t, u);
  ASSERT_EQ(g.size(), 5u);
  EXPECT_EQ(g[0], g0);
  for (int k = 0; k < 5; ++k) {
    const ap::Matrix3 exact = g0 * ap::so3::exp(ap::Vector3(0.3, -0.7, 1.0) * t[k]);
    EXPECT_LT(ap::so3::angleBetween(g[k], exact), 1e-14) << "k = " << k;
  }
}

TEST(DriftTwoInputReplay, SampledExtremalControlsReplayToFourthOrder) {
  const double e60 = replayError(60), e120 = replayError(120), e600 = replayError(600);
  RecordProperty("error_N60", std::to_string(e60));
  RecordProperty("error_N120", std::to_string(e120));
  RecordProperty("error_N600", std::to_string(e600));
  std::printf("replay terminal error: N = 60 %.3g rad, N = 120 %.3g rad, N = 600 %.3g rad\n", e60,
              e120, e600);
  EXPECT_GT(e60 / e120, 12.0);  // 2⁴ = 16 for a fourth-order replay
  EXPECT_LT(e600, 1e-9);        // the tracker rostest's drift scene uses N = 600
}

TEST(DriftTwoInputReplay, BadSamplesAreRefused) {
  const ap::Matrix3 I = ap::Matrix3::Identity();
  EXPECT_THROW(ap::replayDriftTwoInputControls(I, {0.0, 1.0}, {Eigen::Vector2d::Zero()}),
               ap::InvalidInput);
  EXPECT_THROW(ap::replayDriftTwoInputControls(I, {0.0, 0.0},
                                               {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()}),
               ap::InvalidInput);
  EXPECT_THROW(ap::replayDriftTwoInputControls(
                   I, {0.0, 1.0}, {Eigen::Vector2d::Zero(), Eigen::Vector2d(NAN, 0.0)}),
               ap::InvalidInput);
}
