#include "attitude_planner/analysis/seed_conditions.hpp"

#include <algorithm>

namespace attitude_planner {

namespace {

/// Sum of vector terms and the largest term magnitude, for a relative residual.
struct TermSum {
  Vector3 sum = Vector3::Zero();
  double largest = 0.0;
  void add(const Vector3& v) {
    sum += v;
    largest = std::max(largest, v.norm());
  }
  double relative() const { return largest > 0 ? sum.norm() / largest : 0.0; }
};

}  // namespace

std::vector<double> seedConditionRelativeResiduals(const Maneuver& m, const Matrix3& J,
                                                   SeedConditionForm form) {
  const int N = m.steps();
  const double h = m.time_step;
  std::vector<Matrix3> g(N);  // g_k = R_kᵀ R_{k+1} = exp(hΩ_k)
  for (int k = 0; k < N; ++k) g[k] = m.attitude[k].transpose() * m.attitude[k + 1];
  const auto& tau = m.torque;
  const auto& W = m.angular_velocity;
  std::vector<double> residuals;
  for (int k = 2; k <= N - 2; ++k) {
    TermSum t;
    if (form == SeedConditionForm::Printed) {
      const Matrix3 Ad_star = g[k].transpose();  // Ad*_{g_k} as printed
      t.add(-J * tau[k] / (h * h));
      t.add(Ad_star * J * tau[k + 1] / (h * h));
      t.add(J * g[k - 1].transpose() * tau[k - 1] / (h * h));
      t.add(-Ad_star * J * g[k].transpose() * tau[k] / (h * h));
      t.add(-Ad_star * (J * W[k]).cross(g[k].transpose() * tau[k]) / h);
      t.add((J * W[k - 1]).cross(g[k - 1].transpose() * tau[k - 1]) / (h * h));  // inner 1/h
    } else {
      const bool dexp = form == SeedConditionForm::Corrected;
      const Matrix3 Jk =
          dexp ? Matrix3(so3::rightJacobianInverse(Vector3(h * W[k])).transpose() * J) : J;
      const Matrix3 Jkm =
          dexp ? Matrix3(so3::rightJacobianInverse(Vector3(h * W[k - 1])).transpose() * J) : J;
      t.add(-Jkm * tau[k] / (h * h));
      t.add(g[k] * Jk * tau[k + 1] / (h * h));
      t.add(Jkm * g[k - 1].transpose() * tau[k - 1] / (h * h));
      t.add(-g[k] * Jk * g[k].transpose() * tau[k] / (h * h));
      t.add(-g[k] * (J * W[k]).cross(g[k].transpose() * tau[k]) / h);
      t.add((J * W[k - 1]).cross(g[k - 1].transpose() * tau[k - 1]) / h);
    }
    residuals.push_back(t.relative());
  }
  return residuals;
}

std::pair<double, double> seedBoundaryConditionRelativeResiduals(const Maneuver& m,
                                                                 const Matrix3& J) {
  // 0 = −(1/h²)(𝕁(τ_k) + Ad*_{g_k} 𝕁(Ad_{g_k} τ_k)) − (1/h) Ad*_{g_k}[𝕁(Ω_k), Ad_{g_k} τ_k]
  const double h = m.time_step;
  const auto at = [&](int k) {
    const Matrix3 g = m.attitude[k].transpose() * m.attitude[k + 1];
    TermSum t;
    t.add(-J * m.torque[k] / (h * h));
    t.add(-g.transpose() * J * g * m.torque[k] / (h * h));
    t.add(-g.transpose() * (J * m.angular_velocity[k]).cross(g * m.torque[k]) / h);
    return t.relative();
  };
  return {at(1), at(m.steps() - 1)};
}

}  // namespace attitude_planner
