// The interior point's line search: Armijo backtracking on φ_μ over a BarrierProblem, with a
// second-order correction of a rejected full step, in two profiles (fixed h, free time).
#pragma once

#include <Eigen/Core>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "planning/interior_point/barrier_problem.hpp"

namespace attitude_planner {

/// One profile's values.
struct LineSearchProfile {
  double armijo = 1e-4;    ///< η: accept φ(α) ≤ φ(0) + η α ∇φᵀd
  int max_halvings = 60;   ///< trial step lengths, halving from α₀
  int floor_halvings = 5;  ///< the same at the round-off floor (LineSearchRequest::at_floor)
  double merit_round_off = 1e-14;  ///< a predicted decrease ≤ this × |φ| is round-off
  /// A step whose predicted decrease is round-off is taken outright (fixed h: no step length can
  /// be told from another there); else it is searched and only flagged (free time), but for one
  /// at the round-off floor (LineSearchRequest::at_floor), which is not taken.
  bool take_round_off_step = true;
  /// In the end game (LineSearchRequest::late) every rejected trial step α d, the full one and
  /// each halving, is retried once with its second-order correction before the next halving
  /// (BarrierProblem::correctedStep). The boundary, not the merit, cuts the steps of a feasible
  /// method there: a constraint's curvature along d carries the trial outside while its linear
  /// model still grows, at whatever α the halving has reached.
  bool second_order_correction = false;
};
/// Fixed h: armijo, the fixed-step profile's halvings; round-off steps taken; no correction.
LineSearchProfile fixedStepLineSearch(const InteriorPointParameters& parameters);
/// Free time: armijo, the free-time profile's halvings; round-off steps flagged; the correction.
LineSearchProfile freeTimeLineSearch(const InteriorPointParameters& parameters);

/// One search's inputs from the loop.
struct LineSearchRequest {
  double slope = 0.0;   ///< ∇φ_μᵀd (< 0 for a descent direction)
  double alpha0 = 1.0;  ///< the first step length (fixed h, free slacks: the slacks' fraction)
  bool take_outright = false;  ///< the barrier problem's last step: taken without a search
  bool at_floor = false;       ///< at the round-off floor: floor_halvings trials only
  bool late = false;           ///< the second-order correction may be tried
};

struct LineSearchResult {
  bool accepted = false;
  double alpha = 0.0;         ///< the accepted step length
  bool at_round_off = false;  ///< the predicted decrease was round-off
};

/// Armijo backtracking: the accepted iterate's φ_μ, the full (or corrected) step, then halvings;
/// the iterate is left at the accepted trial point, or restored.
class ArmijoBacktracking {
 public:
  explicit ArmijoBacktracking(const LineSearchProfile& profile) : profile_(profile) {}
  /// `d` may be replaced by its second-order correction when that is the step taken.
  LineSearchResult search(BarrierProblem& problem, const LineSearchRequest& request,
                          Eigen::VectorXd* d) const;

 private:
  /// Whether the trial α d, else its second-order correction, meets the Armijo condition at α.
  bool correctedTrial(BarrierProblem& problem, double phi, double slope, double* alpha,
                      Eigen::VectorXd* d) const;
  LineSearchProfile profile_;
};

}  // namespace attitude_planner
