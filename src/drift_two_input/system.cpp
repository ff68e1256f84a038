// Extremal flow of Remsing's drift + two-input system (seed 001, eqs. 3.8, 3.15–3.17).
#include "attitude_planner/drift_two_input/system.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/input_rules.hpp"

namespace attitude_planner {

void validateDriftTwoInputWeights(const DriftTwoInputWeights& w) {
  for (const auto& [name, value] : {std::pair<const char*, double>{"c1", w.c1}, {"c2", w.c2}}) {
    if (!std::isfinite(value) || value <= 0.0) {
      std::ostringstream os;
      os << "cost weight " << name << " must be finite and > 0, got " << value;
      throw InvalidInput(os.str());
    }
  }
}

void validateDriftTwoInputExtremalInputs(const DriftTwoInputWeights& w, double T, int steps,
                                         const Vector3& p0) {
  validateDriftTwoInputWeights(w);
  requireDuration(T, "duration");
  if (steps < 1) throw InvalidInput("steps must be >= 1, got " + std::to_string(steps));
  if (!p0.allFinite()) throw InvalidInput("initial costate p0 must be finite");
}

DriftTwoInputTrajectory integrateDriftTwoInputExtremal(const Matrix3& g0, const Vector3& p0,
                                                       double T, int steps,
                                                       const DriftTwoInputWeights& w,
                                                       const DriftTwoInputIntegration& opts) {
  validateDriftTwoInputExtremalInputs(w, T, steps, p0);
  if (opts.substeps < 1) {
    throw InvalidInput("substeps must be >= 1, got " + std::to_string(opts.substeps));
  }
  if (opts.order != 2 && opts.order != 4) {
    throw InvalidInput("order must be 2 or 4, got " + std::to_string(opts.order));
  }

  DriftTwoInputTrajectory out;
  out.t.reserve(steps + 1);
  out.p.reserve(steps + 1);
  out.g.reserve(steps + 1);
  out.u.reserve(steps + 1);
  Matrix3 g = g0;
  Vector3 p = p0;
  const double h = T / (static_cast<double>(steps) * opts.substeps);
  auto record = [&](int k) {
    out.t.push_back(T * k / steps);
    out.p.push_back(p);
    out.g.push_back(g);
    out.u.emplace_back(p.x() / w.c1, p.y() / w.c2);
  };
  record(0);
  for (int k = 1; k <= steps; ++k) {
    for (int j = 0; j < opts.substeps; ++j) {
      double dc = 0.0;
      if (!drift_two_input::stepOfOrder<double>(g, p, h, w, opts.order, &dc)) {
        std::ostringstream os;
        os << "implicit midpoint step " << k << " (h = " << h << " s, |p| = " << p.norm()
           << ") did not converge: reduce the step";
        throw StepTooLarge(os.str());
      }
      out.cost += dc;
    }
    record(k);
  }
  return out;
}

namespace {

/// The replay's control between samples: Lagrange interpolation of u through the `points`
/// samples first..first+points−1 at time s.
Eigen::Vector2d cubicControl(const std::vector<double>& t, const std::vector<Eigen::Vector2d>& u,
                             int first, int points, double s) {
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  for (int i = first; i < first + points; ++i) {
    double l = 1.0;
    for (int j = first; j < first + points; ++j) {
      if (j != i) l *= (s - t[j]) / (t[i] - t[j]);
    }
    v += l * u[i];
  }
  return v;
}

/// The first of the (up to) 4 samples whose cubic drives interval k, and how many there are.
std::pair<int, int> cubicWindow(int k, int n) {
  const int points = std::min(4, n);  // cubic through the 4 nearest samples
  return {std::max(0, std::min(k - 1, n - points)), points};
}

/// `substeps` fourth-order Magnus steps of ġ = g(E3 + u1 E1 + u2 E2) over [from, to] of interval
/// k's cubic, starting at g.
Matrix3 magnusSteps(Matrix3 g, const std::vector<double>& t, const std::vector<Eigen::Vector2d>& u,
                    int k, double from, double to, int substeps) {
  const auto [first, points] = cubicWindow(k, static_cast<int>(t.size()));
  auto xi = [&](double s) {
    const Eigen::Vector2d c = cubicControl(t, u, first, points, s);
    return Vector3(c.x(), c.y(), 1.0);  // body rate E3 + u1 E1 + u2 E2 [rad/s]
  };
  constexpr double kGaussOffset = 0.28867513459481287;  // √3/6
  constexpr double kCommutator = 0.14433756729740643;   // √3/12
  const double hs = (to - from) / substeps;
  for (int j = 0; j < substeps; ++j) {
    const double s0 = from + j * hs;
    const Vector3 a = xi(s0 + (0.5 - kGaussOffset) * hs);
    const Vector3 b = xi(s0 + (0.5 + kGaussOffset) * hs);
    // Fourth-order Magnus for the right-invariant form ġ = g ξ^: Ω = s/2 (a + b) + √3/12 s² a × b
    const Vector3 omega = 0.5 * hs * (a + b) + kCommutator * hs * hs * a.cross(b);
    g = g * so3::exp(omega);
  }
  return g;
}

}  // namespace

std::vector<Matrix3> replayDriftTwoInputControls(const Matrix3& g0, const std::vector<double>& t,
                                                 const std::vector<Eigen::Vector2d>& u,
                                                 int substeps) {
  const int n = static_cast<int>(t.size());
  if (n < 1 || u.size() != t.size()) {
    throw InvalidInput("replay: need as many controls as sample times (>= 1), got " +
                       std::to_string(u.size()) + " controls and " + std::to_string(n) + " times");
  }
  if (substeps < 1) throw InvalidInput("replay: substeps must be >= 1");
  for (int k = 0; k < n; ++k) {
    if (!std::isfinite(t[k]) || !u[k].allFinite()) {
      throw InvalidInput("replay: sample " + std::to_string(k) + " is not finite");
    }
    if (k > 0 && !(t[k] > t[k - 1])) {
      throw InvalidInput("replay: sample times must increase (t[" + std::to_string(k) + "] <= t[" +
                         std::to_string(k - 1) + "])");
    }
  }
  std::vector<Matrix3> g(n);
  g[0] = g0;
  for (int k = 0; k + 1 < n; ++k) {
    g[k + 1] = so3::projectToSO3(magnusSteps(g[k], t, u, k, t[k], t[k + 1], substeps));
  }
  return g;
}

DriftTwoInputReplaySample replayedDriftTwoInputAt(const std::vector<Matrix3>& g,
                                                  const std::vector<double>& t,
                                                  const std::vector<Eigen::Vector2d>& u, double s,
                                                  int substeps) {
  const int n = static_cast<int>(t.size());
  if (n < 1 || u.size() != t.size() || g.size() != t.size()) {
    throw InvalidInput("replayedDriftTwoInputAt: need as many attitudes and controls as times");
  }
  s = std::clamp(s, t.front(), t.back());
  int k = static_cast<int>(std::upper_bound(t.begin(), t.end(), s) - t.begin()) - 1;
  k = std::clamp(k, 0, n - 1);
  DriftTwoInputReplaySample out;
  if (s == t[k] || k == n - 1) {  // a sample itself: the replay's own row
    out.g = g[k];
    out.u = u[k];
    return out;
  }
  out.g = so3::projectToSO3(magnusSteps(g[k], t, u, k, t[k], s, substeps));
  const auto [first, points] = cubicWindow(k, n);
  out.u = cubicControl(t, u, first, points, s);
  return out;
}

}  // namespace attitude_planner
