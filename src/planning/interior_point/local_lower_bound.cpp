#include "planning/interior_point/local_lower_bound.hpp"

#include <sstream>

namespace attitude_planner {

bool cannotEndBelowLeast(const LocalLowerBound& at, double least) {
  return at.holds && at.lower_bound > least;
}

std::string cannotEndBelow(const LocalLowerBound& at, double least, std::string_view what) {
  if (!cannotEndBelowLeast(at, least)) return "";
  std::ostringstream why;
  why << "stopped at " << at.value << ": it can no longer end below " << least << ", " << what
      << " (its local lower bound " << at.lower_bound << ")";
  return why.str();
}

}  // namespace attitude_planner
