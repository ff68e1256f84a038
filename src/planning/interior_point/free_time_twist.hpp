// The twist ψ of a pointing end condition as a global unknown of the free-time interior point
// (free_time_solver.cpp), beside η = h/h₀: its entries of one local block of the Newton system.
//
// ψ moves R_N by exp(Δψ b^) and, for paper and variational, R_{N−1} = R_N F_{N−1}ᵀ by
// exp(Δψ e^), e = F_{N−1} b (ReducedProblem::twistMotion): at fixed h a straight line in the
// right-perturbation coordinates x of those nodes, so a local gradient g (fixed nodes' columns
// included, as the stencils carry them) has ψ-component gᵀe and a local Hessian H has ψ-column
// H e and corner eᵀHe. With h free the motions compose: h moves R_{N−1} along its boundary path
// d(h) (ReducedProblem::nodePath), and
//     R_N exp(Δψ b^) F(h)ᵀ = R_{N−1} exp(Δψ e^) exp(d^),   x = Δψ e + d + ½ Δψ e × d + O(3)
// (Baker–Campbell–Hausdorff), so the mixed derivative of the Lagrangian L gains the path's
// curvature term ∇_{x_{N−1}}L · ½ (e × ∂d/∂h): ∂²L/∂ψ∂η = e·H(:, η) + ∇_{x_{N−1}}L · ½ (e × d′) h₀.
// test_free_time_twist.cpp checks every entry against central differences of C(h, ψ).
#pragma once

#include <Eigen/Core>

#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_transcription.hpp"  // localTwistMotion

namespace attitude_planner {

/// ψ's entries of one local block of the free-time system over (local nodes, η = h/h₀), from that
/// block's Hessian H (barrier terms included), right-hand side and Lagrangian gradient (fixed
/// nodes' columns included).
struct TwistEntries {
  Eigen::Matrix<double, 9, 1> nodes = Eigen::Matrix<double, 9, 1>::Zero();  ///< H e
  double time = 0.0;        ///< ∂²/∂η∂ψ, with the path's curvature term
  double twist = 0.0;       ///< eᵀ H e
  double rhs = 0.0;         ///< rhsᵀ e
  double lagrangian = 0.0;  ///< ∇Lᵀ e: the block's part of ∂L/∂ψ
  bool any = false;         ///< whether the block reaches a node the twist moves
};
TwistEntries twistEntries(const ReducedProblem& np, int first_node, int width, double h0,
                          const Eigen::Matrix<double, 10, 10>& H,
                          const Eigen::Matrix<double, 10, 1>& rhs,
                          const Eigen::Matrix<double, 10, 1>& lagrangian);

}  // namespace attitude_planner
