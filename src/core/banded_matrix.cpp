#include "attitude_planner/banded_matrix.hpp"

#include <algorithm>
#include <cmath>

namespace attitude_planner {

BandedSymmetricMatrix::BandedSymmetricMatrix(int n, int bandwidth)
    : n_(n), p_(bandwidth), band_(Eigen::MatrixXd::Zero(n, bandwidth + 1)) {}

double BandedSymmetricMatrix::operator()(int i, int j) const {
  if (i < j) std::swap(i, j);
  return i - j <= p_ ? band_(i, i - j) : 0.0;
}

Eigen::MatrixXd BandedSymmetricMatrix::toDense() const {
  Eigen::MatrixXd A(n_, n_);
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j) A(i, j) = (*this)(i, j);
  }
  return A;
}

bool BandedSymmetricMatrix::solvePositiveDefinite(Eigen::VectorXd* b) const {
  Eigen::MatrixXd L = band_;  // L(i, d) = L_{i, i−d}
  for (int j = 0; j < n_; ++j) {
    double d = L(j, 0);
    for (int k = std::max(0, j - p_); k < j; ++k) d -= L(j, j - k) * L(j, j - k);
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double ljj = std::sqrt(d);
    L(j, 0) = ljj;
    for (int i = j + 1; i <= std::min(n_ - 1, j + p_); ++i) {
      double s = L(i, i - j);
      for (int k = std::max(0, i - p_); k < j; ++k) s -= L(i, i - k) * L(j, j - k);
      L(i, i - j) = s / ljj;
    }
  }
  Eigen::VectorXd& y = *b;
  for (int i = 0; i < n_; ++i) {  // L y = b
    double s = y(i);
    for (int k = std::max(0, i - p_); k < i; ++k) s -= L(i, i - k) * y(k);
    y(i) = s / L(i, 0);
  }
  for (int i = n_ - 1; i >= 0; --i) {  // Lᵀ x = y
    double s = y(i);
    for (int k = i + 1; k <= std::min(n_ - 1, i + p_); ++k) s -= L(k, k - i) * y(k);
    y(i) = s / L(i, 0);
  }
  return true;
}

}  // namespace attitude_planner
