// The chain rule of the interior point's rows on one stage quantity, written once for both
// assemblers (constrained_system.cpp at a fixed h, free_time_solver.cpp with h free): the
// constraints on one quantity object (a block of quantityBlocks, stage_constraints.hpp) are
// contracted together, c_i = c_i(q) and λ = −Σ z_i c_i'(q), so that the quantity forms λ·∇²q in
// its own pass (StageQuantityModel::forEachTerms / forEachTermsWithTimeStep); then, from the
// instance's terms, ∇c_i = ∇qᵀ c_i'(q) and the Lagrangian's curvature on the instance's entries
//     −Σ z_i ∇²c_i = λ·∇²q − Σ z_i c_i'' ∇qᵀ∇q        (c_i'' the constraint's isotropic curvature).
// What each assembler does with a row afterwards (its barrier form's g gᵀ weight, the band's
// precision, the border) stays its own. The torque constraints ride in the cost's stencil pass
// instead (formedByCostStencil), where their weights fold into the cost's Gauss–Newton terms.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "planning/interior_point/barrier_forms.hpp"

namespace attitude_planner {

/// The rows of `block` at instance k with quantity value q: each row's value c(q), then
/// prepare(rows, row) (its barrier form's multiplier and condensation terms at that value);
/// returns λ = −Σ z c'(q), what the quantity contracts its curvature with.
template <int Entries, typename Prepare>
Vector3 contractQuantityRows(std::vector<ConstraintRows<Entries>>& groups,
                             const std::vector<int>& block, int k, const Vector3& q,
                             const Prepare& prepare) {
  Vector3 lambda = Vector3::Zero();
  for (const int i : block) {
    ConstraintRow<Entries>& in = groups[i].instance(k);
    in.c = groups[i].constraint->value(q);
    prepare(groups[i], in);
    lambda -= in.z * groups[i].constraint->gradient(q);
  }
  return lambda;
}

/// From one instance's terms (QuantityTerms, or QuantityTermsWithTimeStep with Entries = 10):
/// each row's gradient g = ∇qᵀ c'(q) and, with `curvature`, the Lagrangian's curvature on the
/// instance's entries, λ·∇²q − Σ z c'' ∇qᵀ∇q (the terms' curvature was contracted with
/// contractQuantityRows' λ).
template <int Entries, typename Terms>
void chainQuantityRows(std::vector<ConstraintRows<Entries>>& groups, const std::vector<int>& block,
                       const Terms& t, Eigen::Matrix<double, Entries, Entries>* curvature) {
  if (curvature) *curvature = t.curvature;
  for (const int i : block) {
    const StageConstraint& c = *groups[i].constraint;
    ConstraintRow<Entries>& in = groups[i].instance(t.k);
    in.g = t.jacobian.transpose() * c.gradient(t.value);
    if (curvature && c.curvature() != 0.0) {
      *curvature -= (in.z * c.curvature()) * t.jacobian.transpose() * t.jacobian;
    }
  }
}

}  // namespace attitude_planner
