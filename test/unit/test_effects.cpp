// Effect models: torques, Jacobians and second derivatives against definitions and
// finite differences; only the listed effects change a simulation.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstring>
#include <random>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/dynamics/simulation.hpp"

using namespace attitude_planner;

namespace {

const Matrix3 kInertia =
    (Matrix3() << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37).finished();
constexpr double kMu = 3.986004418e14, kRadius = 6.778e6;  // Earth, 400 km orbit

std::vector<std::unique_ptr<TorqueEffect>> sampleEffects() {
  std::vector<std::unique_ptr<TorqueEffect>> out;
  out.push_back(std::make_unique<GravityGradient>(kMu, kRadius, kInertia));
  out.push_back(
      std::make_unique<DisturbanceTorque>(Vector3(1e-3, -2e-3, 5e-4), TorqueFrame::World));
  out.push_back(std::make_unique<DisturbanceTorque>(Vector3(1e-3, -2e-3, 5e-4), TorqueFrame::Body));
  return out;
}

Maneuver run(const std::vector<Vector3>& torque, const EffectModel* effects, Actuation* actuation,
             SchemeKind kind = SchemeKind::Variational) {
  SimulationInput input;
  input.initial_attitude = so3::exp(Vector3(0.3, -0.2, 0.9));
  input.initial_velocity = Vector3(0.01, 0.02, -0.005);
  input.torque = torque;
  input.effects = effects;
  input.actuation = actuation;
  return simulate(DiscreteScheme(kind, kInertia, 1.0), input);
}

std::vector<Vector3> someTorques(int N) {
  std::vector<Vector3> t(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) t[k] = 1e-3 * Vector3(std::sin(0.1 * k), std::cos(0.07 * k), 0.3);
  return t;
}

}  // namespace

TEST(Effects, GravityGradientMatchesItsDefinition) {
  const GravityGradient gg(kMu, kRadius, kInertia);
  const double n = std::sqrt(kMu / (kRadius * kRadius * kRadius));
  EXPECT_NEAR(gg.meanMotion(), n, 1e-18);
  const Matrix3 R = so3::exp(Vector3(0.4, 1.1, -0.3));
  const double t = 1234.5;
  const Vector3 r_hat(std::cos(n * t), std::sin(n * t), 0.0);
  const Vector3 b = R.transpose() * r_hat;
  EXPECT_LE((gg.torque(R, t) - 3 * n * n * b.cross(kInertia * b)).norm(), 1e-20);
  // no torque when a principal axis points at the Earth
  Eigen::SelfAdjointEigenSolver<Matrix3> eig(kInertia);
  Matrix3 principal = eig.eigenvectors();
  if (principal.determinant() < 0) principal.col(2) *= -1;
  const Matrix3 aligned = so3::exp(Vector3(0, 0, n * t)) * principal.transpose();
  EXPECT_LE(gg.torque(aligned, t).norm(), 1e-12 * 3 * n * n * kInertia.norm());
}

TEST(Effects, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (const auto& effect : sampleEffects()) {
    for (int trial = 0; trial < 5; ++trial) {
      const Matrix3 R = so3::exp(Vector3(g(rng), g(rng), g(rng)));
      const double t = 500.0 * trial;
      const Matrix3 J = effect->jacobian(R, t);
      const double eps = 1e-6, scale = std::max(J.norm(), effect->torque(R, t).norm());
      for (int i = 0; i < 3; ++i) {
        const Vector3 e = eps * Vector3::Unit(i);
        const Vector3 fd = (effect->torque(Matrix3(R * so3::exp(e)), t) -
                            effect->torque(Matrix3(R * so3::exp(Vector3(-e))), t)) /
                           (2 * eps);
        EXPECT_LE((fd - J.col(i)).norm(), 1e-7 * scale + 1e-30) << effect->name();
      }
    }
  }
}

TEST(Effects, WeightedSecondDerivativesMatchSecondDifferences) {
  // w·τ(R exp δ): its Hessian at δ = 0 is the symmetric weighted second derivative.
  std::mt19937 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  for (const auto& effect : sampleEffects()) {
    const Matrix3 R = so3::exp(Vector3(g(rng), g(rng), g(rng)));
    const Vector3 w(g(rng), g(rng), g(rng));
    const double t = 777.0;
    const Matrix3 H = effect->weightedSecondDerivative(R, t, w);
    const auto f = [&](const Vector3& d) {
      return w.dot(effect->torque(Matrix3(R * so3::exp(d)), t));
    };
    const double eps = 1e-4;
    Matrix3 fd;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const Vector3 ei = eps * Vector3::Unit(i), ej = eps * Vector3::Unit(j);
        fd(i, j) = (f(ei + ej) - f(ei - ej) - f(ej - ei) + f(-ei - ej)) / (4 * eps * eps);
      }
    }
    const double scale = std::max(1e-30, std::max(fd.norm(), H.norm()));
    EXPECT_LE((fd - H).norm(), 1e-6 * scale) << effect->name();
  }
}

TEST(Effects, TimeDerivativesMatchCentralDifferencesInTime) {
  // ∂τ_e/∂t, ∂²τ_e/∂t² and ∂(∂τ_e/∂δ)/∂t at fixed R (minimum time: t_k = k h moves with h)
  // against central differences of torque() and jacobian() in t, also through a shifted clock.
  // The gravity gradient's r̂(t) turns (nonzero rates); a constant torque has none in either frame.
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::unique_ptr<TorqueEffect>> effects = sampleEffects();
  const double n = std::sqrt(kMu / (kRadius * kRadius * kRadius));
  EffectModel shifted_source;
  shifted_source.add(std::make_unique<GravityGradient>(kMu, kRadius, kInertia));
  const EffectModel shifted = shifted_source.timeShifted(321.0);
  for (std::size_t i = 0; i <= effects.size(); ++i) {
    const bool model = i == effects.size();
    const auto torque = [&](const Matrix3& R, double t) {
      return model ? shifted.torque(R, t) : effects[i]->torque(R, t);
    };
    const auto jacobian = [&](const Matrix3& R, double t) {
      return model ? shifted.jacobian(R, t) : effects[i]->jacobian(R, t);
    };
    const std::string name = model ? "time-shifted gravity_gradient" : effects[i]->name();
    for (int trial = 0; trial < 3; ++trial) {
      const Matrix3 R = so3::exp(Vector3(g(rng), g(rng), g(rng)));
      const double t = 700.0 * trial + 13.0;
      const EffectTimeDerivatives d =
          model ? shifted.timeDerivatives(R, t) : effects[i]->timeDerivatives(R, t);
      const double dt = 1e-4 / n;  // a small fraction of the orbit's time scale
      const Vector3 rate_fd = (torque(R, t + dt) - torque(R, t - dt)) / (2 * dt);
      const Vector3 acceleration_fd =
          (torque(R, t + dt) - 2 * torque(R, t) + torque(R, t - dt)) / (dt * dt);
      const Matrix3 jacobian_fd = (jacobian(R, t + dt) - jacobian(R, t - dt)) / (2 * dt);
      const double scale = std::max(torque(R, t).norm(), jacobian(R, t).norm());
      EXPECT_LE((d.torque_rate - rate_fd).norm(), 1e-6 * n * scale) << name;
      EXPECT_LE((d.torque_acceleration - acceleration_fd).norm(), 1e-5 * n * n * scale) << name;
      EXPECT_LE((d.jacobian_rate - jacobian_fd).norm(), 1e-6 * n * scale) << name;
      const bool turning = name != "disturbance_torque";
      EXPECT_EQ(d.torque_rate.norm() > 1e-3 * n * scale, turning) << name;
      EXPECT_EQ(d.jacobian_rate.norm() > 1e-3 * n * scale, turning) << name;
    }
  }
}

TEST(Effects, AnEmptyEffectListIsBitIdenticalToTheBareIntegrator) {
  const auto torque = someTorques(200);
  EffectModel none;
  Actuation nothing;
  const Maneuver bare = run(torque, nullptr, nullptr);
  const Maneuver listed = run(torque, &none, &nothing);
  for (int k = 0; k <= 200; ++k) {
    EXPECT_EQ(std::memcmp(bare.attitude[k].data(), listed.attitude[k].data(), sizeof(Matrix3)), 0);
    EXPECT_EQ(std::memcmp(bare.angular_velocity[k].data(), listed.angular_velocity[k].data(),
                          sizeof(Vector3)),
              0);
  }
}

TEST(Effects, ABodyDisturbanceActsLikeAnExtraControlTorque) {
  const Vector3 d(2e-3, -1e-3, 4e-4);
  auto torque = someTorques(150);
  EffectModel disturbed;
  disturbed.add(std::make_unique<DisturbanceTorque>(d, TorqueFrame::Body));
  const Maneuver a = run(torque, &disturbed, nullptr);
  for (int k = 1; k < 150; ++k) torque[k] += d;
  const Maneuver b = run(torque, nullptr, nullptr);
  for (int k = 0; k <= 150; ++k) EXPECT_LE((a.attitude[k] - b.attitude[k]).norm(), 1e-13);
  EXPECT_GT((a.attitude[150] - run(someTorques(150), nullptr, nullptr).attitude[150]).norm(), 1e-3);
}

TEST(Effects, ActuatorLimitsAreNeverExceededAndNoiseIsReproducible) {
  Actuation a, b, c;
  const Vector3 limit(1e-3, 2e-3, 3e-3);
  a.setLimits(limit);
  EXPECT_LE((a.apply(Vector3(5, -5, 1e-4)) - Vector3(1e-3, -2e-3, 1e-4)).norm(), 0.0);
  b.setNoise(Vector3(1e-4, 1e-4, 1e-4), 42);
  c.setNoise(Vector3(1e-4, 1e-4, 1e-4), 42);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(b.apply(Vector3::Zero()), c.apply(Vector3::Zero()));
  Actuation limited;
  limited.setLimits(limit);
  const auto torque = someTorques(120);
  std::vector<Vector3> big = torque;
  for (auto& t : big) t *= 10.0;
  big.front().setZero();
  big.back().setZero();
  const Maneuver m = run(big, nullptr, &limited);
  for (int k = 0; k <= 120; ++k) {
    EXPECT_LE((m.torque[k].cwiseAbs() - limit).maxCoeff(), 1e-18);
  }
}

#include "attitude_planner/planner.hpp"

namespace {
// A low-Earth-orbit slew: 90° about z in 10 min, with the orbit's gravity gradient and a small
// world-frame disturbance (both comparable to the control torque).
PlanningProblem leoSlew(bool with_effects) {
  PlanningProblem p;
  p.inertia = Vector3(800, 1200, 1500).asDiagonal();  // kg m², a small satellite
  p.duration = 600.0;
  p.steps = 300;
  p.final_attitude = so3::fromAxisAngle(Vector3::UnitZ(), M_PI / 2);
  p.scheme = SchemeKind::Variational;
  if (with_effects) {
    auto model = std::make_shared<EffectModel>();
    model->add(std::make_unique<GravityGradient>(kMu, kRadius, p.inertia));
    model->add(std::make_unique<DisturbanceTorque>(Vector3(2e-4, 0, -1e-4), TorqueFrame::World));
    p.effects = model;
  }
  return p;
}
}  // namespace

TEST(Effects, PlanningWithEffectsLandsWhenReplayedUnderTheSameEffects) {
  const PlanResult r = planManeuver(leoSlew(true));
  ASSERT_TRUE(r.converged()) << r.message();
  EXPECT_LE(r.terminal_attitude_error, 1e-9);  // evaluatePlan replays with the same effects
  EXPECT_LE(r.terminal_velocity_error, 1e-9);
  ASSERT_EQ(r.effects.size(), 2u);
  EXPECT_EQ(r.effects[0], "gravity_gradient");
  // The same torques replayed without the effects miss: the effects are in the plan.
  SimulationInput bare;
  bare.torque = r.maneuver.torque;
  const PlanningProblem p = leoSlew(true);
  const Maneuver m = simulate(DiscreteScheme(p.scheme, p.inertia, p.duration / p.steps), bare);
  EXPECT_GT(so3::angleBetween(p.final_attitude, m.attitude[p.steps]), 1e-4);
  // And a plan that ignores them lands only without them.
  const PlanResult ignorant = planManeuver(leoSlew(false));
  ASSERT_TRUE(ignorant.converged());
  EffectModel actual;
  actual.add(std::make_unique<GravityGradient>(kMu, kRadius, p.inertia));
  SimulationInput replay;
  replay.torque = ignorant.maneuver.torque;
  replay.effects = &actual;
  const Maneuver missed =
      simulate(DiscreteScheme(p.scheme, p.inertia, p.duration / p.steps), replay);
  EXPECT_GT(so3::angleBetween(p.final_attitude, missed.attitude[p.steps]), 1e-4);
}

TEST(Effects, TorqueLimitedPlansRespectTheBoundsAndCostAtLeastTheUnlimitedOne) {
  PlanningProblem p;
  p.inertia << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  p.allow_nonphysical_inertia = true;
  p.duration = 12.8;
  p.steps = 32;
  p.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3);
  const PlanResult free = planManeuver(p);
  ASSERT_TRUE(free.converged());
  double largest = 0;
  for (const Vector3& t : free.maneuver.torque)
    largest = std::max(largest, t.cwiseAbs().maxCoeff());
  // inactive bounds: the Newton optimum is kept
  p.max_torque = Vector3::Constant(2 * largest);
  const PlanResult loose = planManeuver(p);
  EXPECT_TRUE(loose.converged());
  EXPECT_EQ(loose.solver, "newton");
  EXPECT_EQ(loose.cost, free.cost);
  // active bounds at 70 % of the unbounded peak
  p.max_torque = Vector3::Constant(0.7 * largest);
  const PlanResult tight = planManeuver(p);
  ASSERT_TRUE(tight.converged()) << tight.message();
  EXPECT_EQ(tight.solver, "interior_point");
  EXPECT_LE(tight.terminal_attitude_error, 1e-10);
  int at_bound = 0;
  for (const Vector3& t : tight.maneuver.torque) {
    EXPECT_LE((t.cwiseAbs() - p.max_torque).maxCoeff(), 1e-12);
    if ((t.cwiseAbs() - p.max_torque).maxCoeff() > -1e-9) ++at_bound;
  }
  EXPECT_GT(at_bound, 0);  // the limit is active
  EXPECT_GE(tight.cost, free.cost * (1 - 1e-12));
}
