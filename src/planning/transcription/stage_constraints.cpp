// The stage constraints (stage_constraints.hpp): one class per kind.
#include "planning/transcription/stage_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/wheel_quantities.hpp"

namespace attitude_planner {

namespace {

/// One side of the actuator box: c = 1 − σ τ_a/a (σ = +1 upper, −1 lower).
class TorqueBoxSide final : public StageConstraint {
 public:
  TorqueBoxSide(std::shared_ptr<const StageQuantityModel> torque, int axis, double limit,
                double sign)
      : StageConstraint(std::move(torque), nullptr), axis_(axis), limit_(limit), sign_(sign) {}
  double value(const Vector3& tau) const override { return 1.0 - sign_ * tau(axis_) / limit_; }
  Vector3 gradient(const Vector3&) const override {
    Vector3 g = Vector3::Zero();
    g(axis_) = -sign_ / limit_;
    return g;
  }
  int axis() const override { return axis_; }
  std::string describe() const override {
    static const char* kAxis[] = {"x", "y", "z"};
    std::ostringstream s;
    s << "|tau_" << kAxis[axis_] << "| <= " << limit_ << " N m";
    return s.str();
  }
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return limit_ - sign_ * quantityModel().valueOnPlan(plan, k)(axis_);
  }
  double slackScale() const override { return limit_; }
  double rowValue(const Vector3& tau) const override { return tau(axis_); }
  Vector3 rowGradient(const Vector3&) const override { return Vector3::Unit(axis_); }
  double rowLower() const override { return sign_ > 0 ? StageConstraint::rowLower() : -limit_; }
  double rowUpper() const override { return sign_ > 0 ? limit_ : StageConstraint::rowUpper(); }

 private:
  int axis_;
  double limit_, sign_;
};

/// max_torque_norm t: c = 1 − |τ|²/t².
class TorqueNorm final : public StageConstraint {
 public:
  TorqueNorm(std::shared_ptr<const StageQuantityModel> torque, const PlanningConstraint* spec)
      : StageConstraint(std::move(torque), spec), limit_(spec->limit) {}
  double value(const Vector3& tau) const override {
    return 1.0 - tau.squaredNorm() / (limit_ * limit_);
  }
  Vector3 gradient(const Vector3& tau) const override { return -2.0 / (limit_ * limit_) * tau; }
  double curvature() const override { return -2.0 / (limit_ * limit_); }
  std::string describe() const override { return describeConstraint(*spec()); }
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return limit_ - quantityModel().valueOnPlan(plan, k).norm();
  }
  double slackScale() const override { return limit_; }
  /// g = |τ|²/t² ≤ 1.
  double rowValue(const Vector3& tau) const override {
    return tau.squaredNorm() / (limit_ * limit_);
  }
  Vector3 rowGradient(const Vector3& tau) const override { return 2.0 * tau / (limit_ * limit_); }
  double rowCurvature() const override { return 2.0 / (limit_ * limit_); }
  double rowUpper() const override { return 1.0; }

 private:
  double limit_;
};

/// max_angular_rate w on q = ½|Ω|² (a step's or a node's): c = 1 − 2q/w².
class AngularRate final : public StageConstraint {
 public:
  AngularRate(std::shared_ptr<const StageQuantityModel> rate, const PlanningConstraint* spec)
      : StageConstraint(std::move(rate), spec),
        limit_(spec->limit),
        slope_(-2.0 / (spec->limit * spec->limit)) {}
  double value(const Vector3& q) const override { return 1.0 + slope_ * q(0); }
  Vector3 gradient(const Vector3&) const override { return Vector3(slope_, 0.0, 0.0); }
  std::string describe() const override { return describeConstraint(*spec()); }
  /// On the plan's reported Ω_k (the scheme's node or step rate).
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return limit_ - quantityModel().valueOnPlan(plan, k).norm();
  }
  double slackScale() const override { return limit_; }
  /// The motion between nodes turns at log(F_k)/h (a scheme's reported Ω_k may differ from it by
  /// O(h²)).
  double slackBetweenNodes(const Maneuver& plan, int k) const override {
    const Matrix3 F = plan.attitude[k].transpose() * plan.attitude[k + 1];
    return limit_ - so3::log(F).norm() / plan.time_step;
  }
  /// g = |Ω|²/w² ≤ 1.
  double rowValue(const Vector3& omega) const override {
    return omega.squaredNorm() / (limit_ * limit_);
  }
  Vector3 rowGradient(const Vector3& omega) const override {
    return 2.0 * omega / (limit_ * limit_);
  }
  double rowCurvature() const override { return 2.0 / (limit_ * limit_); }
  double rowUpper() const override { return 1.0; }

 private:
  double limit_;  ///< w [rad/s]
  double slope_;  ///< −2/w²
};

/// keep_out / keep_in on the pointing cosine p = sᵀR b: c = ±(p − cos α), α the node half angle
/// (keep_out: cos α − p ≥ 0, the axis at least α from s; keep_in: p − cos α ≥ 0).
class PointingCone final : public StageConstraint {
 public:
  explicit PointingCone(const PlanningConstraint* spec)
      : StageConstraint(makePointingQuantity(spec->body_axis, spec->world_direction), spec),
        sign_(spec->kind == ConstraintKind::KeepOut ? -1.0 : 1.0),
        bound_(std::cos(spec->nodeHalfAngle())) {}
  double value(const Vector3& p) const override { return sign_ * (p(0) - bound_); }
  Vector3 gradient(const Vector3&) const override { return Vector3(sign_, 0.0, 0.0); }
  std::string describe() const override { return describeConstraint(*spec()); }
  /// The angle's margin (coneMargin on the attitude: atan2, accurate at every angle, where acos
  /// of the quantity's cosine would not be).
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return coneMargin(*spec(), plan.attitude[k]);
  }
  double nodeTightening() const override { return spec()->margin; }
  double slackScale() const override { return 1.0; }
  double slackBetweenNodes(const Maneuver& plan, int k) const override {
    return coneMarginOverStep(*spec(), plan.attitude[k], plan.attitude[k + 1]);
  }
  /// g = p, keep_out: p ≤ cos α; keep_in: p ≥ cos α.
  double rowValue(const Vector3& p) const override { return p(0); }
  Vector3 rowGradient(const Vector3&) const override { return Vector3::UnitX(); }
  double rowLower() const override { return sign_ > 0 ? bound_ : StageConstraint::rowLower(); }
  double rowUpper() const override { return sign_ > 0 ? StageConstraint::rowUpper() : bound_; }

 private:
  double sign_, bound_;
};

}  // namespace

StageConstraints buildStageConstraints(const PlanningProblem& problem) {
  StageConstraints out;
  // One quantity object per quantity: the constraints on it share one pass over the band.
  const std::shared_ptr<const StageQuantityModel> torque = makeTorqueQuantity();
  const std::shared_ptr<const StageQuantityModel> rate =
      makeRateQuantity(schemeHasEndTorques(problem.scheme), problem.inertia);
  if (problem.hasTorqueBounds()) {
    for (int a = 0; a < 3; ++a) {
      for (const double sign : {1.0, -1.0}) {
        out.push_back(std::make_unique<TorqueBoxSide>(torque, a, problem.max_torque(a), sign));
      }
    }
  }
  for (const PlanningConstraint& c : problem.constraints) {
    switch (c.kind) {
      case ConstraintKind::MaxTorqueNorm:
        out.push_back(std::make_unique<TorqueNorm>(torque, &c));
        break;
      case ConstraintKind::MaxAngularRate:
        out.push_back(std::make_unique<AngularRate>(rate, &c));
        break;
      case ConstraintKind::KeepOut:
      case ConstraintKind::KeepIn:
        out.push_back(std::make_unique<PointingCone>(&c));
        break;
    }
  }
  appendWheelConstraints(problem, &out);
  return out;
}

QuantityBlocks quantityBlocks(const StageConstraints& constraints) {
  QuantityBlocks out;
  std::vector<const StageQuantityModel*> quantities;  // one per block
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const StageQuantityModel* q = &constraints[i]->quantityModel();
    if (q->formedByCostStencil()) {
      out.on_cost_stencil.push_back(static_cast<int>(i));
      continue;
    }
    const auto known = std::find(quantities.begin(), quantities.end(), q);
    if (known == quantities.end()) {
      quantities.push_back(q);
      out.blocks.push_back({static_cast<int>(i)});
    } else {
      out.blocks[known - quantities.begin()].push_back(static_cast<int>(i));
    }
  }
  return out;
}

namespace {

/// The running figures of checkConstraints.
struct CheckTally {
  ConstraintCheck out;
  int worst_k = -1;

  /// One instance: `slack` to the stated limit (≥ 0: holds; violations are measured against
  /// it), `node_slack` to the bound the planner imposes (activity), against `scale`.
  void node(double slack, double node_slack, double scale, const std::string& what, int k) {
    if (node_slack <= kActiveConstraintTolerance * scale) ++out.active;
    out.max_node_bound_violation = std::max(out.max_node_bound_violation, -node_slack);
    out.max_violation_between_nodes = std::max(out.max_violation_between_nodes, -slack);
    // The solver's verdict (planInconsistency) is on the bound it was asked to meet.
    out.max_relative_violation = std::max(out.max_relative_violation, -node_slack / scale);
    if (-slack > out.max_violation) {
      out.max_violation = -slack;
      out.worst = what;
      worst_k = k;  // worst_where is written once, at the end
    }
  }
  void between(double slack) {
    out.max_violation_between_nodes = std::max(out.max_violation_between_nodes, -slack);
  }
};

}  // namespace

ConstraintCheck checkConstraints(const PlanningProblem& problem, const Maneuver& maneuver) {
  CheckTally tally;
  ConstraintCheck& out = tally.out;
  if (problem.hasTorqueBounds()) out.names.push_back("actuator_limits");
  for (const PlanningConstraint& c : problem.constraints)
    out.names.push_back(constraintKindName(c.kind));
  if (problem.reaction_wheels.present()) out.names.push_back("reaction_wheels");
  const int N = maneuver.steps();
  const bool end_torques = schemeHasEndTorques(problem.scheme);
  for (const auto& c : buildStageConstraints(problem)) {
    // Formed once: a stream per node cost as much as the solve's replay (measured, N = 128).
    const std::string what = c->describe();
    const StageSupport s = c->quantityModel().planSupport(end_torques, N);
    for (int k = s.first_k; k <= s.last_k; ++k) {
      const double slack = c->slackOnPlan(maneuver, k);
      tally.node(slack, slack - c->nodeTightening(), c->slackScale(), what, k);
      if (k < N) tally.between(c->slackBetweenNodes(maneuver, k));
    }
  }
  if (tally.worst_k >= 0) {
    std::ostringstream w;
    w << "by " << out.max_violation << " at k = " << tally.worst_k
      << " (t = " << tally.worst_k * maneuver.time_step << " s)";
    out.worst_where = w.str();
  }
  return out;
}

std::string fixedNodeConeViolation(const PlanningProblem& problem, const ReducedProblem& np,
                                   std::initializer_list<int> nodes) {
  const std::vector<Matrix3> R = np.attitudes(np.current());
  for (const PlanningConstraint& c : problem.constraints) {
    if (!c.isCone()) continue;
    for (const int k : nodes) {
      if (np.variableIndex(k) >= 0) continue;
      const double slack = coneMargin(c, R[k]) - c.margin;  // to the node bound
      if (slack < 0.0) {
        std::ostringstream why;
        why << describeConstraint(c) << " is violated by " << -slack << " rad at k = " << k;
        return why.str();
      }
    }
  }
  return "";
}

}  // namespace attitude_planner
