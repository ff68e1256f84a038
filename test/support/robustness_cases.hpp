// The named hard cases (each must stay numerically stable): each case plans (or
// integrates) one or more problems and checks its pass criterion, recording every figure it
// measured. One catalog, two readers: test/unit/test_hard_cases.cpp asserts every check (the
// slow cases only under ATTITUDE_PLANNER_SLOW_TESTS=1, i.e. `scripts/test --all`), and the tool
// `robustness_report` writes the same figures into docs/results/robustness.md
// (`scripts/robustness`).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "attitude_planner/planner.hpp"

namespace attitude_planner {
namespace robustness {

/// The figures of one planManeuver call inside a case.
struct RunFigures {
  std::string label;  ///< what was planned, e.g. "θ = π − 1e-6"
  bool converged = false;
  bool finite = false;  ///< every R_k, Ω_k, τ_k finite (no NaN/Inf anywhere in the maneuver)
  int steps = 0;        ///< N
  int iterations = 0;
  double cost = 0.0;                     ///< Σ ½|τ_k|² [N²·m²]
  double terminal_attitude_error = 0.0;  ///< [rad]
  double terminal_velocity_error = 0.0;  ///< [rad/s]
  double max_residual = 0.0;             ///< relative first-order residual at the end
  double newton_decrement = 0.0;         ///< relative torque accuracy of the last step
  double dynamics_residual = 0.0;        ///< worst implicit-step residual of the replay [N·m·s]
  double solve_time_s = 0.0;             ///< wall time [s]
  std::string extremal;                  ///< which extremal (PlanResult::extremal)
  std::string message;                   ///< PlanResult::message
};

/// One checked quantity: `measured` against `bound` (relation "<=", ">=", "==" or "true").
struct Check {
  std::string quantity;
  double measured = 0.0;
  std::string relation;
  double bound = 0.0;
  bool passed = false;
  std::string note;  ///< e.g. the error message a refusal produced
};

/// Everything a case measured.
struct CaseOutcome {
  std::vector<RunFigures> runs;
  std::vector<Check> checks;
  double time_s = 0.0;  ///< wall time of the whole case [s]
  bool passed() const;
  /// The failed checks, one per line ("" if none).
  std::string failures() const;
};

/// Records runs and checks while a case runs.
class Recorder {
 public:
  /// Plans `problem`, records its figures and checks the defaults every run must meet: converged,
  /// and checkConverged.
  PlanResult plan(const std::string& label, const PlanningProblem& problem,
                  const SolverOptions& options = {}, double terminal_bound = 1e-9);
  /// The checks every converged run must meet: finite, residuals finite, and its ends. Where the
  /// open-loop replay ran to the end, its terminal attitude and velocity error ≤
  /// `terminal_bound`. Where it parted (replay_miss +inf, the terminal errors and the dynamics
  /// residual not measured: judgeFailedReplay kept the plan because every step replayed from
  /// the plan's own state lands on it), the plan's own end attitude ≤ `terminal_bound`, its
  /// ends and steps (planInconsistency) and every step replayed (replayStepByStep) instead; each
  /// check's label says which rule it is.
  void checkConverged(const std::string& label, const PlanningProblem& problem,
                      const PlanResult& result, double terminal_bound);
  /// Records the figures of a result without the default checks (a run whose expected outcome
  /// is not "converged"; the case checks what it expects).
  void record(const std::string& label, const PlanningProblem& problem, const PlanResult& result);
  /// Records measured ≤ bound.
  bool atMost(const std::string& quantity, double measured, double bound);
  /// Records measured ≥ bound.
  bool atLeast(const std::string& quantity, double measured, double bound);
  /// Records a yes/no property (measured 1 or 0); `note` is shown with it.
  bool holds(const std::string& quantity, bool value, const std::string& note = "");
  CaseOutcome& outcome() { return outcome_; }

 private:
  CaseOutcome outcome_;
};

/// A named hard case.
struct HardCase {
  std::string name;       ///< identifier (gtest parameter name), e.g. "CutLocusAboutX"
  std::string group;      ///< the issue's group, e.g. "1. cut locus"
  std::string what;       ///< the problem(s) in words
  std::string criterion;  ///< the pass criterion in words (also checked by `run`)
  bool slow = false;      ///< only under `scripts/test --all` (ATTITUDE_PLANNER_SLOW_TESTS=1)
  std::function<void(Recorder&)> run;
};

/// The catalog, in the order.
const std::vector<HardCase>& hardCases();

/// Runs one case (never throws: an unexpected exception is a failed check naming it).
CaseOutcome runCase(const HardCase& hard_case);

/// The seed's example inertia (seed 000; violates J1 + J2 ≥ J3, so problems opt in).
Matrix3 seedInertia();

}  // namespace robustness
}  // namespace attitude_planner
