#include "planning/linalg/banded_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace attitude_planner {

namespace {
// std:: for the built-in types, DoubleDouble's own by argument-dependent lookup.
template <typename Scalar>
Scalar scalarAbs(Scalar x) {
  using std::abs;
  return abs(x);
}
template <typename Scalar>
bool scalarIsFinite(Scalar x) {
  using std::isfinite;
  return isfinite(x);
}
template <typename Scalar>
Scalar scalarSqrt(Scalar x) {
  using std::sqrt;
  return sqrt(x);
}
/// s − Σ_{k = first}^{last − 1} a(k) b(k) (double-double: DoubleDoubleDifference), for the
/// factorization's and both substitutions' inner products.
template <typename Scalar, typename A, typename B>
Scalar minusDot(Scalar s, int first, int last, A a, B b) {
  if constexpr (std::is_same_v<Scalar, DoubleDouble>) {
    DoubleDoubleDifference d(s);
    for (int k = first; k < last; ++k) d.subtractProduct(a(k), b(k));
    return d.value();
  } else {
    for (int k = first; k < last; ++k) s -= a(k) * b(k);
    return s;
  }
}

/// The Newton systems' half bandwidth (ReducedProblem::kHalfBandwidth, which this layer may not
/// include): their rows away from the ends are factored and substituted with the sums' lengths
/// known at compile time, and fully unrolled (`GCC unroll`: without it GCC unrolled only part of
/// the factor's nested sums, 322 instructions a column against 232; the same operations in the same
/// order either way).
constexpr int kFixedBandwidth = 8;

/// Whether row (column) i of an n-row band of half bandwidth P has all P entries on both sides:
/// then the general loops' sums run over exactly the ranges the fixed ones below spell out.
template <int P>
bool hasFullBand(int i, int n) {
  return i >= P && i + P <= n - 1;
}

/// Column j of the Cholesky factor (BandedCholeskyFactor::factor's loop body) where
/// hasFullBand<P>(j): the same products subtracted in the same order, in double. `lj` is
/// row(j) (row(j)[k] = L(j, k)); row(j + t) = row(j) + t P in that layout. False if the
/// pivot is not positive.
template <int P>
bool factorFullColumn(double* lj, int j) {
  const int base = j - P;  // L(·, base + m), m = 0..P − 1: the columns the sums run over
  double d = lj[j];
#pragma GCC unroll 16
  for (int m = 0; m < P; ++m) d -= lj[base + m] * lj[base + m];
  if (!(d > 0) || !std::isfinite(d)) return false;
  lj[j] = std::sqrt(d);
#pragma GCC unroll 16
  for (int t = 1; t <= P; ++t) {
    double* li = lj + t * P;  // row(j + t): its sum starts at column j + t − P = base + t
    double s = li[j];
#pragma GCC unroll 16
    for (int m = t; m < P; ++m) s -= li[base + m] * lj[base + m];
    li[j] = s / lj[j];
  }
  return true;
}

/// Forward substitution's row i (L y = b) where hasFullBand<P>(i); `li` is row(i).
template <int P>
void forwardFullRow(const double* li, double* y, int i) {
  double s = y[i];
#pragma GCC unroll 16
  for (int m = 0; m < P; ++m) s -= li[i - P + m] * y[i - P + m];
  y[i] = s / li[i];
}

/// Back substitution's row i (Lᵀ x = y) where hasFullBand<P>(i): L(i + t, i) = row(i)[i + t P].
template <int P>
void backwardFullRow(const double* li, double* y, int i) {
  double s = y[i];
#pragma GCC unroll 16
  for (int t = 1; t <= P; ++t) s -= li[i + t * P] * y[i + t];
  y[i] = s / li[i];
}
}  // namespace

template <typename Scalar>
BandedSymmetric<Scalar>::BandedSymmetric(int n, int bandwidth)
    : n_(n), p_(bandwidth), data_(static_cast<size_t>(n) * (bandwidth + 1), Scalar(0)) {}

template <typename Scalar>
void BandedSymmetric<Scalar>::addToDiagonal(double v) {
  for (int i = 0; i < n_; ++i) at(i, i) += v;
}

template <typename Scalar>
void BandedSymmetric<Scalar>::addRelativeToDiagonal(double factor, double floor) {
  for (int i = 0; i < n_; ++i) at(i, i) += factor * (scalarAbs(at(i, i)) + floor);
}

template <typename Scalar>
double BandedSymmetric<Scalar>::maxAbsDiagonal() const {
  double m = 0.0;
  for (int i = 0; i < n_; ++i) {
    m = std::max(m, static_cast<double>(scalarAbs(data_[static_cast<size_t>(i) * (p_ + 1) + p_])));
  }
  return m;
}

template <typename Scalar>
double BandedSymmetric<Scalar>::operator()(int i, int j) const {
  if (i < j) std::swap(i, j);
  return i - j <= p_ ? static_cast<double>(data_[static_cast<size_t>(i) * (p_ + 1) + (j - i + p_)])
                     : 0.0;
}

template <typename Scalar>
Eigen::MatrixXd BandedSymmetric<Scalar>::toDense() const {
  Eigen::MatrixXd A(n_, n_);
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j) A(i, j) = (*this)(i, j);
  }
  return A;
}

template <typename Scalar>
bool BandedSymmetric<Scalar>::solvePositiveDefinite(Eigen::VectorXd* b,
                                                    const Interruption* interruption) const {
  BandedCholeskyFactor<Scalar> cholesky;
  if (!cholesky.factor(*this, interruption)) return false;
  cholesky.solve(b);
  return true;
}

template <typename Scalar>
bool BandedCholeskyFactor<Scalar>::factor(const BandedSymmetric<Scalar>& A,
                                          const Interruption* interruption) {
  // Cholesky A = L Lᵀ in a copy with the same layout: row i of L holds L(i, i − p..i) at
  // w·i .. w·i + p, so L(i, k) for consecutive k is consecutive memory. Column by column: the
  // p entries below a diagonal are independent of one another (the processor overlaps their
  // inner products), where along a row each entry waits for the one before it. Each entry is
  //   L(i, j) = (A(i, j) − Σ_{k = max(0, i − p)}^{j − 1} L(i, k) L(j, k)) / L(j, j),
  // its sum in the same order whatever the order of the entries.
  n_ = A.n_;
  p_ = A.p_;
  const int w = p_ + 1;
  L_ = A.data_;
  const auto row = [&](int i) {
    return L_.data() + static_cast<size_t>(i) * w + p_ - i;
  };  // row(i)[j] = L(i, j)
  if constexpr (kMultipliesByReciprocal) reciprocal_diagonal_.resize(n_);
  for (int j = 0; j < n_; ++j) {
    if (interruption && j % kColumnsBetweenPolls == 0) interruption->poll();
    Scalar* lj = row(j);
    if constexpr (std::is_same_v<Scalar, double>) {
      if (p_ == kFixedBandwidth && hasFullBand<kFixedBandwidth>(j, n_)) {
        if (!factorFullColumn<kFixedBandwidth>(lj, j)) return false;
        continue;
      }
    }
    const auto lj_at = [lj](int k) { return lj[k]; };
    const Scalar d = minusDot(lj[j], std::max(0, j - p_), j, lj_at, lj_at);
    if (!(d > 0) || !scalarIsFinite(d)) return false;
    lj[j] = scalarSqrt(d);
    if constexpr (kMultipliesByReciprocal) reciprocal_diagonal_[j] = Scalar(1.0) / lj[j];
    const int last = std::min(n_ - 1, j + p_);
    for (int i = j + 1; i <= last; ++i) {
      Scalar* li = row(i);
      const Scalar s = minusDot(
          li[j], std::max(0, i - p_), j, [li](int k) { return li[k]; }, lj_at);
      li[j] = divideByDiagonal(s, j);
    }
  }
  return true;
}

template <typename Scalar>
void BandedCholeskyFactor<Scalar>::solve(Eigen::VectorXd* b) const {
  if constexpr (std::is_same_v<Scalar, double>) {
    substitute(b->data());
  } else {
    std::vector<Scalar> y(b->data(), b->data() + n_);
    substitute(y.data());
    for (int i = 0; i < n_; ++i) (*b)(i) = static_cast<double>(y[i]);
  }
}

template <typename Scalar>
void BandedCholeskyFactor<Scalar>::substitute(Scalar* y) const {
  const int w = p_ + 1;
  const auto row = [&](int i) { return L_.data() + static_cast<size_t>(i) * w + p_ - i; };
  [[maybe_unused]] const bool fixed = p_ == kFixedBandwidth;
  for (int i = 0; i < n_; ++i) {  // L y = b
    const Scalar* li = row(i);
    if constexpr (std::is_same_v<Scalar, double>) {
      if (fixed && hasFullBand<kFixedBandwidth>(i, n_)) {
        forwardFullRow<kFixedBandwidth>(li, y, i);
        continue;
      }
    }
    const Scalar s = minusDot(
        y[i], std::max(0, i - p_), i, [li](int k) { return li[k]; }, [y](int k) { return y[k]; });
    y[i] = divideByDiagonal(s, i);
  }
  for (int i = n_ - 1; i >= 0; --i) {  // Lᵀ x = y
    if constexpr (std::is_same_v<Scalar, double>) {
      if (fixed && hasFullBand<kFixedBandwidth>(i, n_)) {
        backwardFullRow<kFixedBandwidth>(row(i), y, i);
        continue;
      }
    }
    const Scalar s = minusDot(
        y[i], i + 1, std::min(n_ - 1, i + p_) + 1, [&row, i](int k) { return row(k)[i]; },
        [y](int k) { return y[k]; });
    y[i] = divideByDiagonal(s, i);
  }
}

template class BandedSymmetric<double>;
template class BandedCholeskyFactor<double>;
template class BandedSymmetric<long double>;
template class BandedCholeskyFactor<long double>;
template class BandedSymmetric<DoubleDouble>;
template class BandedCholeskyFactor<DoubleDouble>;

}  // namespace attitude_planner

namespace attitude_planner {

BandedLinearSystem::BandedLinearSystem(int n, int bandwidth, const Interruption* interruption)
    : n_(n), p_(bandwidth) {
  const size_t rows_per_poll = kColumnsBetweenPolls * (3 * static_cast<size_t>(bandwidth) + 1);
  const size_t total = static_cast<size_t>(n) * (3 * bandwidth + 1);
  data_.reserve(total);  // address space only: the pages are touched below, chunk by chunk
  while (data_.size() < total) {
    if (interruption) interruption->poll();
    data_.resize(std::min(total, data_.size() + rows_per_poll), 0.0);
  }
}

void BandedLinearSystem::setZero(const Interruption* interruption) {
  const size_t rows_per_poll = kColumnsBetweenPolls * (3 * static_cast<size_t>(p_) + 1);
  for (size_t begin = 0; begin < data_.size(); begin += rows_per_poll) {
    if (interruption) interruption->poll();
    std::fill(data_.begin() + begin, data_.begin() + std::min(data_.size(), begin + rows_per_poll),
              0.0);
  }
}

double BandedLinearSystem::operator()(int i, int j) const {
  const int offset = j - i + p_;
  return offset >= 0 && offset <= 3 * p_ ? data_[static_cast<size_t>(i) * (3 * p_ + 1) + offset]
                                         : 0.0;
}

bool BandedLinearSystem::solve(Eigen::VectorXd* b_in, const Interruption* interruption) {
  Eigen::VectorXd& b = *b_in;
  const size_t w = 3 * p_ + 1;
  // row(i)[j] = A(i, j) for i − p ≤ j ≤ i + 2p.
  const auto row = [&](int i) { return data_.data() + i * w + p_ - i; };
  for (int k = 0; k < n_; ++k) {
    if (interruption && k % kColumnsBetweenPolls == 0) interruption->poll();
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
