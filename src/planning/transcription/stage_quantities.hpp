// Stage quantities: the q of every stage constraint c(q) ≥ 0 (stage_constraints.hpp) as objects
// of the transcription, one class per quantity, so that the readers (the interior point at a fixed
// h, the free-time solver with h free, the plan's check) loop over constraints and ask the
// quantity instead of re-deriving it per kind.
//
// A quantity knows, for instance k of a reduced problem: its value q, its derivatives in the node
// unknowns δ (the Jacobian over its local nodes and its curvature contracted with a multiplier λ,
// Σ_i λ_i ∇²q_i: the Lagrangian's part the assemblers add), its derivatives in the time step h
// where it moves with h, its support (which instances exist, on which nodes), and its value on a
// plan. The constraint applies the chain rule on top: ∇c = c'(q) ∇q, ∇²c = c'∇²q + ∇qᵀ c'' ∇q.
//
// The dense NLPs (crosscheck/nlopt_solver.cpp, studies/benchmark_solvers.cpp) keep their own
// derivatives on purpose: they are the independent checks of these.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// What a stage constraint is a function of (its quantity's name, for the dense NLPs and the
/// tests; the solvers ask the StageQuantityModel instead).
enum class StageQuantity {
  Torque,  ///< q = τ_k [N m] (3-vector) on R_{k−1}, R_k, R_{k+1}; moves with h
  StepRate,  ///< q = ½|Ω_k|² [rad²/s²] of step F_k = R_kᵀR_{k+1} (paper, variational); moves with h
  NodeRate,  ///< q = ½|J⁻¹Π_k|² [rad²/s²] of node k (schemes with end torques) on R_{k−1..k+1};
             ///< moves with h
  Pointing,  ///< q = sᵀR_k b (the cosine of the angle between R_k b and s) on R_k; no h
  /// q = R_kᵀπ₀ − Π_k [N m s]: the reaction wheels' momentum A h_w in the body frame
  /// (wheel_quantities.hpp) on R_{k−1..k+1}; moves with h
  WheelMomentum,
  /// q = −(τ_k + J⁻¹Π_k × (R_kᵀπ₀ − Π_k)) [N m]: the wheels' torque A u on the body frame's
  /// axes (wheel_quantities.hpp) on R_{k−1..k+1}; moves with h
  WheelTorque,
};

/// Where the instances of a quantity sit: k = first_k..last_k, each on the nodes
/// k + node_offset .. k + node_offset + width − 1 (at most three: the band is kept).
struct StageSupport {
  int first_k = 0, last_k = 0;
  int node_offset = 0;
  int width = 1;
};

/// The products of one iterate that the quantities share, each formed on first use: the torques
/// τ_0..τ_N, the attitudes R_0..R_N of `steps` and the interior node momenta.
class QuantityInputs {
 public:
  QuantityInputs(const ReducedProblem& np, const ReducedProblem::StepVectors& steps)
      : np_(np), steps_(steps) {}
  const ReducedProblem& problem() const { return np_; }
  const ReducedProblem::StepVectors& steps() const { return steps_; }
  const std::vector<Vector3>& torques() const;
  const std::vector<Matrix3>& attitudes() const;
  /// Π_k, k = 1..N−1 (entries 0 and N unset): the mean of the two adjacent steps' momenta seen
  /// from node k, ½(μ(ω_k) + exp(ω_{k−1}^)ᵀ μ(ω_{k−1})). Every constraint on a wheel quantity
  /// reads it at every node, so it is formed once per iterate, not once per constraint.
  const std::vector<Vector3>& nodeMomenta() const;

 private:
  const ReducedProblem& np_;
  const ReducedProblem::StepVectors& steps_;
  mutable std::optional<std::vector<Vector3>> torques_;
  mutable std::optional<std::vector<Matrix3>> attitudes_;
  mutable std::optional<std::vector<Vector3>> node_momenta_;
};

/// λ_k = ∂L/∂q at instance k with value q: the caller forms its constraints' values and
/// multipliers here (L's part on this quantity, Σ −z c(q) over the constraints on it).
using QuantityContraction = std::function<Vector3(int k, const Vector3& q)>;

/// One instance's derivatives at a fixed h, over its local nodes (zero beyond its width).
struct QuantityTerms {
  int k = 0;
  Vector3 value = Vector3::Zero();  ///< q (scalar quantities in entry 0)
  /// ∂q/∂δ over the local nodes (row i: q_i; scalar quantities in row 0).
  Eigen::Matrix<double, 3, 9> jacobian = Eigen::Matrix<double, 3, 9>::Zero();
  /// Σ_i λ_i ∂²q_i/∂δ², λ what the contraction returned for this instance.
  Eigen::Matrix<double, 9, 9> curvature = Eigen::Matrix<double, 9, 9>::Zero();
};

/// One instance's derivatives with h free: entries 0..8 the local nodes, entry 9 the global unknown
/// η = h/scale (forEachTermsWithTimeStep's time_scale; the free-time solver's η = h/h₀).
struct QuantityTermsWithTimeStep {
  int k = 0;
  Vector3 value = Vector3::Zero();
  Eigen::Matrix<double, 3, 10> jacobian = Eigen::Matrix<double, 3, 10>::Zero();
  Eigen::Matrix<double, 10, 10> curvature = Eigen::Matrix<double, 10, 10>::Zero();
};

/// One stage quantity of a transcription. Instances of one object share one pass over the band
/// (the constraints on it are contracted together); the objects are shared by the constraints on
/// the same quantity (buildStageConstraints: one torque, one rate, one pointing per cone).
class StageQuantityModel {
 public:
  using TermsVisitor = std::function<void(const QuantityTerms&)>;
  using TimeStepTermsVisitor = std::function<void(const QuantityTermsWithTimeStep&)>;

  virtual ~StageQuantityModel() = default;
  virtual StageQuantity kind() const = 0;

  /// The instances on a reduced problem whose free attitudes are R_first_free..R_last_free.
  virtual StageSupport support(int first_free, int last_free) const = 0;
  /// The instances when a pointing end condition's free twist moves R_N (and R_{N−1} of paper and
  /// variational: ReducedProblem::twistMotion) on a plan of `steps` steps: support() but where an
  /// instance on those nodes is excluded as boundary data (a cone's).
  virtual StageSupport supportWithTwist(int first_free, int last_free, int /*steps*/) const {
    return support(first_free, last_free);
  }
  /// The instances on a plan of `steps` steps (checkConstraints).
  virtual StageSupport planSupport(bool end_torques, int steps) const = 0;
  /// True where q changes with the time step at fixed free attitudes.
  virtual bool dependsOnTimeStep() const = 0;
  /// True where the instances are the cost's own stencil residuals (the torque): the assemblers
  /// form them in the cost's stencil pass (one pass, and a box side folds into the Gauss–Newton
  /// weights: the precision rule of constrained_system.hpp) rather than through forEachTerms.
  virtual bool formedByCostStencil() const { return false; }

  /// q at instance k of `at` (scalar quantities in entry 0).
  virtual Vector3 value(const QuantityInputs& at, int k) const = 0;
  /// q in its plain form on a plan: τ_k, Ω_k (the plan's reported rate, not squared), the
  /// pointing cosine in entry 0 (what the constraints' slackOnPlan and the dense NLPs' rows read).
  virtual Vector3 valueOnPlan(const Maneuver& plan, int k) const = 0;

  /// Calls visit(terms) for every instance of `support` at the current iterate of `np` (fixed h),
  /// the curvature contracted with contract(k, q), which is called first.
  virtual void forEachTerms(const ReducedProblem& np, const StageSupport& support,
                            const QuantityContraction& contract,
                            const TermsVisitor& visit) const = 0;
  /// The same with h free: the derivatives in (local nodes, η = h/time_scale) at the current h
  /// (the boundary data held: ReducedProblem::setTimeStep, nodePath), the scale applied before
  /// the contraction (so that the free-time solver's sums are formed as they always were).
  virtual void forEachTermsWithTimeStep(const ReducedProblem& np, const StageSupport& support,
                                        double time_scale, const QuantityContraction& contract,
                                        const TimeStepTermsVisitor& visit) const = 0;
};

/// The quantity objects a problem's constraints are on (buildStageConstraints makes them).
std::shared_ptr<const StageQuantityModel> makeTorqueQuantity();
/// ½|Ω|² of the steps (paper, variational) or of the nodes (schemes with end torques: J⁻¹Π_k).
std::shared_ptr<const StageQuantityModel> makeRateQuantity(bool end_torques,
                                                           const Matrix3& inertia);
/// sᵀR_k b, b the body axis and s the world direction (unit).
std::shared_ptr<const StageQuantityModel> makePointingQuantity(const Vector3& body_axis,
                                                               const Vector3& world_direction);

/// The support of a quantity of this kind (StageQuantityModel::support).
StageSupport stageSupport(StageQuantity quantity, int first_free, int last_free);
/// True where a quantity of this kind moves with h (all but Pointing). The wheel kinds answer
/// for a scheme without end torques (their support depends on the scheme: ask the object).
bool quantityDependsOnTimeStep(StageQuantity quantity);
/// The instances on a plan (StageQuantityModel::planSupport): the torques the plan carries
/// (1..N−1; 0..N with end torques), the step rates 0..N−1, node rates and cones 0..N.
StageSupport planSupport(StageQuantity quantity, bool end_torques, int steps);

}  // namespace attitude_planner
