// Symmetric banded matrices with an O(n·p²) Cholesky solve: the Newton systems of the discrete
// optimal control problem are block-pentadiagonal (half bandwidth 8 for 3×3 blocks).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <type_traits>
#include <vector>

#include "planning/linalg/double_double.hpp"
#include "planning/linalg/interruption.hpp"

namespace attitude_planner {

/// Symmetric matrix stored by its lower band, row by row: row i holds A(i, i − p..i) contiguously
/// (the Cholesky inner products then run over consecutive memory). Scalar: double, or long double
/// or DoubleDouble (ExtendedBandedMatrix, ~106 significant bits) where a system's entries span more
/// orders than double can add and factor without losing the small ones (the interior point's
/// barrier terms and its N⁴ condition; see grid_solve.hpp: resolvePrecision).
template <typename Scalar>
class BandedSymmetric {
 public:
  BandedSymmetric(int n, int bandwidth);
  int size() const { return n_; }
  int bandwidth() const { return p_; }
  void setZero() { std::fill(data_.begin(), data_.end(), Scalar(0)); }
  /// Adds v to A(i, j) (and so to A(j, i)); |i − j| ≤ bandwidth.
  void add(int i, int j, double v) {
    if (i < j) std::swap(i, j);
    at(i, j) += v;
  }
  /// Adds the symmetric K×K block M at rows/columns offset..offset+K−1, restricted to the
  /// block's indices first..last−1 (the others are skipped: fixed variables). Uses M's lower
  /// triangle; the block must lie within the band.
  template <int K>
  void addSymmetricBlock(int offset, const Eigen::Matrix<double, K, K>& M, int first, int last) {
    for (int r = first; r < last; ++r) {
      Scalar* row = &at(offset + r, offset);
      for (int c = first; c <= r; ++c) row[c] += M(r, c);
    }
  }
  /// Adds weight·g gᵀ at rows/columns offset..offset+K−1, restricted as addSymmetricBlock, each
  /// product formed in Scalar (a rank-one term far larger than the rest keeps the rest).
  template <int K>
  void addRankOne(int offset, const Eigen::Matrix<double, K, 1>& g, double weight, int first,
                  int last) {
    for (int r = first; r < last; ++r) {
      Scalar* row = &at(offset + r, offset);
      const Scalar gr = Scalar(weight) * Scalar(g(r));
      for (int c = first; c <= r; ++c) row[c] += gr * Scalar(g(c));
    }
  }
  void addToDiagonal(double v);
  /// A(i, i) += factor · (|A(i, i)| + floor): a shift relative to each row's own scale, so that a
  /// matrix whose diagonal spans many orders (barrier terms) is regularized in every direction
  /// alike; `floor` gives zero diagonals a scale.
  void addRelativeToDiagonal(double factor, double floor);
  double maxAbsDiagonal() const;
  /// A(i, j), for tests and diagnostics.
  double operator()(int i, int j) const;
  /// The full matrix, for tests and diagnostics.
  Eigen::MatrixXd toDense() const;
  /// Solves A x = b in place by a banded Cholesky factorization of a copy of A.
  /// Returns false (x unspecified) if A is not numerically positive definite. `interruption`
  /// (optional) is polled every kColumnsBetweenPolls columns and may throw to stop the solve.
  bool solvePositiveDefinite(Eigen::VectorXd* b, const Interruption* interruption = nullptr) const;

 private:
  template <typename>
  friend class BandedCholeskyFactor;
  /// A(i, j) for i − p ≤ j ≤ i.
  Scalar& at(int i, int j) { return data_[static_cast<size_t>(i) * (p_ + 1) + (j - i + p_)]; }
  int n_, p_;
  std::vector<Scalar> data_;
};

/// The banded Cholesky factor L Lᵀ = A of a BandedSymmetric, kept so that several right-hand
/// sides can be solved with one factorization (e.g. a predictor–corrector's second solve).
/// Factors and solves in Scalar.
template <typename Scalar>
class BandedCholeskyFactor {
 public:
  /// Factors A (the factor replaces any previous one). Returns false if A is not numerically
  /// positive definite (then solve must not be called). `interruption` (optional) is polled
  /// every kColumnsBetweenPolls columns and may throw to stop the factorization.
  bool factor(const BandedSymmetric<Scalar>& A, const Interruption* interruption = nullptr);
  /// Solves A x = b in place with the last successful factor.
  void solve(Eigen::VectorXd* b) const;
  /// The same on y[0..n−1] held in Scalar (no rounding to double in between: the bordered solve
  /// forms its Schur complement from these).
  void solveInScalar(Scalar* y) const { substitute(y); }
  int size() const { return n_; }

 private:
  /// Forward and back substitution on y (in place).
  void substitute(Scalar* y) const;
  /// Double-double division costs several multiplications: its factor keeps 1/L(i, i) and
  /// multiplies (the other scalars divide, as the hardware does it about as fast).
  static constexpr bool kMultipliesByReciprocal = std::is_same_v<Scalar, DoubleDouble>;
  /// s / L(i, i).
  Scalar divideByDiagonal(const Scalar& s, int i) const {
    if constexpr (kMultipliesByReciprocal) {
      return s * reciprocal_diagonal_[i];
    } else {
      return s / L_[static_cast<size_t>(i) * (p_ + 1) + p_];
    }
  }
  int n_ = 0, p_ = 0;
  std::vector<Scalar> L_;  ///< row i holds L(i, i − p..i), as BandedSymmetric's layout
  std::vector<Scalar> reciprocal_diagonal_;  ///< 1/L(i, i) (kMultipliesByReciprocal only)
};

using BandedSymmetricMatrix = BandedSymmetric<double>;
using BandedCholesky = BandedCholeskyFactor<double>;
/// Double-double arithmetic (double_double.hpp): ε ≈ 1.2e-32, the same on every platform.
using ExtendedBandedMatrix = BandedSymmetric<DoubleDouble>;
using ExtendedBandedCholesky = BandedCholeskyFactor<DoubleDouble>;

}  // namespace attitude_planner

namespace attitude_planner {

/// General square banded matrix (lower and upper bandwidth p) with an LU solve with partial
/// pivoting, O(n·p²). For symmetric indefinite systems, such as the augmented Newton system
/// whose condition number is the square root of the normal equations'.
class BandedLinearSystem {
 public:
  /// An n × n zero matrix. `interruption` (optional) is polled every kColumnsBetweenPolls rows
  /// while its storage is zeroed: at N = 1e5 the augmented Newton system is ~200 MB, whose first
  /// touch (page faults) took 0.1-0.3 s of a cancelled solve's hand-over.
  BandedLinearSystem(int n, int bandwidth, const Interruption* interruption = nullptr);
  int size() const { return n_; }
  /// Zeroes every entry, polling `interruption` (optional) as the constructor does.
  void setZero(const Interruption* interruption = nullptr);
  /// Adds v to A(i, j); |i − j| ≤ bandwidth.
  void add(int i, int j, double v) { at(i, j) += v; }
  /// A(i, j) (0 outside the band), for tests.
  double operator()(int i, int j) const;
  /// Solves A x = b in place (A is overwritten by its factors). Returns false if singular.
  /// `interruption` (optional) is polled every kColumnsBetweenPolls columns and may throw.
  bool solve(Eigen::VectorXd* b, const Interruption* interruption = nullptr);

 private:
  /// Row i holds A(i, i − p..i + 2p) contiguously (the upper 2p: room for pivoting fill-in), so
  /// eliminations run over consecutive memory.
  double& at(int i, int j) { return data_[static_cast<size_t>(i) * (3 * p_ + 1) + (j - i + p_)]; }
  int n_, p_;
  std::vector<double> data_;
};

}  // namespace attitude_planner
