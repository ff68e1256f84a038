// The three barrier rules (barrier_update.hpp).
#include "planning/interior_point/barrier_update.hpp"

#include <algorithm>
#include <cmath>

namespace attitude_planner {

double snapToFinalBarrier(double mu, double mu_final, const InteriorPointParameters& parameters) {
  return mu < parameters.barrier_snap_factor * mu_final ? mu_final : mu;
}

namespace {

/// Mehrotra's predictor–corrector: the affine-scaling step (μ = 0) says how far the
/// complementarity can fall; the barrier of this step is σ·mean(s z), σ = (μ_aff/mean)³, and the
/// corrector adds the affine step's second-order term ds_aff·dz_aff. One factorization, two more
/// solves.
class MehrotraPredictorCorrector : public BarrierUpdate {
 public:
  explicit MehrotraPredictorCorrector(const InteriorPointParameters& parameters)
      : parameters_(parameters) {}
  BarrierRule rule() const override { return BarrierRule::Mehrotra; }

  void beforeStep(const BarrierAccess& b, const FactorSolve& solve, const Eigen::VectorXd& rhs,
                  Eigen::VectorXd* delta) override {
    BarrierRows& state = *b.rows;
    const BarrierScales& scales = b.scales;
    double* mu = b.mu;
    Eigen::VectorXd barrier_part = Eigen::VectorXd::Zero(rhs.size());  // Σ g/s
    state.addSlackWeightedGradients(nullptr, &barrier_part);
    const Eigen::VectorXd affine_rhs = rhs - *mu * barrier_part;
    Eigen::VectorXd affine = affine_rhs;
    solve(&affine);
    double average = 0.0;
    const double mu_affine = state.affineComplementarity(affine, &average, &products_);
    const double sigma =
        std::pow(std::min(1.0, mu_affine / average), parameters_.mehrotra_exponent);
    *mu = std::max(
        scales.mu_final,
        std::min(*mu, std::max(sigma * average, progressFloor(scales, b.previous_decrement, *mu))));
    *mu = snapToFinalBarrier(*mu, scales.mu_final, parameters_);
    state.setComplementarityTarget(*mu, &products_);
    *delta = affine_rhs + *mu * barrier_part;
    state.addSlackWeightedGradients(&products_, delta);
    solve(delta);
  }

 private:
  /// Not below what the iterate's distance to the barrier problem's solution warrants (a
  /// relative decrement d is a cost error ~d²·f; the barrier's is ~m μ): a μ far below it leaves
  /// the rest of the way to Newton steps at a tiny μ, whose condensed system (its condition grows
  /// like N⁴ and 1/μ) no longer resolves them. The floor rises with N² above
  /// barrier_progress_floor_steps for the same reason.
  double progressFloor(const BarrierScales& scales, double previous_decrement, double mu) const {
    const double growth = std::max(
        1.0,
        std::pow(scales.steps / static_cast<double>(parameters_.barrier_progress_floor_steps), 2));
    const double floor_factor = std::min(1.0, parameters_.barrier_progress_floor * growth);
    return std::isfinite(previous_decrement)
               ? floor_factor * previous_decrement * previous_decrement * scales.f_scale /
                     scales.constraints
               : mu;
  }

  const InteriorPointParameters& parameters_;
  std::vector<double> products_;  ///< ds_aff·dz_aff per constraint
};

/// LOQO's adaptive rule: μ ← σ · mean(s z, v u), σ = 0.1 min(0.05 (1 − ξ)/ξ, 2)³, ξ = smallest /
/// mean product (how far from central), never increasing.
class LoqoBarrier : public BarrierUpdate {
 public:
  explicit LoqoBarrier(const InteriorPointParameters& parameters) : parameters_(parameters) {}
  BarrierRule rule() const override { return BarrierRule::Loqo; }

  void afterStep(const BarrierAccess& b, const AcceptedStep&) override {
    const InteriorPointParameters& p = parameters_;
    double* mu = b.mu;
    const BarrierScales& scales = b.scales;
    double average = 0.0, smallest = 0.0;
    b.rows->complementarity(*mu, b.rho, &average, &smallest);
    const double xi = smallest / average;
    const double sigma =
        p.loqo_scale * std::pow(std::min(p.loqo_centrality * (1 - xi) / xi, p.loqo_cap), 3);
    *mu = std::max(scales.mu_final, std::min(*mu, sigma * average));
    *mu = snapToFinalBarrier(*mu, scales.mu_final, p);
  }

 private:
  const InteriorPointParameters& parameters_;
};

}  // namespace

MonotoneProfile fixedStepMonotone(const InteriorPointParameters& parameters) {
  return {parameters.fixed_step.theta_mu, BarrierProblemTest::Decrement, true};
}

MonotoneProfile freeTimeMonotone(const InteriorPointParameters& parameters) {
  return {parameters.free_time.theta_mu, BarrierProblemTest::KktResidual, false};
}

bool MonotoneBarrier::subproblemSolved(const BarrierState& state, const BarrierAccess& b) const {
  return profile_.test == BarrierProblemTest::KktResidual && !state.at_final_barrier &&
         (state.solved_to_round_off || solved(state.barrier_residual, *b.mu, b.scales));
}

void MonotoneBarrier::afterStep(const BarrierAccess& b, const AcceptedStep& step) {
  if (profile_.test != BarrierProblemTest::Decrement) return;
  const InteriorPointParameters& p = parameters_;
  double* mu = b.mu;
  const BarrierScales& scales = b.scales;
  const double scaled_mu = *mu * scales.constraints / scales.f_scale;
  const bool stalled =
      step.alpha == 1.0 && step.relative_decrement > p.stall_ratio * b.previous_decrement;
  stalled_steps_ = stalled ? stalled_steps_ + 1 : 0;
  const bool solved = step.relative_decrement <= p.monotone_kappa_epsilon * scaled_mu ||
                      stalled_steps_ >= p.monotone_stalled_steps;
  if (b.rows->maxSlackResidual() <= p.monotone_kappa_epsilon * scaled_mu && solved) {
    *mu = decreased(*mu, scales);
    stalled_steps_ = 0;
  }
}

bool MonotoneBarrier::solved(double kkt_residual, double mu, const BarrierScales& scales) const {
  return kkt_residual <=
         parameters_.monotone_kappa_epsilon * (mu * scales.constraints / scales.f_scale);
}

double MonotoneBarrier::decreased(double mu, const BarrierScales& scales) const {
  const InteriorPointParameters& p = parameters_;
  const double scaled_mu = mu * scales.constraints / scales.f_scale;
  const double next = std::max(
      scales.mu_final, std::min(p.monotone_kappa_mu * mu, std::pow(scaled_mu, profile_.theta_mu) *
                                                              scales.f_scale / scales.constraints));
  return profile_.snap_to_final ? snapToFinalBarrier(next, scales.mu_final, p) : next;
}

std::unique_ptr<BarrierUpdate> makeBarrierUpdate(BarrierRule rule,
                                                 const InteriorPointParameters& parameters) {
  switch (rule) {
    case BarrierRule::Mehrotra:
      return std::make_unique<MehrotraPredictorCorrector>(parameters);
    case BarrierRule::Monotone:
      return std::make_unique<MonotoneBarrier>(parameters, fixedStepMonotone(parameters));
    case BarrierRule::Loqo:
      return std::make_unique<LoqoBarrier>(parameters);
  }
  return nullptr;
}

}  // namespace attitude_planner
