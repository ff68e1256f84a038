// The starts of minimum time (drivers/minimum_time*.cpp): the smallest authority of the bounds,
// the eigenaxis bang–bang slew at its closed-form T and excursions off it (for the free-time
// solves and the search), the free-time solve's structured starts, and a start made to clear the
// pointing cones (a free-time solve cannot move an attitude by raising T, so its start must clear
// them strictly).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// The structured starts' first T, relative to the eigenaxis slew's least T.
constexpr double kEigenaxisStartFactor = 1.02;

/// A free-time solve's start must clear its cones strictly: raising T moves no attitude, so the
/// start's clearance is all the room the barrier has. Starts are taken this far [rad] inside the
/// cones' node bounds.
constexpr double kConeStartClearance = 0.01;

/// A rest-to-rest slew R(t) = R_0 exp(θ(s) ê) exp(b(s) p̂), s = t/T: the eigenaxis bang–bang
/// θ(s) = 2Θs² (s ≤ ½), Θ(1 − 2(1 − s)²) (s > ½) about ê = log(R_0ᵀR_T)/Θ, and an excursion
/// b(s) = ε sin²(πs) about a unit p̂ ⟂ ê (ε = 0: the eigenaxis slew itself), which leaves both
/// ends and their rest untouched. The attitudes at the N + 1 nodes: a start for the search.
Maneuver excursionSlew(const PlanningProblem& problem, const Vector3& excursion_axis,
                       double excursion);

/// The least T at which the eigenaxis bang–bang slew keeps the torque bounds (per axis, norm and
/// the reaction wheels' torque limits under the minimum-norm law) and rate limits in force: its
/// torques τ = J ê θ̈ + θ̇² ê × J ê scale like 1/T² and its peak rate 2Θ/T like 1/T, so T follows in
/// closed form from the profile at T = 1.
double eigenaxisBangBangDuration(const PlanningProblem& problem);

/// One start of the free-time solve.
struct FreeTimeStart {
  std::string name;
  AttemptStart kind;
  std::vector<Matrix3> attitudes;  ///< R_0..R_N
  double duration;
  StartDetail detail = {};  ///< its parameters, structured (Attempt::start_detail)
};

/// The axes ⟂ ê the excursions turn about: the body axes' parts perpendicular to the eigenaxis
/// and their normalized sums and differences (the box bounds act on body axes, so the nutating
/// optima turn about them and their diagonals: measured, Bilimoria–Wie reaches its published T*
/// only from a diagonal, Betts's from the diagonals of y and z). Body-fixed: the same in every
/// world frame.
std::vector<Vector3> excursionAxes(const Vector3& e);

/// The structured starts: rest to rest, the eigenaxis bang–bang slew at its closed-form T and
/// excursions off it (excursionAxes; with cones larger ones about directions evenly spaced round
/// the eigenaxis, coneExcursionAxes, and the slew turned round the cone on each side); otherwise the reduced problem's own start at the eigenaxis
/// guess, and the unconstrained optima of its classes, solved in `context` (the request's: its
/// budget, cancel flag and iteration numbering).
std::vector<FreeTimeStart> freeTimeStarts(const PlanningProblem& problem, bool rest_to_rest,
                                          SolveContext& context);

/// The largest entry of R_k − R'_k over two lists of attitudes of one length.
double largestDifference(const std::vector<Matrix3>& a, const std::vector<Matrix3>& b);

/// The smallest clearance of the free attitudes R_1..R_{N−1} to their cones' node bounds [rad]
/// (+∞ without cones).
double coneClearance(const PlanningProblem& problem, const std::vector<Matrix3>& R);

/// A start that is a neighbouring KKT point's plan (a coarser level's answer prolonged, a saddle
/// left) clears its cones by this much [rad]: strict room for the barrier, no more. Measured on
/// seeded keep-out slews (scripts/minimum_time_cost.py, N = 64 -> 128): a 1e-2 rad push cost the
/// refined level 100-330 iterations, 1e-4 rad 29-37 (the same T*).
constexpr double kNeighbourConeClearance = 1e-4;

/// A node's turn out of a cone is spread over its neighbours within N/this nodes
/// (pushedOutOfCones).
constexpr int kConePushTaper = 16;

/// R_k turned (in the world frame, about s × R_k b) far enough to clear each cone's node bound by
/// `clearance`: for a resampled coarse T* plan, whose new nodes between the coarse ones dip past
/// an active bound by O(h²). The turn is tapered over the neighbouring nodes
/// (kConePushTaper): a turn δ of single nodes is a kink, a torque of about J δ/h² (measured at N
/// = 128: 3.4-11x the torque bound for pushes of 1e-4 to 1e-2 rad, the start then began elastic;
/// tapered, the prolongation's own 1.2-1.4x).
std::vector<Matrix3> pushedOutOfCones(const PlanningProblem& problem, std::vector<Matrix3> R,
                                      double clearance);

/// A start that clears the cones: the minimum-effort plan at `duration` under the cones alone,
/// their node bounds tightened by kConeStartClearance (the torque bounds left out: the free-time
/// solve meets them by raising T), warm-started from `attitudes` so that each start keeps its own
/// side of a cone: where they cross a keep-out cone, from them turned round it on the side nearer
/// them (coneSideStarts); cold if that does not converge in a few iterations (a warm solve that
/// long is crossing the cone the long way). Empty if none converges. Its solves run in
/// `context` with its options(). `joins` (where given) watches their iterates
/// (SolveContext::IterateWatch): where it stops one the clearing ends there, empty (the caller
/// knows the plan its watch recognized).
std::optional<std::vector<Matrix3>> coneClearStart(const PlanningProblem& problem,
                                                   const std::vector<Matrix3>& attitudes,
                                                   double duration, SolveContext& context,
                                                   const SolveContext::IterateWatch& joins = {});
/// The same as a request of its own (tests).
std::optional<std::vector<Matrix3>> coneClearStart(const PlanningProblem& problem,
                                                   const std::vector<Matrix3>& attitudes,
                                                   double duration, const SolverOptions& options);

}  // namespace attitude_planner
