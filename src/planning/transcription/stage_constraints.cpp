// The stage constraints (stage_constraints.hpp): one class per kind.
#include "planning/transcription/stage_constraints.hpp"

#include <cmath>
#include <sstream>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

/// One side of the actuator box: c = 1 − σ τ_a/a (σ = +1 upper, −1 lower).
class TorqueBoxSide final : public StageConstraint {
 public:
  TorqueBoxSide(int axis, double limit, double sign)
      : StageConstraint(StageQuantity::Torque, nullptr), axis_(axis), limit_(limit), sign_(sign) {}
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
    s << (sign_ > 0 ? "tau_" : "-tau_") << kAxis[axis_] << " <= " << limit_ << " N m";
    return s.str();
  }

 private:
  int axis_;
  double limit_, sign_;
};

/// max_torque_norm t: c = 1 − |τ|²/t².
class TorqueNorm final : public StageConstraint {
 public:
  explicit TorqueNorm(const PlanningConstraint* spec)
      : StageConstraint(StageQuantity::Torque, spec), limit_(spec->limit) {}
  double value(const Vector3& tau) const override {
    return 1.0 - tau.squaredNorm() / (limit_ * limit_);
  }
  Vector3 gradient(const Vector3& tau) const override { return -2.0 / (limit_ * limit_) * tau; }
  double curvature() const override { return -2.0 / (limit_ * limit_); }
  std::string describe() const override { return describeConstraint(*spec()); }

 private:
  double limit_;
};

/// max_angular_rate w on q = ½|Ω|² (a step's or a node's): c = 1 − 2q/w².
class AngularRate final : public StageConstraint {
 public:
  AngularRate(const PlanningConstraint* spec, StageQuantity quantity)
      : StageConstraint(quantity, spec), slope_(-2.0 / (spec->limit * spec->limit)) {}
  double value(const Vector3& q) const override { return 1.0 + slope_ * q(0); }
  Vector3 gradient(const Vector3&) const override { return Vector3(slope_, 0.0, 0.0); }
  std::string describe() const override { return describeConstraint(*spec()); }

 private:
  double slope_;  ///< −2/w²
};

/// keep_out / keep_in on the pointing cosine p = sᵀR b: c = ±(p − cos α), α the node half angle
/// (keep_out: cos α − p ≥ 0, the axis at least α from s; keep_in: p − cos α ≥ 0).
class PointingCone final : public StageConstraint {
 public:
  explicit PointingCone(const PlanningConstraint* spec)
      : StageConstraint(StageQuantity::Pointing, spec),
        sign_(spec->kind == ConstraintKind::KeepOut ? -1.0 : 1.0),
        bound_(std::cos(spec->nodeHalfAngle())) {}
  double value(const Vector3& p) const override { return sign_ * (p(0) - bound_); }
  Vector3 gradient(const Vector3&) const override { return Vector3(sign_, 0.0, 0.0); }
  std::string describe() const override { return describeConstraint(*spec()); }

 private:
  double sign_, bound_;
};

}  // namespace

StageSupport stageSupport(StageQuantity quantity, int first_free, int last_free) {
  const int first = first_free - 1, last = last_free + 1;  // the torques' range
  switch (quantity) {
    case StageQuantity::Torque:
      return {first, last, -1, 3};
    case StageQuantity::StepRate:
      return {first, last - 1, 0, 2};
    case StageQuantity::NodeRate:
      return {first + 1, last - 1, -1, 3};
    case StageQuantity::Pointing:
      return {first + 1, last - 1, 0, 1};
  }
  return {};
}

bool quantityDependsOnTimeStep(StageQuantity quantity) {
  return quantity != StageQuantity::Pointing;
}

StageConstraints buildStageConstraints(const PlanningProblem& problem) {
  StageConstraints out;
  if (problem.hasTorqueBounds()) {
    for (int a = 0; a < 3; ++a) {
      for (const double sign : {1.0, -1.0}) {
        out.push_back(std::make_unique<TorqueBoxSide>(a, problem.max_torque(a), sign));
      }
    }
  }
  const StageQuantity rate =
      schemeHasEndTorques(problem.scheme) ? StageQuantity::NodeRate : StageQuantity::StepRate;
  for (const PlanningConstraint& c : problem.constraints) {
    switch (c.kind) {
      case ConstraintKind::MaxTorqueNorm:
        out.push_back(std::make_unique<TorqueNorm>(&c));
        break;
      case ConstraintKind::MaxAngularRate:
        out.push_back(std::make_unique<AngularRate>(&c, rate));
        break;
      case ConstraintKind::KeepOut:
      case ConstraintKind::KeepIn:
        out.push_back(std::make_unique<PointingCone>(&c));
        break;
    }
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
