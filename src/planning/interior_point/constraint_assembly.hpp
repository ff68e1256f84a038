// What both interior points share about their rows: the row set each holds (ConstraintRowSet),
// where a local block lands among the unknowns (localSlots, addBandBlock, addNodeVector,
// addNodeDot), and the chain rule of the rows on one stage quantity, written once for both
// assemblers (constrained_system.cpp at a fixed h, free_time_solver.cpp with h free): the
// constraints on one quantity object (a block of quantityBlocks, stage_constraints.hpp) are
// contracted together, c_i = c_i(q) and λ = −Σ z_i c_i'(q), so that the quantity forms λ·∇²q in
// its own pass (StageQuantityModel::forEachTerms / forEachTermsWithTimeStep); then, from the
// instance's terms, ∇c_i = ∇qᵀ c_i'(q) and the Lagrangian's curvature on the instance's entries
//     −Σ z_i ∇²c_i = λ·∇²q − Σ z_i c_i'' ∇qᵀ∇q        (c_i'' the constraint's isotropic curvature).
// What each assembler does with a row afterwards (its barrier form's g gᵀ weight, the band's
// precision, the border) stays its own. The torque constraints ride in the cost's stencil pass
// instead (formedByCostStencil): the same chain rule in the residual's space ρ = √w τ
// (contractTorqueRows, chainTorqueRows), their part of λ added to the cost's second-order weights;
// how each assembler folds their curvature and barrier terms stays its own.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "planning/interior_point/barrier_forms.hpp"
#include "planning/linalg/banded_matrix.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// Every row of one problem's stage constraints, as both interior points hold them (9 entries at
/// fixed h, 10 with η): one group per constraint on its quantity's support (with a free twist, the
/// support that reaches the nodes ψ moves: R_N, and R_{N−1} of paper and variational), the torque
/// groups (formed in the cost's stencil pass) and the other groups by quantity (one pass each).
template <int Entries>
struct ConstraintRowSet {
  using Rows = ConstraintRows<Entries>;
  ConstraintRowSet(const StageConstraints& constraints, const ReducedProblem& np) {
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
    visit(*this, f);
  }
  template <typename F>
  void forEach(F&& f) const {
    visit(*this, f);
  }
  /// f(group, k, row, c) with each row's value c at `at` (the row's c untouched).
  template <typename F>
  void forEachValue(const QuantityInputs& at, F&& f) {
    visit(*this, [&](Rows& g, int k, auto& row) { f(g, k, row, valueAt(g, at, k)); });
  }
  template <typename F>
  void forEachValue(const QuantityInputs& at, F&& f) const {
    visit(*this, [&](const Rows& g, int k, auto& row) { f(g, k, row, valueAt(g, at, k)); });
  }
  std::vector<Rows> groups;
  std::vector<int> stencil;              ///< the groups on the cost's stencil (the torques)
  std::vector<std::vector<int>> blocks;  ///< the other groups by quantity (indices into groups)
  int count = 0;                         ///< rows in all

 private:
  template <typename Self, typename F>
  static void visit(Self& self, F&& f) {
    for (auto& g : self.groups) {
      for (int k = g.support.first_k; k <= g.support.last_k; ++k) f(g, k, g.instance(k));
    }
  }
  static double valueAt(const Rows& g, const QuantityInputs& at, int k) {
    return g.constraint->value(g.quantity->value(at, k));
  }
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
/// (`root` = √w, w the cost's weight of τ_k): each row's value c(τ), then row(group, row) (the
/// assembler's: its barrier form's preparation, fixed h's c''); returns `weights` − Σ (z/√w) c'(τ),
/// the stencil's second-order weights (`weights` on entry the cost's own: ρ, or ε ρ).
template <int Entries, typename Row>
Vector3 contractTorqueRows(std::vector<ConstraintRows<Entries>>& groups,
                           const std::vector<int>& block, int k, const Vector3& residual,
                           double root, Vector3 weights, const Row& row) {
  const Vector3 tau = residual / root;
  for (const int i : block) {
    ConstraintRow<Entries>& in = groups[i].instance(k);
    in.c = groups[i].constraint->value(tau);
    row(groups[i], in);
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

}  // namespace attitude_planner
