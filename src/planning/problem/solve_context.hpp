// What every solve of one request shares: the clock and its deadline, the cancel flag, the
// iteration numbering reported to the caller, and the trail of attempts. Solvers, strategies and
// drivers take a SolveContext& instead of re-deriving budgets, renumbering iterations and
// concatenating messages by hand.
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

  /// The clock starts now; options.time_budget_s (0 = none) sets the deadline.
  explicit SolveContext(const SolverOptions& options);

  const SolverOptions& options() const { return options_; }
  Clock::time_point start() const { return start_; }
  double elapsedSeconds() const;
  /// Seconds left before the deadline (+∞ without a budget, 0 once spent).
  double remainingSeconds() const;
  /// `options()` with what is left of the budget (kSpentBudget once spent): for a sub-solve that
  /// still takes SolverOptions.
  SolverOptions remainingOptions() const;

  /// Cancelled (the flag or an earlier on_iteration refusal) or TimedOut if the solve must stop
  /// now, else nothing.
  std::optional<Termination> stopReason() const;
  /// Throws SolveInterrupted if stopReason() says so (called inside long loops).
  void poll() const override;

  /// Reports one iteration to options().on_iteration, numbered across every attempt of the
  /// request (1, 2, ...); returns false if the caller asked to stop (then stopReason() is
  /// Cancelled from here on).
  bool reportIteration(const IterationInfo& info);
  /// Whether a caller reads the reports (options().on_iteration set): figures that cost a pass
  /// over the grid are formed only then.
  bool hasIterationCallback() const { return static_cast<bool>(options_.on_iteration); }
  /// Iterations reported so far.
  int iterations() const { return iterations_; }

  /// Appends an attempt to the trail (in the order attempts end).
  void record(const Attempt& attempt) { attempts_.push_back(attempt); }
  /// Marks the attempt at `index` as the one whose plan is returned, clearing the others' mark
  /// (a later solve of the same request, e.g. the interior point after Newton, marks its own).
  void markKept(std::size_t index);
  const std::vector<Attempt>& attempts() const { return attempts_; }

 private:
  SolverOptions options_;
  Clock::time_point start_;
  int iterations_ = 0;
  bool refused_by_callback_ = false;
  std::vector<Attempt> attempts_;
};

}  // namespace attitude_planner
