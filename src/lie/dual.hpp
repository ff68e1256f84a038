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
  /// ∂value/∂direction_i. A plain array: the small fixed loops below inline and vectorize, which
  /// an Eigen vector member did not (it dominated the Newton solver's profile).
  struct Derivatives {
    double x[N] = {};
    double& operator()(int i) { return x[i]; }
    double operator()(int i) const { return x[i]; }
    /// As an Eigen column, for assembling Jacobians.
    Eigen::Map<const Eigen::Matrix<double, N, 1>> vector() const {
      return Eigen::Map<const Eigen::Matrix<double, N, 1>>(x);
    }
    Eigen::Matrix<double, 1, N> transpose() const { return vector().transpose(); }
    /// Derivatives start..start+K−1.
    template <int K>
    Eigen::Matrix<double, K, 1> segment(int start) const {
      return vector().template segment<K>(start);
    }
  };

  double v = 0.0;  ///< value
  Derivatives d;   ///< derivatives

  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT: implicit from constants, as Eigen expects
  Dual(double value, int direction) : v(value) { d.x[direction] = 1.0; }

  Dual& operator+=(const Dual& o) {
    v += o.v;
    for (int i = 0; i < N; ++i) d.x[i] += o.d.x[i];
    return *this;
  }
  Dual& operator-=(const Dual& o) {
    v -= o.v;
    for (int i = 0; i < N; ++i) d.x[i] -= o.d.x[i];
    return *this;
  }
  Dual& operator*=(const Dual& o) {
    for (int i = 0; i < N; ++i) d.x[i] = d.x[i] * o.v + o.d.x[i] * v;
    v *= o.v;
    return *this;
  }
  Dual& operator/=(const Dual& o) {
    const double inv = 1.0 / o.v;
    const double q = v * inv;
    for (int i = 0; i < N; ++i) d.x[i] = (d.x[i] - o.d.x[i] * q) * inv;
    v = q;
    return *this;
  }
  /// Multiplies value and derivatives by s.
  Dual& scale(double s) {
    v *= s;
    for (int i = 0; i < N; ++i) d.x[i] *= s;
    return *this;
  }
  Dual operator-() const {
    Dual r;
    r.v = -v;
    for (int i = 0; i < N; ++i) r.d.x[i] = -d.x[i];
    return r;
  }
  Dual operator+() const { return *this; }
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
  Dual<N> r = -a;
  r.v += b;
  return r;
}
template <int N>
Dual<N> operator*(Dual<N> a, double b) {
  return a.scale(b);
}
template <int N>
Dual<N> operator*(double b, Dual<N> a) {
  return a.scale(b);
}
template <int N>
Dual<N> operator/(Dual<N> a, double b) {
  return a.scale(1.0 / b);
}
template <int N>
Dual<N> operator/(double b, const Dual<N>& a) {
  return Dual<N>(b) / a;
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

/// f(a) given f(a.v) = value and f'(a.v) = slope.
template <int N>
Dual<N> chain(const Dual<N>& a, double value, double slope) {
  Dual<N> r;
  r.v = value;
  for (int i = 0; i < N; ++i) r.d.x[i] = slope * a.d.x[i];
  return r;
}
template <int N>
Dual<N> sqrt(const Dual<N>& a) {
  const double s = std::sqrt(a.v);
  return chain(a, s, 0.5 / s);
}
template <int N>
Dual<N> sin(const Dual<N>& a) {
  return chain(a, std::sin(a.v), std::cos(a.v));
}
template <int N>
Dual<N> cos(const Dual<N>& a) {
  return chain(a, std::cos(a.v), -std::sin(a.v));
}
template <int N>
Dual<N> abs(const Dual<N>& a) {
  return a.v < 0 ? -a : a;
}
template <int N>
Dual<N> atan2(const Dual<N>& y, const Dual<N>& x) {
  Dual<N> r;
  r.v = std::atan2(y.v, x.v);
  const double n = x.v * x.v + y.v * y.v;
  for (int i = 0; i < N; ++i) r.d.x[i] = (y.d.x[i] * x.v - x.d.x[i] * y.v) / n;
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
