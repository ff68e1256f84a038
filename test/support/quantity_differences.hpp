// A stage quantity's terms (value, node Jacobian, contracted curvature, and with h free the h
// column, mixed and hh entries) against central differences of its values along one direction
// of the node unknowns and in h, and the curvature times a direction against mixed differences
// along two directions: the check every quantity's typed suite runs
// (test_stage_constraints, test_reaction_wheels).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_quantities.hpp"

namespace attitude_planner::test_support {

struct QuantityDifferences {
  const StageQuantityModel& quantity;
  const ReducedProblem& np;
  StageSupport support;
  Eigen::VectorXd direction;  ///< in the node unknowns δ
  Vector3 lambda;             ///< what the contraction returns
  Vector3 contracted;         ///< λ as the quantity contracts it (scalar quantities: λ(0) alone)
  double value_tolerance;     ///< relative, terms' value against value()

  /// q_k for every instance at `at`'s current iterate.
  std::vector<Vector3> values(const ReducedProblem& at) const {
    const QuantityInputs inputs(at, at.current());
    std::vector<Vector3> out;
    for (int k = support.first_k; k <= support.last_k; ++k)
      out.push_back(quantity.value(inputs, k));
    return out;
  }
  /// The iterate moved by α·direction (the retraction the terms are derivatives of) at step h.
  ReducedProblem moved(double alpha, double h) const {
    ReducedProblem out = np;
    out.setTimeStep(h);
    out.setCurrent(out.retract(direction, alpha));
    return out;
  }
  /// δ (`of`: the direction) restricted to the local nodes of instance k (fixed nodes 0).
  Eigen::Matrix<double, 9, 1> localPart(int k, const Eigen::VectorXd& of) const {
    Eigen::Matrix<double, 9, 1> out = Eigen::Matrix<double, 9, 1>::Zero();
    for (int n = 0; n < support.width; ++n) {
      const int v = np.variableIndex(k + support.node_offset + n);
      if (v >= 0) out.segment<3>(3 * n) = of.segment<3>(v);
    }
    return out;
  }
  Eigen::Matrix<double, 9, 1> localPart(int k) const { return localPart(k, direction); }

  /// forEachTerms at the current h; returns the instances visited.
  int checkAtFixedTimeStep() const {
    const double h = np.timeStep(), e = 1e-6, e2 = 1e-4;
    const std::vector<Vector3> q0 = values(np);
    const std::vector<Vector3> up = values(moved(e, h)), down = values(moved(-e, h));
    const std::vector<Vector3> up2 = values(moved(e2, h)), down2 = values(moved(-e2, h));
    int visited = 0;
    quantity.forEachTerms(
        np, support, [&](int, const Vector3&) { return lambda; },
        [&](const QuantityTerms& t) {
          const int i = t.k - support.first_k;
          const std::string where = "k = " + std::to_string(t.k);
          ++visited;
          EXPECT_LE((t.value - q0[i]).norm(), value_tolerance * (1 + q0[i].norm())) << where;
          const Eigen::Matrix<double, 9, 1> d = localPart(t.k);
          const Vector3 slope = t.jacobian * d, fd = (up[i] - down[i]) / (2 * e);
          EXPECT_LE((slope - fd).norm(), 1e-6 * (1 + fd.norm())) << where;
          // d²/dα² λᵀq(R exp(α d)) = dᵀ(Σ λ_i ∇²q_i)d: the retraction is a straight line in δ.
          const double second = d.dot(t.curvature * d);
          const double fd2 = contracted.dot(up2[i] - 2 * q0[i] + down2[i]) / (e2 * e2);
          EXPECT_NEAR(second, fd2, 1e-5 * (1 + std::abs(fd2))) << where;
        });
    return visited;
  }

  /// The curvature times the direction against mixed central differences: for `count` seeded
  /// random directions e of the node unknowns, eᵀ(Σ λ_i ∇²q_i)d = ∂²(λᵀq)/∂α∂β of
  /// q(R exp((α d + β e)^)) at 0 (exponential coordinates at the iterate, as the terms are), which
  /// holds the Hessian–vector product along every e (dᵀH d alone, checkAtFixedTimeStep's, sees only
  /// the symmetric part of H along d). Returns the products checked.
  int checkCurvatureTimesDirection(int count, unsigned seed) const {
    const double h = np.timeStep(), e = 1e-4;
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal;
    int checked = 0;
    for (int j = 0; j < count; ++j) {
      Eigen::VectorXd other(direction.size());
      for (int i = 0; i < other.size(); ++i) other(i) = normal(rng);
      const auto at = [&](double a, double b) {
        ReducedProblem out = np;
        out.setTimeStep(h);
        out.setCurrent(out.retract(a * direction + b * other, 1.0));
        return values(out);
      };
      // The mixed difference at steps e and e/2, extrapolated (Richardson): its O(e²) truncation
      // error, visible on the wheels' quartic ½|q|², goes.
      const auto mixed = [&](double step) {
        const std::vector<Vector3> pp = at(step, step), pm = at(step, -step), mp = at(-step, step),
                                   mm = at(-step, -step);
        std::vector<double> out;
        for (std::size_t i = 0; i < pp.size(); ++i)
          out.push_back(contracted.dot(pp[i] - pm[i] - mp[i] + mm[i]) / (4 * step * step));
        return out;
      };
      const std::vector<double> coarse = mixed(e), fine = mixed(e / 2);
      quantity.forEachTerms(
          np, support, [&](int, const Vector3&) { return lambda; },
          [&](const QuantityTerms& t) {
            const int i = t.k - support.first_k;
            // The lower triangle, as the band reads it (BandedSymmetric::addSymmetricBlock).
            const Eigen::Matrix<double, 9, 1> product =
                t.curvature.template selfadjointView<Eigen::Lower>() * localPart(t.k, direction);
            const double fd = (4 * fine[i] - coarse[i]) / 3;
            EXPECT_NEAR(localPart(t.k, other).dot(product), fd, 1e-5 * (1 + std::abs(fd)))
                << "k = " << t.k << ", direction " << j;
            ++checked;
          });
    }
    return checked;
  }

  /// forEachTermsWithTimeStep with η = h/scale; returns the instances visited.
  int checkWithTimeStep(double scale) const {
    const double h = np.timeStep(), dh = 1e-5 * h, e = 1e-4, fine = 1e-6;
    const std::vector<Vector3> q0 = values(np);
    const std::vector<Vector3> later = values(moved(0, h + dh)), earlier = values(moved(0, h - dh));
    // Mixed: λᵀq at (α, h) = (±e, h ± dh).
    const std::vector<Vector3> pp = values(moved(e, h + dh)), pm = values(moved(e, h - dh)),
                               mp = values(moved(-e, h + dh)), mm = values(moved(-e, h - dh));
    const std::vector<Vector3> up = values(moved(e, h)), down = values(moved(-e, h));
    // The slope from the fine differences (the coarse ones, for the curvature, carry an O(e²)
    // truncation error a quantity's third derivative can make visible).
    const std::vector<Vector3> fine_up = values(moved(fine, h)),
                               fine_down = values(moved(-fine, h));
    int visited = 0;
    quantity.forEachTermsWithTimeStep(
        np, support, scale, [&](int, const Vector3&) { return lambda; },
        [&](const QuantityTermsWithTimeStep& t) {
          const int i = t.k - support.first_k;
          const std::string where = "k = " + std::to_string(t.k);
          ++visited;
          EXPECT_LE((t.value - q0[i]).norm(), value_tolerance * (1 + q0[i].norm())) << where;
          const Vector3 fd_h = (later[i] - earlier[i]) / (2 * dh);
          const Vector3 in_h = t.jacobian.col(9) / scale;
          EXPECT_LE((in_h - fd_h).norm(), 1e-6 * (1 + fd_h.norm())) << where;
          if (!quantity.dependsOnTimeStep()) {
            EXPECT_EQ(in_h.norm(), 0.0) << where;
          }
          Eigen::Matrix<double, 10, 1> d = Eigen::Matrix<double, 10, 1>::Zero();
          d.head<9>() = localPart(t.k);
          const Vector3 slope = t.jacobian * d, fd = (fine_up[i] - fine_down[i]) / (2 * fine);
          EXPECT_LE((slope - fd).norm(), 1e-6 * (1 + fd.norm())) << where;
          const double second = d.dot(t.curvature * d);  // h entry of d is 0: the δδ block
          const double fd2 = contracted.dot(up[i] - 2 * q0[i] + down[i]) / (e * e);
          EXPECT_NEAR(second, fd2, 1e-5 * (1 + std::abs(fd2))) << where;
          const double fd_hh = contracted.dot(later[i] - 2 * q0[i] + earlier[i]) / (dh * dh);
          EXPECT_NEAR(t.curvature(9, 9) / (scale * scale), fd_hh, 1e-4 * (1 + std::abs(fd_hh)))
              << where;
          const double fd_mixed = contracted.dot(pp[i] - pm[i] - mp[i] + mm[i]) / (4 * e * dh);
          const double mixed = d.head<9>().dot(t.curvature.block<9, 1>(0, 9)) / scale;
          EXPECT_NEAR(mixed, fd_mixed, 1e-4 * (1 + std::abs(fd_mixed))) << where;
        });
    return visited;
  }
};

}  // namespace attitude_planner::test_support
