#include "attitude_planner/dynamics/discrete_scheme.hpp"

#include <Eigen/LU>
#include <cmath>
#include <sstream>

#include "lie/skew_products.hpp"

namespace attitude_planner {

namespace {

/// so3::rightJacobianInverse(ω)'s values with its coefficient c(|ω|²) given (formed once where
/// a caller reads it twice). Eigen forms c (W W) as (W c) W, and W c = (c ω)^: the product of two
/// skew matrices skips their zeros (skew_products.hpp), the same entries.
Matrix3 rightJacobianInverseWith(const Vector3& omega, double c) {
  return Matrix3::Identity() + 0.5 * so3::hat<double>(omega) +
         so3::hatTimesHat(Vector3(c * omega), omega);
}

/// paperMomentumJacobian(F, ω)'s values (the formula momentumJacobianOfStep reads from the
/// step's terms), for solveStep's iterates: its Jr⁻¹(ω) by the skew products.
Matrix3 paperMomentumJacobianOfIterate(const Matrix3& J, double h, const Matrix3& F,
                                       const Vector3& omega) {
  const double c = so3::rightJacobianInverseCoefficient<double>(omega.squaredNorm());
  const Matrix3 JJr_inverse = J * rightJacobianInverseWith(omega, c);
  return F * (JJr_inverse - so3::hat<double>(Vector3(J * omega))) / h;
}

}  // namespace

DiscreteScheme::DiscreteScheme(SchemeKind kind, const Matrix3& inertia, double time_step)
    : kind_(kind), J_(inertia), J_inverse_(inertia.inverse()), h_(time_step) {
  if (!schemeIsDiscretization(kind)) {
    throw InvalidInput("scheme '" + schemeName(kind) +
                       "' has no discrete equations of motion (it extrapolates two second_order "
                       "plans); use planAtResolution to plan and replayPlan to replay it");
  }
  Jd_ = 0.5 * J_.trace() * Matrix3::Identity() - J_;
}

double schemeCost(SchemeKind kind, const std::vector<Vector3>& torque) {
  const int N = static_cast<int>(torque.size()) - 1;
  double c = 0.0;
  for (int k = 0; k <= N; ++k) c += schemeTorqueWeight(kind, k, N) * 0.5 * torque[k].squaredNorm();
  return c;
}

double DiscreteScheme::cost(const std::vector<Vector3>& torque) const {
  return schemeCost(kind_, torque);
}

Vector3 DiscreteScheme::momentumOfStep(const Vector3& omega) const {
  return momentumOfStep(omega, so3::expMinusIdentity(omega));
}

Vector3 DiscreteScheme::momentumOfStep(const Vector3& omega, const Matrix3& E) const {
  if (kind_ == SchemeKind::Paper) {
    const Vector3 Jw = J_ * omega;
    return (Jw + E * Jw) / h_;  // F J ω / h
  }
  const Matrix3 A = E * Jd_;  // F J_d − J_d Fᵀ = (F − I) J_d − J_d (F − I)ᵀ
  return Vector3(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1)) / h_;
}

Matrix3 DiscreteScheme::momentumJacobianOfStep(const Matrix3& F, const Vector3& omega) const {
  return kind_ == SchemeKind::Paper ? paperMomentumJacobian<double>(F, omega)
                                    : momentumJacobian<double>(F);
}

bool DiscreteScheme::onPrincipalBranch(const Vector3& omega) const {
  return momentumJacobianOfStep(so3::exp(omega), omega).determinant() > 0.0;
}

Matrix3 DiscreteScheme::momentumJacobianContraction(const Matrix3& F, const Vector3& omega,
                                                    const Vector3& tau) const {
  return momentumJacobianContraction(stepJacobianTerms(F, omega), tau);
}

DiscreteScheme::StepJacobianTerms DiscreteScheme::stepJacobianTerms(const Matrix3& F,
                                                                    const Vector3& omega) const {
  StepJacobianTerms step;
  step.F = F;
  step.omega = omega;
  if (kind_ != SchemeKind::Paper) return step;
  const double theta2 = omega.squaredNorm();
  step.c = so3::rightJacobianInverseCoefficient<double>(theta2);
  step.dc = so3::rightJacobianInverseCoefficientDerivative(theta2);
  step.W = so3::hat<double>(omega);
  step.Jr_inverse = rightJacobianInverseWith(omega, step.c);
  step.JJr_inverse = J_ * step.Jr_inverse;
  step.Jw = J_ * omega;
  return step;
}

Matrix3 DiscreteScheme::momentumJacobianOfStep(const StepJacobianTerms& step) const {
  if (kind_ != SchemeKind::Paper) return momentumJacobian<double>(step.F);
  // paperMomentumJacobian's formula over the step's terms
  return step.F * (step.JJr_inverse - so3::hat<double>(step.Jw)) / h_;
}

Matrix3 DiscreteScheme::momentumJacobianContraction(const StepJacobianTerms& step,
                                                    const Vector3& tau) const {
  const Matrix3& F = step.F;
  if (kind_ != SchemeKind::Paper) {  // the variational μ
    // The bilinear part of h μ(F e^ε e^η) is (A − Aᵀ)^∨, A = F ε^ η^ J_d, and
    // τ·(A − Aᵀ)^∨ = −tr(P ε^ η^) = εᵀ(tr(P) I − P)η with P = J_d τ^ F.
    const Matrix3 P = so3::timesHat(Jd_, tau) * F / h_;
    const Matrix3 K = P.trace() * Matrix3::Identity() - P;
    return K.transpose();
  }
  // h μ(F e^ε e^η) = F e^ε e^η J ω(ε, η), ω = log(F e^ε e^η) with ∂ω/∂η = Jr⁻¹(ω(ε)) and
  // ∂ω/∂ε = Jr⁻¹(ω) at 0. Its mixed second derivative, weighted by τ (a = Fᵀτ):
  //   aᵀ ε^ η^ Jω + aᵀ ε^ J Jr⁻¹ η + aᵀ η^ J Jr⁻¹ ε + (Ja)ᵀ dJr⁻¹(ω)[Jr⁻¹ε] η,
  // and with Jr⁻¹(ω) = I + ½ω^ + c(|ω|²) ω^², for q = Ja and u = Jr⁻¹ε:
  //   qᵀ dJr⁻¹[u] η = uᵀ(−½ q^ + 2c' ω (ω^² q)ᵀ − c q^ ω^ − c (q × ω)^) η.
  const Vector3& w = step.omega;
  const double c = step.c, dc = step.dc;
  const Matrix3& Jr_inverse = step.Jr_inverse;
  const Vector3 a = F.transpose() * tau;
  const Vector3 q = J_ * a;
  const Matrix3& M = step.JJr_inverse;
  // Mᵀ a^ = −(a^ M)ᵀ (a^ is antisymmetric): one product, not two, and the same sums. The products
  // with a skew factor skip its zeros (skew_products.hpp: the dense products' values).
  const Matrix3 AM = so3::hatTimes(a, M);
  // B = −½ q^ + 2c' ω (ω^ ω^ q)ᵀ − c q^ ω^ − c (q × ω)^, with s v^ formed as (s v)^ (the same
  // entries, up to the sign of the zeros on the diagonal).
  const Matrix3 B = so3::hat<double>(Vector3(-0.5 * q)) +
                    Vector3(2 * dc * w) * so3::hatTimes(w, so3::hatTimes(w, q)).transpose() -
                    so3::hatTimesHat(Vector3(c * q), w) - so3::hat<double>(Vector3(c * q.cross(w)));
  const Matrix3 K = so3::hatTimesHat(a, step.Jw) - AM - AM.transpose() + Jr_inverse.transpose() * B;
  return K.transpose() / h_;
}

Vector3 DiscreteScheme::velocity(const Matrix3& F) const {
  if (kind_ == SchemeKind::Paper) return so3::log(F) / h_;
  return J_inverse_ * momentum<double>(F);
}

Vector3 DiscreteScheme::velocityOfStep(const Vector3& omega) const {
  if (kind_ == SchemeKind::Paper) return omega / h_;
  return J_inverse_ * momentumOfStep(omega);
}

Vector3 DiscreteScheme::momentumOfVelocity(const Vector3& omega) const {
  if (kind_ == SchemeKind::Paper) return momentumOfStep(h_ * omega);
  return J_ * omega;
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
  const bool paper = kind_ == SchemeKind::Paper;
  // Warm starts chain F from step to step: restore orthogonality so round-off in F cannot
  // accumulate over millions of steps (μ of a non-orthogonal F breaks momentum conservation).
  Matrix3 F = 0.5 * guess * (3.0 * Matrix3::Identity() - guess.transpose() * guess);
  // log(F), formed once per iterate: the paper μ, its Jacobian and the tolerance all read it.
  Vector3 w = so3::log(F);
  Vector3 r = momentumWithLog<double>(F, w) - p;
  double r_norm = r.norm();
  // |p| and ‖J‖ formed once, not at every test (the same values)
  const double p_norm = p.norm(), J_norm = J_.norm();
  auto tolerance = [&](const Vector3& log_of_F) {
    // relative part, plus the absolute round-off floor of evaluating μ (≈ eps·‖J‖/h at any F)
    return 1e-14 * (p_norm + J_norm * log_of_F.norm() / h_) + 1e-15 * J_norm / h_;
  };
  report->converged = false;
  int polish_steps = 0;
  int it = 0;
  for (; it < kMaxIterations; ++it) {
    if (r_norm <= tolerance(w)) {
      report->converged = true;
      // Newton converges quadratically: up to two more steps take the residual from the
      // tolerance to round-off, so conserved quantities do not drift by tolerance × steps.
      if (r_norm == 0.0 || polish_steps >= 2) break;
      ++polish_steps;
    }
    const Matrix3 D =
        paper ? paperMomentumJacobianOfIterate(J_, h_, F, w) : momentumJacobian<double>(F);
    // 3×3 cofactor inverse (a Newton step corrects its own round-off); singular relative to
    // D's scale means no step can be found from here.
    const double scale = D.cwiseAbs().maxCoeff();
    if (!(std::abs(D.determinant()) > 1e-13 * scale * scale * scale)) break;
    const Vector3 delta = -(D.inverse() * r);
    if (!delta.allFinite()) break;
    // Backtracking on |μ(F) − p| keeps the iteration inside the region where a solution exists.
    double step = 1.0;
    bool improved = false;
    for (int back = 0; back < 30; ++back) {
      const Matrix3 trial = F * so3::exp(Vector3(step * delta));
      const Vector3 w_trial = paper ? so3::log(trial) : Vector3::Zero();
      const Vector3 r_trial = momentumWithLog<double>(trial, w_trial) - p;
      if (r_trial.allFinite() && r_trial.norm() < r_norm) {
        F = trial;
        w = paper ? w_trial : so3::log(F);
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
      if (r_norm <= 100.0 * tolerance(w)) report->converged = true;
      break;
    }
  }
  report->iterations = it;
  // r is μ(F) − p of the F and w kept (the variational μ does not read w), formed as the same
  // expression: its norm is the residual, not evaluated again.
  report->residual = r_norm;
  if (!report->converged && report->residual <= tolerance(w)) report->converged = true;
  // |p| beyond ~1e154 overflows the norms: the tolerance becomes +inf and every test above
  // passes (found by fuzz_request: Ω_0 = −5e153 rad/s was "solved"). No such step exists.
  if (!std::isfinite(report->residual) || !F.allFinite()) report->converged = false;
  return F;
}

}  // namespace attitude_planner
