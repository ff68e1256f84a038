// Least-squares multipliers of the near-active node constraints at a plan
// (multiplier_estimate.hpp).
#include "planning/interior_point/multiplier_estimate.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <limits>

namespace attitude_planner {

namespace {

/// Ridge of the normal equations relative to their largest diagonal entry: far below any
/// multiplier that matters, enough to determine a column that duplicates another (both bounds of
/// one component never bind together, but a torque bound and a torque-norm bound can).
constexpr double kRelativeRidge = 1e-10;
/// Active-set passes: each drops the columns whose least-squares multiplier came out negative
/// (a bound touched but not pushed against); one or two suffice on the scenes.
constexpr int kMaxActiveSetPasses = 5;
/// Refinement steps of the normal equations' solution (see leastSquares).
constexpr int kRefinementSteps = 2;

/// Least squares of ∇f = Σ_{i∈set} z_i ∇c_i through the normal equations (banded: a column
/// touches three consecutive nodes), ridge-regularized.
Eigen::VectorXd leastSquares(const Eigen::VectorXd& cost_gradient,
                             const std::vector<StationarityColumn>& columns,
                             const std::vector<int>& set) {
  const int m = static_cast<int>(set.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(9 * m);
  for (int j = 0; j < m; ++j) {
    const StationarityColumn& c = columns[set[j]];
    for (int n = 0; n < 3; ++n) {
      if (c.index[n] < 0) continue;
      for (int r = 0; r < 3; ++r) entries.emplace_back(c.index[n] + r, j, c.gradient(3 * n + r));
    }
  }
  Eigen::SparseMatrix<double> G(cost_gradient.size(), m);
  G.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> normal = G.transpose() * G;
  double largest = 0.0;
  for (int j = 0; j < m; ++j) largest = std::max(largest, normal.coeff(j, j));
  const double ridge = kRelativeRidge * (largest > 0.0 ? largest : 1.0);
  for (int j = 0; j < m; ++j) normal.coeffRef(j, j) += ridge;
  // The set is in node order, so the normal matrix is banded (a column overlaps those within
  // two nodes): factored in that order it does not fill beyond the band (O(m)); AMD fills it.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>>
      solver(normal);
  const Eigen::VectorXd rhs = G.transpose() * cost_gradient;
  if (solver.info() != Eigen::Success) return Eigen::VectorXd::Zero(m);
  Eigen::VectorXd z = solver.solve(rhs);
  // The normal equations square the condition of G (consecutive torque columns are second
  // differences: a long arc's smooth multiplier profile is poorly determined by them alone);
  // refinement on the residual of the least-squares problem itself recovers it (corrected
  // semi-normal equations: as accurate as a dense QR).
  for (int step = 0; step < kRefinementSteps; ++step) {
    const Eigen::VectorXd residual = cost_gradient - G * z;
    z += solver.solve(G.transpose() * residual);
  }
  return z.allFinite() ? z : Eigen::VectorXd::Zero(m);
}

/// One column's slack and multiplier on the central path s z = μ. The slack is the column's value
/// (c − s = 0 holds at the start: a slack above the value would make the first Newton step move
/// the plan off the bound it rides, and the next ones back) unless the value is below the central
/// slack of a typical multiplier, s = μ/z̄ = kEstimateComplementarity (z̄ the mean active one):
/// then an active column keeps its multiplier where it is at least z̄ (slack μ/z), else takes z̄
/// (the central slack: no binding column is pushed further off its bound, as the finer grid
/// levels push one by InteriorPointParameters::warm_slack_push; a weakly active one, z ≈ 0, starts
/// off the degenerate corner s = z = 0, from which Newton's steps on s z = μ only halve the gap),
/// and an inactive one takes the central slack.
void centerPair(double value, bool active, double mu, double* s, double* z) {
  constexpr double kCentralSlack = kEstimateComplementarity;
  *s = active ? std::min(mu / std::max(*z, mu / kCentralSlack), kCentralSlack) : kCentralSlack;
  *s = std::max(*s, value);
  *z = mu / *s;
}

}  // namespace

MultiplierEstimate estimateMultipliers(const Eigen::VectorXd& cost_gradient,
                                       const std::vector<StationarityColumn>& columns,
                                       double fallback_scale) {
  const int count = static_cast<int>(columns.size());
  MultiplierEstimate out;
  out.z.assign(count, 0.0);
  out.s.assign(count, 0.0);
  std::vector<int> set;
  for (int i = 0; i < count; ++i) {
    const StationarityColumn& c = columns[i];
    const bool touches_unknowns = *std::max_element(c.index.begin(), c.index.end()) >= 0;
    if (c.value <= kNearActiveValue && touches_unknowns) set.push_back(i);
  }
  // Node order (the first unknown a column touches), for the band of the normal equations.
  const auto first_unknown = [&](int i) {
    int first = std::numeric_limits<int>::max();
    for (int v : columns[i].index)
      if (v >= 0) first = std::min(first, v);
    return first;
  };
  std::stable_sort(set.begin(), set.end(),
                   [&](int a, int b) { return first_unknown(a) < first_unknown(b); });
  std::vector<bool> active(count, false);
  for (int pass = 0; pass < kMaxActiveSetPasses && !set.empty(); ++pass) {
    const Eigen::VectorXd z = leastSquares(cost_gradient, columns, set);
    std::vector<int> kept;
    for (int j = 0; j < static_cast<int>(set.size()); ++j) {
      if (z(j) > 0.0) kept.push_back(set[j]);
      out.z[set[j]] = std::max(z(j), 0.0);
    }
    if (kept.size() == set.size()) break;
    for (int i : set) out.z[i] = 0.0;
    set = kept;
  }
  double sum = 0.0;
  for (int i : set) {
    active[i] = true;
    sum += out.z[i];
  }
  out.active = static_cast<int>(set.size());
  out.complementarity = kEstimateComplementarity *
                        (set.empty() ? fallback_scale : sum / static_cast<double>(set.size()));
  for (int i = 0; i < count; ++i)
    centerPair(columns[i].value, active[i], out.complementarity, &out.s[i], &out.z[i]);
  return out;
}

}  // namespace attitude_planner
