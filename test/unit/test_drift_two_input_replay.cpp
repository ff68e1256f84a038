// Open-loop replay of sampled drift + two-input controls (seed 001): replayDriftTwoInputControls,
// what attitude_tracker_node integrates for a DriftTwoInputManeuver.
#include <gtest/gtest.h>

#include <cmath>

#include "attitude_planner/drift_two_input/system.hpp"
#include "attitude_planner/errors.hpp"

namespace ap = attitude_planner;

namespace {

/// p(0) of the worked example's extremal (docs/design/drift_two_input.md): g0 = I, T = 3 s, c = (1,
/// 2).
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

// Between samples (the tracker's stream at ~rate): the replay's own motion, exact at the samples.
TEST(DriftTwoInputReplay, BetweenSamplesTheReplayMovesOnItsOwnMotion) {
  const std::vector<double> t = {0.0, 0.5, 1.0, 1.5, 2.0};
  const std::vector<Eigen::Vector2d> u(5, Eigen::Vector2d(0.3, -0.7));
  const ap::Matrix3 g0 = ap::so3::fromAxisAngle(ap::Vector3(1, 2, 3), 0.4);
  const std::vector<ap::Matrix3> g = ap::replayDriftTwoInputControls(g0, t, u);
  for (double s : {0.0, 0.2, 0.5, 0.77, 1.49, 2.0}) {
    const ap::DriftTwoInputReplaySample at = ap::replayedDriftTwoInputAt(g, t, u, s);
    const ap::Matrix3 exact = g0 * ap::so3::exp(ap::Vector3(0.3, -0.7, 1.0) * s);
    EXPECT_LT(ap::so3::angleBetween(at.g, exact), 1e-14) << "s = " << s;
    EXPECT_LT((at.u - u[0]).norm(), 1e-15) << "s = " << s;
  }
  // At a sample: the replay's own row, bit for bit; varying controls interpolated by the cubic.
  ap::DriftTwoInputIntegration opts;
  opts.order = 4;
  opts.substeps = 100;  // the extremal's flow to round-off at both resolutions
  const ap::DriftTwoInputTrajectory tr = ap::integrateDriftTwoInputExtremal(
      ap::Matrix3::Identity(), kWorkedP0, 3.0, 60, kWeights, opts);
  const std::vector<ap::Matrix3> replayed = ap::replayDriftTwoInputControls(tr.g[0], tr.t, tr.u);
  EXPECT_EQ(ap::replayedDriftTwoInputAt(replayed, tr.t, tr.u, tr.t[17]).g, replayed[17]);
  const double mid = 0.5 * (tr.t[17] + tr.t[18]);
  const ap::DriftTwoInputReplaySample at = ap::replayedDriftTwoInputAt(replayed, tr.t, tr.u, mid);
  // The extremal itself at the midpoint (integrated at twice the resolution): close to the
  // replay's own error at N = 60 (a held or linear control would miss by ~1e-3).
  const ap::DriftTwoInputTrajectory fine = ap::integrateDriftTwoInputExtremal(
      ap::Matrix3::Identity(), kWorkedP0, 3.0, 120, kWeights, opts);
  EXPECT_LT(ap::so3::angleBetween(at.g, fine.g[35]), 1e-5);
  EXPECT_LT((at.u - fine.u[35]).norm(), 1e-4);
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
