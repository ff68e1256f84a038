// The interior point's node constraints and its condensed Newton system (constrained_system.hpp).
#include "planning/interior_point/constrained_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "planning/interior_point/multiplier_estimate.hpp"
#include "planning/linalg/double_double.hpp"
#include "planning/transcription/node_constraints.hpp"

namespace attitude_planner {

ConstrainedSystem::ConstrainedSystem(const PlanningProblem& problem, ReducedProblem* np,
                                     Formulation formulation,
                                     const InteriorPointParameters& parameters)
    : problem_(problem),
      np_(*np),
      parameters_(parameters),
      free_slacks_(formulation == Formulation::FreeSlacks),
      form_(makeSlackForm(formulation, parameters)),
      constraints_(buildStageConstraints(problem)),
      block_(
          constraints_, *np,
          [form = form_.get()](const FixedStepRows&) -> const BarrierForm<9>& { return *form; }) {}

void ConstrainedSystem::evaluateValues(const ReducedProblem::StepVectors& steps,
                                       std::vector<Vector3>* torques_out) {
  const QuantityInputs at(np_, steps);
  block_.rows.evaluate(at);
  if (torques_out) *torques_out = at.torques();
}

double ConstrainedSystem::merit(const ReducedProblem::StepVectors& steps, double mu, double rho,
                                double* cost, double slack_alpha) {
  std::vector<Vector3> tau;
  evaluateValues(steps, &tau);
  const double f = np_.scheme().cost(tau);
  if (cost) *cost = f;
  return f + block_.merit(mu, rho, slack_alpha);
}

void ConstrainedSystem::pollEvery(int k) const {
  if (interruption_ && k % kColumnsBetweenPolls == 0) interruption_->poll();
}

/// The stencils hold the residuals r_k = √w_k τ_k (w_k the cost weight, 1 but at the end nodes of
/// schemes with end torques): constraints are on τ_k = r_k/√w_k, so with c' = ∂c/∂τ,
/// ∇c = Jᵀc'/√w_k and −z∇²c = Σ_i (−z c'_i/√w_k) ∇²r_i − (z c''/w_k) JᵀJ (c'' the constraint's
/// isotropic curvature). The rows are prepared where their values are formed, in the stencil's
/// weights callback: their multipliers enter the second-order weights; the rows' right-hand
/// side terms are added after the pass (addConstraintGradients).
template <typename Scalar>
double ConstrainedSystem::assemble(double mu, double rho, bool primal, KktBlocks<Scalar>* kkt,
                                   Eigen::VectorXd* rhs, Eigen::VectorXd* merit_gradient) {
  std::optional<KktSink<Scalar, FixedTimeStep>> sink;
  if (kkt) sink.emplace(np_, FixedTimeStep{}, kkt);
  rhs->setZero(np_.unknowns() + globals());
  merit_gradient->setZero(np_.unknowns() + globals());
  AssemblyChoices choices;
  choices.prepare_at_value = true;
  choices.primal = primal;
  const double cost = block_.assemble(sink ? &*sink : nullptr, FixedTimeStep{}, mu, rho, choices,
                                      rhs, merit_gradient, [&](int k) { pollEvery(k); });
  addConstraintGradients(mu, rhs, merit_gradient);
  return cost;
}

/// ∇φ_μ = ∇f − Σ (μ/s) g (Elastic; FreeSlacks: ∇_δ φ = ∇f, the slacks' part is the slack step's
/// slope); rhs = −∇f + Σ g (z + q/D).
void ConstrainedSystem::addConstraintGradients(double mu, Eigen::VectorXd* rhs,
                                               Eigen::VectorXd* merit_gradient) const {
  block_.rows.forEach([&](const FixedStepRows& g, int k, const FixedStepRow& in) {
    if (form_->barrierInMeritGradient())
      block_.rows.addRow(np_, g, k, in.g, -mu / in.s, merit_gradient);
    block_.rows.addRow(np_, g, k, in.g, form_->terms(in, mu).rhs, rhs);
  });
}

/// FreeSlacks (the affine-scaling step solved with μ = 0, i.e. q = −c).
double ConstrainedSystem::affineComplementarity(const Eigen::VectorXd& d, double* average,
                                                std::vector<double>* products) const {
  products->clear();
  double alpha_p = 1.0, alpha_d = 1.0, sum = 0.0;
  std::vector<double> ds, dz;
  block_.rows.forEach([&](const FixedStepRows& g, int k, const FixedStepRow& in) {
    const double lin = block_.rows.dot(np_, g, k, in.g, d);
    ds.push_back(lin + in.c - in.s);
    dz.push_back((-in.c - lin) / in.D);
    if (ds.back() < 0) alpha_p = std::min(alpha_p, -in.s / ds.back());
    if (dz.back() < 0) alpha_d = std::min(alpha_d, -in.z / dz.back());
    sum += in.s * in.z;
  });
  double affine = 0.0;
  std::size_t i = 0;
  block_.rows.forEach([&](const FixedStepRows&, int, const FixedStepRow& in) {
    affine += (in.s + alpha_p * ds[i]) * (in.z + alpha_d * dz[i]);
    products->push_back(ds[i] * dz[i]);
    ++i;
  });
  const double m = std::max<double>(1.0, static_cast<double>(i));
  *average = sum / m;
  return affine / m;
}

void ConstrainedSystem::addSlackWeightedGradients(const std::vector<double>* products,
                                                  Eigen::VectorXd* out) const {
  std::size_t i = 0;
  block_.rows.forEach([&](const FixedStepRows& g, int k, const FixedStepRow& in) {
    block_.rows.addRow(np_, g, k, in.g, products ? -(*products)[i++] / in.s : 1.0 / in.s, out);
  });
}

/// The condensation's q for that target (FreeSlacks).
void ConstrainedSystem::setComplementarityTarget(double mu, const std::vector<double>* products) {
  std::size_t i = 0;
  block_.rows.forEach([&](FixedStepRows&, int, FixedStepRow& in) {
    in.q = (mu - (products ? (*products)[i++] : 0.0)) / in.z - in.c;
  });
}

ConstrainedSystem::SlackStep ConstrainedSystem::slackStep(const Eigen::VectorXd& d, double mu) {
  SlackStep step;
  block_.rows.forEach([&](const FixedStepRows& g, int k, FixedStepRow& in) {
    in.ds = block_.rows.dot(np_, g, k, in.g, d) + in.c - in.s;
    if (in.ds < 0) {
      step.alpha = std::min(step.alpha, -parameters_.fraction_to_boundary * in.s / in.ds);
    }
    step.barrier_slope -= mu * in.ds / in.s;
    step.residual += std::abs(in.c - in.s);
    if (std::abs(in.c - in.s) > parameters_.round_off_slack_residual) {
      step.significant_residual += std::abs(in.c - in.s);
    }
  });
  return step;
}

void ConstrainedSystem::applySlackStep(double alpha) {
  block_.rows.forEach([&](FixedStepRows&, int, FixedStepRow& in) { in.s += alpha * in.ds; });
}

void ConstrainedSystem::complementarity(double mu, double rho, double* average,
                                        double* smallest) const {
  const Complementarity products = block_.complementarity(mu, rho);
  *average = products.average();
  *smallest = products.low;
}

/// Empty without per-axis bounds.
std::vector<Vector3> ConstrainedSystem::switchingFunction(
    const std::vector<Vector3>& torque) const {
  if (!block_.rows.hasTorqueBox()) return {};
  std::vector<Vector3> sigma = torque;
  block_.rows.addBoxMultipliers(np_, torque, &sigma, nullptr);
  return sigma;
}

/// As the Newton solver's max_residual; the gradients re-formed at the iterate (the last
/// assembly's are the previous iterate's), the multipliers left as they are.
double ConstrainedSystem::relativeStationarity(double mu, double rho, Eigen::VectorXd* rhs,
                                               Eigen::VectorXd* merit_gradient) {
  assemble<double>(mu, rho, false, nullptr, rhs, merit_gradient);
  double scale = 0.0;  // max|∂τ/∂δ| · max|τ|
  Eigen::VectorXd residual;
  if (np_.hasTwist()) {
    np_.evaluateWithTwist(&residual, nullptr, nullptr, nullptr, &scale);  // ∇f, ∂f/∂ψ last
  } else {
    np_.evaluate(&residual, nullptr, &scale);  // ∇f
  }
  block_.rows.forEach([&](const FixedStepRows& g, int k, const FixedStepRow& in) {
    block_.rows.addRow(np_, g, k, in.g, -in.z, &residual);
  });
  twist_gradient_ = np_.hasTwist() ? residual(np_.unknowns()) : 0.0;
  twist_stationarity_ = scale > 0 ? std::abs(twist_gradient_) / scale : 0.0;
  return residual.size() && scale > 0 ? residual.cwiseAbs().maxCoeff() / scale : 0.0;
}

LevelDuals ConstrainedSystem::duals() const {
  LevelDuals d;
  d.steps = np_.steps();
  for (const FixedStepRows& g : block_.rows.groups) {
    d.first_k.push_back(g.support.first_k);
    d.z.emplace_back();
    d.s.emplace_back();
    for (const FixedStepRow& in : g.at) {
      d.z.back().push_back(in.z);
      d.s.back().push_back(in.s);
    }
  }
  return d;
}

/// FreeSlacks from a coarser level's duals: each instance takes the multiplier of the coarse
/// instance nearest in time (a node constraint's multiplier does not scale with h: the cost
/// Σ ½|τ_k|² weighs every node alike), and its slack c pushed inside by at most
/// parameters_.warm_slack_push where the coarse constraint was binding (its coarse slack below the
/// push), else as the form's initialize pushes it. Returns mean(s z).
double ConstrainedSystem::warmStartDuals(const LevelDuals& coarse) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t gi = 0; gi < block_.rows.groups.size() && gi < coarse.z.size(); ++gi) {
    FixedStepRows& g = block_.rows.groups[gi];
    const std::vector<double>& zc = coarse.z[gi];
    if (zc.empty()) continue;
    for (int k = g.support.first_k; k <= g.support.last_k; ++k) {
      const int kc = static_cast<int>(std::lround(double(k) * coarse.steps / np_.steps()));
      const int i = std::min<int>(zc.size() - 1, std::max(0, kc - coarse.first_k[gi]));
      FixedStepRow& in = g.instance(k);
      const bool binding = coarse.s[gi][i] < parameters_.warm_slack_push;
      in.z = zc[i];
      in.s = std::max(in.c, binding ? parameters_.warm_slack_push : parameters_.slack_push);
      // Duals of this very grid (an estimate at an initial guess) come with their own slacks.
      if (coarse.steps == np_.steps()) in.s = std::max(in.c, coarse.s[gi][i]);
      in.ds = 0.0;
      sum += in.s * in.z;
      ++count;
    }
  }
  return sum / std::max(count, 1);
}

LevelDuals ConstrainedSystem::estimatedDuals() {
  Eigen::VectorXd rhs, merit_gradient, cost_gradient;
  // Gradients of every constraint (H = null leaves multipliers and slacks untouched), then the
  // values (the torque constraints' are formed with the Hessian only).
  assemble<double>(0.0, 1.0, false, nullptr, &rhs, &merit_gradient);
  evaluateValues(np_.current(), nullptr);
  double gradient_scale = 0.0;
  const double cost = np_.evaluate(&cost_gradient, nullptr, &gradient_scale);
  std::vector<StationarityColumn> columns;
  block_.rows.forEach([&](const FixedStepRows& g, int k, const FixedStepRow& in) {
    StationarityColumn column{in.c, in.g};
    for (int n = 0; n < g.support.width; ++n)
      column.index[n] = np_.variableIndex(k + g.support.node_offset + n);
    columns.push_back(column);
  });
  // Without an active constraint the multipliers take μ/c with μ a share of the cost per
  // constraint: the scale the cold start's barrier has too.
  const MultiplierEstimate e =
      estimateMultipliers(cost_gradient, columns, cost / std::max(block_.rows.count, 1));
  LevelDuals d;
  d.steps = np_.steps();
  std::size_t i = 0;
  for (const FixedStepRows& g : block_.rows.groups) {
    d.first_k.push_back(g.support.first_k);
    d.z.emplace_back(e.z.begin() + i, e.z.begin() + i + g.at.size());
    d.s.emplace_back(e.s.begin() + i, e.s.begin() + i + g.at.size());
    i += g.at.size();
  }
  return d;
}

template double ConstrainedSystem::assemble<double>(double, double, bool, KktBlocks<double>*,
                                                    Eigen::VectorXd*, Eigen::VectorXd*);
template double ConstrainedSystem::assemble<long double>(double, double, bool,
                                                         KktBlocks<long double>*, Eigen::VectorXd*,
                                                         Eigen::VectorXd*);
template double ConstrainedSystem::assemble<DoubleDouble>(double, double, bool,
                                                          KktBlocks<DoubleDouble>*,
                                                          Eigen::VectorXd*, Eigen::VectorXd*);

}  // namespace attitude_planner
