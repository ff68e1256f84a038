// Error types of the core. Every message names the field (or step) and the offending value.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>

namespace attitude_planner {

/// A number as messages, scenes and JSON spell it: %.17g, so every double round-trips and a
/// message shows the value exactly as given (NaN and Inf as nan, inf).
inline std::string exactNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

/// Bad user input: a scene key, a request field, a command-line flag.
class InvalidInput : public std::runtime_error {
 public:
  explicit InvalidInput(const std::string& message) : std::runtime_error(message) {}
};

/// The implicit step of a scheme has no solution the Newton iteration can find (h·|Ω| too large).
class StepTooLarge : public std::runtime_error {
 public:
  explicit StepTooLarge(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace attitude_planner
