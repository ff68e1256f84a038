// ψ's entries of the free-time system (the model in free_time_twist.hpp).
#include "planning/interior_point/free_time_twist.hpp"

namespace attitude_planner {

TwistEntries twistEntries(const ReducedProblem& np, int first_node, int width, double h0,
                          const Eigen::Matrix<double, 10, 10>& H,
                          const Eigen::Matrix<double, 10, 1>& rhs,
                          const Eigen::Matrix<double, 10, 1>& lagrangian) {
  TwistEntries t;
  const Eigen::Matrix<double, 9, 1> e = localTwistMotion(np, first_node, width);
  if (e.isZero(0.0)) return t;
  t.any = true;
  t.nodes = H.topLeftCorner<9, 9>() * e;
  t.twist = e.dot(t.nodes);
  t.time = e.dot(H.block<9, 1>(0, 9));
  t.rhs = rhs.head<9>().dot(e);
  t.lagrangian = lagrangian.head<9>().dot(e);
  // The path's curvature at R_{N−1} (paper, variational: h and ψ both move it).
  const int slot = np.steps() - 1 - first_node;
  if (slot >= 0 && slot < width) {
    const Vector3 e_last = e.segment<3>(3 * slot);
    const Vector3 path = np.nodePath(np.steps() - 1).first * h0;
    t.time += lagrangian.segment<3>(3 * slot).dot(0.5 * e_last.cross(path));
  }
  return t;
}

}  // namespace attitude_planner
