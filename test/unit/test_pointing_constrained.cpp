// The pointing end condition under stage constraints and torque bounds: the twist ψ as a global
// unknown of the fixed-h interior point (ConstrainedSystem's border column and corner, every
// constraint row's ψ-derivative through R_{N−1} and R_N) against central differences for every
// scheme, and the planned answer against a 5° sweep of fixed-attitude constrained solves refined by
// golden section on seeded random requests (a keep-out cone, torque bounds, spinning starts), each
// solved as one problem (the interior point with ψ free from unconstrained optima, no fixed-twist
// interior point; an optimum on a cone's ridge started from both its sides).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>

#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/drivers/constrained_recipe.hpp"
#include "planning/drivers/pointing.hpp"
#include "planning/interior_point/constrained_system.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "support/perturbed_problem.hpp"
#include "support/pointing_requests.hpp"

using namespace attitude_planner;
using test_support::PointingBinding;

namespace {

constexpr SchemeKind kDiscretizations[] = {SchemeKind::Paper, SchemeKind::Variational,
                                           SchemeKind::SecondOrder};

/// A pointing request at ψ = 0.7 with every kind of row, each near R_N so that ψ moves it: a
/// keep-out cone on an axis other than the boresight (its value at R_N depends on ψ), a rate
/// limit, a torque norm and a torque box, all below what the perturbed iterate does (violated rows
/// exercise the elastic terms).
PlanningProblem everyRowRequest(SchemeKind scheme) {
  PlanningProblem p = test_support::randomPointingRequest(61, 24, true, scheme);
  p.final_attitude = pointingAttitude(p.end_condition, 0.7);
  const Vector3 axis = p.end_condition.body_axis.cross(Vector3(0.3, -0.5, 0.8)).normalized();
  const Vector3 near_end = p.final_attitude * so3::exp(Vector3(0.4, 0.2, -0.3)) * axis;
  p.constraints.push_back(PlanningConstraint::keepOut(axis, near_end, 0.6));
  p.constraints.push_back(PlanningConstraint::maxAngularRate(0.5));
  p.constraints.push_back(PlanningConstraint::maxTorqueNorm(0.05));
  p.max_torque = Vector3::Constant(0.04);
  return p;
}

/// The elastic merit φ_μ and its gradient (δ, ψ) at `rp` moved by Δψ, with a system built anew
/// (an assembly with the matrix: the elastic slacks are formed there).
struct MeritAt {
  double merit = 0.0;
  Eigen::VectorXd gradient;
};
MeritAt meritAt(const PlanningProblem& p, const ReducedProblem& rp, double dpsi, double mu,
                double rho) {
  ReducedProblem q = rp;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.unknowns());
  q.setCurrentWithTwist(q.retractWithTwist(zero, dpsi, 1.0), dpsi);
  const InteriorPointParameters parameters;
  ConstrainedSystem system(p, &q, Formulation::Elastic, parameters);
  MeritAt out;
  out.merit = system.merit(q.current(), mu, rho, nullptr);
  Eigen::VectorXd rhs;
  KktBlocks<double> kkt(q.unknowns());
  system.assemble<double>(mu, rho, true, &kkt, &rhs, &out.gradient);  // slacks formed
  return out;
}

}  // namespace

// With the elastic form's primal multipliers (μ/s) the condensed matrix is the exact Hessian of
// φ_μ (constrained_system.hpp): its ψ border and corner are the central differences of the
// assembled gradient, whose ψ entry is the central difference of φ_μ itself (a fresh system on the
// twisted problem each time: the rows on R_{N−1}, R_N are re-evaluated from the moved attitudes).
TEST(ConstrainedTwist, BorderAndGradientMatchCentralDifferencesForEveryScheme) {
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    const PlanningProblem p = everyRowRequest(scheme);
    ReducedProblem rp = test_support::perturbedReducedProblem(p, 17);
    const int n = rp.unknowns();
    const double mu = 1e-3, rho = 10.0;
    const InteriorPointParameters parameters;
    ConstrainedSystem system(p, &rp, Formulation::Elastic, parameters);
    ASSERT_EQ(system.globals(), 1);
    const double merit = system.merit(rp.current(), mu, rho, nullptr);
    KktBlocks<double> kkt(n);
    Eigen::VectorXd rhs, gradient;
    system.assemble<double>(mu, rho, true, &kkt, &rhs, &gradient);
    ASSERT_EQ(gradient.size(), n + 1);
    ASSERT_EQ(kkt.globals(), 1);
    const Eigen::VectorXd border = kkt.border.col(0);
    const double corner = kkt.corner(0, 0);
    EXPECT_GT(std::abs(gradient(n)), 1e-6);  // ψ matters here: the test can fail
    const double e = 1e-5;
    const MeritAt plus = meritAt(p, rp, e, mu, rho), minus = meritAt(p, rp, -e, mu, rho);
    const double slope = (plus.merit - minus.merit) / (2 * e);
    EXPECT_NEAR(gradient(n), slope, 1e-6 * (std::abs(slope) + std::abs(merit)));
    const Eigen::VectorXd fd = (plus.gradient - minus.gradient) / (2 * e);
    const double size = border.cwiseAbs().maxCoeff() + std::abs(corner);
    EXPECT_LT((fd.head(n) - border).cwiseAbs().maxCoeff(), 1e-5 * size);
    EXPECT_NEAR(corner, fd(n), 1e-5 * size);
    EXPECT_GT(border.cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(ConstrainedTwist, FixedEndHasNoBorder) {
  PlanningProblem p = everyRowRequest(SchemeKind::Paper);
  p.end_condition = EndCondition();
  ReducedProblem rp(p);
  const InteriorPointParameters parameters;
  ConstrainedSystem system(p, &rp, Formulation::FreeSlacks, parameters);
  EXPECT_EQ(system.globals(), 0);
}

namespace {

/// The answer against the sweep: cost at most its best + 1e-6 relative, the end condition met,
/// the constraints held and ψ stationary.
PlanResult expectAtMostTheSweep(const PlanningProblem& p) {
  const PlanResult r = planManeuver(p);
  EXPECT_TRUE(r.converged()) << r.message();
  EXPECT_TRUE(r.pointing.active);
  if (!r.converged() || !r.pointing.active) return r;
  const test_support::TwistSweep sweep = test_support::sweepTwist(p);
  EXPECT_LE(r.cost, sweep.best * (1.0 + 1e-6))
      << "swept best " << sweep.best << " at twist " << sweep.best_twist << ", answer twist "
      << r.pointing.final_twist;
  EXPECT_LT(r.pointing.error, 1e-9);
  EXPECT_LT(pointingError(r.maneuver.attitude.back(), p.end_condition), 1e-9);
  EXPECT_LT(r.max_constraint_violation, 1e-6);
  EXPECT_LT(r.pointing.twist_stationarity, 1e-6);
  return r;
}

/// expectAtMostTheSweep, and the request solved as one problem: its trail holds the twist
/// Newton's starts (every start twist each way round), unconstrained solves (their refinements,
/// fixed-twist optima) and interior-point runs with ψ free from those optima (or an optimum that
/// meets every constraint itself), no fixed-twist interior point; the answer is the cheapest run.
void expectOneProblemAtMostTheSweep(const PlanningProblem& p) {
  const PlanResult r = expectAtMostTheSweep(p);
  EXPECT_EQ(r.pointing.starts, 2 * kPointingStartTwists);
  int surveyed = 0, interior = 0;
  double cheapest = std::numeric_limits<double>::infinity();
  for (const Attempt& a : r.attempts) {
    SCOPED_TRACE(attemptStageName(a.stage) + " from " + attemptStartName(a.start));
    surveyed += a.stage == AttemptStage::ClassSurvey;
    if (a.stage != AttemptStage::Constrained) {
      EXPECT_EQ(a.formulation, Formulation::Unconstrained);
      continue;
    }
    EXPECT_EQ(a.start, AttemptStart::UnconstrainedOptimum);
    // An interior-point run, or an unconstrained ψ optimum meeting every node constraint taken as
    // it is (the constrained optimum of its basin: no iterations of its own).
    if (a.formulation == Formulation::Unconstrained) EXPECT_EQ(a.iterations, 0);
    if (a.termination == Termination::Converged) cheapest = std::min(cheapest, a.cost);
    ++interior;
  }
  EXPECT_EQ(surveyed, 2 * kPointingStartTwists);
  EXPECT_GE(interior, 1);
  EXPECT_DOUBLE_EQ(cheapest, r.cost);
}

/// The generator's spinning request `seed` under a torque box (paper, N = 32) at 0.8 of its T:
/// every start ends certified locally infeasible.
PlanningProblem spinningUnderATorqueBoxAtFourFifthsOfT(unsigned seed) {
  PlanningProblem p = test_support::randomConstrainedPointingRequest(
      seed, 32, true, SchemeKind::Paper, PointingBinding::TorqueBox);
  p.duration *= 0.8;
  return p;
}

}  // namespace

TEST(ConstrainedTwist, AFeasibleIteratesLowerBoundIsBelowTheEndAndItsWatchStopsTheSolve) {
  // The interior point with ψ free from the geodesic at ψ = 0.3 on seeded requests (a cone, a
  // torque box, a spinning start): every bound it reports lies below the cost it converges to,
  // and a watch that stops once the bound passes just below that cost ends it sooner.
  int bounds = 0;
  const std::pair<unsigned, PointingBinding> requests[] = {{201u, PointingBinding::KeepOut},
                                                           {202u, PointingBinding::KeepOut},
                                                           {211u, PointingBinding::TorqueBox},
                                                           {221u, PointingBinding::KeepOut}};
  for (const auto& [seed, binding] : requests) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    PlanningProblem p = test_support::randomConstrainedPointingRequest(seed, 32, seed == 221u,
                                                                       SchemeKind::Paper, binding);
    p.final_attitude = pointingAttitude(p.end_condition, 0.3);
    std::vector<FeasibleIterate> seen;
    const FeasibleIterateWatch silent = [&seen](const FeasibleIterate& at) {
      seen.push_back(at);
      return std::string();
    };
    SolveContext context{SolverOptions{}};
    const GridOutcome plain =
        solveInteriorPointOnGrid(p, SolverOptions{}, context, nullptr, nullptr, &silent);
    if (!plain.result.converged()) continue;
    const double end = plain.result.cost;
    for (const FeasibleIterate& at : seen) {
      EXPECT_LE(at.lower_bound, end * (1.0 + 1e-9)) << "iteration " << at.iteration;
      EXPECT_GE(at.cost, at.lower_bound);
    }
    bounds += static_cast<int>(seen.size());
    const auto first_above = std::find_if(seen.begin(), seen.end(), [&](const FeasibleIterate& at) {
      return at.lower_bound > end * (1.0 - 1e-3);
    });
    if (first_above == seen.end()) continue;
    const FeasibleIterateWatch stop = [&](const FeasibleIterate& at) {
      return at.lower_bound > end * (1.0 - 1e-3) ? std::string("bound passed") : std::string();
    };
    SolveContext again{SolverOptions{}};
    const GridOutcome stopped =
        solveInteriorPointOnGrid(p, SolverOptions{}, again, nullptr, nullptr, &stop);
    EXPECT_TRUE(stopped.stopped_by_watch);
    EXPECT_EQ(stopped.result.termination, Termination::NotConverged);
    EXPECT_LT(stopped.result.iterations, plain.result.iterations);
  }
  EXPECT_GE(bounds, 4);  // the bound was put to the test
}

TEST(ConstrainedPointingPlan, KeepOutConeAtMostTheSweepsBest) {
  for (unsigned seed : {201u, 202u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expectOneProblemAtMostTheSweep(test_support::randomConstrainedPointingRequest(
        seed, 32, false, SchemeKind::Paper, PointingBinding::KeepOut));
  }
}

TEST(ConstrainedPointingPlan, TorqueBoundsAtMostTheSweepsBest) {
  SCOPED_TRACE("box");
  expectOneProblemAtMostTheSweep(test_support::randomConstrainedPointingRequest(
      211, 32, false, SchemeKind::Paper, PointingBinding::TorqueBox));
  SCOPED_TRACE("norm, second_order");
  expectOneProblemAtMostTheSweep(test_support::randomConstrainedPointingRequest(
      212, 32, false, SchemeKind::SecondOrder, PointingBinding::TorqueNorm));
}

TEST(ConstrainedPointingPlan, SpinningStartUnderAConeAtMostTheSweepsBest) {
  expectOneProblemAtMostTheSweep(test_support::randomConstrainedPointingRequest(
      221, 32, true, SchemeKind::Paper, PointingBinding::KeepOut));
}

TEST(ConstrainedPointingPlan, SpinningStartUnderATorqueBoxAtMostTheSweepsBest) {
  expectOneProblemAtMostTheSweep(test_support::randomConstrainedPointingRequest(
      223, 32, true, SchemeKind::SecondOrder, PointingBinding::TorqueBox));
}

TEST(ConstrainedPointingPlan, LocalInfeasibilityCertifiedFromEnoughStartsEndsTheStartLoop) {
  // A spinning start under a torque box with 0.8 of the generator's T: every interior point with
  // ψ free ends with its certificate of local infeasibility. Once 4 distinct starts (twist, way
  // round) hold one, the start twists' fixed-twist constrained optima (interior-point attempts of
  // stage solve) are not run; the verdict is not converged or infeasible, never converged.
  for (unsigned seed : {231u, 232u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanResult r = planManeuver(spinningUnderATorqueBoxAtFourFifthsOfT(seed));
    EXPECT_FALSE(r.converged()) << r.message();
    std::set<std::pair<long, bool>> certified;
    int fixed_twist_interior_points = 0;
    for (const Attempt& a : r.attempts) {
      if (a.stage == AttemptStage::Constrained && a.termination == Termination::Infeasible &&
          std::isfinite(a.start_detail.twist)) {
        certified.insert({std::lround(a.start_detail.twist * 1e4), a.homotopy.long_way});
      }
      const bool interior_point = a.formulation != Formulation::Unconstrained;
      fixed_twist_interior_points += a.stage == AttemptStage::Solve && interior_point;
    }
    EXPECT_GE(certified.size(), std::size_t(kPointingStartTwists));
    EXPECT_EQ(fixed_twist_interior_points, 0);
  }
}

namespace {

/// The least margin of `p`'s cones over the nodes of `plan` (node bounds) relative to each cone's
/// node half angle (−1 on its axis).
double leastConeMargin(const PlanningProblem& p, const Maneuver& plan) {
  double least = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : p.constraints) {
    if (!c.isCone()) continue;
    for (const Matrix3& R : plan.attitude) {
      least = std::min(least, (coneMargin(c, R) - c.margin) / c.nodeHalfAngle());
    }
  }
  return least;
}

/// Whether the constrained attempts of `r` include one started at `twist` (modulo 2π).
bool startedAt(const PlanResult& r, double twist) {
  for (const Attempt& a : r.attempts) {
    if (a.stage == AttemptStage::Constrained &&
        std::abs(std::remainder(a.start_detail.twist - twist, 2.0 * M_PI)) < 1e-6) {
      return true;
    }
  }
  return false;
}

}  // namespace

TEST(ConstrainedPointingPlan, AConesRidgeIsStartedFromBothSidesAndAtMostTheSweepsBest) {
  // Where the unconstrained twist optimum ψ* (the request without its cone) crosses the cone
  // near its axis (deeper than kPointingRidgeDepth of its half angle) and deeper than the
  // fixed-twist unconstrained optima at ψ* ± kPointingRidgeOffset, each measured
  // here on planManeuver's own plans, the constrained cost over ψ has a ridge at ψ*: the interior
  // point with ψ free starts from both those optima, else from ψ*'s. Either way the answer is at
  // most the sweep's best. Seeded so that both kinds occur.
  int ridges = 0, others = 0;
  for (unsigned seed : {201u, 202u, 203u, 204u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanningProblem p = test_support::randomConstrainedPointingRequest(
        seed, 32, false, SchemeKind::Paper, PointingBinding::KeepOut);
    PlanningProblem free_of_cones = p;
    free_of_cones.constraints.clear();
    const PlanResult optimum = planManeuver(free_of_cones);
    ASSERT_TRUE(optimum.converged()) << optimum.message();
    const double twist = optimum.pointing.final_twist;
    const double deepest = leastConeMargin(p, optimum.maneuver);
    bool ridge = deepest < -kPointingRidgeDepth;
    for (const double offset : {-kPointingRidgeOffset, kPointingRidgeOffset}) {
      PlanningProblem fixed = free_of_cones;
      fixed.end_condition = EndCondition();
      fixed.final_attitude = pointingAttitude(p.end_condition, twist + offset);
      const PlanResult side = planManeuver(fixed);
      ASSERT_TRUE(side.converged()) << side.message();
      ridge = ridge && leastConeMargin(p, side.maneuver) > deepest;
    }
    const PlanResult r = expectAtMostTheSweep(p);
    const bool both_sides =
        startedAt(r, twist - kPointingRidgeOffset) && startedAt(r, twist + kPointingRidgeOffset);
    EXPECT_EQ(both_sides, ridge) << "twist optimum " << twist << ", least margin " << deepest;
    (ridge ? ridges : others) += 1;
  }
  EXPECT_GE(ridges, 1);
  EXPECT_GE(others, 1);
}

TEST(ConstrainedPointingPlan, AnInfeasibleAnswerSolvesMinimumTimeOverTheTwistOnly) {
  // The requests of the test above (every start certified locally infeasible): no plan at the
  // unconverged run's twist either, and minimum time is solved over the twist only (every
  // minimum-time attempt has its start twist), not again at that one fixed twist: an infeasible
  // verdict names the least T over the twist, above T.
  for (unsigned seed : {231u, 232u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanningProblem p = spinningUnderATorqueBoxAtFourFifthsOfT(seed);
    const PlanResult r = planManeuver(p);
    EXPECT_FALSE(r.converged()) << r.message();
    int over_the_twist = 0;
    for (const Attempt& a : r.attempts) {
      if (a.stage != AttemptStage::MinimumTimeSolve) continue;
      EXPECT_TRUE(std::isfinite(a.start_detail.twist));
      ++over_the_twist;
    }
    EXPECT_GE(over_the_twist, 1);
    if (r.termination == Termination::Infeasible) {
      EXPECT_EQ(r.pointing.infeasible_basis, PointingInfeasibleBasis::MinimumTimeOverTwist);
      EXPECT_GT(r.duration_verdict.least_duration_found, p.duration);
    }
  }
}
