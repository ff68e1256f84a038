#include "attitude_planner/so3.hpp"

#include <Eigen/SVD>

namespace attitude_planner {
namespace so3 {

Eigen::Quaterniond toQuaternion(const Matrix3& R) {
  const Eigen::Vector4d q = quaternionCoefficients<double>(R);
  return Eigen::Quaterniond(q(0), q(1), q(2), q(3));
}

Matrix3 fromQuaternion(const Eigen::Quaterniond& q) {
  return matrixFromQuaternion<double>(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()));
}

Matrix3 fromAxisAngle(const Vector3& axis, double angle) {
  return exp(Vector3(axis.normalized() * angle));
}

Matrix3 projectToSO3(const Matrix3& M) {
  Eigen::JacobiSVD<Matrix3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 D = Matrix3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

double orthogonalityError(const Matrix3& R) {
  return (R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff() +
         std::abs(R.determinant() - 1.0);
}

double angleBetween(const Matrix3& A, const Matrix3& B) {
  return log(Matrix3(A.transpose() * B)).norm();
}

}  // namespace so3
}  // namespace attitude_planner
