#include "planning/drivers/constrained_classes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

/// `problem` in class `homotopy` on `steps` steps.
PlanningProblem pinnedTo(const PlanningProblem& problem, const HomotopyClass& homotopy, int steps) {
  PlanningProblem out = pinnedToClass(problem, homotopy);
  out.steps = steps;
  return out;
}

/// The classes the survey solved to convergence, `first_class` first, their costs there, and its
/// grid (the fewest steps among its class_survey attempts; the requested N if none).
struct SurveyedClasses {
  std::vector<HomotopyClass> classes;
  std::vector<double> costs;  ///< each class's survey cost (NaN: not surveyed on that grid)
  int steps = 0;
  /// The survey's refine margin (NewtonParameters::class_refine_margin: coarse costs reorder on
  /// refinement within it).
  double refine_margin = 0.0;
};

SurveyedClasses surveyedClasses(const ExtremalSummary& survey, const HomotopyClass& first_class,
                                int requested_steps, double refine_margin) {
  SurveyedClasses out{
      {first_class}, {std::numeric_limits<double>::quiet_NaN()}, requested_steps, refine_margin};
  for (const Attempt& a : survey.others) {
    if (a.stage == AttemptStage::ClassSurvey) out.steps = std::min(out.steps, a.steps);
  }
  for (const Attempt& a : survey.others) {
    if (a.termination != Termination::Converged) continue;
    const auto it =
        std::find_if(out.classes.begin(), out.classes.end(),
                     [&](const HomotopyClass& c) { return sameHomotopyClass(c, a.homotopy); });
    const double cost = a.stage == AttemptStage::ClassSurvey && a.steps == out.steps
                            ? a.cost
                            : std::numeric_limits<double>::quiet_NaN();
    if (it == out.classes.end()) {
      out.classes.push_back(a.homotopy);
      out.costs.push_back(cost);
    } else if (std::isnan(out.costs[it - out.classes.begin()])) {
      out.costs[it - out.classes.begin()] = cost;
    }
  }
  return out;
}

/// Whether plan r is better than `best`: it converged and either holds the constraints between
/// the nodes where `best` does not, or holds them as well and costs less. (A plan can meet a
/// cone at every node and still jump across it between two: measured, the nearest lift + 1 extra
/// turn round a cone on the path, 0.9 rad into the cone between nodes at a lower cost.)
bool better(const PlanResult& r, const PlanResult& best) {
  if (!r.converged()) return false;
  if (!best.converged()) return true;
  const double jump = r.max_violation_between_nodes;
  const double best_jump = best.max_violation_between_nodes;
  if (jump > best_jump + kBetweenNodesSlack) return false;
  if (best_jump > jump + kBetweenNodesSlack) return true;
  return r.cost < best.cost;
}

/// Whether every constraint of the request is a cone (no torque bound, norm or rate limit).
bool conesOnly(const PlanningProblem& problem) {
  return !problem.hasTorqueBounds() &&
         std::all_of(problem.constraints.begin(), problem.constraints.end(),
                     [](const PlanningConstraint& c) { return c.isCone(); });
}

/// Whether a converged plan cuts a cone between two nodes by more than the slack.
bool cutsBetweenNodes(const PlanResult& r) {
  return r.converged() && r.max_violation_between_nodes > kBetweenNodesSlack;
}

/// The longest step |log(R_kᵀ R_{k+1})| of a plan [rad].
double longestStepAngle(const Maneuver& plan) {
  double longest = 0.0;
  for (int k = 0; k < plan.steps(); ++k) {
    const Matrix3 step = plan.attitude[k].transpose() * plan.attitude[k + 1];
    longest = std::max(longest, so3::log(step).norm());
  }
  return longest;
}

/// How much longer than a plan's longest step the steps of its re-solve at tightened node bounds
/// may be (the detour round the wider cone), docs/notes/constraints_notes.md "Between nodes".
constexpr double kTightenedDetour = 1.25;

/// `problem` with each cone's node bound tightened by the margin that keeps the cone between
/// nodes over steps up to `step_angle` (requiredConeMargin; a cone's own margin where larger),
/// and that margin (the largest); nothing where a cone's node bound would leave (0, π).
std::optional<std::pair<PlanningProblem, double>> tightenedForSteps(const PlanningProblem& problem,
                                                                    double step_angle) {
  PlanningProblem out = problem;
  double largest = 0.0;
  for (PlanningConstraint& c : out.constraints) {
    if (!c.isCone()) continue;
    c.margin = std::max(c.margin, requiredConeMargin(c, step_angle));
    const double node = c.nodeHalfAngle();
    if (!std::isfinite(c.margin) || !(node > 0.0 && node < M_PI)) return std::nullopt;
    largest = std::max(largest, c.margin);
  }
  return std::make_pair(std::move(out), largest);
}

/// One class's constrained solve, as the extremal's entry.
Attempt classAttempt(const HomotopyClass& homotopy, const PlanResult& r, int steps,
                     AttemptStart start) {
  Attempt a;
  a.stage = AttemptStage::ConstrainedClass;
  a.start = start;
  a.formulation = Formulation::FreeSlacks;
  a.homotopy = homotopy;
  a.steps = steps;
  a.termination = r.termination;
  a.iterations = r.iterations;
  a.cost = r.converged() ? r.cost : std::numeric_limits<double>::quiet_NaN();
  return a;
}

/// Where a class's constrained solve starts: by default from its unconstrained optimum (the
/// survey's plan of it on that grid if there is one); `unconstrained_optimum` hands that optimum
/// in; `constrained_plan` (a plan of the class under the constraints on another grid) starts the
/// interior point itself, so the solve keeps the side of each cone that plan passes.
struct ClassStart {
  const Maneuver* unconstrained_optimum = nullptr;
  const Maneuver* constrained_plan = nullptr;
};

/// The classes' solves and the trail they leave in the context (after `first`'s, which begins
/// at `first_recorded`).
class ClassSearch {
 public:
  ClassSearch(const PlanningProblem& problem, const SolveRequest& options, SolveContext& context,
              const std::vector<ClassPlan>& survey_plans, const HomotopyClass& first_class,
              PlanResult first, std::size_t first_recorded)
      : problem_(problem),
        options_(options),
        context_(context),
        survey_plans_(survey_plans),
        first_recorded_(first_recorded),
        first_iterations_(first.iterations),
        first_attempt_(
            classAttempt(first_class, first, problem.steps, AttemptStart::UnconstrainedOptimum)),
        best_(std::move(first)),
        kept_(context.keptAttempt()) {
    options_.enumerate_classes = false;  // each solve in its own class
    if (cutsBetweenNodes(best_)) cheapest_cut_ = CutPlan{first_class, best_};
  }

  /// One solve of `homotopy` on `steps` steps from `start` (its attempts named constrained_class
  /// where they were the solver's own solve). A grid with no boundary step at its h gives no plan.
  PlanResult solve(const HomotopyClass& homotopy, int steps, const ClassStart& start = {}) {
    return solveProblem(problem_, homotopy, steps, start);
  }

  /// `solve` of `problem` (the request, or the request with tightened cones).
  PlanResult solveProblem(const PlanningProblem& problem, const HomotopyClass& homotopy, int steps,
                          const ClassStart& start) {
    PlanResult r;
    SolveRequest options = options_;
    options.start.unconstrained_optimum = start.unconstrained_optimum;
    if (!start.unconstrained_optimum && !start.constrained_plan) {
      options.start.unconstrained_optimum = surveyPlan(homotopy, steps);
    }
    options.warm_start = start.constrained_plan;
    options.start.from_constrained_plan = start.constrained_plan != nullptr;
    const std::size_t before = context_.attempts().size();
    r = inClass(homotopy, [&] {
      return planAtResolution(pinnedTo(problem, homotopy, steps), options, context_);
    });
    // A solve from a constrained plan runs the interior point alone, which names no extremal.
    if (r.converged() && !r.extremal_summary.known) {
      r.extremal_summary = extremalIn(homotopy, steps);
    }
    // The attempt whose plan r is: its kept one, else its last.
    const std::optional<std::size_t> kept = context_.keptAttempt();
    const std::size_t end = context_.attempts().size();
    if (end > before) last_kept_ = kept && *kept >= before ? *kept : end - 1;
    const AttemptStart from =
        start.constrained_plan ? AttemptStart::PreviousAttempt : AttemptStart::UnconstrainedOptimum;
    tried_.push_back(classAttempt(homotopy, r, steps, from));
    return r;
  }

  /// The unconstrained optimum of `homotopy` on `steps` steps, by Newton from the survey's finest
  /// plan of it (the constraints ignored, as the unconstrained solve ignores them).
  PlanResult unconstrainedOptimum(const HomotopyClass& homotopy, int steps) {
    const PlanningProblem pinned = pinnedTo(problem_, homotopy, steps);
    SolveRequest options = options_;
    Maneuver guess;
    if (const Maneuver* surveyed = finestSurveyPlan(homotopy)) {
      guess = initialGuessOnGrid(*surveyed, pinned);
      options.warm_start = &guess;
    }
    return inClass(homotopy, [&] { return solveWithNewton(pinned, options, context_); });
  }

  /// The cheapest converged plan of `homotopy` under the constraints on `steps` steps, from its
  /// unconstrained optimum there and from a start on each side of the cone that optimum violates
  /// most deeply (coneSideStarts); not converged if none is.
  PlanResult cheapestOnGrid(const HomotopyClass& homotopy, int steps) {
    PlanResult best = solve(homotopy, steps);
    const Maneuver* optimum = surveyPlan(homotopy, steps);
    Maneuver resampled;
    if (!optimum) {
      const Maneuver* finest = finestSurveyPlan(homotopy);
      if (!finest) return best;
      resampled = initialGuessOnGrid(*finest, pinnedTo(problem_, homotopy, steps));
      optimum = &resampled;
    }
    for (const Maneuver& side : coneSideStarts(problem_, *optimum)) {
      if (stopped()) break;
      PlanResult r = solve(homotopy, steps, ClassStart{nullptr, &side});
      if (r.converged() && (!best.converged() || r.cost < best.cost)) best = std::move(r);
    }
    return best;
  }

  /// Keeps r (a plan of `homotopy` on the requested grid) if it is better than the best so far,
  /// and the cheapest plan that cut a cone between nodes (for holdTheCheapestBetweenNodes).
  void offer(const HomotopyClass& homotopy, PlanResult r) {
    if (cutsBetweenNodes(r) && (!cheapest_cut_ || r.cost < cheapest_cut_->plan.cost)) {
      cheapest_cut_ = CutPlan{homotopy, r};
    }
    offerAsIs(std::move(r));
  }

  /// Where the best plan holds the cones between nodes and a cheaper plan cut one (`better`
  /// passed it over for that): the cheaper plan's class re-solved from it at node bounds
  /// tightened so its motion keeps the cones between the nodes too (offerHeldBetweenNodes), so a
  /// coarse grid's cut does not hand the answer to a costlier class.
  void holdTheCheapestBetweenNodes() {
    if (!cheapest_cut_ || !holdsAPlanWithinTheConstraints()) return;
    if (cheapest_cut_->plan.cost >= best_.cost) return;
    const CutPlan cut = *cheapest_cut_;
    offerHeldBetweenNodes(cut.homotopy, cut.plan.maneuver, cut.plan.max_violation_between_nodes);
  }

  /// Keeps r if it is better than the best so far.
  void offerAsIs(PlanResult r) {
    if (!better(r, best_)) return;
    best_ = std::move(r);
    best_tried_ = tried_.size() - 1;
    kept_ = last_kept_;
  }

  /// Whether the best plan converged and holds the constraints between the nodes too.
  bool holdsAPlanWithinTheConstraints() const {
    return best_.converged() && best_.max_violation_between_nodes <= kBetweenNodesSlack;
  }

  /// Whether a plan of this cost could replace the best one (there is no best plan yet, or it
  /// costs more).
  bool couldBeat(double cost) const { return !best_.converged() || cost < best_.cost; }
  bool holdsAPlan() const { return best_.converged(); }

  bool stopped() const { return context_.stopReason().has_value(); }

  /// The best plan with the whole trail, the classes tried in its extremal (the first class's
  /// solve among them where another plan is kept).
  PlanResult finish(const ExtremalSummary& survey, const HomotopyClass& first_class) {
    context_.restoreKept(kept_);
    best_.attempts = context_.attemptsFrom(first_recorded_);
    best_.iterations = first_iterations_ + iterations_;
    ExtremalSummary& extremal = best_.extremal_summary;
    if (firstKept()) extremal.homotopy = first_class;
    extremal.others = survey.others;
    if (!firstKept()) extremal.others.push_back(first_attempt_);
    for (std::size_t i = 0; i < tried_.size(); ++i) {
      if (!best_tried_ || i != *best_tried_) extremal.others.push_back(tried_[i]);
    }
    best_.extremal = describeExtremal(extremal);
    return best_;
  }

  bool firstKept() const { return !best_tried_; }

 private:
  /// A plan that cut a cone between nodes (by `cut`) re-solved from itself, its class pinned, at
  /// node bounds tightened for steps up to kTightenedDetour times its longest (the class keeps
  /// its side of each cone; the plan's own steps fix the margin, which no grid alone does), and
  /// offered with the note of the margin.
  void offerHeldBetweenNodes(const HomotopyClass& homotopy, const Maneuver& plan, double cut) {
    if (stopped()) return;
    const auto tightened = tightenedForSteps(problem_, kTightenedDetour * longestStepAngle(plan));
    if (!tightened) return;
    PlanResult held =
        solveProblem(tightened->first, homotopy, problem_.steps, ClassStart{nullptr, &plan});
    if (!held.converged()) return;
    addNote(&held, notes::ConesTightenedBetweenNodes{cut, tightened->second});
    offerAsIs(std::move(held));
  }

  /// `solve()` in the context's scope of `homotopy`, its iterations counted; a grid with no
  /// boundary step at its h gives no plan.
  template <class Solve>
  PlanResult inClass(const HomotopyClass& homotopy, Solve&& solve) {
    PlanResult r;
    r.termination = Termination::NotConverged;
    try {
      const SolveContext::Scope scope(context_, AttemptStage::ConstrainedClass, homotopy);
      r = solve();
    } catch (const StepTooLarge& e) {
      recordReason(&r, e.what());
    }
    iterations_ += r.iterations;
    return r;
  }

  /// The extremal of a plan of `homotopy` on `steps` steps: its class's lift.
  ExtremalSummary extremalIn(const HomotopyClass& homotopy, int steps) const {
    const PlanningProblem pinned = pinnedTo(problem_, homotopy, steps);
    const std::vector<Lift> lifts = nearestLifts(pinned, ReducedProblem(pinned));
    return extremalOf(lifts[homotopy.long_way ? 1 : 0]);
  }

  const Maneuver* surveyPlan(const HomotopyClass& homotopy, int steps) const {
    const auto surveyed =
        std::find_if(survey_plans_.begin(), survey_plans_.end(), [&](const ClassPlan& c) {
          return sameHomotopyClass(c.homotopy, homotopy) && c.plan.steps() == steps;
        });
    return surveyed != survey_plans_.end() ? &surveyed->plan : nullptr;
  }

  const Maneuver* finestSurveyPlan(const HomotopyClass& homotopy) const {
    const Maneuver* finest = nullptr;
    for (const ClassPlan& c : survey_plans_) {
      if (!sameHomotopyClass(c.homotopy, homotopy)) continue;
      if (!finest || c.plan.steps() > finest->steps()) finest = &c.plan;
    }
    return finest;
  }

  const PlanningProblem& problem_;
  SolveRequest options_;
  SolveContext& context_;
  const std::vector<ClassPlan>& survey_plans_;
  std::size_t first_recorded_;
  std::vector<Attempt> tried_;
  int first_iterations_ = 0;
  Attempt first_attempt_;
  PlanResult best_;
  std::optional<std::size_t> kept_;        ///< the best plan's attempt in the context's trail
  std::optional<std::size_t> last_kept_;   ///< the last solve's
  std::optional<std::size_t> best_tried_;  ///< empty: `first` is kept
  struct CutPlan {
    HomotopyClass homotopy;
    PlanResult plan;
  };
  std::optional<CutPlan> cheapest_cut_;  ///< the cheapest converged plan that cut a cone
  int iterations_ = 0;
};

bool listed(const std::vector<HomotopyClass>& classes, const HomotopyClass& c) {
  return std::any_of(classes.begin(), classes.end(),
                     [&](const HomotopyClass& d) { return sameHomotopyClass(c, d); });
}

/// Under torque or rate bounds, the best coarse plan's class `c` on the requested grid: from its
/// coarse plan under the bounds, resampled (a continuation of a plan that holds them, which the
/// unconstrained optimum, outside them, is not), then, where that gives no plan and `c` is another
/// class than the first, from its unconstrained optimum (the first class's solve from its optimum
/// is the one that failed). A cold start's "infeasible" near the least duration is local: measured
/// on the held-out seed-47 spinning suite's #45, the probe 1 % below T* = 1.781 s ended
/// "infeasible" on N = 64 with the class's plan under the bounds on N = 16 in hand (whether it did
/// flipped with an ulp of the probe's T); from that plan it converges, and T* falls to 1.4998 s.
/// The coarse plan comes first because the cold start near the least duration runs to its limits
/// before it (docs/results/near_minimum_time_cones.md's 240 requests at 1.05 T*: 8 answers sooner,
/// 16,542 -> 14,520 iterations, every cost the same).
void carryUnderBounds(ClassSearch& search, const HomotopyClass& c, const Maneuver& coarse_plan,
                      const HomotopyClass& first_class, int steps) {
  search.offer(c, search.solve(c, steps, ClassStart{nullptr, &coarse_plan}));
  if (search.holdsAPlan() || search.stopped() || sameHomotopyClass(c, first_class)) return;
  search.offer(c, search.solve(c, steps));
}

/// The surveyed classes' plans under the constraints on the survey grid (converged ones, in the
/// survey's order).
using CoarsePlans = std::vector<std::pair<HomotopyClass, PlanResult>>;

/// With cones only, each surveyed class's cheapest plan on the survey grid (cheapestOnGrid).
CoarsePlans cheapestPlansOnSurveyGrid(ClassSearch& search, const SurveyedClasses& surveyed) {
  CoarsePlans coarse;
  for (const HomotopyClass& c : surveyed.classes) {
    if (search.stopped()) break;
    PlanResult r = search.cheapestOnGrid(c, surveyed.steps);
    if (r.converged()) coarse.emplace_back(c, std::move(r));
  }
  return coarse;
}

/// The surveyed classes in order of their survey cost, those without one (NaN) first.
std::vector<std::size_t> bySurveyCost(const SurveyedClasses& surveyed) {
  std::vector<std::size_t> order(surveyed.classes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto key = [&](std::size_t i) {
    const double cost = surveyed.costs[i];
    return std::isnan(cost) ? -std::numeric_limits<double>::infinity() : cost;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  return order;
}

/// Whether a class of this survey cost (its unconstrained optimum on the survey grid) is not
/// expected to beat `best`, a plan under the constraints there: the constraints only add to a
/// class's cost from its own optimum (the rule of solveClassesThatCouldBeatIt, on one grid: no
/// refine margin). A gate, not a bound: a solve pinned to a class can slide to another lift, and
/// `better` prefers a plan that holds the cones between nodes to a cheaper one that does not.
bool cannotBeatOnTheSurveyGrid(double survey_cost, const PlanResult* best) {
  return best && !std::isnan(survey_cost) && survey_cost >= best->cost;
}

/// Under torque or rate bounds, the surveyed classes under the constraints on the survey grid, in
/// order of their survey cost until a plan in hand is cheaper than the next class's unconstrained
/// optimum (cannotBeatOnTheSurveyGrid): near the least duration most classes end without a plan
/// after some hundreds of iterations each (docs/results/near_minimum_time_cones.md, "Session
/// 65"), and the ones skipped could not have been carried. Returned in the survey's order, as
/// every class's plan was.
CoarsePlans plansUnderBoundsOnSurveyGrid(ClassSearch& search, const SurveyedClasses& surveyed) {
  std::vector<std::optional<PlanResult>> plans(surveyed.classes.size());
  const PlanResult* best = nullptr;
  for (std::size_t i : bySurveyCost(surveyed)) {
    if (search.stopped() || cannotBeatOnTheSurveyGrid(surveyed.costs[i], best)) break;
    PlanResult r = search.solve(surveyed.classes[i], surveyed.steps);
    if (!r.converged()) continue;
    plans[i] = std::move(r);
    if (!best || better(*plans[i], *best)) best = &*plans[i];
  }
  CoarsePlans coarse;
  for (std::size_t i = 0; i < plans.size(); ++i) {
    if (plans[i]) coarse.emplace_back(surveyed.classes[i], std::move(*plans[i]));
  }
  return coarse;
}

/// Where the first class ended without a plan on the requested grid: every surveyed class under
/// the constraints on the survey grid, then carried to the requested grid. With cones only, each
/// class's cheapest plan there (cheapestOnGrid) and the converged ones carried in order of their
/// cost, each from its own coarse plan (a class's plan on a coarse grid says which side of each
/// cone it passes, which its unconstrained optimum does not: the first class's solve from that
/// optimum is the one that failed), until one converges within the constraints between the nodes
/// too. Under torque or rate bounds, the best coarse plan's class alone (each further solve there
/// runs to its limit near the least duration): from its coarse plan, and where that gives no plan
/// and it is another class, from its unconstrained optimum (carryUnderBounds). On the
/// requested grid already (no coarser survey), each class's solve is its answer. Returns the
/// classes solved on the requested grid.
std::vector<HomotopyClass> carryFromSurveyGrid(ClassSearch& search, const SurveyedClasses& surveyed,
                                               const HomotopyClass& first_class, int steps,
                                               bool cones_only) {
  std::vector<HomotopyClass> solved;
  if (surveyed.steps >= steps) {
    for (const HomotopyClass& c : surveyed.classes) {
      if (search.stopped()) break;
      if (sameHomotopyClass(c, first_class)) continue;  // `first` is that solve
      search.offer(c, search.solve(c, steps));
      solved.push_back(c);
    }
    return solved;
  }
  CoarsePlans coarse = cones_only ? cheapestPlansOnSurveyGrid(search, surveyed)
                                  : plansUnderBoundsOnSurveyGrid(search, surveyed);
  std::stable_sort(coarse.begin(), coarse.end(), [&](const auto& a, const auto& b) {
    return cones_only ? a.second.cost < b.second.cost : better(a.second, b.second);
  });
  for (const auto& [c, plan] : coarse) {
    if (search.stopped() || search.holdsAPlanWithinTheConstraints()) break;
    if (!cones_only) {
      carryUnderBounds(search, c, plan.maneuver, first_class, steps);
      solved.push_back(c);
      break;
    }
    search.offer(c, search.solve(c, steps, ClassStart{nullptr, &plan.maneuver}));
    solved.push_back(c);
  }
  return solved;
}

/// Whether a cost ratio is within the class survey's refine margin. NaN: not within.
bool withinSurveyMargin(const SurveyedClasses& surveyed, double ratio) {
  return ratio <= 1 + surveyed.refine_margin;
}

/// Where the first class converged at a cost the constraints raised beyond the survey's margin
/// (measured on docs/results/keep_out_grids.md's suite: 1.00–1.75 times the unconstrained optimum
/// where the first plan was the class's best, 27–733 where it was not): the class's cheapest plan
/// under the constraints on the survey grid (on twice as many steps while a coarser grid's solves
/// end without a plan, below the requested grid) and, if its effort h·cost is below the first
/// plan's, the class solved once more on the requested grid from it. A finer grid's optimum in one
/// basin costs no more than a coarse one's (the coarse grid holds the cones at fewer nodes, and its
/// discretization costs more: measured, h·cost falls with N on every request of that page whose
/// answer keeps its basin), so a first plan above it sits in a costlier basin, one its start from
/// the unconstrained optimum, which crosses a cone, led it into.
/// `whatever_it_costs`: the class is solved from the coarse plan however the two compare (a first
/// plan whose basin the fallback formulation chose, fromTheElasticFallback: on the survey grid
/// the paper scheme's discretization alone can outweigh a basin's difference).
void retryFromItsCoarsePlan(ClassSearch& search, const HomotopyClass& first_class,
                            double first_cost, int coarse_steps, int steps,
                            bool whatever_it_costs) {
  for (int coarse = coarse_steps; coarse < steps && !search.stopped(); coarse *= 2) {
    const PlanResult plan = search.cheapestOnGrid(first_class, coarse);
    if (!plan.converged()) continue;
    if (search.stopped()) return;
    if (!whatever_it_costs && plan.cost / coarse >= first_cost / steps) return;
    search.offer(first_class,
                 search.solve(first_class, steps, ClassStart{nullptr, &plan.maneuver}));
    return;
  }
}

/// Whether the first class's plan on `steps` came from the ℓ1-elastic formulation, the interior
/// point's fallback where the free-slacks one ended without a plan: then the fallback's path, not
/// the start, chose the plan's basin, e.g. the side of a cone it passes (a keep-out slew at
/// N = 256 alone passing on the side that costs 16 % more: docs/results/keep_out_grids_6565.md).
bool fromTheElasticFallback(const SolveContext& context, std::size_t first_recorded, int steps) {
  const std::vector<Attempt>& trail = context.attempts();
  for (std::size_t i = trail.size(); i-- > first_recorded;) {
    const Attempt& a = trail[i];
    if (a.steps != steps || a.formulation == Formulation::Unconstrained) continue;
    return a.termination == Termination::Converged && a.formulation == Formulation::Elastic;
  }
  return false;
}

/// Whether class i of the survey could beat a plan that cost `rise` times its class's
/// unconstrained optimum: its survey cost is within the survey's own refine margin (coarse costs
/// reorder on refinement within it, NewtonParameters::class_refine_margin) of the first class's
/// survey cost raised by the constraints as much. Unknown costs: it could.
bool couldBeatOnTheSurvey(const SurveyedClasses& surveyed, std::size_t i, double rise) {
  const double own = surveyed.costs[i];
  const double first = surveyed.costs.front();
  if (std::isnan(own) || std::isnan(first) || !std::isfinite(rise)) return true;
  return withinSurveyMargin(surveyed, own / (first * rise));
}

/// Once a plan is in hand, every other surveyed class whose unconstrained optimum on the
/// requested grid costs less than it is solved under the constraints too (from that optimum):
/// the constraints only add to a class's cost from its own optimum, so a class whose
/// unconstrained optimum costs more cannot beat the plan, and is not solved under them. A class
/// whose survey cost is beyond the survey's margin of the first class's, raised by `rise` (the
/// best plan's cost over its class's unconstrained optimum), is not solved at all.
void solveClassesThatCouldBeatIt(ClassSearch& search, const SurveyedClasses& surveyed,
                                 const std::vector<HomotopyClass>& solved, double rise, int steps) {
  for (std::size_t i = 0; i < surveyed.classes.size(); ++i) {
    const HomotopyClass& c = surveyed.classes[i];
    if (search.stopped() || !search.holdsAPlan()) break;
    if (listed(solved, c) || !couldBeatOnTheSurvey(surveyed, i, rise)) continue;
    const PlanResult optimum = search.unconstrainedOptimum(c, steps);
    if (!optimum.converged() || !search.couldBeat(optimum.cost)) continue;
    search.offer(c, search.solve(c, steps, ClassStart{&optimum.maneuver, nullptr}));
  }
}

}  // namespace

PlanResult cheapestConstrainedClass(const PlanningProblem& problem, const SolveRequest& options,
                                    SolveContext& context, const ExtremalSummary& survey,
                                    const std::vector<ClassPlan>& survey_plans, PlanResult first,
                                    double unconstrained_cost, std::size_t first_recorded) {
  // Under torque or rate bounds a converged first class answers: there the constraints' rise
  // over the unconstrained optimum measures the bounds, not the basin, and the other classes'
  // solves near the least duration run to their limits (measured, min_time_keep_out.yaml's
  // bounded minimum effort at 1.02 T*: 110 -> 3,087 iterations for the same plan).
  if (first.converged() && !conesOnly(problem)) return first;
  const HomotopyClass first_class = survey.known ? survey.homotopy : homotopyClassOf(problem);
  const SurveyedClasses surveyed = surveyedClasses(survey, first_class, problem.steps,
                                                   options.advanced.newton.class_refine_margin);
  const bool alone = surveyed.classes.size() < 2;
  if (alone && (surveyed.steps >= problem.steps || !conesOnly(problem))) return first;
  const std::vector<MessageClause> first_said = first.clauses;
  const bool first_converged = first.converged();
  const bool from_fallback =
      first_converged && fromTheElasticFallback(context, first_recorded, problem.steps);
  const double first_cost = first.cost;
  ClassSearch search(problem, options, context, survey_plans, first_class, std::move(first),
                     first_recorded);
  std::vector<HomotopyClass> solved{first_class};
  // How much the constraints raised the first class's cost from its unconstrained optimum.
  const double first_rise = first_cost / unconstrained_cost;
  if (first_converged && surveyed.steps < problem.steps &&
      (from_fallback || !withinSurveyMargin(surveyed, first_rise))) {
    retryFromItsCoarsePlan(search, first_class, first_cost, surveyed.steps, problem.steps,
                           from_fallback);
  } else if (!first_converged) {
    const std::vector<HomotopyClass> carried =
        carryFromSurveyGrid(search, surveyed, first_class, problem.steps, conesOnly(problem));
    solved.insert(solved.end(), carried.begin(), carried.end());
  }
  const double rise =
      search.firstKept() && first_converged ? first_rise : std::numeric_limits<double>::infinity();
  if (conesOnly(problem)) {
    solveClassesThatCouldBeatIt(search, surveyed, solved, rise, problem.steps);
    search.holdTheCheapestBetweenNodes();
  }
  const bool first_kept = search.firstKept();
  PlanResult result = search.finish(survey, first_class);
  if (!first_kept) {
    addNote(&result, notes::CheapestClass{first_said});
  }
  return result;
}

}  // namespace attitude_planner
