// Bordered banded systems: the Newton/KKT matrix of a transcription with a few global unknowns
// (the time step h, the duration T, …) next to the node unknowns,
//
//     K = [ A   B ]     A  n×n symmetric banded (the stage-wise part, BandedSymmetric),
//         [ Bᵀ  D ],    B  n×m dense (the global unknowns couple to every node), D m×m, m small.
//
// Solved by the Schur complement on the border: with A = L Lᵀ (the banded Cholesky factor),
// Z = A⁻¹B (m extra banded solves), S = D − BᵀZ (m×m), then for the right-hand side (b, c):
// u = A⁻¹b, y = S⁻¹(c − Bᵀu), x = u − Z y. Cost O(n·p²) to factor A plus O(n·p·m) for Z and
// O(n·m²) for S: still linear in n. K's inertia is (n + n₊(S), n₋(S), n₀(S)) when A is positive
// definite (Haynsworth): the border may make K indefinite (a saddle point, e.g. a constrained
// problem's multiplier), which the eigenvalues of S report; a band that is not positive
// definite is reported as such (no inertia is claimed then).
#pragma once

#include <Eigen/Core>

#include "planning/linalg/banded_matrix.hpp"

namespace attitude_planner {

/// What factoring a bordered system found.
struct BorderedInertia {
  bool band_positive_definite = false;  ///< A's banded Cholesky factorization succeeded
  /// Eigenvalue signs of S = D − BᵀA⁻¹B (only if band_positive_definite); an eigenvalue is
  /// counted as zero when |λ| ≤ kSchurZeroRelative · max(|λ|, ‖D‖, ‖BᵀZ‖).
  int positive = 0, negative = 0, zero = 0;
  /// The border's contribution to K's inertia: K has n + positive positive, negative negative and
  /// zero zero eigenvalues when A is positive definite.
  bool solvable() const { return band_positive_definite && zero == 0; }
};

/// Relative size below which an eigenvalue of the Schur complement counts as zero: its entries
/// are differences D − BᵀZ, exact to about this much of the larger term.
inline constexpr double kSchurZeroRelative = 1e-13;

/// The factorization of a bordered banded system, kept for several right-hand sides.
/// Scalar as BandedSymmetric's (double, long double, DoubleDouble): A's factor, Z and the
/// products BᵀZ and Z y are formed in Scalar; S (m×m) is kept in Scalar and solved through the
/// eigen-decomposition of its double rounding (which also gives its inertia) refined in Scalar,
/// so that the extended precisions keep their accuracy on the border too.
template <typename Scalar>
class BorderedBandedFactor {
 public:
  /// Factors K = [[A, B], [Bᵀ, D]] (B: A.size() × m, D: m × m symmetric, m ≥ 0).
  /// Returns inertia().solvable(); solve must not be called otherwise.
  bool factor(const BandedSymmetric<Scalar>& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& D);
  /// Solves K (x, y) = (b, c) in place: `rhs` holds b (n entries) then c (m entries). Uses a
  /// work vector of the factor: not for concurrent calls on one factor.
  void solve(Eigen::VectorXd* rhs) const;
  const BorderedInertia& inertia() const { return inertia_; }
  /// S = D − BᵀA⁻¹B, for tests and diagnostics.
  const Eigen::MatrixXd& schurComplement() const { return S_; }

 private:
  BandedCholeskyFactor<Scalar> band_;
  int n_ = 0, m_ = 0;
  Eigen::MatrixXd B_;
  std::vector<Scalar> Z_;          ///< A⁻¹B, column-major (column j at j·n)
  std::vector<Scalar> S_scalar_;   ///< S in Scalar, column-major
  mutable std::vector<Scalar> u_;  ///< solve's A⁻¹b, kept to reuse its storage
  /// y = S⁻¹ r: the double eigen-decomposition's solve plus kSchurRefinements corrections with
  /// the residual in Scalar.
  std::vector<Scalar> solveSchur(const std::vector<Scalar>& r) const;
  Eigen::MatrixXd S_, eigenvectors_;
  Eigen::VectorXd eigenvalues_;
  BorderedInertia inertia_;
};

using BorderedBanded = BorderedBandedFactor<double>;
using ExtendedBorderedBanded = BorderedBandedFactor<DoubleDouble>;

}  // namespace attitude_planner
