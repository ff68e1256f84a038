#include "planning/drivers/minimum_time_search.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "planning/drivers/bounded_verdicts.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"

namespace attitude_planner {

namespace {

/// Each step of the downward continuation in T shortens it by 5 %.
constexpr double kContinuationFactor = 0.95;
/// The largest angles of the search's excursion starts off the eigenaxis [rad], and their first
/// T relative to the eigenaxis slew's least T.
constexpr double kExcursionAngles[] = {0.3, 0.8};
constexpr double kExcursionStartFactors[] = {1.04, 0.96};
/// A search doubles its first T at most this many times looking for a feasible one.
constexpr int kMaxDoublings = 12;
/// Where doubling reaches the durations the grid cannot hold before any T is found feasible, the
/// search goes below its first T by this factor, at most kMaxShortenings times and never below
/// the proven least duration, then by a finer spread where the floor is near (shortened). Why: with
/// spinning ends the first T sits at the grid's largest boundary step (eigenaxisDurationGuess),
/// where a cold minimum-effort solve fails locally while plans exist well below it (measured on the
/// seed-45 spinning suite: five requests answered "no plan found below" their first T, with
/// minimum-effort plans converged at 0.3-0.5 of it).
constexpr double kShorteningFactor = 0.7;
constexpr int kMaxShortenings = 6;
/// Grids above this N search from the T* plan of the grid with half the steps.
constexpr int kCoarsestSearchGrid = 64;
/// That search's first T, relative to the coarse grid's T*.
constexpr double kCoarseStartFactor = 1.01;

/// One search on T from one start.
struct SearchOutcome {
  explicit SearchOutcome(const SolveContext& context) : tally(context) {}
  std::string start;                          ///< which start
  AttemptStart kind = AttemptStart::Hermite;  ///< its kind (the trail's `start`)
  StartDetail detail;                         ///< its parameters (the trail's start_detail)
  PlanResult best;                            ///< the plan at the least feasible T (if feasible)
  bool feasible = false;                      ///< some T was found feasible
  double T_lo = 0.0;                          ///< the bracket [T_lo infeasible, T_hi feasible]
  double T_hi = 0.0;
  int solves = 0;
  /// The iterations of all its solves: counting while it searches down, then while its bracket
  /// is bisected (paused in between: the other starts' searches run there).
  SolveContext::IterationTally tally;
};

/// The search for T*: several starts, each a continuation downwards in T over minimum-effort
/// solves warm-started from the last feasible plan, and a bisection of the best bracket.
class MinimumTimeSearch {
 public:
  /// `allowance`: the work the search may spend, shared with the search on a coarser grid that
  /// starts it (searchFromCoarseGrid).
  MinimumTimeSearch(const PlanningProblem& problem, SolveContext& context,
                    const SolveContext::WorkAllowance& allowance)
      : problem_(problem),
        context_(context),
        allowance_(allowance),
        no_room_(noRoomBeforeTheEnd(problem)) {
    effort_ = problem;
    effort_.objective = Objective::MinimumEffort;
    effort_.time_margin = 0.0;
  }

  /// The plan at the least feasible T found (minimum_duration = T*), or why there is none.
  PlanResult run() {
    const double guess =
        problem_.duration > 0 ? problem_.duration : eigenaxisDurationGuess(problem_);
    SearchOutcome* found = nullptr;
    {
      // The probes' own attempts are parts of the search's: it records one per start (below).
      const SolveContext::Aside probes(context_);
      searchFromCoarseGrid();
      const bool searched_coarse = !outcomes_.empty() && outcomes_.back().feasible;
      if (!searched_coarse) {
        outcomes_.push_back(search("continuation", nullptr, guess));
        outcomes_.back().detail.duration = guess;
      }
      if (!searched_coarse && isRestToRest()) searchStructuredStarts();
      found = leastFeasible();
      if (found) bisect(found);
    }
    for (const SearchOutcome& o : outcomes_) solves_ += o.solves;
    const std::size_t first = context_.attempts().size();
    for (const Attempt& a : trail()) context_.record(a);
    if (!found) return noneFeasible(guess, first);
    context_.markKept(first + static_cast<std::size_t>(found - outcomes_.data()));
    return atMinimumTime(*found, first);
  }

 private:
  /// One minimum-effort solve at T from `warm`: true, with the plan kept in `out`, if it proves
  /// T feasible (provesFeasible).
  bool tryDuration(double T, const Maneuver* warm, SearchOutcome* out) {
    // No plan exists there on this grid (the last step into the final rate has no room under the
    // rate limit, proven): no solve.
    if (T >= no_room_.from && T <= no_room_.to) return false;
    if (allowance_.exhausted()) return false;
    effort_.duration = T;
    const SolveContext::Scope scope(context_, AttemptStage::MinimumTimeProbe,
                                    homotopyClassOf(effort_));
    SolveRequest o(context_.options());
    if (warm) {
      o.warm_start = warm;
      o.start.from_constrained_plan = true;
    }
    PlanResult r;
    try {
      r = planAtResolution(effort_, o, context_);
    } catch (const StepTooLarge&) {  // no boundary step on this grid at T: nothing shown at T
      ++out->solves;
      unrepresentable_from_ = std::min(unrepresentable_from_, T);
      return false;
    }
    ++out->solves;
    least_tried_ = std::min(least_tried_, T);
    if (stoppedByRequest(r.termination)) {
      stopped_ = r.termination;
    }
    if (!provesFeasible(effort_, r)) return false;
    out->best = std::move(r);
    out->feasible = true;
    return true;
  }

  bool stopped() const { return stopped_.has_value() || allowance_.exhausted(); }

  /// One search from one start: `from` (attitudes, any T) starts the first solve at T_first;
  /// null: the minimum-effort problem's own start (its unconstrained optimum). Each later solve
  /// starts from the last feasible plan (same N).
  SearchOutcome search(const std::string& name, const Maneuver* from, double T_first) {
    SearchOutcome out(context_);
    out.start = name;
    descend(from, T_first, &out);
    out.tally.pause();
    return out;
  }

  /// The search of `search`: doubling T from T_first until feasible, then down from there.
  void descend(const Maneuver* from, double T_first, SearchOutcome* found) {
    SearchOutcome& out = *found;
    const auto feasible = [&](double T) {
      return tryDuration(T, out.feasible ? &out.best.maneuver : from, &out);
    };
    double T = T_first;
    for (int doublings = 0; !feasible(T) && !stopped() && T < unrepresentable_from_; T *= 2.0) {
      if (++doublings > kMaxDoublings) return;
    }
    if (!out.feasible && T >= unrepresentable_from_) T = shortened(T_first, feasible);
    if (!out.feasible && T_first < unrepresentable_from_) T = betweenDoublings(T_first, feasible);
    if (!out.feasible) return;
    // Down from the first feasible T in small steps, each warm-started from the last feasible
    // plan: a large step leaves the interior point far outside the bounds (torques grow like
    // 1/T²), where it can stop at a local minimum of the violation.
    out.T_hi = T;
    out.T_lo = T * kContinuationFactor;
    while (!stopped() && feasible(out.T_lo)) {
      out.T_hi = out.T_lo;
      out.T_lo *= kContinuationFactor;
    }
  }

  /// Below T_first, cold, until `feasible` holds: the T where it did, or 0. First
  /// kShorteningFactor^j of T_first (j = 1 … kMaxShortenings, above the proven floor); where those
  /// found nothing, kMaxShortenings durations spread evenly in log T between T_first and the floor,
  /// where that spread is finer than kShorteningFactor. Where the floor is near T_first the factor
  /// steps over the durations at which a plan converges (feasibility in T is patchy with spinning
  /// ends: measured on #108 of the seed-45 spinning suite, first T 12.58 s, floor 6.31 s: cold
  /// minimum-effort plans at 11, 11.4 and 12 s, none at 8.8, 9, 10, 12.58 and 14 s; 0.7 tried only
  /// 8.8 s). The spread comes second: first on the seed-45 suite it found #77's first plan at
  /// another T, from which the descent ended at 5.738 s instead of 5.182 s.
  template <typename Feasible>
  double shortened(double T_first, const Feasible& feasible) {
    const double floor = discreteDurationLowerBound(problem_);
    double T = T_first;
    for (int k = 0; k < kMaxShortenings && !stopped(); ++k) {
      T *= kShorteningFactor;
      if (T < floor) break;
      if (feasible(T)) return T;
    }
    if (!(floor > 0.0 && floor < T_first)) return 0.0;
    const double spread = std::pow(floor / T_first, 1.0 / (kMaxShortenings + 1));
    if (spread <= kShorteningFactor) return 0.0;  // no duration the factor did not reach
    T = T_first;
    for (int k = 0; k < kMaxShortenings && !stopped(); ++k) {
      T *= spread;
      if (feasible(T)) return T;
    }
    return 0.0;
  }

  /// Between the durations doubling tried, where neither doubling nor `shortened` found a plan:
  /// each doubling [T_first 2^j, T_first 2^(j+1)] at 2^(1/4), 2^(1/2) and 2^(3/4) of its start,
  /// the shortest first, below the durations the grid cannot hold: the T where `feasible` held, or
  /// 0. Why: with spinning ends the durations with a plan can lie in a window narrower than a
  /// doubling (measured on the seed-45 spinning suite's #206: cold minimum-effort plans at 28.95
  /// and 33.30 s, none at 25.18 or 38.29 s, where doubling tried 25.28 and 50.57 s).
  template <typename Feasible>
  double betweenDoublings(double T_first, const Feasible& feasible) {
    for (double start = T_first; start < unrepresentable_from_; start *= 2.0) {
      for (const double quarter : {0.25, 0.5, 0.75}) {
        const double T = start * std::pow(2.0, quarter);
        if (T >= unrepresentable_from_ || stopped()) return 0.0;
        if (feasible(T)) return T;
      }
    }
    return 0.0;
  }

  /// Bisection of a search's bracket [T_lo infeasible, T_hi feasible], from its plans.
  void bisect(SearchOutcome* out) {
    out->tally.resume();
    while (!stopped() && out->T_hi - out->T_lo > kMinimumTimeTolerance * out->T_hi) {
      const double mid = 0.5 * (out->T_lo + out->T_hi);
      const Maneuver from = out->best.maneuver;
      (tryDuration(mid, &from, out) ? out->T_hi : out->T_lo) = mid;
    }
    out->tally.pause();
  }

  /// Above kCoarsestSearchGrid the starts are searched on a coarser grid (N/2, recursively) and
  /// its T* plan, resampled, starts the search here just above its T* (the discrete T*
  /// converges in N; measured, Betts's case: every start searched at N = 128 stopped above 34 s,
  /// while the N = 64 search reaches 28.6 s). The full set of starts runs here only if that
  /// finds nothing.
  void searchFromCoarseGrid() {
    if (problem_.steps <= kCoarsestSearchGrid || problem_.steps % 2 != 0) return;
    PlanningProblem coarse_problem = problem_;
    coarse_problem.steps = problem_.steps / 2;
    coarse_problem.time_margin = 0.0;
    const PlanResult coarse = MinimumTimeSearch(coarse_problem, context_, allowance_).run();
    if (!coarse.converged()) return;
    Maneuver resampled = coarse.maneuver;
    resampled.attitude = resampleAttitudes(coarse.maneuver, problem_.steps);
    outcomes_.push_back(search("coarse grid (N = " + std::to_string(coarse_problem.steps) + ")",
                               &resampled, coarse.minimum_duration * kCoarseStartFactor));
    coarse_minimum_duration_ = coarse.minimum_duration;
    // Its start's parameters: the coarse search's kept start's, refined from N/2.
    SearchOutcome& refined = outcomes_.back();
    refined.kind = AttemptStart::CoarseLevel;
    for (const Attempt& a : coarse.attempts) {
      if (!a.kept) continue;
      refined.detail = a.start_detail;
      refined.detail.origin = originOf(a);
    }
    refined.detail.duration = coarse.minimum_duration * kCoarseStartFactor;
    refined.detail.coarse_steps = coarse_problem.steps;
  }

  bool isRestToRest() const {
    return !stopped() && problem_.initial_velocity.isZero(0.0) &&
           problem_.final_velocity.isZero(0.0) &&
           so3::angleBetween(problem_.initial_attitude, problem_.final_attitude) > 0;
  }

  /// Rest to rest: the eigenaxis bang–bang slew at the least T its bounds allow and excursions
  /// off it about the two axes perpendicular to the eigenaxis, both signs, two sizes, first
  /// solved just above and just below the eigenaxis T (the eigenaxis slew is a symmetric saddle
  /// the solver cannot leave on its own; the nutating time-optimal slews lie below it, and which
  /// excursion reaches the published T* differs between Betts's and Bilimoria–Wie's cases).
  void searchStructuredStarts() {
    const double T_eigenaxis = eigenaxisBangBangDuration(problem_);
    const Vector3 e =
        so3::log(problem_.initial_attitude.transpose() * problem_.final_attitude).normalized();
    const Vector3 p1 = e.unitOrthogonal(), p2 = e.cross(p1);
    std::vector<StructuredStart> starts{{"eigenaxis", e, 0.0, kEigenaxisStartFactor}};
    // Their parameters: body frame (e and the excursion axes are R_0's body axes).
    for (const double angle : kExcursionAngles) {
      for (const double factor : kExcursionStartFactors) {
        for (const auto& [name, axis] : {std::pair<std::string, Vector3>{"+p1", p1},
                                         {"-p1", -p1},
                                         {"+p2", p2},
                                         {"-p2", -p2}}) {
          std::ostringstream label;
          label << "excursion " << angle << " rad " << name << " from " << factor << " T_eig";
          starts.push_back({label.str(), axis, angle, factor});
        }
      }
    }
    for (const StructuredStart& st : starts) {
      if (stopped()) break;
      PlanningProblem shaped = effort_;
      shaped.duration = T_eigenaxis * st.duration_factor;
      const Maneuver slew = excursionSlew(shaped, st.axis, st.angle);
      outcomes_.push_back(search(st.name, &slew, shaped.duration));
      SearchOutcome& o = outcomes_.back();
      o.kind = st.angle > 0 ? AttemptStart::Excursion : AttemptStart::EigenaxisSlew;
      o.detail.duration = shaped.duration;
      o.detail.eigenaxis = e;
      if (st.angle > 0) {
        o.detail.excursion_axis = st.axis;
        o.detail.excursion = st.angle;
      }
    }
  }

  /// The search with the least feasible T (only its bracket is bisected: a 5 % bracket each, and
  /// bisecting them all cost 5× the solves, measured on the seed's torque_limited scene, for T*
  /// within 2e-4 of each other).
  SearchOutcome* leastFeasible() {
    SearchOutcome* found = nullptr;
    for (SearchOutcome& o : outcomes_) {
      if (o.feasible && (!found || o.T_hi < found->T_hi)) found = &o;
    }
    return found;
  }

  PlanResult noneFeasible(double guess, std::size_t first) const {
    PlanResult none;
    const verdicts::ProvenDurations proven = provenDurations(problem_, no_room_);
    if (stopped_) {
      none.termination = *stopped_;
      recordVerdict(&none, verdicts::SearchStopped{*stopped_, proven});
    } else if (allowance_.stopped()) {
      none.termination = Termination::NotConverged;
      recordVerdict(&none, verdicts::SearchStopped{Termination::NotConverged, proven,
                                                   allowance_.allowance()});
    } else if (std::isfinite(unrepresentable_from_)) {
      // Longer plans are not shown infeasible: this grid cannot hold them. Only where the grid
      // is too coarse at the proven least duration is the step count the cause.
      const bool coarse = representableDuration(problem_) < durationLowerBound(problem_).seconds;
      none.termination = coarse ? Termination::StepTooLarge : Termination::NotConverged;
      recordVerdict(&none, verdicts::SearchUnrepresentable{
                               unrepresentable_from_, problem_.steps, coarse,
                               std::isfinite(least_tried_) ? least_tried_ : 0.0, proven});
    } else {
      none.termination = Termination::Infeasible;
      recordVerdict(&none, verdicts::SearchInfeasible{kMaxDoublings, guess, proven});
    }
    none.attempts = context_.attemptsFrom(first);
    return none;
  }

  /// One attempt per start of the search (its solves summed), in the order the starts ran.
  std::vector<Attempt> trail() const {
    std::vector<Attempt> attempts;
    for (const SearchOutcome& o : outcomes_) {
      Attempt a;
      a.stage = AttemptStage::MinimumTimeProbe;
      a.start = o.kind;
      a.start_detail = o.detail;
      a.formulation = Formulation::FreeSlacks;
      a.steps = problem_.steps;
      a.termination = o.feasible ? Termination::Converged : Termination::Infeasible;
      a.iterations = o.tally.iterations();
      if (o.feasible) a.cost = o.best.cost;
      attempts.push_back(a);
    }
    return attempts;
  }

  PlanResult atMinimumTime(const SearchOutcome& found, std::size_t first) const {
    PlanResult result = found.best;
    // At T* the feasible set shrinks to the bang–bang plan: its minimum-effort solve may stop
    // short of optimality while its plan meets every constraint.
    answerFeasibleAt(found.T_hi, &result);
    result.attempts = context_.attemptsFrom(first);
    addNote(&result, notes::SearchSummary{searchNote(found)});
    return result;
  }

  /// T* is the least duration the interior point found feasible: an upper bound on the true
  /// minimum (a false "infeasible" below it cannot be told from a true one;
  /// docs/results/minimum_time.md).
  std::string searchNote(const SearchOutcome& found) const {
    std::ostringstream note;
    note << "; minimum time T* = " << found.T_hi << " s, the least duration found feasible, from "
         << "the " << found.start << " start (bracket [" << found.T_lo << ", " << found.T_hi
         << "] s; starts:";
    for (const SearchOutcome& o : outcomes_) {
      note << " " << o.start << " ";
      if (o.feasible) {
        note << o.T_hi << " s;";
      } else {
        note << "none feasible;";
      }
    }
    note << " " << solves_ << " minimum-effort solves"
         << (stopped_ ? ", stopped by " + terminationName(*stopped_) : std::string())
         << (allowance_.stopped() ? ", stopped at its work allowance" : "") << ")";
    if (coarse_minimum_duration_ > 0) {
      note << "; on the coarse grid T* = " << coarse_minimum_duration_ << " s";
    }
    return note.str();
  }

  struct StructuredStart {
    std::string name;
    Vector3 axis;
    double angle, duration_factor;
  };

  const PlanningProblem& problem_;
  SolveContext& context_;
  const SolveContext::WorkAllowance& allowance_;
  PlanningProblem effort_;
  std::vector<SearchOutcome> outcomes_;
  std::optional<Termination> stopped_;
  /// The least T at which this grid had no boundary step (tryDuration); infinity: none.
  double unrepresentable_from_ = std::numeric_limits<double>::infinity();
  NoRoomBeforeTheEnd no_room_;  ///< the durations proven to hold no plan on this grid
  /// The least T a minimum-effort solve was tried at (tryDuration); infinity: none.
  double least_tried_ = std::numeric_limits<double>::infinity();
  double coarse_minimum_duration_ = 0.0;
  int solves_ = 0;
};

}  // namespace

void answerFeasibleAt(double T, PlanResult* plan) {
  if (!plan->converged()) {
    plan->termination = Termination::Converged;
    recordVerdict(plan, verdicts::FeasibleAtMinimumTime{T});
  }
  plan->minimum_duration = T;
}

PlanResult searchMinimumTime(const PlanningProblem& problem, SolveContext& context) {
  const SolveContext::WorkAllowance allowance(context,
                                              context.request().advanced.search_work_allowance);
  return MinimumTimeSearch(problem, context, allowance).run();
}

PlanResult searchMinimumTime(const PlanningProblem& problem, const SolverOptions& options) {
  SolveContext context(options);
  return searchMinimumTime(problem, context);
}

}  // namespace attitude_planner
