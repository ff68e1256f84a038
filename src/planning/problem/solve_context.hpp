// What every solve of one request shares: the clock and its deadline, the cancel flag, the
// iteration numbering reported to the caller, and the trail of attempts. One is built per request
// (planManeuver, or a public entry point called on its own) and every driver and solver takes it
// by reference, so iterations are numbered once and the budget lives in one place
// (remainingSeconds, stopReason) instead of being re-derived per sub-solve.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
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

/// Whether a solve ended because the request stopped it (Cancelled or TimedOut): no retry, no
/// further level, the last iterate as it is.
inline bool stoppedByRequest(Termination t) {
  return t == Termination::Cancelled || t == Termination::TimedOut;
}

class SolveContext : public Interruption {
 public:
  using Clock = std::chrono::steady_clock;

  /// The clock starts now; the request's options.time_budget_s (0 = none) sets the deadline,
  /// its cancel flag and on_iteration serve every solve of the request.
  explicit SolveContext(const SolverOptions& request);
  SolveContext(const SolveContext&) = delete;
  SolveContext& operator=(const SolveContext&) = delete;

  /// A branch of `parent` for one of several solves run at once on other threads (runBranches):
  /// the parent's request, deadline, cancel flag, solve in progress (options()) and enclosing
  /// attempt; its reports reach the caller one at a time, numbered in the request's one
  /// sequence; its attempts and levels are its own until `join` appends them to the parent's.
  struct Branch {};
  SolveContext(SolveContext& parent, Branch);
  /// Appends a branch's attempts, levels and iteration count to this context's, after the
  /// branch's thread ended (in the order the caller joins branches: the trail's order).
  void join(SolveContext& branch);
  /// Solves the request may run at once (SolverOptions::threads; 0: the machine's cores).
  int threads() const;

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

  /// The iterations reported from its construction on: a phase's count (a continuation's
  /// stages, a Newton start then the interior point) read from the one numbering, instead of
  /// summed from its solves' results. A phase run in separate spans (a minimum-time search's
  /// start, bisected after the other starts ran) pauses it between them.
  class IterationTally {
   public:
    explicit IterationTally(const SolveContext& context)
        : context_(&context), at_open_(context.iterations_) {}
    /// Iterations reported while it counted (up to now if it counts now).
    int iterations() const { return counted_ + (counting_ ? context_->iterations_ - at_open_ : 0); }
    /// Stops counting; what it counted stays.
    void pause() {
      counted_ = iterations();
      counting_ = false;
    }
    /// Counts again from now on, after what it counted before.
    void resume() {
      if (counting_) return;
      at_open_ = context_->iterations_;
      counting_ = true;
    }
    bool counting() const { return counting_; }
    /// Adds what another tally counted apart from this one (a joined branch's, counted in the
    /// branch while this one was paused).
    void addCountedApart(int iterations) { counted_ += iterations; }

   private:
    const SolveContext* context_;
    int at_open_;
    int counted_ = 0;
    bool counting_ = true;
  };

  /// The work an optional phase may spend (work(), counted from its construction): a phase that
  /// searches for a better answer than the one in hand (the probes below a minimum time, the
  /// search on durations) asks exhausted() between its solves and stops once it says so. So such
  /// a phase ends after at most its allowance and the solve in progress, on any grid and
  /// without a time budget, and at the same point on every run.
  class WorkAllowance {
   public:
    WorkAllowance(const SolveContext& context, double node_iterations)
        : context_(&context), at_open_(context.work()), allowance_(node_iterations) {}
    /// Whether the work since it opened reached the allowance; once it said so, stopped() holds.
    bool exhausted() const {
      if (context_->work() - at_open_ >= allowance_) stopped_ = true;
      return stopped_;
    }
    /// Whether exhausted() ever said so (a phase that stopped for it).
    bool stopped() const { return stopped_; }
    double allowance() const { return allowance_; }

   private:
    const SolveContext* context_;
    double at_open_;
    double allowance_;
    mutable bool stopped_ = false;
  };

  /// How a scope names the attempts begun inside it (the trail relabels them the same way).
  enum class Nested {
    /// Theirs, but an attempt of stage Solve (a solver's own solve) takes the scope's stage (a
    /// minimum-time probe's Newton solve is a `minimum_time_probe`).
    OwnStages,
    /// The scope's stage, whatever they call themselves (the plan at (1 + margin) T* is a
    /// `minimum_time_margin` however it was reached).
    ScopeStage,
  };
  /// While alive, the iterations reported belong to a new attempt of `stage` in `homotopy`
  /// (IterationInfo::attempt), numbered after every attempt begun before it, its stage named by
  /// the enclosing scopes (Nested); when it ends the enclosing attempt's tag comes back.
  class Scope {
   public:
    Scope(SolveContext& context, AttemptStage stage, const HomotopyClass& homotopy,
          Nested nested = Nested::OwnStages);
    ~Scope() {
      context_.attempt_ = previous_;
      context_.scope_names_nested_ = previous_names_nested_;
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

    /// Iterations reported while it was open, its nested attempts' included.
    int iterations() const { return tally_.iterations(); }

   private:
    SolveContext& context_;
    AttemptTag previous_;
    bool previous_names_nested_;
    IterationTally tally_;
  };
  /// The attempt the iterations reported now belong to (number 0 outside every Scope).
  const AttemptTag& currentAttempt() const { return attempt_; }

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
  /// request (1, 2, ...) and tagged with the current attempt (currentAttempt()); returns false if
  /// the caller asked to stop (then stopReason() is Cancelled from here on).
  bool reportIteration(const IterationInfo& info);
  /// Whether a caller reads the reports (options().on_iteration set): figures that cost a pass
  /// over the grid are formed only then.
  bool hasIterationCallback() const { return static_cast<bool>(request_.on_iteration); }
  /// Iterations reported so far.
  int iterations() const { return iterations_; }
  /// Work reported so far: Σ over the iterations reported of the grid's N (IterationInfo::steps,
  /// 1 where a report names none), in node-iterations. An iteration's cost grows with N (the
  /// banded KKT system), so a bound on the work bounds the time on any grid; it is the same on
  /// every run of a request (unlike seconds), so an answer bounded by it is reproducible. In a
  /// branch: the parent's work when the branch began, and the branch's own.
  double work() const { return work_before_ + work_; }

  /// Appends an attempt to the trail (in the order attempts end), named as the open scopes name
  /// an attempt begun inside them (Nested: a solver's `solve` takes the scope's stage, and any
  /// stage does under Nested::ScopeStage); a kept attempt clears the others' mark, so the trail
  /// holds one kept attempt, the last one recorded or marked (markKept).
  void record(Attempt attempt);
  /// Marks the attempt at `index` as the one whose plan is returned, clearing the others' mark
  /// (a later solve of the same request, e.g. the interior point after Newton, marks its own).
  void markKept(std::size_t index);
  /// The attempt at `index` had its plan's check deferred (the Newton walk's); it has run now and
  /// says `termination` (not converged where the check failed).
  void planChecked(std::size_t index, Termination termination);
  /// The kept attempt's index (nothing if none is marked).
  std::optional<std::size_t> keptAttempt() const;
  /// The kept attempt if it is one recorded from `first` on (a sub-solve's kept attempt, read
  /// after it returned).
  std::optional<std::size_t> keptSince(std::size_t first) const;
  /// Marks `index` kept (as markKept), or with nothing clears every mark: a plan no single
  /// attempt produced (a combination of two) or an earlier answer kept after later attempts.
  void restoreKept(std::optional<std::size_t> index);
  const std::vector<Attempt>& attempts() const { return attempts_; }
  /// The trail of a driver whose attempts began at `first` (attempts().size() when it started).
  std::vector<Attempt> attemptsFrom(std::size_t first) const;

  /// Appends the levels (LevelSummary) a solve on one grid ended with, in the order solves end:
  /// each of the interior point's grid solves, and a Newton solve's when it returns (the kept
  /// attempt's levels: those of the plan it returns, not of the attempts it left). A solve's
  /// `levels` are levelsFrom(levels().size() when it began).
  void recordLevels(const std::vector<LevelSummary>& levels);
  /// The last level recorded ends as `termination` (a level evaluated after its continuation
  /// stopped reports the stop).
  void endLastLevelAs(Termination termination);
  const std::vector<LevelSummary>& levels() const { return levels_; }
  std::vector<LevelSummary> levelsFrom(std::size_t first) const;
  /// The attempts recorded from `first` on were posed at a pointing request's start twist ψ
  /// [rad] (Attempt::start_detail.twist): the solves of a start R_N fixed there.
  void posedAtTwist(std::size_t first, double twist);

  /// A stop a driver puts on the fixed-h interior point's iterates: asked with the attitudes
  /// R_0..R_N after each accepted step; a non-empty reason stops that solve there (NotConverged,
  /// GridOutcome::stopped_by_watch, so no retry in the other form). Once it stopped a solve it
  /// stops every later one at its first step with the same reason: the driver has what it wanted
  /// (a cone clearing that reached a plan an earlier clearing made), and the fallbacks after a
  /// stopped solve (the other attempts of the constrained recipe) would only repeat the work.
  using IterateWatch = std::function<std::string(const std::vector<Matrix3>&)>;
  /// While alive, `watch` watches the iterates of this context's fixed-h interior points (not a
  /// branch's: a branch runs its own solves, and a watch that records what it saw is not shared
  /// across threads).
  class WatchIterates {
   public:
    WatchIterates(SolveContext& context, IterateWatch watch)
        : context_(context), previous_(context.iterate_watch_), watch_(std::move(watch)) {
      context_.iterate_watch_ = this;
    }
    ~WatchIterates() { context_.iterate_watch_ = previous_; }
    WatchIterates(const WatchIterates&) = delete;
    WatchIterates& operator=(const WatchIterates&) = delete;
    /// The watch's say on an iterate (sticky once it stopped one).
    std::string stopAt(const std::vector<Matrix3>& attitudes) {
      if (stopped_.empty()) stopped_ = watch_(attitudes);
      return stopped_;
    }
    /// Whether it stopped a solve.
    bool stoppedASolve() const { return !stopped_.empty(); }

   private:
    SolveContext& context_;
    WatchIterates* previous_;
    IterateWatch watch_;
    std::string stopped_;
  };
  /// Whether an IterateWatch is in force (the attitudes are formed only then).
  bool watchesIterates() const { return iterate_watch_ != nullptr; }
  /// The reason the IterateWatch in force stops a solve at `attitudes` (empty: go on, or none).
  std::string iterateStop(const std::vector<Matrix3>& attitudes) {
    return iterate_watch_ ? iterate_watch_->stopAt(attitudes) : std::string();
  }

  /// The iterations of the request's cone clearings (minimum time's starts cleared of the cones
  /// by minimum-effort solves that stand aside: in no attempt of the trail), read from the one
  /// numbering by one tally that counts only while a ClearingCones is alive (a branch's clearings
  /// join with the branch). Every minimum-time answer of the request reads it here, so an answer
  /// made of two minimum-time solves (a Richardson pair, a fixed twist then the free one) counts
  /// both without adding them.
  int coneClearingIterations() const { return cone_clearings_.iterations(); }
  /// While alive, the iterations reported in this context (and the branches joined into it) are
  /// the request's cone clearings' (coneClearingIterations).
  class ClearingCones {
   public:
    explicit ClearingCones(SolveContext& context)
        : tally_(context.cone_clearings_), was_counting_(tally_.counting()) {
      tally_.resume();
    }
    ~ClearingCones() {
      if (!was_counting_) tally_.pause();
    }
    ClearingCones(const ClearingCones&) = delete;
    ClearingCones& operator=(const ClearingCones&) = delete;

   private:
    IterationTally& tally_;
    bool was_counting_;
  };

  /// While alive, the attempts recorded are parts of an enclosing attempt (a level's
  /// unconstrained start, a start's helper solve, a search's probes, which the search records as
  /// one attempt per start): when it ends they leave the trail and the kept mark is as before.
  class Aside {
   public:
    explicit Aside(SolveContext& context)
        : context_(context), first_(context.attempts_.size()), kept_(context.keptAttempt()) {}
    ~Aside() {
      context_.attempts_.resize(first_);
      context_.restoreKept(kept_);
    }
    Aside(const Aside&) = delete;
    Aside& operator=(const Aside&) = delete;

   private:
    SolveContext& context_;
    std::size_t first_;
    std::optional<std::size_t> kept_;
  };

 private:
  /// What a request's contexts (its root and the branches) share: the numbering of reports and
  /// attempts, the caller's refusal, and the lock that lets one report reach the caller at a time.
  struct Shared {
    std::mutex report;
    int reported = 0;
    int attempts_begun = 0;
    std::atomic<bool> refused_by_callback{false};
  };

  SolverOptions request_;
  const SolverOptions* call_;
  Clock::time_point start_;
  std::shared_ptr<Shared> shared_;
  int iterations_ = 0;        ///< reported from this context (a branch's own, for its tallies)
  double work_ = 0.0;         ///< node-iterations reported from this context (work())
  double work_before_ = 0.0;  ///< a branch's parent's work() when the branch began
  AttemptTag attempt_;
  bool scope_names_nested_ = false;  ///< an open scope is Nested::ScopeStage
  std::vector<Attempt> attempts_;
  std::vector<LevelSummary> levels_;
  WatchIterates* iterate_watch_ = nullptr;  ///< this context's own (a branch starts without)
  IterationTally cone_clearings_{*this};    ///< paused outside ClearingCones
};

/// Runs work(i, branch) for i in [0, count), up to context.threads() at once, each in its own
/// branch of `context` (SolveContext::Branch); a thread takes the next work as soon as its last one
/// ended (works of unequal length: no thread waits for another's), and the branches join into
/// `context` in the order of i; an exception thrown by any work is rethrown after every branch
/// joined (the first in that order). The work must not touch what another one writes.
void runBranches(SolveContext& context, int count,
                 const std::function<void(int, SolveContext&)>& work);

/// What runSlidingWindow's begin(i) hands over to run for i in a branch (empty: nothing to run).
using BranchWork = std::function<void(SolveContext&)>;
/// Runs `count` works in the order of i, up to context.threads() at once, as a sliding window:
/// begin(i) runs on the calling thread and returns the work for i, run on a thread of its own in
/// a branch of `context`; end(i) runs on the calling thread in the order of i, after work i ended
/// and its branch joined `context`. Before begin(i) the earliest works still open are ended until
/// a place is free, never a later one first, so what begin(i) sees (the ends before it) does not
/// depend on which work finishes first: the same answer on every run. Work i may read what the
/// ends before its begin wrote, never what a later end writes. An exception thrown by a work is
/// rethrown at its end, once every work begun has ended; no work begins after it.
void runSlidingWindow(SolveContext& context, int count, const std::function<BranchWork(int)>& begin,
                      const std::function<void(int)>& end);

}  // namespace attitude_planner
