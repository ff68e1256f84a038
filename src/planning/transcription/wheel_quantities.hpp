// The reaction-wheel stage quantities (attitude_planner/planning/reaction_wheels.hpp has the
// physics) and the constraints on them, as StageQuantityModel / StageConstraint objects: the
// interior point at a fixed h, free time and the plan's check read them like any other.
//
// Both quantities are 3-vectors in the body frame of node k, on the nodes k−1, k, k+1 (the band
// stays 8):
//   WheelMomentum  q_k = R_kᵀπ₀ − Π_k      the array's momentum A h_w,k [N m s]
//   WheelTorque    a_k = −(τ_k + J⁻¹Π_k × q_k)   the array's torque A u_k [N m]
// Π_k the node momentum (ReducedProblem::forEachNodeMomentum), π₀ = R_0 (J Ω(0) + A h_w(0)).
// Each wheel's limits are two linear sides in q (or a): h_w,i = (A⁺q)_i + (null part)_i,
// u_i = (A⁺a)_i; the envelope |q| ≤ H is affine in a third object, ½|q|². So n wheels cost two
// quantities (three with the envelope), not 2n.
#pragma once

#include <memory>

#include "attitude_planner/planning/problem.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

/// The wheel quantities of `problem` (reaction_wheels present): q_k, or ½|q_k|² in entry 0 with
/// `half_squared_norm` (the envelope's: kind WheelMomentum, the same plain form q_k on a plan).
std::shared_ptr<const StageQuantityModel> makeWheelMomentumQuantity(const PlanningProblem& problem,
                                                                    bool half_squared_norm);
std::shared_ptr<const StageQuantityModel> makeWheelTorqueQuantity(const PlanningProblem& problem);

/// Appends the wheel constraints of `problem` to `out`: per wheel the two momentum sides and the
/// two torque sides, then the momentum envelope if given (buildStageConstraints' order).
void appendWheelConstraints(const PlanningProblem& problem, StageConstraints* out);

}  // namespace attitude_planner
