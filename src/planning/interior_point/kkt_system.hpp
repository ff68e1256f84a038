// The interior point's Newton (KKT) system behind one interface: the band of the node unknowns
// alone (fixed h), or that band bordered by a few global unknowns (free time's η = h/h₀, a
// pointing end's twist ψ),
//
//     K = [ A   B ]     A  n×n banded, half bandwidth ReducedProblem::kHalfBandwidth,
//         [ Bᵀ  D ],    B  n×m dense, D m×m (m = 0 at fixed h).
//
// One assembly fills KktBlocks through a KktSink (where each local block lands); a KktSystem
// factors K plus a diagonal shift (the inertia correction's, inertia_correction.hpp), reads its
// inertia, and solves with the last factor (Mehrotra's corrector and the second-order correction
// reuse it).
#pragma once

#include <cmath>
#include <memory>
#include <optional>

#include <Eigen/Core>

#include "planning/linalg/banded_matrix.hpp"
#include "planning/linalg/bordered_band.hpp"
#include "planning/linalg/interruption.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_transcription.hpp"

namespace attitude_planner {

/// What one assembly fills: A (the node unknowns' band), B and D (the global unknowns in force;
/// empty at fixed h).
template <typename Scalar>
struct KktBlocks {
  explicit KktBlocks(int n) : band(n, ReducedProblem::kHalfBandwidth) {}
  int globals() const { return static_cast<int>(corner.rows()); }
  void clear(int n, int m) {
    if (band.size() == n) {
      band.setZero();
    } else {
      band = BandedSymmetric<Scalar>(n, ReducedProblem::kHalfBandwidth);
    }
    border.setZero(n, m);
    corner.setZero(m, m);
  }
  BandedSymmetric<Scalar> band;
  Eigen::MatrixXd border;  ///< B: n × m
  Eigen::MatrixXd corner;  ///< D: m × m
};

/// Where an assembly's local pieces land in K: a block over the unknowns of at most three
/// consecutive nodes (9 entries, a fixed node's included and skipped here) and, with h free
/// (FreeTimeStep), η (entry 9: the border's first column). A pointing end's twist ψ, the last
/// global unknown, moves R_N and, for paper and variational, R_{N−1} linearly in their
/// perturbation coordinates, by e = localTwistMotion (ReducedProblem::twistMotion): a block H has
/// the ψ-column H e and corner eᵀHe (a gradient g the ψ entry gᵀe: addLocalVector). With h free
/// the motions compose: h moves R_{N−1} along its boundary path d(h) (ReducedProblem::nodePath),
///     R_N exp(Δψ b^) F(h)ᵀ = R_{N−1} exp(Δψ e^) exp(d^),   x = Δψ e + d + ½ Δψ e × d + O(3)
/// (Baker–Campbell–Hausdorff), so ∂²L/∂ψ∂η = e·H(:, η) + ∇_{x_{N−1}}L · ½ (e × d′) h₀: the path's
/// curvature term, from the block's Lagrangian gradient. How the blocks are summed is the
/// profile's (AssemblyChoices::sum_in_double).
template <typename Scalar, typename TimeStep>
class KktSink {
 public:
  static constexpr int kEntries = TimeStep::kEntries;
  using Local = Eigen::Matrix<double, kEntries, 1>;
  using Block = Eigen::Matrix<double, kEntries, kEntries>;
  /// Clears `kkt` to the node unknowns and the time step's global unknowns in force.
  KktSink(const ReducedProblem& np, const TimeStep& step, KktBlocks<Scalar>* kkt)
      : np_(np), step_(step), kkt_(*kkt), twist_(TimeStep::twistIndex(np) - np.unknowns()) {
    kkt->clear(np.unknowns(), TimeStep::globals(np));
  }

  /// H at the block's nodes (and η), the lower triangle of its node part used; with h free,
  /// `lagrangian` is the block's ∇L (fixed nodes' entries included) for the path's term.
  void addBlock(int first_node, int width, const Block& H, const Local* lagrangian = nullptr) {
    const Eigen::Matrix<double, 9, 9> nodes = H.template topLeftCorner<9, 9>();
    addBandBlock(np_, &kkt_.band, first_node, width, nodes);
    if constexpr (kEntries == 10) {
      addNodeVector(np_, H.template block<9, 1>(0, 9), 1.0, first_node, width, kkt_.border.col(0));
      kkt_.corner(0, 0) += H(9, 9);
    }
    if (!np_.hasTwist()) return;
    const Eigen::Matrix<double, 9, 1> e = localTwistMotion(np_, first_node, width);
    if (e.isZero(0.0)) return;
    const Eigen::Matrix<double, 9, 1> He = nodes.selfadjointView<Eigen::Lower>() * e;
    kkt_.corner(twist_, twist_) += e.dot(He);
    addNodeVector(np_, He, 1.0, first_node, width, kkt_.border.col(twist_));
    if constexpr (kEntries == 10) {
      double time = e.dot(H.template block<9, 1>(0, 9));
      const int slot = np_.steps() - 1 - first_node;  // R_{N−1}: h and ψ both move it
      if (lagrangian && slot >= 0 && slot < width) {
        const Vector3 path = np_.nodePath(np_.steps() - 1).first * step_.scale;
        time += lagrangian->template segment<3>(3 * slot).dot(
            0.5 * Vector3(e.segment<3>(3 * slot)).cross(path));
      }
      kkt_.corner(0, twist_) += time;
      kkt_.corner(twist_, 0) += time;
    }
  }

  /// weight·g gᵀ over the block's nodes (and η), the band's part formed in its precision.
  void addRankOne(int first_node, int width, const Local& g, double weight) {
    const LocalSlots l = localSlots(np_, first_node, width);
    const Eigen::Matrix<double, 9, 1> nodes = g.template head<9>();
    if (!l.empty()) kkt_.band.template addRankOne<9>(l.offset, nodes, weight, l.first, l.last);
    if constexpr (kEntries == 10) {
      addNodeVector(np_, nodes, weight * g(9), first_node, width, kkt_.border.col(0));
      kkt_.corner(0, 0) += weight * g(9) * g(9);
    }
    if (!np_.hasTwist()) return;
    const double ge = nodes.dot(localTwistMotion(np_, first_node, width));
    if (ge == 0.0) return;
    kkt_.corner(twist_, twist_) += weight * ge * ge;
    addNodeVector(np_, nodes, weight * ge, first_node, width, kkt_.border.col(twist_));
    if constexpr (kEntries == 10) {
      kkt_.corner(0, twist_) += weight * ge * g(9);
      kkt_.corner(twist_, 0) += weight * ge * g(9);
    }
  }

 private:
  const ReducedProblem& np_;
  TimeStep step_;
  KktBlocks<Scalar>& kkt_;
  int twist_;  ///< ψ's column of the border (meaningful with a twist only)
};

/// The diagonal shift added before a factorization. RowRelative (fixed h; a twist's corner alike):
/// A(i, i) += value · (|A(i, i)| + row_floor) (BandedSymmetric::addRelativeToDiagonal); Uniform
/// (free time): value on every diagonal entry of A and D.
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
