// Body + reaction wheels on the plan's discrete scheme (discrete_wheel_replay.hpp).
#include "attitude_planner/dynamics/discrete_wheel_replay.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <sstream>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

using Axes = Eigen::Matrix<double, 3, Eigen::Dynamic>;

/// What the replay carries from node to node.
struct NodeState {
  Matrix3 attitude;
  Vector3 momentum;        ///< Π_k, the body's node momentum
  Vector3 total;           ///< π_k, the total momentum in the world
  Eigen::VectorXd wheels;  ///< h_w,k
};

/// The array's data the replay needs, formed here (not the planner's WheelArray).
struct Array {
  Axes axes;
  Eigen::MatrixXd pseudo_inverse;  ///< A⁺ = Aᵀ(AAᵀ)⁻¹
  Eigen::MatrixXd null_projector;  ///< I − A⁺A
};

Array arrayOf(const Axes& axes) {
  Array a;
  a.axes = axes;
  a.pseudo_inverse = axes.transpose() * (axes * axes.transpose()).inverse();
  a.null_projector = Eigen::MatrixXd::Identity(axes.cols(), axes.cols()) - a.pseudo_inverse * axes;
  return a;
}

/// τ = −A u − ω × q, ω = J⁻¹Π: the torque the array exerts on the body.
Vector3 arrayTorqueOnBody(const Array& array, const Matrix3& J_inverse, const Eigen::VectorXd& u,
                          const Vector3& body_momentum, const Vector3& array_momentum) {
  return -(array.axes * u) - (J_inverse * body_momentum).cross(array_momentum);
}

/// The arrival at node k+1: τ with τ = −A u − J⁻¹Π × (v − Π), Π = arrived + (h/2)(τ + d), by
/// Newton's method on g(τ) = τ + A u + J⁻¹Π × (v − Π): dg/dτ = I − (h/2)((v − Π)^ J⁻¹ + (J⁻¹Π)^).
/// Returns Π_{k+1}.
Vector3 arriveAtNode(const Array& array, const Matrix3& J_inverse, const Eigen::VectorXd& u,
                     const Vector3& arrived, const Vector3& body_total,
                     const Vector3& body_disturbance, double h, int k) {
  constexpr int kMaxIterations = 30;
  const Vector3 pushed = -(array.axes * u);
  const auto momentumOf = [&](const Vector3& tau) {
    return Vector3(arrived + 0.5 * h * (tau + body_disturbance));
  };
  Vector3 tau = arrayTorqueOnBody(array, J_inverse, u, arrived, body_total - arrived);
  double scale = pushed.norm() + (J_inverse * arrived).norm() * body_total.norm();
  int polish = 2;  // Newton steps after the step fell to round-off
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const Vector3 Pi = momentumOf(tau);
    const Vector3 q = body_total - Pi;
    const Vector3 omega = J_inverse * Pi;
    const Vector3 g = tau - pushed + omega.cross(q);
    const Matrix3 dg = Matrix3::Identity() - 0.5 * h * (so3::hat(q) * J_inverse + so3::hat(omega));
    const Vector3 step = dg.lu().solve(-g);
    tau += step;
    scale = std::max(scale, tau.norm());
    if (step.norm() <= 1e-15 * scale && --polish < 0) return momentumOf(tau);
  }
  std::ostringstream msg;
  msg << "the node solve of the wheel replay at k = " << k + 1 << " did not converge in "
      << kMaxIterations << " Newton steps (h = " << h << " s)";
  throw StepTooLarge(msg.str());
}

void checkInput(SchemeKind scheme, const Axes& axes, const Eigen::VectorXd& initial_momentum,
                const std::vector<Eigen::VectorXd>& torque) {
  if (!schemeIsDiscretization(scheme)) {
    throw InvalidInput("scheme",
                       "the discrete wheel replay needs a discretization (paper, "
                       "variational, second_order), got " +
                           schemeName(scheme));
  }
  if (torque.size() < 2) {
    throw InvalidInput("torque",
                       "need at least 2 rows (k = 0..N), got " + std::to_string(torque.size()));
  }
  if (initial_momentum.size() != axes.cols()) {
    throw InvalidInput("initial_momentum", "expected " + std::to_string(axes.cols()) +
                                               " values (one per wheel), got " +
                                               std::to_string(initial_momentum.size()));
  }
  for (std::size_t k = 0; k < torque.size(); ++k) {
    if (torque[k].size() != axes.cols()) {
      throw InvalidInput("torque[" + std::to_string(k) + "]",
                         "expected " + std::to_string(axes.cols()) + " wheel torques, got " +
                             std::to_string(torque[k].size()));
    }
  }
}

}  // namespace

DiscreteWheelReplay replayWithWheelsOnTheScheme(SchemeKind scheme_kind, const Matrix3& inertia,
                                                const Axes& axes, const Matrix3& initial_attitude,
                                                const Vector3& initial_velocity,
                                                const Eigen::VectorXd& initial_momentum, double h,
                                                const std::vector<Eigen::VectorXd>& torque,
                                                const Vector3& world_disturbance) {
  checkInput(scheme_kind, axes, initial_momentum, torque);
  const DiscreteScheme scheme(scheme_kind, inertia, h);
  const Array array = arrayOf(axes);
  const Matrix3 J_inverse = inertia.inverse();
  const int N = static_cast<int>(torque.size()) - 1;
  const bool end_torques = scheme.hasEndTorques();
  NodeState s{initial_attitude, inertia * initial_velocity,
              initial_attitude * (inertia * initial_velocity + axes * initial_momentum),
              initial_momentum};
  DiscreteWheelReplay out;
  const auto record = [&](const Vector3& tau) {
    out.attitude.push_back(s.attitude);
    out.node_velocity.push_back(J_inverse * s.momentum);
    out.body_torque.push_back(tau);
    out.momentum.push_back(s.wheels);
  };
  Matrix3 F = so3::exp(Vector3(h * initial_velocity));
  for (int k = 0; k < N; ++k) {
    const Vector3 q = s.attitude.transpose() * s.total - s.momentum;
    Vector3 tau = arrayTorqueOnBody(array, J_inverse, torque[k], s.momentum, q);
    Vector3 leaving;               // μ(F_k)
    if (k == 0 && !end_torques) {  // the boundary velocity fixes the first step
      tau.setZero();
      F = scheme.stepFromVelocity(initial_velocity);
      leaving = scheme.momentum<double>(F);
    } else {
      leaving = s.momentum + 0.5 * h * (tau + s.attitude.transpose() * world_disturbance);
      StepSolveReport report;
      F = scheme.solveStep(leaving, F, &report);
      if (!report.converged) {
        throw StepTooLarge("the step solve of the wheel replay at k = " + std::to_string(k) +
                           " did not converge (h = " + std::to_string(h) + " s)");
      }
      out.max_step_residual = std::max(out.max_step_residual, report.residual);
    }
    record(tau);
    NodeState next;
    next.attitude = s.attitude * F;
    next.total = s.total + h * world_disturbance;
    const Vector3 body_total = next.attitude.transpose() * next.total;
    const Vector3 arrived = F.transpose() * leaving;
    if (k + 1 == N && !end_torques) {  // the boundary velocity fixes the last step
      next.momentum = inertia * scheme.velocity(F);
    } else {
      next.momentum = arriveAtNode(array, J_inverse, torque[k + 1], arrived, body_total,
                                   next.attitude.transpose() * world_disturbance, h, k);
    }
    next.wheels = array.pseudo_inverse * (body_total - next.momentum) +
                  array.null_projector * (s.wheels + 0.5 * h * (torque[k] + torque[k + 1]));
    s = std::move(next);
  }
  const Vector3 q = s.attitude.transpose() * s.total - s.momentum;
  record(end_torques ? arrayTorqueOnBody(array, J_inverse, torque[N], s.momentum, q)
                     : Vector3(Vector3::Zero()));
  return out;
}

}  // namespace attitude_planner
