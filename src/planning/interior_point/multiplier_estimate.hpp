// Multipliers for a constrained solve started from a plan that carries none (a warm start from a
// CSV or a message): re-derived from the first-order condition at the plan itself
// (multiplier_estimate.cpp; used by the interior point, drivers/constrained_recipe.cpp).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

namespace attitude_planner {

/// One node constraint c_i(δ) ≥ 0 (dimensionless, constrained_system.hpp) at the plan: its
/// value and its gradient over up to three consecutive nodes.
struct StationarityColumn {
  double value = 0.0;                    ///< c_i
  Eigen::Matrix<double, 9, 1> gradient;  ///< ∂c_i/∂δ over its local nodes (3 entries each)
  /// First unknown of local node n (ReducedProblem::variableIndex), −1 where the node is fixed
  /// or absent.
  std::array<int, 3> index{-1, -1, -1};
};

/// A constraint whose value is at most this (relative to its limit; cosine units for cones) is
/// taken as active at the plan: the resampled plan of another N is within ~h² of the bounds it
/// rode on, a converged plan of this N within its final barrier.
constexpr double kNearActiveValue = 1e-3;

/// Complementarity s_i z_i of the estimate, relative to the mean active multiplier: the finer
/// levels of the grid continuation start a binding slack at 1e-6 (kWarmSlackPush), and so does
/// this start.
constexpr double kEstimateComplementarity = 1e-6;

/// The multipliers z ≥ 0 (one per column) and slacks of a start, centered on one
/// complementarity s_i z_i = μ: the near-active columns (value ≤ kNearActiveValue) take the
/// nonnegative least-squares solution of the stationarity condition ∇f = Σ z_i ∇c_i (active-set
/// passes dropping negative ones; a 1e-10 relative ridge keeps dependent columns determined);
/// every column's slack is its value where that is at least kEstimateComplementarity (the central
/// slack of the mean active multiplier), else an active column's μ/z_i capped at that, an
/// inactive one's that; z = μ/s; μ = kEstimateComplementarity × the mean active multiplier
/// (× `fallback_scale` when none is active). O(columns).
struct MultiplierEstimate {
  std::vector<double> z, s;
  int active = 0;                ///< columns taken as active
  double complementarity = 0.0;  ///< μ = s_i z_i of every column
};
MultiplierEstimate estimateMultipliers(const Eigen::VectorXd& cost_gradient,
                                       const std::vector<StationarityColumn>& columns,
                                       double fallback_scale);

}  // namespace attitude_planner
