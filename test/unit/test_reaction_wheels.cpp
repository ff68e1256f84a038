// Reaction wheels (planning/reaction_wheels.hpp, transcription/wheel_quantities.hpp): the input's
// validation; the wheel quantities' derivatives against central differences at a fixed h and in
// h, every scheme, at rest and spinning, with a momentum bias; the discrete wheel states against
// the plan's discrete dynamics (exact conservation, O(h²) torques); minimum time against the
// closed-form bang–coast–bang slew; random converged plans meet every wheel limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/discrete_wheel_replay.hpp"
#include "attitude_planner/dynamics/wheel_replay.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/csv.hpp"
#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "planning/transcription/wheel_quantities.hpp"
#include "support/quantity_differences.hpp"

namespace ap = attitude_planner;

namespace {

/// Four wheels in a pyramid about body z (54.74° from it: the classic NASA-style skew).
std::vector<ap::Vector3> pyramid() {
  const double s = std::sqrt(2.0 / 3.0), c = std::sqrt(1.0 / 3.0);
  return {ap::Vector3(s, 0, c), ap::Vector3(0, s, c), ap::Vector3(-s, 0, c), ap::Vector3(0, -s, c)};
}

/// A generic body with a biased pyramid: every term of the quantities nonzero.
ap::PlanningProblem wheelProblem(ap::SchemeKind scheme, bool spinning, int steps = 16) {
  ap::PlanningProblem p;
  p.inertia << 13.0, -2.0, 1.0, -2.0, 16.0, 0.5, 1.0, 0.5, 18.0;
  p.duration = 8.0;
  p.steps = steps;
  p.scheme = scheme;
  p.final_attitude = ap::so3::exp(ap::Vector3(0.4, -0.7, 0.9));
  if (spinning) {
    p.initial_velocity = ap::Vector3(0.05, -0.03, 0.08);
    p.final_velocity = ap::Vector3(-0.04, 0.06, 0.02);
  }
  p.reaction_wheels.spin_axes = pyramid();
  p.reaction_wheels.max_torque = {0.3};
  p.reaction_wheels.max_momentum = {3.0};
  p.reaction_wheels.initial_momentum = {0.3, -0.2, 0.5, 0.1};
  p.reaction_wheels.max_momentum_norm = 4.0;
  return p;
}

/// A constant world-frame disturbance torque on `p` (scene effects: disturbance_torque, frame
/// world): the one effect the wheels plan with (its impulse t τ_d is independent of the path).
void disturb(ap::PlanningProblem* p, const ap::Vector3& world_torque) {
  auto model = std::make_shared<ap::EffectModel>();
  model->add(std::make_unique<ap::DisturbanceTorque>(world_torque, ap::TorqueFrame::World));
  p->effects = model;
}

/// An InvalidInput's message, or "" if `f` did not throw one.
template <typename F>
std::string refusal(F f) {
  try {
    f();
  } catch (const ap::InvalidInput& e) {
    return e.what();
  }
  return "";
}

std::string refusalOf(const ap::PlanningProblem& p) {
  return refusal([&] { ap::validateProblem(p); });
}

}  // namespace

TEST(ReactionWheelInput, BadArraysAreRefusedByName) {
  const ap::PlanningProblem good = wheelProblem(ap::SchemeKind::SecondOrder, false);
  EXPECT_EQ(refusalOf(good), "");
  ap::PlanningProblem p = good;
  p.reaction_wheels.spin_axes = {ap::Vector3::UnitX(), ap::Vector3::UnitY(), ap::Vector3(1, 1, 0)};
  EXPECT_NE(refusalOf(p).find("spin_axes: the axes do not span R^3"), std::string::npos)
      << refusalOf(p);
  p = good;
  p.reaction_wheels.spin_axes.resize(2);
  p.reaction_wheels.initial_momentum.resize(2);
  EXPECT_NE(refusalOf(p).find("spin_axes: need at least 3 wheels"), std::string::npos);
  p = good;
  p.reaction_wheels.max_torque = {0.3, 0.3, -0.1, 0.3};
  EXPECT_NE(refusalOf(p).find("max_torque: each limit must be a finite number > 0 N m, got -0.1"),
            std::string::npos)
      << refusalOf(p);
  p = good;
  p.reaction_wheels.max_momentum = {3.0, 3.0};
  EXPECT_NE(refusalOf(p).find("max_momentum: give one value or one per wheel (4)"),
            std::string::npos);
  p = good;
  p.reaction_wheels.initial_momentum = {0.3, -3.5, 0.5, 0.1};
  EXPECT_NE(refusalOf(p).find("initial_momentum: wheel 2 starts at -3.5 N m s, beyond its "
                              "max_momentum 3 N m s"),
            std::string::npos)
      << refusalOf(p);
  p = good;
  p.reaction_wheels.initial_momentum = {0.3, 0.5};
  EXPECT_NE(refusalOf(p).find("initial_momentum: give one value per wheel (4)"), std::string::npos);
  p = good;
  p.reaction_wheels.max_momentum_norm = 0.1;
  EXPECT_NE(refusalOf(p).find("max_momentum_norm: the initial momenta give"), std::string::npos);
}

TEST(ReactionWheelInput, CombinationsTheModelDoesNotPlanAreRefusedByName) {
  ap::PlanningProblem p = wheelProblem(ap::SchemeKind::SecondOrder, false);
  p.max_torque = ap::Vector3::Constant(0.5);
  EXPECT_NE(refusalOf(p).find("reaction_wheels: not supported with effects actuator_limits"),
            std::string::npos)
      << refusalOf(p);
  // Effects whose impulse depends on the path are refused by name; a world-frame disturbance is
  // planned, but not in minimum time (the end state's wheel momenta would depend on T).
  p = wheelProblem(ap::SchemeKind::SecondOrder, false);
  auto body_frame = std::make_shared<ap::EffectModel>();
  body_frame->add(
      std::make_unique<ap::DisturbanceTorque>(ap::Vector3(0, 0, 0.01), ap::TorqueFrame::Body));
  p.effects = body_frame;
  EXPECT_NE(refusalOf(p).find("not supported with effects (disturbance_torque)"), std::string::npos)
      << refusalOf(p);
  auto gravity = std::make_shared<ap::EffectModel>();
  gravity->add(std::make_unique<ap::GravityGradient>(3.986e14, 7.0e6, p.inertia));
  p.effects = gravity;
  EXPECT_NE(refusalOf(p).find("not supported with effects (gravity_gradient)"), std::string::npos)
      << refusalOf(p);
  disturb(&p, ap::Vector3(0, 0, 0.01));
  EXPECT_EQ(refusalOf(p), "");
  p.objective = ap::Objective::MinimumTime;
  p.constraints = {ap::PlanningConstraint::maxTorqueNorm(0.3)};
  EXPECT_NE(refusalOf(p).find("not supported with effects and objective minimum_time"),
            std::string::npos)
      << refusalOf(p);
  // The end state fixes the wheels' final momenta: a spin the array cannot absorb is refused.
  p = wheelProblem(ap::SchemeKind::SecondOrder, false);
  p.final_velocity = ap::Vector3(0.0, 0.0, 0.5);  // J Ω(T) ≈ 9 N m s about z
  EXPECT_NE(refusalOf(p).find("the final state (attitude and angular velocity) leaves wheel"),
            std::string::npos)
      << refusalOf(p);
}

TEST(ReactionWheelInput, SceneKeysParseAndRoundTrip) {
  const std::string text =
      "inertia: [10, 10, 10]\nduration: 8\nsteps: 32\nscheme: second_order\n"
      "initial: {attitude: {axis: [0, 0, 1], angle: 0}, angular_velocity: [0, 0, 0]}\n"
      "final: {attitude: {axis: [0, 0, 1], angle: 1}, angular_velocity: [0, 0, 0]}\n"
      "actuators: {reaction_wheels: {spin_axes: [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "
      "max_torque: 1, max_momentum: [2, 2, 2.5], initial_momentum: [0.1, 0, 0], "
      "max_momentum_norm: 3}}\n";
  const ap::Scene scene = ap::parseScene(text, "wheels.yaml");
  const ap::ReactionWheels& w = scene.problem.reaction_wheels;
  ASSERT_EQ(w.count(), 3);
  EXPECT_EQ(w.torqueLimit(2), 1.0);
  EXPECT_EQ(w.momentumLimit(2), 2.5);
  EXPECT_EQ(w.initialMomentum(0), 0.1);
  EXPECT_EQ(w.max_momentum_norm, 3.0);
  const ap::Scene again = ap::parseScene(ap::formatScene(scene), "again.yaml");
  EXPECT_EQ(again.problem.reaction_wheels.momentumLimit(2), 2.5);
  EXPECT_EQ(again.problem.reaction_wheels.max_momentum_norm, 3.0);
  std::string bad = text;
  bad.replace(bad.find("max_torque: 1"), 13, "max_torque: [1, 1]");
  EXPECT_NE(refusal([&] {
              ap::parseScene(bad, "bad.yaml");
            }).find("actuators.reaction_wheels.max_torque: give one value or one per wheel"),
            std::string::npos);
  bad = text;
  bad.replace(bad.find("max_torque"), 10, "max_torqe");
  EXPECT_NE(refusal([&] {
              ap::parseScene(bad, "bad.yaml");
            }).find("actuators.reaction_wheels.max_torqe: unknown key"),
            std::string::npos);
}

// ---- derivatives -------------------------------------------------------------------------------

namespace {

struct WheelCase {
  ap::SchemeKind scheme;
  bool spinning;
  int quantity;  ///< 0: the array momentum q, 1: its half squared norm, 2: the array torque
  bool disturbed = false;  ///< with a world-frame disturbance (π_k = π₀ + k h τ_d)
};

std::vector<WheelCase> wheelCases() {
  std::vector<WheelCase> out;
  for (const ap::SchemeKind s :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder})
    for (const bool spinning : {false, true})
      for (const bool disturbed : {false, true})
        for (const int quantity : {0, 1, 2}) out.push_back({s, spinning, quantity, disturbed});
  return out;
}

std::string wheelCaseName(const testing::TestParamInfo<WheelCase>& info) {
  return ap::schemeName(info.param.scheme) + (info.param.spinning ? "_spinning" : "_rest") +
         (info.param.disturbed ? "_disturbed" : "") +
         (info.param.quantity == 2   ? "_torque"
          : info.param.quantity == 1 ? "_momentum_norm"
                                     : "_momentum");
}

class WheelQuantityDerivatives : public testing::TestWithParam<WheelCase> {
 protected:
  void SetUp() override {
    problem_ = wheelProblem(GetParam().scheme, GetParam().spinning);
    if (GetParam().disturbed) disturb(&problem_, ap::Vector3(0.02, -0.03, 0.015));
    quantity_ = GetParam().quantity == 2
                    ? ap::makeWheelTorqueQuantity(problem_)
                    : ap::makeWheelMomentumQuantity(problem_, GetParam().quantity == 1);
    np_.emplace(problem_);
    std::mt19937 rng(5);
    std::normal_distribution<double> normal(0.0, 0.05);
    Eigen::VectorXd start(np_->unknowns());
    for (int i = 0; i < start.size(); ++i) start(i) = normal(rng);
    np_->setCurrent(np_->retract(start, 1.0));
    support_ = quantity_->support(np_->firstFreeNode(), np_->lastFreeNode());
    std::normal_distribution<double> unit;
    direction_.resize(np_->unknowns());
    for (int i = 0; i < direction_.size(); ++i) direction_(i) = unit(rng);
    lambda_ = ap::Vector3(unit(rng), unit(rng), unit(rng));
  }
  ap::test_support::QuantityDifferences check() const {
    // The contraction λ: all three entries for the vectors, λ(0) for ½|q|² (entries 1, 2 of
    // its value are 0, so λ·Δ²q reads λ(0) alone either way).
    return {*quantity_, *np_, support_, direction_, lambda_, lambda_, 1e-12};
  }

  ap::PlanningProblem problem_;
  std::shared_ptr<const ap::StageQuantityModel> quantity_;
  std::optional<ap::ReducedProblem> np_;
  ap::StageSupport support_;
  Eigen::VectorXd direction_;
  ap::Vector3 lambda_;
};

}  // namespace

TEST_P(WheelQuantityDerivatives, TermsMatchCentralDifferencesAtAFixedTimeStep) {
  const int visited = check().checkAtFixedTimeStep();
  EXPECT_EQ(visited, support_.last_k - support_.first_k + 1);
  EXPECT_GE(visited, problem_.steps - 3);
}

/// The curvature as a Hessian–vector product: three seeded directions against the step direction.
TEST_P(WheelQuantityDerivatives, CurvatureTimesADirectionMatchesMixedCentralDifferences) {
  EXPECT_EQ(check().checkCurvatureTimesDirection(3, 29),
            3 * (support_.last_k - support_.first_k + 1));
}

/// In η = h/2.5: the h column times the scale, the hh corner times its square.
TEST_P(WheelQuantityDerivatives, TermsWithTheTimeStepMatchCentralDifferencesInH) {
  EXPECT_EQ(check().checkWithTimeStep(2.5), support_.last_k - support_.first_k + 1);
}

/// The transcription's value and the plan's (what the checker and the outputs read) agree.
TEST_P(WheelQuantityDerivatives, ValueOnAPlanIsTheTranscriptionsValue) {
  const ap::Maneuver plan = np_->maneuver(np_->current());
  const ap::QuantityInputs at(*np_, np_->current());
  for (int k = support_.first_k; k <= support_.last_k; ++k) {
    const ap::Vector3 on_plan = quantity_->valueOnPlan(plan, k), q = quantity_->value(at, k);
    if (GetParam().quantity == 1) {  // the plain form q of ½|q|²
      EXPECT_NEAR(0.5 * on_plan.squaredNorm(), q(0), 1e-10 * (1 + q(0))) << "k = " << k;
      continue;
    }
    EXPECT_LE((on_plan - q).norm(), 1e-10 * (1 + q.norm())) << "k = " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryScheme, WheelQuantityDerivatives, testing::ValuesIn(wheelCases()),
                         wheelCaseName);

// ---- the discrete wheel states against the plan's discrete dynamics ---------------------------

/// Body and array together conserve π₀ exactly on every step between interior nodes: the spatial
/// array momentum R_k q_k changes by minus the body's trapezoidal impulse (and, with end torques,
/// on the end steps too). Any iterate is a plan of its own torques, so a perturbed one serves.
TEST(ReactionWheelPhysics, BodyAndArrayConserveTheTotalMomentumExactly) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder})
    for (const bool disturbed : {false, true}) {
      ap::PlanningProblem p = wheelProblem(scheme, true);
      // With a world-frame disturbance τ_d the total is π_k = π₀ + k h τ_d, and the identity is
      // the same: the control's impulse alone moves the array (the body takes τ_d's).
      if (disturbed) disturb(&p, ap::Vector3(0.02, -0.03, 0.015));
      const ap::Vector3 tau_d = p.worldDisturbance();
      ap::ReducedProblem np(p);
      std::mt19937 rng(11);
      std::normal_distribution<double> normal(0.0, 0.05);
      Eigen::VectorXd delta(np.unknowns());
      for (int i = 0; i < delta.size(); ++i) delta(i) = normal(rng);
      np.setCurrent(np.retract(delta, 1.0));
      const ap::Maneuver plan = np.maneuver(np.current());
      const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
      const int N = plan.steps();
      const double h = plan.time_step;
      const bool ends = ap::schemeHasEndTorques(scheme);
      double worst = 0.0, scale = 0.0;
      for (int k = ends ? 0 : 1; k <= (ends ? N - 1 : N - 2); ++k) {
        const ap::Vector3 now =
            plan.attitude[k] * ap::planArrayMomentum(scheme, p.inertia, array, plan, k, tau_d);
        const ap::Vector3 next =
            plan.attitude[k + 1] *
            ap::planArrayMomentum(scheme, p.inertia, array, plan, k + 1, tau_d);
        const ap::Vector3 impulse =
            0.5 * h *
            (plan.attitude[k] * plan.torque[k] + plan.attitude[k + 1] * plan.torque[k + 1]);
        worst = std::max(worst, (next - now + impulse).norm());
        scale = std::max(scale, now.norm() + impulse.norm());
      }
      EXPECT_LE(worst, 1e-12 * scale) << ap::schemeName(scheme) << (disturbed ? " disturbed" : "");
      EXPECT_GT(scale, 0.1);
    }
}

/// u_k = A⁺(−τ_k − Ω_k × q_k) is the wheel momenta's rate to O(h²): against their central
/// difference on smooth (converged minimum-effort) plans of a biased, spinning slew.
TEST(ReactionWheelPhysics, WheelTorquesAreTheMomentaRateToSecondOrder) {
  for (const ap::SchemeKind scheme : {ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    std::vector<double> errors;
    for (const int N : {32, 64, 128}) {
      ap::PlanningProblem p = wheelProblem(scheme, true, N);
      const ap::ReactionWheels wheels = p.reaction_wheels;
      p.reaction_wheels = {};  // the plan without limits; the wheels only read it
      const ap::PlanResult r = ap::planManeuver(p);
      ASSERT_TRUE(r.converged()) << r.message();
      const ap::WheelStates w = ap::wheelStates(scheme, p.inertia, wheels, r.maneuver);
      double worst = 0.0;
      for (int k = 2; k < N - 1; ++k) {
        const Eigen::VectorXd rate =
            (w.momentum[k + 1] - w.momentum[k - 1]) / (2 * r.maneuver.time_step);
        worst = std::max(worst, (w.torque[k] - rate).cwiseAbs().maxCoeff());
      }
      errors.push_back(worst);
      std::printf("%s N = %d: max |u_k - central difference of h_w| = %.3g N m\n",
                  ap::schemeName(scheme).c_str(), N, worst);
    }
    EXPECT_GT(errors[0] / errors[1], 3.0)
        << ap::schemeName(scheme) << " " << errors[0] << " " << errors[1];
    EXPECT_GT(errors[1] / errors[2], 3.0)
        << ap::schemeName(scheme) << " " << errors[1] << " " << errors[2];
  }
}

// ---- planning ----------------------------------------------------------------------------------

namespace {

/// J = 10 I, three orthogonal wheels, zero bias, |τ| ≤ 1 N m, |A h_w| ≤ 2 N m s, rest to rest
/// through 1 rad: the eigenaxis bang–coast–bang slew takes T* = θJ/H + H/U = 5 + 2 = 7 s.
ap::PlanningProblem closedFormSlew(int steps) {
  ap::PlanningProblem p;
  p.inertia = 10.0 * ap::Matrix3::Identity();
  p.steps = steps;
  p.scheme = ap::SchemeKind::SecondOrder;
  p.objective = ap::Objective::MinimumTime;
  p.duration = 0.0;
  p.final_attitude = ap::so3::exp(ap::Vector3(1.0, 2.0, -2.0).normalized());
  p.constraints = {ap::PlanningConstraint::maxTorqueNorm(1.0)};
  p.reaction_wheels.spin_axes = {ap::Vector3::UnitX(), ap::Vector3::UnitY(), ap::Vector3::UnitZ()};
  p.reaction_wheels.max_torque = {10.0};    // not binding: the body-torque norm is
  p.reaction_wheels.max_momentum = {10.0};  // not binding: the envelope is
  p.reaction_wheels.max_momentum_norm = 2.0;
  return p;
}

}  // namespace

TEST(ReactionWheelMinimumTime, MomentumLimitedSlewMeetsTheBangCoastBangClosedForm) {
  constexpr double kClosedForm = 7.0;
  std::vector<double> errors;
  for (const int N : {32, 64, 128}) {
    const ap::PlanResult r = ap::planManeuver(closedFormSlew(N));
    ASSERT_TRUE(r.converged()) << "N = " << N << ": " << r.message();
    // Free time's KKT point, not the fallback search on T (a curvature term the free-time
    // assembly omits for non-stencil quantities once made the envelope stall it).
    EXPECT_TRUE(r.minimum_time.kkt_point) << "N = " << N << ": " << r.message();
    // On the bound to the interior point's tolerance (N m and N m s, limits 1 and 2).
    EXPECT_LE(r.max_constraint_violation, 1e-8) << "N = " << N;
    errors.push_back(std::abs(r.minimum_duration - kClosedForm) / kClosedForm);
    std::printf(
        "N = %d: T* = %.9f s (relative error %.3g), violation %.3g, %d iterations, %.3g s\n", N,
        r.minimum_duration, errors.back(), r.max_constraint_violation, r.iterations,
        r.solve_time_s);
  }
  EXPECT_LE(errors.back(), 5e-3);
  EXPECT_LT(errors[1], errors[0]);
  EXPECT_LT(errors[2], errors[1]);
}

/// Minimum time whose only torque bound is the wheels' (a biased pyramid, per-wheel torque and
/// momentum limits, no body-torque bound), on every scheme: a converged plan (the structured
/// starts once began at T = 0 here, the eigenaxis duration not reading the wheel limits, and
/// every request failed), every wheel limit met at the nodes and, from its wheel torques, in the
/// discrete replay on its scheme to 1e-9 relative.
TEST(ReactionWheelMinimumTime, WheelTorqueLimitsAloneBoundMinimumTime) {
  for (const ap::SchemeKind scheme :
       {ap::SchemeKind::Paper, ap::SchemeKind::Variational, ap::SchemeKind::SecondOrder}) {
    ap::PlanningProblem p = wheelProblem(scheme, false, 32);
    p.objective = ap::Objective::MinimumTime;
    p.duration = 0.0;
    p.reaction_wheels.max_torque = {0.19};
    p.reaction_wheels.max_momentum = {0.6};
    p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << ap::schemeName(scheme) << ": " << r.message();
    EXPECT_GT(r.minimum_duration, 0.0);
    const double h = r.maneuver.time_step;
    const ap::WheelStates w = ap::wheelStates(scheme, p.inertia, p.reaction_wheels, r.maneuver);
    Eigen::VectorXd h0(4);
    for (int i = 0; i < 4; ++i) h0(i) = p.reaction_wheels.initialMomentum(i);
    const ap::DiscreteWheelReplay replay =
        ap::replayWithWheelsOnTheScheme(scheme, p.inertia, ap::wheelArray(p.reaction_wheels).axes,
                                        p.initial_attitude, p.initial_velocity, h0, h, w.torque);
    const int first = ap::schemeHasEndTorques(scheme) ? 0 : 1;
    double peak_momentum = 0.0, peak_torque = 0.0;
    for (int k = 0; k <= p.steps; ++k) {
      peak_momentum = std::max(peak_momentum, replay.momentum[k].cwiseAbs().maxCoeff());
      if (k >= first && k <= p.steps - first)
        peak_torque = std::max(peak_torque, w.torque[k].cwiseAbs().maxCoeff());
    }
    std::printf("%s: T* = %.9f s, %d iterations, replay peak |h| %.12g, peak |u| %.12g\n",
                ap::schemeName(scheme).c_str(), r.minimum_duration, r.iterations, peak_momentum,
                peak_torque);
    EXPECT_LE(peak_momentum, 0.6 * (1 + 1e-9)) << ap::schemeName(scheme);
    EXPECT_LE(peak_torque, 0.19 * (1 + 1e-9)) << ap::schemeName(scheme);
  }
}

namespace {

/// The peak wheel momentum and torque [N m s, N m] of `p` planned without the wheels' limits.
struct WheelPeaks {
  double momentum = 0.0, torque = 0.0;
};
WheelPeaks unconstrainedPeaks(ap::PlanningProblem p) {
  const ap::ReactionWheels wheels = p.reaction_wheels;
  p.reaction_wheels = {};
  const ap::PlanResult free = ap::planManeuver(p);
  EXPECT_TRUE(free.converged()) << free.message();
  const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, wheels, free.maneuver);
  WheelPeaks out;
  for (int k = 0; k <= p.steps; ++k) {
    out.momentum = std::max(out.momentum, w.momentum[k].cwiseAbs().maxCoeff());
    out.torque = std::max(out.torque, w.torque[k].cwiseAbs().maxCoeff());
  }
  return out;
}

}  // namespace

/// Seeded random biased pyramid slews whose wheel momentum limit is below the unconstrained
/// plan's peak: converged plans meet every wheel limit on their own wheel states.
TEST(ReactionWheelMinimumEffort, ConvergedPlansMeetEveryWheelLimit) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int converged = 0;
  for (int c = 0; c < 6; ++c) {
    ap::PlanningProblem p = wheelProblem(ap::SchemeKind::SecondOrder, false, 64);
    p.inertia = ap::Vector3(10 + 4 * uniform(rng), 12 + 4 * uniform(rng), 14 + 4 * uniform(rng))
                    .asDiagonal();
    p.final_attitude = ap::so3::exp(ap::Vector3(uniform(rng), uniform(rng), uniform(rng)) * 1.2);
    p.duration = 20.0;
    const WheelPeaks peaks = unconstrainedPeaks(p);
    const double peak_h = peaks.momentum, peak_u = peaks.torque;
    p.reaction_wheels.max_momentum = {0.85 * peak_h};
    p.reaction_wheels.max_torque = {2.0 * peak_u};
    p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
    if (!refusalOf(p).empty()) continue;  // the end state beyond the limit
    const ap::PlanResult r = ap::planManeuver(p);
    if (!r.converged()) continue;
    ++converged;
    const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    for (int k = 0; k <= p.steps; ++k) {
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(std::abs(w.momentum[k](i)), 0.85 * peak_h * (1 + 1e-9))
            << "case " << c << " k " << k;
        EXPECT_LE(std::abs(w.torque[k](i)), 2.0 * peak_u * (1 + 1e-9))
            << "case " << c << " k " << k;
      }
    }
    EXPECT_GT(r.active_constraints, 0) << "case " << c;
  }
  std::printf("%d of 6 wheel-limited requests converged\n", converged);
  EXPECT_GE(converged, 4);
}

/// The seeded suite widened: every scheme the wheels plan with, a random bias, spinning ends on
/// every other request, per-wheel limits and the envelope on every third (each limit below the
/// unconstrained plan's peak unless the end nodes' boundary momenta lie above it). Every
/// converged plan meets every wheel limit and the envelope on its own wheel states to 1e-9
/// relative; the refusals (an end state beyond the envelope) and the unconverged requests are
/// counted, not hidden.
TEST(ReactionWheelMinimumEffort, SeededSuiteAcrossSchemesMeetsEveryWheelLimit) {
  std::mt19937 rng(4201);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const ap::SchemeKind schemes[] = {ap::SchemeKind::Paper, ap::SchemeKind::Variational,
                                    ap::SchemeKind::SecondOrder};
  int planned = 0, converged = 0, refused = 0, binding = 0;
  for (int c = 0; c < 12; ++c) {
    ap::PlanningProblem p = wheelProblem(schemes[c % 3], c % 2 == 1, 48);
    p.duration = 20.0;
    p.final_attitude = ap::so3::exp(ap::Vector3(uniform(rng), uniform(rng), uniform(rng)));
    p.reaction_wheels.initial_momentum.clear();
    for (int i = 0; i < 4; ++i) p.reaction_wheels.initial_momentum.push_back(0.3 * uniform(rng));
    p.reaction_wheels.max_momentum = {100.0};
    p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
    const WheelPeaks peaks = unconstrainedPeaks(p);
    // The end nodes' wheel momenta are boundary data (the same on every plan): a limit below
    // them is refused by name, so each limit stays 5 % above them.
    ap::Maneuver ends;
    ends.attitude = {p.initial_attitude, p.final_attitude};
    ends.angular_velocity = {p.initial_velocity, p.final_velocity};
    ends.torque.assign(2, ap::Vector3::Zero());
    ends.time_step = p.duration;
    const ap::WheelStates end_states =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, ends);
    p.reaction_wheels.max_momentum.clear();
    p.reaction_wheels.max_torque.clear();
    for (int i = 0; i < 4; ++i) {
      const double at_ends =
          std::max(std::abs(end_states.momentum[0](i)), std::abs(end_states.momentum[1](i)));
      p.reaction_wheels.max_momentum.push_back(
          std::max((0.8 + 0.1 * uniform(rng)) * peaks.momentum, 1.05 * at_ends));
      p.reaction_wheels.max_torque.push_back((1.5 + 0.3 * uniform(rng)) * peaks.torque);
    }
    if (c % 3 == 0) p.reaction_wheels.max_momentum_norm = 1.2 * peaks.momentum;
    if (!refusalOf(p).empty()) {
      ++refused;
      continue;
    }
    ++planned;
    const ap::PlanResult r = ap::planManeuver(p);
    if (!r.converged()) {
      std::printf("case %d (%s): %s\n", c, ap::schemeName(p.scheme).c_str(), r.message().c_str());
      continue;
    }
    ++converged;
    const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
    const int first = ap::schemeHasEndTorques(p.scheme) ? 0 : 1;
    for (int k = 0; k <= p.steps; ++k) {
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(std::abs(w.momentum[k](i)), p.reaction_wheels.momentumLimit(i) * (1 + 1e-9))
            << "case " << c << " k " << k << " wheel " << i;
        if (k >= first && k <= p.steps - first) {
          EXPECT_LE(std::abs(w.torque[k](i)), p.reaction_wheels.torqueLimit(i) * (1 + 1e-9))
              << "case " << c << " k " << k << " wheel " << i;
        }
      }
      EXPECT_LE((array.axes * w.momentum[k]).norm(),
                p.reaction_wheels.max_momentum_norm * (1 + 1e-9))
          << "case " << c << " k " << k;
    }
    if (r.active_constraints > 0) ++binding;  // none where the end nodes set every limit
  }
  std::printf("%d planned (%d refused by name), %d converged, %d with active limits\n", planned,
              refused, converged, binding);
  EXPECT_GE(planned, 8);
  EXPECT_GE(converged, planned * 3 / 4);
  EXPECT_GE(binding, converged / 2);
}

// ---- the independent replay --------------------------------------------------------------------

/// A wheel-limited biased pyramid slew, replayed as body + wheels from its wheel torques alone
/// (replayWithWheels: continuous dynamics, RK4): the torques fly the plan (the terminal attitude
/// miss and the wheels' momentum overshoot of the limit between and at the nodes both O(h²)).
TEST(ReactionWheelReplay, WheelTorquesFlyThePlanWithinTheLimitsToSecondOrder) {
  ap::PlanningProblem base = wheelProblem(ap::SchemeKind::SecondOrder, false, 64);
  base.duration = 20.0;
  const ap::ReactionWheels wheels = base.reaction_wheels;
  const double peak = unconstrainedPeaks(base).momentum;
  std::vector<double> misses, overshoots;
  for (const int N : {64, 128, 256}) {
    ap::PlanningProblem p = base;
    p.steps = N;
    p.reaction_wheels.max_momentum = {0.85 * peak};
    p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << "N = " << N << ": " << r.message();
    const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
    const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
    Eigen::VectorXd h0(4);
    for (int i = 0; i < 4; ++i) h0(i) = p.reaction_wheels.initialMomentum(i);
    const ap::WheelReplay replay =
        ap::replayWithWheels(p.inertia, array.axes, p.initial_attitude, p.initial_velocity, h0,
                             r.maneuver.time_step, w.torque);
    misses.push_back(ap::so3::angleBetween(replay.attitude.back(), p.final_attitude));
    overshoots.push_back(std::max(0.0, replay.peak_momentum.maxCoeff() / (0.85 * peak) - 1.0));
    std::printf("N = %d: terminal miss %.3g rad, momentum overshoot %.3g (relative)\n", N,
                misses.back(), overshoots.back());
    // The plan's own wheel states meet the limits at the nodes to round-off.
    for (int k = 0; k <= N; ++k) {
      EXPECT_LE(w.momentum[k].cwiseAbs().maxCoeff(), 0.85 * peak * (1 + 1e-9)) << "k = " << k;
      EXPECT_LE(w.torque[k].cwiseAbs().maxCoeff(), wheels.torqueLimit(0) * (1 + 1e-9))
          << "k = " << k;
    }
  }
  EXPECT_LT(misses[0], 1e-2);
  EXPECT_GT(misses[0] / misses[1], 3.0);
  EXPECT_GT(misses[1] / misses[2], 3.0);
  EXPECT_LT(overshoots[0], 1e-2);
  EXPECT_LE(overshoots[2], overshoots[0] / 8.0 + 1e-12);
}

/// With a constant world-frame disturbance τ_d the wheel-limited plan (π_k = π₀ + t_k τ_d) is
/// flown by its wheel torques: the independent replay of body + wheels + τ_d from u alone reaches
/// the target to O(h²) and keeps the momentum limit to O(h²); the same torques replayed without
/// τ_d miss by far more (the plan carries the disturbance, it does not ignore it).
TEST(ReactionWheelReplay, WorldDisturbanceIsFlownByTheWheelTorquesToSecondOrder) {
  ap::PlanningProblem base = wheelProblem(ap::SchemeKind::SecondOrder, false, 64);
  base.duration = 20.0;
  base.reaction_wheels.max_momentum = {3.0};
  base.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
  disturb(&base, ap::Vector3(0.004, -0.006, 0.003));
  const ap::Vector3 tau_d = base.worldDisturbance();
  const ap::PlanResult free = ap::planManeuver(base);
  ASSERT_TRUE(free.converged()) << free.message();
  double peak = 0.0;
  for (const Eigen::VectorXd& h :
       ap::wheelStates(base.scheme, base.inertia, base.reaction_wheels, free.maneuver, tau_d)
           .momentum)
    peak = std::max(peak, h.cwiseAbs().maxCoeff());
  const double limit = 0.85 * peak;
  std::vector<double> misses, overshoots, undisturbed;
  for (const int N : {64, 128, 256}) {
    ap::PlanningProblem p = base;
    p.steps = N;
    p.reaction_wheels.max_momentum = {limit};
    const ap::PlanResult r = ap::planManeuver(p);
    ASSERT_TRUE(r.converged()) << "N = " << N << ": " << r.message();
    EXPECT_GT(r.active_constraints, 0);
    const ap::WheelStates w =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver, tau_d);
    for (int k = 0; k <= N; ++k)
      EXPECT_LE(w.momentum[k].cwiseAbs().maxCoeff(), limit * (1 + 1e-9)) << "k = " << k;
    const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
    Eigen::VectorXd h0(4);
    for (int i = 0; i < 4; ++i) h0(i) = p.reaction_wheels.initialMomentum(i);
    const auto fly = [&](const ap::Vector3& disturbance) {
      return ap::replayWithWheels(p.inertia, array.axes, p.initial_attitude, p.initial_velocity, h0,
                                  r.maneuver.time_step, w.torque, disturbance);
    };
    const ap::WheelReplay replay = fly(tau_d);
    misses.push_back(ap::so3::angleBetween(replay.attitude.back(), p.final_attitude));
    overshoots.push_back(std::max(0.0, replay.peak_momentum.maxCoeff() / limit - 1.0));
    undisturbed.push_back(
        ap::so3::angleBetween(fly(ap::Vector3::Zero()).attitude.back(), p.final_attitude));
    std::printf("N = %d: terminal miss %.3g rad (without the disturbance %.3g), overshoot %.3g\n",
                N, misses.back(), undisturbed.back(), overshoots.back());
  }
  EXPECT_LT(misses[0], 1e-2);
  EXPECT_GT(misses[0] / misses[1], 3.0);
  EXPECT_GT(misses[1] / misses[2], 3.0);
  EXPECT_LT(overshoots[0], 1e-2);
  EXPECT_LE(overshoots[2], overshoots[0] / 8.0 + 1e-12);
  EXPECT_GT(undisturbed[2], 100.0 * misses[2]);
}

/// A converged wheel plan's wheel torques u_k replayed alone on the plan's own scheme
/// (replayWithWheelsOnTheScheme: the discrete mechanics of body + wheels, independent of the
/// planner's wheel quantities) for seeded biased pyramid slews of every scheme, spinning ends on
/// every other, a world disturbance on one (second_order): the replay reproduces the plan's
/// attitudes and wheel momenta to round-off, so every wheel limit (and the envelope) holds in it to
/// 1e-9 relative; a torque perturbed at one node by 1e-3 of its limit is caught (the replay leaves
/// the plan).
TEST(ReactionWheelReplay, DiscreteReplayFromTheWheelTorquesReproducesThePlanToRoundOff) {
  std::mt19937 rng(4202);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const ap::SchemeKind schemes[] = {ap::SchemeKind::Paper, ap::SchemeKind::Variational,
                                    ap::SchemeKind::SecondOrder};
  int replayed = 0, binding = 0;
  for (int c = 0; c < 7; ++c) {
    ap::PlanningProblem p = wheelProblem(schemes[c % 3], c % 2 == 1, 64);
    p.duration = 20.0;
    p.final_attitude = ap::so3::exp(ap::Vector3(uniform(rng), uniform(rng), uniform(rng)));
    for (double& h0 : p.reaction_wheels.initial_momentum) h0 = 0.3 * uniform(rng);
    p.reaction_wheels.max_momentum = {100.0};
    p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
    if (c == 5) disturb(&p, ap::Vector3(0.004, -0.006, 0.003));
    const ap::Vector3 tau_d = p.worldDisturbance();
    const WheelPeaks peaks = unconstrainedPeaks(p);
    p.reaction_wheels.max_momentum = {0.85 * peaks.momentum};
    p.reaction_wheels.max_torque = {1.5 * peaks.torque};
    if (c % 3 == 2) p.reaction_wheels.max_momentum_norm = 1.1 * peaks.momentum;
    if (!refusalOf(p).empty()) continue;  // an end state beyond a limit: nothing to replay
    const ap::PlanResult r = ap::planManeuver(p);
    if (!r.converged()) {
      std::printf("case %d (%s): %s\n", c, ap::schemeName(p.scheme).c_str(), r.message().c_str());
      continue;
    }
    ++replayed;
    if (r.active_constraints > 0) ++binding;
    const ap::WheelStates w =
        ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver, tau_d);
    const ap::WheelArray array = ap::wheelArray(p.reaction_wheels);
    Eigen::VectorXd h0(4);
    for (int i = 0; i < 4; ++i) h0(i) = p.reaction_wheels.initialMomentum(i);
    const auto replayOf = [&](const std::vector<Eigen::VectorXd>& u) {
      return ap::replayWithWheelsOnTheScheme(p.scheme, p.inertia, array.axes, p.initial_attitude,
                                             p.initial_velocity, h0, r.maneuver.time_step, u,
                                             tau_d);
    };
    const auto departure = [&](const ap::DiscreteWheelReplay& replay) {
      double attitude = 0.0, momentum = 0.0;
      for (int k = 0; k <= p.steps; ++k) {
        attitude =
            std::max(attitude, ap::so3::angleBetween(replay.attitude[k], r.maneuver.attitude[k]));
        momentum = std::max(momentum, (replay.momentum[k] - w.momentum[k]).cwiseAbs().maxCoeff());
      }
      return std::make_pair(attitude, momentum);
    };
    const ap::DiscreteWheelReplay replay = replayOf(w.torque);
    const auto [attitude, momentum] = departure(replay);
    const double velocity = (replay.node_velocity.back() - p.final_velocity).norm();
    std::printf(
        "case %d (%s): attitude departure %.3g rad, wheel momentum departure %.3g N m s, "
        "terminal velocity %.3g rad/s, %d active\n",
        c, ap::schemeName(p.scheme).c_str(), attitude, momentum, velocity, r.active_constraints);
    EXPECT_LT(attitude, 1e-11) << "case " << c;
    EXPECT_LT(momentum, 1e-11 * peaks.momentum) << "case " << c;
    EXPECT_LT(velocity, 1e-11) << "case " << c;
    for (int k = 0; k <= p.steps; ++k) {
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(std::abs(replay.momentum[k](i)), p.reaction_wheels.momentumLimit(i) * (1 + 1e-9))
            << "case " << c << " k " << k << " wheel " << i;
      }
      EXPECT_LE((array.axes * replay.momentum[k]).norm(),
                p.reaction_wheels.max_momentum_norm * (1 + 1e-9))
          << "case " << c << " k " << k;
    }
    // One wheel's torque off by 1e-3 of its limit at one interior node: the replay leaves the plan.
    std::vector<Eigen::VectorXd> wrong = w.torque;
    wrong[p.steps / 3](c % 4) += 1e-3 * p.reaction_wheels.torqueLimit(0);
    const auto [wrong_attitude, wrong_momentum] = departure(replayOf(wrong));
    std::printf("  u perturbed at k = %d: departure %.3g rad, %.3g N m s\n", p.steps / 3,
                wrong_attitude, wrong_momentum);
    EXPECT_GT(wrong_attitude, 1e4 * std::max(attitude, 1e-16)) << "case " << c;
    EXPECT_GT(wrong_momentum, 1e-6 * peaks.momentum) << "case " << c;
  }
  std::printf("%d replayed, %d with active limits\n", replayed, binding);
  EXPECT_GE(replayed, 6);
  EXPECT_GE(binding, replayed / 2);
}

/// The discrete replay refuses by name what it cannot replay: fourth_order (not a discretization),
/// fewer than two torque rows, a row or an initial momentum with the wrong number of wheels.
TEST(ReactionWheelReplay, DiscreteReplayRefusesWhatItCannotReplayByName) {
  const ap::PlanningProblem p = wheelProblem(ap::SchemeKind::SecondOrder, false, 4);
  const Eigen::Matrix<double, 3, Eigen::Dynamic> axes = ap::wheelArray(p.reaction_wheels).axes;
  const Eigen::VectorXd h0 = Eigen::VectorXd::Zero(4);
  const auto replay = [&](ap::SchemeKind scheme, const Eigen::VectorXd& initial,
                          const std::vector<Eigen::VectorXd>& u) {
    return refusal([&] {
      ap::replayWithWheelsOnTheScheme(scheme, p.inertia, axes, p.initial_attitude,
                                      p.initial_velocity, initial, 0.5, u);
    });
  };
  const std::vector<Eigen::VectorXd> rows(5, Eigen::VectorXd::Zero(4));
  EXPECT_NE(replay(ap::SchemeKind::FourthOrder, h0, rows).find("scheme: "), std::string::npos);
  EXPECT_NE(replay(ap::SchemeKind::FourthOrder, h0, rows).find("got fourth_order"),
            std::string::npos);
  EXPECT_NE(replay(ap::SchemeKind::SecondOrder, h0, {rows[0]}).find("torque: need at least 2"),
            std::string::npos);
  std::vector<Eigen::VectorXd> short_row = rows;
  short_row[2] = Eigen::VectorXd::Zero(3);
  EXPECT_NE(replay(ap::SchemeKind::Paper, h0, short_row)
                .find("torque[2]: expected 4 wheel "
                      "torques, got 3"),
            std::string::npos);
  EXPECT_NE(replay(ap::SchemeKind::Variational, Eigen::VectorXd::Zero(3), rows)
                .find("initial_momentum: expected 4 values (one per wheel), got 3"),
            std::string::npos);
  EXPECT_EQ(replay(ap::SchemeKind::SecondOrder, h0, rows), "");  // at rest: nothing to refuse
}

/// The effort the result reports as minimized (PlanResult::minimized_effort) is the one the plan
/// minimizes: on a biased pyramid slew with generous limits (an unconstrained minimum of the
/// transcription), the plan's cost is the body torques' Σ ½ w_k |τ_k|², stationary to round-off
/// along seeded random moves of the interior attitudes, while the wheels' Σ ½ w_k |u_k|² is not
/// (its slope is orders of magnitude larger): had the planner minimized the wheel torques, the
/// two would swap.
TEST(ReactionWheelMinimumEffort, TheReportedEffortIsTheOneThePlanMinimizes) {
  ap::PlanningProblem p = wheelProblem(ap::SchemeKind::SecondOrder, false, 32);
  p.reaction_wheels.max_torque = {10.0};
  p.reaction_wheels.max_momentum = {30.0};
  p.reaction_wheels.max_momentum_norm = std::numeric_limits<double>::infinity();
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  ASSERT_EQ(r.active_constraints, 0);
  const auto costs = [&](const ap::Maneuver& m) {
    const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, m);
    double wheel = 0.0;
    for (int k = 0; k <= p.steps; ++k) {
      wheel += ap::schemeTorqueWeight(p.scheme, k, p.steps) * 0.5 * w.torque[k].squaredNorm();
    }
    return std::make_pair(ap::schemeCost(p.scheme, m.torque), wheel);
  };
  const auto [body0, wheel0] = costs(r.maneuver);
  EXPECT_NEAR(r.cost, body0, 1e-12 * body0) << "the result's cost sums the body torques";
  EXPECT_GT(std::abs(wheel0 - body0), 1e-3 * body0) << "the two efforts differ on this slew";
  EXPECT_EQ(ap::minimizedEffortName(r.minimized_effort), "body_torque");

  ap::ReducedProblem rp(p);
  rp.setInteriorFromAttitudes(r.maneuver.attitude);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const double eps = 1e-5;
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd direction(rp.unknowns());
    for (int i = 0; i < direction.size(); ++i) direction(i) = normal(rng);
    direction.normalize();
    const auto [body_plus, wheel_plus] = costs(rp.maneuver(rp.retract(direction, eps)));
    const auto [body_minus, wheel_minus] = costs(rp.maneuver(rp.retract(direction, -eps)));
    const double body_slope = (body_plus - body_minus) / (2 * eps);
    const double wheel_slope = (wheel_plus - wheel_minus) / (2 * eps);
    const double minimized =
        r.minimized_effort == ap::MinimizedEffort::BodyTorque ? body_slope : wheel_slope;
    const double other =
        r.minimized_effort == ap::MinimizedEffort::BodyTorque ? wheel_slope : body_slope;
    std::printf("trial %d: slope of the reported effort %.3g, of the other %.3g\n", trial,
                minimized, other);
    EXPECT_LT(std::abs(minimized), 1e-3 * std::abs(other))
        << "trial " << trial << ": slope of the reported effort " << minimized << ", of the other "
        << other;
  }
}

// ---- outputs -----------------------------------------------------------------------------------

/// The CSV carries u1..un, h1..hn after tx,ty,tz (and reads back as a plan); the JSON summary
/// carries each wheel's peaks, limits and margins.
TEST(ReactionWheelOutputs, CsvColumnsAndJsonMarginsPerWheel) {
  const ap::PlanningProblem p = closedFormSlew(32);
  const ap::PlanResult r = ap::planManeuver(p);
  ASSERT_TRUE(r.converged()) << r.message();
  const ap::WheelStates w = ap::wheelStates(p.scheme, p.inertia, p.reaction_wheels, r.maneuver);
  const std::string csv = std::string(AP_BINARY_DIR) + "/test_reaction_wheels.csv";
  ap::writeManeuverCsv(r.maneuver, w, csv);
  std::ifstream in(csv);
  std::string header, row;
  std::getline(in, header);
  EXPECT_EQ(header, "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz,u1,u2,u3,h1,h2,h3");
  for (int k = 0; k <= 16; ++k) std::getline(in, row);  // row k = 16: mid-slew
  std::vector<double> cells;
  std::stringstream cells_in(row);
  for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(std::stod(cell));
  ASSERT_EQ(cells.size(), 18u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(cells[12 + i], w.torque[16](i));
    EXPECT_EQ(cells[15 + i], w.momentum[16](i));
  }
  EXPECT_EQ(ap::readManeuverCsv(csv).steps(), 32);
  const std::string json = ap::planResultJson(p, r);
  EXPECT_NE(json.find("\"reaction_wheels\": {\"wheels\": [{\"name\": \"wheel_1\""),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"momentum_norm_margin\": "), std::string::npos);
  EXPECT_NE(
      json.find("\"effort_minimized\": \"" + ap::minimizedEffortName(r.minimized_effort) + "\"}"),
      std::string::npos)
      << json;
  EXPECT_NE(json.find("\"reaction_wheels\"]"), std::string::npos) << "constraints names it";
}
