// A step length below which every step is on its scheme's principal branch, proven from the
// inertia alone (principal_branch.cpp): the branch test of a whole plan skips its short steps.
#pragma once

#include "attitude_planner/dynamics/discrete_scheme.hpp"

namespace attitude_planner {

/// θ₀ ≥ 0 such that every step ω with |ω| < θ₀ has det(∂μ/∂ε) > 0 with the smallest singular
/// value of h ∂μ/∂ε at least λ_min(J)/2, so DiscreteScheme::onPrincipalBranch(ω) is true in
/// floating point too; 0 (no step skips the test) where the inertia's condition number exceeds
/// kPrincipalBranchConditionLimit, whose determinant's round-off that margin does not cover.
double principalBranchRadius(const DiscreteScheme& scheme);

inline constexpr double kPrincipalBranchConditionLimit = 1e3;

}  // namespace attitude_planner
