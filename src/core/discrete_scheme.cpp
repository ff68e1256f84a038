#include "attitude_planner/discrete_scheme.hpp"

#include <Eigen/LU>
#include <cmath>
#include <sstream>

namespace attitude_planner {

std::string schemeName(SchemeKind kind) {
  return kind == SchemeKind::Paper ? "paper" : "variational";
}

SchemeKind parseSchemeName(const std::string& name) {
  if (name == "paper") return SchemeKind::Paper;
  if (name == "variational") return SchemeKind::Variational;
  throw InvalidInput("scheme: unknown value '" + name + "' (expected paper or variational)");
}

DiscreteScheme::DiscreteScheme(SchemeKind kind, const Matrix3& inertia, double time_step)
    : kind_(kind), J_(inertia), J_inverse_(inertia.inverse()), h_(time_step) {
  Jd_ = 0.5 * J_.trace() * Matrix3::Identity() - J_;
}

Vector3 DiscreteScheme::velocity(const Matrix3& F) const {
  if (kind_ == SchemeKind::Paper) return so3::log(F) / h_;
  return J_inverse_ * momentum<double>(F);
}

Matrix3 DiscreteScheme::stepFromVelocity(const Vector3& omega) const {
  if (kind_ == SchemeKind::Paper) {
    if (h_ * omega.norm() >= M_PI) {
      std::ostringstream msg;
      msg << "step too large, increase steps: h*|Omega| = " << h_ * omega.norm()
          << " rad >= pi (one step may not rotate by more than pi)";
      throw StepTooLarge(msg.str());
    }
    return so3::exp(Vector3(h_ * omega));
  }
  StepSolveReport report;
  const Vector3 p = J_ * omega;
  const Matrix3 F = solveStep(p, so3::exp(Vector3(h_ * omega)), &report);
  if (!report.converged) {
    std::ostringstream msg;
    msg << "step too large, increase steps: no step with velocity |Omega| = " << omega.norm()
        << " rad/s at h = " << h_ << " s (residual " << report.residual << ")";
    throw StepTooLarge(msg.str());
  }
  return F;
}

Matrix3 DiscreteScheme::solveStep(const Vector3& p, const Matrix3& guess,
                                  StepSolveReport* report) const {
  constexpr int kMaxIterations = 60;
  // Warm starts chain F from step to step: restore orthogonality so round-off in F cannot
  // accumulate over millions of steps (μ of a non-orthogonal F breaks momentum conservation).
  Matrix3 F = 0.5 * guess * (3.0 * Matrix3::Identity() - guess.transpose() * guess);
  Vector3 r = momentum<double>(F) - p;
  double r_norm = r.norm();
  auto tolerance = [&](const Matrix3& G) {
    // relative part, plus the absolute round-off floor of evaluating μ (≈ eps·‖J‖/h at any F)
    return 1e-14 * (p.norm() + J_.norm() * so3::log(G).norm() / h_) + 1e-15 * J_.norm() / h_;
  };
  report->converged = false;
  int polish_steps = 0;
  int it = 0;
  for (; it < kMaxIterations; ++it) {
    if (r_norm <= tolerance(F)) {
      report->converged = true;
      // Newton converges quadratically: up to two more steps take the residual from the
      // tolerance to round-off, so conserved quantities do not drift by tolerance × steps.
      if (r_norm == 0.0 || polish_steps >= 2) break;
      ++polish_steps;
    }
    const Matrix3 D = momentumJacobian<double>(F);
    Eigen::FullPivLU<Matrix3> lu(D);
    if (!lu.isInvertible()) break;
    const Vector3 delta = -lu.solve(r);
    if (!delta.allFinite()) break;
    // Backtracking on |μ(F) − p| keeps the iteration inside the region where a solution exists.
    double step = 1.0;
    bool improved = false;
    for (int back = 0; back < 30; ++back) {
      const Matrix3 trial = F * so3::exp(Vector3(step * delta));
      const Vector3 r_trial = momentum<double>(trial) - p;
      if (r_trial.allFinite() && r_trial.norm() < r_norm) {
        F = trial;
        r = r_trial;
        r_norm = r_trial.norm();
        improved = true;
        break;
      }
      if (report->converged) break;  // polishing: full steps only
      step *= 0.5;
    }
    if (!improved) {
      // Round-off floor reached: accept if within 100× the tolerance.
      if (r_norm <= 100.0 * tolerance(F)) report->converged = true;
      break;
    }
  }
  report->iterations = it;
  report->residual = (momentum<double>(F) - p).norm();
  if (!report->converged && report->residual <= tolerance(F)) report->converged = true;
  return F;
}

}  // namespace attitude_planner
