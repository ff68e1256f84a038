#include "support/random_problems.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {
namespace robustness {

namespace {

/// Explicit transforms of the raw 64-bit stream: std::*_distribution differ between standard
/// libraries, and a shipped suite must draw the same cases everywhere.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1).
  double uniform() { return (engine_() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  /// Standard normal (Box–Muller).
  double normal() {
    const double u = 1.0 - uniform();  // (0, 1]
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * uniform());
  }
  Vector3 normal3() { return Vector3(normal(), normal(), normal()); }
  Vector3 direction() {
    Vector3 v = normal3();
    while (v.norm() < 1e-6) v = normal3();
    return v.normalized();
  }
  /// Uniform on SO(3): a normalized Gaussian quaternion.
  Matrix3 rotation() {
    Eigen::Vector4d q(normal(), normal(), normal(), normal());
    while (q.norm() < 1e-6) q = Eigen::Vector4d(normal(), normal(), normal(), normal());
    q.normalize();
    return Eigen::Quaterniond(q(0), q(1), q(2), q(3)).toRotationMatrix();
  }

 private:
  std::mt19937_64 engine_;
};

/// Splits the suite seed into independent per-case seeds (SplitMix64 finalizer).
std::uint64_t caseSeed(std::uint64_t suite_seed, int index) {
  std::uint64_t z = suite_seed + 0x9E3779B97F4A7C15ULL * (static_cast<std::uint64_t>(index) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

std::string inertiaFamilyName(InertiaFamily family) {
  return family == InertiaFamily::Physical ? "physical" : "seed-like";
}

RandomCase randomCase(std::uint64_t suite_seed, int index) {
  RandomCase c;
  c.index = index;
  c.seed = caseSeed(suite_seed, index);
  Draw draw(c.seed);
  PlanningProblem& p = c.problem;
  c.family = draw.uniform() < 0.5 ? InertiaFamily::Physical : InertiaFamily::SeedLike;
  const Matrix3 Q = draw.rotation();
  Vector3 moments;
  if (c.family == InertiaFamily::Physical) {
    // J = tr(S) I − S, S = diag(s) ⪰ 0: J_i = s_j + s_k, so J_i + J_j ≥ J_k always.
    const double scale = std::exp(draw.uniform(std::log(0.1), std::log(100.0)));
    const Vector3 s(draw.uniform(0.05, 1.0), draw.uniform(0.05, 1.0), draw.uniform(0.05, 1.0));
    moments = scale * Vector3(s(1) + s(2), s(0) + s(2), s(0) + s(1));
  } else {
    moments = Vector3(3.145834, 12.537921, 32.186245);  // the seed's principal moments
    for (int i = 0; i < 3; ++i) moments(i) *= std::exp(0.2 * draw.normal());
    p.allow_nonphysical_inertia = true;
  }
  p.inertia = Q * moments.asDiagonal() * Q.transpose();
  p.inertia = 0.5 * (p.inertia + p.inertia.transpose()).eval();  // exactly symmetric
  p.initial_attitude = draw.rotation();
  p.final_attitude = draw.rotation();
  const auto rate = [&draw] {
    if (draw.uniform() < 0.2) return Vector3(Vector3::Zero());
    return Vector3(draw.uniform(0.0, kMaxBoundaryRate) * draw.direction());
  };
  p.initial_velocity = rate();
  p.final_velocity = rate();
  p.duration = std::exp(draw.uniform(std::log(0.5), std::log(kMaxHorizon)));
  static const int kBaseSteps[] = {64, 128, 256};
  p.steps = kBaseSteps[std::min(2, static_cast<int>(3 * draw.uniform()))];
  const double fastest = std::max(p.initial_velocity.norm(), p.final_velocity.norm());
  p.steps =
      std::max(p.steps, static_cast<int>(std::ceil(p.duration * fastest / kMaxBoundaryStepAngle)));
  p.scheme = index % 2 == 0 ? SchemeKind::Paper : SchemeKind::Variational;
  char label[200];
  std::snprintf(label, sizeof label, "#%d %s %s T=%.3g s N=%d |W0|=%.2g |WN|=%.2g", index,
                inertiaFamilyName(c.family).c_str(), schemeName(p.scheme).c_str(), p.duration,
                p.steps, p.initial_velocity.norm(), p.final_velocity.norm());
  c.label = label;
  return c;
}

std::vector<RandomCase> randomSuite(std::uint64_t suite_seed, int count) {
  std::vector<RandomCase> out;
  out.reserve(count);
  for (int i = 0; i < count; ++i) out.push_back(randomCase(suite_seed, i));
  return out;
}

}  // namespace robustness
}  // namespace attitude_planner
