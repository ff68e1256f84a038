// What every solve of one request shares: the clock and its deadline, the cancel flag, the
// iteration numbering reported to the caller, and the trail of attempts. One is built per request
// (planManeuver, or a public entry point called on its own) and every driver and solver takes it
// by reference, so iterations are numbered once and the budget lives in one place
// (remainingSeconds, stopReason) instead of being re-derived per sub-solve.
#pragma once

#include <chrono>
#include <optional>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/linalg/interruption.hpp"

namespace attitude_planner {

/// Thrown from inside a long computation (SolveContext::poll) when the solve must stop; the
/// solver that catches it returns its last accepted iterate with `termination`.
struct SolveInterrupted {
  Termination termination = Termination::Cancelled;  ///< Cancelled or TimedOut
};

class SolveContext : public Interruption {
 public:
  using Clock = std::chrono::steady_clock;

  /// The clock starts now; the request's options.time_budget_s (0 = none) sets the deadline,
  /// its cancel flag and on_iteration serve every solve of the request.
  explicit SolveContext(const SolverOptions& request);
  SolveContext(const SolveContext&) = delete;
  SolveContext& operator=(const SolveContext&) = delete;

  /// The options of the solve in progress (what a driver hands its solver: the warm start, the
  /// tolerance, the class policy; the request's own outside any Call). Their time budget, cancel
  /// flag and callback are not read: the request's are (request()).
  const SolverOptions& options() const { return *call_; }
  /// The request's options, as the caller gave them.
  const SolverOptions& request() const { return request_; }

  /// While alive, options() is `options` (a driver's sub-solve); the previous ones come back
  /// when it ends.
  class Call {
   public:
    Call(SolveContext& context, const SolverOptions& options)
        : context_(context), previous_(context.call_) {
      context_.call_ = &options;
    }
    ~Call() { context_.call_ = previous_; }
    Call(const Call&) = delete;
    Call& operator=(const Call&) = delete;

   private:
    SolveContext& context_;
    const SolverOptions* previous_;
  };

  Clock::time_point start() const { return start_; }
  double elapsedSeconds() const;
  /// Seconds left before the deadline (+∞ without a budget, 0 once spent).
  double remainingSeconds() const;
  /// `options()` with the request's cancel flag and callback and what is left of its budget
  /// (kSpentBudget once spent): for a solver that takes SolverOptions alone (NLopt).
  SolverOptions remainingOptions() const;

  /// Cancelled (the flag or an earlier on_iteration refusal) or TimedOut if the solve must stop
  /// now, else nothing.
  std::optional<Termination> stopReason() const;
  /// Throws SolveInterrupted if stopReason() says so (called inside long loops).
  void poll() const override;

  /// Reports one iteration to request().on_iteration, numbered across every attempt of the
  /// request (1, 2, ...); returns false if the caller asked to stop (then stopReason() is
  /// Cancelled from here on).
  bool reportIteration(const IterationInfo& info);
  /// Whether a caller reads the reports (options().on_iteration set): figures that cost a pass
  /// over the grid are formed only then.
  bool hasIterationCallback() const { return static_cast<bool>(request_.on_iteration); }
  /// Iterations reported so far.
  int iterations() const { return iterations_; }

  /// Appends an attempt to the trail (in the order attempts end).
  void record(const Attempt& attempt) { attempts_.push_back(attempt); }
  /// Marks the attempt at `index` as the one whose plan is returned, clearing the others' mark
  /// (a later solve of the same request, e.g. the interior point after Newton, marks its own).
  void markKept(std::size_t index);
  const std::vector<Attempt>& attempts() const { return attempts_; }

 private:
  SolverOptions request_;
  const SolverOptions* call_;
  Clock::time_point start_;
  int iterations_ = 0;
  bool refused_by_callback_ = false;
  std::vector<Attempt> attempts_;
};

}  // namespace attitude_planner
