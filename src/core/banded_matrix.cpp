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

namespace attitude_planner {

BandedLinearSystem::BandedLinearSystem(int n, int bandwidth)
    : n_(n), p_(bandwidth), rows_(Eigen::MatrixXd::Zero(n, 3 * bandwidth + 1)) {}

double BandedLinearSystem::operator()(int i, int j) const {
  const int offset = j - i + p_;
  return offset >= 0 && offset <= 3 * p_ ? rows_(i, offset) : 0.0;
}

bool BandedLinearSystem::solve(Eigen::VectorXd* b_in) {
  Eigen::VectorXd& b = *b_in;
  auto at = [&](int i, int j) -> double& { return rows_(i, j - i + p_); };
  for (int k = 0; k < n_; ++k) {
    const int last_row = std::min(n_ - 1, k + p_);
    const int last_col = std::min(n_ - 1, k + 2 * p_);
    int pivot = k;
    for (int i = k + 1; i <= last_row; ++i) {
      if (std::abs(at(i, k)) > std::abs(at(pivot, k))) pivot = i;
    }
    if (!(std::abs(at(pivot, k)) > 0.0) || !std::isfinite(at(pivot, k))) return false;
    if (pivot != k) {
      for (int j = k; j <= last_col; ++j) std::swap(at(k, j), at(pivot, j));
      std::swap(b(k), b(pivot));
    }
    const double inverse_pivot = 1.0 / at(k, k);
    for (int i = k + 1; i <= last_row; ++i) {
      const double l = at(i, k) * inverse_pivot;
      if (l == 0.0) continue;
      at(i, k) = 0.0;
      for (int j = k + 1; j <= last_col; ++j) at(i, j) -= l * at(k, j);
      b(i) -= l * b(k);
    }
  }
  for (int i = n_ - 1; i >= 0; --i) {
    double s = b(i);
    for (int j = i + 1; j <= std::min(n_ - 1, i + 2 * p_); ++j) s -= at(i, j) * b(j);
    b(i) = s / at(i, i);
  }
  return b.allFinite();
}

}  // namespace attitude_planner
