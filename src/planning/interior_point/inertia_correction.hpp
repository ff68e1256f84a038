// Inertia correction: the diagonal shift δ_w that makes the KKT system (kkt_system.hpp) factor
// with the inertia a descent step needs, in the two schedules the solvers use (both IPOPT's δ_w
// in spirit, measured separately; docs/design/one_interior_point.md §1 compares them).
#pragma once

#include <Eigen/Core>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "planning/interior_point/kkt_system.hpp"

namespace attitude_planner {

/// The inertia correction as the primal–dual loop (primal_dual_loop.hpp) calls it: the shifted
/// factorization of each pass's system, and its schedule's updates after a step and after a line
/// search that took none.
class InertiaCorrection {
 public:
  virtual ~InertiaCorrection() = default;
  /// Factors K + shift with the schedule's shifts and solves *d = K⁻¹ rhs; *shift is the shift
  /// used. False if no shift the schedule allows gives a step.
  virtual bool factorAndSolve(ShiftedSystem& system, const Eigen::VectorXd& rhs, Eigen::VectorXd* d,
                              double* shift) = 0;
  /// After a line search that took no step: true where a stronger regularization is worth a retry
  /// from the same iterate.
  virtual bool afterRejection() { return false; }
  /// After an accepted step of length `alpha`; `end_game`: μ ≤ the damped barrier (free time).
  virtual void afterStep(double /*alpha*/, bool /*end_game*/) {}
};

/// Fixed h: a shift relative to each row's scale (Shift::Rule::RowRelative, the row floor
/// `shift_row_floor` × the largest diagonal), from the current floor, first the fixed-step
/// profile's `first_shift`, then ×`shift_growth`, at most `max_inertia_corrections` factorizations,
/// until the band factors positive definite (at the final barrier the active constraints' rows are
/// ~1/μ larger than the others, and a uniform shift sized by them damps the free directions into
/// linear convergence). After a rejected line search the floor rises (Levenberg–Marquardt), and it
/// is relaxed after every accepted step.
class RowRelativeShift final : public InertiaCorrection {
 public:
  explicit RowRelativeShift(const InteriorPointParameters& parameters) : p_(parameters) {}
  bool factorAndSolve(ShiftedSystem& system, const Eigen::VectorXd& rhs, Eigen::VectorXd* d,
                      double* shift) override;
  /// The floor rises to max(line_search_shift, growth × floor); false when it is at
  /// max_shift_floor already (the direction cannot be regularized further).
  bool afterRejection() override;
  /// The floor falls by the growth factor, to 0 below line_search_shift.
  void afterStep(double alpha, bool end_game) override;

 private:
  const InteriorPointParameters& p_;
  double floor_ = 0.0;
};

/// Free time: a shift times the mean |diagonal| of K (Shift::Rule::Uniform, the globals' corner
/// included: a row-relative shift would scale with the barrier terms of active bounds and stall
/// the step), from the damping (afterStep) or 0, then the first shift or, after a system that
/// needed one, that shift resumed (IPOPT's perturbation handler, Wächter & Biegler 2006, §3.1:
/// ÷ resumed_shift_divisor, i.e. κ_w⁻ = 1/3 applied as a division, as multiplying by the rounded
/// 1/3 would move the iterates; floor smallest_resumed_shift) and grown by resumed_shift_growth
/// (κ_w⁺; else by shift_growth), at most max_uniform_shift; accepted where K's inertia is
/// (n + m, 0, 0) and the step is a descent direction (dᵀrhs > 0). Plus the damping after steps
/// cut short (afterStep).
class PerturbationHandler final : public InertiaCorrection {
 public:
  explicit PerturbationHandler(const InteriorPointParameters& parameters) : p_(parameters) {}
  bool factorAndSolve(ShiftedSystem& system, const Eigen::VectorXd& rhs, Eigen::VectorXd* d,
                      double* shift) override;
  /// A Levenberg–Marquardt damping of the Newton step (the shift of factorAndSolve, from the
  /// first shift, ×growth per further cut step, ÷growth per full step, 0 below the smallest
  /// damping): where minimum time is flat along an arc (only the vanishing ε C curves it) the
  /// Newton step is long there and the constraints' curvature cuts it again and again
  /// (docs/notes/interior_point_tuning.md). The KKT point is the same, the path to it shorter.
  void afterStep(double alpha, bool end_game) override;

 private:
  const InteriorPointParameters& p_;
  double last_shift_ = 0.0;  ///< the last system's shift (0: none)
  double damping_ = 0.0;     ///< the damping (0: none)
  int cut_steps_ = 0;        ///< steps in a row cut below damping_cut_step
};

}  // namespace attitude_planner
