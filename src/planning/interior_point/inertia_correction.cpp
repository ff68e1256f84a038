#include "planning/interior_point/inertia_correction.hpp"

#include <algorithm>
#include <cmath>

namespace attitude_planner {

bool RowRelativeShift::factorAndSolve(ShiftedSystem& system, const Eigen::VectorXd& rhs,
                                      Eigen::VectorXd* d, double* shift) {
  const double row_floor = p_.shift_row_floor * system.maxAbsDiagonal();
  *shift = floor_;
  for (int tries = 0; tries < p_.max_inertia_corrections; ++tries) {
    *d = rhs;
    // With global unknowns (a twist) the Schur complement must be positive too: a descent step.
    if (system.factor({*shift, Shift::Rule::RowRelative, row_floor}) &&
        system.inertia().negative == 0) {
      system.solve(d);
      if (d->allFinite()) return true;
    }
    *shift = *shift == 0.0 ? p_.fixed_step.first_shift : p_.shift_growth * *shift;
  }
  return false;
}

bool RowRelativeShift::afterRejection() {
  if (floor_ >= p_.max_shift_floor) return false;
  floor_ = std::max(p_.line_search_shift, p_.shift_growth * floor_);
  return true;
}

void RowRelativeShift::afterStep(double, bool) {
  floor_ = floor_ > p_.line_search_shift ? floor_ / p_.shift_growth : 0.0;
}

bool PerturbationHandler::factorAndSolve(ShiftedSystem& system, const Eigen::VectorXd& rhs,
                                         Eigen::VectorXd* d, double* used) {
  const int m = system.globals();
  const double scale = system.meanAbsDiagonal();
  const double resumed =
      last_shift_ > 0 ? std::max(p_.smallest_resumed_shift, last_shift_ / p_.resumed_shift_divisor)
                      : p_.free_time.first_shift;
  for (double shift = damping_; shift <= p_.max_uniform_shift;
       shift = shift == 0.0
                   ? resumed
                   : shift * (last_shift_ > 0 ? p_.resumed_shift_growth : p_.shift_growth)) {
    if (!system.factor({shift * scale, Shift::Rule::Uniform, 0.0})) continue;
    if (system.inertia().positive != m) continue;
    *d = rhs;
    system.solve(d);
    if (d->allFinite() && d->dot(rhs) > 0) {
      last_shift_ = shift;
      *used = shift;
      return true;
    }
  }
  return false;
}

void PerturbationHandler::afterStep(double alpha, bool end_game) {
  cut_steps_ = end_game && alpha < p_.damping_cut_step ? cut_steps_ + 1 : 0;
  const double growth = p_.damping_growth;
  if (cut_steps_ >= p_.damping_cut_steps) {
    damping_ = std::max(growth * damping_, p_.free_time.first_shift);
  } else if (alpha == 1.0) {
    damping_ = damping_ / growth >= p_.smallest_damping ? damping_ / growth : 0.0;
  }
}

}  // namespace attitude_planner
