// Stage constraints: every node constraint of a request (the actuator box and the scene's
// `constraints:`) as one kind of object behind one interface, so that the solvers assemble them by
// looping over a list instead of switching on kinds.
//
// Each constraint c ≥ 0 (dimensionless) is a function of ONE stage quantity q of the transcription
// (StageQuantityModel, stage_quantities.hpp): the torque τ_k, the half squared rate ½|Ω|² of a
// step or of a node, or the pointing cosine sᵀR_k b. The constraint knows c(q) and its
// derivatives in q; the quantity knows q's value, support and derivatives in the unknowns and in
// h. The assemblers (interior_point/constrained_system at a fixed h, interior_point/
// free_time_solver with h free) apply the chain rule: ∇c = c'(q) ∇q, ∇²c = c'(q) ∇²q +
// ∇qᵀ c''(q) ∇q, asking the quantity, never switching on it.
//
// The same objects serve the two other places that read constraints, so that adding a kind is one
// class: the plan's check (checkConstraints: each constraint's slack in its physical unit on the
// plan's torques, rates or attitudes, at the nodes and between them), and the dense NLPs (the NLopt
// cross-check, the IPOPT peer in studies/benchmark_solvers.cpp: each constraint as a row
// lower ≤ g(r) ≤ upper in its quantity's plain form r). Those dense NLPs switch on the quantity's
// name (their own transcription forms τ_k, Ω_k or the pointing cosine: independent derivatives on
// purpose), never on the kind.
#pragma once

#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "planning/transcription/stage_quantities.hpp"

namespace attitude_planner {

class ReducedProblem;

/// One node constraint c(q) ≥ 0, imposed at every instance of its quantity.
class StageConstraint {
 public:
  virtual ~StageConstraint() = default;
  StageQuantity quantity() const { return quantity_->kind(); }
  /// The quantity q this constraint is a function of (shared with the other constraints on it).
  const StageQuantityModel& quantityModel() const { return *quantity_; }
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
  StageConstraint(std::shared_ptr<const StageQuantityModel> quantity,
                  const PlanningConstraint* spec)
      : quantity_(std::move(quantity)), spec_(spec) {}

 private:
  std::shared_ptr<const StageQuantityModel> quantity_;
  const PlanningConstraint* spec_;
};

using StageConstraints = std::vector<std::unique_ptr<const StageConstraint>>;

/// Every stage constraint of `problem`, in a fixed order: the actuator box (per finite axis a =
/// 0, 1, 2: upper side, lower side), then `problem.constraints` in their order (the rate limit on
/// the node rates for schemes with end torques, else on the step rates). The list points into
/// `problem.constraints`: `problem` must outlive it.
StageConstraints buildStageConstraints(const PlanningProblem& problem);

/// A list's constraints by quantity object, as indices into the list: those on the cost's stencil
/// residuals (formedByCostStencil: the torques, assembled in the cost's own pass), and the others
/// in one block per quantity (first appearance order), each block assembled in one pass.
struct QuantityBlocks {
  std::vector<int> on_cost_stencil;
  std::vector<std::vector<int>> blocks;
};
QuantityBlocks quantityBlocks(const StageConstraints& constraints);

/// The first cone whose node bound (a ± its margin) is violated at one of `nodes` that the
/// boundary data fix (no unknown of `np`): "<describeConstraint> is violated by x rad at k = K",
/// or empty. No plan on this grid can repair it.
std::string fixedNodeConeViolation(const PlanningProblem& problem, const ReducedProblem& np,
                                   std::initializer_list<int> nodes);

}  // namespace attitude_planner
