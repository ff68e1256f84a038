// Closed-form extremals of the drift + two-input system (seed 001, Section 4): Prop. 4.2
// (c1 = c2, circular functions) and Prop. 4.3 (c1 ≠ c2, Jacobi elliptic functions), with the
// corrections listed in docs/design/drift_two_input.md. Only the cases the seed states are
// evaluated: an initial costate outside them is reported (status kOutsideStatedCases), never
// evaluated.
#pragma once

#include <iosfwd>
#include <string>

#include "attitude_planner/drift_two_input/system.hpp"

namespace attitude_planner {

/// Which statement of the seed covers an initial costate.
enum class DriftTwoInputCase {
  kCircular,           ///< Prop. 4.2: c1 = c2
  kEllipticCaseI,      ///< Prop. 4.3 (i): φ = a·dc or a·ns (modulus b/a)
  kEllipticCaseII,     ///< Prop. 4.3 (ii): φ = a·nc or √(a²+b²)·ds (modulus b/√(a²+b²))
  kOutsideStatedCases  ///< none of the seed's conditions hold: no closed form is evaluated
};

/// Representation of φ(t) in Prop. 4.3; case (i) allows kDc/kNs, case (ii) kNc/kDs. The two
/// forms of a case are the same curve shifted by a quarter period K (ns(u + K) = dc(u)).
enum class EllipticForm { kDc, kNs, kNc, kDs };

/// Human-readable name of a case ("circular (Prop. 4.2)", ...).
std::string toString(DriftTwoInputCase c);
/// Human-readable name of an elliptic form ("a dc", ...).
std::string toString(EllipticForm f);

/// Closed-form solution p(t) of (3.15)–(3.17) through a given p(0).
class DriftTwoInputClosedForm {
 public:
  /// Classifies p0 [c·rad/s] for weights w, checking the seed's conditions, and prepares the
  /// closed form. `form` selects the representation in case (i) (kDc or kNs) and case (ii)
  /// (kNc or kDs); a form of the other case is replaced by that case's default (kDc / kNc).
  DriftTwoInputClosedForm(const Vector3& p0, const DriftTwoInputWeights& w,
                          EllipticForm form = EllipticForm::kDc);

  /// Case that covers p0; kOutsideStatedCases means evaluate() throws.
  DriftTwoInputCase stateCase() const { return case_; }
  /// True when the closed form is available (a stated case, and p0 matched on its orbit).
  bool valid() const { return valid_; }
  /// Why the closed form is (un)available: the conditions checked and their values.
  const std::string& message() const { return message_; }
  /// Elliptic representation used (meaningful for the elliptic cases).
  EllipticForm form() const { return form_; }
  /// True when c1 < c2 and the c2 < c1 formulas are applied to the rotated costate
  /// q = (p2, −p1, p3) (a Poisson automorphism that swaps the roles of c1 and c2).
  bool swapped() const { return swapped_; }
  /// Elliptic modulus k (0 for the circular case).
  double modulus() const { return k_; }
  /// Frequency of the elliptic argument u = λ t + u0 [1/s] (circular: angular rate [rad/s]).
  double argumentRate() const { return lambda_; }
  /// Invariants h0 = H(p0) and c0 = C(p0) used by Prop. 4.3.
  double h0() const { return h0_; }
  /// Casimir c0 = |p0|².
  double c0() const { return c0_; }

  /// p(t) [c·rad/s] at time t [s]; throws InvalidInput when !valid(), naming the reason.
  Vector3 evaluate(double t) const;

 private:
  /// Prop. 4.2 (c1 = c2): the circular constants from p0.
  void initCircular(const Vector3& p0, std::ostream& os);
  /// Prop. 4.3 in the frame where c2 < c1: which case holds and its constants; false (the reason
  /// written to os) when neither does.
  bool initElliptic(double c1, double c2, EllipticForm form, std::ostream& os);
  /// The phase u0 and signs (σ1, σ2) that put q0 on the orbit, moving along the flow; returns
  /// the residual |q(u0) − q0|.
  double matchPhase(const Vector3& q0, double c1, double c2);
  /// q (rotated frame) at the Jacobi values (sn, cn, dn) of u, for signs s1, s2 of q1, q2.
  Vector3 ellipticAt(double sn, double cn, double dn, double s1, double s2) const;

  DriftTwoInputWeights w_;
  DriftTwoInputCase case_ = DriftTwoInputCase::kOutsideStatedCases;
  EllipticForm form_ = EllipticForm::kDc;
  bool valid_ = false, swapped_ = false;
  std::string message_;
  double h0_ = 0, c0_ = 0;
  // circular: p3 = k2, p1 + i p2 = √k1 exp(i(ω t + k3))
  double k1_ = 0, k2_ = 0, k3_ = 0, omega_ = 0;
  // elliptic (rotated frame where c2 < c1): constants of Prop. 4.3
  double alpha_ = 0, beta_ = 0, a_ = 0, r_ = 0, k_ = 0, lambda_ = 0, u0_ = 0;
  double A1_ = 0, A2_ = 0, sigma1_ = 1, sigma2_ = 1;
};

}  // namespace attitude_planner
