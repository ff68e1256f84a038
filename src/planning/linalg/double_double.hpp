// Double-double arithmetic: a number is the unevaluated sum hi + lo of two doubles with
// |lo| ≤ ulp(hi)/2, about 106 significant bits (ε ≈ 1.2e-32), from IEEE double operations and a
// correctly rounded fma alone (Dekker 1971; Knuth's two-sum; Hida, Li and Bailey's QD library
// for the formulas). It is the interior point's scalar above N = 8192 (above 1024 where long
// double is not the x87 format; interior_point/grid_solve.hpp: resolvePrecision), where
// the Newton system's condition (~N⁴ from torques that are second differences of attitudes,
// times the barrier's 1/D) exceeds long double's 64-bit significand. Measured per
// multiply–add in a dependent chain (x86-64): double 0.44 ns, long double (x87) 1.8 ns,
// double-double 5–7 ns, __float128 (software) 23 ns; long double is also a software quad on
// aarch64 and plain double elsewhere, double-double the same everywhere.
//
// Only what the banded Cholesky factorization and its assembly need: +, −, ×, ÷, √, comparisons
// and conversions. Requires strict IEEE double evaluation (no -ffast-math, no x87 excess
// precision), which the build keeps.
#pragma once

#include <cmath>

namespace attitude_planner {

class DoubleDouble {
 public:
  DoubleDouble() = default;
  DoubleDouble(double x) : hi_(x), lo_(0.0) {}  // NOLINT: implicit, as for the built-in types
  explicit operator double() const { return hi_ + lo_; }
  double hi() const { return hi_; }
  double lo() const { return lo_; }

  /// The exact sum a + b as hi + lo (Knuth's two-sum; no condition on |a|, |b|).
  static DoubleDouble twoSum(double a, double b) {
    const double s = a + b, v = s - a;
    return {s, (a - (s - v)) + (b - v)};
  }
  /// The rounding error a·b − p of p = fl(a·b), exactly (as twoProduct).
  static double productError(double a, double b, double p) { return twoProduct(a, b).lo_; }
  /// The exact product a·b as hi + lo: with a hardware fma, which returns the rounding error of
  /// a·b; without one (x86-64's baseline), by Dekker's splitting of a and b into 26-bit halves,
  /// inline (a library fma call cost more). |a|, |b| < 1e300.
  static DoubleDouble twoProduct(double a, double b) {
    const double p = a * b;
#ifdef __FMA__
    return {p, std::fma(a, b, -p)};
#else
    const auto split = [](double x, double* high, double* low) {
      const double t = 134217729.0 * x;  // 2^27 + 1
      *high = t - (t - x);
      *low = x - *high;
    };
    double ah, al, bh, bl;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    return {p, ((ah * bh - p) + ah * bl + al * bh) + al * bl};
#endif
  }

  friend DoubleDouble operator-(DoubleDouble a) {
    return {-a.hi_, -a.lo_};
  }
  friend DoubleDouble operator+(DoubleDouble a, DoubleDouble b) {
    DoubleDouble s = twoSum(a.hi_, b.hi_);
    const DoubleDouble t = twoSum(a.lo_, b.lo_);
    s = fastTwoSum(s.hi_, s.lo_ + t.hi_);
    return fastTwoSum(s.hi_, s.lo_ + t.lo_);
  }
  friend DoubleDouble operator+(DoubleDouble a, double b) {
    const DoubleDouble s = twoSum(a.hi_, b);
    return fastTwoSum(s.hi_, s.lo_ + a.lo_);
  }
  friend DoubleDouble operator-(DoubleDouble a, DoubleDouble b) {
    return a + (-b);
  }
  friend DoubleDouble operator*(DoubleDouble a, DoubleDouble b) {
    const DoubleDouble p = twoProduct(a.hi_, b.hi_);
    return fastTwoSum(p.hi_, p.lo_ + (a.hi_ * b.lo_ + a.lo_ * b.hi_));
  }
  friend DoubleDouble operator*(DoubleDouble a, double b) {
    const DoubleDouble p = twoProduct(a.hi_, b);
    return fastTwoSum(p.hi_, p.lo_ + a.lo_ * b);
  }
  friend DoubleDouble operator*(double a, DoubleDouble b) {
    return b * a;
  }
  /// a/b to ~ε: the quotient of the leading parts, corrected once by the exact remainder.
  friend DoubleDouble operator/(DoubleDouble a, DoubleDouble b) {
    const double q1 = a.hi_ / b.hi_;
    const DoubleDouble r = a - b * q1;
    const double q2 = r.hi_ / b.hi_;
    const DoubleDouble r2 = r - b * q2;
    return fastTwoSum(q1, q2) + r2.hi_ / b.hi_;
  }
  DoubleDouble& operator+=(DoubleDouble b) {
    return *this = *this + b;
  }
  DoubleDouble& operator+=(double b) {
    return *this = *this + b;
  }
  DoubleDouble& operator-=(DoubleDouble b) {
    return *this = *this - b;
  }

  friend bool operator<(DoubleDouble a, DoubleDouble b) {
    return a.hi_ < b.hi_ || (a.hi_ == b.hi_ && a.lo_ < b.lo_);
  }
  friend bool operator>(DoubleDouble a, DoubleDouble b) {
    return b < a;
  }
  friend bool operator==(DoubleDouble a, DoubleDouble b) {
    return a.hi_ == b.hi_ && a.lo_ == b.lo_;
  }

  friend DoubleDouble abs(DoubleDouble a) {
    return a.hi_ < 0.0 ? -a : a;
  }
  friend bool isfinite(DoubleDouble a) {
    return std::isfinite(a.hi_) && std::isfinite(a.lo_);
  }
  /// √a (a ≥ 0): the double root x corrected by one Newton step with the exact residual a − x².
  friend DoubleDouble sqrt(DoubleDouble a) {
    if (!(a.hi_ > 0.0)) return DoubleDouble(std::sqrt(a.hi_));
    const double x = std::sqrt(a.hi_);
    const DoubleDouble residual = a - twoProduct(x, x);
    return fastTwoSum(x, residual.hi_ / (2.0 * x));
  }

 private:
  DoubleDouble(double hi, double lo) : hi_(hi), lo_(lo) {}
  /// The exact sum a + b as hi + lo, given |a| ≥ |b| (or a = 0).
  static DoubleDouble fastTwoSum(double a, double b) {
    const double s = a + b;
    return {s, b - (s - a)};
  }
  double hi_ = 0.0, lo_ = 0.0;
};

/// s − Σ a_k b_k for double-double a_k, b_k, accumulated as Ogita, Rump and Oishi's Dot2: the
/// leading parts' products and sums by error-free transformations, every error term summed in
/// one double, normalized once at the end. About as accurate as double-double arithmetic term by
/// term (error ≲ ε_dd |result| + (n ε)² Σ|a_k b_k|) at ~half the operations: the banded
/// Cholesky factorization's and substitutions' inner products.
class DoubleDoubleDifference {
 public:
  explicit DoubleDoubleDifference(DoubleDouble s) : hi_(s.hi()), error_(s.lo()) {}
  void subtractProduct(DoubleDouble a, DoubleDouble b) {
    const double p = a.hi() * b.hi();
    const double p_error = DoubleDouble::productError(a.hi(), b.hi(), p);
    const DoubleDouble sum = DoubleDouble::twoSum(hi_, -p);
    hi_ = sum.hi();
    error_ += sum.lo() - p_error - (a.hi() * b.lo() + a.lo() * b.hi());
  }
  DoubleDouble value() const { return DoubleDouble::twoSum(hi_, error_); }

 private:
  double hi_, error_;
};

}  // namespace attitude_planner
