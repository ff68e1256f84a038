// Reaction-wheel peaks against limits (wheel_peaks.hpp).
#include "attitude_planner/analysis/wheel_peaks.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace attitude_planner {

void WheelPeaks::observeMomentum(const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                                 const Eigen::VectorXd& momentum) {
  peak_momentum = peak_momentum.cwiseMax(momentum.cwiseAbs());
  peak_momentum_norm = std::max(peak_momentum_norm, (axes * momentum).norm());
}

void WheelPeaks::observeTorque(const Eigen::VectorXd& torque) {
  peak_torque = peak_torque.cwiseMax(torque.cwiseAbs());
}

double WheelPeaks::worstExcess(const ReactionWheels& wheels, std::string* which) const {
  double worst = -std::numeric_limits<double>::infinity();
  const auto consider = [&](double excess, const std::string& name) {
    if (excess > worst) {
      worst = excess;
      if (which) *which = name;
    }
  };
  for (int i = 0; i < wheels.count(); ++i) {
    const std::string wheel = wheelName(i);
    consider(peak_momentum(i) - wheels.momentumLimit(i), wheel + " momentum");
    consider(peak_torque(i) - wheels.torqueLimit(i), wheel + " torque");
  }
  if (std::isfinite(wheels.max_momentum_norm)) {
    consider(peak_momentum_norm - wheels.max_momentum_norm, "max_momentum_norm");
  }
  return worst;
}

WheelPeaks planWheelPeaks(const ReactionWheels& wheels, const WheelStates& states,
                          bool end_torques) {
  const WheelArray array = wheelArray(wheels);
  WheelPeaks peaks(wheels.count());
  const int N = static_cast<int>(states.momentum.size()) - 1;
  for (int k = 0; k <= N; ++k) {
    peaks.observeMomentum(array.axes, states.momentum[k]);
    if (end_torques || (k > 0 && k < N)) peaks.observeTorque(states.torque[k]);
  }
  return peaks;
}

}  // namespace attitude_planner
