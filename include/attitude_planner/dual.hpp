// Forward-mode dual numbers with a fixed number of directions, usable as an Eigen scalar.
//
// The solvers evaluate the same templated formulas (so3.hpp, schemes) with Dual<N> to get exact
// directional derivatives of analytic Jacobians, i.e. exact second derivatives, without a
// hand-expanded (and error-prone) second-order formula. Branches compare values only.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace attitude_planner {

template <int N>
struct Dual {
  double v = 0.0;                                                       ///< value
  Eigen::Matrix<double, N, 1> d = Eigen::Matrix<double, N, 1>::Zero();  ///< ∂value/∂direction_i

  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT: implicit from constants, as Eigen expects
  Dual(double value, int direction) : v(value) { d(direction) = 1.0; }

  Dual& operator+=(const Dual& o) {
    v += o.v;
    d += o.d;
    return *this;
  }
  Dual& operator-=(const Dual& o) {
    v -= o.v;
    d -= o.d;
    return *this;
  }
  Dual& operator*=(const Dual& o) {
    d = d * o.v + o.d * v;
    v *= o.v;
    return *this;
  }
  Dual& operator/=(const Dual& o) {
    d = (d * o.v - o.d * v) / (o.v * o.v);
    v /= o.v;
    return *this;
  }
};

template <int N>
Dual<N> operator+(Dual<N> a, const Dual<N>& b) {
  return a += b;
}
template <int N>
Dual<N> operator-(Dual<N> a, const Dual<N>& b) {
  return a -= b;
}
template <int N>
Dual<N> operator*(Dual<N> a, const Dual<N>& b) {
  return a *= b;
}
template <int N>
Dual<N> operator/(Dual<N> a, const Dual<N>& b) {
  return a /= b;
}
template <int N>
Dual<N> operator+(Dual<N> a, double b) {
  a.v += b;
  return a;
}
template <int N>
Dual<N> operator+(double b, Dual<N> a) {
  a.v += b;
  return a;
}
template <int N>
Dual<N> operator-(Dual<N> a, double b) {
  a.v -= b;
  return a;
}
template <int N>
Dual<N> operator-(double b, const Dual<N>& a) {
  Dual<N> r;
  r.v = b - a.v;
  r.d = -a.d;
  return r;
}
template <int N>
Dual<N> operator*(Dual<N> a, double b) {
  a.v *= b;
  a.d *= b;
  return a;
}
template <int N>
Dual<N> operator*(double b, Dual<N> a) {
  a.v *= b;
  a.d *= b;
  return a;
}
template <int N>
Dual<N> operator/(Dual<N> a, double b) {
  a.v /= b;
  a.d /= b;
  return a;
}
template <int N>
Dual<N> operator/(double b, const Dual<N>& a) {
  return Dual<N>(b) / a;
}
template <int N>
Dual<N> operator-(const Dual<N>& a) {
  Dual<N> r;
  r.v = -a.v;
  r.d = -a.d;
  return r;
}
template <int N>
Dual<N> operator+(const Dual<N>& a) {
  return a;
}

template <int N>
bool operator<(const Dual<N>& a, const Dual<N>& b) {
  return a.v < b.v;
}
template <int N>
bool operator>(const Dual<N>& a, const Dual<N>& b) {
  return a.v > b.v;
}
template <int N>
bool operator<=(const Dual<N>& a, const Dual<N>& b) {
  return a.v <= b.v;
}
template <int N>
bool operator>=(const Dual<N>& a, const Dual<N>& b) {
  return a.v >= b.v;
}
template <int N>
bool operator==(const Dual<N>& a, const Dual<N>& b) {
  return a.v == b.v;
}
template <int N>
bool operator!=(const Dual<N>& a, const Dual<N>& b) {
  return a.v != b.v;
}

template <int N>
Dual<N> sqrt(const Dual<N>& a) {
  Dual<N> r;
  r.v = std::sqrt(a.v);
  r.d = a.d / (2.0 * r.v);
  return r;
}
template <int N>
Dual<N> sin(const Dual<N>& a) {
  Dual<N> r;
  r.v = std::sin(a.v);
  r.d = a.d * std::cos(a.v);
  return r;
}
template <int N>
Dual<N> cos(const Dual<N>& a) {
  Dual<N> r;
  r.v = std::cos(a.v);
  r.d = -a.d * std::sin(a.v);
  return r;
}
template <int N>
Dual<N> abs(const Dual<N>& a) {
  return a.v < 0 ? -a : a;
}
template <int N>
Dual<N> atan2(const Dual<N>& y, const Dual<N>& x) {
  Dual<N> r;
  r.v = std::atan2(y.v, x.v);
  r.d = (y.d * x.v - x.d * y.v) / (x.v * x.v + y.v * y.v);
  return r;
}

}  // namespace attitude_planner

namespace Eigen {
template <int N>
struct NumTraits<attitude_planner::Dual<N>> : NumTraits<double> {
  using Real = attitude_planner::Dual<N>;
  using NonInteger = attitude_planner::Dual<N>;
  using Nested = attitude_planner::Dual<N>;
  using Literal = attitude_planner::Dual<N>;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 1 + N,
    MulCost = 1 + 2 * N
  };
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<attitude_planner::Dual<N>, double, BinaryOp> {
  using ReturnType = attitude_planner::Dual<N>;
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, attitude_planner::Dual<N>, BinaryOp> {
  using ReturnType = attitude_planner::Dual<N>;
};
}  // namespace Eigen
