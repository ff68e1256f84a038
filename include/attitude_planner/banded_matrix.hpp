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
