#include "planning/drivers/pointing_minimum_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/termination.hpp"
#include "planning/drivers/minimum_time_free_time.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/drivers/pointing.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/strategies/starts.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

/// One start twist's answer and its kept attempt in the context's trail (none: no solve, or no
/// attempt of its own kept).
struct TwistStart {
  double twist = 0.0;
  PlanResult result;
  std::optional<std::size_t> kept_attempt;
};

/// The index of the converged start with the least T* (on `steps` steps where given; −1: none).
int leastDuration(const std::vector<TwistStart>& starts, int steps = 0) {
  int kept = -1;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const PlanResult& r = starts[i].result;
    const bool on_grid = steps == 0 || r.maneuver.steps() == steps;
    if (r.converged() && on_grid &&
        (kept < 0 || r.minimum_duration < starts[kept].result.minimum_duration)) {
      kept = static_cast<int>(i);
    }
  }
  return kept;
}

/// The last start with a plan on `steps` steps (else the last start): the answer where none
/// converged.
int lastWithPlan(const std::vector<TwistStart>& starts, int steps) {
  for (int i = static_cast<int>(starts.size()) - 1; i >= 0; --i) {
    if (starts[i].result.maneuver.steps() == steps) return i;
  }
  return static_cast<int>(starts.size()) - 1;
}

/// The pointing summary of a plan that reached R_N by its own twist (kept where the recipe's
/// solver filled it: the free-time answer carries ∂L/∂ψ).
void summarizePointing(const PlanningProblem& problem, int starts, PlanResult* r) {
  if (r->maneuver.attitude.empty()) return;
  summarizePointingEnd(r->maneuver.attitude.back(), problem.end_condition, &r->pointing);
  r->pointing.starts = starts;
}

/// The frame of the message: each start's twist and T* (or termination), the one kept.
frames::PointingStarts startsFrame(const std::vector<TwistStart>& starts, int kept) {
  frames::PointingStarts frame;
  frame.kept = kept;
  for (const TwistStart& s : starts) {
    frame.starts.push_back({s.twist, s.result.termination, s.result.minimum_duration});
  }
  return frame;
}

/// The first cone whose node bound R_N at `twist` violates (empty: none): no plan ends there, so
/// that start twist is not posed (its fixed-attitude request would be refused).
std::string coneAtEnd(const PlanningProblem& problem, double twist) {
  const Matrix3 R_N = pointingAttitude(problem.end_condition, twist);
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.isCone() && coneMargin(c, R_N) - c.margin < 0.0) {
      return "R_N at this start twist violates " + describeConstraint(c);
    }
  }
  return "";
}

/// The attempts a start at `s.twist` recorded from `first` on, tagged with its twist in the
/// context, and its kept attempt among them (the answer's, if the start wins).
void tagStartsAttempts(SolveContext& context, std::size_t first, TwistStart* s) {
  context.posedAtTwist(first, s->twist);
  const std::optional<std::size_t> kept = context.keptAttempt();
  if (kept && *kept >= first) s->kept_attempt = kept;
}

/// One start twist's answer: the recipe at R_N there (its attempts in the context tagged with
/// the twist), or, where a cone excludes that R_N, infeasible without a solve.
TwistStart startAt(const PlanningProblem& problem, double twist, SolveContext& context,
                   const MinimumTimeRecipe& recipe) {
  TwistStart s{twist, {}, std::nullopt};
  const std::string excluded = coneAtEnd(problem, twist);
  if (!excluded.empty()) {
    s.result.termination = Termination::Infeasible;  // no solve: the trail shows none
    return s;
  }
  const std::size_t first = context.attempts().size();
  s.result = recipe(endingAt(problem, pointingAttitude(problem.end_condition, twist)));
  tagStartsAttempts(context, first, &s);
  return s;
}

/// The eigenaxis bang–bang slew to R_N at a start twist as a free-time start: `posed` (R_N there,
/// the end condition still the pointing one), the slew and its T (kEigenaxisStartFactor above the
/// slew's least T). Empty where it is no start: spinning ends, or the slew or R_N not clear of the
/// cones.
struct SlewStart {
  PlanningProblem posed;
  Maneuver slew;
  double duration = 0.0;
};
std::optional<SlewStart> eigenaxisStartAt(const PlanningProblem& problem, double twist) {
  SlewStart s{endingAt(problem, pointingAttitude(problem.end_condition, twist)), {}, 0.0};
  PlanningProblem at = s.posed;
  at.end_condition = EndCondition();
  s.duration = at.duration = kEigenaxisStartFactor * eigenaxisBangBangDuration(at);
  if (hasSpinningEnds(problem) || !coneAtEnd(problem, twist).empty()) return std::nullopt;
  s.slew = excursionSlew(at, Vector3::UnitX(), 0.0);
  if (coneClearance(s.posed, s.slew.attitude) < kConeStartClearance) return std::nullopt;
  return s;
}

/// The watch of a free-time solve that matters only if it ends below `least` [s] (`what` names
/// that T): it stops the solve where it no longer can (cannotEndBelow, the rule the fixed-twist
/// recipe stops its own starts by). No stop while `least` is +∞.
constexpr const char* kSurveysLeast = "the survey's least T* [s] so far";
BarrierWatch endingBelow(double least, const std::string& what) {
  return [least, what](const BarrierPoint& point) {
    return cannotEndBelow(point.bound(), least, what);
  };
}

/// A start twist's free-time solve with ψ free from the eigenaxis slew (eigenaxisStartAt): beside
/// the fixed-twist plan's (fromFixedTwistSlew), the survey's other way into the ψ-free basins
/// (measured on seeded requests: each way alone missed the least basin on one request, by 3.7e-3
/// and 3.6e-3 relative on N). Not converged (no solve) where the slew is no start, where the
/// solve does not converge at or below its start's T, and where it is stopped because it can no
/// longer end below `least`, the survey's least T* so far (cannotEndBelow: the survey carries its
/// least answer alone).
TwistStart fromEigenaxisSlew(const PlanningProblem& problem, double twist, double least,
                             SolveContext& context) {
  TwistStart s{twist, {}, std::nullopt};
  const std::optional<SlewStart> start = eigenaxisStartAt(problem, twist);
  if (!start) return s;
  const std::size_t first = context.attempts().size();
  std::optional<PlanResult> freed =
      freeTimeFromPlan(start->posed, start->slew, start->duration, "eigenaxis slew", context,
                       nullptr, StartBarrier::Initial, endingBelow(least, kSurveysLeast));
  if (freed) s.result = std::move(*freed);
  s.result.minimum_time.solves = 1;
  tagStartsAttempts(context, first, &s);
  s.result.attempts = context.attemptsFrom(first);
  return s;
}

/// A start twist's survey answer where the eigenaxis slew is a start (eigenaxisStartAt; else
/// empty): the fixed-twist free-time solve from that slew (ψ fixed: the recipe's first start
/// alone), then one free-time solve with ψ free from its plan; the fixed-twist plan itself where
/// that ψ-free solve does not end at or below it (a start twist's answer is never worse than its
/// own fixed-twist plan). The recipe's other starts at a survey twist (its excursions) cost 60 %
/// of the survey's iterations (measured on seed 41802: 670 of 1130) and are left out.
std::optional<TwistStart> fromFixedTwistSlew(const PlanningProblem& problem, double twist,
                                             double least, SolveContext& context) {
  const std::optional<SlewStart> start = eigenaxisStartAt(problem, twist);
  if (!start) return std::nullopt;
  TwistStart s{twist, {}, std::nullopt};
  const std::size_t first = context.attempts().size();
  PlanningProblem fixed = start->posed;
  fixed.end_condition = EndCondition();
  std::optional<PlanResult> at_twist =
      freeTimeFromPlan(fixed, start->slew, start->duration, "eigenaxis slew", context);
  s.result.minimum_time.solves = 1;
  if (at_twist) {
    const std::optional<std::size_t> fixed_kept = context.keptAttempt();
    std::optional<PlanResult> freed = freeTimeFromPlan(
        start->posed, at_twist->maneuver, at_twist->minimum_duration, "fixed-twist plan", context,
        nullptr, StartBarrier::Initial, endingBelow(least, kSurveysLeast));
    if (!freed) context.restoreKept(fixed_kept);
    s.result = freed ? std::move(*freed) : std::move(*at_twist);
    s.result.minimum_time.solves = 2;
  }
  tagStartsAttempts(context, first, &s);
  s.result.attempts = context.attemptsFrom(first);
  return s;
}

/// The survey grid of a minimum-time pointing request: N / kSurveyCoarsening, at least
/// kSurveyLeastSteps; 0 where that is not below N (no survey: the start twists on N).
constexpr int kSurveyCoarsening = 4, kSurveyLeastSteps = 16;
int surveySteps(const PlanningProblem& problem) {
  const int steps = std::max(kSurveyLeastSteps, problem.steps / kSurveyCoarsening);
  return steps < problem.steps ? steps : 0;
}

/// A grid level's free-time solve starts from the coarser level's T* raised by this: a finer
/// grid's T* lies above the coarser one's (measured on the seeded requests of
/// docs/results/pointing_minimum_time.md: 0.2–0.4 % from N/4 to N), and the solve from a plan at T
/// is accepted at or below that T (freeTimeFromPlan).
constexpr double kLevelStartSlack = 0.02;

/// The free-time plan `coarse` (ψ free, converged on its grid) carried to `level`'s grid: one
/// free-time solve with ψ free from its plan prolonged (prolonged: its rates interpolated in time)
/// at kLevelStartSlack above its T*. Empty where that solve does not converge at or below its
/// start's T, or the coarse plan admits no prolongation.
std::optional<PlanResult> onFinerLevel(const PlanningProblem& level, const PlanResult& coarse,
                                       SolveContext& context) {
  const Matrix3 R_N = coarse.maneuver.attitude.back();
  PlanningProblem on_coarse = endingAt(level, R_N);
  on_coarse.steps = coarse.maneuver.steps();
  on_coarse.duration = coarse.minimum_duration;
  FreeTimeOutcome carried;
  try {
    ReducedProblem np(on_coarse);
    np.setInteriorFromAttitudes(coarse.maneuver.attitude);
    carried.steps = np.current();
  } catch (const StepTooLarge&) {  // the boundary rates admit no step at the coarse h
    return std::nullopt;
  }
  carried.maneuver = coarse.maneuver;
  carried.duration = coarse.minimum_duration;
  const PlanningProblem posed = endingAt(level, R_N);
  Maneuver start;
  start.attitude = prolonged(posed, carried);
  return freeTimeFromPlan(posed, start, (1.0 + kLevelStartSlack) * coarse.minimum_duration,
                          "coarser grid's plan", context);
}

/// The survey's answer `survey` (a converged ψ-free plan on the survey grid) carried to the
/// requested grid through factor-2 levels, ψ free on each (onFinerLevel): a start for N that costs
/// one free-time solve per level instead of the fixed-twist recipe on N. (By 4 at once the solve
/// slid into another basin on one seeded request, 4.4e-5 above; by 2 it reached the recipe's T* on
/// all 16 measured.) Not converged where a level's solve did not.
TwistStart carriedToGrid(const PlanningProblem& problem, const TwistStart& survey,
                         SolveContext& context) {
  TwistStart s{survey.twist, survey.result, std::nullopt};
  const std::size_t first = context.attempts().size();
  int solves = 0;
  while (s.result.converged() && s.result.maneuver.steps() < problem.steps &&
         !context.stopReason()) {
    PlanningProblem level = problem;
    level.steps = std::min(problem.steps, 2 * s.result.maneuver.steps());
    std::optional<PlanResult> next = onFinerLevel(level, s.result, context);
    ++solves;
    if (!next) {
      s.result = PlanResult();
      s.result.termination = context.stopReason().value_or(Termination::NotConverged);
      break;
    }
    s.result = std::move(*next);
  }
  tagStartsAttempts(context, first, &s);
  s.result.attempts = context.attemptsFrom(first);
  s.result.minimum_time.solves = solves;
  return s;
}

/// Every start twist (ψ₀ + 2πi/kPointingStartTwists) solved by `solve`; stops at a cancel or the
/// deadline.
template <typename Solve>
std::vector<TwistStart> overStartTwists(const PlanningProblem& problem, SolveContext& context,
                                        const Solve& solve) {
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  std::vector<TwistStart> starts;
  for (int i = 0; i < kPointingStartTwists && !context.stopReason(); ++i) {
    starts.push_back(
        solve(std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI)));
  }
  return starts;
}

/// The survey on `survey` steps (each start twist by fromFixedTwistSlew, else by `posed`, and by
/// fromEigenaxisSlew), its least T* carried to N (carriedToGrid), and only where that does not
/// converge `recipe` on N at its twist: the coarse answers rank the basins at a quarter of the
/// cost (measured on the seeded requests of docs/results/pointing_minimum_time.md).
template <typename Posed>
std::vector<TwistStart> surveyThenCarried(const PlanningProblem& problem, int survey,
                                          SolveContext& context, const Posed& posed,
                                          const MinimumTimeRecipe& recipe) {
  PlanningProblem coarse = problem;
  coarse.steps = survey;
  const auto survey_posed = posed(coarse);
  double least = std::numeric_limits<double>::infinity();  // the survey's least T* so far
  const auto lowered = [&least](TwistStart s) {
    if (s.result.converged()) least = std::min(least, s.result.minimum_duration);
    return s;
  };
  std::vector<TwistStart> starts = overStartTwists(coarse, context, [&](double twist) {
    std::optional<TwistStart> s = fromFixedTwistSlew(coarse, twist, least, context);
    return lowered(s ? std::move(*s) : survey_posed(twist));
  });
  const std::vector<TwistStart> slews = overStartTwists(coarse, context, [&](double twist) {
    return lowered(fromEigenaxisSlew(coarse, twist, least, context));
  });
  starts.insert(starts.end(), slews.begin(), slews.end());
  const int best = leastDuration(starts);
  if (best < 0 || context.stopReason()) return starts;
  starts.push_back(carriedToGrid(problem, starts[best], context));
  if (!starts.back().result.converged() && !context.stopReason()) {
    const Matrix3& R_N = starts[best].result.maneuver.attitude.back();
    starts.push_back(startAt(problem, twistOf(R_N, problem.end_condition), context, recipe));
  }
  return starts;
}

/// The fixed-twist probes' offset from a ψ-free answer's twist [rad] (onLowerBranch): on the
/// held-out request behind onLowerBranch the lower branch is reached from 0.01–0.03 rad off the
/// answer's twist, not from 5° off.
constexpr double kBranchProbeOffset = 0.01;
/// At most this many rounds of onLowerBranch, each from the last one's answer: the branches can
/// form a staircase (seeded request 4367: the first round's answer 22.0875 s at ψ = 0.728, a third
/// branch 22.0811 s at 0.711).
constexpr int kBranchProbeRounds = 4;

/// The fixed-twist free-time solve on N from the eigenaxis slew at `twist` (its attempts tagged
/// with the twist); empty where the slew is no start there or the solve did not converge. A probe
/// matters only if it ends below `least` [s]: it is stopped where it no longer can
/// (cannotEndBelow). Measured on the minimum-time page's seeded requests: a probe that ends above
/// the answer spent its last ~30 % of iterations there.
std::optional<PlanResult> fixedTwistProbe(const PlanningProblem& problem, double twist,
                                          double least, SolveContext& context) {
  const std::optional<SlewStart> start = eigenaxisStartAt(problem, twist);
  if (!start) return std::nullopt;
  PlanningProblem fixed = start->posed;
  fixed.end_condition = EndCondition();
  const std::size_t first = context.attempts().size();
  std::optional<PlanResult> r =
      freeTimeFromPlan(fixed, start->slew, start->duration, "eigenaxis slew", context, nullptr,
                       StartBarrier::Initial, endingBelow(least, "the answer's T* [s]"));
  context.posedAtTwist(first, twist);
  return r;
}

/// The ψ-free answer `answer` on N against another branch of the fixed-twist T*(ψ) beside it: T*
/// at a fixed twist can have two branches (two switching structures) whose minima over ψ are
/// both KKT points of the ψ-free problem, and the survey's carried answer can end on the upper
/// one. At ψ* ± kBranchProbeOffset the fixed-twist free-time solve from the eigenaxis slew on N;
/// where the lower of the two ends below the answer's T*, one free-time solve with ψ free from
/// its plan, its barrier begun near that KKT point (StartBarrier::NearKktPoint: begun at μ₀ it
/// re-centres onto the answer's branch). That solve's answer where it converged at or below the
/// probe's T (freeTimeFromPlan); else empty. A probe's fixed-twist plan is never the answer: its
/// ψ-stationarity is not a KKT point's.
std::optional<TwistStart> onLowerBranch(const PlanningProblem& problem, const TwistStart& answer,
                                        SolveContext& context) {
  const double twist = twistOf(answer.result.maneuver.attitude.back(), problem.end_condition);
  const std::size_t first = context.attempts().size();
  std::optional<PlanResult> probe;
  double probe_twist = twist;
  for (const double side : {-1.0, 1.0}) {
    const double at = std::remainder(twist + side * kBranchProbeOffset, 2.0 * M_PI);
    const double least = probe ? probe->minimum_duration : answer.result.minimum_duration;
    std::optional<PlanResult> r = fixedTwistProbe(problem, at, least, context);
    if (r && r->minimum_duration < least) {
      probe = std::move(r);
      probe_twist = at;
    }
  }
  if (!probe || context.stopReason()) return std::nullopt;
  TwistStart s{probe_twist, {}, std::nullopt};
  const PlanningProblem posed =
      endingAt(problem, pointingAttitude(problem.end_condition, probe_twist));
  std::optional<PlanResult> freed =
      freeTimeFromPlan(posed, probe->maneuver, probe->minimum_duration, "fixed-twist probe",
                       context, nullptr, StartBarrier::NearKktPoint);
  if (!freed) return std::nullopt;
  s.result = std::move(*freed);
  s.result.minimum_time.solves = 3;
  tagStartsAttempts(context, first, &s);
  s.result.attempts = context.attemptsFrom(first);
  return s;
}

}  // namespace

PlanResult pointingMinimumTime(const PlanningProblem& problem, SolveContext& context,
                               const MinimumTimeRecipe& recipe) {
  const auto posedAt = [&context, &recipe](const PlanningProblem& on) {
    return [at = &on, &context, &recipe](double twist) {
      return startAt(*at, twist, context, recipe);
    };
  };
  const std::size_t first = context.attempts().size();
  std::vector<TwistStart> starts;
  if (const int survey = surveySteps(problem)) {
    starts = surveyThenCarried(problem, survey, context, posedAt, recipe);
  }
  if (leastDuration(starts, problem.steps) < 0 && !context.stopReason()) {
    // No survey, or its answer did not carry to N: every start twist on N.
    std::vector<TwistStart> on_grid = overStartTwists(problem, context, posedAt(problem));
    starts.insert(starts.end(), on_grid.begin(), on_grid.end());
  }
  for (int round = 0; round < kBranchProbeRounds && !context.stopReason(); ++round) {
    const int answer = leastDuration(starts, problem.steps);
    if (answer < 0) break;
    std::optional<TwistStart> lower = onLowerBranch(problem, starts[answer], context);
    if (!lower) break;
    starts.push_back(std::move(*lower));
  }
  if (starts.empty()) {
    PlanResult none;
    none.termination = context.stopReason().value_or(Termination::NotConverged);
    frameMessage(&none, frames::PointingStarts{});
    return none;
  }
  const int kept = leastDuration(starts, problem.steps);
  PlanResult result = starts[kept >= 0 ? kept : lastWithPlan(starts, problem.steps)].result;
  result.minimum_time.solves = 0;  // every start's free-time solves
  for (const TwistStart& s : starts) result.minimum_time.solves += s.result.minimum_time.solves;
  context.restoreKept(kept >= 0 ? starts[kept].kept_attempt : std::nullopt);
  result.attempts = context.attemptsFrom(first);
  summarizePointing(problem, static_cast<int>(starts.size()), &result);
  frameMessage(&result, startsFrame(starts, kept));
  return result;
}

}  // namespace attitude_planner
