// The cheapest extremal by enumeration of homotopy classes: a request that
// leaves its class free (direction shortest, no extra revolutions, no warm start) is answered by
// the cheapest of the classes {nearest lift, the other way round} × {0, 1 extra revolution};
// a request that names its class gets that class only; the trail lists each class with its cost.
// The held-out measurement (fractions over a seeded suite, against IPOPT, times) is
// docs/results/extremal_classes.md (scripts/extremal_classes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "planning/newton/grid_solve.hpp"
#include "planning/newton/kept_plan.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/starts.hpp"

using namespace attitude_planner;

namespace {

const HomotopyClass kClasses[] = {{false, 0}, {true, 0}, {false, 1}, {true, 1}};

/// Uniform draws from a seeded 64-bit Mersenne twister (the same sequence on every platform).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double uniform(double a, double b) { return a + (b - a) * ((engine_() >> 11) * 0x1.0p-53); }
  Vector3 direction() {
    Vector3 v;
    do {
      v = Vector3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    } while (v.norm() > 1 || v.norm() < 1e-3);
    return v.normalized();
  }
  Matrix3 rotation() { return so3::exp(Vector3(uniform(0, M_PI) * direction())); }

 private:
  std::mt19937_64 engine_;
};

/// A physical body (J_i = s_j + s_k: the triangle inequality holds) with spinning ends: rates up
/// to 5 rad/s, T in 2–12 s, N = 128 (the classes are surveyed at N = 32 and refined).
PlanningProblem spinningProblem(Draw& draw) {
  PlanningProblem p;
  const Vector3 s(draw.uniform(0.05, 1), draw.uniform(0.05, 1), draw.uniform(0.05, 1));
  const Matrix3 Q = draw.rotation();
  p.inertia = Q * Vector3(s(1) + s(2), s(0) + s(2), s(0) + s(1)).asDiagonal() * Q.transpose();
  p.inertia = 0.5 * (p.inertia + p.inertia.transpose()).eval();
  p.initial_attitude = draw.rotation();
  p.final_attitude = draw.rotation();
  p.initial_velocity = draw.uniform(0, 5) * draw.direction();
  p.final_velocity = draw.uniform(0, 5) * draw.direction();
  p.duration = draw.uniform(2, 12);
  p.steps = 128;
  return p;
}

/// A rest-to-rest slew of a physical body (random principal axes) by θ ∈ [0.5, π − 0.02] rad about
/// a random axis, under one keep-out cone across its eigenaxis path: the cone's axis is the
/// boresight's direction at the slew's middle turned off it by up to 0.8 of its half angle, both
/// ends' boresights at least 0.1 rad outside it (scripts/keep_out_grids.py's suite).
PlanningProblem keepOutSlew(Draw& draw) {
  PlanningProblem p;
  const Vector3 s(draw.uniform(0.05, 1), draw.uniform(0.05, 1), draw.uniform(0.05, 1));
  const Matrix3 Q = draw.rotation();
  const double scale = std::exp(draw.uniform(0.0, std::log(100.0)));
  p.inertia =
      scale * Q * Vector3(s(1) + s(2), s(0) + s(2), s(0) + s(1)).asDiagonal() * Q.transpose();
  p.inertia = 0.5 * (p.inertia + p.inertia.transpose()).eval();
  p.duration = std::exp(draw.uniform(std::log(10.0), std::log(100.0)));
  p.scheme = SchemeKind::Paper;
  for (;;) {
    p.initial_attitude = draw.rotation();
    const Vector3 axis = draw.direction();
    const double theta = draw.uniform(0.5, M_PI - 0.02);
    p.final_attitude = p.initial_attitude * so3::exp(Vector3(theta * axis));
    const Vector3 boresight = draw.direction();
    const double half_angle = draw.uniform(0.15, 0.6);
    const Vector3 middle = p.initial_attitude * so3::exp(Vector3(0.5 * theta * axis)) * boresight;
    const Vector3 off = middle.cross(draw.direction()).normalized();
    const Vector3 cone = so3::exp(Vector3(draw.uniform(0, 0.8 * half_angle) * off)) * middle;
    const auto outside = [&](const Matrix3& R) {
      const Vector3 b = R * boresight;
      return std::atan2(b.cross(cone).norm(), b.dot(cone)) > half_angle + 0.1;
    };
    if (!outside(p.initial_attitude) || !outside(p.final_attitude)) continue;
    p.constraints = {PlanningConstraint::keepOut(boresight, cone, half_angle)};
    return p;
  }
}

}  // namespace

// A request that names its class gets exactly that class: one attempt, in that class, and the
// extremal says so.
TEST(ExtremalClasses, ARequestThatNamesItsClassGetsExactlyThatClass) {
  Draw draw(30);
  const PlanningProblem base = spinningProblem(draw);
  for (const HomotopyClass& c : {kClasses[1], kClasses[2], kClasses[3]}) {
    const PlanResult r = planManeuver(pinnedToClass(base, c));
    ASSERT_TRUE(r.converged()) << r.message();
    EXPECT_TRUE(sameHomotopyClass(r.extremal_summary.homotopy, c)) << r.extremal;
    for (const Attempt& a : r.attempts) {
      EXPECT_TRUE(sameHomotopyClass(a.homotopy, c)) << attemptStageName(a.stage);
      EXPECT_NE(a.stage, AttemptStage::ClassSurvey);
    }
  }
}

// A warm-started request stays in its guess's class: no survey of the others.
TEST(ExtremalClasses, AWarmStartedRequestIsNotEnumerated) {
  Draw draw(31);
  const PlanningProblem p = spinningProblem(draw);
  const PlanResult first = planManeuver(pinnedToClass(p, kClasses[1]));
  ASSERT_TRUE(first.converged()) << first.message();
  SolverOptions warm;
  warm.warm_start = &first.maneuver;
  const PlanResult r = planManeuver(p, warm);
  ASSERT_TRUE(r.converged()) << r.message();
  for (const Attempt& a : r.attempts) EXPECT_NE(a.stage, AttemptStage::ClassSurvey);
  EXPECT_NEAR(r.cost, first.cost, 1e-8 * first.cost);  // the guess's extremal, not another
}

// A spin handed over from the body z axis to the x axis (5 rad/s at both ends, T = 4 s,
// J = diag(1, 2, 2.5), the end attitudes 1 rad apart about z): the coasting displacement points
// between the two spin axes, and the nearest lift to it is not the cheapest class. Each class's
// own solve (the nearest with SolverOptions::enumerate_classes off) is the reference.
TEST(ExtremalClasses, ASpinHandedOverBetweenAxesTakesTheCheapestClass) {
  PlanningProblem p;
  p.inertia = Vector3(1, 2, 2.5).asDiagonal();
  p.duration = 4;
  p.steps = 128;
  p.initial_velocity = Vector3(0, 0, 5);
  p.final_attitude = so3::exp(Vector3(0, 0, 1));
  p.final_velocity = Vector3(5, 0, 0);
  SolverOptions nearest_only;
  nearest_only.enumerate_classes = false;
  std::vector<PlanResult> own;
  for (const HomotopyClass& c : kClasses) {
    own.push_back(planManeuver(pinnedToClass(p, c), nearest_only));
    ASSERT_TRUE(own.back().converged()) << own.back().message();
    ASSERT_EQ(own.back().attempts.size(), 1u);  // each class alone, no survey
  }
  const auto cheapest =
      std::min_element(own.begin(), own.end(), [](auto& a, auto& b) { return a.cost < b.cost; });
  // The premise: another class is clearly cheaper than the nearest lift.
  ASSERT_GT(own[0].cost, 1.2 * cheapest->cost);

  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_LE(r.cost, cheapest->cost * (1 + 1e-9)) << r.extremal;
  EXPECT_TRUE(sameHomotopyClass(r.extremal_summary.homotopy, cheapest->extremal_summary.homotopy))
      << r.extremal;
  // The trail lists every class surveyed with its (coarse) cost, and every refined class with
  // the cost of that class's own solve: the survey and refinement are its grid continuation.
  for (std::size_t i = 0; i < own.size(); ++i) {
    const HomotopyClass& c = kClasses[i];
    const auto surveyed = std::find_if(r.attempts.begin(), r.attempts.end(), [&](auto& a) {
      return a.stage == AttemptStage::ClassSurvey && sameHomotopyClass(a.homotopy, c);
    });
    ASSERT_NE(surveyed, r.attempts.end()) << i;
    EXPECT_TRUE(std::isfinite(surveyed->cost)) << i;
    EXPECT_LT(surveyed->steps, p.steps) << i;
    const auto refined = std::find_if(r.attempts.begin(), r.attempts.end(), [&](auto& a) {
      return a.stage == AttemptStage::ClassRefine && sameHomotopyClass(a.homotopy, c);
    });
    if (refined != r.attempts.end()) EXPECT_NEAR(refined->cost, own[i].cost, 1e-9 * own[i].cost);
  }
  EXPECT_EQ(r.extremal_summary.others.size() + 1, r.attempts.size());
  std::printf("nearest %.6g, other way %.6g, +1 turn %.6g, other way +1 %.6g; default %.6g: %s\n",
              own[0].cost, own[1].cost, own[2].cost, own[3].cost, r.cost, r.extremal.c_str());
}

// The issue's target as a property: on seeded spinning problems, the default answer costs no
// more than each class's own solve (1e-6 relative) in at least 99 % of the cases.
TEST(ExtremalClasses, TheDefaultIsNoCostlierThanAnyClassOnSeededSpinningProblems) {
  constexpr int kCases = 100;
  Draw draw(3030);
  SolverOptions nearest_only;
  nearest_only.enumerate_classes = false;
  int cheapest = 0, compared = 0;
  for (int i = 0; i < kCases; ++i) {
    const PlanningProblem p = spinningProblem(draw);
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << i << ": " << r.message();
    double least = std::numeric_limits<double>::infinity();
    for (const HomotopyClass& c : kClasses) {
      const PlanResult own = planManeuver(pinnedToClass(p, c), nearest_only);
      if (own.converged()) least = std::min(least, own.cost);
    }
    if (!std::isfinite(least)) continue;
    ++compared;
    const bool ok = r.cost <= least * (1 + 1e-6);
    cheapest += ok;
    if (!ok)
      std::printf("draw %d: default %.10g, least class %.10g: %s\n", i, r.cost, least,
                  r.extremal.c_str());
  }
  std::printf("default no costlier than every class in %d of %d\n", cheapest, compared);
  EXPECT_GE(compared, kCases - 2);
  EXPECT_GE(cheapest, 0.99 * compared);
}

namespace {

/// Plans `p` on one thread and on two, expects the same answer attempt by attempt (the solves
/// run at once are recorded in the recipe's order), and returns the one-thread result.
PlanResult expectTheSameAnswerOnOneAndTwoThreads(const PlanningProblem& p, int i) {
  SolverOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const PlanResult a = planManeuver(p, one);
  const PlanResult b = planManeuver(p, two);
  EXPECT_EQ(a.cost, b.cost) << i;
  EXPECT_EQ(a.iterations, b.iterations) << i;
  EXPECT_EQ(a.extremal, b.extremal) << i;
  EXPECT_EQ(a.attempts.size(), b.attempts.size()) << i;
  for (std::size_t k = 0; k < std::min(a.attempts.size(), b.attempts.size()); ++k) {
    const Attempt& x = a.attempts[k];
    const Attempt& y = b.attempts[k];
    EXPECT_EQ(x.stage, y.stage) << i << ", attempt " << k;
    EXPECT_EQ(x.start, y.start) << i << ", attempt " << k;
    EXPECT_TRUE(sameHomotopyClass(x.homotopy, y.homotopy)) << i << ", attempt " << k;
    EXPECT_EQ(x.iterations, y.iterations) << i << ", attempt " << k;
    EXPECT_EQ(x.termination, y.termination) << i << ", attempt " << k;
    EXPECT_EQ(x.kept, y.kept) << i << ", attempt " << k;
    EXPECT_EQ(x.plan_checked, y.plan_checked) << i << ", attempt " << k;
    if (x.termination == Termination::Converged) EXPECT_EQ(x.cost, y.cost) << i << ", " << k;
  }
  return a;
}

}  // namespace

// The classes are surveyed and refined in branches on the machine's cores: on two threads each
// seeded request (spinning, and rest to rest with one of each kind's N) gets the answer it gets
// on one, bit for bit, with the same trail in the same order; and the kept class is the cheapest
// of the classes carried to the requested grid.
TEST(ExtremalClasses, TheClassesSolvedAtOnceGiveTheAnswerOfOneThreadAndKeepTheCheapest) {
  Draw draw(5252);
  int refined_at_once = 0;  // requests whose refinements ran in two branches
  for (int i = 0; i < 12; ++i) {
    PlanningProblem p = spinningProblem(draw);
    if (i % 2) {  // at rest at both ends, on a grid the survey reaches through two levels
      p.initial_velocity.setZero();
      p.final_velocity.setZero();
      p.steps = 256;
    }
    const PlanResult a = expectTheSameAnswerOnOneAndTwoThreads(p, i);
    ASSERT_TRUE(a.converged()) << i << ": " << a.message();
    double least_refined = std::numeric_limits<double>::infinity();
    refined_at_once += std::count_if(a.attempts.begin(), a.attempts.end(), [](const Attempt& x) {
                         return x.stage == AttemptStage::ClassRefine;
                       }) > 1;
    for (const Attempt& x : a.attempts) {
      const bool on_grid = x.steps == p.steps && x.termination == Termination::Converged;
      if (x.stage == AttemptStage::ClassRefine && on_grid) {
        least_refined = std::min(least_refined, x.cost);
      }
    }
    EXPECT_LE(a.cost, least_refined * (1 + 1e-12)) << i << ": " << a.extremal;
  }
  EXPECT_GE(refined_at_once, 3);
}

// The walk keeps a plan by its rule over every plan's check (the cheapest converged, ties to the
// earlier); checking on demand gives the rule's answer over what every check would say, runs
// each check at most once, checks the plan it keeps (unless none converged: then the first plan,
// as the rule keeps it) and so never keeps one that fails. Random walks of 1-6 plans whose costs
// fall in clusters within the tie (one extremal reached by several attempts), solvers that
// converged or not, checks that pass or fail.
TEST(ExtremalClasses, TheKeptPlanIsCheckedAndAPlanThatFailsItsCheckIsNeverKept) {
  std::mt19937_64 engine(5454);
  const auto below = [&](int n) { return static_cast<int>(engine() % n); };
  const double tie = 1e-12;
  int walks_with_checks_spared = 0, tie_clusters = 0;
  for (int walk = 0; walk < 20000; ++walk) {
    const int n = 1 + below(6);
    std::vector<double> cost(n);
    std::vector<PlanStanding> standing(n), every_check(n);
    std::vector<bool> passes(n);
    int solver_converged = 0;
    for (int i = 0; i < n; ++i) {
      cost[i] = (1.0 + 0.1 * below(3)) * (1.0 + 0.6e-12 * (below(5) - 2));
      const bool converged = below(5) > 0;
      passes[i] = below(5) > 0;
      solver_converged += converged;
      standing[i] = converged ? PlanStanding::Unchecked : PlanStanding::NotConverged;
      every_check[i] = converged && passes[i] ? PlanStanding::Checked : PlanStanding::NotConverged;
    }
    std::vector<int> checks(n, 0);
    const std::size_t kept = keptWithChecksOnDemand(cost, &standing, tie, [&](std::size_t i) {
      ++checks[i];
      return static_cast<bool>(passes[i]);
    });
    ASSERT_EQ(kept, keptByTheWalksRule(cost, every_check, tie)) << walk;
    int run = 0;
    for (int i = 0; i < n; ++i) {
      ASSERT_LE(checks[i], 1) << walk;
      run += checks[i];
      if (checks[i]) {
        EXPECT_EQ(standing[i], passes[i] ? PlanStanding::Checked : PlanStanding::NotConverged);
      }
    }
    const bool any_converged =
        std::count(every_check.begin(), every_check.end(), PlanStanding::Checked) > 0;
    if (any_converged) {
      EXPECT_EQ(standing[kept], PlanStanding::Checked) << walk;
      EXPECT_TRUE(passes[kept]) << walk;
    } else {
      EXPECT_EQ(kept, 0u) << walk;
    }
    walks_with_checks_spared += run < solver_converged;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < i; ++j) {
        tie_clusters += cost[i] != cost[j] && std::abs(cost[i] - cost[j]) <= 2 * tie * cost[j];
      }
    }
  }
  EXPECT_GT(walks_with_checks_spared, 10000);  // the point of deferring: most walks spare some
  EXPECT_GT(tie_clusters, 1000);               // and the ties the rule reads are exercised
}

// A Newton solve whose check is deferred returns its converged plan and the step residual it
// measured; the check run later leaves a plan that passes as it was, and makes one that fails what
// the solve returns for such a plan: not converged, the check's words as how its Newton solve and
// its level ended (here a residual put beyond its tolerance).
TEST(ExtremalClasses, APlanThatFailsItsDeferredCheckEndsAsItsSolveEndsSuchAPlan) {
  PlanningProblem p;
  p.inertia = Vector3(1.0, 1.2, 1.4).asDiagonal();
  p.final_attitude = so3::exp(Vector3(0.3, -0.5, 1.1));
  p.duration = 10.0;
  p.steps = 32;
  const SolverOptions options;
  SolveContext context(options);
  std::optional<StepResidual> unchecked;
  GridSettings settings;
  settings.deferred_check = &unchecked;
  const PlanResult r = solveOnGrid(p, context, settings, {}, nullptr, options.advanced.newton);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_TRUE(unchecked.has_value());
  PlanResult passing = r;
  EXPECT_TRUE(checkDeferredPlan(p, *unchecked, &passing));
  EXPECT_TRUE(passing.converged());
  EXPECT_EQ(passing.message(), r.message());
  StepResidual beyond = *unchecked;
  beyond.relative = 10 * beyond.tolerance;
  const std::string words = planInconsistency(p, r, false, &beyond);
  ASSERT_FALSE(words.empty());
  PlanResult failing = r;
  EXPECT_FALSE(checkDeferredPlan(p, beyond, &failing));
  EXPECT_EQ(failing.termination, Termination::NotConverged);
  EXPECT_EQ(std::get<verdicts::NewtonEnded>(failing.verdict).how, words);
  EXPECT_EQ(failing.message().rfind(words, 0), 0u) << failing.message();
  EXPECT_EQ(failing.levels.back().termination, Termination::NotConverged);
  EXPECT_EQ(failing.levels.back().reason, failing.message());
  EXPECT_EQ(failing.cost, r.cost);
}

// Requests planned through the walk: the kept attempt's plan is checked; an attempt whose plan
// was not checked converged and was not kept; the replay figures the walk measured beside the
// check are those of the plan returned; one thread and two give the same answer and trail.
TEST(ExtremalClasses, OnlyTheKeptPlanNeedsItsCheckAndItsReplayIsTheReturnedPlans) {
  Draw draw(5454);
  int unchecked = 0;
  for (int i = 0; i < 8; ++i) {
    PlanningProblem p = spinningProblem(draw);
    if (i % 2) {  // at rest at both ends: the walk ends after the classes
      p.initial_velocity.setZero();
      p.final_velocity.setZero();
    }
    const PlanResult a = expectTheSameAnswerOnOneAndTwoThreads(p, i);
    ASSERT_TRUE(a.converged()) << i << ": " << a.message();
    for (const Attempt& x : a.attempts) {
      if (x.kept) {
        EXPECT_TRUE(x.plan_checked) << i;
      }
      if (!x.plan_checked) {
        EXPECT_FALSE(x.kept) << i;
        EXPECT_EQ(x.termination, Termination::Converged) << i;
        ++unchecked;
      }
    }
    EXPECT_TRUE(planInconsistency(p, a, false).empty()) << i;
    PlanResult replayed = a;
    replayFigures(p, &replayed);
    EXPECT_EQ(replayed.replay_miss, a.replay_miss) << i;
    EXPECT_EQ(replayed.terminal_attitude_error, a.terminal_attitude_error) << i;
    EXPECT_EQ(replayed.terminal_velocity_error, a.terminal_velocity_error) << i;
    EXPECT_EQ(replayed.dynamics_residual, a.dynamics_residual) << i;
  }
  EXPECT_GT(unchecked, 0);  // some plans were spared their check
}

// Slow spinning solves (scripts/extremal_classes.py's generator, N = 64) whose more starts run
// in branches: 3 in the kept class, and 6 in two classes (the kept one and the request's own).
// Each start is an independent solve, so one and two threads give the same trail and answer.
TEST(ExtremalClasses, TheMoreStartsRunAtOnceGiveTheAnswerOfOneThread) {
  const char* scenes[] = {
      "inertia: [[40.9053900518525, 3.6054074968064342, -0.28164841523941142], "
      "[3.6054074968064342, 68.978893603131922, -9.804713140251863], [-0.28164841523941142, "
      "-9.804713140251863, 41.87368780680174]]\n"
      "duration: 14.544711502630824\nsteps: 64\nscheme: paper\n"
      "initial: {attitude: {quaternion: [-0.31947350194083779, -0.61958428260905574, "
      "-0.15897861754650094, -0.69912645312881894]}, angular_velocity: [-0.36868571465208672, "
      "-0.0015790015139541987, 4.1043659914646042]}\n"
      "final: {attitude: {quaternion: [-0.14040452528866926, -0.46608876476477235, "
      "0.8219292559260355, -0.29577040232481971]}, angular_velocity: [1.0859671799735451, "
      "3.7173718750229181, -1.2587261631436981]}\n",
      "inertia: [[1.087579760275547, 0.1114897336681428, 0.16150268979342522], "
      "[0.1114897336681428, 0.9886668414034997, 0.16503593828882052], [0.16150268979342522, "
      "0.16503593828882052, 1.5324755258280274]]\n"
      "duration: 19.582854065187238\nsteps: 64\nscheme: paper\n"
      "initial: {attitude: {quaternion: [0.81267929769133418, 0.072567714934403726, "
      "0.2125399903416649, 0.53769232685494417]}, angular_velocity: [-2.3816623399376473, "
      "3.3917483011872682, 2.5181753832412799]}\n"
      "final: {attitude: {quaternion: [0.85233312448114629, 0.27573117313918388, "
      "-0.4269410676538869, -0.12337702307178358]}, angular_velocity: [0.26543858974793527, "
      "0.29630140626943263, 0.16988949986585566]}\n"};
  const long more_starts[] = {3, 6};
  for (int i = 0; i < 2; ++i) {
    const PlanningProblem p = parseScene(scenes[i]).problem;
    const PlanResult a = expectTheSameAnswerOnOneAndTwoThreads(p, i);
    ASSERT_TRUE(a.converged()) << i << ": " << a.message();
    EXPECT_EQ(std::count_if(a.attempts.begin(), a.attempts.end(),
                            [](const Attempt& x) { return x.stage == AttemptStage::MoreStarts; }),
              more_starts[i])
        << i;
  }
}

namespace {

/// Rest to rest, 3 rad about z; a keep-out cone of half angle 0.9 rad round the direction body x
/// points along half way round the short way (1.5 rad about z): the short way's unconstrained
/// optimum runs through the cone's axis, the other way round (3.28 rad) clears it.
PlanningProblem coneAcrossTheShortWay() {
  PlanningProblem p;
  p.inertia = Vector3(1.0, 1.2, 1.4).asDiagonal();
  p.final_attitude = so3::exp(Vector3(0, 0, 3.0));
  p.duration = 10.0;
  p.steps = 64;
  p.constraints.push_back(PlanningConstraint::keepOut(
      Vector3::UnitX(), Vector3(std::cos(1.5), std::sin(1.5), 0.0), 0.9));
  return p;
}

/// The least cost of the classes solved one by one (each in its own class) whose plans hold the
/// constraints between the nodes too, +∞ if none did.
double leastClassCost(const PlanningProblem& p) {
  SolverOptions nearest_only;
  nearest_only.enumerate_classes = false;
  double least = std::numeric_limits<double>::infinity();
  for (const HomotopyClass& c : kClasses) {
    const PlanResult own = planManeuver(pinnedToClass(p, c), nearest_only);
    if (own.converged() && own.max_violation_between_nodes <= 1e-3) {
      least = std::min(least, own.cost);
    }
  }
  return least;
}

bool triedConstrainedClasses(const PlanResult& r) {
  return std::any_of(r.attempts.begin(), r.attempts.end(),
                     [](const Attempt& a) { return a.stage == AttemptStage::ConstrainedClass; });
}

}  // namespace

// Under constraints the classes are solved too: where the unconstrained
// optimum's class cannot clear a cone, the answer is another class's plan, never "infeasible",
// and it is the cheapest of the classes; the extremal names it.
TEST(ExtremalClasses, UnderAConeAcrossTheShortWayTheDefaultIsTheCheapestFeasibleClass) {
  const PlanningProblem p = coneAcrossTheShortWay();
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_TRUE(triedConstrainedClasses(r));
  EXPECT_LE(r.max_constraint_violation, 0.0);
  EXPECT_LE(r.max_violation_between_nodes, 1e-3);
  const double least = leastClassCost(p);
  ASSERT_TRUE(std::isfinite(least));
  EXPECT_LE(r.cost, least * (1 + 1e-6)) << r.extremal;
  // Each class's constrained solve starts from the class survey's plan of it: its unconstrained
  // Newton attempt polishes that plan on its grid (started from that earlier attempt), or starts
  // from it resampled to the requested grid (a warm start), instead of solving the class through
  // the grids again. Here the survey has every class on N = 16 and the two nearest refined on
  // N = 64.
  int from_survey = 0;
  for (const Attempt& a : r.attempts) {
    if (a.stage != AttemptStage::ConstrainedClass || a.formulation != Formulation::Unconstrained) {
      continue;
    }
    ++from_survey;
    EXPECT_TRUE(a.start == AttemptStart::PreviousAttempt || a.start == AttemptStart::WarmStart)
        << a.steps << ": " << r.message();
  }
  EXPECT_GE(from_survey, 4) << r.message();
  ASSERT_TRUE(r.extremal_summary.known);
  SolverOptions nearest_only;
  nearest_only.enumerate_classes = false;
  const PlanResult own = planManeuver(pinnedToClass(p, r.extremal_summary.homotopy), nearest_only);
  ASSERT_TRUE(own.converged()) << own.message();
  EXPECT_NEAR(r.cost, own.cost, 1e-8 * own.cost) << r.extremal;
}

// Seeded keep-out slews on several grids: the default answer is no costlier than any class
// solved on its own whose plan holds the cone between the nodes too, whether the unconstrained
// optimum's class converges under the cone at a higher cost than another class, or ends without a
// plan from its unconstrained optimum (then the classes are carried from the survey grid, each
// from its own plan there). Before, the answer's h·cost jumped with N (e.g. 0.026 at N = 64,
// 0.96 at 128, 0.025 at 256: scripts/keep_out_grids, docs/results/keep_out_grids.md).
TEST(ExtremalClasses, UnderAKeepOutConeTheDefaultIsNoCostlierThanAnyClassOnEveryGrid) {
  constexpr int kCases = 16;
  Draw draw(4848);
  int compared = 0;
  for (int i = 0; i < kCases; ++i) {
    PlanningProblem p = keepOutSlew(draw);
    for (const int steps : {64, 256}) {
      p.steps = steps;
      const double least = leastClassCost(p);
      if (!std::isfinite(least)) continue;
      ++compared;
      const PlanResult r = planManeuver(p);
      ASSERT_TRUE(r.converged()) << i << ", N = " << steps << ": " << r.message();
      EXPECT_LE(r.cost, least * (1 + 1e-6)) << i << ", N = " << steps << ": " << r.extremal;
    }
  }
  std::printf("%d of %d requests compared\n", compared, 2 * kCases);
  EXPECT_GE(compared, kCases);
}

// Seeded keep-out slews on a coarse grid: the answer keeps the basin the finer grid's answer is
// in (h·cost within the paper scheme's own discretization between N = 32 and 64, about 5 %, and
// the 10 % the issue allows). Where the plan round the cone cuts it between two nodes by more than
// 1e-3 rad, the between-nodes rule alone would answer with a costlier class that holds it (seed
// 7002's first request: h·cost 0.60 at N = 32 against 0.18 at N = 64); that plan is solved again
// from itself with the cone's node bound tightened by the margin its longest step needs, and says
// so.
TEST(ExtremalClasses, OnACoarseGridTheAnswerKeepsItsBasinWhereThePlanRoundTheConeCutsIt) {
  constexpr int kCases = 12;
  Draw draw(7002);
  int tightened = 0;
  for (int i = 0; i < kCases; ++i) {
    PlanningProblem p = keepOutSlew(draw);
    double effort[2];
    for (int j = 0; j < 2; ++j) {
      p.steps = j == 0 ? 32 : 64;
      const PlanResult r = planManeuver(p);
      ASSERT_TRUE(r.converged()) << i << ", N = " << p.steps << ": " << r.message();
      effort[j] = r.cost * p.duration / p.steps;
      const bool held = std::any_of(r.clauses.begin(), r.clauses.end(), [](const auto& c) {
        const Note* note = std::get_if<Note>(&c);
        return note && std::holds_alternative<notes::ConesTightenedBetweenNodes>(*note);
      });
      if (!held) continue;
      ++tightened;
      EXPECT_LE(r.max_violation_between_nodes, 1e-3) << i << ", N = " << p.steps;
    }
    EXPECT_LE(effort[0], 1.10 * effort[1]) << i;
  }
  std::printf("%d answers from tightened node bounds\n", tightened);
}

// The starts on either side of a cone: each puts the deepest violating node's boresight
// kConeSideOffset half angles off the cone's axis, the two on opposite sides of the great circle
// through the axis along the path there; the boundary nodes keep their attitudes and every
// attitude stays a rotation. A plan clear of every cone gives none.
TEST(ExtremalClasses, ConeSideStartsPassTheConeOnEitherSide) {
  Draw draw(4949);
  int checked = 0;
  for (int i = 0; i < 8; ++i) {
    PlanningProblem p = keepOutSlew(draw);
    p.steps = 64;
    PlanningProblem free = p;
    free.constraints.clear();
    const PlanResult optimum = planManeuver(free);
    ASSERT_TRUE(optimum.converged()) << optimum.message();
    const std::vector<Matrix3>& R = optimum.maneuver.attitude;
    const PlanningConstraint& cone = p.constraints.front();
    const auto angleOff = [&](const Matrix3& Rk) {
      const Vector3 b = Rk * cone.body_axis;
      return std::atan2(b.cross(cone.world_direction).norm(), b.dot(cone.world_direction));
    };
    int deepest = -1;
    for (int k = 2; k <= p.steps - 2; ++k) {
      if (angleOff(R[k]) < cone.half_angle &&
          (deepest < 0 || angleOff(R[k]) < angleOff(R[deepest]))) {
        deepest = k;
      }
    }
    const std::vector<Maneuver> starts = coneSideStarts(p, optimum.maneuver);
    if (deepest < 0) {
      EXPECT_TRUE(starts.empty()) << i;
      continue;
    }
    ASSERT_EQ(starts.size(), 2u) << i;
    const Vector3 along = R[deepest + 1] * cone.body_axis - R[deepest - 1] * cone.body_axis;
    const Vector3 normal = cone.world_direction.cross(along).normalized();
    double sides[2];
    for (int s = 0; s < 2; ++s) {
      const std::vector<Matrix3>& start = starts[s].attitude;
      ASSERT_EQ(start.size(), R.size());
      EXPECT_NEAR(angleOff(start[deepest]), kConeSideOffset * cone.half_angle, 1e-9) << i;
      sides[s] = (start[deepest] * cone.body_axis).dot(normal);
      for (const int k : {0, 1, p.steps - 1, p.steps}) {
        EXPECT_LE((start[k] - R[k]).norm(), 1e-15) << i << ", k = " << k;
      }
      for (const Matrix3& Rk : start) {
        EXPECT_LE((Rk.transpose() * Rk - Matrix3::Identity()).norm(), 1e-13);
        EXPECT_NEAR(Rk.determinant(), 1.0, 1e-13);
      }
    }
    EXPECT_LT(sides[0] * sides[1], 0.0) << i;
    ++checked;
  }
  std::printf("%d of 8 plans crossed their cone\n", checked);
  EXPECT_GE(checked, 3);
}

// A constrained request pinned to a class (by name, or by SolverOptions::enumerate_classes) is
// solved in that class alone, whatever its verdict there.
TEST(ExtremalClasses, AConstrainedRequestPinnedToItsClassIsNotEnumerated) {
  SolverOptions nearest_only;
  nearest_only.enumerate_classes = false;
  const PlanResult nearest = planManeuver(coneAcrossTheShortWay(), nearest_only);
  EXPECT_FALSE(triedConstrainedClasses(nearest));
  EXPECT_FALSE(nearest.converged());  // the cone sits on the nearest lift's unconstrained path
  const PlanResult named = planManeuver(pinnedToClass(coneAcrossTheShortWay(), kClasses[3]));
  EXPECT_FALSE(triedConstrainedClasses(named));
  EXPECT_TRUE(std::all_of(named.attempts.begin(), named.attempts.end(), [](const Attempt& a) {
    return sameHomotopyClass(a.homotopy, kClasses[3]);
  }));
}

// Seeded spinning problems under a torque-norm bound at 0.85× the peak of their unconstrained plan:
// wherever some class converges, the default converges too and costs no more than the cheapest.
TEST(ExtremalClasses, UnderATorqueNormBoundTheDefaultIsNoCostlierThanAnyClass) {
  constexpr int kCases = 6;
  Draw draw(5050);
  int compared = 0;
  for (int i = 0; i < kCases; ++i) {
    PlanningProblem p = spinningProblem(draw);
    p.steps = 64;
    const PlanResult free = planManeuver(p);
    ASSERT_TRUE(free.converged()) << i << ": " << free.message();
    double peak = 0.0;
    for (const Vector3& tau : free.maneuver.torque) peak = std::max(peak, tau.norm());
    p.constraints.push_back(PlanningConstraint::maxTorqueNorm(0.85 * peak));
    const double least = leastClassCost(p);
    if (!std::isfinite(least)) continue;
    ++compared;
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << i << ": " << r.message();
    EXPECT_LE(r.cost, least * (1 + 1e-6)) << i << ": " << r.extremal;
  }
  std::printf("%d of %d cases compared\n", compared, kCases);
  EXPECT_GE(compared, 2);
}

// A keep-out slew whose first class's plan came from the interior point's ℓ1-elastic fallback
// (the free-slacks formulation ended at its limit) passes the cone on the side the fallback's
// path chose: held out (scripts/keep_out_grids --seed 6565, request 24, paper), at N = 256 alone
// the side costing 16 % more while N = 255 and 257 pass on the cheaper one. The class is then
// solved again from its cheapest coarse plan (both sides of the cone) and the cheaper plan kept,
// so h·cost settles in N.
TEST(ExtremalClasses, APlanFromTheElasticFallbackIsSolvedAgainFromTheClassesCheapestCoarsePlan) {
  const PlanningProblem base = parseScene(R"(
inertia: [[2.0385117765811231, 0.045526310767005362, 0.048908559769587197],
          [0.045526310767005362, 2.1139151255983588, -0.011345479405849096],
          [0.048908559769587197, -0.011345479405849096, 2.3382760787780659]]
duration: 39.200711279408587
steps: 64
scheme: paper
initial: {attitude: {quaternion: [0.2126039490965155, 0.36603876813254388, -0.83910463111518896,
                                  0.34164103836280957]}, angular_velocity: [0, 0, 0]}
final: {attitude: {quaternion: [-0.55475646629963715, 0.48284763182407187, -0.48204717941569891,
                                0.47616587903586111]}, angular_velocity: [0, 0, 0]}
constraints:
  - keep_out: {body_axis: [0.08849657812687993, 0.80757831150457893, 0.58308286413446087],
               world_direction: [0.014908224201728798, -0.19251580973831206, -0.9811806193825644],
               half_angle: 0.22886599318329565}
)")
                                   .problem;
  double effort[3];
  bool fallback_seen = false;
  for (int j = 0; j < 3; ++j) {
    PlanningProblem p = base;
    p.steps = 255 + j;
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << p.steps << ": " << r.message();
    EXPECT_LE(r.max_constraint_violation, 0.0);
    effort[j] = r.cost * p.duration / p.steps;
    // The first class's elastic plan on N, not kept, and a later plan of the class on N that is.
    bool elastic_first = false, kept_after = false;
    for (const Attempt& a : r.attempts) {
      if (a.steps != p.steps || a.formulation == Formulation::Unconstrained) continue;
      if (!elastic_first && a.formulation == Formulation::Elastic && !a.kept) {
        elastic_first = true;
      } else if (elastic_first && a.kept) {
        kept_after = true;
      }
    }
    if (elastic_first) {
      fallback_seen = true;
      EXPECT_TRUE(kept_after) << p.steps << ": " << r.message();
    }
  }
  EXPECT_TRUE(fallback_seen) << "no grid exercised the fallback";
  for (const double e : effort) EXPECT_NEAR(e, effort[0], 0.01 * effort[0]);
}
