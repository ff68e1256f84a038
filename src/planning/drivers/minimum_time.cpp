#include "attitude_planner/planning/minimum_time.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "planning/drivers/bounded_verdicts.hpp"
#include "planning/drivers/fourth_order.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/drivers/lowest_iterate.hpp"
#include "planning/drivers/minimum_time_free_time.hpp"
#include "planning/drivers/minimum_time_phase.hpp"
#include "planning/drivers/minimum_time_search.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/drivers/pointing_minimum_time.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

void validateMinimumTime(const PlanningProblem& problem) {
  if (!std::isfinite(torqueAuthority(problem).smallest_about_any_axis)) {
    throw InvalidInput(
        "objective: 'minimum_time' needs a torque bound (effects: [actuator_limits: ...] or "
        "constraints: [max_torque_norm: ...]); without one any duration > 0 is feasible");
  }
  if (problem.accuracy.active()) {
    throw InvalidInput(
        "objective: 'minimum_time' with an accuracy target is not supported (give steps)");
  }
}

PlanResult minimumTimePlan(const PlanningProblem& problem, SolveContext& context,
                           RichardsonPair* pair = nullptr);

/// `from`'s work (its free-time solves and cone clearings) added to `*to`'s: an answer made of
/// two minimum-time solves (a Richardson pair, a fixed twist then the free one) counts both. The
/// clearings' iterations are the request's (planMinimumTime).
void addSolveWork(const MinimumTimeCertificate& from, MinimumTimeCertificate* to) {
  to->solves += from.solves;
  to->cone_clearings += from.cone_clearings;
  to->cone_clearings_joined += from.cone_clearings_joined;
}

/// `*to` with `from`'s work (its solves and cone clearings) in place of its own.
void setSolveWork(const MinimumTimeCertificate& from, MinimumTimeCertificate* to) {
  to->solves = to->cone_clearings = to->cone_clearings_joined = 0;
  addSolveWork(from, to);
}

}  // namespace

std::string tStarKind(const PlanResult& r) {
  return r.minimum_time.kkt_point
             ? "minimum time, a KKT point of the discrete minimum-time problem: a local minimum"
             : "minimum time, the least duration found feasible: an upper bound";
}

PlanResult planFromMinimumTimePlan(const PlanningProblem& problem, double T,
                                   const Maneuver& at_minimum_time, SolveContext& context) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = T;
  SolveRequest o(context.options());
  o.warm_start = &at_minimum_time;
  o.start.from_constrained_plan = true;
  o.start.strictly_inside = true;
  return planAtResolution(effort, o, context);
}

namespace {

/// fourth_order at T ≥ T*: each second_order sub-solve from its own plan at T*
/// (planFromMinimumTimePlan: time-scaled, inside the bounds), the two plans combined. (Through
/// planFourthOrder the 2N solve starts cold: measured on Betts at N = 64 with time_margin 0.005,
/// 0.02 and 0.1, it ended a false "infeasible" each time.)
PlanResult fourthOrderFromPair(const PlanningProblem& problem, double T, const RichardsonPair& pair,
                               SolveContext& context) {
  PlanningProblem sub = problem;
  sub.scheme = SchemeKind::SecondOrder;
  const std::size_t first = context.attempts().size();
  const PlanResult coarse = planFromMinimumTimePlan(sub, T, pair.coarse, context);
  const std::optional<std::size_t> coarse_kept = context.keptSince(first);
  PlanResult fine;
  if (coarse.converged()) {
    sub.steps = 2 * problem.steps;
    fine = planFromMinimumTimePlan(sub, T, pair.fine, context);
  }
  const frames::RichardsonPair each_from_its_plan{problem.steps, true};
  if (!coarse.converged() || !fine.converged()) {
    PlanResult failed = coarse.converged() ? fine : coarse;
    const int stopped = coarse.converged() ? 2 * problem.steps : problem.steps;
    frameMessage(&failed, frames::PairSolveStopped{each_from_its_plan, stopped});
    failed.attempts = context.attemptsFrom(first);
    return failed;
  }
  PlanningProblem at = problem;
  at.objective = Objective::MinimumEffort;
  at.time_margin = 0.0;
  at.duration = T;
  bool replaced = false;
  PlanResult result = richardsonCombinationWithinTheBounds(at, coarse, fine, &replaced);
  takeReason(&result, coarse);
  frameMessage(&result, frames::PairCombined{each_from_its_plan, replaced, fine.clauses});
  if (replaced) context.restoreKept(coarse_kept);  // the N solve's plan is the one returned
  result.attempts = context.attemptsFrom(first);
  return result;
}

}  // namespace

PlanResult planFromMinimumTime(const PlanningProblem& problem, double T,
                               const Maneuver& at_minimum_time, const RichardsonPair& pair,
                               SolveContext& context) {
  if (problem.scheme == SchemeKind::FourthOrder) {
    return fourthOrderFromPair(problem, T, pair, context);
  }
  return planFromMinimumTimePlan(problem, T, at_minimum_time, context);
}

namespace {

/// fourth_order (docs/design/fourth_order.md, "Minimum time"): a fourth_order plan at T exists
/// exactly when both second_order plans, at N and at 2N, do. So its minimum-time problem is
/// min T s.t. both transcriptions are feasible at T: T* = max(T*_N, T*_2N), each the second_order
/// minimum-time answer (minimumTimePlan: its starts, refinement, polish and fallback). Where the
/// larger (the binding one) is a KKT point, so is the pair: the binding problem's multipliers,
/// zero ones on the other's constraints, which its minimum-effort plan at T* (from its own plan
/// at its T*, time-scaled: inside the bounds) meets. The plan is the two plans' Richardson
/// combination, or the N plan where that leaves a bound (richardsonCombinationWithinTheBounds).
PlanResult fourthOrderMinimumTime(const PlanningProblem& problem, SolveContext& context,
                                  RichardsonPair* pair) {
  const int N = problem.steps;
  PlanningProblem coarse_problem = problem;
  coarse_problem.scheme = SchemeKind::SecondOrder;
  coarse_problem.time_margin = 0.0;
  PlanningProblem fine_problem = coarse_problem;
  fine_problem.steps = 2 * N;
  const std::size_t first = context.attempts().size();
  PlanResult fine = minimumTimePlan(fine_problem, context);
  const std::optional<std::size_t> fine_kept = context.keptSince(first);
  const auto failed = [&](PlanResult sub, bool at_fine, bool effort_at_minimum_time) {
    sub.scheme = SchemeKind::FourthOrder;
    frameMessage(&sub, frames::MinimumTimePairStopped{N, at_fine, effort_at_minimum_time});
    return sub;
  };
  if (!fine.converged()) return failed(fine, true, false);
  const std::size_t coarse_first = context.attempts().size();
  PlanResult coarse = minimumTimePlan(coarse_problem, context);
  const std::optional<std::size_t> coarse_kept = context.keptSince(coarse_first);
  if (!coarse.converged()) return failed(coarse, false, false);
  const bool fine_binds = fine.minimum_duration >= coarse.minimum_duration;
  const double T_star = std::max(fine.minimum_duration, coarse.minimum_duration);
  const double T_N = coarse.minimum_duration, T_2N = fine.minimum_duration;
  // The binding one's certificate with both solves' work, taken before the other's plan at T*
  // (a minimum-effort answer) replaces it below.
  MinimumTimeCertificate certificate = (fine_binds ? fine : coarse).minimum_time;
  setSolveWork(fine.minimum_time, &certificate);
  addSolveWork(coarse.minimum_time, &certificate);
  // The other one's minimum-effort plan at T* (at its own T*: its plan already).
  std::optional<std::size_t> other_kept;
  PlanResult& other = fine_binds ? coarse : fine;
  if (other.minimum_duration < T_star) {
    const std::size_t other_first = context.attempts().size();
    PlanResult at_T_star = [&] {
      const SolveContext::Scope scope(context, AttemptStage::MinimumTimePolish,
                                      homotopyClassOf(problem), SolveContext::Nested::ScopeStage);
      return planFromMinimumTimePlan(fine_binds ? coarse_problem : fine_problem, T_star,
                                     other.maneuver, context);
    }();
    other_kept = context.keptSince(other_first);
    if (!at_T_star.converged()) {
      context.restoreKept(std::nullopt);
      at_T_star.attempts = context.attemptsFrom(first);
      return failed(at_T_star, !fine_binds, true);
    }
    other = at_T_star;
  }
  PlanningProblem at = problem;
  at.duration = T_star;
  bool replaced = false;
  PlanResult result = richardsonCombinationWithinTheBounds(at, coarse, fine, &replaced);
  if (pair) *pair = RichardsonPair{coarse.maneuver, fine.maneuver};
  result.minimum_duration = T_star;
  result.minimum_time = certificate;
  // Kept: the plan returned, the binding one's (the combination) or the N plan's (replaced):
  // the 2N minimum time's, the N minimum time's, or the N plan's polish at T*.
  if (fine_binds) {
    context.restoreKept(replaced ? other_kept : fine_kept);
  } else {
    context.restoreKept(replaced ? coarse_kept : std::nullopt);
  }
  result.attempts = context.attemptsFrom(first);
  takeReason(&result, coarse);
  frameMessage(&result, frames::MinimumTimePairCombined{N, T_star, T_N, T_2N, fine_binds, replaced,
                                                        fine.clauses});
  return result;
}

/// Spinning ends: the probes below T* (probedBelow). A probe asks (1 − δ 2^j) T for the least
/// duration T found so far, δ = kProbeBelow: j grows while probes succeed (a descent by doubling
/// steps), falls back by one after a failure (bisection), and where the probes at both δ and 2δ
/// below T found nothing, the far probes follow (kFarProbes below T, each once; only below an
/// answer not shown a local minimum: farProbesBelow; below one that is, the ladder kLadder within
/// its budget) before the descent stops. A cold
/// minimum-effort solve's failure is local and feasibility in T is not monotone with spinning ends:
/// the seeded bounded suite had requests where 0.99 T failed and 0.98 T converged, and the seed-45
/// spinning suite's #77 (N = 215) a KKT point at 6.8175 s with minimum-effort plans failing at 0.99
/// and 0.98 of it and converging at 6.3 s and 5.3 s (the issue's own evidence: plans at 0.90 T*).
/// kMaxProbes bounds their number (each probe is one constrained minimum-effort solve and, where
/// it finds a plan, one free-time solve), and the work allowance their time (ProbeBudget: a
/// probe's solve at N = 400-800 can take thousands of iterations).
constexpr double kProbeBelow = 0.01;
constexpr int kLargestProbeExponent = 5;  ///< at most 32 δ = 32 % below T per probe
constexpr double kFarProbes[] = {0.1, 0.2};
constexpr int kMaxProbes = 12;
/// Below an answer shown a strict local minimum (second-order sufficient), where the near probes
/// found nothing: the ladder, probes at these fractions below T, each once, while its budget
/// lasts (kLadderShare). Why: a cold probe's outcome alternates with T there (the seed-45
/// spinning suite's #109: plans 2.5-9 % below a second-order sufficient 38.74 s, "infeasible" at
/// durations between them), so two failures are samples, not a verdict; the rungs are spaced by
/// about 1.5 from the near probes' 2 % up to the far probes' first 10 %.
constexpr double kLadder[] = {0.03, 0.05, 0.07, 0.1};

/// What the probes below the current T have shown: which steps δ 2^j found nothing, and which
/// far probe (or rung of the ladder) is next once the near ones found nothing.
struct ProbeSteps {
  int exponent = 0;
  bool failed_at_one = false, failed_at_two = false;  ///< j = 0, j = 1 found nothing
  int far = -1;         ///< the far probe or rung being asked (index); −1: the near ones
  bool ladder = false;  ///< far indexes kLadder (below a strict local minimum), else kFarProbes

  double fraction() const {
    if (far < 0) return kProbeBelow * std::ldexp(1.0, exponent);
    return ladder ? kLadder[far] : kFarProbes[far];
  }
  bool onLadder() const { return far >= 0 && ladder; }
  /// After a probe that found a plan (a lower T): `descended` if a free-time KKT point came of it
  /// (a new basin: start again at δ), else larger steps.
  void found(bool descended) {
    exponent = descended || far >= 0 ? 0 : std::min(exponent + 1, kLargestProbeExponent);
    failed_at_one = failed_at_two = false;
    far = -1;
  }
  /// After a probe that found nothing: false when the descent stops. `look_far`: the far probes
  /// follow once the near ones found nothing (farProbesBelow); else the ladder, where
  /// `ladder_affordable` (its budget holds another probe).
  bool nothingFound(bool look_far, bool ladder_affordable) {
    if (far >= 0) {
      const int rungs = ladder ? std::size(kLadder) : std::size(kFarProbes);
      return ++far < rungs && (!ladder || ladder_affordable);
    }
    if (exponent == 0) failed_at_one = true;
    if (exponent == 1) failed_at_two = true;
    if (failed_at_one && failed_at_two) {
      if (!look_far && !ladder_affordable) return false;
      ladder = !look_far;
      far = 0;
      return true;
    }
    exponent = exponent > 1 ? exponent - 1 : (failed_at_one ? 1 : 0);
    return true;
  }
};

/// The iterations the ladder may take in one run of the probes: kLadderShare of the minimum-time
/// solve's iterations before them, so that a cheap request stays cheap (on the seed-45 spinning
/// suite's 48 cheapest rows no probe 0.5-15 % below T* found a plan) and a request that cost much
/// may spend in proportion on looking below its T*. A rung is asked only where the ladder's
/// iterations so far and the last probe's (the likely cost of the next) fit in it.
constexpr double kLadderShare = 0.5;

/// The ladder's budget for a run of the probes beginning now: kLadderShare of what `solve` (this
/// minimum-time solve's tally, opened where minimumTimePlan began) has counted. Its own
/// iterations, not the request's: what the budget bounds is the cost of this solve's verdict, and
/// a caller's earlier solves are no part of it. Counted from the request, the same minimum-time
/// problem got a larger ladder as a minimum-effort request's minimum-time phase (after the
/// minimum-effort solve that failed) than asked alone: seed-45 spinning #188, 760 iterations
/// against 556, so the check at 0.99 T* ran a rung the request never ran and refuted its T*.
double ladderBudget(const SolveContext::IterationTally& solve) {
  return kLadderShare * solve.iterations();
}

/// What the probes below T* may spend: the ladder's share of the minimum-time solve's
/// iterations (`solve`, ladderBudget) and, for the whole phase (every probe, hand-on and chain),
/// the request's search_work_allowance (AdvancedParameters) of work (`work`, opened where the
/// probes begin).
struct ProbeBudget {
  ProbeBudget(const SolveContext& context, const SolveContext::IterationTally& minimum_time_solve)
      : solve(minimum_time_solve),
        work(context, context.request().advanced.search_work_allowance) {}
  const SolveContext::IterationTally& solve;
  SolveContext::WorkAllowance work;
};

/// Whether the far probes look below `answer` once the near ones found nothing: only where it is
/// not shown a local minimum (a KKT point that is not second-order sufficient, or a probe's plan,
/// an upper bound). Below a second-order sufficient KKT point the near probes have already looked
/// just below a strict local minimum, and the far probes' cold solves below such answers gave no
/// lower answer on the seed-45 spinning page; its two gains came from answers not shown a local
/// minimum (#77's KKT point at 6.8175 s, #221's answer at 91.69 s). A cost rule, not a proof: a
/// strict local minimum can still have another basin far below it: below one, the ladder looks
/// (kLadder, within its budget).
bool farProbesBelow(const PlanResult& answer) {
  return !answer.minimum_time.second_order_sufficient;
}

/// freeTimeFromPlan, its iterate below the plan's T (if any) handed to `*below` with its solve's
/// place in the trail (the solve recorded last).
std::optional<PlanResult> freeTimeFrom(const PlanningProblem& problem, const Maneuver& plan,
                                       double duration, const std::string& start,
                                       SolveContext& context, std::optional<IterateBelow>* below) {
  std::optional<Maneuver> iterate;
  std::optional<PlanResult> solved =
      freeTimeFromPlan(problem, plan, duration, start, context, &iterate);
  below->reset();
  if (iterate) *below = IterateBelow{std::move(*iterate), context.attempts().size() - 1};
  return solved;
}

}  // namespace

PlanningProblem effortAt(const PlanningProblem& problem, double duration) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = duration;
  return effort;
}

/// A free-time iterate strictly inside every bound is such a plan by construction, and T* is at
/// most its T whether or not a minimum-effort solve at that T converges: measured on the seed-45
/// spinning suite's #221 (N = 405), the probes from such iterates ended "infeasible" at 57.93,
/// 56.71 and 55.73 s, and the answer fell back to a probe's plan at 72.62 s, which the page's
/// check refuted.
std::optional<PlanResult> iterateAsPlan(const PlanningProblem& effort, const Maneuver& iterate) {
  PlanResult r;
  r.solver = "interior_point";
  r.termination = Termination::NotConverged;
  try {
    evaluatePlan(effort, iterate.torque, &r, &iterate);
    replayFigures(effort, &r);
  } catch (const StepTooLarge&) {  // the replay found no step: not shown a plan
    return std::nullopt;
  }
  if (!provesFeasible(effort, r)) return std::nullopt;
  recordConstraintFigures(effort, &r);
  // Feasible at its T, as answerFeasibleAt says of a plan, and said to be an iterate.
  r.termination = Termination::Converged;
  recordVerdict(&r, verdicts::FeasibleAtMinimumTime{effort.duration, true});
  return r;
}

void LowestIterate::offer(const PlanningProblem& problem,
                          const std::optional<IterateBelow>& iterate) {
  if (!iterate) return;
  const std::size_t root = iterate->root();
  const auto chain = std::find_if(chains_.begin(), chains_.end(),
                                  [&](const Plan& kept) { return kept.root == root; });
  if (chain != chains_.end() && !(iterate->duration() < chain->effort.duration)) return;
  const PlanningProblem effort = effortAt(problem, iterate->duration());
  std::optional<PlanResult> plan = iterateAsPlan(effort, iterate->plan);
  if (!plan) return;
  Plan kept{effort, std::move(*plan), iterate->attempt, root};
  if (chain != chains_.end()) {
    *chain = std::move(kept);
  } else {
    chains_.push_back(std::move(kept));
  }
}

const LowestIterate::Plan* LowestIterate::below(double duration) const {
  const Plan* lowest = nullptr;
  for (const Plan& kept : chains_) {
    if (kept.effort.duration < (lowest ? lowest->effort.duration : duration)) lowest = &kept;
  }
  return lowest;
}

std::vector<LowestIterate::Plan> LowestIterate::chainsBelow(double duration,
                                                            std::size_t except_root) const {
  std::vector<Plan> below;
  for (const Plan& kept : chains_) {
    if (kept.root != except_root && kept.effort.duration < duration) below.push_back(kept);
  }
  std::stable_sort(below.begin(), below.end(), [](const Plan& a, const Plan& b) {
    return a.effort.duration > b.effort.duration;
  });
  return below;
}

namespace {

/// `below`, a plan at effort.duration below `answer`'s T (its attempt `below_kept`), as the
/// answer: an upper bound on T* (answerFeasibleAt: converged also where the plan is not a
/// minimum-effort optimum, as the search's T* is). Its trail: the context's from `first`.
PlanResult upperBoundAt(const PlanningProblem& effort, const PlanResult& answer,
                        const PlanResult& below, std::optional<std::size_t> below_kept,
                        std::size_t first, SolveContext& context) {
  PlanResult upper = below;
  context.restoreKept(below_kept);
  upper.attempts = context.attemptsFrom(first);
  upper.minimum_time = MinimumTimeCertificate{};
  answerFeasibleAt(effort.duration, &upper);
  setSolveWork(answer.minimum_time, &upper.minimum_time);
  frameMessage(&upper, frames::UpperBoundFromProbe{effort.duration, answer.minimum_duration});
  return upper;
}

/// The answer from a plan at `effort.duration` below `answer`'s T (`below`: a probe's, or an
/// iterate; its attempt kept `below_kept`): the free-time KKT point from it where one lies lower,
/// else that plan as an upper bound on T* (upperBoundAt). Its trail: the context's from `first`.
/// Where that free-time solve ended short of a KKT point at a plan below `below`'s T, the plan
/// goes to `*lower_plan` and is offered to `iterates`, in the chain `chain_root` where `below`
/// came of an iterate of that chain (else a chain of its own).
PlanResult lowerAnswer(const PlanningProblem& problem, const PlanningProblem& effort,
                       const PlanResult& answer, const PlanResult& below,
                       std::optional<std::size_t> below_kept, std::size_t first,
                       SolveContext& context, std::optional<IterateBelow>* lower_plan,
                       LowestIterate& iterates, std::optional<std::size_t> chain_root) {
  std::optional<PlanResult> lower =
      freeTimeFrom(problem, below.maneuver, effort.duration, "probe's plan", context, lower_plan);
  if (*lower_plan) (*lower_plan)->chain_root = chain_root;
  iterates.offer(problem, *lower_plan);
  if (lower && lower->converged() && lower->minimum_duration < effort.duration) {
    lower->attempts = context.attemptsFrom(first);
    addNote(&*lower, notes::DescendedFromProbe{effort.duration, answer.minimum_duration});
    return *lower;
  }
  return upperBoundAt(effort, answer, below, below_kept, first, context);
}

/// The lowest iterate that is a plan as the answer where it lies below `answer`'s T (an upper
/// bound on T*); else `answer`.
PlanResult atMostLowestIterate(PlanResult answer, const LowestIterate& iterates, std::size_t first,
                               SolveContext& context) {
  const LowestIterate::Plan* lowest = iterates.below(answer.minimum_duration);
  if (!lowest || !answer.converged()) return answer;
  return upperBoundAt(lowest->effort, answer, lowest->plan, lowest->attempt, first, context);
}

/// Minimum time with spinning ends has local minima that the structured starts miss, with
/// minimum-effort plans below their T* (docs/results/bounded_verdicts.md). So a free-time answer
/// with spinning ends is probed: cold minimum-effort solves below T* (ProbeSteps); where one
/// finds a plan (provesFeasible), the free-time solve from it descends to a lower KKT point or
/// its plan is the answer, an upper bound; where that free-time solve ended at its iteration limit
/// at a plan below the probe's T (every iterate strictly inside is a plan), the next probe is at
/// that plan's T, warm-started from it (measured on #173 of the seed-45 spinning suite: an iterate
/// at 6.27 s below the probe's 9.94 s, from which the descent reaches 6.095 s). With
/// `iterates_are_plans`, where that probe finds no plan the iterate is the plan at its T
/// (iterateAsPlan) and the free-time solve goes on from it. Every such iterate is offered to
/// `iterates`. No probe goes below the proven bound T_c on the grid. The trail keeps every probe
/// (the context's from `first`, where `answer`'s began). Where `solves_left` is given, each probe
/// takes one of its solves and none is asked once it is spent. `budget`: the ladder's share of the
/// minimum-time solve's iterations (ladderBudget) and the probes' work allowance (none is asked
/// once it is spent).
PlanResult probedBelow(const PlanningProblem& problem, PlanResult answer, std::size_t first,
                       SolveContext& context, const ProbeBudget& budget, LowestIterate& iterates,
                       std::optional<IterateBelow> lower_plan, bool iterates_are_plans,
                       int* solves_left = nullptr) {
  const double floor = discreteDurationLowerBound(problem);  // 0: no bound
  ProbeSteps steps;
  const double ladder_budget = ladderBudget(budget.solve);
  int ladder_spent = 0, last_probe = 0;
  int handed_on = 0;  // probes from such a plan: beside the descent's own, which they do not steer
  for (int probe = 0; probe < kMaxProbes && answer.converged(); ++probe) {
    if (solves_left && (*solves_left)-- <= 0) break;
    PlanningProblem effort =
        effortAt(problem, std::max((1.0 - steps.fraction()) * answer.minimum_duration, floor));
    SolveRequest options(context.options());
    // A cold probe whose unconstrained solve stalls goes to the interior point without the
    // continuation in the boundary rates: measured on the seed-45 spinning suite's #109, it
    // failed in every probe and took two thirds of each probe's iterations (3,094 of 4,609 and
    // 3,917 of 5,628), and where it fails the interior point starts as it would without it
    // (from the coasting start's optimum, or cold). No probe of the 48 cheap rows stalled.
    options.advanced.newton.rate_continuation_max_stages = 0;
    // A rung of the ladder is solved on the request's grid itself, not through the interior
    // point's grid continuation (coarsest_grid raised to N; the same on grids up to it): below a
    // strict local minimum the near probes, through the continuation, have found nothing, and a
    // rung is one more sample, so it samples another start (the request's own unconstrained
    // optimum, not the coarse level's). Measured (docs/results/spinning_minimum_time.md): on
    // held-out spinning requests with N above coarsest_grid, two T* 4-5 % lower and none higher;
    // with every probe so, one request ended higher.
    if (steps.onLadder()) {
      options.advanced.interior_point.coarsest_grid =
          std::max(options.advanced.interior_point.coarsest_grid, problem.steps);
    }
    const bool from_iterate = lower_plan && handed_on < kMaxProbes;
    if (from_iterate) {  // the probe at the iterate's T, from it
      effort.duration = lower_plan->duration();
      options.warm_start = &lower_plan->plan;
      options.start.from_constrained_plan = true;
      ++handed_on;
      --probe;
    }
    if (effort.duration >= answer.minimum_duration || context.stopReason() ||
        budget.work.exhausted()) {
      break;
    }
    const std::optional<std::size_t> answer_kept = context.keptAttempt();
    const std::size_t probe_first = context.attempts().size();
    const int probe_start = context.iterations();
    PlanResult below = runInternalPhase("the probe below T*",
                                        [&] { return planAtResolution(effort, options, context); });
    if (!from_iterate) {
      last_probe = context.iterations() - probe_start;
      if (steps.onLadder()) ladder_spent += last_probe;
    }
    std::optional<std::size_t> below_kept = context.keptSince(probe_first);
    if (from_iterate && iterates_are_plans && !provesFeasible(effort, below)) {
      // No minimum-effort plan came of the iterate: the iterate itself is one at its T.
      if (std::optional<PlanResult> iterate = iterateAsPlan(effort, lower_plan->plan)) {
        below = std::move(*iterate);
        below_kept = lower_plan->attempt;
      }
    }
    const std::optional<std::size_t> chain_root =
        from_iterate ? std::optional<std::size_t>(lower_plan->root()) : std::nullopt;
    lower_plan.reset();
    if (!provesFeasible(effort, below)) {
      context.restoreKept(answer_kept);
      answer.attempts = context.attemptsFrom(first);
      if (!from_iterate &&
          !steps.nothingFound(farProbesBelow(answer), ladder_spent + last_probe <= ladder_budget)) {
        break;
      }
      continue;
    }
    answer = lowerAnswer(problem, effort, answer, below, below_kept, first, context, &lower_plan,
                         iterates, chain_root);
    if (!from_iterate) steps.found(answer.minimum_duration < effort.duration);
  }
  return answer;
}

/// The solves the probes from the other chains' iterates may take in all (probedFromOtherChains):
/// one run of probedBelow's worth, kMaxProbes probes and kMaxProbes hand-ons. Why that many:
/// measured on the seed-45 spinning suite's #221 (N = 405), the crawl from the iterate of the
/// solve from the search's plan (71.13 s) took 12 hand-ons to 62.61 s before a cold probe found
/// the basin of 40.65 s.
constexpr int kOtherChainsSolves = 2 * kMaxProbes;

/// The probes below T* again from `from`, an iterate that is a plan below `answer`'s T: that
/// iterate is the answer, the free-time solve goes on from it, and the probes (probedBelow,
/// iterates as plans) follow, within `*solves_left` solves where that is given (the free-time
/// solve from `from` one of them). Every iterate of the run is in `from`'s chain.
PlanResult probedFromIterate(const PlanningProblem& problem, const PlanResult& answer,
                             const LowestIterate::Plan& from, std::size_t first,
                             SolveContext& context, const ProbeBudget& budget,
                             LowestIterate& iterates, int* solves_left) {
  if (solves_left) --*solves_left;
  std::optional<IterateBelow> lower_plan;
  PlanResult run = lowerAnswer(problem, from.effort, answer, from.plan, from.attempt, first,
                               context, &lower_plan, iterates, from.root);
  return probedBelow(problem, std::move(run), first, context, budget, iterates,
                     std::move(lower_plan), true, solves_left);
}

/// The probes below T* from each other chain's lowest iterate below `answer`'s T (`others`,
/// highest first: probedFromIterate), within kOtherChainsSolves solves in all. `best` (the run
/// from the lowest iterate) stays the answer unless a run ends lower, so the answer is never
/// above it. Highest first: a chain's iterates are successive points of one crawl, so the lowest
/// ones lie on the chain the first run already followed; the chains that begin highest (the
/// solve from the search's plan) are the ones farthest from it.
PlanResult probedFromOtherChains(const PlanningProblem& problem, const PlanResult& answer,
                                 const std::vector<LowestIterate::Plan>& others, PlanResult best,
                                 std::size_t first, SolveContext& context,
                                 const ProbeBudget& budget, LowestIterate& iterates) {
  std::optional<std::size_t> best_kept = context.keptAttempt();
  int solves_left = kOtherChainsSolves;
  for (const LowestIterate::Plan& from : others) {
    if (solves_left <= 0 || context.stopReason() || budget.work.exhausted()) break;
    PlanResult run =
        probedFromIterate(problem, answer, from, first, context, budget, iterates, &solves_left);
    if (run.converged() && run.minimum_duration < best.minimum_duration) {
      best = std::move(run);
      best_kept = context.keptAttempt();
    }
  }
  context.restoreKept(best_kept);
  best.attempts = context.attemptsFrom(first);
  return best;
}

/// The probes below T* again from the lowest iterate that is a plan, where it lies below
/// `answer`'s T (else `answer`): that iterate is the answer, the free-time solve goes on from it,
/// and the probes (probedBelow, iterates as plans) follow; then from each other chain's lowest
/// iterate below `answer`'s T (probedFromOtherChains). The answer is then at most the lowest
/// iterate any solve ended at. So T* is at most the T of every iterate that is a plan, never above
/// `answer`'s (the probes before it are untouched) and never above the run from the lowest alone.
/// Measured on the seed-45 spinning suite: iterates as plans during the first probes (hand-ons from
/// the search's plan) moved #77 from its 5.18 s basin to a second-order sufficient KKT point at
/// 6.54 s, below which the far probes are not asked; run after them, as here, #77 keeps 5.18 s,
/// #221 (N = 405) goes from a probe's plan at 72.62 s to 51.66 s from the lowest, and #47 of the
/// held-out seed-47 suite from 25.19 s to 21.48 s.
PlanResult probedBelowLowestIterate(const PlanningProblem& problem, PlanResult answer,
                                    std::size_t first, SolveContext& context,
                                    const ProbeBudget& budget, LowestIterate& iterates) {
  const LowestIterate::Plan* found = iterates.below(answer.minimum_duration);
  if (!found || !answer.converged() || context.stopReason() || budget.work.exhausted()) {
    return answer;
  }
  const LowestIterate::Plan lowest = *found;  // the solve from it offers lower ones
  const std::vector<LowestIterate::Plan> others =
      iterates.chainsBelow(answer.minimum_duration, lowest.root);
  PlanResult best =
      probedFromIterate(problem, answer, lowest, first, context, budget, iterates, nullptr);
  best = atMostLowestIterate(std::move(best), iterates, first, context);
  best = probedFromOtherChains(problem, answer, others, std::move(best), first, context, budget,
                               iterates);
  return atMostLowestIterate(std::move(best), iterates, first, context);
}

/// T* and its plan: the free-time interior point where it applies (freeTimeUnsupported), else,
/// or if none of its solves converged, the search (searchMinimumTime, an upper bound) with what is
/// left of the time budget; where the free-time problem applies, the search's plan starts one more
/// free-time solve (a KKT point). The trail keeps every stage in order: the free-time solves that
/// did not give the answer, the search's starts, the solve from the search's plan. Where that
/// solve ended short of its KKT point at a plan below the search's T, the plan is offered to
/// `iterates`.
PlanResult structuredMinimumTime(const PlanningProblem& problem, SolveContext& context,
                                 LowestIterate& iterates);

PlanResult minimumTimePlan(const PlanningProblem& problem, SolveContext& context,
                           RichardsonPair* pair) {
  if (problem.scheme == SchemeKind::FourthOrder) {
    return fourthOrderMinimumTime(problem, context, pair);
  }
  const std::size_t first = context.attempts().size();
  const SolveContext::IterationTally solve(context);  // the ladder's budget (ladderBudget)
  LowestIterate iterates;
  PlanResult answer = structuredMinimumTime(problem, context, iterates);
  if (!answer.converged() || !hasSpinningEnds(problem)) return answer;
  const ProbeBudget budget(context, solve);
  answer = probedBelow(problem, std::move(answer), first, context, budget, iterates, std::nullopt,
                       false);
  answer = probedBelowLowestIterate(problem, std::move(answer), first, context, budget, iterates);
  if (budget.work.stopped()) addNote(&answer, notes::ProbesStopped{budget.work.allowance()});
  return answer;
}

/// One start twist of a pointing request (`posed`: R_N at the start twist): the fixed-attitude
/// minimum time there (its starts, ways round and saddles), then one free-time solve with ψ free
/// from its plan, a KKT point at or below it in its basin; where either does not converge, the
/// recipe with ψ free from the posed start. (From the posed starts alone the ψ-free solves of all
/// 4 start twists slid into one basin: measured on seed 4204, variational, N = 32, 20.9055 s
/// against the swept and refined 20.8307 s.)
PlanResult fromFixedTwist(const PlanningProblem& posed, SolveContext& context) {
  PlanningProblem fixed = posed;
  fixed.end_condition = EndCondition();
  const std::size_t first = context.attempts().size();
  const PlanResult at_twist = minimumTimePlan(fixed, context);
  if (at_twist.converged() &&
      at_twist.maneuver.attitude.size() == static_cast<std::size_t>(posed.steps) + 1) {
    std::optional<PlanResult> freed = freeTimeFromPlan(
        posed, at_twist.maneuver, at_twist.minimum_duration, "fixed-twist plan", context);
    if (freed && freed->converged()) {
      freed->attempts = context.attemptsFrom(first);
      addSolveWork(at_twist.minimum_time, &freed->minimum_time);
      return *freed;
    }
  }
  context.restoreKept(std::nullopt);  // the plan returned is the one from the free twist
  PlanResult free_start = minimumTimePlan(posed, context);
  free_start.attempts = context.attemptsFrom(first);
  addSolveWork(at_twist.minimum_time, &free_start.minimum_time);
  return free_start;
}

}  // namespace

PlanResult minimumTimeOverTwists(const PlanningProblem& problem, SolveContext& context,
                                 RichardsonPair* pair) {
  if (!problem.end_condition.pointing()) return minimumTimePlan(problem, context, pair);
  return pointingMinimumTime(problem, context, [&](const PlanningProblem& posed) {
    return fromFixedTwist(posed, context);
  });
}

namespace {

/// minimumTimePlan of a discretization before the probe below T* (probedBelow).
PlanResult structuredMinimumTime(const PlanningProblem& problem, SolveContext& context,
                                 LowestIterate& iterates) {
  const std::string unsupported = freeTimeUnsupported(problem);
  std::string why;
  const std::size_t first = context.attempts().size();
  if (unsupported.empty()) {
    std::optional<PlanResult> free_time = freeTimeMinimumTime(problem, context);
    if (free_time && free_time->converged()) return *free_time;
    why = free_time ? "the free-time plan's replay failed" : "no free-time solve converged";
  } else {
    why = "the free-time interior point does not take " + unsupported + " yet";
  }
  context.restoreKept(std::nullopt);  // a free-time plan whose replay failed is not the answer
  PlanResult result = searchMinimumTime(problem, context);
  addNote(&result, notes::SearchedOnT{why});
  result.attempts = context.attemptsFrom(first);
  if (!unsupported.empty() || !result.converged() ||
      result.maneuver.attitude.size() != static_cast<std::size_t>(problem.steps) + 1) {
    return result;
  }
  // The search's plan meets every bound at its T (an upper bound on T*): started from it, one
  // free-time solve can reach a KKT point at or below it where the structured starts did not.
  const std::optional<std::size_t> search_kept = context.keptAttempt();
  std::optional<IterateBelow> below;
  std::optional<PlanResult> sharpened = freeTimeFrom(
      problem, result.maneuver, result.minimum_duration, "search's plan", context, &below);
  iterates.offer(problem, below);
  if (!sharpened || !sharpened->converged()) {
    // The search's answer stands; its kept probe stays kept, the solve from its plan follows.
    context.restoreKept(search_kept);
    result.attempts = context.attemptsFrom(first);
    return result;
  }
  sharpened->attempts = context.attemptsFrom(first);
  addNote(&*sharpened, notes::SharpenedFromSearch{why, result.minimum_duration});
  return *sharpened;
}

}  // namespace

PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options) {
  SolveContext context(options);
  return planMinimumTime(problem, context);
}

namespace {

/// planMinimumTime's answer before its clearing figure is stamped (planMinimumTime).
PlanResult minimumTimeRequest(const PlanningProblem& problem, SolveContext& context) {
  validateProblem(problem);
  validateOptions(context.options());
  validateMinimumTime(problem);
  const DurationLowerBound bound = durationLowerBound(problem);
  if (std::optional<PlanResult> answer = answerBeforeSolving(problem, bound)) return *answer;
  const NoRoomBeforeTheEnd no_room = noRoomBeforeTheEnd(problem);
  const std::string impossible = infeasibleAtEveryDuration(problem);
  if (!impossible.empty()) {
    PlanResult none;
    none.termination = Termination::Infeasible;
    recordVerdict(&none, verdicts::InfeasibleAtEveryDuration{impossible});
    recordLowerBound(bound, &none);
    recordNoRoom(no_room, &none);
    return none;
  }
  const auto start = std::chrono::steady_clock::now();
  RichardsonPair pair;
  const std::size_t first = context.attempts().size();
  PlanResult result = runInternalPhase(
      "minimum time", [&] { return minimumTimeOverTwists(problem, context, &pair); });
  recordLowerBound(bound, &result);
  recordNoRoom(no_room, &result);
  if (!result.converged()) return result;
  const double T_star = result.minimum_duration;
  if (problem.duration > 0 && T_star > problem.duration * (1.0 + kMinimumTimeTolerance)) {
    // `duration` is an upper bound: the request asked for T ≤ duration. T* is local.
    result.termination = Termination::Infeasible;
    result.duration_verdict.least_duration_found = T_star;
    recordVerdict(&result,
                  localInfeasibility(problem.duration, T_star, tStarKind(result), bound, false));
    return result;
  }
  if (problem.time_margin > 0.0) {
    const Maneuver at_minimum_time = result.maneuver;
    // What backs T* stays with the answer that reports T* (minimum_duration), though its plan is
    // the minimum-effort one at the margin.
    const MinimumTimeCertificate certificate = result.minimum_time;
    context.restoreKept(std::nullopt);  // the plan returned is the one at the margin
    result = runInternalPhase("the plan at (1 + time_margin) T*", [&] {
      const SolveContext::Scope scope(context, AttemptStage::MinimumTimeMargin,
                                      homotopyClassOf(problem), SolveContext::Nested::ScopeStage);
      return planFromMinimumTime(problem, (1.0 + problem.time_margin) * T_star, at_minimum_time,
                                 pair, context);
    });
    recordLowerBound(bound, &result);
    recordNoRoom(no_room, &result);
    result.attempts = context.attemptsFrom(first);
    addNote(&result, notes::PlannedAtMargin{problem.time_margin, result.duration, T_star});
    result.minimum_time = certificate;
  }
  result.minimum_duration = T_star;
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

PlanResult planMinimumTime(const PlanningProblem& problem, SolveContext& context) {
  PlanResult result = minimumTimeRequest(problem, context);
  // The request's cone clearings' iterations, stamped here only: whichever answer leaves (the
  // search's, a Richardson pair's, a plan at the margin, a check before solving) counts every
  // clearing the request ran.
  result.minimum_time.cone_clearing_iterations = context.coneClearingIterations();
  return result;
}

}  // namespace attitude_planner
