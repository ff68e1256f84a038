// The references the seeded bounded suite's bounds are fractions of
// (test/support/bounded_requests.hpp), stored as data so that a request is a function of (seed,
// index) alone: no change of the planner moves a request. Each reference is the unbounded
// minimum-effort plan of the suite's random case (robustness::randomCase) as some library planned
// it once: its peaks, and its state at the re-plan node. The repository's file,
// test/data/bounded_references.csv, holds the seeds its tests and studies use;
// `scripts/bounded_references` regenerates it (that library's plans); a held-out seed's references
// go to a file outside the repository, named by AP_BOUNDED_REFERENCES.
#pragma once

#include <cstdint>
#include <string>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {
namespace robustness {

struct BoundedReference {
  std::uint64_t seed = 0;
  int index = 0;
  /// The random case's duration, step count and boundary rates: an entry whose case no longer
  /// draws these is stale.
  double duration = 0.0;
  int steps = 0;
  double initial_rate = 0.0, final_rate = 0.0;
  bool converged = false;    ///< whether the unbounded plan converged (no: no request)
  double peak_torque = 0.0;  ///< max_k |τ_k|
  Vector3 peak_axis_torque = Vector3::Zero();   ///< max_k |τ_k,i| per axis
  double peak_rate = 0.0;                       ///< max_k |Ω_k|
  int rest_node = 0;                            ///< the re-plan's first node, N/3
  Matrix3 rest_attitude = Matrix3::Identity();  ///< R at the re-plan node
  Vector3 rest_rate = Vector3::Zero();          ///< Ω at the re-plan node
  double rest_peak_torque = 0.0;                ///< max_k |τ_k| from the re-plan node on
};

/// The file references are read from: $AP_BOUNDED_REFERENCES if set, else the repository's
/// test/data/bounded_references.csv.
std::string boundedReferencesPath();

/// The stored reference of request `index` of the suite seeded `seed`, read from `path`. Throws
/// std::runtime_error naming the seed, the index and the file where the file has no entry for
/// it or the entry is stale (its random case now draws another duration, N or boundary rate).
BoundedReference storedReference(std::uint64_t seed, int index,
                                 const std::string& path = boundedReferencesPath());

/// The reference as this library computes it (the unbounded plan of the random case).
BoundedReference computedReference(std::uint64_t seed, int index);

/// Writes the references of `seed`'s requests 0..count−1 (computed by this library) into `path`,
/// keeping the entries of other seeds.
void writeReferences(std::uint64_t seed, int count, const std::string& path);

}  // namespace robustness
}  // namespace attitude_planner
