// The stage rows of one transcription and their assembly over the grid: every instance of every
// stage constraint (stage_constraints.hpp) as a row c ≥ 0 of an interior point's barrier problem,
// one object (StageTranscription) for the interior point at a fixed h and the free-time solver,
// which differ in their time step only (FixedTimeStep: an instance's 9 entries are its local
// nodes'; FreeTimeStep: η = h/h₀ a 10th). It owns the rows, the passes over the grid that form
// them (the cost's stencils with the torque rows, one pass per other quantity object) and the
// chain rule from a quantity to its rows: the constraints on one quantity object (a block of
// quantityBlocks) are contracted together, c_i = c_i(q) and λ = −Σ z_i c_i'(q), so that the
// quantity forms λ·∇²q in its own pass (StageQuantityModel::forEachTerms /
// forEachTermsWithTimeStep); then, from the instance's terms, ∇c_i = ∇qᵀ c_i'(q) and the
// Lagrangian's curvature on the instance's entries
//     −Σ z_i ∇²c_i = λ·∇²q − Σ z_i c_i'' ∇qᵀ∇q        (c_i'' the constraint's isotropic curvature).
// The torque rows ride in the cost's stencil pass (formedByCostStencil): the same chain rule in
// the residual's space ρ = √w τ, their part of λ added to the cost's second-order weights. What an
// interior point does with a row (its barrier form's multiplier and g gᵀ weight, the band's
// precision, the border) stays its own: the passes call it back. Also here: where a local block
// lands among the unknowns (localSlots, addBandBlock, addNodeVector, addNodeDot).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "planning/linalg/banded_matrix.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "planning/transcription/stage_quantities.hpp"

namespace attitude_planner {

/// One row c ≥ 0 (one instance of a stage constraint): value c, gradient g over its local nodes
/// (at most three: 9 entries) and, with h free, η (Entries = 10, entry 9), and the interior
/// point's state of the row: its multiplier z and what its barrier form keeps.
template <int Entries>
struct ConstraintRow {
  double c = 0.0;  ///< value (dimensionless)
  Eigen::Matrix<double, Entries, 1> g = Eigen::Matrix<double, Entries, 1>::Zero();  ///< ∂c/∂x
  double z = 0.0;                                                                   ///< multiplier
  // FreeSlacks, L1Elastic:
  double s = 0.0, v = 0.0;  ///< slacks (L1Elastic: elasticSlacks of c; FreeSlacks: s free)
  double D = 1.0, q = 0.0;  ///< condensation terms
  double ds = 0.0;          ///< FreeSlacks: the slack's Newton step
  // Feasible:
  double dz = 0.0;  ///< the multiplier's step
  /// The second-order correction's curvature term c(x + d) − c − gᵀd at the rejected full step
  /// (0 when the step taken is not a corrected one).
  double r = 0.0;
};

/// The rows of one stage constraint on its quantity's support (stage_quantities.hpp).
template <int Entries>
struct ConstraintRows {
  ConstraintRows(const StageConstraint& c, int first_free_node, int last_free_node)
      : constraint(&c),
        quantity(&c.quantityModel()),
        support(quantity->support(first_free_node, last_free_node)),
        at(support.last_k - support.first_k + 1) {}
  ConstraintRow<Entries>& instance(int k) { return at[k - support.first_k]; }
  const ConstraintRow<Entries>& instance(int k) const { return at[k - support.first_k]; }

  const StageConstraint* constraint;
  const StageQuantityModel* quantity;  ///< &constraint->quantityModel()
  StageSupport support;
  std::vector<ConstraintRow<Entries>> at;  ///< at[k − support.first_k]
};

/// Where a local 9-vector over nodes first_node..first_node+width−1 sits among the node unknowns:
/// its offset and its free entries first..last−1 (fixed nodes skipped).
struct LocalSlots {
  int offset = 0, first = 0, last = 0;
  bool empty() const { return first >= last; }
};
inline LocalSlots localSlots(const ReducedProblem& np, int first_node, int width) {
  const int first_free = std::max(0, np.firstFreeNode() - first_node);
  const int last_free = std::min(width - 1, np.lastFreeNode() - first_node);
  return {3 * (first_node - np.firstFreeNode()), 3 * first_free, 3 * (last_free + 1)};
}
/// Adds a local 9×9 block (lower triangle used) to the band, fixed nodes skipped.
template <typename Scalar>
void addBandBlock(const ReducedProblem& np, BandedSymmetric<Scalar>* H, int first_node, int width,
                  const Eigen::Matrix<double, 9, 9>& M) {
  const LocalSlots l = localSlots(np, first_node, width);
  if (!l.empty()) H->template addSymmetricBlock<9>(l.offset, M, l.first, l.last);
}
/// Adds weight·g over the local nodes' free entries to `out` (node unknowns first).
inline void addNodeVector(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g,
                          double weight, int first_node, int width,
                          Eigen::Ref<Eigen::VectorXd> out) {
  for (int n = 0; n < width; ++n) {
    const int v = np.variableIndex(first_node + n);
    if (v >= 0) out.segment<3>(v) += weight * g.segment<3>(3 * n);
  }
}
/// `sum` plus gᵀd over the local nodes' free entries, node by node.
inline double addNodeDot(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g,
                         int first_node, int width, const Eigen::VectorXd& d, double sum) {
  for (int n = 0; n < width; ++n) {
    const int v = np.variableIndex(first_node + n);
    if (v >= 0) sum += g.segment<3>(3 * n).dot(d.segment<3>(v));
  }
  return sum;
}

/// A pointing end's twist ψ moves R_N by exp(Δψ b^) and, for paper and variational, R_{N−1} by
/// exp(Δψ e^) (ReducedProblem::twistMotion): e over the local nodes first_node .. first_node +
/// width − 1, the ψ-column of a local block (zero past width and where the twist moves nothing).
inline Eigen::Matrix<double, 9, 1> localTwistMotion(const ReducedProblem& np, int first_node,
                                                    int width) {
  Eigen::Matrix<double, 9, 1> e = Eigen::Matrix<double, 9, 1>::Zero();
  if (!np.hasTwist()) return e;
  for (int n = 0; n < width; ++n) e.segment<3>(3 * n) = np.twistMotion(first_node + n);
  return e;
}

/// The time step of a transcription at a fixed h: an instance's entries are its local nodes'.
struct FixedTimeStep {
  static constexpr int kEntries = 9;
  using Stencil = ReducedProblem::Stencil;
  using Terms = QuantityTerms;
  double forEachStencil(const ReducedProblem& np, bool second_order,
                        const std::function<void(const Stencil&)>& visit,
                        const ReducedProblem::SecondOrderWeights& weights) const {
    return np.forEachStencil(second_order, visit, weights);
  }
  void forEachTerms(const StageQuantityModel& q, const ReducedProblem& np,
                    const StageSupport& support, const QuantityContraction& contract,
                    const std::function<void(const Terms&)>& visit) const {
    q.forEachTerms(np, support, contract, visit);
  }
  /// ∂ρ/∂x over the stencil's entries (ρ = √w τ_k the stencil's residual).
  const Eigen::Matrix<double, 3, 9>& jacobian(const Stencil& st) const { return st.jacobian; }
  /// ∂²(wᵀρ) over the same entries (w the stencil's second-order weights).
  const Eigen::Matrix<double, 9, 9>& second(const Stencil& st) const { return st.second; }
  /// The global unknowns after the node unknowns: a pointing end's ψ (index np.unknowns()).
  static int globals(const ReducedProblem& np) { return np.hasTwist() ? 1 : 0; }
  static int twistIndex(const ReducedProblem& np) { return np.unknowns(); }
  /// gᵀd over a local gradient's unknowns: its nodes', then ψ's (this order: bit for bit).
  static double dot(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g, int first_node,
                    int width, const Eigen::VectorXd& d) {
    double sum = addNodeDot(np, g, first_node, width, d, 0.0);
    if (np.hasTwist()) sum += g.dot(localTwistMotion(np, first_node, width)) * d(np.unknowns());
    return sum;
  }
  /// out(ψ) += weight·gᵀe (the globals' part of weight·g; the nodes' is addNodeVector's).
  static void addGlobals(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g,
                         double weight, int first_node, int width, Eigen::VectorXd* out) {
    if (np.hasTwist()) {
      (*out)(np.unknowns()) += weight * g.dot(localTwistMotion(np, first_node, width));
    }
  }
};

/// The fixed-h interior point's rows (the node unknowns only).
using FixedStepRow = ConstraintRow<FixedTimeStep::kEntries>;
using FixedStepRows = ConstraintRows<FixedTimeStep::kEntries>;

/// The time step of a transcription with h free: entry 9 is η = h/scale (the free-time solver's
/// scale is h₀, the start's h), the boundary data held at every h (ReducedProblem::setTimeStep).
struct FreeTimeStep {
  static constexpr int kEntries = 10;
  using Stencil = ReducedProblem::TimeStepStencil;
  using Terms = QuantityTermsWithTimeStep;
  double scale = 1.0;
  double forEachStencil(const ReducedProblem& np, bool,
                        const std::function<void(const Stencil&)>& visit,
                        const ReducedProblem::SecondOrderWeights& weights) const {
    return np.forEachStencilWithTimeStep(visit, weights);
  }
  void forEachTerms(const StageQuantityModel& q, const ReducedProblem& np,
                    const StageSupport& support, const QuantityContraction& contract,
                    const std::function<void(const Terms&)>& visit) const {
    q.forEachTermsWithTimeStep(np, support, scale, contract, visit);
  }
  /// ∂ρ/∂(δ_{k−1}, δ_k, δ_{k+1}, η).
  Eigen::Matrix<double, 3, 10> jacobian(const Stencil& st) const {
    Eigen::Matrix<double, 3, 10> G;
    G.leftCols<9>() = st.jacobian;
    G.col(9) = st.tau_h * scale;
    return G;
  }
  /// ∂²(wᵀρ) over the same entries (w the stencil's second-order weights).
  Eigen::Matrix<double, 10, 10> second(const Stencil& st) const {
    Eigen::Matrix<double, 10, 10> H = Eigen::Matrix<double, 10, 10>::Zero();
    H.topLeftCorner<9, 9>() = st.second;
    H.block<9, 1>(0, 9) = st.second_h * scale;
    H.block<1, 9>(9, 0) = (st.second_h * scale).transpose();
    H(9, 9) = st.second_hh * scale * scale;
    return H;
  }
  /// The global unknowns after the node unknowns: η (index np.unknowns()), then a pointing end's
  /// ψ.
  static int globals(const ReducedProblem& np) { return np.hasTwist() ? 2 : 1; }
  static int twistIndex(const ReducedProblem& np) { return np.unknowns() + 1; }
  /// gᵀd over a local gradient's unknowns: η's, ψ's, then its nodes' (this order: bit for bit).
  static double dot(const ReducedProblem& np, const Eigen::Matrix<double, 10, 1>& g, int first_node,
                    int width, const Eigen::VectorXd& d) {
    double sum = g(9) * d(np.unknowns());
    if (np.hasTwist()) {
      sum += g.head<9>().dot(localTwistMotion(np, first_node, width)) * d(twistIndex(np));
    }
    return addNodeDot(np, g.head<9>(), first_node, width, d, sum);
  }
  /// out(η) += weight·g(9), out(ψ) += weight·gᵀe (the nodes' part is addNodeVector's).
  static void addGlobals(const ReducedProblem& np, const Eigen::Matrix<double, 10, 1>& g,
                         double weight, int first_node, int width, Eigen::VectorXd* out) {
    (*out)(np.unknowns()) += weight * g(9);
    if (np.hasTwist()) {
      (*out)(twistIndex(np)) += weight * g.head<9>().dot(localTwistMotion(np, first_node, width));
    }
  }
};

/// The free-time interior point's rows (the node unknowns and η).
using FreeTimeRow = ConstraintRow<FreeTimeStep::kEntries>;
using FreeTimeRows = ConstraintRows<FreeTimeStep::kEntries>;

/// out += weight·g over a local gradient's unknowns (its free nodes', then the time step's
/// globals): TimeStep::dot's adjoint.
template <typename TimeStep>
void addLocalVector(const ReducedProblem& np, const Eigen::Matrix<double, TimeStep::kEntries, 1>& g,
                    double weight, int first_node, int width, Eigen::VectorXd* out) {
  addNodeVector(np, g.template head<9>(), weight, first_node, width, *out);
  TimeStep::addGlobals(np, g, weight, first_node, width, out);
}

/// The rows of `block` at instance k with quantity value q: each row's value c(q), then
/// prepare(rows, row) (its barrier form's multiplier and condensation terms at that value);
/// returns λ = −Σ z c'(q), what the quantity contracts its curvature with.
template <int Entries, typename Prepare>
Vector3 contractQuantityRows(std::vector<ConstraintRows<Entries>>& groups,
                             const std::vector<int>& block, int k, const Vector3& q,
                             const Prepare& prepare) {
  Vector3 lambda = Vector3::Zero();
  for (const int i : block) {
    ConstraintRow<Entries>& in = groups[i].instance(k);
    in.c = groups[i].constraint->value(q);
    prepare(groups[i], in);
    lambda -= in.z * groups[i].constraint->gradient(q);
  }
  return lambda;
}

/// From one instance's terms (QuantityTerms, or QuantityTermsWithTimeStep with Entries = 10):
/// each row's gradient g = ∇qᵀ c'(q) and, with `curvature`, the Lagrangian's curvature on the
/// instance's entries, λ·∇²q − Σ z c'' ∇qᵀ∇q (the terms' curvature was contracted with
/// contractQuantityRows' λ).
template <int Entries, typename Terms>
void chainQuantityRows(std::vector<ConstraintRows<Entries>>& groups, const std::vector<int>& block,
                       const Terms& t, Eigen::Matrix<double, Entries, Entries>* curvature) {
  if (curvature) *curvature = t.curvature;
  for (const int i : block) {
    const StageConstraint& c = *groups[i].constraint;
    ConstraintRow<Entries>& in = groups[i].instance(t.k);
    in.g = t.jacobian.transpose() * c.gradient(t.value);
    if (curvature && c.curvature() != 0.0) {
      *curvature -= (in.z * c.curvature()) * t.jacobian.transpose() * t.jacobian;
    }
  }
}

/// The torque rows of `block` (indices into groups) at stencil k, whose residual is ρ = √w τ
/// (`root` = √w, w the cost's weight of τ_k): each row's value c(τ), then row(group, row, root)
/// (the assembler's: its barrier form's preparation, fixed h's c''); returns `weights` − Σ (z/√w)
/// c'(τ), the stencil's second-order weights (`weights` on entry the cost's own: ρ, or ε ρ).
template <int Entries, typename Row>
Vector3 contractTorqueRows(std::vector<ConstraintRows<Entries>>& groups,
                           const std::vector<int>& block, int k, const Vector3& residual,
                           double root, Vector3 weights, const Row& row) {
  const Vector3 tau = residual / root;
  for (const int i : block) {
    ConstraintRow<Entries>& in = groups[i].instance(k);
    in.c = groups[i].constraint->value(tau);
    row(groups[i], in, root);
    weights -= (in.z / root) * groups[i].constraint->gradient(tau);
  }
  return weights;
}

/// The torque rows' gradients at stencil k: with a = c'(τ)/√w = ∂c/∂ρ, g = Gᵀa (G = ∂ρ/∂x over
/// the stencil's entries: 9, or 10 with η), then fold(group, row, a): how the assembler adds the
/// row's curvature and barrier term (fixed h folds a box side's into its axis's Gauss–Newton
/// weight, free time every row's into one 3×3 weight of Gᵀ W G).
template <int Entries, typename Fold>
void chainTorqueRows(std::vector<ConstraintRows<Entries>>& groups, const std::vector<int>& block,
                     int k, const Vector3& residual, double root,
                     const Eigen::Matrix<double, 3, Entries>& G, const Fold& fold) {
  const Vector3 tau = residual / root;
  for (const int i : block) {
    ConstraintRow<Entries>& in = groups[i].instance(k);
    const Vector3 a = groups[i].constraint->gradient(tau) / root;
    in.g = G.transpose() * a;
    fold(groups[i], in, a);
  }
}

/// The stage rows of one problem, as both interior points hold them, and their passes over the
/// grid: one group per constraint on its quantity's support (with a free twist, the support that
/// reaches the nodes ψ moves: R_N, and R_{N−1} of paper and variational), the torque groups
/// (formed in the cost's stencil pass) and the other groups by quantity (one pass each).
template <typename TimeStep>
struct StageTranscription {
  static constexpr int kEntries = TimeStep::kEntries;
  using Rows = ConstraintRows<kEntries>;
  using Row = ConstraintRow<kEntries>;
  StageTranscription(const StageConstraints& constraints, const ReducedProblem& np) {
    groups.reserve(constraints.size());
    for (const auto& c : constraints) {
      Rows& g = groups.emplace_back(*c, np.firstFreeNode(), np.lastFreeNode());  // `at` in place
      if (np.hasTwist()) {
        g.support = g.quantity->supportWithTwist(np.firstFreeNode(), np.lastFreeNode(), np.steps());
        g.at.resize(g.support.last_k - g.support.first_k + 1);
      }
      count += static_cast<int>(g.at.size());
    }
    QuantityBlocks b = quantityBlocks(constraints);
    stencil = std::move(b.on_cost_stencil);
    blocks = std::move(b.blocks);
  }
  /// f(group, k, row) for every row: group by group, k rising (the order every sum is formed in).
  template <typename F>
  void forEach(F&& f) {
    visit(*this, 0, [&](Rows& g, int k, Row& row) {
      f(g, k, row);
      return true;
    });
  }
  template <typename F>
  void forEach(F&& f) const {
    visit(*this, 0, [&](const Rows& g, int k, const Row& row) {
      f(g, k, row);
      return true;
    });
  }
  /// f(group, k, row, c) with each row's value c at `at` (the row's c untouched).
  template <typename F>
  void forEachValue(const QuantityInputs& at, F&& f) {
    forEach([&](Rows& g, int k, Row& row) { f(g, k, row, valueAt(g, at, k)); });
  }
  template <typename F>
  void forEachValue(const QuantityInputs& at, F&& f) const {
    forEach([&](const Rows& g, int k, const Row& row) { f(g, k, row, valueAt(g, at, k)); });
  }
  /// f(group, k, row) for the rows from the one at `index` in forEach's order on, until f returns
  /// false: false then, else true.
  template <typename F>
  bool forEachFrom(int index, F&& f) const {
    return visit(*this, index, f);
  }
  /// Row k's value c of group g at `at`.
  static double valueAt(const Rows& g, const QuantityInputs& at, int k) {
    return g.constraint->value(g.quantity->value(at, k));
  }
  /// Each row's value c at `at`, into the row.
  void evaluate(const QuantityInputs& at) {
    forEachValue(at, [](Rows&, int, Row& in, double c) { in.c = c; });
  }
  /// The least value at `at` of the groups `which(group)` selects (+∞ without; rows untouched).
  template <typename Which>
  double smallestValue(const QuantityInputs& at, const Which& which) const {
    double smallest = std::numeric_limits<double>::infinity();
    forEachValue(at, [&](const Rows& g, int, const Row&, double c) {
      if (which(g)) smallest = std::min(smallest, c);
    });
    return smallest;
  }
  /// Σ z c at the rows' values: the duality gap.
  double dualityGap() const {
    double gap = 0.0;
    forEach([&](const Rows&, int, const Row& in) { gap += in.z * in.c; });
    return gap;
  }
  /// gᵀd for a gradient of row k of group g over the unknowns (δ, then the globals in force:
  /// η with h free, a pointing end's ψ), summed in the time step's order.
  double dot(const ReducedProblem& np, const Rows& g, int k,
             const Eigen::Matrix<double, kEntries, 1>& gradient, const Eigen::VectorXd& d) const {
    return TimeStep::dot(np, gradient, k + g.support.node_offset, g.support.width, d);
  }
  /// out += weight·gradient (row k of group g) over the unknowns: dot's adjoint.
  void addRow(const ReducedProblem& np, const Rows& g, int k,
              const Eigen::Matrix<double, kEntries, 1>& gradient, double weight,
              Eigen::VectorXd* out) const {
    addLocalVector<TimeStep>(np, gradient, weight, k + g.support.node_offset, g.support.width, out);
  }
  /// The iterate's steps moved by α d over the unknowns (a pointing end's ψ: R_N moves with it,
  /// and the steps next to it); np's iterate untouched.
  static ReducedProblem::StepVectors retract(const ReducedProblem& np, const Eigen::VectorXd& d,
                                             double alpha) {
    if (!np.hasTwist()) return np.retract(d, alpha);
    return np.retractWithTwist(d, d(TimeStep::twistIndex(np)), alpha);
  }
  /// Takes steps that retract(np, d, α) formed as the iterate (R_N moved by α dψ with a twist).
  static void accept(ReducedProblem& np, const ReducedProblem::StepVectors& steps,
                     const Eigen::VectorXd& d, double alpha) {
    if (np.hasTwist()) {
      np.setCurrentWithTwist(steps, alpha * d(TimeStep::twistIndex(np)));
    } else {
      np.setCurrent(steps);
    }
  }
  /// Whether a per-axis torque bound is among the rows (a box side: the one constraint affine in
  /// one torque axis).
  bool hasTorqueBox() const {
    return std::any_of(groups.begin(), groups.end(),
                       [](const Rows& g) { return g.constraint->axis() >= 0; });
  }
  /// The box sides' multipliers at the torques τ: σ_k(a) −= z ∂c/∂τ_a / w_k (±z/(a w_k), the
  /// multipliers' part of the switching function, PlanResult::switching_function) and, with
  /// `multipliers`, (z⁺ − z⁻)_k(a) −= sign(∂c/∂τ_a) z (the side is that sign: − upper, + lower).
  void addBoxMultipliers(const ReducedProblem& np, const std::vector<Vector3>& torque,
                         std::vector<Vector3>* sigma, std::vector<Vector3>* multipliers) const {
    forEach([&](const Rows& g, int k, const Row& in) {
      const int a = g.constraint->axis();
      if (a < 0) return;
      const double slope = g.constraint->gradient(torque[k])(a);  // ∂c/∂τ_a: ∓1/a
      if (multipliers) (*multipliers)[k](a) -= std::copysign(in.z, slope);
      (*sigma)[k](a) -= in.z * slope / np.scheme().torqueWeight(k, np.steps());
    });
  }
  /// The cost's stencils at the iterate of `np` with the torque rows: the stencil's second-order
  /// weights are cost(k, ρ) (the cost's own) with the rows contracted into them
  /// (contractTorqueRows, row(group, row, √w) after each value); then visit(stencil, √w), which
  /// forms the rows' gradients through chainTorques. Returns the cost.
  template <typename Cost, typename RowFn, typename Visit>
  double forEachTorqueStencil(const ReducedProblem& np, const TimeStep& step, bool second_order,
                              const Cost& cost, const RowFn& row, const Visit& visit) {
    const auto root = [&](int k) { return std::sqrt(np.scheme().torqueWeight(k, np.steps())); };
    const auto weights = [&](int k, const Vector3& residual) {
      const double r = root(k);
      return contractTorqueRows(groups, stencil, k, residual, r, cost(k, residual), row);
    };
    return step.forEachStencil(
        np, second_order, [&](const typename TimeStep::Stencil& st) { visit(st, root(st.k)); },
        weights);
  }
  /// The torque rows' gradients at stencil `st` (chainTorqueRows; G = TimeStep::jacobian), each
  /// row then fold(group, row, ∂c/∂ρ).
  template <typename Fold>
  void chainTorques(const typename TimeStep::Stencil& st, double root,
                    const Eigen::Matrix<double, 3, kEntries>& G, const Fold& fold) {
    chainTorqueRows(groups, stencil, st.k, st.tau, root, G, fold);
  }
  /// The instances of one quantity block through the chain rule: before(k), the rows contracted
  /// (contractQuantityRows with prepare(group, row)), then visit(terms, curvature) with each row's
  /// gradient formed and, with `curvature`, the Lagrangian's curvature on the instance's entries
  /// (else null).
  template <typename Before, typename Prepare, typename Visit>
  void forEachQuantityInstance(const ReducedProblem& np, const TimeStep& step,
                               const std::vector<int>& block, bool curvature, const Before& before,
                               const Prepare& prepare, const Visit& visit) {
    const Rows& first = groups[block.front()];
    const auto contract = [&](int k, const Vector3& q) {
      before(k);
      return contractQuantityRows(groups, block, k, q, prepare);
    };
    step.forEachTerms(*first.quantity, np, first.support, contract,
                      [&](const typename TimeStep::Terms& t) {
                        Eigen::Matrix<double, kEntries, kEntries> H;
                        chainQuantityRows(groups, block, t, curvature ? &H : nullptr);
                        visit(t, curvature ? &H : nullptr);
                      });
  }

  std::vector<Rows> groups;
  std::vector<int> stencil;              ///< the groups on the cost's stencil (the torques)
  std::vector<std::vector<int>> blocks;  ///< the other groups by quantity (indices into groups)
  int count = 0;                         ///< rows in all

 private:
  /// The one traversal: from the row at `index` in forEach's order, until f returns false.
  template <typename Self, typename F>
  static bool visit(Self& self, int index, F&& f) {
    for (auto& g : self.groups) {
      const int rows_in_group = g.support.last_k - g.support.first_k + 1;
      if (index >= rows_in_group) {
        index -= rows_in_group;
        continue;
      }
      for (int k = g.support.first_k + index; k <= g.support.last_k; ++k) {
        if (!f(g, k, g.instance(k))) return false;
      }
      index = 0;
    }
    return true;
  }
};

/// The stage transcription at a fixed h (the interior point's) and with h free (free time's).
using FixedStepTranscription = StageTranscription<FixedTimeStep>;
using FreeTimeTranscription = StageTranscription<FreeTimeStep>;

}  // namespace attitude_planner
