// Extremal flow of the drift + two-input system (seed 001): conservation of the Casimir and the
// Hamiltonian by the implicit midpoint rule, g on SO(3), convergence order, and the sign of the
// Lie–Poisson equations (3.15)–(3.17) through the conserved spatial costate g p.
#include <gtest/gtest.h>

#include <cmath>

#include "attitude_planner/drift_two_input/system.hpp"
#include "attitude_planner/errors.hpp"

using namespace attitude_planner;
namespace dti = attitude_planner::drift_two_input;

TEST(DriftTwoInputFlow, VectorFieldIsSeedEquations315To317) {
  const DriftTwoInputWeights w{2.0, 0.5};
  const Vector3 p(0.3, -1.1, 0.7);
  const Vector3 f = dti::costateRate<double>(p, w);
  // printed (3.15)–(3.17), verified correct (see docs/design/drift_two_input.md)
  EXPECT_NEAR(f.x(), -p.y() * p.z() / w.c2 + p.y(), 1e-15);
  EXPECT_NEAR(f.y(), p.x() * p.z() / w.c1 - p.x(), 1e-15);
  EXPECT_NEAR(f.z(), (1 / w.c2 - 1 / w.c1) * p.x() * p.y(), 1e-15);
}

TEST(DriftTwoInputFlow, CasimirAndHamiltonianConservedOverLongRuns) {
  const DriftTwoInputWeights w{3.0, 1.0};
  const Vector3 p0(1.3, -0.8, 0.6);
  const double C0 = dti::casimir(p0), H0 = dti::hamiltonian(p0, w);
  // 1e5 steps of h = 0.01 s (T = 1000 s, many periods of the p-motion)
  const auto traj = integrateDriftTwoInputExtremal(Matrix3::Identity(), p0, 1000.0, 100000, w);
  double dC = 0.0, dH = 0.0, orth = 0.0;
  for (size_t k = 0; k < traj.p.size(); ++k) {
    dC = std::max(dC, std::abs(dti::casimir(traj.p[k]) - C0) / C0);
    dH = std::max(dH, std::abs(dti::hamiltonian(traj.p[k], w) - H0) / std::abs(H0));
    orth = std::max(orth, so3::orthogonalityError(traj.g[k]));
  }
  RecordProperty("max_rel_casimir_error", std::to_string(dC));
  RecordProperty("max_rel_hamiltonian_error", std::to_string(dH));
  RecordProperty("max_orthogonality_error", std::to_string(orth));
  std::printf("1e5 steps: max rel |dC| = %.3g, max rel |dH| = %.3g, max orth err = %.3g\n", dC, dH,
              orth);
  EXPECT_LE(dC, 1e-12);
  EXPECT_LE(dH, 1e-12);
  EXPECT_LE(orth, 1e-12);
  // the motion is not trivial: p really moves around its orbit
  double spread = 0.0;
  for (const auto& p : traj.p) spread = std::max(spread, (p - p0).norm());
  EXPECT_GT(spread, 0.5);
}

TEST(DriftTwoInputFlow, SpatialCostateIsConservedWhichFixesTheSignOfTheLiePoissonEquations) {
  // First-order optimality of the fixed-endpoint problem requires μ = g p to be constant
  // (docs/design/drift_two_input.md): with the opposite sign, ṗ = −p × ∇H, μ would rotate.
  const DriftTwoInputWeights w{0.7, 1.9};
  const Vector3 p0(0.9, 0.4, -1.2);
  const Matrix3 g0 = so3::exp(Vector3(0.2, -0.4, 1.0));
  DriftTwoInputIntegration opts;
  opts.substeps = 20;
  opts.order = 4;
  const auto traj = integrateDriftTwoInputExtremal(g0, p0, 5.0, 200, w, opts);
  const Vector3 mu0 = g0 * p0;
  double drift = 0.0;
  for (size_t k = 0; k < traj.p.size(); ++k)
    drift = std::max(drift, (traj.g[k] * traj.p[k] - mu0).norm());
  EXPECT_LE(drift, 1e-9);
  // the wrong sign (time-reversed p with forward g) does not conserve it
  Matrix3 g = g0;
  Vector3 p = p0;
  double wrong = 0.0;
  for (int k = 0; k < 4000; ++k) {
    // explicit midpoint rule for ṗ = −p × ∇H: accurate enough to show μ drifting
    const Vector3 m = p - 0.5 * 1.25e-3 * dti::costateRate<double>(p, w);
    p = p - 1.25e-3 * dti::costateRate<double>(m, w);
    g = g * so3::exp(Vector3(1.25e-3 * dti::velocity<double>(m, w)));
    wrong = std::max(wrong, (g * p - mu0).norm());
  }
  EXPECT_GT(wrong, 0.1);
}

TEST(DriftTwoInputFlow, FourthOrderCompositionConvergesAtFourthOrder) {
  const DriftTwoInputWeights w{2.0, 0.8};
  const Vector3 p0(0.5, 1.0, -0.3);
  DriftTwoInputIntegration o4;
  o4.order = 4;
  auto endpoint = [&](int steps, const DriftTwoInputIntegration& o) {
    const auto tr = integrateDriftTwoInputExtremal(Matrix3::Identity(), p0, 4.0, steps, w, o);
    return std::make_pair(tr.p.back(), tr.g.back());
  };
  const auto ref = endpoint(4000, o4);
  auto err = [&](int steps, const DriftTwoInputIntegration& o) {
    const auto e = endpoint(steps, o);
    return (e.first - ref.first).norm() + so3::angleBetween(e.second, ref.second);
  };
  const double r2 = err(100, {}) / err(200, {});
  const double r4 = err(100, o4) / err(200, o4);
  EXPECT_NEAR(std::log2(r2), 2.0, 0.2);
  EXPECT_NEAR(std::log2(r4), 4.0, 0.3);
}

TEST(DriftTwoInputFlow, RejectsBadArguments) {
  EXPECT_THROW(
      integrateDriftTwoInputExtremal(Matrix3::Identity(), Vector3::Zero(), 1.0, 10, {0.0, 1.0}),
      InvalidInput);
  EXPECT_THROW(integrateDriftTwoInputExtremal(Matrix3::Identity(), Vector3::Zero(), -1.0, 10, {}),
               InvalidInput);
  EXPECT_THROW(integrateDriftTwoInputExtremal(Matrix3::Identity(), Vector3::Zero(), 1.0, 0, {}),
               InvalidInput);
}
