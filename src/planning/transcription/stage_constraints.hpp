// Stage constraints: every node constraint of a request (the actuator box and the scene's
// `constraints:`) as one kind of object behind one interface, so that the solvers assemble them by
// looping over a list instead of switching on kinds.
//
// Each constraint c ≥ 0 (dimensionless) is a function of ONE stage quantity q of the transcription
// (StageQuantity): the torque τ_k, the half squared rate ½|Ω|² of a step or of a node, or the
// pointing cosine sᵀR_k b. The constraint knows c(q) and its derivatives in q; the transcription
// knows q's derivatives in the unknowns (ReducedProblem's stencils and node momenta,
// node_constraints.hpp's angularRateTerms and pointingTerms) and, where q depends on the time step,
// in h (ReducedProblem::forEachStencilWithTimeStep). The assemblers (interior_point/
// constrained_system at a fixed h, interior_point/free_time_solver with h free) apply the chain
// rule: ∇c = c'(q) ∇q, ∇²c = c'(q) ∇²q + ∇qᵀ c''(q) ∇q.
//
// The same objects serve the two other places that read constraints, so that adding a kind is one
// class: the plan's check (checkConstraints: each constraint's slack in its physical unit on the
// plan's torques, rates or attitudes, at the nodes and between them), and the dense NLPs (the NLopt
// cross-check, the IPOPT peer in studies/benchmark_solvers.cpp: each constraint as a row
// lower ≤ g(r) ≤ upper in its quantity's plain form r). Those places switch on the quantity (how
// their own transcription forms τ_k, Ω_k or the pointing cosine), never on the kind.
#pragma once

#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

class ReducedProblem;

/// What a stage constraint is a function of: its support on the band and its h dependence.
enum class StageQuantity {
  Torque,  ///< q = τ_k [N m] (3-vector) on R_{k−1}, R_k, R_{k+1}; moves with h
  StepRate,  ///< q = ½|Ω_k|² [rad²/s²] of step F_k = R_kᵀR_{k+1} (paper, variational); moves with h
  NodeRate,  ///< q = ½|J⁻¹Π_k|² [rad²/s²] of node k (schemes with end torques) on R_{k−1..k+1};
             ///< moves with h
  Pointing,  ///< q = sᵀR_k b (the cosine of the angle between R_k b and s) on R_k; no h
};

/// Where the instances of a quantity sit: k = first_k..last_k, each on the nodes
/// k + node_offset .. k + node_offset + width − 1 (at most three: the band is kept).
struct StageSupport {
  int first_k = 0, last_k = 0;
  int node_offset = 0;
  int width = 1;
};

/// The support of `quantity` on a reduced problem whose free attitudes are
/// R_first_free..R_last_free (torques k = first_free − 1..last_free + 1; step rates the steps
/// between them and their neighbours, the boundary steps excluded (boundary data); node rates and
/// cones the free nodes, the fixed attitudes being checked up front).
StageSupport stageSupport(StageQuantity quantity, int first_free, int last_free);

/// True where q changes with the time step at fixed free attitudes (all but Pointing).
bool quantityDependsOnTimeStep(StageQuantity quantity);

/// The instances k = first_k..last_k of a quantity on a plan of `steps` steps (checkConstraints):
/// the torques the plan carries (1..N−1; 0..N with end torques), the step rates 0..N−1 (the
/// plan's reported Ω_k), node rates and cones 0..N.
StageSupport planSupport(StageQuantity quantity, bool end_torques, int steps);

/// One node constraint c(q) ≥ 0, imposed at every instance of its quantity.
class StageConstraint {
 public:
  virtual ~StageConstraint() = default;
  StageQuantity quantity() const { return quantity_; }
  /// The scene's constraint this one imposes (null: a side of the actuator box).
  const PlanningConstraint* spec() const { return spec_; }

  /// c(q), dimensionless (scalar quantities in q(0)).
  virtual double value(const Vector3& q) const = 0;
  /// ∂c/∂q (scalar quantities: in entry 0, the others 0).
  virtual Vector3 gradient(const Vector3& q) const = 0;
  /// ∇²_q c = curvature()·I (every kind here has an isotropic second derivative, most zero).
  virtual double curvature() const { return 0.0; }
  /// ≥ 0: c is affine in this one component of q (a torque box side). Its g gᵀ/D then folds into
  /// that axis's Gauss–Newton weight of the stencil (ConstrainedSystem's precision rule: the
  /// rank-one terms are formed in the band's precision, which a constraint at its bound needs at
  /// N ≥ 1e4).
  virtual int axis() const { return -1; }
  /// One line for messages and the checker (ConstraintCheck::worst), one wording per rule:
  /// describeConstraint's for the scene's constraints ("max_torque_norm 0.45 N m"), the box's
  /// rule for both of its sides ("|tau_y| <= 0.3 N m").
  virtual std::string describe() const = 0;

  // The plan's check (checkConstraints), in the constraint's physical unit (N m, rad/s, rad),
  // against the stated limit (not the dimensionless c, which a cone states at its node bound).
  /// The slack at instance k of `plan` (planSupport), ≥ 0 where the limit holds.
  virtual double slackOnPlan(const Maneuver& plan, int k) const = 0;
  /// How much tighter the node bound the planner imposes is, same unit (a cone's margin).
  virtual double nodeTightening() const { return 0.0; }
  /// The unit a violation is relative to (the limit; 1 rad for cones).
  virtual double slackScale() const = 0;
  /// The least slack over the motion between instances k and k + 1, R_k exp(s ω_k^) (+∞ where
  /// the node values bound it: torques are held, or interpolated linearly under a convex bound).
  virtual double slackBetweenNodes(const Maneuver&, int) const {
    return std::numeric_limits<double>::infinity();
  }

  // The constraint as a row of a dense NLP: lower ≤ g(r) ≤ upper, r the quantity's plain form
  // (τ_k; Ω_k, not squared; the pointing cosine in r(0)), one side finite. A box side (axis() ≥ 0)
  // is a bound on one variable there: g = τ_axis.
  virtual double rowValue(const Vector3& r) const = 0;
  /// ∂g/∂r (scalar quantities: in entry 0).
  virtual Vector3 rowGradient(const Vector3& r) const = 0;
  /// ∇²_r g = rowCurvature()·I (scalar quantities: d²g/dr²).
  virtual double rowCurvature() const { return 0.0; }
  virtual double rowLower() const { return -std::numeric_limits<double>::infinity(); }
  virtual double rowUpper() const { return std::numeric_limits<double>::infinity(); }

 protected:
  StageConstraint(StageQuantity quantity, const PlanningConstraint* spec)
      : quantity_(quantity), spec_(spec) {}

 private:
  StageQuantity quantity_;
  const PlanningConstraint* spec_;
};

using StageConstraints = std::vector<std::unique_ptr<const StageConstraint>>;

/// Every stage constraint of `problem`, in a fixed order: the actuator box (per finite axis a =
/// 0, 1, 2: upper side, lower side), then `problem.constraints` in their order (the rate limit on
/// the node rates for schemes with end torques, else on the step rates). The list points into
/// `problem.constraints`: `problem` must outlive it.
StageConstraints buildStageConstraints(const PlanningProblem& problem);

/// The first cone whose node bound (a ± its margin) is violated at one of `nodes` that the
/// boundary data fix (no unknown of `np`): "<describeConstraint> is violated by x rad at k = K",
/// or empty. No plan on this grid can repair it.
std::string fixedNodeConeViolation(const PlanningProblem& problem, const ReducedProblem& np,
                                   std::initializer_list<int> nodes);

}  // namespace attitude_planner
