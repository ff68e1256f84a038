// A solve against the least answer another start holds: where an interior point's barrier Newton
// matrix is definite (locally convex), weak duality bounds below what the solve can still reach,
// so a start whose bound lies above the least answer held cannot beat it and may be stopped. Free
// time's solved barrier problems (BarrierPoint: T) and the fixed-h interior point's feasible
// iterates (FeasibleIterate: C) both carry such a bound; every watch stops by the one rule here.
#pragma once

#include <limits>
#include <string>
#include <string_view>

namespace attitude_planner {

/// An iterate's objective and the local lower bound below which its solve cannot end, where the
/// bound holds (`holds`: locally convex there); elsewhere the solve may still slide lower.
struct LocalLowerBound {
  double value = 0.0;
  double lower_bound = -std::numeric_limits<double>::infinity();
  bool holds = false;
};

/// Whether a solve at `at` cannot end below `least`, the least answer held: the bound holds there
/// and lies above `least` (never while `least` is +∞ or NaN). The one rule every watch stops by.
bool cannotEndBelowLeast(const LocalLowerBound& at, double least);

/// Why a solve at `at` cannot end below `least`, the least answer held (`what` names it), or empty
/// where it still can: the bound does not hold, or lies at or below `least` (always while `least`
/// is +∞ or NaN).
std::string cannotEndBelow(const LocalLowerBound& at, double least, std::string_view what);

}  // namespace attitude_planner
