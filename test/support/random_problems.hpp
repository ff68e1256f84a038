// A seeded generator of random planning problems, shared by the CI-sized gtest
// (test/unit/test_random_suite.cpp) and the full-size study (benchmark_solvers --random-suite,
// run by scripts/robustness --random, which writes the table in docs/results/robustness.md).
//
// Each case draws, from its own seed (so any case can be re-planned alone):
//   inertia     physical (J = tr(S) I − S for a random second moment S ≻ 0 — the triangle
//               inequality holds by construction — scale 0.1…100 kg m², random orientation) or
//               seed-like (the seed's principal moments 3.15, 12.5, 32.2 kg m², each × e^{0.2 n},
//               randomly rotated: strongly anisotropic and nonphysical, like the seed's J)
//   attitudes   R_0, R_N uniform on SO(3)
//   rates       Ω_0, Ω_{N−1} uniform in direction, |Ω| uniform in [0, 5] rad/s (zero with
//               probability 1/5 each)
//   horizon     T log-uniform in [0.5, 100] s
//   steps       N from {64, 128, 256}, raised until h·max(|Ω_0|, |Ω_{N−1}|) ≤ 0.5
//   scheme      paper and variational alternately (even index: paper)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {
namespace robustness {

/// Which family an inertia was drawn from.
enum class InertiaFamily { Physical, SeedLike };

/// One generated problem.
struct RandomCase {
  int index = 0;           ///< position in the suite
  std::uint64_t seed = 0;  ///< the case's own seed (randomCase(seed, index) reproduces it)
  InertiaFamily family = InertiaFamily::Physical;
  PlanningProblem problem;
  std::string label;  ///< e.g. "#3 seed-like paper T=12.3 s N=256 |Ω0|=4.1 |ΩN|=0"
};

/// The largest h·|Ω| at either end the generator allows [rad].
constexpr double kMaxBoundaryStepAngle = 0.5;
/// The largest boundary rate [rad/s] and horizon [s] it draws.
constexpr double kMaxBoundaryRate = 5.0;
constexpr double kMaxHorizon = 100.0;

/// Case `index` of the suite seeded with `suite_seed` (deterministic across platforms: only
/// std::mt19937_64 and explicit transforms, no std::*_distribution).
RandomCase randomCase(std::uint64_t suite_seed, int index);

/// Cases 0..count−1 of the suite seeded with `suite_seed`.
std::vector<RandomCase> randomSuite(std::uint64_t suite_seed, int count);

/// "physical" or "seed-like".
std::string inertiaFamilyName(InertiaFamily family);

}  // namespace robustness
}  // namespace attitude_planner
