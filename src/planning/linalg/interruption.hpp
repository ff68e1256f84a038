// A way for long linear-algebra loops to stop a solve promptly: a banded factorization at
// N = 1e5 in double-double takes most of a second, so a cancel or a deadline checked only
// between iterations would answer late. The loops call poll() every few hundred columns; an
// implementation throws to end the solve (problem/solve_context.hpp: SolveInterrupted).
#pragma once

namespace attitude_planner {

class Interruption {
 public:
  virtual ~Interruption() = default;
  /// Returns if the solve may go on; throws if it must stop now.
  virtual void poll() const = 0;
};

/// How many columns (or nodes) a long loop handles between two polls: a poll reads the clock
/// (~20 ns), a column of the band costs ~1 µs, so polling is invisible and stops within ~1 ms.
constexpr int kColumnsBetweenPolls = 256;

}  // namespace attitude_planner
