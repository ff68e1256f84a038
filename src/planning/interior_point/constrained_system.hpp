// The fixed-h interior point's stage constraints c_i(δ) ≥ 0 on the reduced problem's band (torque
// box and norm, rate, keep-out / keep-in cones, for every scheme) and the condensed Newton system
// [W + Σ g_i g_iᵀ/D_i] dδ = −∇f + Σ g_i (z_i + q_i/D_i), assembled in O(N) in the band of the
// unconstrained Hessian; ℓ1-elastic (a certificate of local infeasibility instead of an endless
// restoration) or free slacks (as IPOPT). The cones are imposed at their node half angle tightened
// by the user's margin (between nodes a cone's angle may dip: constraints.hpp:
// requiredConeMargin). The derivation: docs/notes/interior_point_formulation.md.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/barrier_forms.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/linalg/banded_matrix.hpp"
#include "planning/linalg/interruption.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

/// A grid level's multipliers z and slacks s (free-slack form), per group and instance, to start
/// the next finer level from (carried by the instances' times).
struct LevelDuals {
  int steps = 0;
  std::vector<int> first_k;
  std::vector<std::vector<double>> z, s;
  bool empty() const { return steps == 0; }
};

/// The node constraints of one problem in one formulation, and the condensed Newton system.
/// With a pointing end condition (ReducedProblem::hasTwist) the unknowns are (δ, ψ): every vector
/// has unknowns() + 1 entries, ψ last, and an assembly fills K's border and corner on ψ too.
class ConstrainedSystem final : public BarrierRows {
 public:
  ConstrainedSystem(const PlanningProblem& problem, ReducedProblem* np, Formulation formulation,
                    const InteriorPointParameters& parameters);

  int constraintCount() const { return block_.rows.count; }
  /// The constraint block (its rows, their forms, the row-by-row steps).
  BarrierRowBlock<FixedTimeStep>& block() { return block_; }
  const BarrierRowBlock<FixedTimeStep>& block() const { return block_; }
  /// Global unknowns beside the node unknowns: 1 (ψ) with a pointing end condition, else 0.
  int globals() const { return FixedTimeStep::globals(np_); }
  /// ∂L/∂ψ = ∂f/∂ψ − Σ zᵢ∂cᵢ/∂ψ [N²·m²/rad] and its size relative as relativeStationarity's
  /// (set by it; 0 without a twist).
  double twistGradient() const { return twist_gradient_; }
  double twistStationarity() const { return twist_stationarity_; }
  bool freeSlacks() const { return free_slacks_; }
  /// Polled every kColumnsBetweenPolls nodes during an assembly (null: never).
  void setInterruption(const Interruption* interruption) { interruption_ = interruption; }

  /// Constraint values at `steps` into each instance's c (gradients not formed).
  void evaluateValues(const ReducedProblem::StepVectors& steps, std::vector<Vector3>* torques_out);
  /// φ_μ = f + Σ ψ_μ(c_i) at `steps` (and f in *cost); FreeSlacks at s + slack_alpha ds.
  double merit(const ReducedProblem::StepVectors& steps, double mu, double rho, double* cost,
               double slack_alpha = 0.0);
  /// φ_μ from the constraint values of the last assembly (f = its cost): Elastic Σ ψ_μ(c_i) (ρ
  /// the penalty); FreeSlacks Σ −μ ln s_i + ρ|c_i − s_i| (ρ the merit's ν).
  double assembledMerit(double cost, double mu, double rho) const {
    return cost + block_.merit(mu, rho, 0.0);
  }

  /// Assembles the condensed Newton system at the current iterate: K (the band and, with a twist,
  /// its border and corner), rhs, ∇φ_μ. `primal`: the multipliers are replaced by their primal
  /// values μ/s (then the step is Newton's on φ_μ). kkt = null: the constraint values and
  /// gradients only (multipliers and slacks untouched). Returns f at the iterate.
  template <typename Scalar>
  double assemble(double mu, double rho, bool primal, KktBlocks<Scalar>* kkt, Eigen::VectorXd* rhs,
                  Eigen::VectorXd* merit_gradient);

  // BarrierRows (the predictor–corrector's part; q for the complementarity target).
  double affineComplementarity(const Eigen::VectorXd& d, double* average,
                               std::vector<double>* products) const override;
  void addSlackWeightedGradients(const std::vector<double>* products,
                                 Eigen::VectorXd* out) const override;
  void setComplementarityTarget(double mu, const std::vector<double>* products) override;

  /// What slackStep measures about the slack step.
  struct SlackStep {
    double alpha = 1.0;                 ///< largest step by the fraction to the boundary
    double barrier_slope = 0.0;         ///< −μ Σ ds/s
    double residual = 0.0;              ///< ‖c − s‖₁
    double significant_residual = 0.0;  ///< the same without round-off residuals
  };
  /// FreeSlacks: the slack steps ds = gᵀdδ + c − s (stored in the instances).
  SlackStep slackStep(const Eigen::VectorXd& d, double mu);
  void applySlackStep(double alpha);
  // BarrierRows (FreeSlacks' max |c − s|; the complementarity products).
  double maxSlackResidual() const override { return block_.maxSlackResidual(); }
  void complementarity(double mu, double rho, double* average, double* smallest) const override;
  /// σ_k = τ_k + (z⁺ − z⁻)/(a w_k) per axis (PlanResult::switching_function).
  std::vector<Vector3> switchingFunction(const std::vector<Vector3>& torque) const;
  /// max-norm of ∇f − Σ zᵢ∇cᵢ relative to |∂τ/∂R|·max|τ| at the current iterate.
  double relativeStationarity(double mu, double rho, Eigen::VectorXd* rhs,
                              Eigen::VectorXd* merit_gradient);
  /// The multipliers and slacks of this iterate (FreeSlacks), to start a finer level from.
  LevelDuals duals() const;
  /// FreeSlacks from a coarser level's duals (nearest in time); returns mean(s z).
  double warmStartDuals(const LevelDuals& coarse);
  /// The duals of a start from a plan that carries none (an initial guess of this N), in the form
  /// warmStartDuals takes them: re-derived from stationarity at the current iterate
  /// (multiplier_estimate.hpp). Evaluates the constraints' values and gradients.
  LevelDuals estimatedDuals();

 private:
  void addConstraintGradients(double mu, Eigen::VectorXd* rhs,
                              Eigen::VectorXd* merit_gradient) const;
  void pollEvery(int k) const;

  const PlanningProblem& problem_;
  ReducedProblem& np_;
  const InteriorPointParameters& parameters_;
  bool free_slacks_;
  std::unique_ptr<BarrierForm<9>> form_;  ///< FreeSlacks or L1Elastic: how a row enters φ_μ
  StageConstraints constraints_;          ///< buildStageConstraints(problem): one group each
  BarrierRowBlock<FixedTimeStep> block_;  ///< the rows (all in form_) and their passes
  const Interruption* interruption_ = nullptr;
  double twist_gradient_ = 0.0, twist_stationarity_ = 0.0;
};

}  // namespace attitude_planner
