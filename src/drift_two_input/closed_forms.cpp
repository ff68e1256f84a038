// Closed forms of seed 001, Prop. 4.2 and Prop. 4.3, re-derived (docs/design/drift_two_input.md).
//
// Prop. 4.3 in brief (c2 < c1): with h0 = H(p0), c0 = C(p0), s = √(h0² − c0), α = h0 + s,
// β = h0 − s, the Möbius substitution p3 = (α − βφ)/(1 − φ) turns (4.22) into
// φ'² = Ω²(φ² − a²)(φ² − b²), Ω = (α − β)√(μ1 μ2)/√(c1 c2), whose solutions are the Jacobi forms
// of (4.18)–(4.21) up to a phase u0. p1 and p2 follow from the invariants; each is written as
// (constant)·g(u)/(den(u) − num(u)) with φ = num/den, so nothing is evaluated at a pole of φ.
#include "attitude_planner/drift_two_input/closed_forms.hpp"

#include <boost/math/special_functions/ellint_1.hpp>
#include <boost/math/special_functions/jacobi_elliptic.hpp>
#include <cmath>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

std::string toString(DriftTwoInputCase c) {
  switch (c) {
    case DriftTwoInputCase::kCircular:
      return "circular (Prop. 4.2, c1 = c2)";
    case DriftTwoInputCase::kEllipticCaseI:
      return "elliptic case (i) (Prop. 4.3)";
    case DriftTwoInputCase::kEllipticCaseII:
      return "elliptic case (ii) (Prop. 4.3)";
    case DriftTwoInputCase::kOutsideStatedCases:
      return "outside the cases stated in the seed";
  }
  return "?";
}

std::string toString(EllipticForm f) {
  switch (f) {
    case EllipticForm::kDc:
      return "a dc";
    case EllipticForm::kNs:
      return "a ns";
    case EllipticForm::kNc:
      return "a nc";
    case EllipticForm::kDs:
      return "sqrt(a^2+b^2) ds";
  }
  return "?";
}

namespace {

// q = (p2, −p1, p3): rotation by −90° about e3. A Lie–Poisson automorphism (rotations preserve the
// cross product) mapping H with (c1, c2) to H with (c2, c1); used to reduce c1 < c2 to c2 < c1.
Vector3 rotateToSwapped(const Vector3& p) {
  return Vector3(p.y(), -p.x(), p.z());
}
Vector3 rotateFromSwapped(const Vector3& q) {
  return Vector3(-q.y(), q.x(), q.z());
}

}  // namespace

DriftTwoInputClosedForm::DriftTwoInputClosedForm(const Vector3& p0, const DriftTwoInputWeights& w,
                                                 EllipticForm form)
    : w_(w) {
  validateDriftTwoInputWeights(w);
  if (!p0.allFinite()) throw InvalidInput("initial costate p0 must be finite");
  h0_ = drift_two_input::hamiltonian(p0, w);
  c0_ = drift_two_input::casimir(p0);
  std::ostringstream os;
  os.precision(17);

  if (w.c1 == w.c2) {
    initCircular(p0, os);
    message_ = os.str();
    return;
  }

  // Reduce to c2 < c1 (the ordering Prop. 4.3 states).
  swapped_ = w.c1 < w.c2;
  const Vector3 q0 = swapped_ ? rotateToSwapped(p0) : p0;
  const double c1 = swapped_ ? w.c2 : w.c1, c2 = swapped_ ? w.c1 : w.c2;
  if (!initElliptic(c1, c2, form, os)) {
    message_ = os.str();
    return;
  }
  const double best = matchPhase(q0, c1, c2);
  const double tol = 1e-10 * (1.0 + q0.norm());
  if (!(best <= tol)) {
    os << toString(case_) << " holds but p0 was not matched on the closed-form orbit (residual "
       << best << ")";
    case_ = DriftTwoInputCase::kOutsideStatedCases;
    message_ = os.str();
    return;
  }
  valid_ = true;
  os << toString(case_) << ", phi = " << toString(form_) << ", modulus k = " << k_
     << ", u = " << lambda_ << " t + " << u0_;
  message_ = os.str();
}

void DriftTwoInputClosedForm::initCircular(const Vector3& p0, std::ostream& os) {
  // Prop. 4.2 (corrected): p3 = k2 is constant, and (3.15)–(3.16) read ṗ1 = (1 − k2/c) p2,
  // ṗ2 = −(1 − k2/c) p1, so p1 + i p2 = √k1 exp(i((k2/c − 1) t + k3)), k3 = atan2(p2(0), p1(0)).
  case_ = DriftTwoInputCase::kCircular;
  k1_ = p0.x() * p0.x() + p0.y() * p0.y();
  k2_ = p0.z();
  k3_ = std::atan2(p0.y(), p0.x());
  omega_ = k2_ / w_.c1 - 1.0;
  lambda_ = omega_;
  valid_ = true;
  os << "c1 = c2 = " << w_.c1 << ": circular functions (Prop. 4.2)";
}

bool DriftTwoInputClosedForm::initElliptic(double c1, double c2, EllipticForm form,
                                           std::ostream& os) {
  const char* big = swapped_ ? "c2" : "c1";
  const char* small = swapped_ ? "c1" : "c2";
  os << "h0 = " << h0_ << ", c0 = " << c0_ << ", " << small << " = " << c2 << " < " << big << " = "
     << c1 << (swapped_ ? " (seed's c2 < c1 formulas after q = (p2, -p1, p3))" : "") << ": ";
  if (!(c0_ > 0.0) || !(h0_ * h0_ > c0_)) {
    os << "Prop. 4.3 needs c0 > 0 and h0^2 > c0 (h0^2 - c0 = " << h0_ * h0_ - c0_ << ")";
    return false;
  }
  const double s = std::sqrt(h0_ * h0_ - c0_);
  alpha_ = h0_ + s;
  beta_ = h0_ - s;
  const double a2 = (alpha_ - c2) / (beta_ - c2);  // seed's a²
  const double b2 = (alpha_ - c1) / (beta_ - c1);  // seed's b²
  const bool cond_small = s < h0_ - c2;            // β > c2 (both cases)
  const bool case_i = (h0_ - c1 < -s) && cond_small && (b2 < a2);
  const bool case_ii = (-s < h0_ - c1) && (h0_ - c1 < s) && cond_small;
  if (!case_i && !case_ii) {
    os << "neither (i) [h0 - " << big << " < -sqrt(h0^2-c0), sqrt(h0^2-c0) < h0 - " << small
       << ", b^2 < a^2] nor (ii) [|h0 - " << big << "| < sqrt(h0^2-c0) < h0 - " << small
       << "] holds (h0 - " << big << " = " << h0_ - c1 << ", h0 - " << small << " = " << h0_ - c2
       << ", sqrt(h0^2-c0) = " << s << ")";
    return false;
  }
  case_ = case_i ? DriftTwoInputCase::kEllipticCaseI : DriftTwoInputCase::kEllipticCaseII;
  // μ1 μ2 of the proof (4.22); M = √(μ1 μ2) (the statement's M lacks the square root).
  const double mu1 = (beta_ - c2) / (2 * s), mu2 = (c1 - beta_) / (2 * s);
  const double Omega = (alpha_ - beta_) * std::sqrt(mu1 * mu2) / std::sqrt(c1 * c2);
  // p1² = κ1 (φ² − a²)/(1 − φ)², p2² = κ2 (φ² − b²)/(1 − φ)² (from the invariants)
  const double kappa1 = c1 / (c1 - c2) * (alpha_ - beta_) * (alpha_ - beta_) * mu1;
  const double kappa2 = c2 / (c1 - c2) * (alpha_ - beta_) * (alpha_ - beta_) * mu2;
  a_ = std::sqrt(a2);
  double m1 = 0.0, m2 = 0.0;
  if (case_i) {
    form_ = (form == EllipticForm::kNs) ? EllipticForm::kNs : EllipticForm::kDc;
    k_ = std::sqrt(b2) / a_;
    lambda_ = a_ * Omega;  // dc/ns argument is aΩt (the statement's "Ωt" lacks the factor a)
    const double kp2 = 1.0 - k_ * k_;
    m1 = form_ == EllipticForm::kDc ? a2 * kp2 : a2;
    m2 = m1;
  } else {
    form_ = (form == EllipticForm::kDs) ? EllipticForm::kDs : EllipticForm::kNc;
    // b² < 0 here: the seed's "b" in (4.20)/(4.21) is √(−b²)
    r_ = std::sqrt(a2 - b2);
    k_ = std::sqrt(-b2) / r_;
    lambda_ = r_ * Omega;
    m1 = form_ == EllipticForm::kNc ? a2 : r_ * r_;
    m2 = r_ * r_;
  }
  A1_ = std::sqrt(kappa1 * m1);
  A2_ = std::sqrt(kappa2 * m2);
  return true;
}

double DriftTwoInputClosedForm::matchPhase(const Vector3& q0, double c1, double c2) {
  // Find the amplitude θ0 (sn = sin θ0, cn = cos θ0) and signs (σ1, σ2) with q(θ0) = q0
  // moving along the vector field; coarse grid, then Gauss–Newton in θ. The orbit has two
  // components (σ2 = ±1); σ1 = −1 is the time reversal θ → −θ of σ1 = +1, so the direction of
  // the flow at q0 picks σ1.
  auto at = [&](double th, double s1, double s2) {
    const double sn = std::sin(th), cn = std::cos(th);
    return ellipticAt(sn, cn, std::sqrt(1.0 - k_ * k_ * sn * sn), s1, s2);
  };
  const DriftTwoInputWeights wq{c1, c2};
  const Vector3 fq = drift_two_input::costateRate<double>(q0, wq);
  double best = INFINITY;
  for (double s1 : {1.0, -1.0}) {
    for (double s2 : {1.0, -1.0}) {
      double th = 0.0, res = INFINITY;
      const int n = 720;
      for (int i = 0; i < n; ++i) {
        const double t = 2 * M_PI * i / n;
        const double e = (at(t, s1, s2) - q0).norm();
        if (e < res) res = e, th = t;
      }
      for (int it = 0; it < 40; ++it) {
        const double dth = 1e-6;
        const Vector3 d = (at(th + dth, s1, s2) - at(th - dth, s1, s2)) / (2 * dth);
        const Vector3 e = at(th, s1, s2) - q0;
        if (d.squaredNorm() == 0.0) break;
        const double step = d.dot(e) / d.squaredNorm();
        th -= step;
        if (std::abs(step) < 1e-16) break;
      }
      res = (at(th, s1, s2) - q0).norm();
      const Vector3 d = (at(th + 1e-6, s1, s2) - at(th - 1e-6, s1, s2));
      // direction: dq/dt = (dq/dθ) λ dn > 0 must point along f(q0); a tie (f ≈ 0) is harmless
      const bool forward = d.dot(fq) >= -1e-12 * d.norm() * fq.norm();
      if (forward && res < best) {
        best = res;
        u0_ = boost::math::ellint_1(k_, th);
        sigma1_ = s1;
        sigma2_ = s2;
      }
    }
  }
  return best;
}

Vector3 DriftTwoInputClosedForm::ellipticAt(double sn, double cn, double dn, double s1,
                                            double s2) const {
  double num = 0, den = 0, g1 = 0, g2 = 0;  // φ = num/den
  switch (form_) {
    case EllipticForm::kDc:  // φ = a dn/cn
      num = a_ * dn, den = cn, g1 = sn, g2 = 1.0;
      break;
    case EllipticForm::kNs:  // φ = a/sn
      num = a_, den = sn, g1 = cn, g2 = dn;
      break;
    case EllipticForm::kNc:  // φ = a/cn
      num = a_, den = cn, g1 = sn, g2 = dn;
      break;
    case EllipticForm::kDs:  // φ = r dn/sn
      num = r_ * dn, den = sn, g1 = cn, g2 = 1.0;
      break;
  }
  const double d = den - num;  // ≠ 0: |φ| ≥ a > 1 on the orbit
  return Vector3(s1 * A1_ * g1 / d, s2 * A2_ * g2 / d, (alpha_ * den - beta_ * num) / d);
}

Vector3 DriftTwoInputClosedForm::evaluate(double t) const {
  if (!valid_) throw InvalidInput("no closed form for this initial costate: " + message_);
  if (case_ == DriftTwoInputCase::kCircular) {
    const double r = std::sqrt(k1_), ph = omega_ * t + k3_;
    return Vector3(r * std::cos(ph), r * std::sin(ph), k2_);
  }
  double cn = 0, dn = 0;
  const double sn = boost::math::jacobi_elliptic(k_, lambda_ * t + u0_, &cn, &dn);
  const Vector3 q = ellipticAt(sn, cn, dn, sigma1_, sigma2_);
  return swapped_ ? rotateFromSwapped(q) : q;
}

}  // namespace attitude_planner
