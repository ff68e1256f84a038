// Shooting planner for the drift + two-input BVP (seed 001, (3.8)–(3.10)): it reaches g1, the
// extremal it returns is (locally) optimal against perturbed admissible controls reaching the
// same endpoint, it is the same whatever the output sampling N, a guess selects among coexisting
// extremals, the time budget stops the search, and bad requests name the field.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <filesystem>

#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"

using namespace attitude_planner;
namespace dti = attitude_planner::drift_two_input;

namespace {

DriftTwoInputRequest exampleRequest() {
  DriftTwoInputRequest rq;
  rq.g0 = Matrix3::Identity();
  rq.g1 = so3::fromAxisAngle(Vector3(1, 1, 0), 1.2);
  rq.duration = 3.0;
  rq.steps = 60;
  rq.weights = {1.0, 2.0};
  rq.initial_costate = Vector3(-1.6, -0.9, -1.3);  // near the least-cost extremal: fast solve
  return rq;
}

// Independent model of the control problem: piecewise-constant controls u_k on N intervals,
// g_{k+1} = g_k exp(h (e3 + u1 e1 + u2 e2)), cost Σ h ½(c1 u1² + c2 u2²).
struct Discretized {
  Matrix3 g0;
  double h;
  DriftTwoInputWeights w;
  Matrix3 endpoint(const std::vector<Eigen::Vector2d>& u) const {
    Matrix3 g = g0;
    for (const auto& uk : u) g = g * so3::exp(Vector3(h * uk.x(), h * uk.y(), h));
    return g;
  }
  double cost(const std::vector<Eigen::Vector2d>& u) const {
    double J = 0;
    for (const auto& uk : u) J += 0.5 * h * (w.c1 * uk.x() * uk.x() + w.c2 * uk.y() * uk.y());
    return J;
  }
};

}  // namespace

TEST(DriftTwoInputPlanner, PlannedManeuverReachesTheTargetAttitude) {
  DriftTwoInputRequest rq = exampleRequest();
  rq.initial_costate.reset();  // default starts
  const DriftTwoInputPlan plan = planDriftTwoInput(rq);
  std::printf("%s\n", plan.message.c_str());
  ASSERT_TRUE(plan.converged()) << plan.message;
  EXPECT_LE(plan.terminal_error, 1e-10);
  const auto& tr = plan.trajectory;
  ASSERT_EQ(tr.g.size(), static_cast<size_t>(rq.steps + 1));
  EXPECT_LE((tr.g.front() - rq.g0).norm(), 0.0);
  EXPECT_LE(so3::angleBetween(tr.g.back(), rq.g1), 1e-10);
  EXPECT_NEAR(tr.t.back(), rq.duration, 1e-12);
  EXPECT_LE((tr.p.front() - plan.initial_costate).norm(), 0.0);
  const double H0 = dti::hamiltonian(tr.p[0], rq.weights), C0 = dti::casimir(tr.p[0]);
  for (size_t k = 0; k < tr.p.size(); ++k) {
    EXPECT_NEAR(tr.u[k].x(), tr.p[k].x() / rq.weights.c1, 1e-15);  // Prop. 3.1
    EXPECT_NEAR(tr.u[k].y(), tr.p[k].y() / rq.weights.c2, 1e-15);
    EXPECT_NEAR(dti::hamiltonian(tr.p[k], rq.weights), H0, 1e-12 * (1 + std::abs(H0)));
    EXPECT_NEAR(dti::casimir(tr.p[k]), C0, 1e-12 * (1 + C0));
    EXPECT_LE(so3::orthogonalityError(tr.g[k]), 1e-13);
  }
  EXPECT_GT(plan.cost, 0.0);
  // the cost is ½∫(p1²/c1 + p2²/c2) dt: trapezoid on the samples agrees to O(h²)
  double trap = 0;
  for (size_t k = 0; k + 1 < tr.p.size(); ++k) {
    trap += 0.25 * (tr.t[k + 1] - tr.t[k]) *
            (dti::runningCost<double>(tr.p[k], rq.weights) * 2 +
             dti::runningCost<double>(tr.p[k + 1], rq.weights) * 2);
  }
  EXPECT_NEAR(plan.cost, trap, 1e-2 * plan.cost);
}

TEST(DriftTwoInputPlanner, ExtremalCostIsBelowPerturbedAdmissibleControlsReachingTheSameEndpoint) {
  DriftTwoInputRequest rq = exampleRequest();
  rq.steps = 3000;  // fine samples: the controls of the independent model
  rq.max_step = 1e-3;
  const DriftTwoInputPlan plan = planDriftTwoInput(rq);
  ASSERT_TRUE(plan.converged()) << plan.message;
  const auto& tr = plan.trajectory;
  const int N = rq.steps;
  const Discretized model{rq.g0, rq.duration / N, rq.weights};
  std::vector<Eigen::Vector2d> u_star(N);
  for (int k = 0; k < N; ++k) u_star[k] = 0.5 * (tr.u[k] + tr.u[k + 1]);
  // endpoint corrections: w_j(t) = Bᵀ g(t)ᵀ g(T) e_j span the reachable directions (Gramian)
  std::vector<Eigen::Matrix<double, 2, 3>> W(N);
  for (int k = 0; k < N; ++k) {
    const Matrix3 Phi = (0.5 * (tr.g[k] + tr.g[k + 1])).transpose() * tr.g.back();
    W[k] = Phi.topRows<2>();
  }
  // admissible control through u + Σ a_j w_j that reaches g1 exactly (Newton on a ∈ R³)
  auto reachG1 = [&](const std::vector<Eigen::Vector2d>& u) {
    Vector3 a = Vector3::Zero();
    std::vector<Eigen::Vector2d> v = u;
    for (int it = 0; it < 20; ++it) {
      for (int k = 0; k < N; ++k) v[k] = u[k] + W[k] * a;
      const Vector3 r = so3::log(Matrix3(rq.g1.transpose() * model.endpoint(v)));
      if (r.norm() < 1e-14) break;
      Matrix3 J;
      for (int j = 0; j < 3; ++j) {
        std::vector<Eigen::Vector2d> vj = v;
        for (int k = 0; k < N; ++k) vj[k] += W[k].col(j) * 1e-7;
        J.col(j) = (so3::log(Matrix3(rq.g1.transpose() * model.endpoint(vj))) - r) / 1e-7;
      }
      a -= J.fullPivLu().solve(r);
    }
    for (int k = 0; k < N; ++k) v[k] = u[k] + W[k] * a;
    EXPECT_LE(so3::angleBetween(model.endpoint(v), rq.g1), 1e-12);
    return v;
  };
  const double J0 = model.cost(reachG1(u_star));
  EXPECT_NEAR(J0, plan.cost, 1e-4 * plan.cost);  // the model agrees with the planner
  const double T = rq.duration;
  const std::function<Eigen::Vector2d(double)> directions[] = {
      [&](double t) { return Eigen::Vector2d(std::sin(M_PI * t / T), 0.0); },
      [&](double t) { return Eigen::Vector2d(0.0, std::cos(2 * M_PI * t / T)); },
      [&](double t) { return Eigen::Vector2d(t / T - 0.5, std::sin(3 * M_PI * t / T)); },
      [&](double t) { return Eigen::Vector2d(std::cos(5 * t), -std::sin(7 * t)); }};
  for (const auto& d : directions) {
    double Jp = 0, Jm = 0;
    const double eps = 0.05;
    for (double sgn : {1.0, -1.0}) {
      std::vector<Eigen::Vector2d> u = u_star;
      for (int k = 0; k < N; ++k) u[k] += sgn * eps * d((k + 0.5) * model.h);
      (sgn > 0 ? Jp : Jm) = model.cost(reachG1(u));
    }
    // second-order growth, and no first-order term: the extremal is a constrained stationary point
    EXPECT_GT(Jp, J0);
    EXPECT_GT(Jm, J0);
    const double even = 0.5 * (Jp + Jm) - J0, odd = 0.5 * (Jp - Jm);
    std::printf("J0 = %.10f  J(+eps) - J0 = %.3g  J(-eps) - J0 = %.3g  odd/even = %.3g\n", J0,
                Jp - J0, Jm - J0, std::abs(odd) / even);
    EXPECT_LE(std::abs(odd), 0.05 * even);
  }
}

TEST(DriftTwoInputPlanner, GuessSelectsWhichOfCoexistingExtremalsIsFound) {
  // g1 = exp(T E3): the uncontrolled drift reaches it at zero cost, and other extremals, which
  // spend control effort, reach it too.
  DriftTwoInputRequest rq;
  rq.duration = 3.0;
  rq.steps = 60;
  rq.weights = {1.0, 2.0};
  rq.g1 = so3::exp(Vector3(0, 0, 3.0));
  rq.initial_costate = Vector3(0.0, 0.0, 0.0);
  const DriftTwoInputPlan a = planDriftTwoInput(rq);
  rq.initial_costate = Vector3(2.0, 1.0, 0.0);
  const DriftTwoInputPlan b = planDriftTwoInput(rq);
  std::printf("guess 0: %s\nguess (2, 1, 0): %s\n", a.message.c_str(), b.message.c_str());
  ASSERT_TRUE(a.converged()) << a.message;
  ASSERT_TRUE(b.converged()) << b.message;
  EXPECT_LE(a.terminal_error, 1e-10);
  EXPECT_LE(b.terminal_error, 1e-10);
  EXPECT_LE(a.cost, 1e-20);
  EXPECT_GT(b.cost, 1.0);
  EXPECT_GT((a.initial_costate - b.initial_costate).norm(), 1.0);
  EXPECT_NE(b.message.find("cost"), std::string::npos);
}

TEST(DriftTwoInputPlanner, ShootingJacobianFromDualNumbersMatchesFiniteDifferences) {
  const Matrix3 g0 = so3::exp(Vector3(0.3, -0.2, 0.5)), g1 = so3::exp(Vector3(-0.4, 0.9, 0.1));
  const DriftTwoInputWeights w{0.8, 1.6};
  const Vector3 p0(0.7, -0.4, 0.9);
  Vector3 r;
  Matrix3 J;
  driftTwoInputShootingResidual(g0, g1, 2.5, w, p0, &r, &J);
  Matrix3 fd;
  for (int j = 0; j < 3; ++j) {
    const double e = 1e-6;
    Vector3 rp, rm;
    driftTwoInputShootingResidual(g0, g1, 2.5, w, p0 + e * Vector3::Unit(j), &rp, nullptr);
    driftTwoInputShootingResidual(g0, g1, 2.5, w, p0 - e * Vector3::Unit(j), &rm, nullptr);
    fd.col(j) = (rp - rm) / (2 * e);
  }
  EXPECT_LE((J - fd).norm(), 1e-8 * J.norm()) << J << "\n" << fd;
  EXPECT_GT(J.norm(), 0.1);
}

TEST(DriftTwoInputPlanner, LeftInvarianceGivesTheSameCostateForRotatedBoundaryAttitudes) {
  // (3.8)–(3.10) are left-invariant: (g0, g1) → (R g0, R g1) leaves p(t) and the cost unchanged
  DriftTwoInputRequest rq = exampleRequest();
  rq.weights = {2.5, 0.7};  // the other ordering, c2 < c1
  rq.initial_costate = Vector3(-1.0, -1.0, -1.0);
  const DriftTwoInputPlan a = planDriftTwoInput(rq);
  const Matrix3 R = so3::exp(Vector3(1.1, -0.3, 2.0));
  rq.g0 = R * rq.g0;
  rq.g1 = R * rq.g1;
  const DriftTwoInputPlan b = planDriftTwoInput(rq);
  ASSERT_TRUE(a.converged()) << a.message;
  ASSERT_TRUE(b.converged()) << b.message;
  EXPECT_LE((a.initial_costate - b.initial_costate).norm(), 1e-8);
  EXPECT_NEAR(a.cost, b.cost, 1e-9 * a.cost);
  EXPECT_LE(b.terminal_error, 1e-10);
  for (size_t k = 0; k < a.trajectory.g.size(); ++k) {
    EXPECT_LE((R * a.trajectory.g[k] - b.trajectory.g[k]).norm(), 1e-8);
  }
}

TEST(DriftTwoInputPlanner, MultipleShootingSolvesALongHorizonAndSingleShootingConfirmsIt) {
  DriftTwoInputRequest rq = exampleRequest();
  rq.duration = 20.0;
  rq.steps = 100;
  rq.shooting_intervals = 8;
  rq.initial_costate = Vector3(0.5, 0.5, 0.0);
  const DriftTwoInputPlan ms = planDriftTwoInput(rq);
  std::printf("multiple shooting, T = 20 s: %s\n", ms.message.c_str());
  ASSERT_TRUE(ms.converged()) << ms.message;
  EXPECT_LE(ms.terminal_error, 1e-10);
  // the same extremal is a fixed point of single shooting: started there it stays there
  rq.shooting_intervals = 1;
  rq.initial_costate = ms.initial_costate;
  const DriftTwoInputPlan ss = planDriftTwoInput(rq);
  ASSERT_TRUE(ss.converged()) << ss.message;
  EXPECT_LE(ss.iterations, 2);
  EXPECT_LE((ss.initial_costate - ms.initial_costate).norm(), 1e-9);
  EXPECT_NEAR(ss.cost, ms.cost, 1e-9 * ms.cost);
}

TEST(DriftTwoInputPlanner, InvalidRequestsNameTheField) {
  DriftTwoInputRequest rq = exampleRequest();
  rq.duration = 0.0;
  try {
    planDriftTwoInput(rq);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("duration"), std::string::npos) << e.what();
  }
  rq = exampleRequest();
  rq.g1 = 2.0 * Matrix3::Identity();
  try {
    planDriftTwoInput(rq);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("g1"), std::string::npos) << e.what();
  }
  rq = exampleRequest();
  rq.shooting_intervals = 0;
  EXPECT_THROW(planDriftTwoInput(rq), InvalidInput);
  rq = exampleRequest();
  rq.weights.c2 = -1.0;
  EXPECT_THROW(planDriftTwoInput(rq), InvalidInput);
}

TEST(DriftTwoInputPlanner, TaylorIntegratorMatchesTheStructurePreservingFlow) {
  // The planner's integrator (order-20 Taylor series, adaptive step) against the fourth-order
  // implicit-midpoint composition of drift_two_input.hpp at a fine step, on three costates from
  // small to large: attitudes, costates and cost agree to the reference's own error.
  const Matrix3 g0 = so3::exp(Vector3(0.3, -0.2, 0.5));
  const DriftTwoInputWeights w{1.0, 2.0};
  for (const Vector3& p0 :
       {Vector3(0.7, -0.4, 0.9), Vector3(-0.94, -0.52, 1.6), Vector3(-3.6, 13.4, -13.0)}) {
    int steps = 0;
    const DriftTwoInputTrajectory a = sampleDriftTwoInputExtremal(g0, p0, 3.0, 30, w, 0.0, &steps);
    DriftTwoInputIntegration o;
    o.order = 4;
    o.substeps = 800;  // h = 1.25e-4 s
    const DriftTwoInputTrajectory b = integrateDriftTwoInputExtremal(g0, p0, 3.0, 30, w, o);
    double eg = 0, ep = 0;
    for (size_t k = 0; k < a.g.size(); ++k) {
      eg = std::max(eg, so3::angleBetween(a.g[k], b.g[k]));
      ep = std::max(ep, (a.p[k] - b.p[k]).norm() / p0.norm());
      EXPECT_LE(so3::orthogonalityError(a.g[k]), 1e-14);
    }
    std::printf(
        "|p0| = %.2f: %d Taylor steps, max attitude difference %.2g rad, costate %.2g, "
        "cost %.2g\n",
        p0.norm(), steps, eg, ep, std::abs(a.cost - b.cost) / b.cost);
    EXPECT_LE(eg, 1e-10);
    EXPECT_LE(ep, 1e-10);
    EXPECT_NEAR(a.cost, b.cost, 1e-10 * b.cost);
    EXPECT_NEAR(dti::casimir(a.p.back()), dti::casimir(p0), 1e-13 * dti::casimir(p0));
  }
}

TEST(DriftTwoInputPlanner, SameExtremalWhateverTheOutputSamplingForEveryDriftScene) {
  // N sets only where the extremal is sampled. Every drift scene of scenes/ is
  // planned with its default starts at N = 60 … 4000: the same p(0) and cost to 1e-12 (the
  // solve never sees N; only the dense output does), g(T) = g1, and the samples of one N are
  // those of another at common times.
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(AP_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".yaml") continue;
    const Scene scene = loadScene(entry.path().string());
    if (scene.system != SystemKind::DriftTwoInput) continue;
    ++scenes;
    DriftTwoInputRequest rq = driftTwoInputRequest(scene);
    std::optional<DriftTwoInputPlan> first;
    for (int N : {60, 100, 400, 1000, 4000}) {
      rq.steps = N;
      const DriftTwoInputPlan plan = planDriftTwoInput(rq);
      std::printf("%s N = %d: cost %.12g, p(0) = (%.9f, %.9f, %.9f); %s\n",
                  entry.path().filename().c_str(), N, plan.cost, plan.initial_costate.x(),
                  plan.initial_costate.y(), plan.initial_costate.z(), plan.extremal.c_str());
      ASSERT_TRUE(plan.converged()) << entry.path() << " N = " << N << ": " << plan.message;
      EXPECT_LE(plan.terminal_error, 1e-10);
      ASSERT_EQ(plan.trajectory.g.size(), static_cast<size_t>(N + 1));
      if (!first) {
        first = plan;
        continue;
      }
      EXPECT_NEAR(plan.cost, first->cost, 1e-12 * first->cost) << entry.path() << " N = " << N;
      EXPECT_LE((plan.initial_costate - first->initial_costate).norm(),
                1e-12 * first->initial_costate.norm())
          << entry.path() << " N = " << N;
      EXPECT_EQ(plan.other_costs.size(), first->other_costs.size());
      // t = T/2 is a sample of every N used here
      const int k = N / 2, k0 = static_cast<int>(first->trajectory.t.size() - 1) / 2;
      EXPECT_LE(so3::angleBetween(plan.trajectory.g[k], first->trajectory.g[k0]), 1e-13);
      EXPECT_LE((plan.trajectory.p[k] - first->trajectory.p[k0]).norm(),
                1e-13 * (1 + first->initial_costate.norm()));
    }
  }
  EXPECT_GE(scenes, 2);
}

TEST(DriftTwoInputPlanner, WorkedExampleReturnsTheCheapestExtremalFoundAndReportsTheOthers) {
  // The worked example (scenes/drift_two_input.yaml) has extremals of cost 4.02383 (from the
  // guess alone at N ≤ 100) and 158.3 (at N ≥ 400); started from the symmetric problem's
  // extremals too, the planner returns the cheaper one of cost 3.75294 and reports 4.02383
  // among the others.
  DriftTwoInputRequest rq = exampleRequest();
  rq.initial_costate.reset();
  const DriftTwoInputPlan plan = planDriftTwoInput(rq);
  std::printf("%s\n", plan.message.c_str());
  ASSERT_TRUE(plan.converged()) << plan.message;
  EXPECT_NEAR(plan.cost, 3.752939785, 1e-8);
  ASSERT_FALSE(plan.other_costs.empty()) << plan.extremal;
  EXPECT_NEAR(plan.other_costs.front(), 4.023833777, 1e-8) << plan.extremal;
  for (double c : plan.other_costs) EXPECT_GT(c, plan.cost);
  EXPECT_NE(plan.extremal.find("the others cost 4.02383"), std::string::npos) << plan.extremal;
  EXPECT_NE(plan.message.find(plan.extremal), std::string::npos);
  EXPECT_NE(plan.termination, Termination::TimedOut);
  // the cheaper extremal is a local minimum too: started next to it, the solve stays there
  rq.initial_costate = plan.initial_costate + Vector3(0.01, -0.01, 0.01);
  const DriftTwoInputPlan again = planDriftTwoInput(rq);
  ASSERT_TRUE(again.converged()) << again.message;
  EXPECT_NEAR(again.cost, plan.cost, 1e-10 * plan.cost);
}

TEST(DriftTwoInputPlanner, TimeBudgetStopsTheSearchAndSaysSo) {
  DriftTwoInputRequest rq = exampleRequest();
  rq.initial_costate.reset();
  rq.time_budget_s = 1e-9;  // expires before the first start is solved
  const DriftTwoInputPlan plan = planDriftTwoInput(rq);
  std::printf("%s\n", plan.message.c_str());
  EXPECT_EQ(plan.termination, Termination::TimedOut);
  EXPECT_FALSE(plan.converged());
  EXPECT_NE(plan.message.find("time budget"), std::string::npos) << plan.message;
  EXPECT_EQ(plan.trajectory.g.size(), static_cast<size_t>(rq.steps + 1));  // best attempt
  // a generous budget changes nothing
  rq.time_budget_s = 60.0;
  const DriftTwoInputPlan full = planDriftTwoInput(rq);
  ASSERT_TRUE(full.converged()) << full.message;
  EXPECT_NE(full.termination, Termination::TimedOut);
  rq.time_budget_s = -1.0;
  EXPECT_THROW(planDriftTwoInput(rq), InvalidInput);
}
