// The interior point's KKT-system interface and its two inertia corrections
// (interior_point/kkt_system.hpp, inertia_correction.hpp) against dense Eigen solves of the same
// shifted matrices.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "planning/interior_point/inertia_correction.hpp"
#include "planning/interior_point/kkt_system.hpp"

namespace ap = attitude_planner;

namespace {

constexpr int kN = 30;

/// A random symmetric band (half bandwidth ReducedProblem::kHalfBandwidth) made diagonally
/// dominant, so positive definite, with `diagonal_offset` added to its first diagonal entry.
ap::KktBlocks<double> randomBlocks(int globals, double diagonal_offset, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ap::KktBlocks<double> k(kN);
  const int p = ap::ReducedProblem::kHalfBandwidth;
  for (int i = 0; i < kN; ++i) {
    for (int j = std::max(0, i - p); j < i; ++j) k.band.add(i, j, u(rng));
    k.band.add(i, i, 2.0 * p + 1.0 + u(rng));
  }
  k.band.add(0, 0, diagonal_offset);
  k.border = Eigen::MatrixXd::NullaryExpr(kN, globals, [&] { return 0.3 * u(rng); });
  k.corner = Eigen::MatrixXd::Identity(globals, globals) * 5.0;
  return k;
}

Eigen::MatrixXd dense(const ap::KktBlocks<double>& k) {
  const int m = k.globals();
  Eigen::MatrixXd K(kN + m, kN + m);
  K.topLeftCorner(kN, kN) = k.band.toDense();
  K.topRightCorner(kN, m) = k.border;
  K.bottomLeftCorner(m, kN) = k.border.transpose();
  K.bottomRightCorner(m, m) = k.corner;
  return K;
}

Eigen::VectorXd ones(int size) {
  return Eigen::VectorXd::LinSpaced(size, 1.0, 2.0);
}

}  // namespace

TEST(KktSystem, BandKktSolvesTheRowRelativeShiftedBand) {
  const ap::KktBlocks<double> k = randomBlocks(0, 0.0, 1);
  const double shift = 1e-3, row_floor = 0.5;
  ap::BandKkt<double> kkt;
  ASSERT_TRUE(kkt.factor(k, {shift, ap::Shift::Rule::RowRelative, row_floor}));
  Eigen::MatrixXd K = dense(k);
  for (int i = 0; i < kN; ++i) K(i, i) += shift * (std::abs(K(i, i)) + row_floor);
  Eigen::VectorXd x = ones(kN);
  kkt.solve(&x);
  EXPECT_LT((K * x - ones(kN)).lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_TRUE(kkt.inertia().band_positive_definite);
}

TEST(KktSystem, BorderedBandKktSolvesTheUniformlyShiftedSystem) {
  const ap::KktBlocks<double> k = randomBlocks(2, 0.0, 2);
  const double shift = 0.25;
  ap::BorderedBandKkt<double> kkt;
  ASSERT_TRUE(kkt.factor(k, {shift, ap::Shift::Rule::Uniform, 0.0}));
  const Eigen::MatrixXd K = dense(k) + shift * Eigen::MatrixXd::Identity(kN + 2, kN + 2);
  Eigen::VectorXd x = ones(kN + 2);
  kkt.solve(&x);
  EXPECT_LT((K * x - ones(kN + 2)).lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_EQ(kkt.inertia().positive, 2);
}

TEST(KktSystem, MakeKktPicksTheBandWithoutGlobalsAndTheBorderWithThem) {
  EXPECT_NE(dynamic_cast<ap::BandKkt<double>*>(ap::makeKkt<double>(0).get()), nullptr);
  EXPECT_NE(dynamic_cast<ap::BorderedBandKkt<double>*>(ap::makeKkt<double>(1).get()), nullptr);
  ap::BandKkt<double> band;
  EXPECT_THROW(band.factor(randomBlocks(1, 0.0, 3), {}), std::logic_error);
}

TEST(InertiaCorrection, RowRelativeShiftGrowsUntilAnIndefiniteBandFactors) {
  const ap::InteriorPointParameters p;
  // One diagonal entry far below zero: the band is indefinite until the shift outgrows it.
  const ap::KktBlocks<double> k = randomBlocks(0, -40.0, 4);
  ap::RowRelativeShift correction(p);
  ap::BandKkt<double> kkt;
  Eigen::VectorXd d;
  double shift = 0.0;
  ASSERT_TRUE(correction.factorAndSolve(kkt, k, ones(kN), &d, &shift, nullptr));
  // The schedule: 0, first_shift, then ×shift_growth.
  EXPECT_GT(shift, p.first_shift);
  const double steps = std::log(shift / p.first_shift) / std::log(p.shift_growth);
  EXPECT_NEAR(steps, std::round(steps), 1e-9);
  Eigen::MatrixXd K = dense(k);
  const double row_floor = p.shift_row_floor * k.band.maxAbsDiagonal();
  for (int i = 0; i < kN; ++i) K(i, i) += shift * (std::abs(K(i, i)) + row_floor);
  EXPECT_LT((K * d - ones(kN)).lpNorm<Eigen::Infinity>(), 1e-10);
}

TEST(InertiaCorrection, RowRelativeShiftFloorRisesPastItsCapOnceAndRelaxes) {
  const ap::InteriorPointParameters p;
  ap::RowRelativeShift correction(p);
  const ap::KktBlocks<double> definite = randomBlocks(0, 0.0, 5);
  ap::BandKkt<double> kkt;
  Eigen::VectorXd d;
  // A positive definite band factors at the floor itself: the shift used is the floor.
  const auto floor = [&] {
    double shift = -1.0;
    EXPECT_TRUE(correction.factorAndSolve(kkt, definite, ones(kN), &d, &shift, nullptr));
    return shift;
  };
  std::vector<double> floors;
  while (correction.raiseFloor()) floors.push_back(floor());
  // line_search_shift, then ×shift_growth while below max_shift_floor. With the defaults
  // 1e-8 × 100³ rounds to just below 1e-2, so one more raise takes the floor to about 1: the cap
  // says when the raises stop, not how large the floor gets.
  ASSERT_GE(floors.size(), 2u);
  EXPECT_EQ(floors.front(), p.line_search_shift);
  for (std::size_t i = 1; i < floors.size(); ++i) {
    EXPECT_EQ(floors[i], p.shift_growth * floors[i - 1]);
    EXPECT_LT(floors[i - 1], p.max_shift_floor);
  }
  EXPECT_GE(floors.back(), p.max_shift_floor);
  // ÷shift_growth per accepted step, and 0 once at or below line_search_shift.
  for (std::size_t i = 0; i <= floors.size(); ++i) correction.relax();
  EXPECT_EQ(floor(), 0.0);
}

TEST(InertiaCorrection, PerturbationHandlerRestoresTheInertiaAndADescentStep) {
  const ap::InteriorPointParameters p;
  // A corner far below BᵀA⁻¹B: the Schur complement is negative, K has the wrong inertia.
  ap::KktBlocks<double> k = randomBlocks(1, 0.0, 6);
  k.corner(0, 0) = -50.0;
  ap::PerturbationHandler handler(p);
  ap::BorderedBandKkt<double> kkt;
  const Eigen::VectorXd rhs = ones(kN + 1);
  Eigen::VectorXd d;
  ASSERT_TRUE(handler.factorAndSolve(kkt, k, rhs, &d));
  EXPECT_EQ(kkt.inertia().positive, 1);
  EXPECT_EQ(kkt.inertia().negative, 0);
  EXPECT_GT(d.dot(rhs), 0.0);
  // Positive definite to begin with: the first system takes no shift, d = K⁻¹ rhs.
  const ap::KktBlocks<double> definite = randomBlocks(1, 0.0, 7);
  ap::PerturbationHandler fresh(p);
  ASSERT_TRUE(fresh.factorAndSolve(kkt, definite, rhs, &d));
  EXPECT_LT((dense(definite) * d - rhs).lpNorm<Eigen::Infinity>(), 1e-12);
}
