#include "planning/linalg/bordered_band.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <type_traits>

namespace attitude_planner {

namespace {
/// Σ_i a_i b_i over n entries in Scalar (a in Scalar, b as double).
template <typename Scalar>
Scalar dotInScalar(const Scalar* a, const double* b, int n) {
  Scalar s(0.0);
  for (int i = 0; i < n; ++i) s += a[i] * Scalar(b[i]);
  return s;
}
}  // namespace

template <typename Scalar>
bool BorderedBandedFactor<Scalar>::factor(const BandedSymmetric<Scalar>& A,
                                          const Eigen::MatrixXd& B, const Eigen::MatrixXd& D) {
  n_ = A.size();
  m_ = static_cast<int>(D.rows());
  inertia_ = BorderedInertia{};
  S_.resize(m_, m_);
  inertia_.band_positive_definite = band_.factor(A);
  if (!inertia_.band_positive_definite) return false;
  B_ = B;
  // Z = A⁻¹B, one banded solve per border column, kept in Scalar.
  Z_.assign(static_cast<size_t>(n_) * m_, Scalar(0.0));
  for (int j = 0; j < m_; ++j) {
    Scalar* z = Z_.data() + static_cast<size_t>(j) * n_;
    for (int i = 0; i < n_; ++i) z[i] = Scalar(B(i, j));
    band_.solveInScalar(z);
  }
  // S = D − BᵀZ, each product summed in Scalar; the scale judges which eigenvalues are zero.
  double scale = 0.0;
  S_scalar_.assign(static_cast<size_t>(m_) * m_, Scalar(0.0));
  for (int r = 0; r < m_; ++r) {
    for (int c = 0; c <= r; ++c) {
      const Scalar BtZ = dotInScalar(Z_.data() + static_cast<size_t>(c) * n_, B.col(r).data(), n_);
      const Scalar S_rc = Scalar(D(r, c)) - BtZ;
      S_scalar_[static_cast<size_t>(c) * m_ + r] = S_scalar_[static_cast<size_t>(r) * m_ + c] =
          S_rc;
      S_(r, c) = S_(c, r) = static_cast<double>(S_rc);
      scale = std::max({scale, std::abs(D(r, c)), std::abs(static_cast<double>(BtZ))});
    }
  }
  if (m_ == 0) return true;
  if (!S_.allFinite()) {
    inertia_.zero = m_;  // no claim on its signs: not solvable
    return false;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(S_);
  eigenvalues_ = eigen.eigenvalues();
  eigenvectors_ = eigen.eigenvectors();
  scale = std::max(scale, eigenvalues_.cwiseAbs().maxCoeff());
  for (int i = 0; i < m_; ++i) {
    const double lambda = eigenvalues_(i);
    if (std::abs(lambda) <= kSchurZeroRelative * scale) {
      ++inertia_.zero;
    } else if (lambda > 0.0) {
      ++inertia_.positive;
    } else {
      ++inertia_.negative;
    }
  }
  return inertia_.solvable();
}

template <typename Scalar>
void BorderedBandedFactor<Scalar>::solve(Eigen::VectorXd* rhs) const {
  Eigen::VectorXd& v = *rhs;
  // u = A⁻¹b in Scalar.
  std::vector<Scalar>& u = u_;
  u.assign(v.data(), v.data() + n_);
  band_.solveInScalar(u.data());
  if (m_ == 0) {
    for (int i = 0; i < n_; ++i) v(i) = static_cast<double>(u[i]);
    return;
  }
  // y = S⁻¹(c − Bᵀu).
  std::vector<Scalar> r(m_);
  for (int j = 0; j < m_; ++j) {
    r[j] = Scalar(v(n_ + j)) - dotInScalar(u.data(), B_.col(j).data(), n_);
  }
  const std::vector<Scalar> y = solveSchur(r);
  // x = u − Z y.
  for (int i = 0; i < n_; ++i) {
    Scalar x = u[i];
    for (int j = 0; j < m_; ++j) x -= Z_[static_cast<size_t>(j) * n_ + i] * y[j];
    v(i) = static_cast<double>(x);
  }
  for (int j = 0; j < m_; ++j) v(n_ + j) = static_cast<double>(y[j]);
}

template <typename Scalar>
std::vector<Scalar> BorderedBandedFactor<Scalar>::solveSchur(const std::vector<Scalar>& r) const {
  // Each correction gains about −log10(κ(S)·ε_double) digits; two take double's accuracy to
  // double-double's for κ(S) up to ~1e5 (in double there is nothing to gain).
  constexpr int kSchurRefinements = std::is_same_v<Scalar, double> ? 0 : 2;
  const auto solveInDouble = [&](const Eigen::VectorXd& b) {
    return Eigen::VectorXd(eigenvectors_ *
                           (eigenvectors_.transpose() * b).cwiseQuotient(eigenvalues_));
  };
  std::vector<Scalar> y(m_), residual = r;
  for (int pass = 0; pass <= kSchurRefinements; ++pass) {
    Eigen::VectorXd b(m_);
    for (int j = 0; j < m_; ++j) b(j) = static_cast<double>(residual[j]);
    const Eigen::VectorXd correction = solveInDouble(b);
    for (int j = 0; j < m_; ++j) y[j] += Scalar(correction(j));
    for (int i = 0; i < m_; ++i) {  // residual = r − S y, in Scalar
      residual[i] = r[i];
      for (int j = 0; j < m_; ++j) residual[i] -= S_scalar_[static_cast<size_t>(j) * m_ + i] * y[j];
    }
  }
  return y;
}

template class BorderedBandedFactor<double>;
template class BorderedBandedFactor<long double>;
template class BorderedBandedFactor<DoubleDouble>;

}  // namespace attitude_planner
