// The reaction-wheel quantities and constraints (wheel_quantities.hpp).
//
// Each quantity is composed of three parts of node k, each a vector function p(x, h) of the
// window's node unknowns x (δ_{k−1}, δ_k, δ_{k+1}) and of h, formed as a Jet: value, ∂p and
// Σ_i w_i ∇²p_i for weights w chosen per instance (the contraction's λ carried through the
// composition):
//   τ_k   the torque stencil (ReducedProblem::forEachStencil[WithTimeStep]);
//   Π_k   the node momentum, Π(x, h) = (h₀/h) Π̃(x + d(h)) (every μ scales like 1/h; d the
//         window's node path, ReducedProblem::nodePath), constant J Ω(0), J Ω(T) at the end
//         nodes of schemes with end torques;
//   v_k   = R_kᵀπ₀ = exp(−δ_k^) R_kᵀπ₀: ∂v = v^ (on δ_k), λᵀ∇²v = ½(λvᵀ + vλᵀ) − (λ·v) I.
// q = v − Π is linear in the parts; a = −τ − ω × q (ω = J⁻¹Π) is bilinear: with
// B(ω, q) = −λᵀ(ω × q) = ωᵀλ^q, λᵀ∇²a = −Σλ_i∇²τ_i + Σ(g_Π)_i∇²Π_i + Σ(g_v)_i∇²v_i + M + Mᵀ,
// g_Π = J⁻¹λ^q + λ^ω, g_v = −λ^ω, M = (∂Π)ᵀJ⁻¹λ^(∂v − ∂Π) (the second differential 2B(dω, dq)).
// Tested against central differences in x and in h (test_reaction_wheels).
#include "planning/transcription/wheel_quantities.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <utility>
#include <vector>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

using Vector9 = Eigen::Matrix<double, 9, 1>;
using Matrix3x10 = Eigen::Matrix<double, 3, 10>;
using Matrix10 = Eigen::Matrix<double, 10, 10>;

/// One part at one instance: value, ∂p over (x, h) (column 9 in h itself) and Σ_i w_i ∇²p_i.
struct Jet {
  Vector3 value = Vector3::Zero();
  Matrix3x10 d = Matrix3x10::Zero();
  Matrix10 s = Matrix10::Zero();
};

/// d(h) = e Δh + ½ e₂ Δh² of the window k−1..k+1 (zero for nodes that do not move with h).
struct WindowPath {
  Vector9 first = Vector9::Zero(), second = Vector9::Zero();
};
WindowPath windowPath(const ReducedProblem& np, int k) {
  WindowPath out;
  for (int node = 0; node < 3; ++node) {
    const int j = k - 1 + node;
    if (j < 0 || j > np.steps()) continue;
    const ReducedProblem::BoundaryPath path = np.nodePath(j);
    out.first.segment<3>(3 * node) = path.first;
    out.second.segment<3>(3 * node) = path.second;
  }
  return out;
}

/// The node momentum's jet from its stencil (weights w) and the scaling with h:
/// ∂Π/∂h = s'Π + ∂Π e, ∂²(wᵀΠ)/∂x∂h = s'∂Πᵀw + S e, ∂²(wᵀΠ)/∂h² = s''wᵀΠ + 2s'wᵀ∂Π e + eᵀSe +
/// wᵀ∂Π e₂ with s = h₀/h (s' = −1/h, s'' = 2/h² at h₀).
Jet momentumJet(const ReducedProblem::NodeMomentum& node, const Vector3& w, const WindowPath* path,
                double h) {
  Jet out;
  out.value = node.momentum;
  out.d.leftCols<9>() = node.jacobian;
  out.s.topLeftCorner<9, 9>() = node.second;
  if (!path) return out;
  const double s1 = -1.0 / h, s2 = 2.0 / (h * h);
  const Vector3 moved = node.jacobian * path->first;
  out.d.col(9) = s1 * node.momentum + moved;
  const Vector9 cross = s1 * node.jacobian.transpose() * w + node.second * path->first;
  out.s.block<9, 1>(0, 9) = cross;
  out.s.block<1, 9>(9, 0) = cross.transpose();
  out.s(9, 9) = s2 * w.dot(node.momentum) + 2 * s1 * w.dot(moved) +
                path->first.dot(node.second * path->first) + w.dot(node.jacobian * path->second);
  return out;
}

/// v = R_kᵀπ_k on the window's middle node, weights c; `rate` = R_kᵀ ∂π_k/∂h = R_kᵀ k τ_d (π_k =
/// π₀ + k h τ_d): ∂v/∂h = v^e + rate, ∂²(cᵀv)/∂δ∂h = H e + c × rate (cᵀexp(−δ^)g =
/// cᵀg + δ·(c × g)), ∂²(cᵀv)/∂h² = eᵀHe + cᵀv^e₂ + 2 (c × rate)·e (π is affine in h).
Jet bodyTotalJet(const Vector3& v, const Vector3& c, const WindowPath* path, const Vector3& rate) {
  Jet out;
  out.value = v;
  const Matrix3 G = so3::hat(v);
  const Matrix3 H = 0.5 * (c * v.transpose() + v * c.transpose()) - c.dot(v) * Matrix3::Identity();
  out.d.block<3, 3>(0, 3) = G;
  out.s.block<3, 3>(3, 3) = H;
  if (!path) return out;
  const Vector3 e = path->first.segment<3>(3), e2 = path->second.segment<3>(3);
  const Vector3 turn = c.cross(rate);
  out.d.col(9) = G * e + rate;
  out.s.block<3, 1>(3, 9) = H * e + turn;
  out.s.block<1, 3>(9, 3) = (H * e + turn).transpose();
  out.s(9, 9) = e.dot(H * e) + c.dot(G * e2) + 2.0 * turn.dot(e);
  return out;
}

/// The jet in η = h/time_scale.
void scaleTimeStep(Jet* jet, double time_scale) {
  jet->d.col(9) *= time_scale;
  jet->s.col(9) *= time_scale;
  jet->s.row(9) *= time_scale;
}

/// What both wheel quantities share: the array, π₀, the end momenta and the parts' passes.
class WheelQuantity : public StageQuantityModel {
 public:
  explicit WheelQuantity(const PlanningProblem& p)
      : scheme_(p.scheme),
        end_torques_(schemeHasEndTorques(p.scheme)),
        inertia_(p.inertia),
        inverse_inertia_(p.inertia.inverse()),
        array_(wheelArray(p.reaction_wheels)),
        total_(p.initial_attitude *
               (p.inertia * p.initial_velocity + array_.initial_array_momentum)),
        disturbance_(p.worldDisturbance()),
        start_momentum_(p.inertia * p.initial_velocity),
        end_momentum_(p.inertia * p.final_velocity) {}
  bool dependsOnTimeStep() const override { return true; }
  const WheelArray& array() const { return array_; }
  void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                    const QuantityContraction& contract, const TermsVisitor& visit) const override {
    forEachJet(np, support, false, 1.0, contract, [&](int k, const Jet& jet) {
      QuantityTerms t;
      t.k = k;
      t.value = jet.value;
      t.jacobian = jet.d.leftCols<9>();
      t.curvature = jet.s.topLeftCorner<9, 9>();
      visit(t);
    });
  }
  void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                double time_scale, const QuantityContraction& contract,
                                const TimeStepTermsVisitor& visit) const override {
    forEachJet(np, support, true, time_scale, contract, [&](int k, const Jet& jet) {
      QuantityTermsWithTimeStep t;
      t.k = k;
      t.value = jet.value;
      t.jacobian = jet.d;
      t.curvature = jet.s;
      visit(t);
    });
  }

 protected:
  /// The quantity's jets over `support`: in (x, h) with h in η = h/time_scale if `with_h`, else
  /// in x alone (column 9 and the h entries zero), the curvature contracted with `contract`.
  virtual void forEachJet(const ReducedProblem& np, const StageSupport& support, bool with_h,
                          double time_scale, const QuantityContraction& contract,
                          const std::function<void(int, const Jet&)>& visit) const = 0;

  /// Π_k at the iterate `at` (the end nodes' J Ω(0), J Ω(T)).
  Vector3 nodeMomentum(const QuantityInputs& at, int k) const {
    const int N = at.problem().steps();
    if (k <= 0) return start_momentum_;
    if (k >= N) return end_momentum_;
    return at.nodeMomenta()[k];
  }
  /// v_k = R_kᵀπ_k, π_k = π₀ + k h τ_d.
  Vector3 bodyTotal(const QuantityInputs& at, int k) const {
    return at.attitudes()[k].transpose() * (total_ + (k * at.problem().timeStep()) * disturbance_);
  }
  /// The Π and v jets of every instance of `support` (weights from `weights_of(k)`: first Π's,
  /// then v's), visited in k order with the instance's index.
  void forEachMomentumParts(const ReducedProblem& np, const StageSupport& support, bool with_h,
                            const std::vector<std::pair<Vector3, Vector3>>& weights,
                            const std::function<void(int, const Jet&, const Jet&)>& visit) const {
    const QuantityInputs at(np, np.current());
    const double h = np.timeStep();
    const auto partsAt = [&](int k, Jet Pi) {
      const int i = k - support.first_k;
      const WindowPath path = windowPath(np, k);
      const Vector3 rate = at.attitudes()[k].transpose() * (k * disturbance_);
      const Jet v =
          bodyTotalJet(bodyTotal(at, k), weights[i].second, with_h ? &path : nullptr, rate);
      visit(k, Pi, v);
    };
    const auto constantMomentum = [&](int k) {
      Jet Pi;
      Pi.value = nodeMomentum(at, k);
      return Pi;
    };
    const int N = np.steps();
    if (support.first_k <= 0 && support.last_k >= 0) partsAt(0, constantMomentum(0));
    np.forEachNodeMomentum(
        [&](const ReducedProblem::NodeMomentum& node) {
          if (node.k < support.first_k || node.k > support.last_k) return;
          const WindowPath path = windowPath(np, node.k);
          partsAt(node.k, momentumJet(node, weights[node.k - support.first_k].first,
                                      with_h ? &path : nullptr, h));
        },
        [&](int k, const Vector3&) {
          if (k < support.first_k || k > support.last_k) return Vector3(Vector3::Zero());
          return weights[k - support.first_k].first;
        });
    if (support.first_k <= N && support.last_k >= N) partsAt(N, constantMomentum(N));
  }

  SchemeKind scheme_;
  bool end_torques_;
  Matrix3 inertia_, inverse_inertia_;
  WheelArray array_;
  Vector3 total_;                          ///< π₀, world
  Vector3 disturbance_;                    ///< τ_d, world: π_k = π₀ + k h τ_d
  Vector3 start_momentum_, end_momentum_;  ///< J Ω(0), J Ω(T)
};

/// q_k = R_kᵀπ₀ − Π_k, the array's momentum A h_w,k; or, with `half_squared_norm`, ½|q_k|² in
/// entry 0 (the envelope's quantity: its constraint is then affine in it, so the free-time
/// solver, whose quantity assembly takes the constraints as affine, needs no curvature term).
class WheelMomentumQuantity final : public WheelQuantity {
 public:
  WheelMomentumQuantity(const PlanningProblem& p, bool half_squared_norm)
      : WheelQuantity(p), half_squared_norm_(half_squared_norm) {}
  StageQuantity kind() const override { return StageQuantity::WheelMomentum; }
  /// The nodes with a free attitude in their window, but 0 and N (their q is boundary data).
  StageSupport support(int first_free, int last_free) const override {
    return {std::max(1, first_free - 1), end_torques_ ? last_free : last_free + 1, -1, 3};
  }
  StageSupport planSupport(bool, int steps) const override { return {0, steps, 0, 1}; }
  Vector3 value(const QuantityInputs& at, int k) const override {
    const Vector3 q = bodyTotal(at, k) - nodeMomentum(at, k);
    return half_squared_norm_ ? Vector3(0.5 * q.squaredNorm(), 0.0, 0.0) : q;
  }
  /// q_k itself (the plain form, also for the half squared norm).
  Vector3 valueOnPlan(const Maneuver& plan, int k) const override {
    return planArrayMomentum(scheme_, inertia_, array_, plan, k, disturbance_);
  }

 private:
  /// The parts' weights carry λ (q), or λ q (½|q|²: λ∇²s = λ ∂qᵀ∂q + Σ (λq)_i ∇²q_i).
  void forEachJet(const ReducedProblem& np, const StageSupport& support, bool with_h,
                  double time_scale, const QuantityContraction& contract,
                  const std::function<void(int, const Jet&)>& visit) const override {
    const QuantityInputs at(np, np.current());
    std::vector<std::pair<Vector3, Vector3>> weights;  // (Π's, v's) = (−w, w)
    std::vector<double> scalar;                        // λ of ½|q|²
    for (int k = support.first_k; k <= support.last_k; ++k) {
      const Vector3 lambda = contract(k, value(at, k));
      const Vector3 q = bodyTotal(at, k) - nodeMomentum(at, k);
      const Vector3 w = half_squared_norm_ ? Vector3(lambda(0) * q) : lambda;
      scalar.push_back(lambda(0));
      weights.emplace_back(-w, w);
    }
    forEachMomentumParts(np, support, with_h, weights, [&](int k, const Jet& Pi, const Jet& v) {
      Jet q;
      q.value = v.value - Pi.value;
      q.d = v.d - Pi.d;
      q.s = v.s + Pi.s;  // each formed with its own sign of the weights
      if (half_squared_norm_) {
        Jet s;
        s.value(0) = 0.5 * q.value.squaredNorm();
        s.d.row(0) = q.value.transpose() * q.d;
        s.s = scalar[k - support.first_k] * q.d.transpose() * q.d + q.s;
        q = s;
      }
      if (with_h) scaleTimeStep(&q, time_scale);
      visit(k, q);
    });
  }
  bool half_squared_norm_;
};

/// a_k = −(τ_k + J⁻¹Π_k × q_k), the array's torque A u_k.
class WheelTorqueQuantity final : public WheelQuantity {
 public:
  using WheelQuantity::WheelQuantity;
  StageQuantity kind() const override { return StageQuantity::WheelTorque; }
  /// The torques' instances (k = 1..N−1; 0..N with end torques).
  StageSupport support(int first_free, int last_free) const override {
    return {first_free - 1, last_free + 1, -1, 3};
  }
  StageSupport planSupport(bool end_torques, int steps) const override {
    return end_torques ? StageSupport{0, steps, 0, 1} : StageSupport{1, steps - 1, 0, 1};
  }
  Vector3 value(const QuantityInputs& at, int k) const override {
    const Vector3 Pi = nodeMomentum(at, k);
    return torqueOf(at.torques()[k], Pi, bodyTotal(at, k) - Pi);
  }
  Vector3 valueOnPlan(const Maneuver& plan, int k) const override {
    return planArrayTorque(scheme_, inertia_, array_, plan, k, disturbance_);
  }

 private:
  Vector3 torqueOf(const Vector3& tau, const Vector3& Pi, const Vector3& q) const {
    return -(tau + (inverse_inertia_ * Pi).cross(q));
  }
  /// The torque stencil's jets with weights −λ_k (τ = r/√w_k, so the stencil gets −λ_k/√w_k).
  std::vector<Jet> torqueJets(const ReducedProblem& np, const StageSupport& support, bool with_h,
                              const std::vector<Vector3>& lambda) const {
    std::vector<Jet> out(support.last_k - support.first_k + 1);
    const auto root = [&](int k) { return std::sqrt(np.scheme().torqueWeight(k, np.steps())); };
    const auto weights = [&](int k, const Vector3&) {
      if (k < support.first_k || k > support.last_k) return Vector3(Vector3::Zero());
      return Vector3(-lambda[k - support.first_k] / root(k));
    };
    const auto store = [&](const ReducedProblem::Stencil& st) -> Jet* {
      if (st.k < support.first_k || st.k > support.last_k) return nullptr;
      Jet& jet = out[st.k - support.first_k];
      jet.value = st.tau / root(st.k);
      jet.d.leftCols<9>() = st.jacobian / root(st.k);
      jet.s.topLeftCorner<9, 9>() = st.second;
      return &jet;
    };
    if (!with_h) {
      np.forEachStencil(
          true, [&](const ReducedProblem::Stencil& st) { store(st); }, weights);
      return out;
    }
    np.forEachStencilWithTimeStep(
        [&](const ReducedProblem::TimeStepStencil& st) {
          Jet* jet = store(st);
          if (!jet) return;
          jet->d.col(9) = st.tau_h / root(st.k);
          jet->s.block<9, 1>(0, 9) = st.second_h;
          jet->s.block<1, 9>(9, 0) = st.second_h.transpose();
          jet->s(9, 9) = st.second_hh;
        },
        weights);
    return out;
  }
  void forEachJet(const ReducedProblem& np, const StageSupport& support, bool with_h,
                  double time_scale, const QuantityContraction& contract,
                  const std::function<void(int, const Jet&)>& visit) const override;
};

void WheelTorqueQuantity::forEachJet(const ReducedProblem& np, const StageSupport& support,
                                     bool with_h, double time_scale,
                                     const QuantityContraction& contract,
                                     const std::function<void(int, const Jet&)>& visit) const {
  const QuantityInputs at(np, np.current());
  std::vector<Vector3> lambda;
  std::vector<std::pair<Vector3, Vector3>> weights;  // (g_Π, g_v)
  for (int k = support.first_k; k <= support.last_k; ++k) {
    const Vector3 Pi = nodeMomentum(at, k), q = bodyTotal(at, k) - Pi;
    const Vector3 l = contract(k, torqueOf(at.torques()[k], Pi, q));
    const Vector3 omega = inverse_inertia_ * Pi;
    lambda.push_back(l);
    weights.emplace_back(inverse_inertia_ * l.cross(q) + l.cross(omega), -l.cross(omega));
  }
  const std::vector<Jet> tau = torqueJets(np, support, with_h, lambda);
  forEachMomentumParts(np, support, with_h, weights, [&](int k, const Jet& Pi, const Jet& v) {
    const int i = k - support.first_k;
    const Vector3 omega = inverse_inertia_ * Pi.value, q = v.value - Pi.value;
    const Matrix3x10 dq = v.d - Pi.d;
    Jet a;
    a.value = torqueOf(tau[i].value, Pi.value, q);
    // d(ω × q) = −q^ J⁻¹ dΠ + ω^ dq
    a.d = -tau[i].d + so3::hat(q) * inverse_inertia_ * Pi.d - so3::hat(omega) * dq;
    const Matrix10 M = Pi.d.transpose() * inverse_inertia_ * so3::hat(lambda[i]) * dq;
    a.s = tau[i].s + Pi.s + v.s + M + M.transpose();
    if (with_h) scaleTimeStep(&a, time_scale);
    visit(k, a);
  });
}

/// One side of one wheel's limit on a linear function of the quantity: σ (p_iᵀx + n_i) ≤ L,
/// c = 1 − σ(p_iᵀx + n_i)/L (p_i the row of A⁺, n_i the null-space momentum, or 0 for torques).
class WheelLimitSide final : public StageConstraint {
 public:
  WheelLimitSide(std::shared_ptr<const StageQuantityModel> quantity, const Vector3& row,
                 double offset, double limit, double sign, std::string what, const char* unit)
      : StageConstraint(std::move(quantity), nullptr),
        row_(row),
        offset_(offset),
        limit_(limit),
        sign_(sign),
        what_(std::move(what)),
        unit_(unit) {}
  double value(const Vector3& x) const override { return 1.0 - sign_ * wheel(x) / limit_; }
  Vector3 gradient(const Vector3&) const override { return -sign_ / limit_ * row_; }
  std::string describe() const override {
    std::ostringstream s;
    s << what_ << " <= " << limit_ << " " << unit_;
    return s.str();
  }
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return limit_ - sign_ * wheel(quantityModel().valueOnPlan(plan, k));
  }
  double slackScale() const override { return limit_; }
  double rowValue(const Vector3& x) const override { return wheel(x); }
  Vector3 rowGradient(const Vector3&) const override { return row_; }
  double rowLower() const override { return sign_ > 0 ? StageConstraint::rowLower() : -limit_; }
  double rowUpper() const override { return sign_ > 0 ? limit_ : StageConstraint::rowUpper(); }

 private:
  double wheel(const Vector3& x) const { return row_.dot(x) + offset_; }
  Vector3 row_;
  double offset_, limit_, sign_;
  std::string what_;
  const char* unit_;
};

/// max_momentum_norm H on s = ½|q|²: c = 1 − 2s/H² (affine in its quantity).
class WheelMomentumEnvelope final : public StageConstraint {
 public:
  WheelMomentumEnvelope(std::shared_ptr<const StageQuantityModel> half_squared_norm, double limit)
      : StageConstraint(std::move(half_squared_norm), nullptr),
        limit_(limit),
        slope_(-2.0 / (limit * limit)) {}
  double value(const Vector3& s) const override { return 1.0 + slope_ * s(0); }
  Vector3 gradient(const Vector3&) const override { return Vector3(slope_, 0.0, 0.0); }
  std::string describe() const override {
    std::ostringstream s;
    s << "reaction_wheels |A h_w| <= " << limit_ << " N m s";
    return s.str();
  }
  /// On the plan's q_k (the quantity's plain form).
  double slackOnPlan(const Maneuver& plan, int k) const override {
    return limit_ - quantityModel().valueOnPlan(plan, k).norm();
  }
  double slackScale() const override { return limit_; }
  /// g = |q|²/H² ≤ 1 in the plain form q.
  double rowValue(const Vector3& q) const override { return q.squaredNorm() / (limit_ * limit_); }
  Vector3 rowGradient(const Vector3& q) const override { return 2.0 * q / (limit_ * limit_); }
  double rowCurvature() const override { return 2.0 / (limit_ * limit_); }
  double rowUpper() const override { return 1.0; }

 private:
  double limit_;  ///< H [N m s]
  double slope_;  ///< −2/H²
};

}  // namespace

std::shared_ptr<const StageQuantityModel> makeWheelMomentumQuantity(const PlanningProblem& problem,
                                                                    bool half_squared_norm) {
  return std::make_shared<WheelMomentumQuantity>(problem, half_squared_norm);
}

std::shared_ptr<const StageQuantityModel> makeWheelTorqueQuantity(const PlanningProblem& problem) {
  return std::make_shared<WheelTorqueQuantity>(problem);
}

void appendWheelConstraints(const PlanningProblem& problem, StageConstraints* out) {
  const ReactionWheels& wheels = problem.reaction_wheels;
  if (!wheels.present()) return;
  const auto momentum = makeWheelMomentumQuantity(problem, false);
  const auto torque = makeWheelTorqueQuantity(problem);
  const WheelArray array = wheelArray(wheels);
  for (int i = 0; i < wheels.count(); ++i) {
    const Vector3 row = array.pseudo_inverse.row(i).transpose();
    const std::string wheel = "reaction wheel " + std::to_string(i + 1);
    for (const double sign : {1.0, -1.0}) {
      out->push_back(std::make_unique<WheelLimitSide>(momentum, row, array.null_momentum(i),
                                                      wheels.momentumLimit(i), sign, wheel + " |h|",
                                                      "N m s"));
    }
    for (const double sign : {1.0, -1.0}) {
      out->push_back(std::make_unique<WheelLimitSide>(torque, row, 0.0, wheels.torqueLimit(i), sign,
                                                      wheel + " |u|", "N m"));
    }
  }
  if (std::isfinite(wheels.max_momentum_norm)) {
    out->push_back(std::make_unique<WheelMomentumEnvelope>(makeWheelMomentumQuantity(problem, true),
                                                           wheels.max_momentum_norm));
  }
}

}  // namespace attitude_planner
