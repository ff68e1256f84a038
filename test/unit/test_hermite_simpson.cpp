// The Hermite–Simpson peer of frontier_study (test/support/hermite_simpson.hpp). Its
// exact derivatives against central differences (the objective's gradient, the constraint
// Jacobian, the Hessian of the Lagrangian against differences of the exact gradient of the
// Lagrangian), its sparsity patterns, and its constraints on the continuous optimum (they must
// vanish at the collocation method's order as h → 0), and a smoke run of frontier_study at tiny
// sizes (every scheme of the name table, and the IPOPT peer when CMake found IPOPT). Runs in about
// a second.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/analysis/continuous_reference.hpp"
#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "support/hermite_simpson.hpp"
#include "support/robustness_cases.hpp"

namespace attitude_planner {
namespace {

using peers::HermiteSimpsonTranscription;

/// The seed's inertia and the slew-up example's boundary data, shortened (nonzero Ω at both
/// ends, so every block of the transcription is exercised).
PlanningProblem slewProblem(int steps) {
  PlanningProblem p;
  p.inertia = robustness::seedInertia();
  p.allow_nonphysical_inertia = true;
  p.duration = 4.0;
  p.steps = steps;
  p.initial_attitude = so3::exp(Vector3(0.1, -0.2, 0.3));
  p.initial_velocity = Vector3(0.05, -0.1, 0.02);
  p.final_attitude = so3::exp(Vector3(0.6, 0.4, -0.5));
  p.final_velocity = Vector3(0.3, 0.2, 0.3);
  return p;
}

/// A point off the solution: the geodesic start, perturbed (quaternions off the unit sphere).
std::vector<double> randomPoint(const HermiteSimpsonTranscription& hs, std::mt19937& rng) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> x(hs.variables());
  hs.startingPoint(x.data());
  for (double& v : x) v += 0.3 * uniform(rng);
  return x;
}

Eigen::MatrixXd denseJacobian(const HermiteSimpsonTranscription& hs, const std::vector<double>& x) {
  std::vector<double> v(hs.jacobianRows().size());
  hs.jacobianValues(x.data(), v.data());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(hs.constraints(), hs.variables());
  for (size_t i = 0; i < v.size(); ++i) J(hs.jacobianRows()[i], hs.jacobianColumns()[i]) += v[i];
  return J;
}

Eigen::VectorXd lagrangianGradient(const HermiteSimpsonTranscription& hs,
                                   const std::vector<double>& x, double sigma,
                                   const Eigen::VectorXd& lambda) {
  Eigen::VectorXd g(hs.variables());
  hs.objectiveGradient(x.data(), g.data());
  return sigma * g + denseJacobian(hs, x).transpose() * lambda;
}

TEST(HermiteSimpson, SizesAndPatternsAreConsistent) {
  const HermiteSimpsonTranscription hs(slewProblem(5));
  EXPECT_EQ(hs.points(), 11);
  EXPECT_EQ(hs.variables(), 110);
  EXPECT_EQ(hs.constraints(), 14 * 5 + 3);
  // No repeated entries; Hessian entries in the lower triangle.
  Eigen::MatrixXi seen = Eigen::MatrixXi::Zero(hs.constraints(), hs.variables());
  for (size_t i = 0; i < hs.jacobianRows().size(); ++i) {
    ASSERT_LT(hs.jacobianRows()[i], hs.constraints());
    ASSERT_LT(hs.jacobianColumns()[i], hs.variables());
    EXPECT_EQ(seen(hs.jacobianRows()[i], hs.jacobianColumns()[i])++, 0) << "repeated entry " << i;
  }
  Eigen::MatrixXi hseen = Eigen::MatrixXi::Zero(hs.variables(), hs.variables());
  for (size_t i = 0; i < hs.hessianRows().size(); ++i) {
    EXPECT_GE(hs.hessianRows()[i], hs.hessianColumns()[i]);
    EXPECT_EQ(hseen(hs.hessianRows()[i], hs.hessianColumns()[i])++, 0) << "repeated entry " << i;
  }
}

TEST(HermiteSimpson, ExactDerivativesAgreeWithFiniteDifferences) {
  for (int steps : {1, 3, 5}) {
    SCOPED_TRACE("N = " + std::to_string(steps));
    const HermiteSimpsonTranscription hs(slewProblem(steps));
    std::mt19937 rng(20261123 + steps);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const std::vector<double> x = randomPoint(hs, rng);
    const int n = hs.variables(), m = hs.constraints();
    Eigen::VectorXd lambda(m);
    for (int i = 0; i < m; ++i) lambda(i) = uniform(rng);
    const double sigma = 0.7;
    constexpr double kStep = 1e-6;

    // Gradient of the objective and the constraint Jacobian.
    Eigen::VectorXd gradient(n);
    hs.objectiveGradient(x.data(), gradient.data());
    const Eigen::MatrixXd J = denseJacobian(hs, x);
    Eigen::MatrixXd J_fd(m, n);
    Eigen::VectorXd gradient_fd(n);
    std::vector<double> y = x;
    Eigen::VectorXd c_plus(m), c_minus(m);
    for (int j = 0; j < n; ++j) {
      y[j] = x[j] + kStep;
      const double f_plus = hs.objective(y.data());
      hs.constraintValues(y.data(), c_plus.data());
      y[j] = x[j] - kStep;
      const double f_minus = hs.objective(y.data());
      hs.constraintValues(y.data(), c_minus.data());
      y[j] = x[j];
      gradient_fd(j) = (f_plus - f_minus) / (2 * kStep);
      J_fd.col(j) = (c_plus - c_minus) / (2 * kStep);
    }
    EXPECT_LT((gradient - gradient_fd).cwiseAbs().maxCoeff(),
              1e-8 * gradient.cwiseAbs().maxCoeff());
    // Entrywise: every FD entry (inside the pattern or not) matches the exact Jacobian.
    EXPECT_LT((J - J_fd).cwiseAbs().maxCoeff(), 1e-7 * J.cwiseAbs().maxCoeff());

    // Hessian of σf + λᵀc against central differences of the exact ∇L.
    std::vector<double> hv(hs.hessianRows().size());
    hs.hessianValues(x.data(), sigma, lambda.data(), hv.data());
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
    for (size_t i = 0; i < hv.size(); ++i) {
      H(hs.hessianRows()[i], hs.hessianColumns()[i]) = hv[i];
      H(hs.hessianColumns()[i], hs.hessianRows()[i]) = hv[i];
    }
    Eigen::MatrixXd H_fd(n, n);
    for (int j = 0; j < n; ++j) {
      y[j] = x[j] + 1e-5;
      const Eigen::VectorXd plus = lagrangianGradient(hs, y, sigma, lambda);
      y[j] = x[j] - 1e-5;
      const Eigen::VectorXd minus = lagrangianGradient(hs, y, sigma, lambda);
      y[j] = x[j];
      H_fd.col(j) = (plus - minus) / 2e-5;
    }
    const double scale = H.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 0.0);
    EXPECT_LT((H - H_fd).cwiseAbs().maxCoeff(), 1e-7 * scale);
    EXPECT_LT((H_fd - H_fd.transpose()).cwiseAbs().maxCoeff(), 1e-7 * scale);
  }
}

TEST(HermiteSimpson, StartIsOnTheBoundsAndTheGeodesic) {
  const PlanningProblem p = slewProblem(4);
  const HermiteSimpsonTranscription hs(p);
  std::vector<double> x(hs.variables()), lower(hs.variables()), upper(hs.variables());
  hs.startingPoint(x.data());
  hs.bounds(lower.data(), upper.data());
  for (int i = 0; i < hs.variables(); ++i) {
    EXPECT_LE(lower[i], x[i] + 1e-15) << i;
    EXPECT_GE(upper[i], x[i] - 1e-15) << i;
  }
  // The start ends on the target attitude: the terminal rows vanish there.
  std::vector<double> c(hs.constraints());
  hs.constraintValues(x.data(), c.data());
  for (int r = 0; r < 3; ++r) EXPECT_NEAR(c[14 * 4 + r], 0.0, 1e-14);
}

/// The continuous optimum satisfies the collocation rows to O(h⁵) and the interpolation rows to
/// O(h⁴) (Simpson's rule, the cubic Hermite interpolant at the midpoint).
TEST(HermiteSimpson, ContinuousOptimumSatisfiesTheRowsAtTheMethodsOrder) {
  const PlanningProblem p = slewProblem(8);
  const ContinuousReference ref = solveContinuousReference(p);
  ASSERT_TRUE(ref.converged) << ref.message;
  double previous_interpolation = 0.0, previous_collocation = 0.0;
  for (int steps : {8, 16, 32}) {
    PlanningProblem at = p;
    at.steps = steps;
    const HermiteSimpsonTranscription hs(at);
    std::vector<double> t(hs.points());
    for (int q = 0; q < hs.points(); ++q) t[q] = hs.time(q);
    const std::vector<ContinuousState> states = ref.sample(t);
    std::vector<double> x(hs.variables());
    Eigen::Vector4d previous = so3::quaternionCoefficients<double>(p.initial_attitude);
    for (int q = 0; q < hs.points(); ++q) {
      Eigen::Vector4d quaternion = so3::quaternionCoefficients<double>(states[q].attitude);
      if (quaternion.dot(previous) < 0) quaternion = -quaternion;
      previous = quaternion;
      Eigen::Map<Eigen::Vector4d>(x.data() + hs.qIndex(q)) = quaternion;
      Eigen::Map<Vector3>(x.data() + hs.omegaIndex(q)) = states[q].angular_velocity;
      Eigen::Map<Vector3>(x.data() + hs.torqueIndex(q)) = states[q].torque();
    }
    std::vector<double> c(hs.constraints());
    hs.constraintValues(x.data(), c.data());
    double interpolation = 0.0, collocation = 0.0, terminal = 0.0;
    for (int k = 0; k < steps; ++k)
      for (int r = 0; r < 7; ++r) {
        interpolation = std::max(interpolation, std::abs(c[14 * k + r]));
        collocation = std::max(collocation, std::abs(c[14 * k + 7 + r]));
      }
    for (int r = 0; r < 3; ++r) terminal = std::max(terminal, std::abs(c[14 * steps + r]));
    EXPECT_LT(terminal, 1e-12);
    // The effort by Simpson's rule converges to the continuous one (order 4).
    EXPECT_NEAR(hs.objective(x.data()), ref.cost, 1e-3 * ref.cost);
    if (previous_interpolation > 0) {
      EXPECT_GT(previous_interpolation / interpolation, 12.0);  // 2⁴ = 16
      EXPECT_GT(previous_collocation / collocation, 24.0);      // 2⁵ = 32
    }
    previous_interpolation = interpolation;
    previous_collocation = collocation;
  }
}

/// frontier_study at tiny sizes: every scheme of kSchemeNames and (with IPOPT) ipopt_hs appear,
/// converge, and their torque error falls with N.
TEST(FrontierStudy, SmallRunMeasuresEverySchemeAndThePeer) {
  const std::string tool = AP_STUDY_DIR "frontier_study";
  ASSERT_EQ(access(tool.c_str(), X_OK), 0) << "frontier_study not built at " << tool;
  const std::string out = AP_BINARY_DIR "/frontier_smoke.json";
  const std::string command = "cd '" AP_BINARY_DIR "' && '" + tool + "' '" + out +
                              "' '" AP_SOURCE_DIR
                              "/scenes/slew_up.yaml' --repeats 1 "
                              "--max-steps 16 --max-hs-steps 8 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string log;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) log.append(buffer, n);
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << log;
  std::ifstream in(out);
  std::stringstream json;
  json << in.rdbuf();
  const std::string text = json.str();
  std::vector<std::string> methods;
  for (const auto& entry : kSchemeNames) methods.push_back(entry.name);
#ifdef AP_FRONTIER_HAS_IPOPT
  methods.push_back("ipopt_hs");
#endif
  for (const std::string& m : methods) {
    EXPECT_NE(text.find("\"method\": \"" + m + "\""), std::string::npos) << m << " missing:\n"
                                                                         << text;
  }
  EXPECT_EQ(text.find("\"converged\": false"), std::string::npos) << text;
#ifdef AP_FRONTIER_HAS_IPOPT
  // The peer at N = 4, 6, 8 (stderr lines "ipopt_hs N=… torque E …"): its torque error falls.
  std::vector<double> errors;
  for (std::size_t at = log.find("ipopt_hs N="); at != std::string::npos;
       at = log.find("ipopt_hs N=", at + 1)) {
    const std::size_t t = log.find("torque ", at);
    ASSERT_NE(t, std::string::npos) << log;
    errors.push_back(std::stod(log.substr(t + 7)));
  }
  ASSERT_EQ(errors.size(), 3u) << log;
  EXPECT_LT(errors[1], errors[0]) << log;
  EXPECT_LT(errors[2], errors[1]) << log;
#endif
}

}  // namespace
}  // namespace attitude_planner
