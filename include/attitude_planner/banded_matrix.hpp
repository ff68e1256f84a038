// Symmetric banded matrices with an O(n·p²) Cholesky solve: the Newton systems of the discrete
// optimal control problem are block-pentadiagonal (half bandwidth 8 for 3×3 blocks).
#pragma once

#include <Eigen/Core>

namespace attitude_planner {

/// Symmetric matrix stored by its lower band (band(i, d) = A(i, i − d), d = 0..bandwidth).
class BandedSymmetricMatrix {
 public:
  BandedSymmetricMatrix(int n, int bandwidth);
  int size() const { return n_; }
  int bandwidth() const { return p_; }
  void setZero() { band_.setZero(); }
  /// Adds v to A(i, j) (and so to A(j, i)); |i − j| ≤ bandwidth.
  void add(int i, int j, double v) {
    if (i < j) std::swap(i, j);
    band_(i, i - j) += v;
  }
  void addToDiagonal(double v) { band_.col(0).array() += v; }
  double maxAbsDiagonal() const { return band_.col(0).cwiseAbs().maxCoeff(); }
  /// A(i, j), for tests and diagnostics.
  double operator()(int i, int j) const;
  /// The full matrix, for tests and diagnostics.
  Eigen::MatrixXd toDense() const;
  /// Solves A x = b in place by a banded Cholesky factorization of a copy of A.
  /// Returns false (x unspecified) if A is not numerically positive definite.
  bool solvePositiveDefinite(Eigen::VectorXd* b) const;

 private:
  int n_, p_;
  Eigen::MatrixXd band_;
};

}  // namespace attitude_planner

namespace attitude_planner {

/// General square banded matrix (lower and upper bandwidth p) with an LU solve with partial
/// pivoting, O(n·p²). For symmetric indefinite systems, such as the augmented Newton system
/// whose condition number is the square root of the normal equations'.
class BandedLinearSystem {
 public:
  BandedLinearSystem(int n, int bandwidth);
  int size() const { return n_; }
  void setZero() { rows_.setZero(); }
  /// Adds v to A(i, j); |i − j| ≤ bandwidth.
  void add(int i, int j, double v) { rows_(i, j - i + p_) += v; }
  /// A(i, j) (0 outside the band), for tests.
  double operator()(int i, int j) const;
  /// Solves A x = b in place (A is overwritten by its factors). Returns false if singular.
  bool solve(Eigen::VectorXd* b);

 private:
  int n_, p_;
  Eigen::MatrixXd rows_;  ///< rows_(i, j − i + p) = A(i, j), j ∈ [i − p, i + 2p] (room for fill-in)
};

}  // namespace attitude_planner
