#include "planning/drivers/constrained_classes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

namespace {

/// `problem` in class `homotopy` on `steps` steps.
PlanningProblem pinnedTo(const PlanningProblem& problem, const HomotopyClass& homotopy, int steps) {
  PlanningProblem out = pinnedToClass(problem, homotopy);
  out.steps = steps;
  return out;
}

/// The classes the survey solved to convergence, `first_class` first, and its grid (the fewest
/// steps among its class_survey attempts; the requested N if none).
struct SurveyedClasses {
  std::vector<HomotopyClass> classes;
  int steps = 0;
};

SurveyedClasses surveyedClasses(const ExtremalSummary& survey, const HomotopyClass& first_class,
                                int requested_steps) {
  SurveyedClasses out{{first_class}, requested_steps};
  for (const Attempt& a : survey.others) {
    if (a.stage == AttemptStage::ClassSurvey) out.steps = std::min(out.steps, a.steps);
    if (a.termination != Termination::Converged) continue;
    const bool listed =
        std::any_of(out.classes.begin(), out.classes.end(),
                    [&](const HomotopyClass& c) { return sameHomotopyClass(c, a.homotopy); });
    if (!listed) out.classes.push_back(a.homotopy);
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

/// One class's constrained solve, as the extremal's entry.
Attempt classAttempt(const HomotopyClass& homotopy, const PlanResult& r, int steps) {
  Attempt a;
  a.stage = AttemptStage::ConstrainedClass;
  a.start = AttemptStart::UnconstrainedOptimum;
  a.formulation = Formulation::FreeSlacks;
  a.homotopy = homotopy;
  a.steps = steps;
  a.termination = r.termination;
  a.iterations = r.iterations;
  a.cost = r.converged() ? r.cost : std::numeric_limits<double>::quiet_NaN();
  return a;
}

/// The classes' solves and the trail they leave in the context (after `first`'s, which begins
/// at `first_recorded`).
class ClassSearch {
 public:
  ClassSearch(const PlanningProblem& problem, const SolverOptions& options, SolveContext& context,
              const std::vector<ClassPlan>& survey_plans, PlanResult first,
              std::size_t first_recorded)
      : problem_(problem),
        options_(options),
        context_(context),
        survey_plans_(survey_plans),
        first_recorded_(first_recorded),
        first_iterations_(first.iterations),
        best_(std::move(first)),
        kept_(context.keptAttempt()) {
    options_.enumerate_classes = false;  // each solve in its own class
  }

  /// One solve of `homotopy` on `steps` steps, from the survey's plan of it on that grid if there
  /// is one (its attempts named constrained_class where they were the solver's own solve). A grid
  /// with no boundary step at its h gives no plan.
  PlanResult solve(const HomotopyClass& homotopy, int steps) {
    PlanResult r;
    r.termination = Termination::NotConverged;
    SolverOptions options = options_;
    const auto surveyed =
        std::find_if(survey_plans_.begin(), survey_plans_.end(), [&](const ClassPlan& c) {
          return sameHomotopyClass(c.homotopy, homotopy) && c.plan.steps() == steps;
        });
    options.unconstrained_optimum = surveyed != survey_plans_.end() ? &surveyed->plan : nullptr;
    const std::size_t before = context_.attempts().size();
    try {
      const SolveContext::Scope scope(context_, AttemptStage::ConstrainedClass, homotopy);
      r = planAtResolution(pinnedTo(problem_, homotopy, steps), options, context_);
    } catch (const StepTooLarge& e) {
      recordReason(&r, e.what());
    }
    iterations_ += r.iterations;
    // The attempt whose plan r is: its kept one, else its last.
    const std::optional<std::size_t> kept = context_.keptAttempt();
    const std::size_t end = context_.attempts().size();
    if (end > before) last_kept_ = kept && *kept >= before ? *kept : end - 1;
    tried_.push_back(classAttempt(homotopy, r, steps));
    return r;
  }

  /// Keeps r (a plan on the requested grid) if it is better than the best so far.
  void offer(PlanResult r) {
    if (!better(r, best_)) return;
    best_ = std::move(r);
    best_tried_ = tried_.size() - 1;
    kept_ = last_kept_;
  }

  bool stopped() const { return context_.stopReason().has_value(); }

  /// The best plan with the whole trail, the classes tried in its extremal.
  PlanResult finish(const ExtremalSummary& survey, const HomotopyClass& first_class) {
    context_.restoreKept(kept_);
    best_.attempts = context_.attemptsFrom(first_recorded_);
    best_.iterations = first_iterations_ + iterations_;
    ExtremalSummary& extremal = best_.extremal_summary;
    if (firstKept()) extremal.homotopy = first_class;
    extremal.others = survey.others;
    for (std::size_t i = 0; i < tried_.size(); ++i) {
      if (!best_tried_ || i != *best_tried_) extremal.others.push_back(tried_[i]);
    }
    best_.extremal = describeExtremal(extremal);
    return best_;
  }

  bool firstKept() const { return !best_tried_; }

 private:
  const PlanningProblem& problem_;
  SolverOptions options_;
  SolveContext& context_;
  const std::vector<ClassPlan>& survey_plans_;
  std::size_t first_recorded_;
  std::vector<Attempt> tried_;
  int first_iterations_ = 0;
  PlanResult best_;
  std::optional<std::size_t> kept_;        ///< the best plan's attempt in the context's trail
  std::optional<std::size_t> last_kept_;   ///< the last solve's
  std::optional<std::size_t> best_tried_;  ///< empty: `first` is kept
  int iterations_ = 0;
};

}  // namespace

PlanResult cheapestConstrainedClass(const PlanningProblem& problem, const SolverOptions& options,
                                    SolveContext& context, const ExtremalSummary& survey,
                                    const std::vector<ClassPlan>& survey_plans, PlanResult first,
                                    std::size_t first_recorded) {
  // A class that converged answers: solving the others costs more than the whole request on
  // a constrained scene (measured, min_time_keep_out.yaml at N = 128 and 1.05 T*: 9 → 69 ms, the
  // other classes infeasible on the survey grid after hundreds of iterations) for a cheaper plan
  // seen in none of 8 seeded cases (docs/results/extremal_classes.md).
  if (first.converged()) return first;
  const HomotopyClass first_class = survey.known ? survey.homotopy : homotopyClassOf(problem);
  const SurveyedClasses surveyed = surveyedClasses(survey, first_class, problem.steps);
  if (surveyed.classes.size() < 2) return first;
  const std::vector<MessageClause> first_said = first.clauses;
  ClassSearch search(problem, options, context, survey_plans, std::move(first), first_recorded);
  const bool on_requested_grid = surveyed.steps >= problem.steps;
  std::optional<HomotopyClass> cheapest;  // on the survey grid
  PlanResult cheapest_plan;
  for (const HomotopyClass& c : surveyed.classes) {
    if (search.stopped()) break;
    if (on_requested_grid && sameHomotopyClass(c, first_class)) continue;  // `first` is that solve
    PlanResult r = search.solve(c, on_requested_grid ? problem.steps : surveyed.steps);
    if (on_requested_grid) {
      search.offer(std::move(r));
    } else if (!cheapest || better(r, cheapest_plan)) {
      cheapest = c;
      cheapest_plan = std::move(r);
    }
  }
  const bool refine = !on_requested_grid && cheapest && cheapest_plan.converged() &&
                      !sameHomotopyClass(*cheapest, first_class) && !search.stopped();
  if (refine) search.offer(search.solve(*cheapest, problem.steps));
  const bool first_kept = search.firstKept();
  PlanResult result = search.finish(survey, first_class);
  if (!first_kept) {
    addNote(&result, notes::CheapestClass{first_said});
  }
  return result;
}

}  // namespace attitude_planner
