// The free-time recipe: one minimum-time solve on one grid, each stage behind a named gate (the
// method itself is interior_point/free_time_solver.cpp, the barrier problem it solves):
// - the grid posed at the start's T, refused where a cone fails at a node no iterate moves;
// - the attempts (kFreeTimeRecipe), each from the same start: the start as the raise places it
//   (placeStart: raised inside, or elastic at its own T past a bounded raise), then, where
//   elasticStartEndedShort holds, the start raised inside alone; a start the raise cannot place
//   ends the recipe (the answer before it stands);
// - the second-order check of a converged end (checkSecondOrder).
#include "planning/drivers/free_time_recipe.hpp"

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

namespace {

/// The start every attempt begins from, as posed on the grid.
struct Start {
  ReducedProblem::StepVectors steps;
  double h = 0.0;
  Matrix3 end;  ///< R_N (a pointing end's twist moves it)
};

/// Back at the start (R_N where the twist started, then its h, then its steps).
void returnTo(const Start& start, ReducedProblem& np) {
  np.setCurrentWithFinalAttitude(start.steps, start.end);
  np.setTimeStep(start.h);
  np.setCurrent(start.steps);
}

/// h raised for the start; false (h unchanged) where the boundary rates admit no step at it.
bool raisedTo(ReducedProblem& np, double h) {
  try {
    np.setTimeStep(h);
    return true;
  } catch (const StepTooLarge&) {
    return false;
  }
}

/// The gate of an unbounded raise, StartRaise::UntilInside where it applies: rest to rest,
/// without wheels, a raise of h at fixed attitudes scales every row that moves with h down
/// (torques like 1/h², rates like 1/h), so it reaches a strictly feasible start however far
/// outside the start's own T is. (A wheel's momentum keeps its initial value; with spinning ends
/// an end torque carries the boundary momentum: largest_start_raise.)
bool raisesUntilInside(const PlanningProblem& problem, StartRaise raise) {
  return raise == StartRaise::UntilInside && problem.initial_velocity.isZero(0.0) &&
         problem.final_velocity.isZero(0.0) && !problem.reaction_wheels.present();
}

/// Empty where every cone holds strictly at the start's attitudes, else why not (raising T does
/// not move an attitude, so no raise can help).
std::string conesBeforeRaise(const FreeTimeProblem& solver) {
  const double cone_value = solver.smallestValue(false);
  if (cone_value > 0) return "";
  std::ostringstream why;
  why << "the start's attitudes violate a cone (smallest value " << cone_value
      << "; raising T does not move them)";
  return why.str();
}

/// Empty where every cone still holds strictly at the raised h, else why not: with spinning
/// ends h moves R_{N−1} of paper and variational (ReducedProblem::nodePath), a cone's row where
/// a pointing end's twist makes it one.
std::string conesAfterRaise(const FreeTimeProblem& solver) {
  const double cone_value = solver.smallestValue(false);
  if (cone_value > 0) return "";
  std::ostringstream why;
  why << "raising T for the start moved an attitude the boundary rate fixes into a cone "
         "(smallest value "
      << cone_value << ")";
  return why.str();
}

/// Places the start and begins the solve there; empty where placed, else why not. h is raised
/// until every constraint that moves with h holds with the start margin. Where `elastic` allows,
/// a raise past largest_start_raise (unless raisesUntilInside), or one to an h without a boundary
/// step, gives way to the elastic start at the start's own T: every constraint that moves with h
/// ℓ1-elastic.
std::string placeStart(const PlanningProblem& problem, ReducedProblem& np, FreeTimeProblem& solver,
                       const InteriorPointParameters& p, StartRaise raise, bool elastic) {
  if (std::string outside = conesBeforeRaise(solver); !outside.empty()) return outside;
  const Start start{np.current(), np.timeStep(), np.finalAttitude()};
  const auto startElastic = [&] {
    np.setTimeStep(start.h);
    np.setCurrent(start.steps);
    solver.beginAt(true);
    return std::string();
  };
  for (int i = 0; i < p.max_start_growths; ++i) {
    if (solver.smallestValue(true) >= p.start_margin) {
      solver.beginAt(false);
      return conesAfterRaise(solver);
    }
    const double raised = np.timeStep() * p.start_growth;
    if (elastic && !raisesUntilInside(problem, raise) && raised > p.largest_start_raise * start.h) {
      return startElastic();
    }
    if (!raisedTo(np, raised)) {
      if (elastic) return startElastic();
      return "no strictly feasible start: at T = " + std::to_string(raised * np.steps()) +
             " s the boundary rates admit no step before the constraints hold";
    }
  }
  return "no strictly feasible start: the constraints still fail at " +
         std::to_string(std::pow(p.start_growth, p.max_start_growths)) +
         " times the start's duration";
}

/// The second-order check at a converged end (FreeTimeOutcome::second_order_sufficient): the
/// condensed barrier Hessian factors without a shift. Where it does not, its least eigenpair from
/// the dense matrix (n ≤ a few hundred at the start grid; once per converged solve, and only
/// there) gives the direction of negative curvature over δ, the `n` node unknowns.
void checkSecondOrder(const FreeTimeProblem& solver, int n, FreeTimeOutcome* out) {
  const bool definite = solver.barrierHessianDefinite();
  out->second_order_sufficient = definite;
  if (definite) return;
  const std::optional<LeastEigenpair> least = solver.barrierHessianLeastEigenpair();
  if (!least) return;
  out->least_curvature = least->value / least->scale;
  const Eigen::VectorXd v = least->vector.head(n);
  Eigen::Index at = 0;
  v.cwiseAbs().maxCoeff(&at);
  if (v(at) != 0) out->negative_curvature = v / v(at);  // max |δ_j| = 1, that entry positive
}

/// The gate of the retry: the start placed elastic ended short of a KKT point.
bool elasticStartEndedShort(const FreeTimeOutcome& first) {
  return first.termination == Termination::NotConverged && first.elastic_start;
}

/// One attempt: whether its start may be placed elastic, and its gate on the answer before it.
struct FreeTimeAttempt {
  bool elastic;
  bool (*when)(const FreeTimeOutcome& before);
};

/// The attempts in order: the start as the raise places it; then, where the elastic start ended
/// short, the same start raised inside alone. A closed gate ends the recipe.
constexpr FreeTimeAttempt kFreeTimeRecipe[] = {
    {true, nullptr},
    {false, elasticStartEndedShort},
};

}  // namespace

std::string freeTimeUnsupported(const PlanningProblem&) {
  return "";
}

FreeTimeOutcome solveFreeTime(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double start_duration, double tolerance, int max_iterations,
                              SolveContext& context, const BarrierWatch& watch,
                              ElasticBarrier elastic_barrier, StartBarrier start_barrier,
                              StartRaise start_raise, const FreeTimeScale& scale) {
  PlanningProblem at = endingAt(problem, attitudes.back());  // a pointing start's own twist
  at.duration = start_duration;
  FreeTimeOutcome failed;
  failed.termination = Termination::NotConverged;
  const InteriorPointParameters& parameters = context.options().advanced.interior_point;
  try {
    ReducedProblem np(at);
    np.setInteriorFromAttitudes(attitudes);
    // R_0, R_N and, where the boundary data fix them, R_1, R_{N−1}: no iterate moves them.
    // A free twist moves R_{N−1} and R_N: their cones are rows then (a start outside them is
    // refused by placeStart).
    const std::string fixed =
        np.hasTwist() ? fixedNodeConeViolation(problem, np, {0, 1})
                      : fixedNodeConeViolation(problem, np, {0, 1, np.steps() - 1, np.steps()});
    if (!fixed.empty()) {
      recordVerdict(&failed, verdicts::FreeTimeConeAtFixedNode{fixed});
      return failed;
    }
    const StageConstraints constraints = buildStageConstraints(problem);
    const Start start{np.current(), np.timeStep(), np.finalAttitude()};
    std::optional<FreeTimeOutcome> answer;
    for (const FreeTimeAttempt& attempt : kFreeTimeRecipe) {
      if (answer && !attempt.when(*answer)) break;
      if (answer) returnTo(start, np);
      const std::unique_ptr<FreeTimeProblem> solver = makeFreeTimeProblem(
          problem, &np, constraints, parameters, elastic_barrier, start_barrier, scale);
      const std::string outside =
          placeStart(problem, np, *solver, parameters, start_raise, attempt.elastic);
      if (!outside.empty()) {
        if (answer) break;
        recordVerdict(&failed, verdicts::NoStrictlyFeasibleStart{outside});
        return failed;
      }
      answer = solver->run(tolerance, max_iterations, context, watch);
      if (answer->termination == Termination::Converged) {
        checkSecondOrder(*solver, np.unknowns(), &*answer);
      }
    }
    return *answer;
  } catch (const StepTooLarge& e) {
    recordVerdict(&failed, verdicts::NoBoundaryStep{e.what(), true});
    return failed;
  }
}

FreeTimeScale freeTimeScaleOf(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double duration) {
  PlanningProblem at = endingAt(problem, attitudes.back());
  at.duration = duration;
  try {
    ReducedProblem np(at);
    np.setInteriorFromAttitudes(attitudes);
    const double cost = np.cost(np.current());
    if (std::isfinite(cost)) return {duration, cost};
  } catch (const StepTooLarge&) {  // no step at this T: no scale to share
  }
  return {};
}

FreeTimeOutcome solveFreeTime(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double start_duration, double tolerance, int max_iterations) {
  SolveContext context{SolverOptions{}};
  FreeTimeOutcome outcome =
      solveFreeTime(problem, attitudes, start_duration, tolerance, max_iterations, context);
  outcome.iterations = context.iterations();  // both runs' where the start was raised inside
  return outcome;
}

}  // namespace attitude_planner
