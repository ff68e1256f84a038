// Warm starts: re-planning from a state on a plan with the plan's remainder as
// the initial guess recovers the remainder (the target: its cost to 1e-8 in ≤ 2 iterations), a
// warm-started re-plan stays in the guess's homotopy class, guesses of another N are resampled,
// guesses that only start are not refused while malformed ones are (naming the field and the
// row), constrained re-plans start the interior point from the guess with re-derived
// multipliers, and those multipliers solve stationarity.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "planning/interior_point/multiplier_estimate.hpp"
#include "support/random_problems.hpp"

namespace ap = attitude_planner;

namespace {

ap::PlanningProblem scene(const std::string& name, int steps) {
  ap::PlanningProblem p = ap::loadScene(AP_SOURCE_DIR "/scenes/" + name).problem;
  p.steps = steps;
  return p;
}

ap::PlanResult plan(const ap::PlanningProblem& p, const ap::Maneuver* guess = nullptr) {
  ap::SolverOptions o;
  o.warm_start = guess;
  return ap::planManeuver(p, o);
}

/// Σ_{j>k} ½|τ_j|²: the plan's cost still to come after node k (paper and variational).
double remainderCost(const ap::Maneuver& m, int k) {
  double c = 0.0;
  for (int j = k + 1; j < m.steps(); ++j) c += 0.5 * m.torque[j].squaredNorm();
  return c;
}

/// The message of the InvalidInput that planning `p` from `guess` throws ("" if none).
std::string refusal(const ap::PlanningProblem& p, const ap::Maneuver& guess) {
  try {
    plan(p, &guess);
  } catch (const ap::InvalidInput& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// The target: the re-plan from (R_k, Ω_k) warm-started with rows k..N is the remainder, to 1e-8
// in its cost, in at most 2 iterations: spinning states of the seed's slew (both schemes without
// end torques, at three nodes) and random problems with spinning ends.
TEST(WarmStart, RemainderOfThePlanIsRecoveredInAtMostTwoIterations) {
  std::vector<ap::PlanningProblem> problems;
  for (const char* scheme : {"paper", "variational"}) {
    ap::PlanningProblem p = scene("rest_to_rest.yaml", 128);
    ap::applySchemeName(scheme, "scheme", &p);
    problems.push_back(p);
  }
  int spinning = 0;
  for (const auto& c : ap::robustness::randomSuite(19, 8)) {
    // Spinning ends, N ≤ 128 (the suite's larger cases take seconds to plan cold).
    if (c.problem.initial_velocity.isZero() && c.problem.final_velocity.isZero()) continue;
    if (c.problem.steps > 128) continue;
    problems.push_back(c.problem);
    if (++spinning == 3) break;
  }
  ASSERT_EQ(spinning, 3);
  for (const ap::PlanningProblem& p : problems) {
    const ap::PlanResult full = plan(p);
    ASSERT_TRUE(full.converged()) << full.message();
    const int N = p.steps;
    for (const int k : {1, N / 4, N / 2}) {
      SCOPED_TRACE("N = " + std::to_string(N) + ", k = " + std::to_string(k) + ", scheme " +
                   ap::schemeName(p.scheme));
      const ap::PlanningProblem rest = ap::remainderProblem(p, full.maneuver, k);
      ASSERT_FALSE(rest.initial_velocity.isZero());
      const ap::Maneuver guess = ap::remainderOfPlan(full.maneuver, k);
      const ap::PlanResult warm = plan(rest, &guess);
      ASSERT_TRUE(warm.converged()) << warm.message();
      const double expected = remainderCost(full.maneuver, k);
      EXPECT_NEAR(warm.cost, expected, 1e-8 * expected);
      EXPECT_LE(warm.iterations, 2);
    }
  }
}

// Near π both ways round are solved and the cheaper kept, but not when warm-started: the costlier
// way's plan given as the guess of the same request comes back as that way.
TEST(WarmStart, ReplanStaysInTheGuesssHomotopyClass) {
  ap::PlanningProblem p = scene("rest_to_rest.yaml", 64);
  p.inertia = ap::Vector3(10, 12, 14).asDiagonal();  // the short way the cheaper below π
  p.final_attitude = ap::so3::fromAxisAngle(ap::Vector3(1, 0, 0), M_PI - 0.01);
  const ap::PlanResult cheaper = plan(p);
  ap::PlanningProblem long_way = p;
  long_way.direction = ap::RotationDirection::LongWay;
  const ap::PlanResult other = plan(long_way);
  ASSERT_TRUE(cheaper.converged() && other.converged());
  // Both ways were solved cold (the structured extremal lists the other one).
  ASSERT_FALSE(cheaper.extremal_summary.others.empty()) << cheaper.extremal;
  ASSERT_GT(other.cost, 1.001 * cheaper.cost);  // two classes, the cold answer the cheaper
  const ap::PlanResult warm = plan(p, &other.maneuver);
  ASSERT_TRUE(warm.converged()) << warm.message();
  EXPECT_NEAR(warm.cost, other.cost, 1e-9 * other.cost);
  EXPECT_LE(warm.iterations, 1);
}

// A guess of another N is resampled to the problem's grid; the re-plan reaches the cold
// solution's extremal, in fewer iterations than the cold solve (counts, not times).
TEST(WarmStart, GuessOfAnotherResolutionIsResampled) {
  for (const char* name : {"rest_to_rest.yaml", "torque_limited.yaml"}) {
    SCOPED_TRACE(name);
    const ap::PlanResult coarse = plan(scene(name, 64));
    ASSERT_TRUE(coarse.converged()) << coarse.message();
    const ap::PlanningProblem fine = scene(name, 256);
    const ap::Maneuver on_grid = ap::initialGuessOnGrid(coarse.maneuver, fine);
    ASSERT_EQ(on_grid.steps(), 256);
    for (int k = 0; k <= 64; ++k) {  // the coarse nodes are kept
      EXPECT_LE(ap::so3::angleBetween(on_grid.attitude[4 * k], coarse.maneuver.attitude[k]), 1e-12);
    }
    const ap::PlanResult cold = plan(fine);
    const ap::PlanResult warm = plan(fine, &coarse.maneuver);
    ASSERT_TRUE(cold.converged() && warm.converged()) << cold.message() << " | " << warm.message();
    EXPECT_NEAR(warm.cost, cold.cost, 1e-8 * cold.cost);
    EXPECT_LE(warm.iterations, cold.iterations);
  }
}

// A guess is only a start: one planned for other boundary data and another duration is not
// refused, and the solve reaches the problem's own solution.
TEST(WarmStart, GuessThatDoesNotMatchTheBoundaryDataIsOnlyAStart) {
  const ap::PlanningProblem p = scene("rest_to_rest.yaml", 64);
  ap::PlanningProblem other = p;
  other.final_attitude = ap::so3::fromAxisAngle(ap::Vector3(0, 1, 0), 0.7);
  other.duration = 20.0;
  const ap::PlanResult unrelated = plan(other);
  ASSERT_TRUE(unrelated.converged());
  const ap::PlanResult cold = plan(p);
  const ap::PlanResult warm = plan(p, &unrelated.maneuver);
  ASSERT_TRUE(warm.converged()) << warm.message();
  EXPECT_NEAR(warm.cost, cold.cost, 1e-9 * cold.cost);
}

TEST(WarmStart, MalformedGuessesAreRefusedNamingTheRowAndValue) {
  const ap::PlanningProblem p = scene("rest_to_rest.yaml", 16);
  const ap::Maneuver good = plan(p).maneuver;
  ap::Maneuver one_row = good;
  one_row.attitude.resize(1);
  one_row.time.clear();
  one_row.angular_velocity.clear();
  one_row.torque.clear();
  EXPECT_NE(refusal(p, one_row).find("warm_start: needs at least 2 rows (N >= 1), got 1"),
            std::string::npos)
      << refusal(p, one_row);
  ap::Maneuver nan = good;
  nan.attitude[3](0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(p, nan).find("warm_start.attitude[3]: not finite"), std::string::npos)
      << refusal(p, nan);
  ap::Maneuver scaled = good;
  scaled.attitude[5] *= 1.5;
  EXPECT_NE(refusal(p, scaled).find("warm_start.attitude[5]: not a rotation"), std::string::npos)
      << refusal(p, scaled);
  ap::Maneuver nan_torque = good;
  nan_torque.torque[7](2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(p, nan_torque).find("warm_start.torque[7]: not finite"), std::string::npos)
      << refusal(p, nan_torque);
  ap::Maneuver short_torque = good;  // only the attitudes start the solve: not a rule
  short_torque.torque.pop_back();
  EXPECT_EQ(refusal(p, short_torque), "");
  ap::Maneuver inf_rate = good;
  inf_rate.angular_velocity[2](1) = std::numeric_limits<double>::infinity();
  EXPECT_NE(refusal(p, inf_rate).find("warm_start.angular_velocity[2]: not finite: ["),
            std::string::npos)
      << refusal(p, inf_rate);
  EXPECT_NE(refusal(p, inf_rate).find(", inf, "), std::string::npos) << refusal(p, inf_rate);
  EXPECT_EQ(refusal(p, good), "");
}

// Constrained re-plans: the interior point starts from the remainder (its multipliers re-derived)
// and ends at the cold re-plan's optimum with the same constraints active, in fewer iterations
// (counts; the times are in docs/results/warm_start.md).
TEST(WarmStart, ConstrainedReplanStartsFromTheGuess) {
  for (const char* name : {"torque_limited.yaml", "rate_limited.yaml", "sun_keep_out.yaml"}) {
    SCOPED_TRACE(name);
    const ap::PlanningProblem p = scene(name, 128);
    const ap::PlanResult full = plan(p);
    ASSERT_TRUE(full.converged()) << full.message();
    ASSERT_GT(full.active_constraints, 0);
    const ap::PlanningProblem rest = ap::remainderProblem(p, full.maneuver, 32);
    const ap::Maneuver guess = ap::remainderOfPlan(full.maneuver, 32);
    const ap::PlanResult cold = plan(rest);
    const ap::PlanResult warm = plan(rest, &guess);
    ASSERT_TRUE(cold.converged() && warm.converged()) << cold.message() << " | " << warm.message();
    ASSERT_FALSE(warm.attempts.empty());
    EXPECT_EQ(warm.attempts.front().start, ap::AttemptStart::WarmStart);
    EXPECT_EQ(warm.attempts.front().stage, ap::AttemptStage::Constrained);
    EXPECT_NEAR(warm.cost, cold.cost, 1e-7 * cold.cost);
    EXPECT_LE(warm.max_constraint_violation, 1e-9);
    // From the plan's own remainder, its multipliers re-derived and centered: at most half the
    // iterations of the cold re-plan's grid continuation.
    EXPECT_LE(2 * warm.iterations, cold.iterations) << warm.iterations << " vs " << cold.iterations;
  }
}

// The estimate solves stationarity where it can: ∇f = 2 g_0 + 3 g_1 over two near-active
// columns is recovered; a near-active column that would need a negative multiplier is dropped;
// an inactive one gets a small multiplier and its value as slack, and so does a near-active one
// whose value is above the central slack (the free-slack residual c − s starts at zero).
TEST(MultiplierEstimate, RecoversTheMultipliersOfStationarity) {
  std::vector<ap::StationarityColumn> columns(5);
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(9);
  columns[0].value = 1e-9;
  columns[0].gradient << 1, 0, 0, 0, 1, 0, 0, 0, 0;
  columns[0].index = {0, 3, 6};
  columns[1].value = -1e-5;  // slightly violated: still active
  columns[1].gradient << 0, 0, 0, 0, 0, 1, 0, 2, 0;
  columns[1].index = {0, 3, 6};
  columns[2].value = 0.0;  // would need z = −1
  columns[2].gradient << 0, 0, 0, 0, 0, 0, 0, 0, 1;
  columns[2].index = {0, 3, 6};
  columns[3].value = 0.5;  // inactive
  columns[3].gradient << 1, 1, 1, 0, 0, 0, 0, 0, 0;
  columns[3].index = {0, 3, 6};
  columns[4].value = 1e-4;  // near-active, not pushed against (∇f has no component along it)
  columns[4].gradient << 0, 0, 0, 1, 0, 0, 0, 0, 0;
  columns[4].index = {0, 3, 6};
  gradient = 2.0 * columns[0].gradient + 3.0 * columns[1].gradient - columns[2].gradient;
  const ap::MultiplierEstimate e = ap::estimateMultipliers(gradient, columns, 1.0);
  EXPECT_EQ(e.active, 2);
  // The least-squares multipliers 2 and 3; centering keeps each at least the mean (2.5), whose
  // central slack is the most a binding column is pushed off its bound.
  EXPECT_NEAR(e.z[0], 2.5, 1e-8);
  EXPECT_NEAR(e.z[1], 3.0, 1e-8);
  // Centered on μ = kEstimateComplementarity × the mean active multiplier: s_i z_i = μ for
  // every column, no slack below its value, the dropped near-active column at zero off the
  // corner s = z = 0 (the central slack kEstimateComplementarity), the others at their value.
  const double mu = ap::kEstimateComplementarity * 2.5;
  EXPECT_NEAR(e.complementarity, mu, 1e-20);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    EXPECT_NEAR(e.s[i] * e.z[i], mu, 1e-12 * mu) << i;
    EXPECT_GE(e.s[i], std::max(columns[i].value, 0.0)) << i;
  }
  EXPECT_NEAR(e.s[0], ap::kEstimateComplementarity, 1e-20);
  EXPECT_NEAR(e.s[1], mu / 3.0, 1e-20);
  EXPECT_NEAR(e.s[2], ap::kEstimateComplementarity, 1e-20);
  EXPECT_EQ(e.s[3], 0.5);
  EXPECT_EQ(e.s[4], 1e-4);
}
