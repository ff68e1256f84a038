// One Termination per result, per-level progress as data, reports of any length.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planner.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/problem/message_notes.hpp"
#include "tool_runner.hpp"

using namespace attitude_planner;

namespace {

PlanningProblem seedRestToRest(int N) {
  PlanningProblem p = loadScene(std::string(AP_SOURCE_DIR) + "/scenes/rest_to_rest.yaml").problem;
  p.steps = N;
  return p;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(Termination, EveryValueHasADistinctName) {
  const Termination all[] = {Termination::Converged,   Termination::NotConverged,
                             Termination::Infeasible,  Termination::StepTooLarge,
                             Termination::TimedOut,    Termination::Cancelled,
                             Termination::InvalidInput};
  std::set<std::string> names;
  for (Termination t : all) names.insert(terminationName(t));
  EXPECT_EQ(names.size(), std::size(all));
  EXPECT_EQ(terminationName(Termination::Converged), "converged");
  EXPECT_EQ(terminationName(Termination::TimedOut), "timed_out");
}

TEST(Termination, ConvergedSolveListsItsGridLevelsCoarsestFirst) {
  SolverOptions one_class;  // one solve's levels (the class survey: test_extremal_classes)
  one_class.enumerate_classes = false;
  const PlanResult r = planManeuver(seedRestToRest(128), one_class);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_EQ(r.termination, Termination::Converged);
  ASSERT_GE(r.levels.size(), 2u);  // continuation: 16 -> 32 -> 128
  EXPECT_EQ(r.levels.back().steps, 128);
  int iterations = 0;
  for (size_t i = 0; i < r.levels.size(); ++i) {
    if (i > 0) EXPECT_LT(r.levels[i - 1].steps, r.levels[i].steps);
    EXPECT_EQ(r.levels[i].termination, Termination::Converged) << r.levels[i].reason;
    EXPECT_FALSE(r.levels[i].reason.empty());
    iterations += r.levels[i].iterations;
  }
  EXPECT_EQ(iterations, r.iterations);
  // The message explains the outcome in one level: no coarse-level message nested in it.
  EXPECT_LT(r.message().size(), 400u) << r.message();
}

TEST(Termination, CancelledByTheCallback) {
  SolverOptions options;
  options.on_iteration = [](const IterationInfo&) { return false; };
  for (int N : {12, 128}) {  // one grid; several levels (cancelled on the coarsest)
    const PlanResult r = planManeuver(seedRestToRest(N), options);
    EXPECT_EQ(r.termination, Termination::Cancelled) << N << ": " << r.message();
    EXPECT_FALSE(r.converged());
    EXPECT_EQ(r.maneuver.steps(), N);  // the plan so far, on the requested grid
  }
}

TEST(Termination, TimedOutWhenTheBudgetRunsOut) {
  SolverOptions options;
  options.time_budget_s = 1e-9;
  const PlanResult r = planManeuver(seedRestToRest(1024), options);
  EXPECT_EQ(r.termination, Termination::TimedOut) << r.message();
  EXPECT_TRUE(contains(r.message(), "time budget")) << r.message();
  EXPECT_EQ(r.maneuver.steps(), 1024);
}

TEST(Termination, TimedOutAlsoWhenPlanningToAnAccuracy) {
  PlanningProblem p = seedRestToRest(128);
  p.accuracy.measure = AccuracyMeasure::TerminalMiss;
  p.accuracy.value = 1e-9;
  SolverOptions options;
  options.time_budget_s = 1e-9;
  const PlanResult r = planManeuver(p, options);
  EXPECT_EQ(r.termination, Termination::TimedOut) << r.message();
}

TEST(Termination, IterationLimitIsNotConverged) {
  SolverOptions options;
  options.max_iterations = 1;
  const PlanResult r = planManeuver(seedRestToRest(64), options);
  EXPECT_EQ(r.termination, Termination::NotConverged) << r.message();
  EXPECT_TRUE(contains(r.message(), "iteration limit")) << r.message();
}

TEST(Termination, StepTooLargeIsItsOwnStatusOrException) {
  // A boundary velocity without a step at this h is refused up front (exception); the node and
  // the CLI map it to the same status as a result ending StepTooLarge.
  PlanningProblem p = seedRestToRest(8);
  p.initial_velocity = Vector3(0, 0, 40.0);
  EXPECT_THROW(planManeuver(p), StepTooLarge);
}

TEST(Report, TextSummaryKeepsEveryFieldWhateverTheMessageLength) {
  // A message longer than any fixed buffer (5000 bytes) must not cut the fields after it.
  const PlanningProblem p = seedRestToRest(128);
  PlanResult r;
  r.clauses.push_back(clauses::Reason{std::string(5000, 'x')});
  r.extremal = "short way";
  r.solver = "newton";
  r.iterations = 7;
  r.solve_time_s = 0.25;
  const std::string text = planResultText(p, r);
  for (const char* label :
       {"converged", "message", "solver / scheme", "steps N, duration T", "iterations",
        "cost sum 1/2|tau_k|^2", "terminal attitude error", "terminal velocity error",
        "max residual", "dynamics residual", "solve time", "planned effects", "extremal"}) {
    EXPECT_TRUE(contains(text, std::string("\n") + label) || text.rfind(label, 0) == 0) << label;
  }
  EXPECT_TRUE(contains(text, std::string(5000, 'x')));
  EXPECT_TRUE(contains(text, "0.250 s"));
  EXPECT_TRUE(contains(text, "NO (not_converged)"));
}

TEST(Report, JsonSummaryCarriesTheTerminationAndTheLevels) {
  const PlanningProblem p = seedRestToRest(128);
  SolverOptions one_class;  // one solve's levels (the class survey: test_extremal_classes)
  one_class.enumerate_classes = false;
  const PlanResult r = planManeuver(p, one_class);
  const std::string json = planResultJson(p, r);
  EXPECT_TRUE(contains(json, "\"converged\": true"));
  EXPECT_TRUE(contains(json, "\"termination\": \"converged\""));
  EXPECT_TRUE(contains(json, "\"levels\": [{\"steps\": 16"));
  EXPECT_TRUE(contains(json, "{\"steps\": 128, \"iterations\": "));
}

TEST(Report, JsonSummaryCarriesEachAttemptsStartDetail) {
  // attempts[i].start_detail: the start's parameters as data, every number exact (exactNumber
  // reads back to the same double), a duration of the request's own null, the origin of a
  // refinement its coarsest start's.
  const PlanningProblem p = seedRestToRest(16);
  PlanResult r;
  Attempt excursion;
  excursion.stage = AttemptStage::MinimumTimeSolve;
  excursion.start = AttemptStart::Excursion;
  excursion.start_detail.duration = 27.463018551948521;
  excursion.start_detail.eigenaxis = Vector3::UnitX();
  excursion.start_detail.excursion_axis = Vector3(0, 1, 1).normalized();
  excursion.start_detail.excursion = 0.3;
  excursion.start_detail.excursion_peak = 0.4;  // skewed in time (around cones)
  Attempt refined = excursion;
  refined.start = AttemptStart::CoarseLevel;
  refined.start_detail.coarse_steps = 64;
  refined.start_detail.origin = AttemptStart::Excursion;
  refined.kept = true;
  Attempt plain;  // a start without parameters
  r.attempts = {excursion, refined, plain};
  const std::string json = planResultJson(p, r);
  const std::string axis = "[0, " + exactNumber(excursion.start_detail.excursion_axis.y()) + ", " +
                           exactNumber(excursion.start_detail.excursion_axis.z()) + "]";
  EXPECT_EQ(std::stod(exactNumber(excursion.start_detail.excursion_axis.y())),
            excursion.start_detail.excursion_axis.y());
  const StartDetail& d = excursion.start_detail;
  const std::string detail = "\"start_detail\": {\"duration\": " + exactNumber(d.duration) +
                             ", \"eigenaxis\": [1, 0, 0], \"excursion_axis\": " + axis +
                             ", \"excursion\": " + exactNumber(d.excursion) +
                             ", \"excursion_peak\": " + exactNumber(d.excursion_peak) +
                             ", \"cleared_of_cones\": false, \"coarse_steps\": ";
  // A start without a twist (not a pointing request) writes it null.
  EXPECT_TRUE(contains(json, detail + "0, \"origin\": \"excursion\", \"twist\": null, "
                                      "\"elastic_from_violations\": false}"))
      << json;
  EXPECT_TRUE(contains(json, "\"start\": \"coarse_level\"")) << json;
  EXPECT_TRUE(contains(json, detail + "64, \"origin\": \"excursion\", \"twist\": null, "
                                      "\"elastic_from_violations\": false}"))
      << json;
  EXPECT_TRUE(contains(json,
                       "\"start_detail\": {\"duration\": null, \"eigenaxis\": [0, 0, 0], "
                       "\"excursion_axis\": [0, 0, 0], \"excursion\": 0, \"excursion_peak\": 0.5, "
                       "\"cleared_of_cones\": false, \"coarse_steps\": 0, \"origin\": \"hermite\", "
                       "\"twist\": null, \"elastic_from_violations\": false}"))
      << json;
}

TEST(Report, JsonSummaryCarriesTheVerdictsKindAndFigures) {
  // `verdict`: the driver's verdict as data, its figures exact (exactNumber reads back to the
  // same double); a solver's own reason writes its kind and no figures.
  const PlanningProblem p = seedRestToRest(16);
  PlanResult r;
  EXPECT_TRUE(contains(planResultJson(p, r),
                       "\"verdict\": {\"kind\": \"solver_reason\", \"figures\": {}},"));
  const double T = 2.0 + 1.0 / 3.0, least = 2.5 + 1.0 / 7.0;
  r.verdict = verdicts::LocallyInfeasible{T, least, "what", 0.0, "", true};
  EXPECT_TRUE(contains(planResultJson(p, r),
                       "\"verdict\": {\"kind\": \"locally_infeasible\", \"figures\": "
                       "{\"requested_duration\": " +
                           exactNumber(T) + ", \"least_duration_found\": " + exactNumber(least) +
                           ", \"lower_bound\": 0}},"))
      << planResultJson(p, r);
}

TEST(Report, PlanManeuverPrintsTheWholeSummaryAtLargeN) {
  // The same through the tool: at N = 65536 with one iteration per level the message is long,
  // and every field after it must still be printed.
  const attitude_planner_test::ToolRun r = attitude_planner_test::runTool(
      "plan_maneuver",
      std::string(AP_SOURCE_DIR) + "/scenes/rest_to_rest.yaml --steps 65536 --max-iterations 1",
      120);
  EXPECT_EQ(r.status, 1) << r.output;  // not converged after one iteration
  for (const char* label :
       {"solver / scheme", "steps N, duration T      65536", "iterations", "cost sum 1/2|tau_k|^2",
        "terminal attitude error", "solve time", "grid levels"}) {
    EXPECT_TRUE(contains(r.output, label)) << label << "\n" << r.output;
  }
}

TEST(Verdicts, AFreeTimeSolvesEndingIsItsOutcomesVerdictKind) {
  // Minimum time's solver: the free-time solve's own ending is a verdict kind on its outcome,
  // with its KKT figures, and its message is the kind's words (the driver carries both to the
  // level's result; the answer's message is the driver's account of T*).
  PlanningProblem p =
      loadScene(std::string(AP_SOURCE_DIR) + "/scenes/min_time_bilimoria_wie.yaml").problem;
  p.steps = 32;
  const Vector3 turn = so3::log(p.initial_attitude.transpose() * p.final_attitude);
  std::vector<Matrix3> geodesic;
  for (int k = 0; k <= p.steps; ++k) {
    geodesic.push_back(p.initial_attitude * so3::exp(turn * (double(k) / p.steps)));
  }
  const FreeTimeOutcome o = solveFreeTime(p, geodesic, 3.4, 1e-9, 500);
  ASSERT_EQ(o.termination, Termination::Converged) << o.message();
  EXPECT_EQ(verdictKindName(o.verdict), "free_time_ended");
  EXPECT_EQ(o.message(), renderVerdict(o.verdict, ""));
  std::map<std::string, double> figure;
  for (const VerdictFigure& f : verdictFigures(o.verdict)) figure[f.name] = f.value;
  EXPECT_EQ(figure.at("duration"), o.duration);
  EXPECT_EQ(figure.at("stationarity"), o.stationarity);
  EXPECT_EQ(figure.at("time_row"), o.time_row);
  EXPECT_EQ(figure.at("min_constraint_value"), o.smallest_value);
  EXPECT_GT(figure.at("iterations"), 0.0);
  EXPECT_LE(figure.at("iterations"), o.iterations);  // the run that ended, of the solve's
}

TEST(Verdicts, AMinimumTimeAnswerIsItsOwnKindWithTheFiguresOfItsCertificate) {
  // The answer's account of T* is a verdict kind: T*, whether it is shown a strict local minimum,
  // the start it came from and every start solved, its figures those of the certificate.
  for (const char* scene :
       {"min_time_bilimoria_wie", "min_time_keep_out", "min_time_sphere", "min_time_betts"}) {
    for (int steps : {64}) {
      SCOPED_TRACE(std::string(scene) + " N = " + std::to_string(steps));
      PlanningProblem p =
          loadScene(std::string(AP_SOURCE_DIR) + "/scenes/" + scene + ".yaml").problem;
      p.steps = steps;
      const PlanResult r = planManeuver(p, SolverOptions());
      ASSERT_TRUE(r.converged()) << r.message();
      ASSERT_TRUE(r.minimum_time.kkt_point) << r.message();
      ASSERT_TRUE(std::holds_alternative<verdicts::MinimumTimeAnswer>(r.verdict)) << r.message();
      const auto& answer = std::get<verdicts::MinimumTimeAnswer>(r.verdict);
      EXPECT_EQ(answer.minimum_duration, r.minimum_duration);
      EXPECT_EQ(answer.second_order_sufficient, r.minimum_time.second_order_sufficient);
      EXPECT_EQ(answer.stationarity, r.minimum_time.stationarity);
      EXPECT_EQ(answer.time_row, r.minimum_time.time_stationarity);
      EXPECT_EQ(answer.complementarity, r.minimum_time.complementarity);
      EXPECT_EQ(answer.solves, r.minimum_time.solves);
      EXPECT_FALSE(answer.start.empty());
      ASSERT_FALSE(answer.starts.empty());
      // The start it came from is among the starts solved, converged at T*.
      bool found = false;
      for (const verdicts::MinimumTimeAnswer::Start& s : answer.starts) {
        found = found ||
                (s.name == answer.start && s.termination == Termination::Converged &&
                 std::abs(s.duration - answer.minimum_duration) <= 1e-9 * answer.minimum_duration);
      }
      EXPECT_TRUE(found) << r.message();
      std::map<std::string, double> figure;
      for (const VerdictFigure& f : verdictFigures(r.verdict)) figure[f.name] = f.value;
      EXPECT_EQ(figure.at("minimum_duration"), r.minimum_duration);
      EXPECT_EQ(figure.at("solves"), r.minimum_time.solves);
      EXPECT_EQ(figure.at("second_order_sufficient"),
                r.minimum_time.second_order_sufficient ? 1.0 : 0.0);
      EXPECT_EQ(figure.at("kkt_point"), 1.0);
      EXPECT_TRUE(answer.kkt_point);
      EXPECT_EQ(r.message().rfind(renderVerdict(r.verdict, ""), 0), 0u) << r.message();
    }
  }
}

TEST(Verdicts, ASolversFirstReasonIsItsVerdictKind) {
  // The Newton solver's and the interior point's own endings are verdict kinds with their
  // figures: the message begins with the verdict's words, and the figures are the solve's.
  struct Case {
    const char* scene;
    const char* kind;
  };
  for (const Case& c :
       {Case{"rest_to_rest", "newton_ended"}, Case{"torque_limited", "interior_point_ended"},
        Case{"sun_keep_out", "interior_point_ended"}}) {
    SCOPED_TRACE(c.scene);
    PlanningProblem p =
        loadScene(std::string(AP_SOURCE_DIR) + "/scenes/" + c.scene + ".yaml").problem;
    p.steps = 32;
    const PlanResult r = planManeuver(p, SolverOptions());
    ASSERT_TRUE(r.converged()) << r.message();
    EXPECT_EQ(verdictKindName(r.verdict), c.kind);
    const std::string words = renderVerdict(r.verdict, "");
    EXPECT_EQ(r.message().rfind(words, 0), 0u) << r.message() << "\n" << words;
    const std::vector<VerdictFigure> figures = verdictFigures(r.verdict);
    ASSERT_FALSE(figures.empty());
    EXPECT_EQ(figures[0].name, "iterations");
    EXPECT_GT(figures[0].value, 0.0);
    EXPECT_LE(figures[0].value, r.iterations);  // one grid's solve among the request's
  }
}
