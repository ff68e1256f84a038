// The interior point's stopping tests, one per profile: the decrement test (fixed h: the Newton
// decrement of φ_μ at μ_final, with its stall and round-off rules) and the KKT residual test (free
// time: stationarity and duality gap of the Lagrangian at μ_final).
#pragma once

#include <optional>
#include <string>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/termination.hpp"

namespace attitude_planner {

/// What the stopping tests and the μ rule read of the iterate; both problems expose it
/// (PrimalDualProblem::state), each filling what its strategies read.
struct BarrierState {
  int iteration = 0;              ///< the passes counted so far
  bool at_final_barrier = false;  ///< μ ≤ μ_final
  bool elastic = false;           ///< free time: still in the elastic start (it never ends there)
  double max_violation = 0.0;     ///< fixed h: the largest elastic violation at the iterate
  double stationarity = 0.0;      ///< free time: ‖∇L‖∞ at the assembled iterate
  double gap = 0.0;               ///< free time: the duality gap Σ zc there
  double f_scale = 1.0;           ///< fixed h: the start's cost (floored), the decrement's scale
  /// Free time: the barrier problem's KKT residual at the assembled iterate (its μ rule's test).
  double barrier_residual = 0.0;
  /// Free time: the last search found the barrier problem solved as far as round-off allows.
  bool solved_to_round_off = false;
  bool end_game = false;  ///< free time: μ ≤ the damped barrier (the damping after cut steps)
};

/// What the decrement test reads of a direction.
struct DirectionMeasures {
  double decrement_slope = 0.0;  ///< the slope the decrement is measured on (≤ 0)
  double shift = 0.0;            ///< the inertia correction used
};

/// How a stopping test ends a solve (the problem keeps it: PrimalDualProblem::ended).
struct LoopEnd {
  Termination termination = Termination::Converged;
  std::string reason;
  std::optional<double> decrement;  ///< the relative Newton decrement it ended at (fixed h)
};

/// The decrement test's verdict on one direction.
struct StopVerdict {
  double relative_decrement = 0.0;
  bool at_final_barrier = false;
  bool violated = false;
  bool at_floor = false;    ///< at μ_final, feasible, at the round-off floor of the decrement
  bool final_step = false;  ///< this step is the barrier problem's last
};

/// What the decrement test reads of one direction and the iterate.
struct DecrementProbe {
  double decrement_slope = 0.0;  ///< the slope the decrement is measured on (≤ 0)
  double shift = 0.0;            ///< the inertia correction used
  bool at_final_barrier = false;
  double max_violation = 0.0;  ///< the largest elastic violation at the iterate
  int iteration = 0;
  double f_scale = 1.0;  ///< the start's cost (floored): the decrement's scale
};

/// The stopping test as the primal–dual loop calls it: at the assembled iterate before the
/// direction, on the direction, after a step taken, and after a line search that took none.
class ConvergenceCheck {
 public:
  virtual ~ConvergenceCheck() = default;
  /// Before the direction: the end where the iterate has converged.
  virtual std::optional<LoopEnd> beforeDirection(const BarrierState& /*state*/) {
    return std::nullopt;
  }
  /// The verdict on a direction: whether its step ends the barrier problem, the round-off floor.
  virtual StopVerdict afterDirection(const BarrierState& /*state*/,
                                     const DirectionMeasures& /*direction*/) {
    return {};
  }
  /// After a step of length `alpha` with verdict `v` whose pass goes on.
  virtual void accepted(const StopVerdict& /*v*/, double /*alpha*/) {}
  /// The line search took no step (or no direction was found): the end where the iterate is at
  /// the round-off floor (nullopt: the problem decides, a retry or a failure).
  virtual std::optional<LoopEnd> onRejected(const BarrierState& state, const StopVerdict& v) = 0;
};

/// Fixed h: the relative Newton decrement √(−slope / 2 f_scale) of φ_μ. A barrier problem at
/// μ_final ends when the decrement reaches the tolerance on an unshifted system, when full steps
/// stall at the condensed system's round-off, when quadratic convergence is seen (Mehrotra), or
/// when a violation no iteration reduces any more (a local minimum of the ℓ1 infeasibility).
class DecrementTest final : public ConvergenceCheck {
 public:
  DecrementTest(const InteriorPointParameters& parameters, double tolerance, int steps,
                bool mehrotra, bool free_slacks);
  StopVerdict check(const DecrementProbe& probe);
  StopVerdict afterDirection(const BarrierState& state,
                             const DirectionMeasures& direction) override {
    return check({direction.decrement_slope, direction.shift, state.at_final_barrier,
                  state.max_violation, state.iteration, state.f_scale});
  }
  /// After an accepted step of length `alpha` with verdict `v`. A barrier problem's last step
  /// (v.final_step) is not remembered: the solve ends there, or the barrier problem starts
  /// again after a penalty raise (restart) with the memory of the step before it.
  void accepted(const StopVerdict& v, double alpha) override;
  /// At the round-off floor (v.at_floor) the iterate is as good as it gets: converged.
  std::optional<LoopEnd> onRejected(const BarrierState& state, const StopVerdict& v) override;
  /// After a penalty raise (a new barrier problem from μ₀): the stall memory starts again.
  void restart(int iteration);
  /// The last accepted step's relative decrement (+∞ before the first).
  double previousDecrement() const { return previous_decrement_; }

 private:
  void countStalls(const StopVerdict& t);
  bool violationStalled(bool violated, double violation, int iteration);

  const InteriorPointParameters& p_;
  double tolerance_, stall_acceptance_;
  bool mehrotra_, free_slacks_;
  int stalled_iterations_ = 0;
  double best_violation_;
  int last_violation_progress_ = 0;
  double best_final_decrement_;
  double previous_decrement_;
  double previous_alpha_ = 0.0;  ///< the last accepted step length
  bool previous_at_final_barrier_ = false;
};

/// Free time: converged at μ_final where the Lagrangian's stationarity is within the tolerance
/// × max(1, (N/256)²) (torques are second differences of the attitudes: their round-off grows
/// like N²) and the duality gap Σ zc within the tolerance.
class KktResidualTest final : public ConvergenceCheck {
 public:
  KktResidualTest(double tolerance, int steps);
  /// Converged at μ_final outside the elastic start.
  std::optional<LoopEnd> beforeDirection(const BarrierState& state) override;
  /// At the round-off floor (StopVerdict::at_floor): at μ_final outside the elastic start, both
  /// residuals within kRoundOffFloor of their tolerances.
  StopVerdict afterDirection(const BarrierState& state, const DirectionMeasures&) override;
  /// No descent step left outside the elastic start, both residuals at the round-off floor.
  std::optional<LoopEnd> onRejected(const BarrierState& state, const StopVerdict& v) override;
  bool converged(double stationarity, double gap) const {
    return stationarity <= stationarity_tolerance_ && gap <= tolerance_;
  }
  /// Where no descent step is left: both residuals within kRoundOffFloor of their tolerances.
  bool atRoundOffFloor(double stationarity, double gap) const {
    return stationarity <= kRoundOffFloor * stationarity_tolerance_ &&
           gap <= kRoundOffFloor * tolerance_;
  }
  /// The iterate at the round-off floor: outside the elastic start, both residuals there.
  bool atRoundOffFloor(const BarrierState& s) const {
    return !s.elastic && atRoundOffFloor(s.stationarity, s.gap);
  }

 private:
  static constexpr double kRoundOffFloor = 100.0;
  double tolerance_, stationarity_tolerance_;
};

}  // namespace attitude_planner
