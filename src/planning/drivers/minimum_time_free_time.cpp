#include "planning/drivers/minimum_time_free_time.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/drivers/minimum_time_search.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/interior_point/local_lower_bound.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

/// The free-time solves' tolerance on the KKT residuals (objective T/T₀, constraints
/// dimensionless): the duality gap Σ zc bounds T − T* relative to T₀ by this much.
constexpr double kFreeTimeTolerance = 1e-9;
constexpr int kFreeTimeMaxIterations = 500;
/// Two solves whose solved barrier problems at the same μ have attitudes within this (max entry
/// of R_k − R'_k) are on one central path (sameCentralPath).
constexpr double kSamePath = 1e-3;
/// Two starts at the same T whose attitudes differ by at most this much (max entry of R_k − R'_k)
/// are one start: the free-time solve from either would join the other's central path at its
/// first barrier problem (kSamePath). Starts cleared of the cones to the same minimum-effort plan
/// differ by the clearing solve's tolerance (kConeClearTolerance).
constexpr double kSameStart = kSamePath;
/// A KKT point that is not second-order sufficient (a saddle: FreeTimeOutcome) is left along its
/// negative-curvature direction, both signs, by this much [rad, the largest node turn]: one
/// free-time solve from each. Measured on scenes/min_time_keep_out.yaml: the structured starts
/// are symmetric in time and so is the KKT point they reach, a saddle whose descent is the
/// time-asymmetric passage of the cone.
constexpr double kSaddleEscape = 0.05;
/// A saddle's descent followed at most this many times (each to a lower saddle).
constexpr int kMaxSaddleEscapes = 3;
/// Two saddles whose T agree within this (relative) are one KKT point: left once; and a descent
/// from a saddle that ends within it of the saddle's T went nowhere (not followed further).
/// Measured with the keep-out cone and max_angular_rate 0.05 (N = 64): a KKT point at 44.2472 s
/// whose least curvature is at round-off, left either way, ends at the same T to 1e-9; followed
/// on, it cost 8 solves for nothing.
constexpr double kSameSaddle = 1e-6;

/// Where a start's outcome comes from.
enum class OutcomeFrom {
  ItsSolve,  ///< solved as posed
  Repeat,    ///< the same attitudes and T as an earlier start: not solved, that start's outcome
  Joined,    ///< solved until it joined an earlier start's central path: that start's outcome
};

/// One start of the free-time solves: its attitudes as solved (cleared of the cones), T, name,
/// the outcome, and where the outcome comes from (an earlier start's: `earlier`).
struct StartRecord {
  std::vector<Matrix3> attitudes;
  double duration = 0.0;
  std::string name;
  FreeTimeOutcome outcome;
  OutcomeFrom from = OutcomeFrom::ItsSolve;
  int earlier = -1;                ///< the start whose outcome it took (−1: its own)
  std::vector<BarrierPoint> path;  ///< its solve's solved barrier problems (sameCentralPath)
  std::size_t attempt = 0;         ///< its solve in the trail (a taken outcome: the earlier's)
  /// Where its watch stopped its solve because it could not end below the least T so far: that
  /// lower bound [s], which held (cannotEndBelow); a start that joined such a start's central
  /// path carries the same (−∞: neither).
  double cannot_end_below = -std::numeric_limits<double>::infinity();
  bool tookEarlierOutcome() const { return from != OutcomeFrom::ItsSolve; }
};

/// The starts recorded so far (a record stays where it is while later ones are recorded) and the
/// least T among the converged ones (+∞: none): what a watched solve is watched against, read
/// only, on any thread.
struct Recorded {
  std::vector<const StartRecord*> starts;
  double least_duration = std::numeric_limits<double>::infinity();
};

/// A watched solve's outcome, its attempt, the barrier points it passed (sameCentralPath) and the
/// earlier start whose central path it joined (−1: none).
struct WatchedRun {
  FreeTimeOutcome outcome;
  Attempt attempt;
  std::vector<BarrierPoint> path;
  int joined = -1;
  /// The lower bound [s] at which the watch stopped it as unable to end below the least T (−∞:
  /// not stopped so).
  double cannot_end_below = -std::numeric_limits<double>::infinity();
};

/// A refined level's outcome and its solve in the trail (a resume's, where the resume answered).
struct RefinedOutcome {
  FreeTimeOutcome outcome;
  std::size_t attempt = 0;
};

/// The cone clearings run (coneClearStart; minimum_time.cone_clearings) and how many of them
/// ended at a plan an earlier clearing reached. Their iterations are the context's tally
/// (SolveContext::coneClearingIterations), stamped on the request's answer by planMinimumTime.
struct ClearingWork {
  int clearings = 0;
  int joined = 0;
  void add(const ClearingWork& other) {
    clearings += other.clearings;
    joined += other.joined;
  }
};

/// What one free-time grid level hands the next: its outcome (plan, T, steps).
struct FreeTimeCarry {
  FreeTimeOutcome outcome;
  bool empty() const { return outcome.steps.empty(); }
};

/// The structured starts' T is the eigenaxis slew's profile, a guess: raised until inside (where
/// a raise scales every bound down). Every other start's T is its answer's neighbour.
StartRaise startRaiseOf(AttemptStart kind) {
  const bool guess = kind == AttemptStart::EigenaxisSlew || kind == AttemptStart::Excursion;
  return guess ? StartRaise::UntilInside : StartRaise::Bounded;
}

/// A free-time level's end as the continuation's result and its LevelSummary (the relative
/// gradient: the stationarity of the minimum-time Lagrangian).
PlanResult levelResult(int steps, const FreeTimeOutcome& o) {
  PlanResult r;
  r.termination = o.termination;
  carryReason(&r, o);
  r.iterations = o.iterations;
  LevelSummary level;
  level.steps = steps;
  level.iterations = o.iterations;
  level.termination = o.termination;
  level.relative_gradient = o.stationarity;
  level.reason = renderClauses(o.clauses);
  r.levels.push_back(level);
  return r;
}

/// Minimum time as one interior-point problem per start (free_time_solver.hpp): each start one
/// free-time solve, the least T kept; the starts run on the coarsest level of the free-time grid
/// continuation (freeTimeGridRule) and the best is resumed through the finer levels, each solved
/// once from the coarser answer prolonged (its rates interpolated). The answer is the kept
/// free-time plan (answerAt). Empty if no solve converged (the caller falls back to the search).
class FreeTimeMinimumTime {
 public:
  FreeTimeMinimumTime(const PlanningProblem& problem, SolveContext& context)
      : problem_(problem), context_(context), first_recorded_(context.attempts().size()) {}

  std::optional<PlanResult> run() {
    const bool rest_to_rest =
        problem_.initial_velocity.isZero(0.0) && problem_.final_velocity.isZero(0.0) &&
        so3::angleBetween(problem_.initial_attitude, problem_.final_attitude) > 0;
    const std::vector<PlanningProblem> levels = freeTimeLevels(problem_);
    const PlanningProblem& coarsest = levels.front();
    const std::vector<FreeTimeStart> starts = freeTimeStarts(coarsest, rest_to_rest, context_);
    const std::size_t first = starts_.size();
    int best = solveStarts(coarsest, starts);
    if (!rest_to_rest) best = solveFromViolations(coarsest, starts, first, best);
    // Saddles are left where cones are present: without them the excursion axes reach the least
    // basin (Bilimoria–Wie, Betts: no descent went lower), and the descent from a far saddle
    // (Betts's eigenaxis slew, 20 % above T*) ran to the iteration limit (0.08 → 0.77 s at N = 64).
    if (best >= 0 && coarsest.hasCones()) best = leaveSaddles(coarsest, best, 0);
    if (coarsest.steps < kFreeTimeStartGrid && coarsest.hasCones()) {
      best = fromStartGrid(coarsest, rest_to_rest, best);
    }
    if (best < 0) return std::nullopt;
    if (levels.size() == 1) {
      levels_ = levelResult(coarsest.steps, starts_[best].outcome).levels;
      return answerAt(starts_[best].outcome, starts_[best].name);
    }
    return refineLeast(levels, refinementCandidates(best, rest_to_rest));
  }

  /// One free-time solve on the requested grid from `plan` (a plan meeting every bound at T =
  /// duration, e.g. the search's): its KKT point if it converged at or below that T.
  std::optional<PlanResult> runFrom(const Maneuver& plan, double duration, const std::string& name,
                                    std::optional<Maneuver>* below, StartBarrier barrier,
                                    const BarrierWatch& watch) {
    StartDetail detail;
    detail.duration = duration;
    const FreeTimeOutcome o = solve(problem_, plan.attitude, duration,
                                    AttemptStart::PreviousAttempt, detail, watch, barrier);
    recordStart(plan.attitude, duration, name, o);
    // Every iterate strictly inside its bounds is a plan (the reduced problem meets the dynamics
    // and the boundary data by construction): one that ended short of a KKT point below T is
    // still a plan at its own T.
    if (below && o.termination == Termination::NotConverged && o.smallest_value > 0 &&
        o.duration < duration && !o.maneuver.attitude.empty()) {
      *below = o.maneuver;
    }
    // The plan's T is known to the search's tolerance: a KKT point a rounding above it is the
    // same answer, sharpened (measured: 2.4e-11 relative above).
    if (o.termination != Termination::Converged ||
        o.duration > duration * (1.0 + kMinimumTimeTolerance)) {
      return std::nullopt;
    }
    best_attempt_ = trail_.size() - 1;
    levels_ = levelResult(problem_.steps, o).levels;
    return answerAt(o, name);
  }

 private:
  /// One free-time solve from `start` (N + 1 attitudes, clear of the cones) at T = duration,
  /// recorded in the trail with its start's parameters.
  FreeTimeOutcome solve(const PlanningProblem& p, const std::vector<Matrix3>& start,
                        double duration, AttemptStart kind, const StartDetail& detail,
                        const BarrierWatch& watch = {},
                        StartBarrier start_barrier = StartBarrier::Initial) {
    Attempt a;
    FreeTimeOutcome o =
        solveIn(context_, p, start, duration, kind, detail, watch, start_barrier, &a);
    recordSolve(a);
    return o;
  }

  /// solve's work in `context` (the request's, or a branch of it: runBranches), its attempt
  /// recorded there and returned in `*attempt`; nothing of this object is written.
  static FreeTimeOutcome solveIn(SolveContext& context, const PlanningProblem& p,
                                 const std::vector<Matrix3>& start, double duration,
                                 AttemptStart kind, const StartDetail& detail,
                                 const BarrierWatch& watch, StartBarrier start_barrier,
                                 Attempt* attempt, const FreeTimeScale& scale = {}) {
    const SolveContext::Scope scope(context, AttemptStage::MinimumTimeSolve, homotopyClassOf(p));
    const ElasticBarrier barrier =
        detail.elastic_from_violations ? ElasticBarrier::FromViolations : ElasticBarrier::Initial;
    FreeTimeOutcome o =
        solveFreeTime(p, start, duration, kFreeTimeTolerance, kFreeTimeMaxIterations, context,
                      watch, barrier, start_barrier, startRaiseOf(kind), scale);
    o.iterations = scope.iterations();  // an elastic start's run and the raised one's
    Attempt& a = *attempt;
    a.stage = AttemptStage::MinimumTimeSolve;
    a.start = kind;
    a.formulation = Formulation::FreeSlacks;
    a.steps = p.steps;
    a.termination = o.termination;
    a.iterations = o.iterations;
    // The free-time objective: T [s]; NaN where the solve left no plan (no start inside).
    if (!o.maneuver.attitude.empty()) a.cost = o.duration;
    a.start_detail = detail;
    context.record(a);
    return o;
  }

  /// A solve's attempt in this object's trail (the context holds it already).
  void recordSolve(const Attempt& a) {
    trail_.push_back(a);
    ++solves_;
  }

  /// A structured start made to clear the cones: a start too close to a cone is replaced by the
  /// minimum-effort plan under the cones alone from it (coneClearStart), solved in `context`. A
  /// clearing whose iterate is already the same start (kSameStart) as a plan in `earlier` (what
  /// the earlier clearings at its T reached) ends there with that plan: its free-time solve would
  /// be a repeat of that plan's (sameStartAs), the rest of the clearing only the way there
  /// (measured, seed 4949's 20 cone requests: 70 of 137 clearings ended at such a plan, 1,919
  /// iterations). It is counted in `*work`.
  static std::vector<Matrix3> clearOfCones(const PlanningProblem& p, const FreeTimeStart& st,
                                           const std::vector<const std::vector<Matrix3>*>& earlier,
                                           SolveContext& context, ClearingWork* work) {
    if (coneClearance(p, st.attitudes) >= 0.5 * kConeStartClearance) return st.attitudes;
    int joined = -1;
    const auto joins = [&](const std::vector<Matrix3>& attitudes) -> std::string {
      joined = sameAttitudesIn(attitudes, earlier);
      return joined >= 0 ? "at a plan an earlier start's cone clearing reached" : std::string();
    };
    const std::optional<std::vector<Matrix3>> cleared =
        coneClearStart(p, st.attitudes, st.duration, context, joins);
    ++work->clearings;
    if (joined >= 0) ++work->joined;
    if (joined >= 0) return *earlier[joined];
    return cleared.value_or(st.attitudes);
  }

  /// The first of `plans` within kSameStart of `attitudes` (the same start), or −1.
  static int sameAttitudesIn(const std::vector<Matrix3>& attitudes,
                             const std::vector<const std::vector<Matrix3>*>& plans) {
    for (std::size_t j = 0; j < plans.size(); ++j) {
      if (plans[j]->size() == attitudes.size() &&
          largestDifference(attitudes, *plans[j]) <= kSameStart) {
        return static_cast<int>(j);
      }
    }
    return -1;
  }

  /// The earlier start whose solve this one would repeat (the same T and attitudes within
  /// kSameStart), or −1. Around a cone most starts clear it to the same minimum-effort plan
  /// (measured, scenes/min_time_keep_out.yaml N = 64: 18 starts, 8 distinct once cleared). A
  /// start that joined an earlier start's central path is one to repeat too: the solve from the
  /// same start at the same T on the grid's shared scale is its solve again, up to where it joined
  /// that path (measured, seed 4949's 20 cone requests: 29 such solves, 272 iterations, each
  /// joined where the start it repeated had). A repeat is never one: within kSameStart of a
  /// repeat is within 2 kSameStart of the start it repeats.
  int sameStartAs(const std::vector<Matrix3>& start, double duration) const {
    for (std::size_t j = 0; j < starts_.size(); ++j) {
      const StartRecord& earlier = starts_[j];
      if (earlier.from == OutcomeFrom::Repeat || earlier.duration != duration ||
          earlier.attitudes.size() != start.size()) {
        continue;
      }
      if (largestDifference(start, earlier.attitudes) <= kSameStart) return static_cast<int>(j);
    }
    return -1;
  }

  /// Records a start (its attitudes as solved, T, name) with the outcome of its own solve, for
  /// sameStartAs and the message.
  void recordStart(const std::vector<Matrix3>& start, double duration, const std::string& name,
                   FreeTimeOutcome outcome) {
    starts_.push_back({start,
                       duration,
                       name,
                       std::move(outcome),
                       OutcomeFrom::ItsSolve,
                       -1,
                       {},
                       trail_.size() - 1});
  }

  /// Records a start whose outcome is the earlier start's (a repeat, or a solve that joined its
  /// central path).
  void recordTaken(const std::vector<Matrix3>& start, double duration, const std::string& name,
                   int earlier, OutcomeFrom from) {
    const StartRecord& taken = starts_[earlier];
    starts_.push_back({start,
                       duration,
                       name,
                       taken.outcome,
                       from,
                       earlier,
                       {},
                       taken.attempt,
                       taken.cannot_end_below});
  }

  /// Runs every start on `grid` (a start that repeats an earlier one takes its outcome); returns
  /// the index of the converged one with the least T (−1: none converged). The starts are cleared
  /// of the cones, then solved in a sliding window (solveInWindow): a start repeats one recorded
  /// before it or one still being solved when it is posed.
  int solveStarts(const PlanningProblem& grid, const std::vector<FreeTimeStart>& starts) {
    const std::vector<std::vector<Matrix3>> cleared = clearedOfCones(grid, starts);
    if (!starts.empty()) shareScale(grid, cleared.front(), starts.front().duration);
    int best = -1;
    std::vector<int> repeats(starts.size(), -1);       // the start it repeats, by index in starts_
    std::vector<int> repeats_open(starts.size(), -1);  // ... or by index in `starts`
    std::vector<int> recorded_as(starts.size(), -1);   // each start's index in starts_
    std::vector<std::size_t> open;                     // the starts being solved, not yet recorded
    const auto pose = [&](int i) -> std::optional<WindowStart> {
      const FreeTimeStart& st = starts[i];
      repeats[i] = sameStartAs(cleared[i], st.duration);
      for (const std::size_t k : open) {
        if (repeats[i] < 0 && repeats_open[i] < 0 && starts[k].duration == st.duration &&
            largestDifference(cleared[k], cleared[i]) <= kSameStart) {
          repeats_open[i] = static_cast<int>(k);
        }
      }
      if (repeats[i] >= 0 || repeats_open[i] >= 0) return std::nullopt;
      open.push_back(i);
      return WindowStart{&cleared[i], st.duration, st.kind, clearedDetail(st, cleared[i])};
    };
    const auto record = [&](int i, std::optional<WatchedRun> run) {
      const FreeTimeStart& st = starts[i];
      if (run) {
        open.erase(std::find(open.begin(), open.end(), static_cast<std::size_t>(i)));
        recordWatched(std::move(*run), cleared[i], st.duration, st.name);
        keepIfLeast(&best);
      } else {
        const int same = repeats_open[i] >= 0 ? recorded_as[repeats_open[i]] : repeats[i];
        recordTaken(cleared[i], st.duration, st.name, same, OutcomeFrom::Repeat);
      }
      recorded_as[i] = static_cast<int>(starts_.size()) - 1;
    };
    solveInWindow(grid, static_cast<int>(starts.size()), &best, pose, record);
    return best;
  }

  /// Every start cleared of the cones (clearOfCones), in a sliding window of the request's
  /// threads (runSlidingWindow): a clearing may join the plans of the clearings ended before it
  /// began (on one thread every earlier one), the same ones on every run. They are counted
  /// in clearing_work_, their iterations in the context's tally (SolveContext::ClearingCones).
  std::vector<std::vector<Matrix3>> clearedOfCones(const PlanningProblem& grid,
                                                   const std::vector<FreeTimeStart>& starts) {
    const int count = static_cast<int>(starts.size());
    std::vector<std::vector<Matrix3>> cleared(count);
    std::vector<ClearingWork> work(count);
    std::vector<int> ended;  // the starts whose clearing ended, in order
    const auto begin = [&](int i) -> BranchWork {
      cleared[i] = starts[i].attitudes;
      if (context_.stopReason()) return {};
      std::vector<const std::vector<Matrix3>*> earlier;  // the plans earlier clearings reached
      for (const int k : ended) {
        if (starts[k].duration == starts[i].duration && cleared[k] != starts[k].attitudes) {
          earlier.push_back(&cleared[k]);
        }
      }
      return [&, i, earlier = std::move(earlier)](SolveContext& branch) {
        if (branch.stopReason()) return;
        cleared[i] = clearOfCones(grid, starts[i], earlier, branch, &work[i]);
      };
    };
    const SolveContext::ClearingCones counted(context_);  // the branches join their iterations
    runSlidingWindow(context_, count, begin, [&](int i) {
      ended.push_back(i);
      clearing_work_.add(work[i]);
    });
    return cleared;
  }

  /// The scale every watched solve on `grid` shares from now on: the first start's (T and effort
  /// before any raise; FreeTimeScale). Measured on the seeded minimum-time suite without cones: on
  /// their own scales the excursions that fall into the eigenaxis start's basin ran to its KKT
  /// point (seed 4949 #6: 233 and 242 iterations each); on one scale the watch sees them join
  /// its central path within 5-14 (docs/results/minimum_time_shared_scale.md).
  void shareScale(const PlanningProblem& grid, const std::vector<Matrix3>& start, double duration) {
    shared_scale_ = freeTimeScaleOf(grid, start, duration);
    shared_scale_steps_ = grid.steps;
  }

  /// The scale of the watched solves on `grid` (unset on a grid no starts were solved on).
  FreeTimeScale scaleOn(const PlanningProblem& grid) const {
    return grid.steps == shared_scale_steps_ ? shared_scale_ : FreeTimeScale{};
  }

  /// A start solveInWindow solves: its attitudes (alive until it is recorded), T and parameters.
  struct WindowStart {
    const std::vector<Matrix3>* attitudes = nullptr;
    double duration = 0.0;
    AttemptStart kind = AttemptStart::EigenaxisSlew;
    StartDetail detail;
  };

  /// Solves `count` starts in a sliding window of the request's threads (runSlidingWindow): start
  /// i is posed (pose(i), on this thread: the start to solve, or nothing where it repeats an
  /// earlier one) once the starts before it leave a place free, solved in a branch watched
  /// against the starts recorded by then and the least T among them (`*best`), and recorded
  /// (record(i, its run or nothing), on this thread) in the order of i. On one thread each start
  /// sees every start before it; on more, start i sees those up to i − threads at least, the
  /// same ones on every run. Nothing is posed once the request must stop.
  void solveInWindow(const PlanningProblem& grid, int count, const int* best,
                     const std::function<std::optional<WindowStart>(int)>& pose,
                     const std::function<void(int, std::optional<WatchedRun>)>& record) {
    std::vector<std::optional<WatchedRun>> runs(count);
    std::vector<char> posed(count, 0);
    const auto begin = [&](int i) -> BranchWork {
      if (context_.stopReason()) return {};
      posed[i] = 1;
      const std::optional<WindowStart> start = pose(i);
      if (!start) return {};
      return [this, &grid, &runs, i, start = *start,
              seen = recordedSoFar(*best)](SolveContext& branch) {
        runs[i] = solveWatchedIn(branch, grid, *start.attitudes, start.duration, start.kind,
                                 start.detail, seen);
      };
    };
    runSlidingWindow(context_, count, begin, [&](int i) {
      if (posed[i]) record(i, std::move(runs[i]));
    });
  }

  static StartDetail clearedDetail(const FreeTimeStart& st, const std::vector<Matrix3>& cleared) {
    StartDetail detail = st.detail;
    detail.cleared_of_cones = cleared != st.attitudes;
    return detail;
  }

  /// Spinning ends: every start (those recorded from `first` on, one per entry of `starts`) solved
  /// once more with its elastic phase begun at a barrier on the scale of its violations
  /// (ElasticBarrier::FromViolations). From one start the two solves reach different KKT points
  /// and neither is always the lower (measured on the seed-45 spinning suite: #173 9.94 s at μ₀,
  /// 6.10 s from its violations; #76 19.84 s against 25.05 s), so both are starts. A start
  /// without an elastic phase solves the same problem again: the watch stops it on the first
  /// start's central path. A start whose first solve joined another's central path is solved
  /// again too: its elastic phase from its own violations is another solve, whose end the join
  /// says nothing of (measured on the seed-45 spinning suite's #45: its coasting start joined the
  /// eigenaxis start's path at μ = 2.2e-5 on the shared scale, T 0.678182 against 0.678192 s, and
  /// from its violations ends at 0.65754 s on N = 64, the basin of T* = 0.653 s; skipped as a
  /// repeat, the answer was 0.6661 s). So this round poses the starts it would pose without the
  /// join. Returns the least converged start.
  int solveFromViolations(const PlanningProblem& grid, const std::vector<FreeTimeStart>& starts,
                          std::size_t first, int best) {
    std::vector<std::size_t> solved;  // the starts solved the first time (not repeats of a start)
    for (std::size_t i = 0; i < starts.size() && first + i < starts_.size(); ++i) {
      const StartRecord& once = starts_[first + i];
      if (once.from != OutcomeFrom::Repeat) solved.push_back(i);
    }
    const auto pose = [&](int j) -> std::optional<WindowStart> {
      const std::size_t i = solved[j];
      const StartRecord& once = starts_[first + i];
      return WindowStart{&once.attitudes, starts[i].duration, starts[i].kind,
                         fromViolationsDetail(starts[i], once)};
    };
    const auto record = [&](int j, std::optional<WatchedRun> run) {
      const std::size_t i = solved[j];
      recordWatched(std::move(*run), starts_[first + i].attitudes, starts[i].duration,
                    starts[i].name + ", its elastic phase from its violations");
      keepIfLeast(&best);
    };
    solveInWindow(grid, static_cast<int>(solved.size()), &best, pose, record);
    return best;
  }

  static StartDetail fromViolationsDetail(const FreeTimeStart& st, const StartRecord& solved) {
    StartDetail detail = clearedDetail(st, solved.attitudes);
    detail.elastic_from_violations = true;
    return detail;
  }

  /// The last recorded start kept (best, best_attempt_) if it converged below the best's T.
  void keepIfLeast(int* best) {
    const FreeTimeOutcome& o = starts_.back().outcome;
    if (o.termination == Termination::Converged &&
        (*best < 0 || o.duration < starts_[*best].outcome.duration)) {
      *best = static_cast<int>(starts_.size()) - 1;
      best_attempt_ = trail_.size() - 1;
    }
  }

  /// One start's free-time solve on `grid`, watched (BarrierWatch): stopped where it can no
  /// longer end below the least T so far (`best`'s; its lower bound above it at a locally convex
  /// barrier point, where the bound holds), or where it joins
  /// the central path of an earlier start on the grid (sameCentralPath: that start's end is its
  /// end, taken as its outcome). Recorded as a start.
  void solveWatched(const PlanningProblem& grid, const std::vector<Matrix3>& start, double duration,
                    AttemptStart kind, const StartDetail& detail, const std::string& name,
                    int best) {
    recordWatched(
        solveWatchedIn(context_, grid, start, duration, kind, detail, recordedSoFar(best)), start,
        duration, name);
  }

  /// The starts recorded so far and the least T among the converged ones (`best`'s).
  Recorded recordedSoFar(int best) const {
    Recorded seen;
    for (const StartRecord& st : starts_) seen.starts.push_back(&st);
    if (best >= 0) seen.least_duration = starts_[best].outcome.duration;
    return seen;
  }

  /// solveWatched's solve in `context` (the request's or a branch), watched against `seen`.
  WatchedRun solveWatchedIn(SolveContext& context, const PlanningProblem& grid,
                            const std::vector<Matrix3>& start, double duration, AttemptStart kind,
                            const StartDetail& detail, const Recorded& seen) const {
    const double least = seen.least_duration;
    WatchedRun run;
    const BarrierWatch watch = [&](const BarrierPoint& point) -> std::string {
      const std::string above = cannotEndBelow(point.bound(), least, "the least T [s] so far");
      if (!above.empty()) {
        run.cannot_end_below = point.lower_bound;
        return above;
      }
      run.joined = sameCentralPath(point, seen.starts, least);
      if (run.joined >= 0) {
        const StartRecord& joined = *seen.starts[run.joined];
        std::ostringstream why;
        why << "stopped at T = " << point.duration << " s: on the central path of the start "
            << joined.name << " (the same barrier problem's point, mu = " << point.mu << ")";
        if (joined.outcome.termination != Termination::Converged) {
          why << ", which cannot end below the least T so far, " << least
              << " s (its local lower bound " << joined.cannot_end_below << ")";
        }
        return why.str();
      }
      run.path.push_back(point);
      return "";
    };
    run.outcome = solveIn(context, grid, start, duration, kind, detail, watch,
                          StartBarrier::Initial, &run.attempt, scaleOn(grid));
    return run;
  }

  /// A watched solve's attempt and start recorded (a joined one takes the earlier start's
  /// outcome).
  void recordWatched(WatchedRun run, const std::vector<Matrix3>& start, double duration,
                     const std::string& name) {
    recordSolve(run.attempt);
    if (run.joined >= 0) {
      recordTaken(start, duration, name, run.joined, OutcomeFrom::Joined);
    } else {
      recordStart(start, duration, name, std::move(run.outcome));
      starts_.back().cannot_end_below = run.cannot_end_below;
    }
    starts_.back().path = std::move(run.path);
  }

  /// The earlier start whose solve passed through `point` (the same μ, every attitude within
  /// kSamePath) and whose end is known (pathEndKnown against `least`), or −1: one barrier
  /// problem's local solution is one point of one central path, so the two solves go on to the
  /// same end.
  static int sameCentralPath(const BarrierPoint& point, const std::vector<const StartRecord*>& seen,
                             double least) {
    int closest = -1;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < seen.size(); ++j) {
      if (!pathEndKnown(*seen[j], least)) continue;
      for (const BarrierPoint& q : seen[j]->path) {
        if (q.mu != point.mu || q.attitudes.size() != point.attitudes.size()) continue;
        const double difference = largestDifference(q.attitudes, point.attitudes);
        if (difference < nearest) {
          nearest = difference;
          closest = static_cast<int>(j);
        }
      }
    }
    return nearest <= kSamePath ? closest : -1;
  }

  /// Whether a solve that joins start `st`'s central path knows its end: the KKT point where `st`
  /// converged, or that it cannot end below `least`, where `st`'s watch stopped it at a locally
  /// convex barrier point whose lower bound, which holds there, lies above `least`
  /// (cannotEndBelowLeast, the one rule, tested against the least T held now). Safe because a
  /// watch stops only a start whose bound holds: the joining solve follows `st`'s central path
  /// from the join on, so its basin is `st`'s, and it would pass that same point and be stopped by
  /// that same bound; it is stopped at the join instead (measured,
  /// seed 4949's 20 cone requests: 32 solves reached such a path at their first barrier problem
  /// and ran 211 iterations more to the bound). A path that ended otherwise (the iteration limit,
  /// no descent step) is not followed to its end by joining it: its end is not known.
  static bool pathEndKnown(const StartRecord& st, double least) {
    if (st.outcome.termination == Termination::Converged) return true;
    return cannotEndBelowLeast({st.outcome.duration, st.cannot_end_below, true}, least);
  }

  /// A request below the start grid, with cones: the structured starts and their saddles solved
  /// on kFreeTimeStartGrid too, and that answer restricted to `grid` (every (kFreeTimeStartGrid /
  /// N)th node, turned out of the cones where it dips in) one more free-time solve on `grid` at
  /// its T. Measured on scenes/min_time_keep_out.yaml N = 32: the starts and saddles of N = 32
  /// end at 28.9937 s at best, the restricted N = 64 answer (28.7743 s) at 28.7643 s, below the
  /// search's 28.9825 s (T*(N) rises with N: 28.7643, 28.7743, 28.7807 at 32, 64, 128). Returns
  /// the least converged start on `grid` (best: the least so far, −1: none).
  int fromStartGrid(const PlanningProblem& grid, bool rest_to_rest, int best) {
    PlanningProblem fine = grid;
    fine.steps = kFreeTimeStartGrid;
    std::vector<FreeTimeStart> starts = freeTimeStarts(fine, rest_to_rest, context_);
    for (FreeTimeStart& st : starts) st.name = "N = " + std::to_string(fine.steps) + " " + st.name;
    const std::size_t kept_attempt = best_attempt_;
    const std::size_t first = starts_.size();
    int fine_best = solveStarts(fine, starts);
    if (fine_best >= 0) fine_best = leaveSaddles(fine, fine_best, first);
    best_attempt_ = kept_attempt;
    if (fine_best < 0 || fine.steps % grid.steps != 0) return best;
    const StartRecord& answer = starts_[fine_best];
    const int ratio = fine.steps / grid.steps;
    std::vector<Matrix3> start;
    for (int k = 0; k <= grid.steps; ++k)
      start.push_back(answer.outcome.maneuver.attitude[k * ratio]);
    if (coneClearance(grid, start) < 0.5 * kConeStartClearance) {
      start = pushedOutOfCones(grid, start, kConeStartClearance);
    }
    const double T = answer.outcome.duration;
    StartDetail detail;
    detail.duration = T;
    FreeTimeOutcome o = solve(grid, start, T, AttemptStart::PreviousAttempt, detail);
    recordStart(start, T, "restricted (" + answer.name + ")", std::move(o));
    keepIfLeast(&best);
    return best;
  }

  /// Every distinct saddle the starts on `grid` reached (those recorded from `first` on) (a
  /// converged KKT point that is not second-order sufficient, FreeTimeOutcome; saddles at the same
  /// T within kSameSaddle taken as one) left along its negative-curvature direction (leaveSaddle).
  /// Returns the least converged start. Measured on scenes/min_time_keep_out.yaml N = 64: the
  /// structured starts are symmetric in time and so are the KKT points most of them reach, saddles
  /// at 29.0081 s and 30.8839 s; the least answer among them, 29.0078 s, is a local minimum on the
  /// far side of the cone's passage; the eigenaxis saddle left either way descends to 28.7743 s (a
  /// time-asymmetric passage).
  int leaveSaddles(const PlanningProblem& grid, int best, std::size_t first) {
    std::vector<double> left;  // the T of the saddles left
    const std::size_t structured = starts_.size();
    for (std::size_t i = first; i < structured; ++i) {
      const FreeTimeOutcome& o = starts_[i].outcome;
      if (starts_[i].tookEarlierOutcome() || o.termination != Termination::Converged ||
          o.second_order_sufficient) {
        continue;
      }
      const bool seen = std::any_of(left.begin(), left.end(), [&](double T) {
        return std::abs(T - o.duration) <= kSameSaddle * o.duration;
      });
      if (seen) continue;
      left.push_back(o.duration);
      best = leaveSaddle(grid, static_cast<int>(i), best);
    }
    return best;
  }

  /// One free-time solve from the saddle `from` displaced along its negative-curvature direction
  /// by ±kSaddleEscape (turned out of the cones where it dips in), at its T; if the lower of the
  /// two is a saddle again, the same from there (at most kMaxSaddleEscapes). Returns the least
  /// converged start so far.
  int leaveSaddle(const PlanningProblem& grid, int from, int best) {
    for (int escape = 0; escape < kMaxSaddleEscapes; ++escape) {
      const StartRecord saddle = starts_[from];
      int lower = -1;
      for (const double sign : {1.0, -1.0}) {
        if (context_.stopReason()) return best;
        std::vector<Matrix3> start =
            displacedAlongNegativeCurvature(grid, saddle.outcome, sign * kSaddleEscape);
        if (start.empty()) continue;
        if (coneClearance(grid, start) < 0.5 * kConeStartClearance) {
          start = pushedOutOfCones(grid, start, kConeStartClearance);
        }
        StartDetail detail;
        detail.duration = saddle.outcome.duration;
        solveWatched(grid, start, saddle.outcome.duration, AttemptStart::PreviousAttempt, detail,
                     std::string(sign > 0 ? "+" : "-") + "off the saddle of " + saddle.name, best);
        keepIfLeast(&best);
        const FreeTimeOutcome& got = starts_.back().outcome;
        if (got.termination == Termination::Converged &&
            got.duration < saddle.outcome.duration * (1 - kSameSaddle) &&
            (lower < 0 || got.duration < starts_[lower].outcome.duration)) {
          lower = static_cast<int>(starts_.size()) - 1;
        }
      }
      if (lower < 0 || starts_[lower].outcome.second_order_sufficient) break;
      from = lower;
    }
    return best;
  }

  /// The starts whose coarse answers are refined: the least converged and, with spinning ends,
  /// the least converged of the other elastic barrier (solveFromViolations) where its T differs:
  /// the coarse grid need not order two basins as the requested grid does (measured: #45 of the
  /// seed-45 spinning suite, 0.6661 s refined from the lesser coarse answer, 0.653 s from the
  /// other barrier's).
  std::vector<int> refinementCandidates(int best, bool rest_to_rest) const {
    std::vector<int> candidates{best};
    if (rest_to_rest) return candidates;
    const auto fromViolations = [&](int i) {
      return trail_[starts_[i].attempt].start_detail.elastic_from_violations;
    };
    int other = -1;
    for (int i = 0; i < static_cast<int>(starts_.size()); ++i) {
      const FreeTimeOutcome& o = starts_[i].outcome;
      if (o.termination != Termination::Converged || fromViolations(i) == fromViolations(best)) {
        continue;
      }
      if (other < 0 || o.duration < starts_[other].outcome.duration) other = i;
    }
    const double T = starts_[best].outcome.duration;
    if (other >= 0 && starts_[other].outcome.duration > T * (1 + kSameSaddle)) {
      candidates.push_back(other);
    }
    return candidates;
  }

  /// Each candidate's coarse answer refined (refine); the least T* on the requested grid is the
  /// answer. Empty if none refined.
  std::optional<PlanResult> refineLeast(const std::vector<PlanningProblem>& levels,
                                        const std::vector<int>& candidates) {
    std::optional<RefinedOutcome> least;
    std::string name;
    std::vector<LevelSummary> least_levels;
    for (const int c : candidates) {
      if (least && context_.stopReason()) break;
      best_attempt_ = starts_[c].attempt;
      levels_ = levelResult(levels.front().steps, starts_[c].outcome).levels;
      std::optional<RefinedOutcome> refined = refine(levels, starts_[c].outcome);
      if (!refined || (least && refined->outcome.duration >= least->outcome.duration)) continue;
      least = std::move(refined);
      name = starts_[c].name;
      least_levels = levels_;
    }
    if (!least) return std::nullopt;
    best_attempt_ = least->attempt;
    levels_ = least_levels;
    return answerAt(least->outcome, "coarse grid (N = " + std::to_string(levels.front().steps) +
                                        ", " + name + "), refined by 2 at a time");
  }

  /// The coarsest level's best answer carried through the finer `levels` (the grid continuation
  /// resumed from it): each level one free-time solve from the coarser answer prolonged, at its
  /// T, with its attempt in the trail. Empty if the solve is stopped (cancel, deadline) or a
  /// level does not converge, but for the requested grid's ending short inside its bounds
  /// (endedShortInside, after its resume): that plan is returned, not a KKT point.
  std::optional<RefinedOutcome> refine(const std::vector<PlanningProblem>& levels,
                                       const FreeTimeOutcome& coarsest) {
    std::optional<RefinedOutcome> finest;
    const Attempt origin = trail_[best_attempt_];  // the coarsest level's kept solve
    const LevelSolver<FreeTimeCarry> level = [&](const LevelRequest<FreeTimeCarry>& r,
                                                 FreeTimeCarry* handed_on) {
      if (r.replay_only || !r.coarse) {  // stopped: no answer on this level
        PlanResult stopped;
        stopped.termination = r.stop ? r.stop->termination : Termination::NotConverged;
        return stopped;
      }
      const FreeTimeOutcome& coarse = r.coarse->outcome;
      StartDetail detail = origin.start_detail;
      detail.duration = coarse.duration;
      detail.coarse_steps = coarse.maneuver.steps();
      detail.origin = originOf(origin);
      // A level's start is the coarser answer prolonged, a little outside its bounds at most: its
      // elastic phase begins at μ₀ whichever barrier the coarse start's began at (measured: #45
      // of the seed-45 spinning suite refined from its violations to a saddle at 0.6661 s, at μ₀
      // to a local minimum at 0.6530 s from the same coarse answer).
      detail.elastic_from_violations = false;
      RefinedOutcome o;
      o.outcome = solve(r.problem, prolonged(r.problem, coarse), coarse.duration,
                        AttemptStart::CoarseLevel, detail);
      o.attempt = trail_.size() - 1;
      if (endedShortInside(o.outcome)) o = resumed(r.problem, std::move(o), detail);
      PlanResult result = levelResult(r.problem.steps, o.outcome);
      if (handed_on) {
        handed_on->outcome = std::move(o.outcome);
      } else {
        finest = std::move(o);
      }
      return result;
    };
    // answerAt writes the message from the whole trail; the levels keep their own.
    const ContinuationFinish finish = [](const ContinuationRecord&, PlanResult*) {};
    const SolvedLevel<FreeTimeCarry> from{0, Termination::Converged, {coarsest}, {}, false};
    const PlanResult result = resumeGridContinuation(levels, from, context_, freeTimeGridRule(),
                                                     kFreeTimeTolerance, level, finish);
    if (!finest) return std::nullopt;
    // The requested grid's level ended short of its KKT point inside every bound, resumed too: its
    // iterate is still a plan at its own T, an upper bound on T* (answerAt says so). Discarded,
    // the search from scratch answered a worse bound (measured: a seeded slew around a cone,
    // 13.5065 s after 24,000 iterations against the plan's 13.4896 s, T* reached to 1e-13).
    if (!result.converged() && !endedShortInside(finest->outcome)) return std::nullopt;
    levels_.insert(levels_.end(), result.levels.begin(), result.levels.end());
    return finest;
  }

  /// A solve that ended short of its KKT point (not stopped by the watch, the budget or a cancel)
  /// at an iterate strictly inside every bound: a plan at its own T, near the KKT point where the
  /// line search found no descent step at the round-off floor's edge.
  bool endedShortInside(const FreeTimeOutcome& o) const {
    return o.termination == Termination::NotConverged && !o.stopped_by_watch &&
           o.smallest_value > 0 && !o.maneuver.attitude.empty() && !context_.stopReason();
  }

  /// One more free-time solve from a level's plan that ended short (endedShortInside), at its T,
  /// its barrier begun near the KKT point (StartBarrier::NearKktPoint); the earlier outcome where
  /// it does not converge. Measured on a seeded rest-to-rest slew (N = 128): the refined level
  /// stopped at T* to 5e-12 with stationarity 1.6e-7 (the floor 1e-7), the search then took 8,000
  /// iterations to the same T*; resumed, it converges in 40.
  RefinedOutcome resumed(const PlanningProblem& p, RefinedOutcome ended, StartDetail detail) {
    detail.duration = ended.outcome.duration;
    FreeTimeOutcome o =
        solve(p, ended.outcome.maneuver.attitude, ended.outcome.duration,
              AttemptStart::PreviousAttempt, detail, {}, StartBarrier::NearKktPoint);
    if (o.termination != Termination::Converged) return ended;
    return {std::move(o), trail_.size() - 1};
  }

  /// The answer: the free-time plan at T* itself, measured as every plan is (freeTimePlan), its
  /// switching functions from the solve's own bound multipliers. A KKT point where the solve
  /// converged; else (refine: ended short inside every bound) a plan at its T, an upper bound. No
  /// minimum-effort solve at T* follows: at T* the feasible set is that one plan to the tolerance,
  /// so such a solve is degenerate and ends where it starts (measured: 40–150 interior-point
  /// iterations at N = 128 for the same plan, more than every start together around a cone).
  PlanResult answerAt(const FreeTimeOutcome& answer, const std::string& from) {
    PlanningProblem at = endingAt(problem_, answer.maneuver.attitude.back());
    at.objective = Objective::MinimumEffort;
    at.time_margin = 0.0;
    at.duration = answer.duration;
    PlanResult result = freeTimePlan(at, answer);
    if (!trail_.empty()) trail_[best_attempt_].kept = true;
    if (!trail_.empty()) context_.markKept(first_recorded_ + best_attempt_);
    const bool kkt_point = answer.termination == Termination::Converged;
    const bool second_order_sufficient = kkt_point && answer.second_order_sufficient;
    verdicts::MinimumTimeAnswer told{
        answer.duration,     kkt_point,       second_order_sufficient, from, answer.iterations,
        answer.stationarity, answer.time_row, answer.complementarity,  {},   solves_};
    for (const StartRecord& st : starts_) {
      told.starts.push_back(
          {st.name, st.tookEarlierOutcome() ? starts_[st.earlier].name : std::string(),
           st.outcome.termination, st.outcome.duration, st.outcome.second_order_sufficient});
    }
    // A replay that failed (freeTimePlan) is the reason it is given, said after its account.
    recordVerdict(&result, told);
    result.minimum_duration = answer.duration;
    result.minimum_time.kkt_point = kkt_point;
    result.minimum_time.stationarity = answer.stationarity;
    result.minimum_time.time_stationarity = answer.time_row;
    result.minimum_time.complementarity = answer.complementarity;
    result.minimum_time.solves = solves_;
    result.minimum_time.second_order_sufficient = second_order_sufficient;
    result.minimum_time.cone_clearings = clearing_work_.clearings;
    result.minimum_time.cone_clearings_joined = clearing_work_.joined;
    recordTwist(at, answer, &result);
    result.attempts = context_.attemptsFrom(first_recorded_);
    result.levels = levels_;
    return result;
  }

  /// A pointing answer's twist, end-condition residual and stationarity in ψ (∂L/∂ψ of the
  /// minimum-time Lagrangian, relative to T₀ as the other residuals).
  static void recordTwist(const PlanningProblem& at, const FreeTimeOutcome& answer,
                          PlanResult* result) {
    if (!at.end_condition.pointing()) return;
    summarizePointingEnd(answer.maneuver.attitude.back(), at.end_condition, &result->pointing);
    result->pointing.twist_gradient = answer.twist_gradient;
    result->pointing.twist_stationarity = std::abs(answer.twist_gradient);
  }

  /// The free-time plan as the answer (at T*, measured as every plan is: evaluatePlan, the
  /// replay, the constraint figures).
  static PlanResult freeTimePlan(const PlanningProblem& effort, const FreeTimeOutcome& answer) {
    PlanResult r;
    r.solver = "interior_point";
    r.termination = Termination::Converged;
    r.iterations = answer.iterations;
    r.switching_function = answer.switching_function;
    evaluatePlan(effort, answer.maneuver.torque, &r, &answer.maneuver);
    try {
      replayFigures(effort, &r);
    } catch (const StepTooLarge& e) {
      r.termination = Termination::StepTooLarge;
      recordReason(&r, std::string("replay of the planned torques failed: ") + e.what());
    }
    recordConstraintFigures(effort, &r);
    return r;
  }

  const PlanningProblem& problem_;
  SolveContext& context_;
  std::size_t first_recorded_;  ///< where its solves begin in the context's trail
  /// Every start solved (or repeated), in order; a deque, so that a record stays where it is
  /// while later ones are recorded (solves on other threads read the earlier ones: Recorded).
  std::deque<StartRecord> starts_;
  std::vector<LevelSummary> levels_;  ///< the kept start's level and each refined level
  std::vector<Attempt> trail_;
  std::size_t best_attempt_ = 0;
  int solves_ = 0;
  ClearingWork clearing_work_;   ///< the cone clearings of every start (clearedOfCones)
  FreeTimeScale shared_scale_;   ///< the watched solves' scale on the starts' grid (shareScale)
  int shared_scale_steps_ = -1;  ///< that grid's N
};

}  // namespace

std::vector<Matrix3> displacedAlongNegativeCurvature(const PlanningProblem& problem,
                                                     const FreeTimeOutcome& outcome, double size) {
  if (outcome.negative_curvature.size() == 0) return {};
  PlanningProblem at = endingAt(problem, outcome.maneuver.attitude.back());
  at.duration = outcome.duration;
  ReducedProblem np(at);
  np.setCurrent(outcome.steps);
  if (np.unknowns() != outcome.negative_curvature.size()) return {};
  return np.attitudes(np.retract(outcome.negative_curvature, size));
}

std::vector<Matrix3> prolonged(const PlanningProblem& p, const FreeTimeOutcome& coarse) {
  PlanningProblem at = endingAt(p, coarse.maneuver.attitude.back());
  at.duration = coarse.duration;
  std::vector<Matrix3> attitudes;
  try {
    ReducedProblem np(at);
    np.initializeFromCoarser(coarse.steps);
    attitudes = np.attitudes(np.current());
  } catch (const StepTooLarge&) {  // the boundary rates admit no step at this h
    attitudes = resampleAttitudes(coarse.maneuver, p.steps);
  }
  return pushedOutOfCones(p, attitudes, kNeighbourConeClearance);
}

GridLevelRule freeTimeGridRule() {
  GridLevelRule rule;
  rule.coarsest_steps = kFreeTimeStartGrid;
  rule.coarsening_factor = 2;
  rule.direct_up_to = 2 * kFreeTimeStartGrid - 1;
  rule.coarse_tolerance_floor = 0.0;
  rule.unconverged_ends = true;
  return rule;
}

std::vector<PlanningProblem> freeTimeLevels(const PlanningProblem& problem) {
  std::vector<PlanningProblem> levels = gridLevels(problem, freeTimeGridRule());
  const double least = durationLowerBound(problem).seconds;
  while (levels.size() > 1 && representableDuration(levels.front()) < least) {
    levels.erase(levels.begin());
  }
  return levels;
}

std::optional<PlanResult> freeTimeMinimumTime(const PlanningProblem& problem,
                                              SolveContext& context) {
  return FreeTimeMinimumTime(problem, context).run();
}

std::optional<PlanResult> freeTimeFromPlan(const PlanningProblem& problem, const Maneuver& plan,
                                           double duration, const std::string& start,
                                           SolveContext& context, std::optional<Maneuver>* below,
                                           StartBarrier barrier, const BarrierWatch& watch) {
  return FreeTimeMinimumTime(problem, context)
      .runFrom(plan, duration, start, below, barrier, watch);
}

}  // namespace attitude_planner
