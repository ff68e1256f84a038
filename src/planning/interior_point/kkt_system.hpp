// The interior point's Newton (KKT) system behind one interface: the band of the node unknowns
// alone (fixed h), or that band bordered by a few global unknowns (free time: η = h/h₀ and, while
// the start is elastic, θ),
//
//     K = [ A   B ]     A  n×n banded, half bandwidth ReducedProblem::kHalfBandwidth,
//         [ Bᵀ  D ],    B  n×m dense, D m×m (m = 0 at fixed h).
//
// One assembly fills KktBlocks; a KktSystem factors K plus a diagonal shift (the inertia
// correction's, inertia_correction.hpp), reads its inertia, and solves with the last factor
// (Mehrotra's corrector and the second-order correction reuse it).
#pragma once

#include <cmath>
#include <memory>
#include <optional>

#include <Eigen/Core>

#include "planning/linalg/banded_matrix.hpp"
#include "planning/linalg/bordered_band.hpp"
#include "planning/linalg/interruption.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// What one assembly fills: A (the node unknowns' band), B and D (the global unknowns in force;
/// empty at fixed h).
template <typename Scalar>
struct KktBlocks {
  explicit KktBlocks(int n) : band(n, ReducedProblem::kHalfBandwidth) {}
  int globals() const { return static_cast<int>(corner.rows()); }
  BandedSymmetric<Scalar> band;
  Eigen::MatrixXd border;  ///< B: n × m
  Eigen::MatrixXd corner;  ///< D: m × m
};

/// The diagonal shift added before a factorization. RowRelative (fixed h; a twist's corner alike):
/// A(i, i) += value ·
/// (|A(i, i)| + row_floor) on the band's rows (BandedSymmetric::addRelativeToDiagonal); Uniform
/// (free time): value on every diagonal entry of A and D. A zero value leaves the band as it is.
struct Shift {
  enum class Rule { RowRelative, Uniform };
  double value = 0.0;
  Rule rule = Rule::Uniform;
  double row_floor = 0.0;
};

/// K's inertia: the band positive definite or not, and the signs of the Schur complement's
/// eigenvalues (BorderedInertia; all zero counts at m = 0).
using KktInertia = BorderedInertia;

template <typename Scalar>
class KktSystem {
 public:
  virtual ~KktSystem() = default;
  /// Factors K + shift. False where the band is not numerically positive definite or the Schur
  /// complement is singular (then solve must not be called). `interruption` (optional) is polled
  /// inside the band's factorization and may throw.
  virtual bool factor(const KktBlocks<Scalar>& k, const Shift& shift,
                      const Interruption* interruption = nullptr) = 0;
  virtual const KktInertia& inertia() const = 0;
  /// Solves with the last successful factor, in place: n entries then m.
  virtual void solve(Eigen::VectorXd* rhs) const = 0;
};

/// m = 0: the band's Cholesky factor (fixed h).
template <typename Scalar>
class BandKkt final : public KktSystem<Scalar> {
 public:
  bool factor(const KktBlocks<Scalar>& k, const Shift& shift,
              const Interruption* interruption = nullptr) override;
  const KktInertia& inertia() const override { return inertia_; }
  void solve(Eigen::VectorXd* rhs) const override { cholesky_.solve(rhs); }

 private:
  BandedCholeskyFactor<Scalar> cholesky_;
  KktInertia inertia_;
};

/// m ≥ 1: the Schur complement on the border (linalg/bordered_band.hpp; free time).
template <typename Scalar>
class BorderedBandKkt final : public KktSystem<Scalar> {
 public:
  bool factor(const KktBlocks<Scalar>& k, const Shift& shift,
              const Interruption* interruption = nullptr) override;
  const KktInertia& inertia() const override { return factor_.inertia(); }
  void solve(Eigen::VectorXd* rhs) const override { factor_.solve(rhs); }

 private:
  BorderedBandedFactor<Scalar> factor_;
};

/// One assembled K and its KktSystem as the inertia correction sees them, whatever the precision:
/// the primal–dual loop factors through this (PrimalDualProblem::newtonSystem).
class ShiftedSystem {
 public:
  virtual ~ShiftedSystem() = default;
  /// Factors K + shift (polling the problem's interruption where it has one).
  virtual bool factor(const Shift& shift) = 0;
  virtual const KktInertia& inertia() const = 0;
  virtual void solve(Eigen::VectorXd* rhs) const = 0;
  virtual int globals() const = 0;
  /// max |A(i, i)|, the row-relative shift's floor scale.
  virtual double maxAbsDiagonal() const = 0;
  /// The mean |diagonal| of K (A and D): the uniform shift's scale.
  virtual double meanAbsDiagonal() const = 0;
};

/// A KktSystem<Scalar> over the blocks one assembly fills.
template <typename Scalar>
class KktFactorization final : public ShiftedSystem {
 public:
  KktFactorization(KktSystem<Scalar>& kkt, const KktBlocks<Scalar>& k,
                   const Interruption* interruption)
      : kkt_(kkt), k_(k), interruption_(interruption) {}
  bool factor(const Shift& shift) override { return kkt_.factor(k_, shift, interruption_); }
  const KktInertia& inertia() const override { return kkt_.inertia(); }
  void solve(Eigen::VectorXd* rhs) const override { kkt_.solve(rhs); }
  int globals() const override { return k_.globals(); }
  double maxAbsDiagonal() const override { return k_.band.maxAbsDiagonal(); }
  double meanAbsDiagonal() const override {
    const int n = k_.band.size();
    double scale = k_.corner.diagonal().cwiseAbs().sum();
    for (int i = 0; i < n; ++i) scale += std::abs(k_.band(i, i));
    return scale / (n + k_.globals());
  }

 private:
  KktSystem<Scalar>& kkt_;
  const KktBlocks<Scalar>& k_;
  const Interruption* interruption_;
};

/// The implementation for m global unknowns (the loop never asks which).
template <typename Scalar>
std::unique_ptr<KktSystem<Scalar>> makeKkt(int globals);

/// The least eigenpair of a K (m ≥ 1: the bordered band) that is not positive definite, from
/// banded factorizations alone: λ_min ≤ 0 as the largest σ ≤ 0 with K − σI positive definite
/// (bisection from a Gershgorin bound), then inverse iteration just below it (kkt_system.cpp).
/// nullopt where even the Gershgorin shift does not factor. Free time's second-order check calls
/// it once per converged solve whose barrier Hessian is not definite.
struct LeastEigenpair {
  double value = 0.0;      ///< the Rayleigh quotient of `vector`
  Eigen::VectorXd vector;  ///< unit, n + m entries
  double scale = 0.0;      ///< K's mean |diagonal|
};
std::optional<LeastEigenpair> leastEigenpair(const KktBlocks<double>& kkt);

}  // namespace attitude_planner
