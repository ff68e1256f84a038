// Honest verdicts on bounded requests: the proven lower bound on the duration
// against closed forms, invariances and every scheme's minimum time; the requests answered
// before any solve; the floating-point range refused by name; classes the grid cannot represent
// refused and a plan never answered as a class it is not in; and a seeded suite of bounded
// requests whose every verdict is checked independently (test/support/bounded_requests.hpp).
#include <gtest/gtest.h>
#include <map>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <variant>

#include <unistd.h>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "planning/drivers/bounded_verdicts.hpp"
#include "planning/drivers/constrained_classes.hpp"
#include "planning/drivers/constrained_recipe.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/drivers/minimum_time_free_time.hpp"
#include "planning/drivers/minimum_time_search.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/strategies/starts.hpp"
#include "support/bounded_references.hpp"
#include "support/bounded_requests.hpp"
#include "support/random_problems.hpp"
#include "support/scene_problem.hpp"

using namespace attitude_planner;
using test_support::sceneProblem;

namespace {

/// θ about `axis`, rest to rest, the body J = diag(moments).
PlanningProblem slew(const Vector3& moments, double theta, const Vector3& axis) {
  PlanningProblem p;
  p.inertia = moments.asDiagonal();
  p.allow_nonphysical_inertia = true;
  p.final_attitude = so3::fromAxisAngle(axis.normalized(), theta);
  p.duration = 10.0;
  p.steps = 64;
  return p;
}

PlanningProblem minimumTime(PlanningProblem p) {
  p.objective = Objective::MinimumTime;
  p.duration = 0.0;
  return p;
}

/// An iteration limit at which the seeded suite's solves stop short of optimality.
constexpr int kCutIterations = 12;

}  // namespace

TEST(DurationBound, IsTheEigenaxisBangBangTimeOfASphericalBody) {
  // J = jI, |τ| ≤ a: the eigenaxis bang–bang slew is optimal, T* = 2√(θj/a); with |Ω| ≤ w below
  // its peak √(aθ/j), bang–coast–bang, T* = θ/w + wj/a. The bound meets both.
  const double j = 2.5, a = 0.3, theta = 2.2;
  PlanningProblem p = slew(Vector3::Constant(j), theta, Vector3(1, -2, 0.5));
  p.constraints = {PlanningConstraint::maxTorqueNorm(a)};
  EXPECT_NEAR(durationLowerBound(p).seconds, 2 * std::sqrt(theta * j / a), 1e-9);
  EXPECT_EQ(durationLowerBound(p).torque_limit, a);  // the proof's figures, as fields
  EXPECT_EQ(durationLowerBound(p).rate_limit, 0.0);
  const double w = 0.5 * std::sqrt(a * theta / j);
  p.constraints.push_back(PlanningConstraint::maxAngularRate(w));
  const DurationLowerBound both = durationLowerBound(p);
  EXPECT_NEAR(both.seconds, theta / w + w * j / a, 1e-5);
  EXPECT_NEAR(both.seconds, theta / both.rate_limit + both.rate_limit * j / both.torque_limit,
              1e-5);
  EXPECT_EQ(both.rate_limit, w);
  EXPECT_EQ(both.torque_limit, a);
}

TEST(DurationBound, BoundsTheMomentumChangeOfASpinUp) {
  // From rest to a spin of Ω about x, no turn asked for (θ = 0 up to the final attitude at
  // rest): the momentum J Ω must be supplied at |τ| ≤ a, so T ≥ |JΩ|/a.
  PlanningProblem p = slew(Vector3(1, 2, 3), 0.0, Vector3::UnitX());
  p.final_velocity = Vector3(0.4, 0, 0);
  p.max_torque = Vector3::Constant(0.1);
  EXPECT_NEAR(durationLowerBound(p).seconds, 0.4 / (0.1 * std::sqrt(3.0)), 1e-12);
  // The box's corner is the largest torque magnitude; no rate limit.
  EXPECT_NEAR(durationLowerBound(p).torque_limit, 0.1 * std::sqrt(3.0), 1e-15);
  EXPECT_EQ(durationLowerBound(p).rate_limit, 0.0);
}

TEST(DurationBound, IsInvariantUnderWorldRotationAndScalesWithTimeAndInertia) {
  PlanningProblem p = slew(Vector3(1, 2, 3.5), 2.0, Vector3(1, 1, 0));
  p.initial_velocity = Vector3(0.1, -0.2, 0.05);
  p.constraints = {PlanningConstraint::maxTorqueNorm(0.2), PlanningConstraint::maxAngularRate(0.6)};
  const double base = durationLowerBound(p).seconds;
  ASSERT_GT(base, 0.0);
  PlanningProblem turned = p;
  const Matrix3 Q = so3::fromAxisAngle(Vector3(0.3, -1, 2).normalized(), 2.7);
  turned.initial_attitude = Q * p.initial_attitude;
  turned.final_attitude = Q * p.final_attitude;
  EXPECT_NEAR(durationLowerBound(turned).seconds, base, 1e-12 * base);
  // t → s t: rates / s, torques / s²; J → j J: torques × j.
  const double s = 7.0, jscale = 40.0;
  PlanningProblem scaled = p;
  scaled.inertia *= jscale;
  scaled.initial_velocity /= s;
  scaled.constraints = {PlanningConstraint::maxTorqueNorm(0.2 * jscale / (s * s)),
                        PlanningConstraint::maxAngularRate(0.6 / s)};
  EXPECT_NEAR(durationLowerBound(scaled).seconds, s * base, 1e-9 * s * base);
}

TEST(DurationBound, NoSchemesMinimumTimePlanIsShorter) {
  // The bound holds for the continuous problem and, within kDiscreteMargin / N, for every
  // transcription: checked against the minimum time of random bodies and slews, rest and
  // spinning ends, norm and box bounds, every scheme.
  const SchemeKind schemes[] = {SchemeKind::Paper, SchemeKind::Variational,
                                SchemeKind::SecondOrder};
  int checked = 0;
  for (int i = 0; i < 9; ++i) {
    PlanningProblem p = robustness::randomCase(4501, i).problem;
    p.scheme = schemes[i % 3];
    p.steps = 32;
    p.initial_velocity *= (i % 2 == 0) ? 0.0 : 0.05;
    p.final_velocity *= (i % 4 == 1) ? 0.05 : 0.0;
    const double j = p.inertia.trace() / 3.0;
    if (i % 2 == 0) {
      p.constraints = {PlanningConstraint::maxTorqueNorm(0.05 * j)};
    } else {
      p.max_torque = Vector3::Constant(0.04 * j);
    }
    p = minimumTime(p);
    SCOPED_TRACE(robustness::randomCase(4501, i).label + " " + schemeName(p.scheme));
    const PlanResult r = planManeuver(p);
    if (!r.converged()) continue;
    ++checked;
    const double bound = discreteDurationLowerBound(p);
    EXPECT_GE(r.minimum_duration, bound);
    EXPECT_DOUBLE_EQ(r.duration_verdict.lower_bound, durationLowerBound(p).seconds);
    EXPECT_DOUBLE_EQ(r.duration_verdict.torque_limit, durationLowerBound(p).torque_limit);
    EXPECT_EQ(r.duration_verdict.rate_limit, 0.0);
  }
  EXPECT_GE(checked, 7);
}

TEST(BoundedVerdicts, AHopelessRequestAtTwoMillionStepsIsProvenInfeasibleBeforeAnySolve) {
  // 3 rad with |τ| ≤ 0.1 N m on J = diag(10, 20, 30): T ≥ 2√(3·10/0.1) = 34.6 s, asked for 20 s.
  PlanningProblem p = slew(Vector3(10, 20, 30), 3.0, Vector3::UnitZ());
  p.constraints = {PlanningConstraint::maxTorqueNorm(0.1)};
  p.duration = 20.0;
  p.steps = 2000000;
  const PlanResult r = planManeuver(p);
  EXPECT_EQ(r.termination, Termination::Infeasible) << r.message();
  EXPECT_TRUE(r.duration_verdict.proven_infeasible);
  EXPECT_GT(r.duration_verdict.lower_bound, p.duration);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_TRUE(r.attempts.empty());
  // The verdict as data: the bound, the request's T below the bound on its grid, which the
  // grid holds within O(h) of the continuous one.
  ASSERT_TRUE(std::holds_alternative<verdicts::BelowProvenBound>(r.verdict)) << r.message();
  const auto& below = std::get<verdicts::BelowProvenBound>(r.verdict);
  EXPECT_EQ(below.lower_bound, r.duration_verdict.lower_bound);
  EXPECT_EQ(below.basis, r.duration_verdict.lower_bound_basis);
  EXPECT_EQ(below.steps, p.steps);
  EXPECT_EQ(below.requested, p.duration);
  EXPECT_LT(below.requested, below.grid_lower_bound);
  EXPECT_NEAR(below.grid_lower_bound, below.lower_bound, 1e-3 * below.lower_bound);
  EXPECT_FALSE(below.upper_limit);
  // The same as minimum time with that duration as its upper bound.
  p.objective = Objective::MinimumTime;
  const PlanResult fastest = planManeuver(p);
  EXPECT_EQ(fastest.termination, Termination::Infeasible) << fastest.message();
  EXPECT_TRUE(fastest.duration_verdict.proven_infeasible);
  ASSERT_TRUE(std::holds_alternative<verdicts::BelowProvenBound>(fastest.verdict));
  EXPECT_TRUE(std::get<verdicts::BelowProvenBound>(fastest.verdict).upper_limit);
}

TEST(BoundedVerdicts, JustAboveTheBoundIsNotDeclaredInfeasibleByIt) {
  // Spherical body: the bound is T*; 1 % above it a plan exists and converges.
  PlanningProblem p = slew(Vector3::Constant(2.0), 2.0, Vector3(0, 1, 1));
  p.constraints = {PlanningConstraint::maxTorqueNorm(0.2)};
  p.duration = 1.05 * durationLowerBound(p).seconds;
  const PlanResult r = planManeuver(p);
  EXPECT_TRUE(r.converged()) << r.message();
  EXPECT_FALSE(r.duration_verdict.proven_infeasible);
}

TEST(BoundedVerdicts, MinimumTimeBetweenIdenticalRestStatesIsAnsweredAtOnce) {
  PlanningProblem p = minimumTime(slew(Vector3(1, 2, 3), 0.0, Vector3::UnitX()));
  p.initial_attitude = p.final_attitude = so3::fromAxisAngle(Vector3(1, 2, 2).normalized(), 1.0);
  p.max_torque = Vector3::Constant(0.1);
  const PlanResult r = planManeuver(p);
  EXPECT_TRUE(r.converged()) << r.message();
  EXPECT_EQ(r.minimum_duration, 0.0);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_TRUE(std::holds_alternative<verdicts::AlreadyAtRest>(r.verdict)) << r.message();
  ASSERT_EQ(r.maneuver.steps(), p.steps);
  for (const Matrix3& R : r.maneuver.attitude) EXPECT_EQ(R, p.initial_attitude);
  for (const Vector3& tau : r.maneuver.torque) EXPECT_TRUE(tau.isZero(0.0));
}

TEST(BoundedVerdicts, TheZeroManeuverReachesTheEndOnlyAtRestThereInTheShortestClassUnpushed) {
  PlanningProblem there = slew(Vector3(1, 2, 3), 0.0, Vector3::UnitX());
  there.initial_attitude = there.final_attitude = so3::fromAxisAngle(Vector3(1, 2, 2), 1.0);
  EXPECT_TRUE(there.zeroManeuverReachesTheEnd());
  const auto with = [&](auto change) {
    PlanningProblem p = there;
    change(p);
    return p.zeroManeuverReachesTheEnd();
  };
  EXPECT_FALSE(with([](PlanningProblem& p) {
    p.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), 1e-9) * p.final_attitude;
  }));
  EXPECT_FALSE(with([](PlanningProblem& p) { p.initial_velocity = Vector3(0, 0, 1e-12); }));
  EXPECT_FALSE(with([](PlanningProblem& p) { p.final_velocity = Vector3(1e-12, 0, 0); }));
  EXPECT_FALSE(with([](PlanningProblem& p) { p.extra_revolutions = 1; }));
  EXPECT_FALSE(with([](PlanningProblem& p) { p.direction = RotationDirection::LongWay; }));
  EXPECT_FALSE(with([](PlanningProblem& p) {
    auto model = std::make_shared<EffectModel>();
    model->add(std::make_unique<DisturbanceTorque>(Vector3(1e-4, 0, 0), TorqueFrame::World));
    p.effects = model;
  }));
  // A pointing end: reached where R_0 b = d, whatever final_attitude holds.
  const Vector3 b = Vector3(0, 1, 1).normalized();
  EXPECT_TRUE(with([&](PlanningProblem& p) {
    p.end_condition = {EndConditionKind::Pointing, b, p.initial_attitude * b};
    p.final_attitude = so3::fromAxisAngle(Vector3::UnitZ(), 2.0);
  }));
  EXPECT_FALSE(with([&](PlanningProblem& p) {
    p.end_condition = {EndConditionKind::Pointing, b, p.initial_attitude * Vector3::UnitX()};
  }));
}

TEST(BoundedVerdicts, MagnitudesOutsideTheFloatingPointRangeAreRefusedByField) {
  const PlanningProblem base = [] {
    PlanningProblem p = slew(Vector3(1, 2, 3), 3.0, Vector3::UnitZ());
    p.constraints = {PlanningConstraint::maxTorqueNorm(0.1)};
    return p;
  }();
  struct Case {
    const char* what;
    PlanningProblem problem;
    const char* field;
  };
  std::vector<Case> cases;
  PlanningProblem huge_bound = minimumTime(base);
  huge_bound.constraints = {};
  huge_bound.max_torque = Vector3::Constant(1e300);
  cases.push_back({"|tau_i| <= 1e300, minimum time", huge_bound, "actuator_limits.max_torque"});
  PlanningProblem slow = minimumTime(base);
  slow.constraints.push_back(PlanningConstraint::maxAngularRate(1e-300));
  cases.push_back({"|Omega| <= 1e-300, minimum time", slow, "constraints[1].max_angular_rate"});
  PlanningProblem heavy = base;
  heavy.inertia *= 1e300;
  cases.push_back({"J x 1e300", heavy, "inertia"});
  PlanningProblem light = base;
  light.inertia *= 1e-300;
  cases.push_back({"J x 1e-300", light, "inertia"});
  PlanningProblem brief = base;
  brief.duration = 1e-300;
  cases.push_back({"T = 1e-300 s", brief, "duration"});
  PlanningProblem long_one = base;
  long_one.duration = 1e300;
  cases.push_back({"T = 1e300 s", long_one, "duration"});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    try {
      const PlanResult r = planManeuver(c.problem);
      ADD_FAILURE() << "answered " << terminationName(r.termination) << ": " << r.message();
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.field(), c.field) << e.what();
    }
  }
}

TEST(HomotopyClasses, ExtraTurnsTheStepsCannotTurnAreRefused) {
  PlanningProblem p = sceneProblem("rest_to_rest", 128);
  for (int turns : {63, 64, 1000}) {
    p.extra_revolutions = turns;
    try {
      planManeuver(p);
      ADD_FAILURE() << turns << " extra turns on 128 steps were planned";
    } catch (const StepTooLarge& e) {
      EXPECT_EQ(e.field(), "extra_revolutions") << e.what();
    }
  }
  p.extra_revolutions = 62;  // 2K < N − 2: representable, so not refused up front
  EXPECT_NO_THROW(validateProblem(p));
}

TEST(HomotopyClasses, APlanIsNeverAnsweredAsAClassItIsNotIn) {
  // Each converged answer to a named class turns at least its lift between R_1 and R_{N−1}
  // (measured here on the plan, independently of classInconsistency).
  PlanningProblem p = sceneProblem("rest_to_rest", 128);
  for (int turns : {1, 2, 5, 8, 20}) {
    p.extra_revolutions = turns;
    SCOPED_TRACE(std::to_string(turns) + " extra turns");
    const PlanResult r = planManeuver(p);
    if (!r.converged()) continue;
    double turned = 0.0;
    for (int k = 1; k + 1 < r.maneuver.steps(); ++k) {
      turned += so3::angleBetween(r.maneuver.attitude[k], r.maneuver.attitude[k + 1]);
    }
    EXPECT_GE(turned, 2 * M_PI * turns) << r.message();
    ASSERT_TRUE(r.extremal_summary.known);
    EXPECT_EQ(r.extremal_summary.homotopy.extra_revolutions, turns);
  }
}

TEST(BoundedVerdicts, SeededBoundedRequestsHaveHonestVerdicts) {
  // A CI-sized slice of the study's suite (scripts/bounded_verdicts, 200 requests): no internal
  // error reaches the user as an input error, and no verdict is contradicted by its check.
  int requests = 0;
  for (int i = 0; i < 16; ++i) {
    const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(4545, i);
    if (!request) continue;
    ++requests;
    SCOPED_TRACE(request->label);
    const robustness::VerdictCheck check = robustness::planAndCheck(*request);
    EXPECT_EQ(check.input_error, "");
    EXPECT_EQ(check.wrong, "") << check.result.message();
  }
  EXPECT_GE(requests, 12);
}

TEST(BoundedVerdicts, TheSuitesRequestsComeFromStoredReferencesAndAMissingOrStaleOneIsRefused) {
  // A request is a function of (seed, index) alone: its bounds are fractions of a stored
  // reference (the unbounded plan's peaks as planned once), never of this library's own plan. A
  // file without the entry, or with an entry whose random case now draws another duration, is
  // refused naming the seed and the request.
  const std::filesystem::path dir = std::filesystem::temp_directory_path();
  const std::string good = (dir / ("bounded_references_" + std::to_string(::getpid()) + ".csv"));
  const std::string stale = good + ".stale.csv";
  robustness::writeReferences(4545, 2, good);
  const robustness::BoundedReference first = robustness::storedReference(4545, 0, good);
  ASSERT_TRUE(first.converged);
  EXPECT_GT(first.peak_torque, 0.0);
  EXPECT_EQ(first.rest_node, first.steps / 3);
  std::ifstream in(good);
  std::ofstream out(stale);
  for (std::string line; std::getline(in, line);) {
    // The duration of request 1 (third field) moved by a part in 1e12.
    if (line.rfind("4545,1,", 0) == 0) {
      const std::size_t end = line.find(',', 7);
      char moved[40];
      std::snprintf(moved, sizeof moved, "%.17g", std::stod(line.substr(7, end - 7)) * (1 + 1e-12));
      line = "4545,1," + std::string(moved) + line.substr(end);
    }
    out << line << "\n";
  }
  out.close();
  const auto refusal = [](std::uint64_t seed, int index, const std::string& path) {
    try {
      robustness::storedReference(seed, index, path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal(4545, 2, good).find("seed 4545 request 2: no reference"), std::string::npos);
  EXPECT_NE(refusal(4546, 0, good).find("seed 4546 request 0: no reference"), std::string::npos);
  EXPECT_NE(refusal(4545, 1, stale).find("seed 4545 request 1: the reference"), std::string::npos);
  EXPECT_NE(refusal(4545, 1, stale).find("is stale"), std::string::npos);
  EXPECT_EQ(refusal(4545, 0, stale), "");
  // The repository's references give the suite's requests their bounds: f times the peak.
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(4545, 0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->kind, "norm");
  const robustness::BoundedReference stored = robustness::storedReference(4545, 0);
  ASSERT_EQ(request->problem.constraints.size(), 1u);
  EXPECT_EQ(request->problem.constraints[0].limit, request->fraction * stored.peak_torque);
  std::filesystem::remove(good);
  std::filesystem::remove(stale);
}

TEST(BoundedVerdicts, AnAnswerStoppedShortSaysWhetherItHoldsAPlanAtT) {
  // The seeded suites' minimum-effort requests under box bounds (where the interior point's two
  // formulations stop at different iterates) with the iteration limit cut, so that solves stop
  // short of optimality: every answer says as data whether its plan meets the request at T
  // (plan_within_bounds), and where a stopped answer says so, its plan is checked independently
  // (boundary states, every bound: planAndCheck); a converged answer always holds one.
  SolverOptions options;
  options.max_iterations = kCutIterations;
  int stopped_within = 0;
  int requests = 0;
  for (const std::uint64_t seed : {4545u, 4646u}) {
    for (int i = 0; i < 24; ++i) {
      const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(seed, i);
      if (!request || request->kind != "box" ||
          request->problem.objective != Objective::MinimumEffort) {
        continue;
      }
      ++requests;
      SCOPED_TRACE(request->label);
      const robustness::VerdictCheck check = robustness::planAndCheck(*request, options);
      const PlanResult& r = check.result;
      EXPECT_EQ(check.input_error, "");
      EXPECT_EQ(check.wrong, "") << r.message();
      if (r.converged()) EXPECT_TRUE(r.duration_verdict.plan_within_bounds) << r.message();
      if (!r.converged() && r.duration_verdict.plan_within_bounds) ++stopped_within;
    }
  }
  EXPECT_GE(requests, 8);
  EXPECT_GE(stopped_within, 1);
}

TEST(BoundedVerdicts, AMinimumEffortAnswerHoldingAPlanAtTIsNeverInfeasible) {
  // The spinning study suite's request #109 (spinning ends, box bounds) asked for minimum effort
  // at 37.577 s (docs/results/spinning_minimum_time.md, the probe scan): its interior point stops
  // at the iteration limit at a plan within the bounds, and the minimum-time phase's local T*
  // (38.74 s) lies above T: the answer must hold that plan (not converged, plan_within_bounds, T*
  // as data), never "infeasible" (the check's "infeasible with a plan").
  std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 109);
  ASSERT_TRUE(request);
  request->problem.objective = Objective::MinimumEffort;
  request->problem.time_margin = 0.0;
  request->problem.duration = 37.577;
  const robustness::VerdictCheck check = robustness::planAndCheck(*request);
  const PlanResult& r = check.result;
  EXPECT_EQ(check.input_error, "");
  EXPECT_EQ(check.wrong, "") << r.message();
  EXPECT_NE(r.termination, Termination::Infeasible) << r.message();
  if (!r.converged()) {
    EXPECT_TRUE(r.duration_verdict.plan_within_bounds) << r.message();
  }
}

TEST(BoundedVerdicts, BelowAStrictLocalMinimumTheProbesGoOnPastTwoFailuresWithinABudget) {
  // The spinning study suite's request #12 (rest to spin, N = 124): its T* (2.424 s) is a
  // second-order sufficient KKT point and the cold probes 1 % and 2 % below it find nothing. A cold
  // probe's outcome alternates with T there, so two failures do not end the probes: the ladder
  // below T* asks more (probedBelow, kLadder), within a budget of half the request's iterations
  // before the probes (about 1,950 here, each probe about 720), so it stops before its last rung.
  // Each cold probe's interior point from its unconstrained optimum is one `constrained` attempt
  // on the request's grid started there. (Where two failures ended the probes: 2 of them.)
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 12);
  ASSERT_TRUE(request);
  const PlanResult r = planManeuver(request->problem);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_TRUE(r.minimum_time.second_order_sufficient) << r.message();
  const auto probes = std::count_if(r.attempts.begin(), r.attempts.end(), [&](const Attempt& a) {
    return a.stage == AttemptStage::Constrained && a.steps == request->problem.steps &&
           a.start == AttemptStart::UnconstrainedOptimum;
  });
  EXPECT_GT(probes, 2) << r.message();
  EXPECT_LT(probes, 2 + 4) << r.message();  // the near probes and fewer than the four rungs
}

TEST(BoundedVerdicts, TheLaddersRungsAreSolvedOnTheRequestsGridAlone) {
  // The spinning study suite's request #188 (seed 45; paper, N = 315, above the interior point's
  // coarsest_grid): its T* is a second-order sufficient KKT point and the near probes below it
  // find nothing, so rungs of the ladder follow (probedBelow). A near probe's interior point runs
  // through its grid continuation (iterations on coarser grids first); a rung samples another
  // start, the request's own grid alone.
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 188);
  ASSERT_TRUE(request);
  const int N = request->problem.steps;
  ASSERT_GT(N, InteriorPointParameters{}.coarsest_grid);
  // Each probe's interior point is one or more `constrained` attempts (formulations side by
  // side): the least N each iterated on, by attempt number (the order they began).
  std::map<int, int> coarsest_of_attempt;
  SolverOptions options;
  options.on_iteration = [&](const IterationInfo& i) {
    if (i.attempt.stage == AttemptStage::Constrained && i.steps > 0) {
      const auto [at, fresh] = coarsest_of_attempt.emplace(i.attempt.number, i.steps);
      if (!fresh) at->second = std::min(at->second, i.steps);
    }
    return true;
  };
  const PlanResult r = planManeuver(request->problem, options);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_TRUE(r.minimum_time.second_order_sufficient) << r.message();
  // The near probes' attempts through the continuation first, then the rungs' on N alone.
  std::vector<bool> on_grid_alone;
  for (const auto& [number, steps] : coarsest_of_attempt) on_grid_alone.push_back(steps == N);
  const auto first_rung = std::find(on_grid_alone.begin(), on_grid_alone.end(), true);
  ASSERT_NE(first_rung, on_grid_alone.end()) << r.message();
  EXPECT_NE(first_rung, on_grid_alone.begin()) << r.message();
  EXPECT_TRUE(std::all_of(first_rung, on_grid_alone.end(), [](bool b) { return b; }));
}

TEST(BoundedVerdicts, AMinimumTimeSolveGetsTheSameLadderWhoeverAsks) {
  // The spinning study suite's request #188 (seed 45): below its second-order sufficient T* the
  // near probes find nothing and the ladder's budget holds one rung only (probedBelow,
  // ladderBudget). The same minimum-time problem is also asked after other solves of a request
  // (a minimum-effort request's minimum-time phase, after its first solve failed: the check at
  // 0.99 T*). Asked twice in one context, the second solve follows the first's iterations and
  // must still take the same trail: the same attempts, iterations and T*, so the same ladder.
  // (Where the budget was a share of the request's iterations, the second got a larger ladder.)
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 188);
  ASSERT_TRUE(request);
  SolveContext context{SolverOptions{}};
  const PlanResult alone = planMinimumTime(request->problem, context);
  ASSERT_TRUE(alone.converged()) << alone.message();
  const std::size_t first_again = context.attempts().size();
  const PlanResult again = planMinimumTime(request->problem, context);
  EXPECT_EQ(again.minimum_duration, alone.minimum_duration) << again.message();
  const std::vector<Attempt> trail_alone = context.attemptsFrom(0);
  const std::vector<Attempt> trail_again = context.attemptsFrom(first_again);
  ASSERT_EQ(trail_again.size(), first_again) << again.message();
  for (std::size_t i = 0; i < first_again; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(trail_again[i].stage, trail_alone[i].stage);
    EXPECT_EQ(trail_again[i].steps, trail_alone[i].steps);
    EXPECT_EQ(trail_again[i].iterations, trail_alone[i].iterations);
    EXPECT_EQ(trail_again[i].termination, trail_alone[i].termination);
  }
}

TEST(BoundedVerdicts, SpinningRequestsAboveTStarClimbFromIt) {
  // Requests of the seeded suite (seed 45) whose T lies several times above T* with spinning
  // ends, where the minimum-time plan time-scaled to T is no start. The answer either converges
  // within its bounds at T (the ladder of durations from T*, in the trail), or is a local verdict
  // that names T* and the longest duration it reached, below T, or says it did not converge;
  // never "feasible" claimed from T* <= T alone (spinning ends: longer need not be feasible).
  // #89 (T 4 % above T*): the first solve ends infeasible, the ladder converges one rung and the
  // answer is not converged; the durations of its plans are data, not only words.
  for (int i : {161, 168, 89}) {
    const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, i);
    ASSERT_TRUE(request.has_value());
    SCOPED_TRACE(request->label);
    const robustness::VerdictCheck check = robustness::planAndCheck(*request);
    const PlanResult& r = check.result;
    EXPECT_EQ(check.wrong, "") << r.message();
    const bool climbed = std::any_of(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) {
      return a.stage == AttemptStage::DurationLadder;
    });
    EXPECT_TRUE(climbed) << r.message();
    const DurationVerdict& v = r.duration_verdict;
    if (r.converged()) {
      EXPECT_LE(checkConstraints(request->problem, r.maneuver).max_relative_violation, 1e-6);
      EXPECT_EQ(v.longest_duration_found, 0.0);
    } else if (r.termination == Termination::Infeasible) {
      EXPECT_FALSE(v.proven_infeasible);
      EXPECT_GT(v.least_duration_found, 0.0);
      EXPECT_GE(v.longest_duration_found, v.least_duration_found);
      EXPECT_LT(v.longest_duration_found, request->problem.duration);
    } else {
      EXPECT_EQ(r.termination, Termination::NotConverged) << r.message();
      EXPECT_EQ(r.message().find("(feasible:"), std::string::npos) << r.message();
      // Where a rung converged, the durations at which plans were found are the answer's data.
      const bool rung_converged =
          std::any_of(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) {
            return a.stage == AttemptStage::DurationLadder &&
                   a.termination == Termination::Converged;
          });
      if (rung_converged) {
        EXPECT_GT(v.least_duration_found, 0.0);
        EXPECT_GE(v.longest_duration_found, v.least_duration_found);
        EXPECT_LT(v.longest_duration_found, request->problem.duration);
      }
    }
  }
}

TEST(BoundedVerdicts, SpinningMinimumTimeIsNotLeftWithoutAPlanWhereOneExists) {
  // The spinning minimum-time requests of a slice of the seeded suite, re-posed at N = 64: the
  // search's first T sits at the largest duration the grid holds (eigenaxisDurationGuess), where
  // a cold minimum-effort solve can fail locally while plans exist far below it. Every answer is
  // a plan (checked: replayed within its bounds, none found at 0.99 T*) or a verdict with a
  // reason that is not "no plan found": the step count (step_too_large) or a proven bound.
  int requests = 0;
  for (int i = 74; i < 80; ++i) {
    std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, i);
    if (!request || request->problem.objective != Objective::MinimumTime ||
        !hasSpinningEnds(request->problem)) {
      continue;
    }
    ++requests;
    request->problem.steps = 64;
    SCOPED_TRACE(request->label);
    const robustness::VerdictCheck check = robustness::planAndCheck(*request);
    EXPECT_EQ(check.input_error, "");
    EXPECT_EQ(check.wrong, "") << check.result.message();
    EXPECT_NE(check.result.termination, Termination::NotConverged) << check.result.message();
    if (check.result.converged()) EXPECT_GT(check.result.minimum_duration, 0.0);
  }
  EXPECT_GE(requests, 3);
}

namespace {

/// Request `index` of the seeded bounded suite `seed` (spinning ends, at its drawn N) is answered
/// with a plan checked as planAndCheck does (replayed within its bounds, none found at 0.99 T*),
/// at or above the proven bound on its grid (discreteDurationLowerBound).
void expectACheckedPlanAtOrAboveTheFloor(int seed, int index) {
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(seed, index);
  ASSERT_TRUE(request.has_value());
  ASSERT_TRUE(hasSpinningEnds(request->problem));
  SCOPED_TRACE(request->label);
  const robustness::VerdictCheck check = robustness::planAndCheck(*request);
  EXPECT_EQ(check.input_error, "");
  ASSERT_TRUE(check.result.converged()) << check.result.message();
  EXPECT_EQ(check.wrong, "") << check.result.message();
  EXPECT_GE(check.result.minimum_duration, discreteDurationLowerBound(request->problem));
}

}  // namespace

TEST(BoundedVerdicts, SpinningMinimumTimeWithoutAConvergedStartSearchesDurationsUntilAPlan) {
  // Where no free-time start converges, minimum time searches durations for a minimum-effort
  // plan. Two requests of the seeded suite where a fixed search found none though plans exist:
  // - its first T (the eigenaxis guess, 12.58 s) lies within 2x of the proven floor: cold
  //   minimum-effort plans converge at 11 and 12 s, none at 8.8, 9 and 10 s, so a shortening by a
  //   fixed 0.7 (8.8 s, then below the floor) found no plan: "not converged";
  // - the doublings of its first T (25.28, 50.57, 101.1, 202.3 s) and the shortenings below it
  //   find no plan while cold minimum-effort plans converge in between (28.95 and 33.30 s, none
  //   at 25.18 or 38.29 s): "not converged, no plan found".
  expectACheckedPlanAtOrAboveTheFloor(45, 108);
  expectACheckedPlanAtOrAboveTheFloor(45, 206);
}

TEST(BoundedVerdicts, AStartThatJoinedAnotherStartsPathIsSolvedAgainFromItsViolations) {
  // Spinning ends: every start on the starts' grid is solved a second time with its elastic
  // phase from its own violations, a different solve. A start whose first solve was stopped on an
  // earlier start's central path (a join) is a start of its own there too. A request of the seeded
  // suite where a start joins (its coasting start, on the shared objective scale), and its second
  // solve is the one that reaches the lower basin: every first solve on that grid has its second,
  // and the answer lies in that basin (0.653 s; the joined start skipped: 0.6661 s).
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 45);
  ASSERT_TRUE(request.has_value());
  ASSERT_TRUE(hasSpinningEnds(request->problem));
  SCOPED_TRACE(request->label);
  const robustness::VerdictCheck check = robustness::planAndCheck(*request);
  ASSERT_TRUE(check.result.converged()) << check.result.message();
  EXPECT_EQ(check.wrong, "") << check.result.message();
  const std::vector<Attempt>& trail = check.result.attempts;
  ASSERT_FALSE(trail.empty());
  const int starts_grid = trail.front().steps;
  int first_solves = 0, second_solves = 0;
  for (const Attempt& a : trail) {
    if (a.stage != AttemptStage::MinimumTimeSolve || a.steps != starts_grid) continue;
    if (a.start_detail.elastic_from_violations) {
      ++second_solves;
    } else if (second_solves == 0) {  // the first round, before any second solve
      ++first_solves;
    }
  }
  EXPECT_GE(first_solves, 5);
  EXPECT_EQ(second_solves, first_solves);
  EXPECT_LT(check.result.minimum_duration, 0.66);
}

TEST(BoundedVerdicts, SpinningMinimumTimeHasNoPlanFarBelowIt) {
  // Feasibility in T is not monotone with spinning ends: a KKT point can have no plan found 1 %
  // and 2 % below it and minimum-effort plans further below (the evidence: plans at
  // 0.90 T*). A request of the seeded suite where that happened (at its drawn N: a KKT point at
  // 6.8175 s, cold minimum effort failing at 0.99, 0.98 and 0.9 of it and converging at 0.8 of
  // it): its answer is checked as planAndCheck does, and a cold minimum-effort solve at 0.8 T*
  // finds no plan within the bounds.
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 77);
  ASSERT_TRUE(request.has_value());
  ASSERT_TRUE(hasSpinningEnds(request->problem));
  SCOPED_TRACE(request->label);
  const robustness::VerdictCheck check = robustness::planAndCheck(*request);
  ASSERT_TRUE(check.result.converged()) << check.result.message();
  EXPECT_EQ(check.wrong, "") << check.result.message();
  PlanningProblem below = request->problem;
  below.objective = Objective::MinimumEffort;
  below.duration = 0.8 * check.result.minimum_duration;
  const PlanResult r = planManeuver(below);
  EXPECT_FALSE(r.converged() && checkConstraints(below, r.maneuver).max_relative_violation <= 1e-6)
      << "a plan at 0.8 T* = " << below.duration << " s: " << r.message();
}

namespace {

/// A paper-scheme request that ends spinning at `final_rate` under a norm bound `a` and the rate
/// limit `w`, from rest, on J = Rᵀ diag(moments) R.
PlanningProblem spinningEnd(const Vector3& moments, const Matrix3& R, const Vector3& final_rate,
                            double a, double w) {
  PlanningProblem p = slew(moments, 1.0, Vector3(1, 2, 2));
  p.inertia = R.transpose() * moments.asDiagonal() * R;
  p.scheme = SchemeKind::Paper;
  p.final_velocity = final_rate;
  p.constraints = {PlanningConstraint::maxTorqueNorm(a), PlanningConstraint::maxAngularRate(w)};
  return p;
}

/// The least |J⁻¹(c − hτ)| over |τ| ≤ a by projected gradient from the best of many samples of
/// the ball: an independent solver of the problem leastRateBeforeTheEnd bounds by duality.
double leastRateByProjectedGradient(const PlanningProblem& p, double h, double a,
                                    std::mt19937_64& rng) {
  const Matrix3 M = p.inertia.inverse();
  const Vector3 c = so3::exp(h * p.final_velocity) * (p.inertia * p.final_velocity);
  const auto value = [&](const Vector3& t) { return (M * (c - h * t)).norm(); };
  const auto project = [&](Vector3 t) { return t.norm() > a ? Vector3(t * (a / t.norm())) : t; };
  std::normal_distribution<double> normal;
  Vector3 best = Vector3::Zero();
  for (int i = 0; i < 2000; ++i) {
    const Vector3 t = project(a * Vector3(normal(rng), normal(rng), normal(rng)));
    if (value(t) < value(best)) best = t;
  }
  const double step = 1.0 / (h * h * (M * M).norm());  // 1 / the gradient's Lipschitz constant
  for (int i = 0; i < 20000; ++i) {
    const Vector3 gradient = -h * M * M * (c - h * best);
    best = project(best - step * gradient);
  }
  return value(best);
}

}  // namespace

TEST(BoundedVerdicts, TheLeastRateBeforeTheEndIsTheLeastOverTheTorqueBall) {
  // Random bodies, final rates, bounds and steps: the bound by weak duality is at most the least
  // rate an independent projected-gradient solve finds over the ball, and within 1e-6 of it.
  std::mt19937_64 rng(4548);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 12; ++i) {
    const Vector3 moments(0.5 + 4 * unit(rng), 0.5 + 4 * unit(rng), 0.5 + 4 * unit(rng));
    const Matrix3 R = so3::exp(Vector3(normal(rng), normal(rng), normal(rng)));
    const Vector3 rate =
        (0.5 + 4 * unit(rng)) * Vector3(normal(rng), normal(rng), normal(rng)).normalized();
    const double a = 0.05 + 2 * unit(rng);
    PlanningProblem p = spinningEnd(moments, R, rate, a, rate.norm());
    const double h = 0.005 + 0.4 * unit(rng) / rate.norm();
    SCOPED_TRACE("case " + std::to_string(i));
    const double bound = leastRateBeforeTheEnd(p, h * p.steps);
    const double found = leastRateByProjectedGradient(p, h, a, rng);
    EXPECT_LE(bound, found * (1 + 1e-12));
    EXPECT_NEAR(bound, found, 1e-6 * found);
  }
}

TEST(BoundedVerdicts, APaperPlansLastFreeStepIsTheStepTheLeastRateBeforeTheEndBounds) {
  // A converged paper plan ending spinning under a norm bound: its Ω_{N−2} follows from its τ_{N−1}
  // by J Ω_{N−2} = exp(hΩ̂_{N−1}) J Ω_{N−1} − h τ_{N−1}, and its rate there is at least the least
  // rate any plan at its T can have.
  PlanningProblem p = spinningEnd(Vector3(1, 2, 3), so3::exp(Vector3(0.3, -0.2, 0.5)),
                                  Vector3(0.3, -0.2, 0.4), 1.0, 10.0);
  p.constraints = {PlanningConstraint::maxTorqueNorm(1.0)};
  p.duration = 6.0;
  p.steps = 32;
  const PlanResult r = planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  const Maneuver& m = r.maneuver;
  const int N = p.steps;
  const double h = m.time_step;
  EXPECT_LT((m.angular_velocity[N - 1] - p.final_velocity).norm(), 1e-9);  // the boundary datum
  const Vector3 momentum =
      so3::exp(h * m.angular_velocity[N - 1]) * (p.inertia * m.angular_velocity[N - 1]) -
      h * m.torque[N - 1];
  EXPECT_LT((p.inertia * m.angular_velocity[N - 2] - momentum).norm(), 1e-9 * momentum.norm());
  EXPECT_GE(m.angular_velocity[N - 2].norm(), leastRateBeforeTheEnd(p, p.duration) * (1 - 1e-12));
}

namespace {

/// A random body (moments in [0.5, 4.5], random axes) on N = 64 ending at a random rate on the
/// rate limit under a random norm bound (spinningEnd).
PlanningProblem finalRateOnTheLimit(std::mt19937_64& rng,
                                    std::uniform_real_distribution<double>& unit,
                                    std::normal_distribution<double>& normal) {
  const Vector3 moments(0.5 + 4 * unit(rng), 0.5 + 4 * unit(rng), 0.5 + 4 * unit(rng));
  const Matrix3 R = so3::exp(Vector3(normal(rng), normal(rng), normal(rng)));
  const Vector3 rate =
      (0.5 + 4 * unit(rng)) * Vector3(normal(rng), normal(rng), normal(rng)).normalized();
  PlanningProblem p = spinningEnd(moments, R, rate, 0.05 + 2 * unit(rng), rate.norm());
  p.steps = 64;
  return p;
}

}  // namespace

namespace {

/// `check(p, none, draw)` on each of `cases` seeded random bodies whose final rate lies on the
/// rate limit (finalRateOnTheLimit) and that have a range of durations proven without room before
/// the end (with `partial_only`, not every duration); `draw()` is the suite's uniform [0, 1).
/// Returns how many were checked.
template <typename Check>
int forEachProvenRange(std::uint64_t seed, int cases, bool partial_only, Check check) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal;
  const auto draw = [&] { return unit(rng); };
  int checked = 0;
  for (int i = 0; i < cases; ++i) {
    PlanningProblem p = finalRateOnTheLimit(rng, unit, normal);
    const NoRoomBeforeTheEnd none = noRoomBeforeTheEnd(p);
    if (!(none.to > none.from) || (partial_only && none.everywhere)) continue;
    ++checked;
    SCOPED_TRACE("case " + std::to_string(i));
    check(p, none, draw);
  }
  return checked;
}

}  // namespace

TEST(BoundedVerdicts, AFinalRateOnTheRateLimitHasNoRoomOverTheDurationsProven) {
  // Random bodies whose final rate lies on the rate limit: wherever durations are proven to have
  // no room before the end, the least rate there exceeds the limit at random durations in them.
  const int proven = forEachProvenRange(
      4549, 12, false, [](const PlanningProblem& p, const NoRoomBeforeTheEnd& none, auto draw) {
        for (int j = 0; j < 50; ++j) {
          const double T = none.from + draw() * (none.to - none.from);
          EXPECT_GT(leastRateBeforeTheEnd(p, T), p.final_velocity.norm()) << "T = " << T;
        }
      });
  EXPECT_GE(proven, 6);
}

TEST(BoundedVerdicts, AFinalRateTheTorqueCannotApproachFromInsideIsInfeasibleAtEveryDuration) {
  // J = diag(1, 2, 4) ending at Ω_N = 2 (1, 1, 1)/√3 on the rate limit w = 2 under |τ| ≤ 0.3:
  // d|Ω|²/2dt = Ω·J⁻¹(JΩ × Ω + τ) ≤ −0.1443 w³ + 0.661 a w < 0 there for every allowed torque, so
  // no continuous plan reaches Ω_N from inside the rate ball, and on the paper grid the last free
  // step has no room at any step h (proven over intervals of h): answered before any solve.
  PlanningProblem p = spinningEnd(Vector3(1, 2, 4), Matrix3::Identity(),
                                  2.0 * Vector3(1, 1, 1).normalized(), 0.3, 2.0);
  p = minimumTime(p);
  p.steps = 64;
  const Vector3& W = p.final_velocity;
  const Matrix3 Ji = p.inertia.inverse();
  EXPECT_LT(W.dot(Ji * (p.inertia * W).cross(W)) + 0.3 * (Ji * W).norm(), 0.0);
  const NoRoomBeforeTheEnd none = noRoomBeforeTheEnd(p);
  EXPECT_TRUE(none.everywhere);
  const PlanResult r = planManeuver(p);
  EXPECT_EQ(r.termination, Termination::Infeasible) << r.message();
  EXPECT_TRUE(std::holds_alternative<verdicts::InfeasibleAtEveryDuration>(r.verdict))
      << r.message();
  EXPECT_TRUE(r.attempts.empty());
  // The range proven without a plan is data of the answer.
  EXPECT_EQ(r.duration_verdict.no_plan_from, none.from);
  EXPECT_EQ(r.duration_verdict.no_plan_to, none.to);
  // With 10x the torque the end can be approached from inside (d|Ω|²/2dt > 0 is allowed there):
  // not refused so.
  p.constraints[0] = PlanningConstraint::maxTorqueNorm(3.0);
  EXPECT_GT(W.dot(Ji * (p.inertia * W).cross(W)) + 3.0 * (Ji * W).norm(), 0.0);
  EXPECT_EQ(infeasibleAtEveryDuration(p), "");
}

TEST(BoundedVerdicts, AMinimumEffortRequestInARangeWithoutRoomIsProvenInfeasibleWithTheRange) {
  // Random bodies whose final rate lies on the rate limit: a minimum-effort request at a T inside
  // a range proven without room before the end is answered infeasible before any solve, proven,
  // the range as data; just below the range's start (room there) it is not answered so.
  const int ranges = forEachProvenRange(
      4950, 16, true, [](PlanningProblem p, const NoRoomBeforeTheEnd& none, auto draw) {
        const Vector3 rate = p.final_velocity;
        p.duration = none.from + draw() * (none.to - none.from);
        const PlanResult r = planManeuver(p);
        EXPECT_EQ(r.termination, Termination::Infeasible) << r.message();
        EXPECT_TRUE(r.duration_verdict.proven_infeasible);
        EXPECT_TRUE(std::holds_alternative<verdicts::NoRoomAtDuration>(r.verdict)) << r.message();
        EXPECT_EQ(r.duration_verdict.no_plan_from, none.from);
        EXPECT_EQ(r.duration_verdict.no_plan_to, none.to);
        EXPECT_TRUE(r.attempts.empty());
        // The least rate before the end exceeds the limit at the requested T: no plan exists there.
        EXPECT_GT(leastRateBeforeTheEnd(p, p.duration), rate.norm());
        p.duration = none.from * (1 - 1e-3);
        if (p.duration > discreteDurationLowerBound(p)) {
          EXPECT_FALSE(answerBeforeSolving(p, durationLowerBound(p)).has_value());
        }
      });
  EXPECT_GE(ranges, 4);
}

namespace {

/// The durations a verdict of the search that found no plan says are proven (nothing: another
/// kind).
std::optional<verdicts::ProvenDurations> provenDurationsOf(const Verdict& verdict) {
  if (const auto* v = std::get_if<verdicts::SearchUnrepresentable>(&verdict)) return v->proven;
  if (const auto* v = std::get_if<verdicts::SearchInfeasible>(&verdict)) return v->proven;
  if (const auto* v = std::get_if<verdicts::SearchStopped>(&verdict)) return v->proven;
  return std::nullopt;
}

/// The figure `name` of `verdict` (NaN: none).
double figureOf(const Verdict& verdict, const std::string& name) {
  for (const VerdictFigure& f : verdictFigures(verdict))
    if (f.name == name) return f.value;
  return std::nan("");
}

}  // namespace

TEST(BoundedVerdicts, MinimumTimeWithoutAPlanSaysTheDurationsProvenWithoutOneAsItsDataHasThem) {
  // The seeded suite's #158 (paper, N = 256, its final rate on the rate limit): minimum time
  // finds no plan, and the bounds prove none below the grid's lower bound and none from where
  // the last free step has no room on (up to the largest step at the boundary rates). The
  // verdict holds those durations as data, the same as the answer's duration_verdict; its words
  // say each figure, and the one window left where a plan may lie.
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 158);
  ASSERT_TRUE(request.has_value());
  SCOPED_TRACE(request->label);
  const PlanningProblem& p = request->problem;
  const PlanResult r = planManeuver(p);
  ASSERT_FALSE(r.converged()) << r.message();
  const std::optional<verdicts::ProvenDurations> proven = provenDurationsOf(r.verdict);
  ASSERT_TRUE(proven.has_value()) << r.message();
  EXPECT_EQ(proven->steps, p.steps);
  EXPECT_EQ(proven->least, discreteDurationLowerBound(p));
  ASSERT_TRUE(proven->rangeProven());
  EXPECT_EQ(proven->no_plan_from, r.duration_verdict.no_plan_from);
  EXPECT_EQ(proven->no_plan_to, r.duration_verdict.no_plan_to);
  EXPECT_LT(proven->least, proven->no_plan_from);
  EXPECT_EQ(figureOf(r.verdict, "grid_lower_bound"), proven->least);
  EXPECT_EQ(figureOf(r.verdict, "no_plan_from"), proven->no_plan_from);
  EXPECT_EQ(figureOf(r.verdict, "no_plan_to"), proven->no_plan_to);
  const std::string message = r.message();
  for (const std::string& said :
       {"no plan below " + exactNumber(proven->least) + " s (" + proven->least_basis + ")",
        "none from " + exactNumber(proven->no_plan_from) + " s on (to " +
            exactNumber(proven->no_plan_to) + " s",
        "a plan can lie only in [" + exactNumber(proven->least) + ", " +
            exactNumber(proven->no_plan_from) + ") s"}) {
    EXPECT_NE(message.find(said), std::string::npos) << said << "\n" << message;
  }
  // What the words call proven holds: the last free step has no room inside the range.
  double rate_limit = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : p.constraints)
    if (c.kind == ConstraintKind::MaxAngularRate) rate_limit = std::min(rate_limit, c.limit);
  for (const double f : {0.0, 0.25, 0.5, 0.75, 1.0}) {
    const double T = proven->no_plan_from + f * (proven->no_plan_to - proven->no_plan_from);
    EXPECT_GT(leastRateBeforeTheEnd(p, T), rate_limit) << "T = " << T;
  }
}

TEST(BoundedVerdicts, ElasticFreeTimeStartsNeverEndBelowTheProvenLeastDuration) {
  // An elastic free-time iterate is no plan: its phase traded violation for a T below every
  // plan's on a spinning request of the bounded study's held-out seed 46 (#46, as data here: that
  // seed's references are not in the repository; paper, N = 256, norm bound and rate limit),
  // whose coarse class starts begun from their violations ended at 8.28-8.33 s under the proven
  // 8.595 s. Every coarse start at both elastic barriers ends at or above the floor on its grid.
  PlanningProblem p;
  p.inertia << 14.138140231626437, -13.14804847138962, -9.1253416004876833, -13.14804847138962,
      30.579447516923576, 11.78627806384689, -9.1253416004876833, 11.78627806384689,
      11.011565836368069;
  p.initial_attitude << -0.82936600057099152, 0.54259359572032739, 0.1332074584254356,
      0.49786589576875939, 0.82593452865191597, -0.26450274896663767, -0.25353813702725086,
      -0.15305013643843393, -0.95514086333321946;
  p.final_attitude << 0.28016549894181941, -0.61024244895761726, -0.74102054404239792,
      -0.055188705310766306, 0.76041920107971084, -0.64708333731862977, 0.95836397052936151,
      0.22218639049119121, 0.17936473419179455;
  p.initial_velocity = Vector3(-1.5118626030515825, -0.16725371625865323, -0.21867321968467629);
  p.final_velocity = Vector3(-0.16488544854140738, 0.45302444036048151, 2.3502422591330778);
  p.steps = 256;
  p.scheme = SchemeKind::Paper;
  p.constraints = {PlanningConstraint::maxTorqueNorm(9.5011139798689559),
                   PlanningConstraint::maxAngularRate(6.0939914090523617)};
  p = minimumTime(p);
  const PlanningProblem coarsest = freeTimeLevels(p).front();
  const double floor = discreteDurationLowerBound(coarsest);
  ASSERT_GT(floor, 0.0);
  SolveContext context{SolverOptions{}};
  for (const FreeTimeStart& start : freeTimeStarts(coarsest, false, context)) {
    for (const ElasticBarrier barrier : {ElasticBarrier::Initial, ElasticBarrier::FromViolations}) {
      const FreeTimeOutcome o =
          solveFreeTime(coarsest, start.attitudes, start.duration, 1e-9, 500, context, {}, barrier);
      if (o.maneuver.attitude.empty()) continue;
      EXPECT_GE(o.duration, floor) << start.name << ": " << o.message();
    }
  }
}

TEST(BoundedVerdicts,
     UnderTorqueBoundsAloneAConstrainedWarmStartBeginsTheCoarsestLevelAtItsOptimum) {
  // A plan under a torque box warm-starting minimum effort at a shorter T above the interior
  // point's coarsest grid (the minimum-time search's probes, the restart from T*): only a cone has
  // a side the coarsest level's unconstrained optimum could drop, so without cones that level
  // begins at its unconstrained optimum (a Newton level on the coarsest grid, from the plan
  // resampled) and the answer is a plan at the shorter T.
  PlanningProblem p = sceneProblem("torque_limited", 512);
  const PlanResult plan = planAtResolution(p, {});
  ASSERT_TRUE(plan.converged()) << plan.message();
  p.duration *= 0.97;
  SolveRequest from_plan(SolverOptions{});
  from_plan.warm_start = &plan.maneuver;
  from_plan.start.from_constrained_plan = true;
  SolveContext context(from_plan);
  const PlanResult shorter = planAtResolution(p, from_plan, context);
  EXPECT_TRUE(shorter.converged()) << shorter.message();
  const int coarsest = std::min_element(context.levels().begin(), context.levels().end(),
                                        [](const LevelSummary& a, const LevelSummary& b) {
                                          return a.steps < b.steps;
                                        })
                           ->steps;
  const bool newton_on_coarsest =
      std::any_of(context.levels().begin(), context.levels().end(), [&](const LevelSummary& l) {
        return l.steps == coarsest && l.reason.rfind("interior point", 0) != 0;
      });
  EXPECT_LT(coarsest, p.steps);
  EXPECT_TRUE(newton_on_coarsest);
}

TEST(BoundedVerdicts, AFirstClassWithoutAPlanIsContinuedFromItsPlanUnderTheBoundsOnTheSurveyGrid) {
  // Under torque bounds, where the first class's solve on the requested grid ends without a plan
  // (here stopped at an iteration limit of 2, as a cold start near the least duration ends
  // "infeasible"), the best class under the bounds on the survey's coarse grid is carried to the
  // requested grid from its coarse plan and, where that gives no plan, from its unconstrained
  // optimum (carryUnderBounds). Stated on the seeded suite's minimum-effort requests at N = 64:
  // where a coarse plan under the bounds converged, the first solve on the requested grid starts
  // from it; every answer that converged holds the bounds; and the rule gives plans on some of
  // them.
  constexpr int kSteps = 64;
  int exercised = 0, continued = 0, planned = 0;
  for (int i = 0; i < 60 && exercised < 6; ++i) {
    const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, i);
    if (!request || request->problem.objective != Objective::MinimumEffort ||
        request->kind == "replan" || request->kind == "norm+rate") {
      continue;
    }
    PlanningProblem p = request->problem;
    p.steps = kSteps;
    SCOPED_TRACE(request->label);
    const SolverOptions options;
    SolveContext context(options);
    const SolveRequest asked(options);
    std::vector<ClassPlan> plans;
    PlanResult unconstrained;
    try {
      unconstrained = solveWithNewton(p, asked, context, &plans);
    } catch (const StepTooLarge&) {
      continue;  // N = 64 cannot hold the request's steps
    }
    if (!unconstrained.converged() || !unconstrained.extremal_summary.known) continue;
    const std::size_t first_recorded = context.attempts().size();
    SolverOptions cut = options;
    cut.max_iterations = 2;
    SolveRequest first_request(cut);
    first_request.warm_start = &unconstrained.maneuver;
    PlanResult first;
    {
      const SolveContext::Call call(context, cut);
      first = solveWithInteriorPoint(p, first_request, context);
    }
    if (first.converged()) continue;
    const std::size_t after_first = context.attempts().size();
    const PlanResult r = cheapestConstrainedClass(p, asked, context, unconstrained.extremal_summary,
                                                  plans, first, unconstrained.cost, first_recorded);
    const std::vector<Attempt>& trail = context.attempts();
    std::optional<std::size_t> coarse_plan;  // the first coarse plan under the bounds
    for (std::size_t a = after_first; a < trail.size() && !coarse_plan; ++a) {
      if (trail[a].stage == AttemptStage::Constrained && trail[a].steps < kSteps &&
          trail[a].termination == Termination::Converged) {
        coarse_plan = a;
      }
    }
    if (!coarse_plan) continue;
    ++exercised;
    // The class's first solve on the requested grid starts from its coarse plan.
    const auto first_fine = std::find_if(
        trail.begin() + *coarse_plan + 1, trail.end(),
        [](const Attempt& a) { return a.stage == AttemptStage::Constrained && a.steps == kSteps; });
    const bool from_it =
        first_fine != trail.end() && first_fine->start == AttemptStart::PreviousAttempt;
    EXPECT_TRUE(from_it) << r.message();
    continued += from_it;
    if (r.converged()) {
      ++planned;
      EXPECT_LE(checkConstraints(p, r.maneuver).max_relative_violation, 1e-6) << r.message();
    }
  }
  EXPECT_GE(exercised, 3);
  EXPECT_GE(continued, 1);
  EXPECT_GE(planned, 1);
  RecordProperty("exercised", exercised);
  RecordProperty("continued", continued);
  RecordProperty("planned", planned);
}

/// Minimum effort at 1.05 T* under per-axis torque bounds and a keep-out cone, where the first
/// class ends without a plan on the requested grid (scripts/near_minimum_time_cones.py, seed
/// 9191 #30 and seed 7474 #14; the duration is 1.05 times main's T*).
const char* const kNearTheLeastDurationUnderACone[] = {
    "inertia: [[2.2121386778804291, -0.0064727781838871123, -0.054160142310838232], "
    "[-0.0064727781838871123, 2.1320935127401528, -0.0062827507104379066], [-0.054160142310838232, "
    "-0.0062827507104379066, 2.2409388690820271]]\n"
    "steps: 128\n"
    "scheme: second_order\n"
    "objective: minimum_effort\n"
    "initial: {attitude: {quaternion: [0.21895206630893171, 0.83713011956334171, "
    "0.099241687143981003, -0.49134941041150171]}, angular_velocity: [0, 0, 0]}\n"
    "final: {attitude: {quaternion: [-0.18705466826518327, 0.80597511256400511, "
    "-0.54473209459024163, -0.13668070138453825]}, angular_velocity: [0, 0, 0]}\n"
    "effects: [{actuator_limits: {max_torque: [0.085895741230969477, 0.023826742140102105, "
    "0.017387843053482885]}}]\n"
    "constraints:\n"
    "  - keep_out: {body_axis: [-0.35677833800157588, 0.93175638222124102, -0.067374043390742613], "
    "world_direction: [-0.58456093352922556, -0.66503172326299054, 0.4647809398472541], "
    "half_angle: 0.42032900218845193}\n"
    "duration: 20.680709723033971\n",
    "inertia: [[1.1451055146576339, 0.26168301581586872, 0.02505750365208842], "
    "[0.26168301581586872, 0.75531797387366906, 0.16719331517004593], [0.02505750365208842, "
    "0.16719331517004593, 1.1727665241943992]]\n"
    "steps: 128\n"
    "scheme: second_order\n"
    "objective: minimum_effort\n"
    "initial: {attitude: {quaternion: [0.78484928208051175, 0.50639170033517233, "
    "0.27565971061274469, -0.22713602575165456]}, angular_velocity: [0, 0, 0]}\n"
    "final: {attitude: {quaternion: [0.52410475288991276, 0.32304332246807982, "
    "0.76157064054440426, 0.20240400012789675]}, angular_velocity: [0, 0, 0]}\n"
    "effects: [{actuator_limits: {max_torque: [0.017520112968561857, 0.05148324470221436, "
    "0.014489500847364719]}}]\n"
    "constraints:\n"
    "  - keep_out: {body_axis: [-0.77716726565809724, -0.46034036433974812, -0.42906618387967188], "
    "world_direction: [-0.82020892460116057, -0.48053631685782083, 0.31039034808661081], "
    "half_angle: 0.5053208697987126}\n"
    "duration: 18.981120292613692\n",
};

TEST(BoundedVerdicts, UnderBoundsTheSurveyGridSolvesOnlyClassesThatCouldBeatThePlanInHand) {
  // Under torque bounds a first class without a plan has the surveyed classes solved under the
  // constraints on the survey grid, in order of their survey cost, until the next class's
  // unconstrained optimum there costs at least a plan in hand (the constraints only add to a
  // class's cost). Stated from the answer's extremal: no class solved there after a cheaper plan
  // was in hand, at least one surveyed class left unsolved, and each class left unsolved, solved
  // on its own under the constraints there, gives no plan cheaper than the one in hand.
  for (const char* text : kNearTheLeastDurationUnderACone) {
    const PlanningProblem p = parseScene(text).problem;
    const PlanResult r = planAtResolution(p, SolverOptions{});
    ASSERT_TRUE(r.converged()) << r.message();
    const std::vector<Attempt>& others = r.extremal_summary.others;
    int survey_steps = p.steps;
    for (const Attempt& a : others) {
      if (a.stage == AttemptStage::ClassSurvey) survey_steps = std::min(survey_steps, a.steps);
    }
    std::vector<Attempt> surveyed;  // each class's survey entry on the survey grid
    for (const Attempt& a : others) {
      if (a.stage == AttemptStage::ClassSurvey && a.steps == survey_steps) surveyed.push_back(a);
    }
    const auto surveyCost = [&](const HomotopyClass& c) {
      for (const Attempt& s : surveyed) {
        if (sameHomotopyClass(s.homotopy, c)) return s.cost;
      }
      return std::numeric_limits<double>::quiet_NaN();
    };
    double in_hand = std::numeric_limits<double>::infinity();
    std::vector<HomotopyClass> solved;
    for (const Attempt& a : others) {
      if (a.stage != AttemptStage::ConstrainedClass || a.steps != survey_steps) continue;
      EXPECT_LT(surveyCost(a.homotopy), in_hand);
      solved.push_back(a.homotopy);
      if (a.termination == Termination::Converged) in_hand = std::min(in_hand, a.cost);
    }
    ASSERT_TRUE(std::isfinite(in_hand)) << "no plan under the constraints on the survey grid";
    int skipped = 0;
    for (const Attempt& s : surveyed) {
      const bool was_solved =
          std::any_of(solved.begin(), solved.end(),
                      [&](const HomotopyClass& c) { return sameHomotopyClass(c, s.homotopy); });
      if (was_solved) continue;
      ++skipped;
      PlanningProblem alone = pinnedToClass(p, s.homotopy);
      alone.steps = survey_steps;
      SolverOptions pinned;
      pinned.enumerate_classes = false;
      const PlanResult own = planAtResolution(alone, pinned);
      if (own.converged()) EXPECT_GE(own.cost, in_hand);
    }
    EXPECT_GE(skipped, 1);
  }
}

namespace {

/// Whether `r`'s message holds the note that its probes below T* stopped at their allowance.
bool probesStopped(const PlanResult& r) {
  return std::any_of(r.clauses.begin(), r.clauses.end(), [](const MessageClause& c) {
    const Note* note = std::get_if<Note>(&c);
    return note && std::holds_alternative<notes::ProbesStopped>(*note);
  });
}

/// The cold probes below T* of a minimum-time answer (each a `constrained` attempt on the
/// request's grid from its unconstrained optimum: probedBelow).
long coldProbes(const PlanResult& r, int steps) {
  return std::count_if(r.attempts.begin(), r.attempts.end(), [&](const Attempt& a) {
    return a.stage == AttemptStage::Constrained && a.steps == steps &&
           a.start == AttemptStart::UnconstrainedOptimum;
  });
}

}  // namespace

TEST(SolveContext, WorkCountsEachIterationAtItsGridsStepsAndBranchesJoinIt) {
  SolveContext context{SolverOptions{}};
  IterationInfo info;
  info.steps = 128;
  context.reportIteration(info);
  info.steps = 0;  // a report without a grid counts one
  context.reportIteration(info);
  EXPECT_EQ(context.work(), 129.0);
  const SolveContext::WorkAllowance allowance(context, 300.0);
  SolveContext branch(context, SolveContext::Branch{});
  info.steps = 200;
  branch.reportIteration(info);
  EXPECT_EQ(branch.work(), 329.0);      // the parent's when it began, and its own
  EXPECT_FALSE(allowance.exhausted());  // the parent's own count has not seen it yet
  context.join(branch);
  EXPECT_EQ(context.work(), 329.0);
  EXPECT_FALSE(allowance.exhausted());  // 200 of 300 since it opened
  info.steps = 100;
  context.reportIteration(info);
  EXPECT_TRUE(allowance.exhausted());
  EXPECT_TRUE(allowance.stopped());
}

TEST(BoundedVerdicts, TheProbesBelowTStarStopAtTheirWorkAllowanceAndSaySo) {
  // The spinning study suite's request #12 (N = 124): with the default allowance its probes below
  // T* run to their own end (more than one cold probe: the near probes and rungs of the ladder,
  // BelowAStrictLocalMinimumTheProbesGoOnPastTwoFailuresWithinABudget); with an allowance of one
  // node-iteration the first probe spends it, so it is the only one, and the answer says that the
  // probes stopped.
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 12);
  ASSERT_TRUE(request);
  const int N = request->problem.steps;
  const PlanResult free = planManeuver(request->problem);
  ASSERT_TRUE(free.converged()) << free.message();
  EXPECT_GT(coldProbes(free, N), 1) << free.message();
  EXPECT_FALSE(probesStopped(free)) << free.message();
  SolverOptions options;
  options.advanced.search_work_allowance = 1.0;
  const PlanResult held = planManeuver(request->problem, options);
  ASSERT_TRUE(held.converged()) << held.message();
  EXPECT_EQ(coldProbes(held, N), 1) << held.message();
  EXPECT_TRUE(probesStopped(held)) << held.message();
  EXPECT_GE(held.minimum_duration, free.minimum_duration * (1.0 - 1e-9));
}

TEST(BoundedVerdicts, TheSearchOnDurationsStopsAtItsWorkAllowanceWithAVerdictSayingSo) {
  // The spinning study suite's request #108 (N = 128): the search's first duration holds no plan
  // (SpinningMinimumTimeWithoutAConvergedStartSearchesDurationsUntilAPlan). With an allowance of
  // one node-iteration the search, its coarse grid's included, stops after that first solve:
  // not converged, the verdict search_stopped with the allowance as a figure, not "infeasible".
  const std::optional<robustness::BoundedRequest> request = robustness::boundedRequest(45, 108);
  ASSERT_TRUE(request);
  SolverOptions options;
  options.advanced.search_work_allowance = 1.0;
  SolveContext context(options);
  const PlanResult r = searchMinimumTime(request->problem, context);
  EXPECT_EQ(r.termination, Termination::NotConverged) << r.message();
  EXPECT_TRUE(std::holds_alternative<verdicts::SearchStopped>(r.verdict)) << r.message();
  EXPECT_EQ(figureOf(r.verdict, "work_allowance"), 1.0) << r.message();
}
