// The stage quantities (stage_quantities.hpp): one class per quantity.
#include "planning/transcription/stage_quantities.hpp"

#include <cmath>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "planning/transcription/node_constraints.hpp"
#include "planning/transcription/stage_transcription.hpp"
#include "planning/transcription/wheel_quantities.hpp"

namespace attitude_planner {

const std::vector<Vector3>& QuantityInputs::torques() const {
  if (!torques_) torques_ = np_.torques(steps_);
  return *torques_;
}

const std::vector<Matrix3>& QuantityInputs::attitudes() const {
  if (!attitudes_) attitudes_ = np_.attitudes(steps_);
  return *attitudes_;
}

const std::vector<Vector3>& QuantityInputs::nodeMomenta() const {
  if (node_momenta_) return *node_momenta_;
  const int N = np_.steps();
  const DiscreteScheme& scheme = np_.scheme();
  std::vector<Vector3> step_momenta(N);
  for (int k = 0; k < N; ++k) step_momenta[k] = scheme.momentumOfStep(steps_[k]);
  node_momenta_.emplace(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) {
    (*node_momenta_)[k] =
        0.5 * (step_momenta[k] + so3::exp(steps_[k - 1]).transpose() * step_momenta[k - 1]);
  }
  return *node_momenta_;
}

namespace {

/// The support every kind shares: the torques' range k = first_free − 1..last_free + 1.
struct FreeRange {
  int first, last;
  FreeRange(int first_free, int last_free) : first(first_free - 1), last(last_free + 1) {}
};

/// A scalar quantity's ∇q, ∇²q over (local nodes, h) from its node derivatives and how q moves
/// with h. A rate moves with h in two ways: at fixed free attitudes every momentum scales like
/// 1/h, and the attitudes a boundary rate fixes move with h (ReducedProblem::nodePath: R_1,
/// R_{N−1} of paper and variational, whose boundary steps honour Ω(0), Ω(T) at every h; none for
/// second_order), as node perturbations d(h) = e Δh + ½ e₂ Δh². So q(δ, h) = s(h) q̃(δ + d(h)),
/// s = (h₀/h)², and at h₀
///     ∂q/∂h = s'q + ∇qᵀe,   ∂∇q/∂h = s'∇q + ∇²q e,   ∂²q/∂h² = s''q + 2s'∇qᵀe + eᵀ∇²q e + ∇qᵀe₂,
/// s' = −2/h, s'' = 6/h² (rest to rest e = e₂ = 0: q = q̃/h²); in η = h/time_scale times
/// time_scale, time_scale².
QuantityTermsWithTimeStep rateTermsWithTimeStep(const ReducedProblem& np,
                                                const StageSupport& support, double time_scale,
                                                int k, double q,
                                                const Eigen::Matrix<double, 9, 1>& gradient,
                                                const Eigen::Matrix<double, 9, 9>& hessian,
                                                double lambda) {
  const double h = np.timeStep();
  const double s1 = -2.0 / h, s2 = 6.0 / (h * h);
  Eigen::Matrix<double, 9, 1> e = Eigen::Matrix<double, 9, 1>::Zero(), e2 = e;
  for (int node = 0; node < support.width; ++node) {
    const ReducedProblem::BoundaryPath path = np.nodePath(k + support.node_offset + node);
    e.segment<3>(3 * node) = path.first;
    e2.segment<3>(3 * node) = path.second;
  }
  const Eigen::Matrix<double, 9, 1> He = hessian * e;
  QuantityTermsWithTimeStep out;
  out.k = k;
  out.value(0) = q;
  out.jacobian.block<1, 9>(0, 0) = gradient.transpose();
  out.jacobian(0, 9) = (s1 * q + gradient.dot(e)) * time_scale;
  Eigen::Matrix<double, 10, 10> d2q;
  d2q.topLeftCorner<9, 9>() = hessian;
  d2q.block<9, 1>(0, 9) = (s1 * gradient + He) * time_scale;
  d2q.block<1, 9>(9, 0) = d2q.block<9, 1>(0, 9).transpose();
  d2q(9, 9) =
      (s2 * q + 2 * s1 * gradient.dot(e) + e.dot(He) + gradient.dot(e2)) * time_scale * time_scale;
  out.curvature = lambda * d2q;
  return out;
}

/// q = τ_k: the cost's stencil residual r_k = √w_k τ_k over the root √w_k.
class TorqueQuantity final : public StageQuantityModel {
 public:
  StageQuantity kind() const override { return StageQuantity::Torque; }
  StageSupport support(int first_free, int last_free) const override {
    const FreeRange r(first_free, last_free);
    return {r.first, r.last, -1, 3};
  }
  StageSupport planSupport(bool end_torques, int steps) const override {
    return end_torques ? StageSupport{0, steps, 0, 1} : StageSupport{1, steps - 1, 0, 1};
  }
  bool dependsOnTimeStep() const override { return true; }
  bool formedByCostStencil() const override { return true; }
  Vector3 value(const QuantityInputs& at, int k) const override { return at.torques()[k]; }
  Vector3 valueOnPlan(const Maneuver& plan, int k) const override { return plan.torque[k]; }

  /// Σ_i λ_i ∇²τ_i = Σ_i (λ_i/√w_k) ∇²r_i: the stencil's `second` with weights λ/√w_k.
  void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                    const QuantityContraction& contract, const TermsVisitor& visit) const override {
    const auto weights = [&](int k, const Vector3& r) {
      if (k < support.first_k || k > support.last_k) return Vector3(Vector3::Zero());
      const double root = rootWeight(np, k);
      return Vector3(contract(k, r / root) / root);
    };
    np.forEachStencil(
        true,
        [&](const ReducedProblem::Stencil& st) {
          if (st.k < support.first_k || st.k > support.last_k) return;
          const double root = rootWeight(np, st.k);
          QuantityTerms t;
          t.k = st.k;
          t.value = st.tau / root;
          t.jacobian = st.jacobian / root;
          t.curvature = st.second;
          visit(t);
        },
        weights);
  }
  void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                double time_scale, const QuantityContraction& contract,
                                const TimeStepTermsVisitor& visit) const override {
    const auto weights = [&](int k, const Vector3& r) {
      if (k < support.first_k || k > support.last_k) return Vector3(Vector3::Zero());
      const double root = rootWeight(np, k);
      return Vector3(contract(k, r / root) / root);
    };
    np.forEachStencilWithTimeStep(
        [&](const ReducedProblem::TimeStepStencil& st) {
          if (st.k < support.first_k || st.k > support.last_k) return;
          const double root = rootWeight(np, st.k);
          QuantityTermsWithTimeStep t;
          t.k = st.k;
          t.value = st.tau / root;
          const FreeTimeStep step{time_scale};
          t.jacobian = step.jacobian(st) / root;
          t.curvature = step.second(st);
          visit(t);
        },
        weights);
  }

 private:
  static double rootWeight(const ReducedProblem& np, int k) {
    return std::sqrt(np.scheme().torqueWeight(k, np.steps()));
  }
};

/// q = ½|Ω|², of a step or of a node: the shared h-derivatives and plan value.
class RateQuantity : public StageQuantityModel {
 public:
  bool dependsOnTimeStep() const override { return true; }
  /// The plan's reported Ω_k (the scheme's step or node rate).
  Vector3 valueOnPlan(const Maneuver& plan, int k) const override {
    return plan.angular_velocity[k];
  }
};

/// ½|Ω_k|² of step F_k (paper, variational): angularRateTerms on (δ_k, δ_{k+1}).
class StepRateQuantity final : public RateQuantity {
 public:
  StageQuantity kind() const override { return StageQuantity::StepRate; }
  /// The steps between the free attitudes and their neighbours, the boundary steps excluded
  /// (boundary data).
  StageSupport support(int first_free, int last_free) const override {
    const FreeRange r(first_free, last_free);
    return {r.first, r.last - 1, 0, 2};
  }
  StageSupport planSupport(bool, int steps) const override { return {0, steps - 1, 0, 2}; }
  Vector3 value(const QuantityInputs& at, int k) const override {
    const DiscreteScheme& scheme = at.problem().scheme();
    return Vector3(0.5 * scheme.velocity(so3::exp(at.steps()[k])).squaredNorm(), 0.0, 0.0);
  }
  void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                    const QuantityContraction& contract, const TermsVisitor& visit) const override {
    for (int k = support.first_k; k <= support.last_k; ++k) {
      const AngularRateTerms r = angularRateTerms(np.scheme(), np.current()[k]);
      QuantityTerms t;
      t.k = k;
      t.value(0) = r.half_squared_rate;
      t.jacobian.block<1, 6>(0, 0) = r.gradient.transpose();
      t.curvature.topLeftCorner<6, 6>() = contract(k, t.value)(0) * r.hessian;
      visit(t);
    }
  }
  void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                double time_scale, const QuantityContraction& contract,
                                const TimeStepTermsVisitor& visit) const override {
    for (int k = support.first_k; k <= support.last_k; ++k) {
      const AngularRateTerms r = angularRateTerms(np.scheme(), np.current()[k]);
      Eigen::Matrix<double, 9, 1> gradient = Eigen::Matrix<double, 9, 1>::Zero();
      Eigen::Matrix<double, 9, 9> hessian = Eigen::Matrix<double, 9, 9>::Zero();
      gradient.head<6>() = r.gradient;
      hessian.topLeftCorner<6, 6>() = r.hessian;
      const double q = r.half_squared_rate;
      const double lambda = contract(k, Vector3(q, 0.0, 0.0))(0);
      visit(rateTermsWithTimeStep(np, support, time_scale, k, q, gradient, hessian, lambda));
    }
  }
};

/// ½|J⁻¹Π_k|² of node k (schemes with end torques), through the node momentum's stencil:
/// ∇q = J_Πᵀ J⁻²Π, ∇²q = J_Πᵀ J⁻² J_Π + Σ_i (J⁻²Π)_i ∇²Π_i.
class NodeRateQuantity final : public RateQuantity {
 public:
  explicit NodeRateQuantity(const Matrix3& inertia)
      : inverse_inertia_(inertia.inverse()),
        inverse_inertia_squared_(inverse_inertia_ * inverse_inertia_) {}
  StageQuantity kind() const override { return StageQuantity::NodeRate; }
  /// The free nodes (the fixed ones' rates are boundary data).
  StageSupport support(int first_free, int last_free) const override {
    const FreeRange r(first_free, last_free);
    return {r.first + 1, r.last - 1, -1, 3};
  }
  StageSupport planSupport(bool, int steps) const override { return {0, steps, 0, 1}; }
  /// Π_k = (μ(F_k) + F_{k−1}ᵀ μ(F_{k−1}))/2 (ReducedProblem::NodeMomentum).
  Vector3 value(const QuantityInputs& at, int k) const override {
    const DiscreteScheme& scheme = at.problem().scheme();
    const ReducedProblem::StepVectors& steps = at.steps();
    const Vector3 Pi =
        0.5 * (scheme.momentumOfStep(steps[k]) +
               so3::exp(steps[k - 1]).transpose() * scheme.momentumOfStep(steps[k - 1]));
    return Vector3(0.5 * (inverse_inertia_ * Pi).squaredNorm(), 0.0, 0.0);
  }
  /// The contraction λ∇²q = λ J_Πᵀ J⁻² J_Π + Σ_i (λ J⁻²Π)_i ∇²Π_i: the momentum's stencil with
  /// weights λ J⁻²Π.
  void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                    const QuantityContraction& contract, const TermsVisitor& visit) const override {
    double lambda = 0.0;
    const auto weights = [&](int k, const Vector3& Pi) {
      lambda = 0.0;
      if (k < support.first_k || k > support.last_k) return Vector3(Vector3::Zero());
      const Vector3 a = inverse_inertia_squared_ * Pi;  // J⁻²Π
      lambda = contract(k, Vector3(0.5 * Pi.dot(a), 0.0, 0.0))(0);
      return Vector3(lambda * a);
    };
    np.forEachNodeMomentum(
        [&](const ReducedProblem::NodeMomentum& node) {
          if (node.k < support.first_k || node.k > support.last_k) return;
          const Vector3 a = inverse_inertia_squared_ * node.momentum;
          QuantityTerms t;
          t.k = node.k;
          t.value(0) = 0.5 * node.momentum.dot(a);
          t.jacobian.row(0) = (node.jacobian.transpose() * a).transpose();
          t.curvature =
              lambda * node.jacobian.transpose() * inverse_inertia_squared_ * node.jacobian +
              node.second;
          visit(t);
        },
        weights);
  }
  void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                double time_scale, const QuantityContraction& contract,
                                const TimeStepTermsVisitor& visit) const override {
    // ∇²q uncontracted (the h terms contract it with e): the momentum's stencil with weights J⁻²Π.
    np.forEachNodeMomentum(
        [&](const ReducedProblem::NodeMomentum& node) {
          if (node.k < support.first_k || node.k > support.last_k) return;
          const Vector3 a = inverse_inertia_squared_ * node.momentum;
          const double q = 0.5 * node.momentum.dot(a);
          const Eigen::Matrix<double, 9, 1> gradient = node.jacobian.transpose() * a;
          const Eigen::Matrix<double, 9, 9> hessian =
              node.jacobian.transpose() * inverse_inertia_squared_ * node.jacobian + node.second;
          const double lambda = contract(node.k, Vector3(q, 0.0, 0.0))(0);
          visit(
              rateTermsWithTimeStep(np, support, time_scale, node.k, q, gradient, hessian, lambda));
        },
        [&](int, const Vector3& Pi) { return Vector3(inverse_inertia_squared_ * Pi); });
  }

 private:
  Matrix3 inverse_inertia_;          ///< J⁻¹
  Matrix3 inverse_inertia_squared_;  ///< J⁻²
};

/// p = sᵀR_k b (pointingTerms on δ_k): a function of R_k alone, not of h.
class PointingQuantity final : public StageQuantityModel {
 public:
  PointingQuantity(const Vector3& body_axis, const Vector3& world_direction)
      : body_axis_(body_axis), world_direction_(world_direction) {}
  StageQuantity kind() const override { return StageQuantity::Pointing; }
  /// The free nodes (a fixed attitude's cone is checked up front: fixedNodeConeViolation).
  StageSupport support(int first_free, int last_free) const override {
    const FreeRange r(first_free, last_free);
    return {r.first + 1, r.last - 1, 0, 1};
  }
  /// The twist moves R_N (and R_{N−1}): their cones are instances up to node N.
  StageSupport supportWithTwist(int first_free, int, int steps) const override {
    return {first_free, steps, 0, 1};
  }
  StageSupport planSupport(bool, int steps) const override { return {0, steps, 0, 1}; }
  bool dependsOnTimeStep() const override { return false; }
  Vector3 value(const QuantityInputs& at, int k) const override {
    return Vector3(cosine(at.attitudes()[k]), 0.0, 0.0);
  }
  Vector3 valueOnPlan(const Maneuver& plan, int k) const override {
    return Vector3(cosine(plan.attitude[k]), 0.0, 0.0);
  }
  void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                    const QuantityContraction& contract, const TermsVisitor& visit) const override {
    forEachInstance<QuantityTerms>(np, support, contract, visit);
  }
  /// h moves R_k only where a boundary rate fixes it (R_{N−1} of paper and variational, an
  /// instance where a pointing end's free twist makes it one; ReducedProblem::nodePath), as a node
  /// perturbation d(h) = e Δh + ½ e₂ Δh²: ∂q/∂h = ∇qᵀe, ∂∇q/∂h = ∇²q e, ∂²q/∂h² = eᵀ∇²q e +
  /// ∇qᵀe₂ (in η = h/time_scale: e, e₂ times time_scale, time_scale²). Elsewhere they are zero.
  void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                double time_scale, const QuantityContraction& contract,
                                const TimeStepTermsVisitor& visit) const override {
    const std::vector<Matrix3> R = np.attitudes(np.current());
    for (int k = support.first_k; k <= support.last_k; ++k) {
      const PointingTerms p = pointingTerms(R[k], body_axis_, world_direction_);
      QuantityTermsWithTimeStep t;
      t.k = k;
      t.value(0) = p.cosine;
      const double lambda = contract(k, t.value)(0);
      const ReducedProblem::BoundaryPath path = np.nodePath(k);
      const Vector3 e = path.first * time_scale, e2 = path.second * (time_scale * time_scale);
      const Vector3 He = p.hessian * e;
      t.jacobian.block<1, 3>(0, 0) = p.gradient.transpose();
      t.jacobian(0, 9) = p.gradient.dot(e);
      t.curvature.topLeftCorner<3, 3>() = lambda * p.hessian;
      t.curvature.block<3, 1>(0, 9) = lambda * He;
      t.curvature.block<1, 3>(9, 0) = lambda * He.transpose();
      t.curvature(9, 9) = lambda * (e.dot(He) + p.gradient.dot(e2));
      visit(t);
    }
  }

 private:
  /// The instances' terms on node k alone (the first three entries of either kind of terms).
  template <typename Terms, typename Visit>
  void forEachInstance(const ReducedProblem& np, const StageSupport& support,
                       const QuantityContraction& contract, const Visit& visit) const {
    const std::vector<Matrix3> R = np.attitudes(np.current());
    for (int k = support.first_k; k <= support.last_k; ++k) {
      const PointingTerms p = pointingTerms(R[k], body_axis_, world_direction_);
      Terms t;
      t.k = k;
      t.value(0) = p.cosine;
      t.jacobian.template block<1, 3>(0, 0) = p.gradient.transpose();
      t.curvature.template topLeftCorner<3, 3>() = contract(k, t.value)(0) * p.hessian;
      visit(t);
    }
  }
  /// As pointingTerms forms it (v = Rᵀs, p = vᵀb), so that a value and its terms agree bit for bit.
  double cosine(const Matrix3& R) const {
    const Vector3 v = R.transpose() * world_direction_;
    return v.dot(body_axis_);
  }
  Vector3 body_axis_, world_direction_;
};

/// The wheel kinds' prototypes' problem: three orthogonal wheels, the paper scheme.
PlanningProblem threeWheelProblem() {
  PlanningProblem p;
  p.reaction_wheels.spin_axes = {Vector3::UnitX(), Vector3::UnitY(), Vector3::UnitZ()};
  p.reaction_wheels.max_torque = {1.0};
  p.reaction_wheels.max_momentum = {1.0};
  return p;
}

/// One object per kind for the kind-level questions (support, h dependence) the tests and the
/// dense NLPs ask by name.
const StageQuantityModel& prototype(StageQuantity quantity) {
  static const TorqueQuantity torque;
  static const StepRateQuantity step_rate;
  static const NodeRateQuantity node_rate{Matrix3::Identity()};
  static const PointingQuantity pointing{Vector3::UnitX(), Vector3::UnitX()};
  static const std::shared_ptr<const StageQuantityModel> wheel_momentum =
      makeWheelMomentumQuantity(threeWheelProblem(), false);
  static const std::shared_ptr<const StageQuantityModel> wheel_torque =
      makeWheelTorqueQuantity(threeWheelProblem());
  switch (quantity) {
    case StageQuantity::WheelMomentum:
      return *wheel_momentum;
    case StageQuantity::WheelTorque:
      return *wheel_torque;
    case StageQuantity::Torque:
      return torque;
    case StageQuantity::StepRate:
      return step_rate;
    case StageQuantity::NodeRate:
      return node_rate;
    case StageQuantity::Pointing:
      break;
  }
  return pointing;
}

}  // namespace

std::shared_ptr<const StageQuantityModel> makeTorqueQuantity() {
  return std::make_shared<TorqueQuantity>();
}

std::shared_ptr<const StageQuantityModel> makeRateQuantity(bool end_torques,
                                                           const Matrix3& inertia) {
  if (end_torques) return std::make_shared<NodeRateQuantity>(inertia);
  return std::make_shared<StepRateQuantity>();
}

std::shared_ptr<const StageQuantityModel> makePointingQuantity(const Vector3& body_axis,
                                                               const Vector3& world_direction) {
  return std::make_shared<PointingQuantity>(body_axis, world_direction);
}

StageSupport stageSupport(StageQuantity quantity, int first_free, int last_free) {
  return prototype(quantity).support(first_free, last_free);
}

bool quantityDependsOnTimeStep(StageQuantity quantity) {
  return prototype(quantity).dependsOnTimeStep();
}

StageSupport planSupport(StageQuantity quantity, bool end_torques, int steps) {
  return prototype(quantity).planSupport(end_torques, steps);
}

}  // namespace attitude_planner
