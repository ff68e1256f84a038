#include "planning/interior_point/kkt_system.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "planning/linalg/double_double.hpp"

namespace attitude_planner {

namespace {

/// leastEigenpair: bisections of the shift down to this fraction of the Gershgorin radius (at
/// most kEigenBisections), then this many inverse iterations.
constexpr double kEigenBisectionPrecision = 1e-12;
constexpr int kEigenBisections = 60;
constexpr int kInverseIterations = 4;

/// A with the shift's band part (a copy; the assembled blocks stay as they are), or A itself
/// where the shift is zero.
template <typename Scalar>
const BandedSymmetric<Scalar>& shiftedBand(const BandedSymmetric<Scalar>& A, const Shift& shift,
                                           std::optional<BandedSymmetric<Scalar>>* copy) {
  if (!(shift.value > 0)) return A;
  copy->emplace(A);
  if (shift.rule == Shift::Rule::RowRelative) {
    (*copy)->addRelativeToDiagonal(shift.value, shift.row_floor);
  } else {
    (*copy)->addToDiagonal(shift.value);
  }
  return **copy;
}

}  // namespace

template <typename Scalar>
bool BandKkt<Scalar>::factor(const KktBlocks<Scalar>& k, const Shift& shift,
                             const Interruption* interruption) {
  if (k.globals() != 0) throw std::logic_error("BandKkt: the system has global unknowns");
  std::optional<BandedSymmetric<Scalar>> copy;
  inertia_ = KktInertia{};
  inertia_.band_positive_definite =
      cholesky_.factor(shiftedBand(k.band, shift, &copy), interruption);
  return inertia_.band_positive_definite;
}

template <typename Scalar>
bool BorderedBandKkt<Scalar>::factor(const KktBlocks<Scalar>& k, const Shift& shift,
                                     const Interruption*) {
  std::optional<BandedSymmetric<Scalar>> copy;
  const BandedSymmetric<Scalar>& A = shiftedBand(k.band, shift, &copy);
  // The shift reaches the globals' diagonal too (a zero shift adds nothing): uniform, or relative
  // to each global's own diagonal entry as to a band row's.
  Eigen::MatrixXd D = k.corner;
  if (shift.rule == Shift::Rule::Uniform) D.diagonal().array() += shift.value;
  if (shift.rule == Shift::Rule::RowRelative) {
    D.diagonal().array() += shift.value * (D.diagonal().array().abs() + shift.row_floor);
  }
  return factor_.factor(A, k.border, D);
}

template <typename Scalar>
std::unique_ptr<KktSystem<Scalar>> makeKkt(int globals) {
  if (globals == 0) return std::make_unique<BandKkt<Scalar>>();
  return std::make_unique<BorderedBandKkt<Scalar>>();
}

template class BandKkt<double>;
template class BandKkt<long double>;
template class BandKkt<DoubleDouble>;
template class BorderedBandKkt<double>;
template class BorderedBandKkt<long double>;
template class BorderedBandKkt<DoubleDouble>;
template std::unique_ptr<KktSystem<double>> makeKkt<double>(int);
template std::unique_ptr<KktSystem<long double>> makeKkt<long double>(int);
template std::unique_ptr<KktSystem<DoubleDouble>> makeKkt<DoubleDouble>(int);

// Banded factorizations alone: O(n b²) each, where a dense eigensolver costs O(n³). Inverse
// iteration just below λ_min converges at the ratio (λ₁ − σ)/(λ₂ − σ) per step.
std::optional<LeastEigenpair> leastEigenpair(const KktBlocks<double>& kkt) {
  const int n = kkt.band.size(), b = kkt.globals();
  const int size = n + b;
  double radius = 0.0, scale = 0.0;  // Gershgorin: every eigenvalue ≥ min_i (K_ii − Σ|K_ij|)
  for (int i = 0; i < size; ++i) {
    double off = 0.0;
    for (int j = std::max(0, i - kkt.band.bandwidth());
         j <= std::min(n - 1, i + kkt.band.bandwidth()); ++j) {
      if (i < n && j != i) off += std::abs(kkt.band(i, j));
    }
    off += i < n ? kkt.border.row(i).cwiseAbs().sum() : kkt.border.col(i - n).cwiseAbs().sum();
    const double diagonal = i < n ? kkt.band(i, i) : kkt.corner(i - n, i - n);
    if (i >= n) off += kkt.corner.row(i - n).cwiseAbs().sum() - std::abs(diagonal);
    radius = std::max(radius, std::abs(diagonal) + off);
    scale += std::abs(diagonal) / size;
  }
  const auto shifted = [&](double sigma, BorderedBanded* factor) {
    BandedSymmetric<double> A = kkt.band;
    A.addToDiagonal(-sigma);
    Eigen::MatrixXd D = kkt.corner;
    D.diagonal().array() -= sigma;
    return factor->factor(A, kkt.border, D) && factor->inertia().positive == b &&
           factor->inertia().negative == 0;
  };
  BorderedBanded factor;
  double below = -radius, above = 0.0;  // K − below·I positive definite, K − above·I not
  if (!shifted(below, &factor)) return std::nullopt;
  for (int i = 0; i < kEigenBisections && above - below > kEigenBisectionPrecision * radius; ++i) {
    const double middle = 0.5 * (below + above);
    (shifted(middle, &factor) ? below : above) = middle;
  }
  shifted(below, &factor);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(size);
  for (int i = 0; i < kInverseIterations; ++i) {
    factor.solve(&x);
    x.normalize();
  }
  LeastEigenpair least;
  Eigen::VectorXd Kx = Eigen::VectorXd::Zero(size);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - kkt.band.bandwidth());
         j <= std::min(n - 1, i + kkt.band.bandwidth()); ++j) {
      Kx(i) += kkt.band(i, j) * x(j);
    }
  }
  Kx.head(n) += kkt.border * x.tail(b);
  Kx.tail(b) = kkt.border.transpose() * x.head(n) + kkt.corner * x.tail(b);
  least.value = x.dot(Kx);  // the Rayleigh quotient
  least.vector = x;
  least.scale = scale;
  return least;
}

}  // namespace attitude_planner
