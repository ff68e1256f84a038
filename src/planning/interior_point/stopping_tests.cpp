// The stopping tests (stopping_tests.hpp).
#include "planning/interior_point/stopping_tests.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace attitude_planner {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// Above this N the free-time stationarity tolerance grows like N² (the reduced problem's band).
constexpr double kRoundOffSteps = 256;

}  // namespace

DecrementTest::DecrementTest(const InteriorPointParameters& parameters, double tolerance, int steps,
                             bool mehrotra, bool free_slacks)
    : p_(parameters),
      tolerance_(tolerance),
      stall_acceptance_(
          parameters.stall_acceptance *
          std::max(1.0, steps / static_cast<double>(parameters.stall_acceptance_steps))),
      mehrotra_(mehrotra),
      free_slacks_(free_slacks),
      best_violation_(kInfinity),
      best_final_decrement_(kInfinity),
      previous_decrement_(kInfinity) {}

StopVerdict DecrementTest::check(const DecrementProbe& d) {
  StopVerdict t;
  t.relative_decrement = std::sqrt(std::max(0.0, -d.decrement_slope)) / std::sqrt(2.0 * d.f_scale);
  const double decrement = t.relative_decrement;
  t.at_final_barrier = d.at_final_barrier;
  t.violated = d.max_violation > p_.feasibility_tolerance;
  countStalls(t);
  const bool violation_stalled = violationStalled(t.violated, d.max_violation, d.iteration);
  const bool unshifted = d.shift <= p_.negligible_shift;
  // Quadratic convergence seen at the final barrier: this step leaves about d·(d/d₋)².
  const bool quadratic_finish = mehrotra_ && t.at_final_barrier && previous_at_final_barrier_ &&
                                !t.violated && unshifted && previous_alpha_ >= p_.quadratic_step &&
                                decrement < previous_decrement_ &&
                                decrement * std::pow(decrement / previous_decrement_, 2) <=
                                    p_.quadratic_margin * stall_acceptance_;
  const double reachable_tolerance =
      mehrotra_ ? std::max(tolerance_, p_.reachable_fraction * stall_acceptance_) : tolerance_;
  t.final_step =
      violation_stalled ||
      (t.at_final_barrier && ((unshifted && decrement <= reachable_tolerance) ||
                              stalled_iterations_ >= p_.stalled_iterations || quadratic_finish));
  t.at_floor =
      t.at_final_barrier && !t.violated && decrement <= p_.floor_factor * stall_acceptance_;
  return t;
}

void DecrementTest::accepted(const StopVerdict& v, double alpha) {
  if (v.final_step) return;
  previous_decrement_ = v.relative_decrement;
  previous_alpha_ = alpha;
  previous_at_final_barrier_ = v.at_final_barrier;
}

std::optional<LoopEnd> DecrementTest::onRejected(const BarrierState&, const StopVerdict& v) {
  if (!v.at_floor) return std::nullopt;
  std::ostringstream why;
  why << "converged to the round-off floor (relative Newton decrement " << v.relative_decrement
      << ", the line search can no longer decrease the merit)";
  return LoopEnd{Termination::Converged, why.str(), v.relative_decrement};
}

void DecrementTest::restart(int iteration) {
  best_violation_ = kInfinity;
  last_violation_progress_ = iteration;
  best_final_decrement_ = kInfinity;
  stalled_iterations_ = 0;
}

/// At μ_final the condensed system's condition limits the decrement: full steps that no longer
/// halve it (below the stall acceptance, or with the constraints still violated) stall.
void DecrementTest::countStalls(const StopVerdict& t) {
  if (!t.at_final_barrier) return;
  const double decrement = t.relative_decrement;
  if ((decrement <= stall_acceptance_ || t.violated) &&
      decrement > p_.stall_ratio * best_final_decrement_) {
    ++stalled_iterations_;
  } else {
    stalled_iterations_ = 0;
  }
  best_final_decrement_ = std::min(best_final_decrement_, decrement);
}

/// A violation that no iteration reduces any more is a local minimum of the ℓ1 infeasibility.
bool DecrementTest::violationStalled(bool violated, double violation, int iteration) {
  if (!violated || violation < best_violation_ * (1.0 - p_.violation_progress)) {
    best_violation_ = violated ? violation : kInfinity;
    last_violation_progress_ = iteration;
  }
  const int patience = free_slacks_ ? p_.free_slack_violation_stall : p_.violation_stall;
  return violated && iteration - last_violation_progress_ >= patience;
}

KktResidualTest::KktResidualTest(double tolerance, int steps)
    : tolerance_(tolerance),
      stationarity_tolerance_(
          tolerance * std::max(1.0, std::pow(static_cast<double>(steps) / kRoundOffSteps, 2))) {}

std::optional<LoopEnd> KktResidualTest::beforeDirection(const BarrierState& s) {
  if (s.elastic || !s.at_final_barrier || !converged(s.stationarity, s.gap)) return std::nullopt;
  return LoopEnd{Termination::Converged, "converged", std::nullopt};
}

StopVerdict KktResidualTest::afterDirection(const BarrierState& s, const DirectionMeasures&) {
  StopVerdict v;
  v.at_floor = s.at_final_barrier && atRoundOffFloor(s);
  return v;
}

std::optional<LoopEnd> KktResidualTest::onRejected(const BarrierState& s, const StopVerdict&) {
  if (!atRoundOffFloor(s)) return std::nullopt;
  return LoopEnd{Termination::Converged, "converged to the round-off floor", std::nullopt};
}

}  // namespace attitude_planner
