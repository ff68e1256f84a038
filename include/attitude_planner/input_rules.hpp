// Rules on input values that more than one layer applies (the rigid-body problem and the drift +
// two-input request): written once here, so every entry point refuses a value with one message.
#pragma once

#include <cmath>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

/// Throws InvalidInput naming `field` and the value unless T is a finite number > 0 [s].
inline void requireDuration(double duration, const std::string& field) {
  if (!std::isfinite(duration) || !(duration > 0.0)) {
    throw InvalidInput(field + ": must be a finite number > 0 s, got " + exactNumber(duration));
  }
}

}  // namespace attitude_planner
