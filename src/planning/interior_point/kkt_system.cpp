#include "planning/interior_point/kkt_system.hpp"

#include <optional>
#include <stdexcept>

#include "planning/linalg/double_double.hpp"

namespace attitude_planner {

namespace {

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
  // The uniform shift reaches the globals' diagonal too (a zero shift adds nothing).
  Eigen::MatrixXd D = k.corner;
  if (shift.rule == Shift::Rule::Uniform) D.diagonal().array() += shift.value;
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

}  // namespace attitude_planner
