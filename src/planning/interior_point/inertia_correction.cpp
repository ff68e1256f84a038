#include "planning/interior_point/inertia_correction.hpp"

#include <algorithm>
#include <cmath>

#include "planning/linalg/double_double.hpp"

namespace attitude_planner {

template <typename Scalar>
bool RowRelativeShift::factorAndSolve(KktSystem<Scalar>& kkt, const KktBlocks<Scalar>& k,
                                      const Eigen::VectorXd& rhs, Eigen::VectorXd* d, double* shift,
                                      const Interruption* interruption) {
  const double row_floor = p_.shift_row_floor * k.band.maxAbsDiagonal();
  *shift = floor_;
  for (int tries = 0; tries < p_.max_inertia_corrections; ++tries) {
    *d = rhs;
    // With global unknowns (a twist) the Schur complement must be positive too: a descent step.
    if (kkt.factor(k, {*shift, Shift::Rule::RowRelative, row_floor}, interruption) &&
        kkt.inertia().negative == 0) {
      kkt.solve(d);
      if (d->allFinite()) return true;
    }
    *shift = *shift == 0.0 ? p_.first_shift : p_.shift_growth * *shift;
  }
  return false;
}

bool RowRelativeShift::raiseFloor() {
  if (floor_ >= p_.max_shift_floor) return false;
  floor_ = std::max(p_.line_search_shift, p_.shift_growth * floor_);
  return true;
}

void RowRelativeShift::relax() {
  floor_ = floor_ > p_.line_search_shift ? floor_ / p_.shift_growth : 0.0;
}

template <typename Scalar>
bool PerturbationHandler::factorAndSolve(KktSystem<Scalar>& kkt, const KktBlocks<Scalar>& k,
                                         const Eigen::VectorXd& rhs, Eigen::VectorXd* d) {
  const int n = k.band.size();
  const int m = k.globals();
  double scale = k.corner.diagonal().cwiseAbs().sum();
  for (int i = 0; i < n; ++i) scale += std::abs(k.band(i, i));
  scale /= n + m;
  const double resumed = last_shift_ > 0 ? std::max(p_.free_time_smallest_shift,
                                                    last_shift_ / kIpoptShiftResumeDivisor)
                                         : p_.free_time_first_shift;
  for (double shift = damping_; shift <= p_.free_time_max_shift;
       shift = shift == 0.0 ? resumed
                            : shift * (last_shift_ > 0 ? kIpoptShiftGrowth : p_.shift_growth)) {
    if (!kkt.factor(k, {shift * scale, Shift::Rule::Uniform, 0.0})) continue;
    if (kkt.inertia().positive != m) continue;
    *d = rhs;
    kkt.solve(d);
    if (d->allFinite() && d->dot(rhs) > 0) {
      last_shift_ = shift;
      return true;
    }
  }
  return false;
}

void PerturbationHandler::afterStep(double alpha, bool late) {
  cut_steps_ = late && alpha < p_.free_time_cut_step ? cut_steps_ + 1 : 0;
  const double growth = p_.free_time_damping_growth;
  if (cut_steps_ >= p_.free_time_cut_steps_before_damping) {
    damping_ = std::max(growth * damping_, p_.free_time_first_shift);
  } else if (alpha == 1.0) {
    damping_ = damping_ / growth >= p_.free_time_smallest_damping ? damping_ / growth : 0.0;
  }
}

#define AP_INSTANTIATE_INERTIA_CORRECTION(Scalar)                                             \
  template bool RowRelativeShift::factorAndSolve<Scalar>(                                     \
      KktSystem<Scalar>&, const KktBlocks<Scalar>&, const Eigen::VectorXd&, Eigen::VectorXd*, \
      double*, const Interruption*);                                                          \
  template bool PerturbationHandler::factorAndSolve<Scalar>(                                  \
      KktSystem<Scalar>&, const KktBlocks<Scalar>&, const Eigen::VectorXd&, Eigen::VectorXd*);
AP_INSTANTIATE_INERTIA_CORRECTION(double)
AP_INSTANTIATE_INERTIA_CORRECTION(long double)
AP_INSTANTIATE_INERTIA_CORRECTION(DoubleDouble)
#undef AP_INSTANTIATE_INERTIA_CORRECTION

}  // namespace attitude_planner
