#include "attitude_planner/lie/so3.hpp"

#include <Eigen/SVD>

namespace attitude_planner {
namespace so3 {

double rightJacobianInverseCoefficientDerivative(double theta2) {
  if (theta2 < 0.25) {
    // (n − 1)|B_2n|/(2n)!, n = 2..8; the first omitted term is below 1e-15 relative at θ = 0.5.
    constexpr double a[] = {1.0 / 720.0,
                            1.0 / 15120.0,
                            1.0 / 403200.0,
                            1.0 / 11975040.0,
                            3455.0 / 1307674368000.0,
                            7.0 / 87178291200.0,
                            25319.0 / 10670622842880000.0};
    double sum = 0.0;
    for (int n = 6; n >= 0; --n) sum = sum * theta2 + a[n];
    return sum;
  }
  // c = (1 − x cot x)/θ², x = θ/2:  dc/dθ² = (−c − (cot x − x/sin²x)/(8x))/θ².
  const double x = std::sqrt(theta2) / 2;
  const double sin_x = std::sin(x);
  const double d_x_cot_x = std::cos(x) / sin_x - x / (sin_x * sin_x);
  return (-rightJacobianInverseCoefficient<double>(theta2) - d_x_cot_x / (8 * x)) / theta2;
}

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
