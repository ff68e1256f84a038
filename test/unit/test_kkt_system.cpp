// The interior point's strategy objects: the KKT-system interface and its two inertia corrections
// (interior_point/kkt_system.hpp, inertia_correction.hpp) against dense Eigen solves of the same
// shifted matrices, the least eigenpair against Eigen's dense eigensolver; the monotone barrier
// rule's two profiles (barrier_update.hpp) and the two stopping tests (stopping_tests.hpp) against
// their closed forms; the Armijo line search (line_search.hpp) on one-dimensional merits whose
// accepted step length is found by enumerating the halvings independently; the primal–dual loop
// (primal_dual_loop.hpp) on a scripted problem whose log is the order of the loop's calls.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "planning/interior_point/barrier_update.hpp"
#include "planning/interior_point/inertia_correction.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/line_search.hpp"
#include "planning/interior_point/primal_dual_loop.hpp"
#include "planning/interior_point/stopping_tests.hpp"

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
  ap::KktFactorization<double> system(kkt, k, nullptr);
  Eigen::VectorXd d;
  double shift = 0.0;
  ASSERT_TRUE(correction.factorAndSolve(system, ones(kN), &d, &shift));
  // The schedule: 0, first_shift, then ×shift_growth.
  EXPECT_GT(shift, p.fixed_step.first_shift);
  const double steps = std::log(shift / p.fixed_step.first_shift) / std::log(p.shift_growth);
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
  ap::KktFactorization<double> system(kkt, definite, nullptr);
  Eigen::VectorXd d;
  // A positive definite band factors at the floor itself: the shift used is the floor.
  const auto floor = [&] {
    double shift = -1.0;
    EXPECT_TRUE(correction.factorAndSolve(system, ones(kN), &d, &shift));
    return shift;
  };
  std::vector<double> floors;
  while (correction.afterRejection()) floors.push_back(floor());
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
  for (std::size_t i = 0; i <= floors.size(); ++i) correction.afterStep(1.0, false);
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
  double shift = 0.0;
  ap::KktFactorization<double> system(kkt, k, nullptr);
  ASSERT_TRUE(handler.factorAndSolve(system, rhs, &d, &shift));
  EXPECT_GT(shift, 0.0);
  EXPECT_EQ(kkt.inertia().positive, 1);
  EXPECT_EQ(kkt.inertia().negative, 0);
  EXPECT_GT(d.dot(rhs), 0.0);
  // Positive definite to begin with: the first system takes no shift, d = K⁻¹ rhs.
  const ap::KktBlocks<double> definite = randomBlocks(1, 0.0, 7);
  ap::PerturbationHandler fresh(p);
  ap::KktFactorization<double> definite_system(kkt, definite, nullptr);
  ASSERT_TRUE(fresh.factorAndSolve(definite_system, rhs, &d, &shift));
  EXPECT_EQ(shift, 0.0);
  EXPECT_DOUBLE_EQ(definite_system.meanAbsDiagonal(), dense(definite).diagonal().cwiseAbs().mean());
  EXPECT_LT((dense(definite) * d - rhs).lpNorm<Eigen::Infinity>(), 1e-12);
}

TEST(KktSystem, LeastEigenpairOfAnIndefiniteBorderedBandMatchesTheDenseEigensolver) {
  for (const int globals : {1, 2}) {
    ap::KktBlocks<double> k = randomBlocks(globals, -30.0, 8 + globals);  // A(0, 0) < 0
    k.corner(0, 0) = -2.0;
    const std::optional<ap::LeastEigenpair> least = ap::leastEigenpair(k);
    ASSERT_TRUE(least.has_value());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> dense_solver(dense(k));
    const double lambda = dense_solver.eigenvalues()(0);
    ASSERT_LT(lambda, 0.0);
    EXPECT_NEAR(least->value, lambda, 1e-9 * std::abs(lambda)) << globals;
    EXPECT_NEAR(std::abs(least->vector.dot(dense_solver.eigenvectors().col(0))), 1.0, 1e-9);
    EXPECT_NEAR(least->scale, dense(k).diagonal().cwiseAbs().mean(), 1e-12);
  }
}

namespace {

/// A barrier state with a given slack residual (the monotone decrement test reads nothing else).
class SlackResidualState final : public ap::BarrierRows {
 public:
  explicit SlackResidualState(double residual) : residual_(residual) {}
  double affineComplementarity(const Eigen::VectorXd&, double*,
                               std::vector<double>*) const override {
    throw std::logic_error("not read by the monotone rule");
  }
  void addSlackWeightedGradients(const std::vector<double>*, Eigen::VectorXd*) const override {
    throw std::logic_error("not read by the monotone rule");
  }
  void setComplementarityTarget(double, const std::vector<double>*) override {
    throw std::logic_error("not set by the monotone rule");
  }
  double maxSlackResidual() const override { return residual_; }
  void complementarity(double, double, double*, double*) const override {
    throw std::logic_error("not read by the monotone rule");
  }

 private:
  double residual_;
};

}  // namespace

TEST(MonotoneBarrier, FreeTimeProfileFallsToTheSmallerOfKappaMuAndThetaMuUnsnapped) {
  const ap::InteriorPointParameters p;
  ap::MonotoneBarrier rule(p, ap::freeTimeMonotone(p));
  const ap::BarrierScales scales{1.0, 1, 64, 2e-5};
  // μ^1.3 = 1.2589e-4 < κ_μ μ = 2e-4, within 10 μ_final: the free-time profile keeps it.
  EXPECT_DOUBLE_EQ(rule.decreased(1e-3, scales), std::pow(1e-3, 1.3));
  EXPECT_DOUBLE_EQ(rule.decreased(0.5, scales), 0.2 * 0.5);         // κ_μ μ the smaller
  EXPECT_DOUBLE_EQ(rule.decreased(3e-5, scales), scales.mu_final);  // never below μ_final
  // Solved where the KKT residual is at most κ_ε μ.
  EXPECT_TRUE(rule.solved(10.0 * 1e-3, 1e-3, scales));
  EXPECT_FALSE(rule.solved(1.0001 * 10.0 * 1e-3, 1e-3, scales));
  // The decrement test is the other profile's: a step leaves μ as it is.
  double mu = 1e-3;
  SlackResidualState rows(0.0);
  rule.afterStep({&mu, scales, &rows, 0.0, 1.0}, {0.0, 1.0});
  EXPECT_EQ(mu, 1e-3);
  // As the loop asks it: solved above μ_final where the residual is within κ_ε μ, or where the
  // problem found the barrier problem solved to round-off; then μ falls.
  ap::BarrierState state;
  state.barrier_residual = 10.0 * 1e-3;
  EXPECT_TRUE(rule.subproblemSolved(state, {&mu, scales, nullptr, 0.0, 0.0}));
  state.barrier_residual = 1.0;
  EXPECT_FALSE(rule.subproblemSolved(state, {&mu, scales, nullptr, 0.0, 0.0}));
  state.solved_to_round_off = true;
  EXPECT_TRUE(rule.subproblemSolved(state, {&mu, scales, nullptr, 0.0, 0.0}));
  state.at_final_barrier = true;
  EXPECT_FALSE(rule.subproblemSolved(state, {&mu, scales, nullptr, 0.0, 0.0}));
  rule.decrease({&mu, scales, nullptr, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(mu, std::pow(1e-3, 1.3));
}

TEST(MonotoneBarrier, FixedStepProfileScalesMuSnapsAndTestsTheDecrement) {
  const ap::InteriorPointParameters p;
  ap::MonotoneBarrier rule(p, ap::fixedStepMonotone(p));
  const ap::BarrierScales unit{1.0, 1, 64, 2e-5};
  // The same μ^θ as above would be 3.2e-5 at θ_μ 1.5: within 10 μ_final, snapped to μ_final.
  EXPECT_EQ(rule.decreased(1e-3, unit), unit.mu_final);
  // Scaled μ = μ m / f_scale: μ⁺ = (μ m/f)^1.5 f/m where that is below κ_μ μ.
  const ap::BarrierScales scaled{4.0, 8, 64, 1e-9};
  const double mu = 1e-2, s = mu * 8 / 4.0;
  EXPECT_DOUBLE_EQ(rule.decreased(mu, scaled), std::pow(s, 1.5) * 4.0 / 8);
  // After a step: μ falls only where the decrement and the slack residual are ≤ κ_ε μ (scaled).
  const double bound = p.monotone_kappa_epsilon * s;
  double at = mu;
  SlackResidualState large(2.0 * bound), small(0.5 * bound);
  rule.afterStep({&at, scaled, &large, 0.0, 1.0}, {0.5 * bound, 0.5});
  EXPECT_EQ(at, mu);  // the slack residual too large
  rule.afterStep({&at, scaled, &small, 0.0, 1.0}, {2.0 * bound, 0.5});
  EXPECT_EQ(at, mu);  // the decrement too large, the step cut (not a stall)
  rule.afterStep({&at, scaled, &small, 0.0, 1.0}, {0.5 * bound, 0.5});
  EXPECT_DOUBLE_EQ(at, std::pow(s, 1.5) * 4.0 / 8);
  // The KKT residual test is the other profile's: never solved at the top of a pass.
  ap::BarrierState state;
  state.solved_to_round_off = true;
  EXPECT_FALSE(rule.subproblemSolved(state, {&at, scaled, nullptr, 0.0, 0.0}));
}

TEST(StoppingTests, KktResidualToleranceGrowsLikeNSquaredAbove256) {
  const ap::KktResidualTest small(1e-9, 128), large(1e-9, 512);
  EXPECT_TRUE(small.converged(1e-9, 1e-9));
  EXPECT_FALSE(small.converged(1.01e-9, 0.0));
  EXPECT_FALSE(small.converged(0.0, 1.01e-9));
  EXPECT_TRUE(large.converged(3.99e-9, 1e-9));  // (512/256)² = 4
  EXPECT_FALSE(large.converged(4.01e-9, 1e-9));
  EXPECT_FALSE(large.converged(1e-9, 1.01e-9));  // the gap's tolerance does not grow
  EXPECT_TRUE(small.atRoundOffFloor(99e-9, 99e-9));
  EXPECT_FALSE(small.atRoundOffFloor(101e-9, 0.0));
}

TEST(StoppingTests, DecrementTestEndsAtTheToleranceAndOnAStalledViolation) {
  const ap::InteriorPointParameters p;
  const double tolerance = 1e-8, f_scale = 2.0;
  ap::DecrementTest test(p, tolerance, 64, /*mehrotra=*/false, /*free_slacks=*/false);
  EXPECT_EQ(test.previousDecrement(), std::numeric_limits<double>::infinity());
  // The relative decrement √(−slope)/√(2 f): at the final barrier, unshifted, ≤ tolerance ends.
  const double slope = -std::pow(0.5 * tolerance, 2) * 2.0 * f_scale;
  ap::StopVerdict v = test.check({slope, 0.0, true, 0.0, 0, f_scale});
  EXPECT_NEAR(v.relative_decrement, 0.5 * tolerance, 1e-12 * tolerance);
  EXPECT_TRUE(v.final_step);
  const ap::StopVerdict shifted = test.check({slope, 1e-3, true, 0.0, 1, f_scale});
  EXPECT_FALSE(shifted.final_step);
  EXPECT_FALSE(test.check({slope, 0.0, false, 0.0, 2, f_scale}).final_step);  // μ above μ_final
  test.accepted(shifted, 1.0);
  EXPECT_EQ(test.previousDecrement(), shifted.relative_decrement);
  // A violation that does not fall for violation_stall iterations ends the barrier problem.
  ap::DecrementTest stalled(p, tolerance, 64, false, false);
  const double violation = 10.0 * p.feasibility_tolerance;
  for (int i = 0; i < p.violation_stall; ++i) {
    EXPECT_FALSE(stalled.check({-1.0, 0.0, false, violation, i, f_scale}).final_step) << i;
  }
  EXPECT_TRUE(stalled.check({-1.0, 0.0, false, violation, p.violation_stall, f_scale}).final_step);
  stalled.restart(p.violation_stall);  // a penalty raise: the patience starts again
  EXPECT_FALSE(
      stalled.check({-1.0, 0.0, false, violation, p.violation_stall + 1, f_scale}).final_step);
}

namespace {

/// A one-dimensional barrier problem φ(x) with admissible region x < wall, recording what the line
/// search asked of it. `corrected`: the second-order correction it offers (none if 0).
class LineProblem final : public ap::BarrierProblem {
 public:
  LineProblem(std::function<double(double)> phi, double wall, double corrected = 0.0)
      : phi_(std::move(phi)), wall_(wall), corrected_([corrected](double) { return corrected; }) {}
  /// A wall a trial point lies past as a feasible method's iterate does (moved there, φ = +∞),
  /// with the correction `corrected(trial step)` offered there (none where it is 0).
  LineProblem(std::function<double(double)> phi, double wall,
              std::function<double(double)> corrected)
      : phi_(std::move(phi)), wall_(wall), corrected_(std::move(corrected)), moves_past_(true) {}
  double merit() override { return phi_(accepted_); }
  double trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) override {
    ++trials;
    if (moved) *moved = false;
    const bool past = accepted_ + alpha * d(0) >= wall_;
    if (past && !moves_past_) return std::numeric_limits<double>::infinity();
    moveTo(d, alpha);
    if (moved) *moved = true;
    return past ? std::numeric_limits<double>::infinity() : phi_(x);
  }
  void moveTo(const Eigen::VectorXd& d, double alpha) override { x = accepted_ + alpha * d(0); }
  void restore() override {
    ++restores;
    x = accepted_;
  }
  bool correctedStep(const Eigen::VectorXd& d, Eigen::VectorXd* corrected) override {
    const double step = corrected_(d(0));
    if (step == 0.0) return false;
    *corrected = Eigen::VectorXd::Constant(1, step);
    return true;
  }
  void clearCorrection() override { ++clears; }
  double x = 0.0;
  int trials = 0, restores = 0, clears = 0;

 private:
  std::function<double(double)> phi_;
  double wall_;
  std::function<double(double)> corrected_;
  bool moves_past_ = false;
  double accepted_ = 0.0;
};

/// The first of α₀, α₀/2, … (at most `halvings`) meeting Armijo's condition for φ along d from 0,
/// or NaN: the closed form of a backtracking search, enumerated.
double firstArmijoStep(const std::function<double(double)>& phi, double d, double slope,
                       double alpha0, int halvings, double wall) {
  const double armijo = ap::InteriorPointParameters{}.armijo;
  double alpha = alpha0;
  for (int i = 0; i < halvings; ++i, alpha /= 2) {
    if (alpha * d < wall && phi(alpha * d) <= phi(0.0) + armijo * alpha * slope) return alpha;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

TEST(LineSearch, ArmijoBacktrackingTakesTheFirstHalvingThatDecreasesEnough) {
  const ap::InteriorPointParameters p;
  const ap::ArmijoBacktracking search(ap::fixedStepLineSearch(p));
  // φ = x⁴ − x along d = 4 (slope −1): the full step overshoots, some halving is accepted; a
  // wall at 0.9 rejects the steps that cross it.
  const auto phi = [](double x) { return std::pow(x, 4) - x; };
  for (const double wall : {100.0, 0.9}) {
    LineProblem problem(phi, wall);
    Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 4.0);
    const ap::LineSearchResult r = search.search(problem, {-4.0, 1.0, false, false, false}, &d);
    const double expected = firstArmijoStep(phi, 4.0, -4.0, 1.0, p.fixed_step.max_halvings, wall);
    ASSERT_TRUE(r.accepted) << wall;
    EXPECT_EQ(r.alpha, expected) << wall;
    EXPECT_LT(r.alpha, 1.0);
    EXPECT_EQ(problem.x, r.alpha * 4.0);  // left at the accepted trial point
    EXPECT_EQ(problem.restores, 0);
  }
}

TEST(LineSearch, AnAscentDirectionIsRejectedAfterEveryHalvingAndTheIterateRestored) {
  const ap::InteriorPointParameters p;
  const auto phi = [](double x) { return x * x + x; };  // d = +1 ascends from 0
  for (const bool at_floor : {false, true}) {
    LineProblem problem(phi, 100.0);
    Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 1.0);
    const ap::LineSearchResult r = ap::ArmijoBacktracking(ap::fixedStepLineSearch(p))
                                       .search(problem, {-1.0, 1.0, false, at_floor, false}, &d);
    EXPECT_FALSE(r.accepted);
    EXPECT_EQ(problem.trials, at_floor ? p.fixed_step.floor_halvings : p.fixed_step.max_halvings);
    EXPECT_EQ(problem.restores, 1);
    EXPECT_EQ(problem.x, 0.0);
  }
}

TEST(LineSearch, ARoundOffDecreaseIsTakenAtFixedStepAndOnlyFlaggedInFreeTime) {
  const ap::InteriorPointParameters p;
  // φ rises along d (by more than its round-off at every trial length): only a step taken as
  // round-off is accepted.
  const auto phi = [](double x) { return 1.0 + x; };
  const double slope = -0.5 * p.merit_round_off;  // |slope| below round-off of φ(0) = 1
  LineProblem fixed(phi, 100.0);
  Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 1e-3);
  const ap::LineSearchResult taken = ap::ArmijoBacktracking(ap::fixedStepLineSearch(p))
                                         .search(fixed, {slope, 0.25, false, false, false}, &d);
  EXPECT_TRUE(taken.accepted && taken.at_round_off);
  EXPECT_EQ(taken.alpha, 0.25);  // α₀, not searched
  EXPECT_EQ(fixed.trials, 0);
  EXPECT_EQ(fixed.x, 0.25e-3);
  LineProblem free_time(phi, 100.0);
  const ap::LineSearchResult flagged =
      ap::ArmijoBacktracking(ap::freeTimeLineSearch(p))
          .search(free_time, {slope, 1.0, false, false, false}, &d);
  EXPECT_TRUE(flagged.at_round_off);
  EXPECT_FALSE(flagged.accepted);
  EXPECT_EQ(free_time.trials, p.free_time.max_halvings);
}

TEST(LineSearch, AtTheRoundOffFloorAFreeTimeRoundOffStepIsNotTried) {
  const ap::InteriorPointParameters p;
  const ap::ArmijoBacktracking search(ap::freeTimeLineSearch(p));
  // φ falls along d, so any trial would pass Armijo's test; the predicted decrease is round-off
  // of φ(0) = 1. At the floor no trial is made and the iterate stays; off the floor, or with a
  // decrease above round-off at the floor, the step is searched (and taken whole here).
  const auto phi = [](double x) { return 1.0 - x; };
  Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 1e-3);
  const double round_off = -0.5 * p.merit_round_off, real = -1e-3;
  for (const bool at_floor : {false, true}) {
    for (const double slope : {round_off, real}) {
      LineProblem problem(phi, 100.0);
      const ap::LineSearchResult r =
          search.search(problem, {slope, 1.0, false, at_floor, false}, &d);
      const bool untried = at_floor && slope == round_off;
      EXPECT_EQ(r.at_round_off, slope == round_off);
      EXPECT_EQ(r.accepted, !untried) << at_floor << " " << slope;
      EXPECT_EQ(problem.trials, untried ? 0 : 1);
      EXPECT_EQ(problem.x, untried ? 0.0 : 1e-3);
    }
  }
}

TEST(LineSearch, TheSecondOrderCorrectionReplacesARejectedFullStepInTheFreeTimeProfile) {
  const ap::InteriorPointParameters p;
  // φ = (x − 2)²: the full step d = 4.5 overshoots the minimum at 2 (φ(4.5) > φ(0)), the
  // corrected step 2 lands on it.
  const auto phi = [](double x) { return (x - 2.0) * (x - 2.0); };
  const double slope = -4.0 * 4.5;  // φ'(0) d
  LineProblem problem(phi, 100.0, 2.0);
  Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 4.5);
  const ap::ArmijoBacktracking search(ap::freeTimeLineSearch(p));
  ap::LineSearchResult r = search.search(problem, {slope, 1.0, false, false, true}, &d);
  EXPECT_TRUE(r.accepted);
  EXPECT_EQ(r.alpha, 1.0);
  EXPECT_EQ(d(0), 2.0);  // the corrected step is the step taken
  EXPECT_EQ(problem.x, 2.0);
  EXPECT_EQ(problem.trials, 2);
  // Without a correction on offer (or not late, or the fixed-h profile) the full step is
  // followed by halvings from 1/2, and the correction's terms are cleared.
  LineProblem plain(phi, 100.0);
  d(0) = 4.5;
  r = search.search(plain, {slope, 1.0, false, false, true}, &d);
  EXPECT_EQ(plain.clears, 1);
  EXPECT_EQ(plain.trials, 2);  // the full step, then α = 1/2 (accepted: φ(2.25) is small)
  EXPECT_EQ(r.alpha, firstArmijoStep(phi, 4.5, slope, 0.5, p.free_time.max_halvings, 100.0));
  EXPECT_EQ(d(0), 4.5);
  LineProblem fixed(phi, 100.0, 2.0);
  r = ap::ArmijoBacktracking(ap::fixedStepLineSearch(p))
          .search(fixed, {slope, 1.0, false, false, true}, &d);
  EXPECT_EQ(r.alpha, firstArmijoStep(phi, 4.5, slope, 1.0, p.fixed_step.max_halvings, 100.0));
  EXPECT_EQ(d(0), 4.5);
  EXPECT_EQ(fixed.clears, 0);
}

TEST(LineSearch, InTheEndGameEveryTrialLengthTheBoundaryRejectsIsRetriedWithItsCorrection) {
  const ap::InteriorPointParameters p;
  const ap::ArmijoBacktracking search(ap::freeTimeLineSearch(p));
  // φ = −x falls along d = 16 up to a wall at 1 that a trial passes as a feasible method's does
  // (moved there, φ = +∞). The correction pulls a trial back to 0.9 of the wall where the trial
  // step is at most 4 (a curvature the linear model misses only that far out), else none.
  const auto phi = [](double x) { return -x; };
  const auto pulled_back = [](double step) { return step <= 4.0 ? 0.9 : 0.0; };
  const double slope = -16.0;
  LineProblem late(phi, 1.0, pulled_back);
  Eigen::VectorXd d = Eigen::VectorXd::Constant(1, 16.0);
  ap::LineSearchResult r = search.search(late, {slope, 1.0, false, false, true}, &d);
  ASSERT_TRUE(r.accepted);
  EXPECT_EQ(r.alpha, 1.0);  // the corrected step, taken whole
  EXPECT_EQ(d(0), 0.9);
  EXPECT_EQ(late.x, 0.9);
  EXPECT_EQ(late.trials, 4);  // α = 1 and 1/2 (no correction there), 1/4 and its correction
  EXPECT_EQ(late.clears, 2);
  // Not in the end game: plain halvings to the first length inside the wall, 1/32 (x = 0.5).
  LineProblem early(phi, 1.0, pulled_back);
  d(0) = 16.0;
  r = search.search(early, {slope, 1.0, false, false, false}, &d);
  ASSERT_TRUE(r.accepted);
  EXPECT_EQ(r.alpha, firstArmijoStep(phi, 16.0, slope, 1.0, p.free_time.max_halvings, 1.0));
  EXPECT_EQ(r.alpha, 1.0 / 32);
  EXPECT_EQ(d(0), 16.0);
  EXPECT_EQ(early.trials, 6);
  EXPECT_EQ(early.clears, 0);
  EXPECT_LT(phi(late.x), phi(early.x));  // the corrected search went further in fewer trials
}

namespace {

/// A problem on φ(x) = (x − 1)² from x = 0 whose hooks log their calls (b: a pass begins, m: μ
/// fell at a solved barrier problem, d/p: the direction assembled (p: with primal multipliers),
/// a: a step accepted (A: one the stopping test marked final), R: a retry the inertia correction
/// granted, r: rejected, E: ended by the stopping test, L: the iteration limit, S/I: stopped
/// between passes / inside one), one pass a '|'. Its direction is Newton's (1 − x), or the ascent
/// direction −1000 (1 − x) where `ascent`; `before` scripts per pass whether the barrier problem
/// is solved there (Step: not; Continue: solved, μ falls; Stop: solved, and the observer stops).
class ScriptedProblem final : public ap::PrimalDualProblem {
 public:
  double merit() override { return phi(accepted_); }
  double trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) override {
    moveTo(d, alpha);
    if (moved) *moved = true;
    return phi(x_);
  }
  void moveTo(const Eigen::VectorXd& d, double alpha) override { x_ = accepted_ + alpha * d(0); }
  void restore() override { x_ = accepted_; }
  void prepare() override { log += 'b'; }
  ap::BarrierState state() const override {
    ap::BarrierState s;
    s.iteration = static_cast<int>(std::count(log.begin(), log.end(), '|'));
    // Solved only where scripted (the residual never passes the μ rule's κ_ε test).
    s.barrier_residual = std::numeric_limits<double>::infinity();
    s.solved_to_round_off = scripted() != ap::Pass::Step;
    return s;
  }
  ap::BarrierAccess barrier() override { return {&mu, {1.0, 1, 1, 0.0}, nullptr, 0.0, 0.0}; }
  ap::Pass atSolvedBarrier() override {
    return scripted() == ap::Pass::Stop ? ap::Pass::Stop : ap::Pass::Step;
  }
  void barrierDecreased() override { log += 'm'; }
  ap::Pass assemble(bool primal) override {
    log += primal ? 'p' : 'd';
    if (throw_in_direction) throw ap::SolveInterrupted{ap::Termination::TimedOut};
    // The ascent is steep enough that even the last halving rises above φ's round-off.
    rhs_ = Eigen::VectorXd::Constant(1, (ascent ? -1000.0 : 1.0) * (1.0 - accepted_));
    return ap::Pass::Step;
  }
  ap::NewtonSystem newtonSystem() override { return {&system_, &rhs_, &d_}; }
  ap::Pass direction(bool primal, double, ap::LineSearchRequest* request, Eigen::VectorXd** d,
                     ap::DirectionMeasures*) override {
    if (no_descent_once && !primal) return ap::Pass::Retry;
    *request = {-2.0 * (1.0 - accepted_) * std::abs(d_(0)), 1.0, false, false, false};
    *d = &d_;
    return ap::Pass::Step;
  }
  ap::Pass accept(const ap::LineSearchResult&, const ap::StopVerdict& verdict) override {
    log += verdict.final_step ? "A|" : "a|";
    accepted_ = x_;
    return ap::Pass::Continue;
  }
  ap::Pass retry(const ap::StopVerdict&) override {
    log += "R|";
    return ap::Pass::Continue;
  }
  ap::Pass rejected(const ap::LineSearchResult&, const ap::StopVerdict&) override {
    log += 'r';
    return ap::Pass::Stop;
  }
  ap::Pass ended(const ap::LoopEnd& end) override {
    log += 'E';
    ending = end.termination;
    return ap::Pass::Stop;
  }
  void iterationLimit() override { log += 'L'; }
  void stopped(ap::Termination t, bool inside) override {
    log += inside ? 'I' : 'S';
    ending = t;
  }
  static double phi(double x) { return (x - 1.0) * (x - 1.0); }

  std::string log;
  std::vector<ap::Pass> before;
  bool ascent = false, throw_in_direction = false, no_descent_once = false;
  ap::Termination ending = ap::Termination::Converged;
  double mu = 1.0;
  int retries = 0;        ///< the inertia correction's retries after a rejection
  int inertia_steps = 0;  ///< the steps the inertia correction was told of

 private:
  /// K = 1: the step is the right-hand side.
  class IdentitySystem final : public ap::ShiftedSystem {
   public:
    bool factor(const ap::Shift&) override { return true; }
    const ap::KktInertia& inertia() const override { return inertia_; }
    void solve(Eigen::VectorXd*) const override {}
    int globals() const override { return 0; }
    double maxAbsDiagonal() const override { return 1.0; }
    double meanAbsDiagonal() const override { return 1.0; }

   private:
    ap::KktInertia inertia_;
  };
  ap::Pass scripted() const {
    const int pass = static_cast<int>(std::count(log.begin(), log.end(), 'b')) - 1;
    return pass >= 0 && pass < static_cast<int>(before.size()) ? before[pass] : ap::Pass::Step;
  }
  double x_ = 0.0, accepted_ = 0.0;
  Eigen::VectorXd rhs_, d_;
  IdentitySystem system_;
};

/// The inertia correction of a ScriptedProblem: no shift, `retries` after rejections, the steps
/// it is told of counted.
class ScriptedInertia final : public ap::InertiaCorrection {
 public:
  explicit ScriptedInertia(ScriptedProblem* problem) : problem_(*problem) {}
  bool factorAndSolve(ap::ShiftedSystem& system, const Eigen::VectorXd& rhs, Eigen::VectorXd* d,
                      double* shift) override {
    *d = rhs;
    system.solve(d);
    *shift = 0.0;
    return true;
  }
  bool afterRejection() override { return problem_.retries-- > 0; }
  void afterStep(double, bool) override { ++problem_.inertia_steps; }

 private:
  ScriptedProblem& problem_;
};

/// A stopping test scripted by pass (the state's iteration): converged before the direction at
/// `converge_at`, a final step at `final_at`, the round-off floor on a rejection where `floor`;
/// it logs the steps it is told of (`accepted`).
class ScriptedCheck final : public ap::ConvergenceCheck {
 public:
  std::optional<ap::LoopEnd> beforeDirection(const ap::BarrierState& s) override {
    if (s.iteration != converge_at) return std::nullopt;
    return ap::LoopEnd{ap::Termination::Converged, "converged", std::nullopt};
  }
  ap::StopVerdict afterDirection(const ap::BarrierState& s, const ap::DirectionMeasures&) override {
    ap::StopVerdict v;
    v.final_step = s.iteration == final_at;
    return v;
  }
  void accepted(const ap::StopVerdict&, double alpha) override { accepted_steps.push_back(alpha); }
  std::optional<ap::LoopEnd> onRejected(const ap::BarrierState&, const ap::StopVerdict&) override {
    if (!floor) return std::nullopt;
    return ap::LoopEnd{ap::Termination::Converged, "converged to the round-off floor", 0.0};
  }
  int converge_at = -1, final_at = -1;
  bool floor = false;
  std::vector<double> accepted_steps;
};

/// Runs the loop in the fixed-h (limits first) or free-time order; returns the passes counted.
int runLoop(ScriptedProblem* problem, bool limits_first, int max_iterations,
            const std::atomic<bool>* cancel = nullptr, ScriptedCheck* check = nullptr) {
  ap::SolverOptions options;
  options.cancel_requested = cancel;
  ap::SolveContext context(options);
  const ap::InteriorPointParameters p;
  int iteration = 0;
  ScriptedCheck never;
  ap::PrimalDualLoop(
      *problem,
      {check ? *check : never, std::make_unique<ap::MonotoneBarrier>(p, ap::freeTimeMonotone(p)),
       std::make_unique<ScriptedInertia>(problem)},
      {ap::fixedStepLineSearch(p), limits_first, true}, context)
      .run(max_iterations, &iteration);
  return iteration;
}

}  // namespace

TEST(PrimalDualLoop, FixedStepTestsTheLimitBeforeAPassAndFreeTimeAfterWhatComesBeforeTheDirection) {
  ScriptedProblem fixed, free_time;
  EXPECT_EQ(runLoop(&fixed, true, 2), 2);
  EXPECT_EQ(fixed.log, "bda|bda|L");
  EXPECT_EQ(runLoop(&free_time, false, 2), 2);
  EXPECT_EQ(free_time.log, "bda|bda|bL");
}

TEST(PrimalDualLoop, APassEndedBeforeItsDirectionCountsAndARejectedStepEndsWhereTheProblemSays) {
  ScriptedProblem problem;
  problem.before = {ap::Pass::Continue, ap::Pass::Step, ap::Pass::Stop};
  // The μ fall and the step count, the observer's Stop not; μ fell once, by the loop's rule.
  EXPECT_EQ(runLoop(&problem, true, 5), 2);
  EXPECT_EQ(problem.log, "bmbda|b");
  const ap::InteriorPointParameters p;
  EXPECT_DOUBLE_EQ(problem.mu, p.monotone_kappa_mu);
  EXPECT_EQ(problem.inertia_steps, 1);  // the inertia correction told of the one step
  ScriptedProblem ascent;
  ascent.ascent = true;  // every halving of an ascent direction is rejected
  EXPECT_EQ(runLoop(&ascent, true, 5), 0);
  EXPECT_EQ(ascent.log, "bdr");
  // The inertia correction's retry after a rejection is a counted pass, before the failure.
  ScriptedProblem retried;
  retried.ascent = true;
  retried.retries = 1;
  EXPECT_EQ(runLoop(&retried, true, 5), 1);
  EXPECT_EQ(retried.log, "bdR|bdr");
  EXPECT_EQ(retried.inertia_steps, 0);
}

TEST(PrimalDualLoop, ADirectionThatIsNoDescentIsAssembledAgainWithPrimalMultipliers) {
  ScriptedProblem problem;
  problem.no_descent_once = true;
  EXPECT_EQ(runLoop(&problem, true, 1), 1);
  EXPECT_EQ(problem.log, "bdpa|L");
}

TEST(PrimalDualLoop, AStopReasonEndsTheSolveInTheProfilesPlaceAndAnInterruptionInsideAPass) {
  const std::atomic<bool> cancel{true};
  ScriptedProblem fixed, free_time, inside;
  EXPECT_EQ(runLoop(&fixed, true, 5, &cancel), 0);
  EXPECT_EQ(fixed.log, "S");
  EXPECT_EQ(fixed.ending, ap::Termination::Cancelled);
  EXPECT_EQ(runLoop(&free_time, false, 5, &cancel), 0);
  EXPECT_EQ(free_time.log, "bS");
  inside.throw_in_direction = true;
  EXPECT_EQ(runLoop(&inside, true, 5), 0);
  EXPECT_EQ(inside.log, "bdI");
  EXPECT_EQ(inside.ending, ap::Termination::TimedOut);
}

TEST(PrimalDualLoop, TheLoopCallsTheStoppingTestBeforeTheDirectionOnItAndOnARejection) {
  ScriptedProblem problem;
  ScriptedCheck check;
  check.converge_at = 2;
  check.final_at = 1;
  EXPECT_EQ(runLoop(&problem, true, 5, nullptr, &check), 2);
  EXPECT_EQ(problem.log, "bda|bdA|bE");  // the verdict reaches the step; converged at pass 3
  EXPECT_EQ(problem.ending, ap::Termination::Converged);
  ASSERT_EQ(check.accepted_steps.size(), 2u);  // told of both steps whose pass goes on
  EXPECT_EQ(check.accepted_steps[0], 1.0);     // Newton's full step on the parabola
  ScriptedProblem ascent, at_floor;
  ascent.ascent = at_floor.ascent = true;
  ScriptedCheck floor;
  floor.floor = true;
  EXPECT_EQ(runLoop(&at_floor, true, 5, nullptr, &floor), 0);
  EXPECT_EQ(at_floor.log, "bdE");  // the test ends the solve before the problem's retry
  EXPECT_EQ(at_floor.ending, ap::Termination::Converged);
  EXPECT_TRUE(floor.accepted_steps.empty());
}

TEST(StoppingTests, EachTestEndsTheSolveWhereItsProfileSays) {
  const ap::KktResidualTest kkt(1e-9, 128);
  ap::KktResidualTest test = kkt;
  ap::BarrierState s;
  s.stationarity = s.gap = 1e-10;
  EXPECT_FALSE(test.beforeDirection(s));  // above μ_final
  s.at_final_barrier = true;
  ASSERT_TRUE(test.beforeDirection(s));
  EXPECT_EQ(test.beforeDirection(s)->termination, ap::Termination::Converged);
  s.elastic = true;  // never inside the elastic start
  EXPECT_FALSE(test.beforeDirection(s));
  EXPECT_FALSE(test.onRejected(s, {}));
  s.elastic = false;
  s.stationarity = 99e-9;  // not converged, but within the round-off floor (100 × tolerance)
  EXPECT_FALSE(test.beforeDirection(s));
  EXPECT_TRUE(test.onRejected(s, {}));
  s.stationarity = 101e-9;
  EXPECT_FALSE(test.onRejected(s, {}));
  // The floor a direction is at (its round-off step is then not tried: the line search): at
  // μ_final, outside the elastic start, both residuals within 100 × their tolerances.
  s.stationarity = 99e-9;
  s.gap = 99e-9;
  EXPECT_TRUE(test.afterDirection(s, {}).at_floor);
  s.gap = 101e-9;
  EXPECT_FALSE(test.afterDirection(s, {}).at_floor);
  s.gap = 1e-10;
  s.elastic = true;
  EXPECT_FALSE(test.afterDirection(s, {}).at_floor);
  s.elastic = false;
  s.at_final_barrier = false;
  EXPECT_FALSE(test.afterDirection(s, {}).at_floor);
  s.at_final_barrier = true;
  EXPECT_FALSE(test.afterDirection(s, {}).final_step);  // the KKT residual test ends before it
  // The decrement test: converged at the floor it found on the direction, with its decrement.
  const ap::InteriorPointParameters p;
  ap::DecrementTest decrement(p, 1e-8, 64, false, false);
  ap::StopVerdict v;
  v.relative_decrement = 3e-9;
  EXPECT_FALSE(decrement.onRejected({}, v));
  v.at_floor = true;
  const std::optional<ap::LoopEnd> end = decrement.onRejected({}, v);
  ASSERT_TRUE(end);
  EXPECT_EQ(end->termination, ap::Termination::Converged);
  EXPECT_EQ(end->decrement, std::optional<double>(3e-9));
  // A barrier problem's last step is not remembered (the solve ends or starts over).
  v.final_step = true;
  decrement.accepted(v, 1.0);
  EXPECT_EQ(decrement.previousDecrement(), std::numeric_limits<double>::infinity());
  v.final_step = false;
  decrement.accepted(v, 1.0);
  EXPECT_EQ(decrement.previousDecrement(), 3e-9);
  // The verdict on a direction is check() on the state and the direction's measures.
  ap::BarrierState at;
  at.at_final_barrier = true;
  at.f_scale = 2.0;
  const double slope = -std::pow(0.5e-8, 2) * 2.0 * 2.0;
  EXPECT_TRUE(decrement.afterDirection(at, {slope, 0.0}).final_step);
  EXPECT_FALSE(decrement.afterDirection(at, {slope, 1e-3}).final_step);  // shifted
}
