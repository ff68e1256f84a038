// Products with a skew matrix v^ (so3::hat) that skip its zero entries: the Newton Hessian's
// per-stencil algebra (discrete_scheme.cpp, reduced_problem.cpp) multiplies by v^ dozens of times.
//
// Each entry is the dense product's sum with its zero terms left out and the others added in the
// dense product's order (Eigen's 3×3 products sum k = 0, 1, 2 left to right; a − b is a + (−b)
// exactly): the same values, bit for bit, but for the sign of an entry that is zero anyway and
// for a non-finite factor meeting a zero (0·∞ is NaN in the dense product, dropped here).
// Replacing a dense product by one of these keeps the bits only where the operands are the
// dense product's own: Eigen evaluates s * (A * B) as (A s) B (ProductEvaluators.h), so the
// replacement of s * (v^ w^) is hatTimesHat(s v, w), not s * hatTimesHat(v, w).
#pragma once

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {
namespace so3 {

/// v^ x = v × x.
inline Vector3 hatTimes(const Vector3& v, const Vector3& x) {
  return Vector3(v.y() * x.z() - v.z() * x.y(), v.z() * x.x() - v.x() * x.z(),
                 v.x() * x.y() - v.y() * x.x());
}

/// v^ M.
inline Matrix3 hatTimes(const Vector3& v, const Matrix3& M) {
  Matrix3 P;
  for (int j = 0; j < 3; ++j) P.col(j) = hatTimes(v, Vector3(M.col(j)));
  return P;
}

/// M v^.
inline Matrix3 timesHat(const Matrix3& M, const Vector3& v) {
  Matrix3 P;
  for (int i = 0; i < 3; ++i) {
    P(i, 0) = M(i, 1) * v.z() - M(i, 2) * v.y();
    P(i, 1) = M(i, 2) * v.x() - M(i, 0) * v.z();
    P(i, 2) = M(i, 0) * v.y() - M(i, 1) * v.x();
  }
  return P;
}

/// x^ y^ (= y xᵀ − (x·y) I; each entry is one product off the diagonal, two on it).
inline Matrix3 hatTimesHat(const Vector3& x, const Vector3& y) {
  Matrix3 P;
  P << -(x.z() * y.z()) - x.y() * y.y(), x.y() * y.x(), x.z() * y.x(),  //
      x.x() * y.y(), -(x.z() * y.z()) - x.x() * y.x(), x.z() * y.y(),   //
      x.x() * y.z(), x.y() * y.z(), -(x.y() * y.y()) - x.x() * y.x();
  return P;
}

}  // namespace so3
}  // namespace attitude_planner
