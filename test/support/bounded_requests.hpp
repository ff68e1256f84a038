// Seeded bounded requests (torque and rate bounds, spinning ends, extreme magnitudes), shared by
// the CI-sized gtest (test/unit/test_bounded_verdicts.cpp) and the full-size study
// (studies/bounded_verdicts_study.cpp, scripts/bounded_verdicts →
// docs/results/bounded_verdicts.md).
//
// Request `index` starts from robustness::randomCase(suite_seed, index) (random body, attitudes,
// spinning or resting ends, horizon, N) and bounds it by kind (index mod 4), against the case's
// stored reference (test/support/bounded_references.hpp: the peaks of its unbounded
// minimum-effort plan as one library planned it once, kept in test/data/bounded_references.csv,
// so a request is a function of (suite_seed, index) alone and no planner change moves it):
//   norm       |τ| ≤ f·(the reference's peak |τ_k|)
//   box        |τ_i| ≤ f·(the reference's peak |τ_i|), each axis
//   norm+rate  the norm bound and |Ω| ≤ max(boundary rates, f'·(the reference's peak |Ω_k|))
//   replan     the rest of the reference plan from node N/3 (analysis/replanning's
//              remainderProblem from the reference's state there, a spinning start), under the
//              norm bound of the rest's peak
// with f drawn in [0.6, 0.9] (f' in [0.8, 1.0]). Every fourth request of a kind is asked as
// minimum time instead (the bound in force, no duration). A case whose reference plan did not
// converge has no request; a seed without references, or a stale reference, is refused
// (std::runtime_error naming the seed and index).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {
namespace robustness {

struct BoundedRequest {
  int index = 0;
  PlanningProblem problem;
  std::string kind;     ///< "norm", "box", "norm+rate", "replan"
  double fraction = 0;  ///< f
  std::string label;    ///< the random case's label, the kind and f
};

/// Request `index` of the suite, or nothing where its reference plan did not converge (no peak
/// to bound by). Throws std::runtime_error where the reference file has no entry for it or a
/// stale one.
std::optional<BoundedRequest> boundedRequest(std::uint64_t suite_seed, int index);

/// One request planned and its verdict checked independently of the planner's own words.
struct VerdictCheck {
  PlanResult result;
  double seconds = 0.0;  ///< planManeuver's wall time
  /// The planner threw InvalidInput / StepTooLarge for this valid request (its text).
  std::string input_error;
  /// What was found wrong with the verdict (empty: nothing):
  ///   converged      its plan leaves a bound by more than 1e-6 (relative)
  ///   proven         a minimum-time plan exists below the proven bound on the grid
  ///   local          least_duration_found X, yet a minimum-effort plan converges at 0.98 X
  ///   minimum time   a minimum-effort plan converges at 0.99 T*
  ///   within bounds  an answer not converged says its plan is within the bounds
  ///                  (plan_within_bounds), yet it leaves a bound by more than 1e-6 or misses
  ///                  its boundary states by more than 1e-8
  ///   infeasible with a plan  an "infeasible" answer whose own plan is a plan of the request
  ///                  at T (its N steps end at T; the boundary states and every bound met)
  std::string wrong;
  double check_duration = 0.0;  ///< the T the check solved at (0: none)
};

/// Plans `request` (planManeuver with `options`) and checks its verdict as above.
VerdictCheck planAndCheck(const BoundedRequest& request, const SolverOptions& options = {});

/// A cold minimum-effort solve at T under the request's bounds (what the check solves at 0.99 T*):
/// whether it found a plan (converged within the bounds, or an answer not converged whose plan
/// meets the request: boundary states and bounds), its outcome and iterations.
struct ProbeAt {
  double duration = 0.0;
  bool converged = false;  ///< a minimum-effort optimum within the bounds
  bool plan = false;       ///< converged, or a plan within the bounds that did not converge
  std::string outcome;     ///< outcomeName, or "input error"
  std::string message;     ///< the answer's message (or the input error's)
  int iterations = 0;
  double seconds = 0.0;
};
ProbeAt probeAt(const PlanningProblem& problem, double T, const SolverOptions& options = {});

/// The attempts of a plan, one line each (a study's --only output).
std::string attemptLines(const PlanResult& result);

/// "converged", "infeasible (proven)", "infeasible (local)", "input error", or the termination.
std::string outcomeName(const VerdictCheck& check);
/// A result's outcome: "converged", "infeasible (proven)", "infeasible (local)", or the
/// termination.
std::string outcomeName(const PlanResult& result);

}  // namespace robustness
}  // namespace attitude_planner
