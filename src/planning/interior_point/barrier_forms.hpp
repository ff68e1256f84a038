// How a row c(x) ≥ 0 of a stage transcription enters a barrier problem (BarrierForm: FreeSlacks,
// L1Elastic, Feasible), and the loops over the rows written once for both interior points
// (BarrierRowBlock).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/transcription/node_constraints.hpp"
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

/// How a prepared row enters the condensed Newton system [W + Σ ω g gᵀ] dx = −∇f + Σ β g.
struct RowTerms {
  double weight;  ///< ω
  double rhs;     ///< β
};

/// The rows' complementarity products (s z; an elastic row also v u; Feasible z c).
struct Complementarity {
  double sum = 0.0;  ///< Σ of the products (an elastic row's pair added as one term)
  double low = std::numeric_limits<double>::infinity();  ///< the least product
  double worst = 0.0;  ///< max |product − μ|: the barrier problem's complementarity residual
  int count = 0;
  double average() const { return sum / std::max(count, 1); }
  /// One row's product (a slack or value times its multiplier) at the barrier μ.
  void add(double product, double mu) {
    sum += product;
    low = std::min(low, product);
    worst = std::max(worst, std::abs(product - mu));
    ++count;
  }
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

/// How a row c(x) ≥ 0 enters a barrier problem, on the rows of either time step (Entries 9 at a
/// fixed h, 10 with h free). κ_Σ keeps each form's moment: the slack forms clamp z in prepare
/// (with the new μ), Feasible in afterAccept (with the step's μ).
template <int Entries>
class BarrierForm {
 public:
  using Row = ConstraintRow<Entries>;
  explicit BarrierForm(const InteriorPointParameters& parameters) : p_(parameters) {}
  virtual ~BarrierForm() = default;
  /// The multiplier (κ_Σ-safeguarded, or the primal one) and the condensation terms for the
  /// row's value c, where the row is prepared for an assembly (Feasible: only the primal one).
  virtual void prepare(Row& row, double mu, double rho, bool primal) const = 0;
  virtual RowTerms terms(const Row& row, double mu) const = 0;
  /// The row's term of the merit at value c (row.c the accepted one; ρ: the elastic penalty,
  /// FreeSlacks the merit's ν at the slack s + α ds); +∞ where c is outside the form's domain
  /// (Feasible, checking the boundary: c ≤ 0 or c < (1 − τ) row.c).
  virtual double rowMerit(const Row& row, double c, double mu, double rho, double alpha,
                          bool check_boundary) const = 0;
  /// The multiplier's step dz (into row.dz) for the row's slope gᵀd (+ r), and `alpha` limited
  /// by the fraction to the boundary after it.
  virtual double dualStep(Row& row, double slope, double mu, double rho, double alpha) const = 0;
  virtual void addComplementarity(const Row& row, double mu, double rho,
                                  Complementarity* out) const = 0;
  /// κ_Σ after an accepted step, at the row's new value c (Feasible's moment; the slack forms
  /// clamp in prepare).
  virtual void afterAccept(Row&, double) const {}
  /// Whether ∇_δ φ_μ carries the row's barrier term −(μ/s) g (L1Elastic: the slacks are
  /// functions of c; FreeSlacks: the slack step's slope carries it).
  virtual bool barrierInMeritGradient() const { return true; }
  /// The first multiplier (and FreeSlacks' slack) at the row's value c: the primal one μ/s,
  /// capped at `cap`.
  virtual void initialize(Row& row, double mu, double rho, double cap) const = 0;

 protected:
  double multiplierLimit(double z, double dz, double alpha) const {
    if (dz < 0) alpha = std::min(alpha, -p_.fraction_to_boundary * z / dz);
    return alpha;
  }
  const InteriorPointParameters& p_;
};

/// c − s = 0 with s > 0 a variable (fixed h), −μ ln s + ν|c − s| in the merit.
class FreeSlacks final : public BarrierForm<9> {
 public:
  using BarrierForm::BarrierForm;
  void prepare(Row& row, double mu, double rho, bool primal) const override;
  RowTerms terms(const Row& row, double) const override {
    return {1.0 / row.D, row.z + row.q / row.D};
  }
  double rowMerit(const Row& row, double c, double mu, double rho, double alpha,
                  bool) const override;
  double dualStep(Row& row, double slope, double, double, double alpha) const override {
    row.dz = (row.q - slope) / row.D;
    return multiplierLimit(row.z, row.dz, alpha);  // z has no upper bound
  }
  void addComplementarity(const Row& row, double mu, double rho,
                          Complementarity* out) const override;
  bool barrierInMeritGradient() const override { return false; }
  void initialize(Row& row, double mu, double rho, double cap) const override;
};

/// c + v − s = 0, ℓ1-penalized v, s and v eliminated for c (elasticSlacks): the certificate of
/// local infeasibility at fixed h, and the free-time solver's elastic start (Entries 10).
template <int Entries>
class L1Elastic final : public BarrierForm<Entries> {
 public:
  using Row = ConstraintRow<Entries>;
  using BarrierForm<Entries>::BarrierForm;
  void prepare(Row& row, double mu, double rho, bool primal) const override {
    prepareElasticRow(row, mu, rho, primal, this->p_);
  }
  RowTerms terms(const Row& row, double) const override {
    return {1.0 / row.D, row.z + row.q / row.D};
  }
  double rowMerit(const Row&, double c, double mu, double rho, double, bool) const override {
    return elasticSlacks(c, mu, rho).psi;
  }
  double dualStep(Row& row, double slope, double, double rho, double alpha) const override {
    row.dz = (row.q - slope) / row.D;
    return elasticDualStepLimit(row.z, row.dz, rho, alpha, this->p_);
  }
  void addComplementarity(const Row& row, double mu, double rho,
                          Complementarity* out) const override {
    const ElasticSlacks sl = elasticSlacks(row.c, mu, rho);
    const double a = sl.s * row.z, b = sl.v * (rho - row.z);
    out->sum += a + b;
    out->low = std::min(out->low, std::min(a, b));
    out->worst = std::max({out->worst, std::abs(a - mu), std::abs(b - mu)});
    out->count += 2;
  }
  void initialize(Row& row, double mu, double rho, double cap) const override {
    const ElasticSlacks sl = elasticSlacks(row.c, mu, rho);
    row.z = std::min(mu / sl.s, std::min(cap, 0.5 * rho));
  }
};

/// The fixed-h form of a formulation (Formulation::FreeSlacks or Elastic).
std::unique_ptr<BarrierForm<9>> makeSlackForm(Formulation formulation,
                                              const InteriorPointParameters& parameters);

/// −μ ln c with every iterate strictly inside (free time): the multiplier's feasible step
/// dz = μ/c − z − (z/c)(gᵀd + r), κ_Σ after each accepted step.
class Feasible final : public BarrierForm<10> {
 public:
  using BarrierForm::BarrierForm;
  void prepare(Row& row, double mu, double, bool primal) const override {
    if (primal) row.z = mu / row.c;
  }
  RowTerms terms(const Row& row, double mu) const override { return {row.z / row.c, mu / row.c}; }
  double rowMerit(const Row& row, double c, double mu, double, double,
                  bool check_boundary) const override;
  double dualStep(Row& row, double slope, double mu, double, double alpha) const override {
    row.dz = mu / row.c - row.z - row.z / row.c * slope;
    return multiplierLimit(row.z, row.dz, alpha);
  }
  void addComplementarity(const Row& row, double mu, double, Complementarity* out) const override;
  void afterAccept(Row& row, double mu) const override;
  void initialize(Row& row, double mu, double, double cap) const override {
    row.z = std::min(mu / row.c, cap);
  }
};

/// Where the two profiles' assemblies differ (BarrierRowBlock::assemble), as values.
struct AssemblyChoices {
  /// The cost's weight on its residual's Gauss–Newton term and gradient: 1 (fixed h: C), or ε
  /// (free time: ε C).
  double cost_weight = 1.0;
  /// A torque row is prepared where its value is formed, before z enters the stencil's
  /// second-order weights (fixed h), or after the weights used z (free time: the elastic
  /// safeguard may change z in between). Its c'' joins W where it is prepared.
  bool prepare_at_value = false;
  /// A local block's rank-one terms folded into it in double and the block added once (free
  /// time), or added one by one in the band's precision (fixed h: the precision rule,
  /// grid_solve.hpp), a box side's into its axis's Gauss–Newton weight.
  bool sum_in_double = false;
  /// Each row's β g and −z g go to the right-hand side and the gradient in the pass (free time:
  /// −∇φ_μ and ∇L); else the gradient is the cost's alone (fixed h adds the rows after it).
  bool row_gradients = false;
  bool primal = false;  ///< the rows prepared with their primal multipliers
  /// The quantities that do not move with h first (free time: the order its sums were formed in).
  bool fixed_quantities_first = false;
};

/// A merit's sum over the rows: +∞ once a row is outside its form's domain.
struct MeritSum {
  double phi = 0.0;
  bool inside = true;
  void add(double term) {
    if (term == std::numeric_limits<double>::infinity()) inside = false;
    if (inside) phi += term;
  }
  double value() const { return inside ? phi : std::numeric_limits<double>::infinity(); }
};

/// The constraint block of a barrier problem over a stage transcription: its rows and what a
/// primal–dual method does with them row by row, for either time step. `form(group)` is the form
/// a group's rows are in now. Sums run in StageTranscription::forEach's order.
template <typename TimeStep>
class BarrierRowBlock {
 public:
  static constexpr int kEntries = TimeStep::kEntries;
  using Rows = ConstraintRows<kEntries>;
  using Row = ConstraintRow<kEntries>;
  using Form = BarrierForm<kEntries>;
  using FormOf = std::function<const Form&(const Rows&)>;

  BarrierRowBlock(const StageConstraints& constraints, const ReducedProblem& np, FormOf form)
      : rows(constraints, np), np_(np), form_(std::move(form)) {}

  const Form& form(const Rows& g) const { return form_(g); }
  void evaluate(const ReducedProblem::StepVectors& steps) {
    rows.evaluate(QuantityInputs(np_, steps));
  }
  /// The rows' merit terms (BarrierForm::rowMerit) at their own values c.
  double merit(double mu, double rho, double alpha) const {
    MeritSum sum;
    rows.forEach([&](const Rows& g, int, const Row& in) {
      sum.add(form(g).rowMerit(in, in.c, mu, rho, alpha, false));
    });
    return sum.value();
  }
  /// Each row's merit term at its value at `at` (rows untouched; `check_boundary` as rowMerit's)
  /// into `terms`, forEach's order, while it is finite; false at the first +∞ term (a value
  /// outside its row's domain: the merit there is +∞), the rows after it not evaluated.
  /// `outside` (optional): the index of a row found outside before, tested first (the trials of
  /// one line search mostly fail at one row), and where a row is found outside now, its index.
  bool rowMeritsInside(const QuantityInputs& at, double mu, double rho, bool check_boundary,
                       std::vector<double>* terms, int* outside = nullptr) const {
    const auto term = [&](const Rows& g, int k, const Row& in) {
      return form(g).rowMerit(in, rows.valueAt(g, at, k), mu, rho, 0.0, check_boundary);
    };
    constexpr double kOutside = std::numeric_limits<double>::infinity();
    const int hint = outside ? *outside : -1;
    double hinted = 0.0;
    terms->clear();
    if (hint >= 0) {
      rows.forEachFrom(hint, [&](const Rows& g, int k, const Row& in) {
        hinted = term(g, k, in);
        return false;
      });
      if (hinted == kOutside) return false;
    }
    return rows.forEachFrom(0, [&](const Rows& g, int k, const Row& in) {
      const int index = static_cast<int>(terms->size());
      terms->push_back(index == hint ? hinted : term(g, k, in));
      if (terms->back() != kOutside) return true;
      if (outside) *outside = index;
      return false;
    });
  }
  /// `start` plus the rows' merit terms as rowMeritsInside gave them, summed in their order.
  static double merit(double start, const std::vector<double>& terms) {
    MeritSum sum{start};
    for (const double term : terms) sum.add(term);
    return sum.value();
  }
  /// The rows' dual steps dz for the step d (slope gᵀd + r, r a second-order correction's term),
  /// and the largest step in (0, 1] by the fraction to the boundary.
  double dualStep(const Eigen::VectorXd& d, double mu, double rho) {
    double alpha = 1.0;
    rows.forEach([&](const Rows& g, int k, Row& in) {
      alpha = form(g).dualStep(in, rows.dot(np_, g, k, in.g, d) + in.r, mu, rho, alpha);
    });
    return alpha;
  }
  void applyDualStep(double alpha) {
    rows.forEach([&](Rows&, int, Row& in) { in.z += alpha * in.dz; });
  }
  void prepare(double mu, double rho, bool primal) {
    rows.forEach([&](const Rows& g, int, Row& in) { form(g).prepare(in, mu, rho, primal); });
  }
  void initialize(double mu, double rho, double cap) {
    rows.forEach([&](const Rows& g, int, Row& in) { form(g).initialize(in, mu, rho, cap); });
  }
  void afterAccept(double mu) {
    rows.forEach([&](const Rows& g, int, Row& in) { form(g).afterAccept(in, mu); });
  }
  Complementarity complementarity(double mu, double rho) const {
    Complementarity out;
    rows.forEach(
        [&](const Rows& g, int, const Row& in) { form(g).addComplementarity(in, mu, rho, &out); });
    return out;
  }
  double largestMultiplier(double alpha) const {
    double largest = 0.0;
    rows.forEach([&](const Rows&, int, const Row& in) {
      largest = std::max(largest, in.z + alpha * in.dz);
    });
    return largest;
  }
  /// min c over the rows at their values (+∞ without rows).
  double smallestValue() const {
    double smallest = std::numeric_limits<double>::infinity();
    rows.forEach([&](const Rows&, int, const Row& in) { smallest = std::min(smallest, in.c); });
    return smallest;
  }
  double maxViolation() const { return std::max(0.0, -smallestValue()); }
  double maxSlackResidual() const {
    double worst = 0.0;
    rows.forEach(
        [&](const Rows&, int, const Row& in) { worst = std::max(worst, std::abs(in.c - in.s)); });
    return worst;
  }

  /// The Newton system at np's iterate: the cost's stencils with the torque rows, then one pass
  /// per other quantity, into `sink` (null: the rows' gradients only, rows not prepared), the
  /// right-hand side `rhs` and `gradient` (AssemblyChoices::row_gradients). `poll(k)` at each
  /// stencil and instance (it may throw). Returns the cost.
  template <typename Scalar, typename Poll>
  double assemble(KktSink<Scalar, TimeStep>* sink, const TimeStep& step, double mu, double rho,
                  const AssemblyChoices& choices, Eigen::VectorXd* rhs, Eigen::VectorXd* gradient,
                  const Poll& poll) {
    const double cost = assembleTorques(sink, step, mu, rho, choices, rhs, gradient, poll);
    for (const bool moving_pass : {false, true}) {
      for (const std::vector<int>& block : rows.blocks) {
        const bool moves = rows.groups[block.front()].quantity->dependsOnTimeStep();
        if (choices.fixed_quantities_first ? moves == moving_pass : !moving_pass)
          assembleQuantity(sink, step, block, mu, rho, choices, rhs, gradient, poll);
      }
    }
    return cost;
  }

 private:
  using Local = Eigen::Matrix<double, kEntries, 1>;
  using Block = Eigen::Matrix<double, kEntries, kEntries>;

  /// The cost's stencils (residual ρ = √w τ, weighted by cost_weight) with the torque rows: the
  /// Lagrangian's block ∂²(wᵀρ) + Gᵀ W G (G = ∂ρ/∂x), W = cost_weight·I − Σ z c''/w (the rows'
  /// isotropic curvature) + Σ ω a aᵀ (a = ∂c/∂ρ), folded as the choices say. The weights callback
  /// forms the rows' values, so the stencil's second-order weights carry −Σ z c'(τ)/√w with z as
  /// prepared there or not yet.
  template <typename Scalar, typename Poll>
  double assembleTorques(KktSink<Scalar, TimeStep>* sink, const TimeStep& step, double mu,
                         double rho, const AssemblyChoices& choices, Eigen::VectorXd* rhs,
                         Eigen::VectorXd* gradient, const Poll& poll) {
    double weight = choices.cost_weight;  // less Σ z c''/w of the rows prepared at their value
    const auto cost = [&](int, const Vector3& residual) {
      weight = choices.cost_weight;
      return Vector3(choices.cost_weight * residual);
    };
    const auto row = [&](const Rows& g, Row& in, double root) {
      if (!choices.prepare_at_value) return;
      form(g).prepare(in, mu, rho, choices.primal);
      weight -= in.z * g.constraint->curvature() / (root * root);
    };
    const auto visit = [&](const typename TimeStep::Stencil& st, double root) {
      poll(st.k);
      const Eigen::Matrix<double, 3, kEntries> G = step.jacobian(st);
      Matrix3 W = weight * Matrix3::Identity();
      const Local grad_f = choices.cost_weight * G.transpose() * st.tau;
      Local local_rhs = -grad_f, local_gradient = grad_f;
      const auto fold = [&](const Rows& g, Row& in, const Vector3& a) {
        if (!sink) return;
        if (!choices.prepare_at_value) {
          form(g).prepare(in, mu, rho, choices.primal);
          W.diagonal().array() -= in.z * g.constraint->curvature() / (root * root);
        }
        const RowTerms terms = form(g).terms(in, mu);
        const int axis = g.constraint->axis();
        if (choices.sum_in_double) {
          W.noalias() += terms.weight * a * a.transpose();
        } else if (axis >= 0) {  // a box side: affine in one axis (the slack forms' ω = 1/D)
          W(axis, axis) += a(axis) * a(axis) / in.D;
        } else {
          sink->addRankOne(st.k - 1, 3, in.g, terms.weight);
        }
        addRowGradient(choices, terms, in, &local_rhs, &local_gradient);
      };
      rows.chainTorques(st, root, G, fold);
      if (sink && choices.sum_in_double) {
        Block H = step.second(st);
        H.noalias() += (G.transpose() * W).lazyProduct(G);
        sink->addBlock(st.k - 1, 3, H, &local_gradient);
      } else if (sink) {
        for (int a = 0; a < 3; ++a) sink->addRankOne(st.k - 1, 3, G.row(a).transpose(), W(a, a));
        sink->addBlock(st.k - 1, 3, step.second(st), &local_gradient);
      }
      addLocalVector<TimeStep>(np_, local_gradient, 1.0, st.k - 1, 3, gradient);
      addLocalVector<TimeStep>(np_, local_rhs, 1.0, st.k - 1, 3, rhs);
    };
    return rows.forEachTorqueStencil(np_, step, sink != nullptr, cost, row, visit);
  }

  /// The groups of one quantity (a rate, a cone, a wheel quantity) through the quantity's terms
  /// and the chain rule (StageTranscription), with each row's barrier term ω g gᵀ.
  template <typename Scalar, typename Poll>
  void assembleQuantity(KktSink<Scalar, TimeStep>* sink, const TimeStep& step,
                        const std::vector<int>& block, double mu, double rho,
                        const AssemblyChoices& choices, Eigen::VectorXd* rhs,
                        Eigen::VectorXd* gradient, const Poll& poll) {
    const StageSupport support = rows.groups[block.front()].support;
    const auto prepare = [&](const Rows& g, Row& in) {
      if (sink) form(g).prepare(in, mu, rho, choices.primal);
    };
    const auto visit = [&](const typename TimeStep::Terms& t, Block* H) {
      if (!sink) return;
      const int node = t.k + support.node_offset;
      Local local_rhs = Local::Zero(), local_gradient = Local::Zero();
      if (!choices.sum_in_double) sink->addBlock(node, support.width, *H);
      for (const int i : block) {
        Row& in = rows.groups[i].instance(t.k);
        const RowTerms terms = form(rows.groups[i]).terms(in, mu);
        if (choices.sum_in_double) {
          addOuterProduct(H, terms.weight, in.g, 3 * support.width);
        } else {
          sink->addRankOne(node, support.width, in.g, terms.weight);
        }
        addRowGradient(choices, terms, in, &local_rhs, &local_gradient);
      }
      if (choices.sum_in_double) sink->addBlock(node, support.width, *H, &local_gradient);
      if (!choices.row_gradients) return;
      addLocalVector<TimeStep>(np_, local_rhs, 1.0, node, support.width, rhs);
      addLocalVector<TimeStep>(np_, local_gradient, 1.0, node, support.width, gradient);
    };
    rows.forEachQuantityInstance(np_, step, block, sink != nullptr, poll, prepare, visit);
  }
  static void addRowGradient(const AssemblyChoices& choices, const RowTerms& terms, const Row& in,
                             Local* rhs, Local* gradient) {
    if (!choices.row_gradients) return;
    *rhs += terms.rhs * in.g;
    *gradient -= in.z * in.g;
  }
  /// H += ω g gᵀ on the entries g can reach: its first m (the instance's nodes) and η.
  static void addOuterProduct(Block* H, double w, const Local& g, int m) {
    H->topLeftCorner(m, m).noalias() += (w * g.head(m)) * g.head(m).transpose();
    if constexpr (kEntries == 10) {
      H->block(0, 9, m, 1) += (w * g.head(m)) * g(9);
      H->block(9, 0, 1, m) += ((w * g(9)) * g.head(m)).transpose();
      (*H)(9, 9) += (w * g(9)) * g(9);
    }
  }

 public:
  StageTranscription<TimeStep> rows;

 private:
  const ReducedProblem& np_;
  FormOf form_;
};

}  // namespace attitude_planner
