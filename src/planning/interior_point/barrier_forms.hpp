// The constraint rows of the interior point and the barrier forms that say how a row c(x) ≥ 0
// enters the barrier problem: its multiplier's safeguard, its merit term, its dual step.
//   FreeSlacks (fixed h): c − s = 0, s > 0 a variable, −μ ln s + ν|c − s| in the merit.
//   L1Elastic  (fixed h): c + v − s = 0, s, v ≥ 0 eliminated for c (elasticSlacks), the merit
//                         ψ_μ(c) = ρ v − μ ln s − μ ln v; its multiplier z < ρ (u = ρ − z > 0).
//   Feasible   (free time): −μ ln c, every iterate strictly inside; the feasible dual step
//                         dz = μ/c − z − (z/c) gᵀd.
// κ_Σ (dual_safeguard) keeps each form's moment: the slack forms clamp z where a row is prepared
// for an assembly (with the new μ), Feasible after a step is accepted (with the step's μ).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/interior_point_parameters.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "planning/transcription/stage_quantities.hpp"
#include "planning/transcription/stage_transcription.hpp"

namespace attitude_planner {

/// What a barrier rule (barrier_update.hpp) reads of the barrier problem's rows, and Mehrotra's
/// corrector sets: a view the problem implements (ConstrainedSystem at fixed h), so that the rules
/// do not depend on the problem they update.
class BarrierRows {
 public:
  virtual ~BarrierRows() = default;
  /// Mehrotra's predictor: from the affine-scaling step d (μ = 0), μ_aff = mean((s + α_p ds)(z +
  /// α_d dz)), and the mean complementarity now (*average); ds_aff·dz_aff in `products`.
  virtual double affineComplementarity(const Eigen::VectorXd& d, double* average,
                                       std::vector<double>* products) const = 0;
  /// Adds Σ_i g_i/s_i or, with `products`, Σ_i −g_i·products_i/s_i, to `out`.
  virtual void addSlackWeightedGradients(const std::vector<double>* products,
                                         Eigen::VectorXd* out) const = 0;
  /// The complementarity target s z = μ − ds_aff dz_aff (`products` null: μ).
  virtual void setComplementarityTarget(double mu, const std::vector<double>* products) = 0;
  /// max |c − s| at the last evaluated c (the barrier problem's primal residual).
  virtual double maxSlackResidual() const = 0;
  /// Mean and smallest complementarity product (s z and v u; FreeSlacks: s z).
  virtual void complementarity(double mu, double rho, double* average, double* smallest) const = 0;
};

/// The ℓ1-elastic row c + v − s = 0 at its value c: the slacks s, v (elasticSlacks), the
/// multiplier z (the primal μ/s, or κ_Σ-safeguarded and kept below ρ so that u = ρ − z > 0) and
/// the condensation terms D = s/z + v/u, q = μ/z − s − μ/u + v: the row adds g gᵀ/D to the
/// Newton matrix, (z + q/D) g to its right-hand side, and dz = (q − gᵀd)/D. One rule for the
/// fixed-h L1Elastic form and the free-time solver's elastic start.
template <int Entries>
void prepareElasticRow(ConstraintRow<Entries>& row, double mu, double rho, bool primal,
                       const InteriorPointParameters& p);
/// `alpha` limited by the fraction to the boundary on z and on u = ρ − z after the step dz.
double elasticDualStepLimit(double z, double dz, double rho, double alpha,
                            const InteriorPointParameters& p);

/// How a row enters the fixed-h barrier problem (Formulation::FreeSlacks or Elastic).
class SlackForm {
 public:
  explicit SlackForm(const InteriorPointParameters& parameters) : p_(parameters) {}
  virtual ~SlackForm() = default;
  /// Slacks, the (κ_Σ-safeguarded, or primal μ/s) multiplier and the condensation terms D, q for
  /// the row's value c.
  virtual void prepare(FixedStepRow& row, double mu, double rho, bool primal) const = 0;
  /// The row's term of the merit (ρ: the elastic penalty; FreeSlacks: the merit's ν, at the slack
  /// s + α ds).
  virtual double rowMerit(const FixedStepRow& row, double mu, double rho, double alpha) const = 0;
  /// Whether ∇_δ φ_μ carries the row's barrier term −(μ/s) g (L1Elastic: the slacks are
  /// functions of c; FreeSlacks: the slack step's slope carries it).
  virtual bool barrierInMeritGradient() const = 0;
  /// `alpha` limited by the fraction to the boundary after the row's dual step dz.
  virtual double dualStepLimit(const FixedStepRow& row, double dz, double rho,
                               double alpha) const = 0;
  /// The first multiplier (and FreeSlacks' slack) at the row's value c: the primal one μ/s,
  /// capped at `cap`.
  virtual void initialize(FixedStepRow& row, double mu, double rho, double cap) const = 0;
  /// Adds the row's complementarity products (s z; L1Elastic also v u) to *sum and *count and
  /// their least to *low.
  virtual void addComplementarity(const FixedStepRow& row, double mu, double rho, double* sum,
                                  double* low, int* count) const = 0;

 protected:
  /// z ≥ 0 kept at least (1 − τ) of itself.
  double multiplierLimit(const FixedStepRow& row, double dz, double alpha) const;
  const InteriorPointParameters& p_;
};

/// c − s = 0 with s > 0 free: the multiplier stays near μ/s, the condensation that of c − s = 0.
class FreeSlacks final : public SlackForm {
 public:
  using SlackForm::SlackForm;
  void prepare(FixedStepRow& row, double mu, double rho, bool primal) const override;
  double rowMerit(const FixedStepRow& row, double mu, double rho, double alpha) const override;
  bool barrierInMeritGradient() const override { return false; }
  double dualStepLimit(const FixedStepRow& row, double dz, double rho, double alpha) const override;
  void initialize(FixedStepRow& row, double mu, double rho, double cap) const override;
  void addComplementarity(const FixedStepRow& row, double mu, double rho, double* sum, double* low,
                          int* count) const override;
};

/// c + v − s = 0, ℓ1-penalized v (the certificate of local infeasibility at fixed h).
class L1Elastic final : public SlackForm {
 public:
  using SlackForm::SlackForm;
  void prepare(FixedStepRow& row, double mu, double rho, bool primal) const override;
  double rowMerit(const FixedStepRow& row, double mu, double rho, double alpha) const override;
  bool barrierInMeritGradient() const override { return true; }
  double dualStepLimit(const FixedStepRow& row, double dz, double rho, double alpha) const override;
  void initialize(FixedStepRow& row, double mu, double rho, double cap) const override;
  void addComplementarity(const FixedStepRow& row, double mu, double rho, double* sum, double* low,
                          int* count) const override;
};

std::unique_ptr<SlackForm> makeSlackForm(Formulation formulation,
                                         const InteriorPointParameters& parameters);

/// −μ Σ ln c with every iterate strictly inside (free time). A scalar barrier unknown (the elastic
/// start's θ ≥ 0) is one more such row with c = θ: the same functions on (z, c).
class Feasible {
 public:
  explicit Feasible(const InteriorPointParameters& parameters) : p_(parameters) {}
  /// The primal multiplier μ/c.
  double initialMultiplier(double c, double mu) const { return mu / c; }
  /// z within [μ/(κ_Σ c), κ_Σ μ/c].
  double safeguarded(double z, double c, double mu) const;
  /// −μ ln c added to *phi while *inside: false (and *inside false) where c ≤ 0 or, checking the
  /// boundary, c < (1 − τ) c_old.
  void addRowMerit(double c, double c_old, double mu, bool check_boundary, bool* inside,
                   double* phi) const;
  /// dz = μ/c − z − (z/c) slope (slope = gᵀd + r at the assembled point), and `alpha` limited
  /// by the fraction to the boundary on z.
  double dualDirection(double z, double c, double mu, double slope, double* alpha) const;
  /// max(‖∇L‖∞, max |zc − μ|) over the rows (the barrier problem's KKT residual without θ).
  double residual(const std::vector<FreeTimeRows>& rows, double stationarity, double mu) const;
  /// Σ zᵢcᵢ at the assembled point.
  double dualityGap(const std::vector<FreeTimeRows>& rows) const;

 private:
  const InteriorPointParameters& p_;
};

}  // namespace attitude_planner
