// The stage constraints (planning/transcription/stage_constraints.hpp): the list one problem
// builds, each constraint's value and derivatives composed with its quantity's (the chain rule the
// assemblers apply, and the interior points' chain rule on their rows) against central differences
// in the node unknowns δ and in the time step h;
// and minimum time with a keep-out cone or a rate limit (free_time_solver.cpp): a KKT point within
// the constraints, no slower than the search on T it replaced, and the same in a rotated world.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "planning/crosscheck/nlopt_solver.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/transcription/node_constraints.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "planning/transcription/stage_transcription.hpp"
#include "support/quantity_differences.hpp"
#include "support/scene_problem.hpp"
#include "support/searched_minimum_time.hpp"
#include "support/turned_world.hpp"

namespace ap = attitude_planner;

namespace {

ap::PlanningProblem scene(const char* name, int steps) {
  return ap::test_support::sceneProblem(name, steps);
}

/// How far above the search's T a cone answer may sit (a missed basin, not a wrong KKT point).
constexpr double kConeBasinTolerance = 5e-3;

/// The search on T over minimum-effort solves (an upper bound) on the same discrete problem.
using ap::test_support::searchedMinimumTime;

/// sun_keep_out's cone, body x at least 0.5 rad from a direction near the eigenaxis path.
ap::PlanningConstraint sunCone() {
  return ap::PlanningConstraint::keepOut(
      ap::Vector3::UnitX(),
      ap::Vector3(0.7035741925769524, 0.7035741925769523, 0.09983341664682815), 0.5);
}

/// A problem with every kind: the box, a norm bound, a rate limit and both cones.
ap::PlanningProblem everyKind(ap::SchemeKind scheme) {
  ap::PlanningProblem p = scene("torque_limited", 16);
  p.scheme = scheme;
  p.constraints = {ap::PlanningConstraint::maxTorqueNorm(0.5),
                   ap::PlanningConstraint::maxAngularRate(0.3),
                   ap::PlanningConstraint::keepOut(ap::Vector3::UnitZ(), ap::Vector3::UnitY(), 0.4),
                   ap::PlanningConstraint::keepIn(ap::Vector3::UnitX(), ap::Vector3::UnitX(), 1.5)};
  return p;
}

/// A reduced problem of `p` moved off its start by a seeded random δ (so torques, rates and
/// pointing are all nonzero and generic).
ap::ReducedProblem perturbed(const ap::PlanningProblem& p, int seed) {
  ap::ReducedProblem np(p);
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 0.05);
  Eigen::VectorXd delta(np.unknowns());
  for (int i = 0; i < delta.size(); ++i) delta(i) = normal(rng);
  np.setCurrent(np.retract(delta, 1.0));
  return np;
}

/// The values c_k of `constraint` at np's current iterate, k over its support (the assemblers'
/// quantities: torques, step rates, pointing cosines).
std::vector<double> valuesOf(const ap::StageConstraint& constraint, const ap::ReducedProblem& np) {
  const ap::StageSupport s =
      ap::stageSupport(constraint.quantity(), np.firstFreeNode(), np.lastFreeNode());
  const std::vector<ap::Vector3> tau = np.torques(np.current());
  const std::vector<ap::Matrix3> R = np.attitudes(np.current());
  std::vector<double> out;
  for (int k = s.first_k; k <= s.last_k; ++k) {
    ap::Vector3 q = ap::Vector3::Zero();
    switch (constraint.quantity()) {
      case ap::StageQuantity::Torque:
        q = tau[k];
        break;
      case ap::StageQuantity::StepRate:
        q(0) = ap::angularRateTerms(np.scheme(), np.current()[k]).half_squared_rate;
        break;
      case ap::StageQuantity::Pointing:
        q(0) = ap::pointingTerms(R[k], constraint.spec()->body_axis,
                                 constraint.spec()->world_direction)
                   .cosine;
        break;
      case ap::StageQuantity::NodeRate:  // the plan's node velocity J⁻¹Π_k
        q(0) = 0.5 * np.maneuver(np.current()).angular_velocity[k].squaredNorm();
        break;
      case ap::StageQuantity::WheelMomentum:  // their own suite: test_reaction_wheels
      case ap::StageQuantity::WheelTorque:
        q = constraint.quantityModel().value(ap::QuantityInputs(np, np.current()), k);
        break;
    }
    out.push_back(constraint.value(q));
  }
  return out;
}

}  // namespace

TEST(StageConstraints, OneListInAFixedOrderWithTheRateOnTheSchemesQuantity) {
  const ap::PlanningProblem p = everyKind(ap::SchemeKind::Paper);
  const ap::StageConstraints list = ap::buildStageConstraints(p);
  ASSERT_EQ(list.size(), 10u);  // 6 box sides, norm, rate, two cones
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(list[i]->quantity(), ap::StageQuantity::Torque);
    EXPECT_EQ(list[i]->axis(), i / 2);
    EXPECT_EQ(list[i]->spec(), nullptr);
  }
  EXPECT_EQ(list[6]->axis(), -1);
  EXPECT_EQ(list[7]->quantity(), ap::StageQuantity::StepRate);
  EXPECT_EQ(list[8]->quantity(), ap::StageQuantity::Pointing);
  EXPECT_EQ(list[9]->quantity(), ap::StageQuantity::Pointing);
  EXPECT_EQ(ap::buildStageConstraints(everyKind(ap::SchemeKind::SecondOrder))[7]->quantity(),
            ap::StageQuantity::NodeRate);
  // Descriptions name the rule, one wording each: the box's for both of its sides,
  // describeConstraint's for the rest.
  EXPECT_EQ(list[0]->describe(), "|tau_x| <= 0.264 N m");
  EXPECT_EQ(list[1]->describe(), list[0]->describe());
  EXPECT_EQ(list[6]->describe(), ap::describeConstraint(p.constraints[0]));
  EXPECT_EQ(list[8]->describe(), ap::describeConstraint(p.constraints[2]));
  // Zero at the bound, one at the centre (dimensionless as the interior point needs them).
  EXPECT_NEAR(list[0]->value(ap::Vector3(0.264, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(list[1]->value(ap::Vector3(-0.264, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(list[6]->value(ap::Vector3(0.3, 0.4, 0.0)), 0.0, 1e-15);
  EXPECT_NEAR(list[7]->value(ap::Vector3(0.5 * 0.3 * 0.3, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(list[8]->value(ap::Vector3(std::cos(0.4), 0, 0)), 0.0, 1e-15);
  EXPECT_GT(list[8]->value(ap::Vector3(0.0, 0, 0)), 0.0) << "keep_out: far from s holds";
  EXPECT_LT(list[9]->value(ap::Vector3(0.0, 0, 0)), 0.0) << "keep_in: far from s fails";
}

namespace {

/// Every ConstraintKind, by its name table (a kind added to the enum and its name is in it).
std::vector<ap::ConstraintKind> everyConstraintKind() {
  std::vector<ap::ConstraintKind> out;
  for (int i = 0; ap::constraintKindName(static_cast<ap::ConstraintKind>(i)) != "unknown"; ++i)
    out.push_back(static_cast<ap::ConstraintKind>(i));
  return out;
}

/// An example of `kind` on `plan` (rest_to_rest's unconstrained optimum): `factor` < 1 makes it
/// violated there (its limit, or a cone about the middle node's pointing whose angle is that
/// fraction of the plan's largest; keep_out: about that pointing), > 1 leaves it met (keep_out:
/// about the antipode) or barely active (limits at 0.8). None for a kind this test does not know:
/// the test then fails, naming it.
std::optional<ap::PlanningConstraint> exampleOf(ap::ConstraintKind kind, const ap::Maneuver& plan,
                                                double factor) {
  const int N = plan.steps();
  const ap::Vector3 axis =
      ap::so3::log(ap::Matrix3(plan.attitude[0].transpose() * plan.attitude[N])).normalized();
  const ap::Vector3 b = axis.unitOrthogonal();  // swept by the rotation
  const ap::Vector3 s = plan.attitude[N / 2] * b;
  double peak_torque = 0.0, peak_rate = 0.0, widest = 0.0;
  for (int k = 0; k <= N; ++k) {
    peak_torque = std::max(peak_torque, plan.torque[k].norm());
    peak_rate = std::max(peak_rate, plan.angular_velocity[k].norm());
    widest = std::max(widest, std::acos(std::min(1.0, s.dot(plan.attitude[k] * b))));
  }
  switch (kind) {
    case ap::ConstraintKind::MaxTorqueNorm:
      return ap::PlanningConstraint::maxTorqueNorm(factor * peak_torque);
    case ap::ConstraintKind::MaxAngularRate:
      return ap::PlanningConstraint::maxAngularRate(factor * peak_rate);
    case ap::ConstraintKind::KeepOut:  // about the middle pointing (violated) or its antipode
      return ap::PlanningConstraint::keepOut(b, factor < 1 ? s : ap::Vector3(-s), 0.2);
    case ap::ConstraintKind::KeepIn:
      return ap::PlanningConstraint::keepIn(b, s, factor * widest);
  }
  return std::nullopt;
}

/// The quantity q (the interior point's) of a row quantity r (the dense NLPs'): ½|Ω|² for rates.
ap::Vector3 stageQuantityOfRow(ap::StageQuantity quantity, const ap::Vector3& r) {
  const bool rate =
      quantity == ap::StageQuantity::StepRate || quantity == ap::StageQuantity::NodeRate;
  return rate ? ap::Vector3(0.5 * r.squaredNorm(), 0.0, 0.0) : r;
}

/// q of constraint `c` at instance k of a plan (the plan's torques, reported rates, attitudes).
ap::Vector3 quantityOnPlan(const ap::StageConstraint& c, const ap::Maneuver& plan, int k) {
  switch (c.quantity()) {
    case ap::StageQuantity::Torque:
      return plan.torque[k];
    case ap::StageQuantity::StepRate:
    case ap::StageQuantity::NodeRate:
      return ap::Vector3(0.5 * plan.angular_velocity[k].squaredNorm(), 0.0, 0.0);
    case ap::StageQuantity::Pointing:
      return ap::Vector3(c.spec()->world_direction.dot(plan.attitude[k] * c.spec()->body_axis), 0.0,
                         0.0);
    case ap::StageQuantity::WheelMomentum:  // their own suite: test_reaction_wheels
    case ap::StageQuantity::WheelTorque:
      return c.quantityModel().valueOnPlan(plan, k);
  }
  return ap::Vector3::Zero();
}

}  // namespace

// Adding a constraint is one class: the interior point (c, ∂c), the plan's check (slackOnPlan)
// and the dense NLPs' rows (the NLopt cross-check, the IPOPT peer) all read it. For every kind:
// the class exists, its row is one-sided with derivatives that match central differences and
// holds exactly where c ≥ 0, the checker's slack has c's sign on a plan and names the kind, and
// NLopt solves with it (converged, within the bound).
TEST(StageConstraints, EveryKindIsOneClassThatTheCheckerAndTheDenseRowsRead) {
  ap::PlanningProblem base = scene("rest_to_rest", 16);
  const ap::PlanResult free_plan = ap::planManeuver(base);
  ASSERT_TRUE(free_plan.converged()) << free_plan.message();
  const ap::Maneuver& plan = free_plan.maneuver;
  std::mt19937 rng(29);
  std::normal_distribution<double> normal(0.0, 0.4);
  const std::vector<ap::ConstraintKind> kinds = everyConstraintKind();
  ASSERT_GE(kinds.size(), 4u);
  for (const ap::ConstraintKind kind : kinds) {
    const std::string name = ap::constraintKindName(kind);
    const std::optional<ap::PlanningConstraint> tight = exampleOf(kind, plan, 0.5);
    ASSERT_TRUE(tight.has_value()) << name << " has no example";
    ap::PlanningProblem p = base;
    p.constraints = {*tight};
    const ap::StageConstraints list = ap::buildStageConstraints(p);
    ASSERT_EQ(list.size(), 1u) << name;
    const ap::StageConstraint& c = *list[0];
    ASSERT_NE(c.spec(), nullptr) << name;
    EXPECT_EQ(c.spec()->kind, kind);
    EXPECT_EQ(c.describe(), ap::describeConstraint(*tight));
    EXPECT_NE(std::isfinite(c.rowLower()), std::isfinite(c.rowUpper())) << name;
    // The row: derivatives against central differences; it holds where c ≥ 0.
    for (int trial = 0; trial < 20; ++trial) {
      ap::Vector3 r(normal(rng), normal(rng), normal(rng));
      if (c.quantity() == ap::StageQuantity::Pointing) r = ap::Vector3(std::tanh(r(0)), 0, 0);
      const int dims = c.quantity() == ap::StageQuantity::Pointing ? 1 : 3;
      constexpr double kStep = 1e-4;  // g is at most quadratic: no truncation error
      for (int i = 0; i < dims; ++i) {
        const ap::Vector3 e = kStep * ap::Vector3::Unit(i);
        const double up = c.rowValue(r + e), down = c.rowValue(r - e), mid = c.rowValue(r);
        const double slope = c.rowGradient(r)(i), curvature = c.rowCurvature();
        EXPECT_NEAR(slope, (up - down) / (2 * kStep), 1e-6 * (1 + std::abs(slope))) << name;
        EXPECT_NEAR(curvature, (up - 2 * mid + down) / (kStep * kStep),
                    1e-4 * (1 + std::abs(curvature)))
            << name;
      }
      const double value = c.value(stageQuantityOfRow(c.quantity(), r));
      const bool holds = c.rowLower() <= c.rowValue(r) && c.rowValue(r) <= c.rowUpper();
      if (std::abs(value) > 1e-12) EXPECT_EQ(holds, value > 0) << name << " r = " << r.transpose();
    }
    // The checker: slack to the node bound with c's sign at every instance; names the kind.
    const ap::StageSupport s = ap::planSupport(c.quantity(), false, plan.steps());
    int violated = 0;
    for (int k = s.first_k; k <= s.last_k; ++k) {
      const double value = c.value(quantityOnPlan(c, plan, k));
      const double node_slack = c.slackOnPlan(plan, k) - c.nodeTightening();
      if (std::abs(value) > 1e-12) EXPECT_EQ(node_slack > 0, value > 0) << name << " k = " << k;
      violated += value < 0;
    }
    EXPECT_GT(violated, 0) << name << ": the example must be violated on the plan";
    const ap::ConstraintCheck check = ap::checkConstraints(p, plan);
    EXPECT_EQ(check.names, std::vector<std::string>{name});
    EXPECT_GT(check.max_violation, 0.0) << name;
    EXPECT_EQ(check.worst, c.describe());
    // NLopt forms its rows from the class: solves with a milder example (met by its start).
    const std::optional<ap::PlanningConstraint> mild =
        exampleOf(kind, plan, kind == ap::ConstraintKind::KeepIn ? 1.2 : 0.8);
    p.constraints = {*mild};
    ap::SolverOptions o;
    o.solver = ap::SolverKind::Nlopt;
    o.max_iterations = 5000;
    const ap::PlanResult slsqp = ap::solveWithNlopt(p, o);
    EXPECT_TRUE(slsqp.converged()) << name << ": " << slsqp.message();
    EXPECT_LE(ap::checkConstraints(p, slsqp.maneuver).max_relative_violation,
              ap::kNodeConstraintTolerance)
        << name;
  }
}

TEST(StageConstraints, ValueDerivativesInTheirQuantityMatchCentralDifferences) {
  const ap::StageConstraints list = ap::buildStageConstraints(everyKind(ap::SchemeKind::Paper));
  const ap::Vector3 q(0.11, -0.07, 0.05), e = 1e-5 * ap::Vector3::Ones();
  for (const auto& c : list) {
    for (int i = 0; i < 3; ++i) {
      const ap::Vector3 d = 1e-5 * ap::Vector3::Unit(i);
      EXPECT_NEAR(c->gradient(q)(i), (c->value(q + d) - c->value(q - d)) / 2e-5,
                  1e-8 * (1 + c->gradient(q).norm()))
          << c->describe();
      // Curvature: ∇²c = c''·I.
      const double second = (c->gradient(q + d)(i) - c->gradient(q - d)(i)) / 2e-5;
      EXPECT_NEAR(second, c->curvature(), 1e-6 * (1 + std::abs(c->curvature()))) << c->describe();
    }
    if (c->axis() >= 0) {  // affine in one axis: the other entries of the gradient vanish
      EXPECT_EQ(c->gradient(q + e).cwiseAbs().sum(), std::abs(c->gradient(q)(c->axis())));
    }
  }
}

TEST(StageConstraints, ChainRuleThroughTheTranscriptionMatchesCentralDifferencesInDeltaAndH) {
  // c_k(δ, h) through the quantity's derivatives as ConstrainedSystem and the free-time solver
  // compose them: torque constraints through the stencil's jacobian and tau_h, step rates through
  // angularRateTerms, cones through pointingTerms (no h dependence).
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    const ap::PlanningProblem p = everyKind(scheme);
    const ap::StageConstraints list = ap::buildStageConstraints(p);
    const ap::ReducedProblem np = perturbed(p, 3);
    const double h = np.timeStep(), dh = 1e-6 * h, e = 1e-6;
    std::mt19937 rng(11);
    std::normal_distribution<double> normal;
    Eigen::VectorXd d(np.unknowns());
    for (int i = 0; i < d.size(); ++i) d(i) = normal(rng);
    ap::ReducedProblem plus = np, minus = np, later = np, earlier = np;
    plus.setCurrent(np.retract(d, e));
    minus.setCurrent(np.retract(d, -e));
    later.setTimeStep(h + dh);
    earlier.setTimeStep(h - dh);
    const std::vector<ap::Matrix3> R = np.attitudes(np.current());
    // The torque stencils' derivatives, per k.
    std::vector<Eigen::Matrix<double, 3, 9>> jacobian(p.steps + 1);
    std::vector<ap::Vector3> tau_h(p.steps + 1);
    np.forEachStencilWithTimeStep([&](const ap::ReducedProblem::TimeStepStencil& st) {
      jacobian[st.k] = st.jacobian;
      tau_h[st.k] = st.tau_h;
    });
    std::vector<Eigen::Matrix<double, 9, 1>> node_rate_gradient(p.steps + 1);
    const ap::Matrix3 Jinv = p.inertia.inverse();
    np.forEachNodeMomentum([&](const ap::ReducedProblem::NodeMomentum& node) {
      node_rate_gradient[node.k] = node.jacobian.transpose() * (Jinv * Jinv * node.momentum);
    });
    const std::vector<ap::Vector3> tau = np.torques(np.current());
    const auto localDot = [&](const Eigen::Matrix<double, 9, 1>& g, int first_node, int width) {
      double sum = 0.0;
      for (int n = 0; n < width; ++n) {
        const int v = np.variableIndex(first_node + n);
        if (v >= 0) sum += g.segment<3>(3 * n).dot(d.segment<3>(v));
      }
      return sum;
    };
    for (const auto& c : list) {
      const ap::StageSupport s =
          ap::stageSupport(c->quantity(), np.firstFreeNode(), np.lastFreeNode());
      const std::vector<double> up = valuesOf(*c, plus), down = valuesOf(*c, minus);
      const std::vector<double> later_c = valuesOf(*c, later), earlier_c = valuesOf(*c, earlier);
      for (int k = s.first_k; k <= s.last_k; ++k) {
        const int i = k - s.first_k;
        double along = 0.0, in_h = 0.0;  // ∇_δ c · d and ∂c/∂h by the chain rule
        Eigen::Matrix<double, 9, 1> g = Eigen::Matrix<double, 9, 1>::Zero();
        if (c->quantity() == ap::StageQuantity::Torque) {
          // The stencils carry r_k = √w_k τ_k (w_k ≠ 1 at second_order's end nodes).
          const double root = std::sqrt(np.scheme().torqueWeight(k, p.steps));
          g = jacobian[k].transpose() * c->gradient(tau[k]) / root;
          in_h = c->gradient(tau[k]).dot(tau_h[k]) / root;
        } else if (c->quantity() == ap::StageQuantity::StepRate) {
          const ap::AngularRateTerms t = ap::angularRateTerms(np.scheme(), np.current()[k]);
          const double slope = c->gradient(ap::Vector3(t.half_squared_rate, 0, 0))(0);
          g.head<6>() = slope * t.gradient;
          // Rest to rest the steps stay at fixed free attitudes and q = q̃/h² (free_time_solver).
          in_h = slope * (-2.0 * t.half_squared_rate / h);
        } else if (c->quantity() == ap::StageQuantity::NodeRate) {
          const double q = 0.5 * np.maneuver(np.current()).angular_velocity[k].squaredNorm();
          const double slope = c->gradient(ap::Vector3(q, 0, 0))(0);
          g = slope * node_rate_gradient[k];
          in_h = slope * (-2.0 * q / h);
        } else {
          const ap::PointingTerms t =
              ap::pointingTerms(R[k], c->spec()->body_axis, c->spec()->world_direction);
          g.head<3>() = c->gradient(ap::Vector3(t.cosine, 0, 0))(0) * t.gradient;
          in_h = 0.0;
        }
        along = localDot(g, k + s.node_offset, s.width);
        const double fd = (up[i] - down[i]) / (2 * e);
        EXPECT_NEAR(along, fd, 1e-6 * (1 + std::abs(fd))) << c->describe() << " k = " << k;
        const double fd_h = (later_c[i] - earlier_c[i]) / (2 * dh);
        EXPECT_NEAR(in_h, fd_h, 1e-5 * (1 + std::abs(fd_h))) << c->describe() << " k = " << k;
      }
    }
  }
}

namespace {

/// The rows of every stage constraint of `list` with seeded random multipliers, in one block per
/// quantity object (the torque's included), as the interior points hold them.
template <int Entries>
struct RowsByQuantity {
  std::vector<ap::ConstraintRows<Entries>> groups;
  std::vector<std::vector<int>> blocks;

  RowsByQuantity(const ap::StageConstraints& list, const ap::ReducedProblem& np, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> multiplier(0.1, 2.0);
    std::vector<const ap::StageQuantityModel*> quantities;
    for (const auto& c : list) {
      groups.emplace_back(*c, np.firstFreeNode(), np.lastFreeNode());
      for (ap::ConstraintRow<Entries>& row : groups.back().at) row.z = multiplier(rng);
      const int i = static_cast<int>(groups.size()) - 1;
      const auto known = std::find(quantities.begin(), quantities.end(), &c->quantityModel());
      if (known == quantities.end()) {
        quantities.push_back(&c->quantityModel());
        blocks.push_back({i});
      } else {
        blocks[known - quantities.begin()].push_back(i);
      }
    }
  }
  /// contractQuantityRows with the multipliers as they are (no barrier form).
  ap::QuantityContraction contraction(const std::vector<int>& block) {
    return [this, &block](int k, const ap::Vector3& q) {
      return ap::contractQuantityRows(groups, block, k, q,
                                      [](const auto&, ap::ConstraintRow<Entries>&) {});
    };
  }
};

/// Row `g`'s value at instance k of `at`'s iterate.
template <int Entries>
double rowValue(const ap::ConstraintRows<Entries>& g, const ap::ReducedProblem& at, int k) {
  return g.constraint->value(g.quantity->value(ap::QuantityInputs(at, at.current()), k));
}

/// A seeded random direction d in the unknowns and the problem moved along it by ±e and ±e2: the
/// points of the central first and second differences.
struct MovedAlong {
  MovedAlong(const ap::ReducedProblem& np, unsigned seed)
      : d(randomDirection(np.unknowns(), seed)),
        up(moved(np, e)),
        down(moved(np, -e)),
        up2(moved(np, e2)),
        down2(moved(np, -e2)) {}
  static Eigen::VectorXd randomDirection(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal;
    Eigen::VectorXd d(n);
    for (int i = 0; i < n; ++i) d(i) = normal(rng);
    return d;
  }
  ap::ReducedProblem moved(const ap::ReducedProblem& np, double alpha) const {
    ap::ReducedProblem out = np;
    out.setCurrent(np.retract(d, alpha));
    return out;
  }
  Eigen::VectorXd d;
  double e = 1e-6, e2 = 1e-4;
  ap::ReducedProblem up, down, up2, down2;
};

}  // namespace

/// The chain rule both interior points call (transcription/stage_transcription.hpp), on the rows
/// of every quantity object's constraints with seeded random multipliers: each row's gradient
/// along a direction, and the Lagrangian's curvature −Σ z∇²c along it (the torque's norm bound
/// carries the c'' term), against central differences of the rows' values.
TEST(StageConstraints, TheInteriorPointsChainRuleMatchesCentralDifferencesOfTheRows) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    const ap::PlanningProblem p = everyKind(scheme);
    const ap::StageConstraints list = ap::buildStageConstraints(p);
    const ap::ReducedProblem np = perturbed(p, 9);
    RowsByQuantity<9> rows(list, np, 21);
    const MovedAlong along(np, 23);
    const Eigen::VectorXd& d = along.d;
    const double e = along.e, e2 = along.e2;
    const ap::ReducedProblem &up = along.up, &down = along.down, &up2 = along.up2,
                             &down2 = along.down2;
    int instances = 0, expected = 0;
    for (const std::vector<int>& block : rows.blocks) {
      const ap::FixedStepRows& first = rows.groups[block.front()];
      expected += first.support.last_k - first.support.first_k + 1;
      first.quantity->forEachTerms(
          np, first.support, rows.contraction(block), [&](const ap::QuantityTerms& t) {
            Eigen::Matrix<double, 9, 9> curvature;
            ap::chainQuantityRows(rows.groups, block, t, &curvature);
            Eigen::Matrix<double, 9, 1> local = Eigen::Matrix<double, 9, 1>::Zero();
            for (int n = 0; n < first.support.width; ++n) {
              const int v = np.variableIndex(t.k + first.support.node_offset + n);
              if (v >= 0) local.segment<3>(3 * n) = d.segment<3>(v);
            }
            double fd2 = 0.0;  // −Σ z c along d, second difference
            for (const int i : block) {
              const ap::FixedStepRows& g = rows.groups[i];
              const std::string where = g.constraint->describe() + " k = " + std::to_string(t.k);
              const double c0 = rowValue(g, np, t.k);
              EXPECT_NEAR(g.instance(t.k).c, c0, 1e-12 * (1 + std::abs(c0))) << where;
              const double fd = (rowValue(g, up, t.k) - rowValue(g, down, t.k)) / (2 * e);
              EXPECT_NEAR(g.instance(t.k).g.dot(local), fd, 1e-6 * (1 + std::abs(fd))) << where;
              fd2 -= g.instance(t.k).z *
                     (rowValue(g, up2, t.k) - 2 * c0 + rowValue(g, down2, t.k)) / (e2 * e2);
            }
            const double second = local.dot(curvature.selfadjointView<Eigen::Lower>() * local);
            EXPECT_NEAR(second, fd2, 1e-5 * (1 + std::abs(fd2)))
                << ap::schemeName(scheme) << " k = " << t.k;
            ++instances;
          });
    }
    EXPECT_EQ(rows.blocks.size(), 4u) << "torque, rate and two cones";
    EXPECT_EQ(instances, expected) << "every quantity's instances were visited";
  }
}

/// The torque rows' chain rule both interior points call in the cost's stencil pass
/// (contractTorqueRows for the stencil's weights, chainTorqueRows for the gradients), with seeded
/// random multipliers and no cost: each row's gradient along a direction, and −Σ z∇²c along it —
/// the stencil's `second` at those weights plus the rows' c'' term −Σ z c''/w |J d|² (the norm
/// bound carries one) — against central differences of the rows' values, on every scheme (second
/// order's end nodes have w ≠ 1).
TEST(StageConstraints, TheTorqueRowsChainRuleMatchesCentralDifferencesOfTheRows) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    const ap::PlanningProblem p = everyKind(scheme);
    const ap::StageConstraints list = ap::buildStageConstraints(p);
    const ap::ReducedProblem np = perturbed(p, 11);
    RowsByQuantity<9> rows(list, np, 41);
    std::vector<int> torque;
    for (int i = 0; i < static_cast<int>(rows.groups.size()); ++i) {
      if (rows.groups[i].quantity->formedByCostStencil()) torque.push_back(i);
    }
    ASSERT_EQ(torque.size(), 7u) << "the box's six sides and the norm bound";
    const MovedAlong along(np, 43);
    const Eigen::VectorXd& d = along.d;
    const double e = along.e, e2 = along.e2;
    const ap::ReducedProblem &up = along.up, &down = along.down, &up2 = along.up2,
                             &down2 = along.down2;
    const auto root = [&](int k) { return std::sqrt(np.scheme().torqueWeight(k, p.steps)); };
    double isotropic = 0.0;  // Σ z c''/w of the stencil the weights were formed for
    const auto weights = [&](int k, const ap::Vector3& residual) {
      isotropic = 0.0;
      return ap::contractTorqueRows(
          rows.groups, torque, k, residual, root(k), ap::Vector3::Zero().eval(),
          [&](const ap::FixedStepRows& g, ap::FixedStepRow& in, double r) {
            isotropic += in.z * g.constraint->curvature() / (r * r);
          });
    };
    int stencils = 0;
    np.forEachStencil(
        true,
        [&](const ap::ReducedProblem::Stencil& st) {
          ap::chainTorqueRows(rows.groups, torque, st.k, st.tau, root(st.k), st.jacobian,
                              [](const auto&, const auto&, const ap::Vector3&) {});
          Eigen::Matrix<double, 9, 1> local = Eigen::Matrix<double, 9, 1>::Zero();
          for (int n = 0; n < 3; ++n) {
            const int v = np.variableIndex(st.k - 1 + n);
            if (v >= 0) local.segment<3>(3 * n) = d.segment<3>(v);
          }
          double fd2 = 0.0;  // −Σ z c along d, second difference
          for (const int i : torque) {
            const ap::FixedStepRows& g = rows.groups[i];
            const std::string where = g.constraint->describe() + " k = " + std::to_string(st.k);
            const ap::FixedStepRow& in = g.instance(st.k);
            const double c0 = rowValue(g, np, st.k);
            EXPECT_NEAR(in.c, c0, 1e-12 * (1 + std::abs(c0))) << where;
            const double fd = (rowValue(g, up, st.k) - rowValue(g, down, st.k)) / (2 * e);
            EXPECT_NEAR(in.g.dot(local), fd, 1e-6 * (1 + std::abs(fd))) << where;
            fd2 -= in.z * (rowValue(g, up2, st.k) - 2 * c0 + rowValue(g, down2, st.k)) / (e2 * e2);
          }
          const double second = local.dot(st.second.selfadjointView<Eigen::Lower>() * local) -
                                isotropic * (st.jacobian * local).squaredNorm();
          EXPECT_NEAR(second, fd2, 1e-5 * (1 + std::abs(fd2)))
              << ap::schemeName(scheme) << " k = " << st.k;
          ++stencils;
        },
        weights);
    const ap::StageSupport& support = rows.groups[torque.front()].support;
    EXPECT_EQ(stencils, support.last_k - support.first_k + 1) << "every torque instance visited";
  }
}

/// The same chain rule with h free (free time's rows, entry 9 the time step): each row's ∂c/∂h and
/// the Lagrangian's ∂²/∂h² against central differences in h, rest to rest and with spinning ends
/// (the boundary paths move R_1, R_{N−1} with h).
TEST(StageConstraints, TheInteriorPointsChainRuleMatchesCentralDifferencesInTheTimeStep) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    for (const bool spinning : {false, true}) {
      ap::PlanningProblem p = everyKind(scheme);
      if (spinning) {
        p.initial_velocity = ap::Vector3(0.05, -0.03, 0.08);
        p.final_velocity = ap::Vector3(-0.04, 0.06, 0.02);
      }
      const ap::StageConstraints list = ap::buildStageConstraints(p);
      const ap::ReducedProblem np = perturbed(p, 10);
      RowsByQuantity<10> rows(list, np, 31);
      const double h = np.timeStep(), dh = 1e-5 * h;
      const auto at = [&](double step) {
        ap::ReducedProblem out = np;
        out.setTimeStep(step);
        return out;
      };
      const ap::ReducedProblem later = at(h + dh), earlier = at(h - dh);
      int instances = 0, expected = 0;
      for (const std::vector<int>& block : rows.blocks) {
        const ap::FreeTimeRows& first = rows.groups[block.front()];
        expected += first.support.last_k - first.support.first_k + 1;
        first.quantity->forEachTermsWithTimeStep(
            np, first.support, 1.0, rows.contraction(block),
            [&](const ap::QuantityTermsWithTimeStep& t) {
              Eigen::Matrix<double, 10, 10> curvature;
              ap::chainQuantityRows(rows.groups, block, t, &curvature);
              double fd_hh = 0.0;  // −Σ z c in h, second difference
              for (const int i : block) {
                const ap::FreeTimeRows& g = rows.groups[i];
                const std::string where = g.constraint->describe() + " k = " + std::to_string(t.k);
                const double c0 = rowValue(g, np, t.k);
                const double fd = (rowValue(g, later, t.k) - rowValue(g, earlier, t.k)) / (2 * dh);
                EXPECT_NEAR(g.instance(t.k).g(9), fd, 1e-6 * (1 + std::abs(fd))) << where;
                fd_hh -= g.instance(t.k).z *
                         (rowValue(g, later, t.k) - 2 * c0 + rowValue(g, earlier, t.k)) / (dh * dh);
              }
              EXPECT_NEAR(curvature(9, 9), fd_hh, 1e-4 * (1 + std::abs(fd_hh)))
                  << ap::schemeName(scheme) << " k = " << t.k;
              ++instances;
            });
      }
      EXPECT_EQ(instances, expected);
    }
  }
}

namespace {

/// sun_keep_out's body and cone as a minimum-time problem under |τ_i| ≤ 0.2 N m.
ap::PlanningProblem minimumTimeWithCone(ap::SchemeKind scheme, int steps) {
  ap::PlanningProblem p = scene("sun_keep_out", steps);
  p.scheme = scheme;
  p.objective = ap::Objective::MinimumTime;
  p.duration = 0.0;
  p.max_torque = ap::Vector3::Constant(0.2);
  p.constraints = {sunCone()};
  return p;
}

}  // namespace

TEST(FreeTimeCones, KeepOutMinimumTimeIsAKktPointOutsideTheConeNearTheSearch) {
  for (const ap::SchemeKind scheme : {ap::SchemeKind::SecondOrder, ap::SchemeKind::Variational}) {
    const ap::PlanningProblem p = minimumTimeWithCone(scheme, 32);
    EXPECT_EQ(ap::freeTimeUnsupported(p), "");
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    ASSERT_TRUE(r.minimum_time.kkt_point) << r.message();
    EXPECT_LE(r.minimum_time.stationarity, 1e-8);
    EXPECT_LE(r.minimum_time.time_stationarity, 1e-8);
    EXPECT_LE(r.minimum_time.complementarity, 1e-8);
    for (const ap::Matrix3& R : r.maneuver.attitude) {
      EXPECT_GE(ap::coneMargin(p.constraints[0], R), -1e-9) << "a node inside the cone";
    }
    EXPECT_LE(r.max_constraint_violation, 1e-8);
    const ap::PlanResult searched = searchedMinimumTime(p);
    ASSERT_TRUE(searched.converged()) << searched.message();
    EXPECT_FALSE(searched.minimum_time.kkt_point) << searched.message();
    // The structured starts do not reach every basin around a cone: the answer is a KKT point,
    // but the search (a continuation over many minimum-effort solves) can end in a lower basin
    // (second_order N = 32: 28.9937 against 28.9825, +0.04 %; docs/results/minimum_time.md).
    // Within the accuracy the published cases are held to.
    std::printf("%s: free time %.9f, search %.9f\n", ap::schemeName(scheme).c_str(),
                r.minimum_duration, searched.minimum_duration);
    EXPECT_LE(r.minimum_duration, searched.minimum_duration * (1 + kConeBasinTolerance))
        << ap::schemeName(scheme) << ": " << ap::exactNumber(r.minimum_duration);
  }
}

TEST(FreeTimeCones, TStarIsInvariantUnderAWorldRotationOfAttitudesAndCone) {
  const ap::PlanningProblem p = minimumTimeWithCone(ap::SchemeKind::SecondOrder, 32);
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged() && r.minimum_time.kkt_point) << r.message();
  std::mt19937 rng(31);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 2; ++trial) {
    const ap::Matrix3 Q = ap::so3::exp(ap::Vector3(normal(rng), normal(rng), normal(rng)));
    ap::test_support::expectSameTStarWhenTurned(ap::test_support::inATurnedWorld(p, Q), r, 1e-7,
                                                "trial " + std::to_string(trial));
  }
}

TEST(FreeTimeCones, AStartInsideTheConeIsRefusedByName) {
  // Raising T moves no attitude: the free-time solve needs a start that already clears the cone.
  const ap::PlanningProblem p = minimumTimeWithCone(ap::SchemeKind::SecondOrder, 16);
  std::vector<ap::Matrix3> through;  // the eigenaxis path, straight through the cone
  const ap::Vector3 span = ap::so3::log(p.initial_attitude.transpose() * p.final_attitude);
  for (int k = 0; k <= p.steps; ++k) {
    through.push_back(p.initial_attitude * ap::so3::exp(span * k / double(p.steps)));
  }
  const ap::FreeTimeOutcome o = ap::solveFreeTime(p, through, 40.0, 1e-9, 100);
  EXPECT_EQ(o.termination, ap::Termination::NotConverged);
  EXPECT_NE(o.message().find("violate a cone"), std::string::npos) << o.message();
}

TEST(FreeTimeRates, RateLimitedMinimumTimeIsAKktPointWithinTheLimit) {
  // Betts with |Ω| ≤ 0.1 rad/s, rest to rest: one free-time problem per start (a KKT point), no
  // slower than the search's upper bound on the same discrete problem.
  ap::PlanningProblem p = scene("min_time_betts", 32);
  p.constraints.push_back(ap::PlanningConstraint::maxAngularRate(0.1));
  EXPECT_EQ(ap::freeTimeUnsupported(p), "");
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_TRUE(r.minimum_time.kkt_point) << r.message();
  EXPECT_LE(r.minimum_time.stationarity, 1e-8);
  EXPECT_LE(r.minimum_time.complementarity, 1e-8);
  for (const ap::Vector3& w : r.maneuver.angular_velocity) EXPECT_LE(w.norm(), 0.1 * (1 + 1e-9));
  const ap::PlanResult searched = searchedMinimumTime(p);
  ASSERT_TRUE(searched.converged()) << searched.message();
  EXPECT_LE(r.minimum_duration, searched.minimum_duration * (1 + 1e-8));
  // With spinning ends too (test_free_time: RateLimited… and RateLimitDerivativesInH…).
  p.initial_velocity = ap::Vector3(0.01, 0, 0);
  EXPECT_EQ(ap::freeTimeUnsupported(p), "");
}

TEST(StageConstraints, AConeViolatedAtAnAttitudeTheBoundaryDataFixIsNamedOnlyThere) {
  // Paper scheme spinning about z: R_1 = R_0 exp(h Ω(0)^) is boundary data, not an unknown. A
  // keep-out cone around R_1's body x (R_0's body x outside it) is violated there and only there.
  ap::PlanningProblem p = scene("rest_to_rest", 16);
  p.scheme = ap::SchemeKind::Paper;
  p.initial_attitude = ap::Matrix3::Identity();
  p.initial_velocity = ap::Vector3(0, 0, 1.0);
  const double h = p.duration / p.steps;
  const ap::Vector3 s = ap::so3::exp(ap::Vector3(0, 0, h)) * ap::Vector3::UnitX();
  p.constraints = {ap::PlanningConstraint::keepOut(ap::Vector3::UnitX(), s, 0.5 * h)};
  const ap::ReducedProblem np(p);
  ASSERT_LT(np.variableIndex(1), 0) << "R_1 must be fixed for this test";
  const std::string at_fixed = ap::fixedNodeConeViolation(p, np, {0, 1});
  EXPECT_NE(at_fixed.find(ap::describeConstraint(p.constraints[0])), std::string::npos) << at_fixed;
  EXPECT_NE(at_fixed.find("at k = 1"), std::string::npos) << at_fixed;
  EXPECT_EQ(ap::fixedNodeConeViolation(p, np, {0}), "") << "R_0 clears the cone";
  // A free node is an unknown: never reported, whatever it violates.
  p.scheme = ap::SchemeKind::SecondOrder;
  const ap::ReducedProblem with_end_torques(p);
  ASSERT_GE(with_end_torques.variableIndex(1), 0);
  EXPECT_EQ(ap::fixedNodeConeViolation(p, with_end_torques, {1}), "");
}

// ---- The quantity objects (stage_quantities.hpp) on their own: value, node Jacobian, contracted
// curvature and h derivatives against central differences, for every quantity each scheme
// transcribes (paper and variational: torque, step rate, two cones; second_order: torque, node
// rate, two cones), rest to rest and with spinning ends (the boundary paths of paper and
// variational move R_1, R_{N−1} with h).

namespace {

struct QuantityCase {
  ap::SchemeKind scheme;
  int quantity;   ///< index among the distinct quantity objects of everyKind(scheme)
  bool spinning;  ///< nonzero boundary rates
};

std::string caseName(const testing::TestParamInfo<QuantityCase>& info) {
  static const char* kNames[] = {"Torque", "Rate", "KeepOutCone", "KeepInCone"};
  return ap::schemeName(info.param.scheme) + kNames[info.param.quantity] +
         (info.param.spinning ? "Spinning" : "RestToRest");
}

std::vector<QuantityCase> quantityCases() {
  std::vector<QuantityCase> out;
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    for (int q = 0; q < 4; ++q) {
      for (const bool spinning : {false, true}) out.push_back({scheme, q, spinning});
    }
  }
  return out;
}

class StageQuantityDerivatives : public testing::TestWithParam<QuantityCase> {
 protected:
  void SetUp() override {
    problem_ = everyKind(GetParam().scheme);
    if (GetParam().spinning) {
      problem_.initial_velocity = ap::Vector3(0.05, -0.03, 0.08);
      problem_.final_velocity = ap::Vector3(-0.04, 0.06, 0.02);
    }
    constraints_ = ap::buildStageConstraints(problem_);
    std::vector<const ap::StageQuantityModel*> distinct;
    for (const auto& c : constraints_) {
      const ap::StageQuantityModel* m = &c->quantityModel();
      if (std::find(distinct.begin(), distinct.end(), m) == distinct.end()) distinct.push_back(m);
    }
    ASSERT_EQ(distinct.size(), 4u) << "torque, rate and two cones";
    quantity_ = distinct[GetParam().quantity];
    np_.emplace(perturbed(problem_, 5));
    support_ = quantity_->support(np_->firstFreeNode(), np_->lastFreeNode());
    std::mt19937 rng(17);
    std::normal_distribution<double> normal;
    direction_.resize(np_->unknowns());
    for (int i = 0; i < direction_.size(); ++i) direction_(i) = normal(rng);
    lambda_ = ap::Vector3(normal(rng), normal(rng), normal(rng));
  }

  /// λ as the quantity contracts it (scalar quantities: λ(0) alone).
  ap::Vector3 contracted() const {
    return quantity_->kind() == ap::StageQuantity::Torque ? lambda_
                                                          : ap::Vector3(lambda_(0), 0.0, 0.0);
  }

  ap::PlanningProblem problem_;
  ap::StageConstraints constraints_;
  const ap::StageQuantityModel* quantity_ = nullptr;
  std::optional<ap::ReducedProblem> np_;
  ap::StageSupport support_;
  Eigen::VectorXd direction_;
  ap::Vector3 lambda_;
};

TEST_P(StageQuantityDerivatives, TermsMatchCentralDifferencesAtAFixedTimeStep) {
  const ap::test_support::QuantityDifferences check{*quantity_, *np_,         support_, direction_,
                                                    lambda_,    contracted(), 1e-13};
  EXPECT_EQ(check.checkAtFixedTimeStep(), support_.last_k - support_.first_k + 1);
}

/// The curvature as a Hessian–vector product (three seeded directions against the step
/// direction) at three seeded random iterates.
TEST_P(StageQuantityDerivatives, CurvatureTimesADirectionMatchesMixedCentralDifferences) {
  for (const int seed : {5, 6, 7}) {
    const ap::ReducedProblem np = perturbed(problem_, seed);
    const ap::test_support::QuantityDifferences check{
        *quantity_, np, support_, direction_, lambda_, contracted(), 1e-13};
    EXPECT_EQ(check.checkCurvatureTimesDirection(3, 100 + seed),
              3 * (support_.last_k - support_.first_k + 1))
        << "iterate seed " << seed;
  }
}

TEST_P(StageQuantityDerivatives, TermsWithTheTimeStepMatchCentralDifferencesInH) {
  EXPECT_EQ(quantity_->dependsOnTimeStep(), quantity_->kind() != ap::StageQuantity::Pointing);
  const ap::test_support::QuantityDifferences check{*quantity_, *np_,         support_, direction_,
                                                    lambda_,    contracted(), 1e-13};
  EXPECT_EQ(check.checkWithTimeStep(1.0), support_.last_k - support_.first_k + 1);
}

/// The value on a plan is the plain form the constraints' slacks read: τ_k, the plan's reported
/// Ω_k, the pointing cosine of R_k.
TEST_P(StageQuantityDerivatives, ValueOnAPlanIsItsPlainForm) {
  const ap::Maneuver plan = np_->maneuver(np_->current());
  const ap::StageSupport s =
      quantity_->planSupport(ap::schemeHasEndTorques(problem_.scheme), plan.steps());
  ASSERT_LE(s.first_k, s.last_k);
  const ap::QuantityInputs at(*np_, np_->current());
  for (int k = s.first_k; k <= s.last_k; ++k) {
    const ap::Vector3 r = quantity_->valueOnPlan(plan, k);
    switch (quantity_->kind()) {
      case ap::StageQuantity::Torque:
        EXPECT_EQ(r, plan.torque[k]);
        break;
      case ap::StageQuantity::StepRate:
      case ap::StageQuantity::NodeRate:
        EXPECT_EQ(r, plan.angular_velocity[k]);
        break;
      case ap::StageQuantity::Pointing: {
        const ap::PlanningConstraint& cone = problem_.constraints[GetParam().quantity];
        EXPECT_NEAR(r(0), cone.world_direction.dot(plan.attitude[k] * cone.body_axis), 1e-15);
        break;
      }
      case ap::StageQuantity::WheelMomentum:  // not in everyKind: test_reaction_wheels
      case ap::StageQuantity::WheelTorque:
        ADD_FAILURE() << "no wheels in this suite's problem";
        break;
    }
  }
  // Where the transcription has the instance too, the two agree (½|Ω|² for the rates).
  for (int k = std::max(s.first_k, support_.first_k); k <= std::min(s.last_k, support_.last_k);
       ++k) {
    const ap::Vector3 r = quantity_->valueOnPlan(plan, k), q = quantity_->value(at, k);
    const double expected = quantity_->kind() == ap::StageQuantity::Torque ? r(0)
                            : quantity_->kind() == ap::StageQuantity::Pointing
                                ? r(0)
                                : 0.5 * r.squaredNorm();
    EXPECT_NEAR(q(0), expected, 1e-12 * (1 + std::abs(expected))) << "k = " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryQuantityAndScheme, StageQuantityDerivatives,
                         testing::ValuesIn(quantityCases()), caseName);

}  // namespace
