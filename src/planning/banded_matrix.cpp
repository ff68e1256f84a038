#include "planning/banded_matrix.hpp"

#include <algorithm>
#include <cmath>

namespace attitude_planner {

BandedSymmetricMatrix::BandedSymmetricMatrix(int n, int bandwidth)
    : n_(n), p_(bandwidth), data_(static_cast<size_t>(n) * (bandwidth + 1), 0.0) {}

void BandedSymmetricMatrix::addToDiagonal(double v) {
  for (int i = 0; i < n_; ++i) at(i, i) += v;
}

void BandedSymmetricMatrix::addRelativeToDiagonal(double factor, double floor) {
  for (int i = 0; i < n_; ++i) at(i, i) += factor * (std::abs(at(i, i)) + floor);
}

double BandedSymmetricMatrix::maxAbsDiagonal() const {
  double m = 0.0;
  for (int i = 0; i < n_; ++i)
    m = std::max(m, std::abs(data_[static_cast<size_t>(i) * (p_ + 1) + p_]));
  return m;
}

double BandedSymmetricMatrix::operator()(int i, int j) const {
  if (i < j) std::swap(i, j);
  return i - j <= p_ ? data_[static_cast<size_t>(i) * (p_ + 1) + (j - i + p_)] : 0.0;
}

Eigen::MatrixXd BandedSymmetricMatrix::toDense() const {
  Eigen::MatrixXd A(n_, n_);
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j) A(i, j) = (*this)(i, j);
  }
  return A;
}

bool BandedSymmetricMatrix::solvePositiveDefinite(Eigen::VectorXd* b) const {
  BandedCholesky cholesky;
  if (!cholesky.factor(*this)) return false;
  cholesky.solve(b);
  return true;
}

bool BandedCholesky::factor(const BandedSymmetricMatrix& A) {
  // Row-oriented Cholesky A = L Lᵀ in a copy with the same layout: row i of L holds
  // L(i, i − p..i) at w·i .. w·i + p, so L(i, k) for consecutive k is consecutive memory.
  n_ = A.n_;
  p_ = A.p_;
  const int w = p_ + 1;
  L_ = A.data_;
  const auto row = [&](int i) {
    return L_.data() + static_cast<size_t>(i) * w + p_ - i;
  };  // row(i)[j] = L(i, j)
  for (int i = 0; i < n_; ++i) {
    double* li = row(i);
    const int first = std::max(0, i - p_);
    for (int j = first; j <= i; ++j) {
      const double* lj = row(j);
      double s = li[j];
      for (int k = std::max(first, j - p_); k < j; ++k) s -= li[k] * lj[k];
      if (j < i) {
        li[j] = s / lj[j];
      } else {
        if (!(s > 0.0) || !std::isfinite(s)) return false;
        li[i] = std::sqrt(s);
      }
    }
  }
  return true;
}

void BandedCholesky::solve(Eigen::VectorXd* b) const {
  const int w = p_ + 1;
  const auto row = [&](int i) { return L_.data() + static_cast<size_t>(i) * w + p_ - i; };
  Eigen::VectorXd& y = *b;
  for (int i = 0; i < n_; ++i) {  // L y = b
    const double* li = row(i);
    double s = y(i);
    for (int k = std::max(0, i - p_); k < i; ++k) s -= li[k] * y(k);
    y(i) = s / li[i];
  }
  for (int i = n_ - 1; i >= 0; --i) {  // Lᵀ x = y
    double s = y(i);
    for (int k = i + 1; k <= std::min(n_ - 1, i + p_); ++k) s -= row(k)[i] * y(k);
    y(i) = s / row(i)[i];
  }
}

}  // namespace attitude_planner

namespace attitude_planner {

BandedLinearSystem::BandedLinearSystem(int n, int bandwidth)
    : n_(n), p_(bandwidth), data_(static_cast<size_t>(n) * (3 * bandwidth + 1), 0.0) {}

double BandedLinearSystem::operator()(int i, int j) const {
  const int offset = j - i + p_;
  return offset >= 0 && offset <= 3 * p_ ? data_[static_cast<size_t>(i) * (3 * p_ + 1) + offset]
                                         : 0.0;
}

bool BandedLinearSystem::solve(Eigen::VectorXd* b_in) {
  Eigen::VectorXd& b = *b_in;
  const size_t w = 3 * p_ + 1;
  // row(i)[j] = A(i, j) for i − p ≤ j ≤ i + 2p.
  const auto row = [&](int i) { return data_.data() + i * w + p_ - i; };
  for (int k = 0; k < n_; ++k) {
    const int last_row = std::min(n_ - 1, k + p_);
    const int last_col = std::min(n_ - 1, k + 2 * p_);
    int pivot = k;
    for (int i = k + 1; i <= last_row; ++i) {
      if (std::abs(row(i)[k]) > std::abs(row(pivot)[k])) pivot = i;
    }
    double* rk = row(k);
    if (!(std::abs(row(pivot)[k]) > 0.0) || !std::isfinite(row(pivot)[k])) return false;
    if (pivot != k) {
      double* rp = row(pivot);
      for (int j = k; j <= last_col; ++j) std::swap(rk[j], rp[j]);
      std::swap(b(k), b(pivot));
    }
    const double inverse_pivot = 1.0 / rk[k];
    for (int i = k + 1; i <= last_row; ++i) {
      double* ri = row(i);
      const double l = ri[k] * inverse_pivot;
      if (l == 0.0) continue;
      ri[k] = 0.0;
      for (int j = k + 1; j <= last_col; ++j) ri[j] -= l * rk[j];
      b(i) -= l * b(k);
    }
  }
  for (int i = n_ - 1; i >= 0; --i) {
    const double* ri = row(i);
    double s = b(i);
    for (int j = i + 1; j <= std::min(n_ - 1, i + 2 * p_); ++j) s -= ri[j] * b(j);
    b(i) = s / ri[i];
  }
  return b.allFinite();
}

}  // namespace attitude_planner
