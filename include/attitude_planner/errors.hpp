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

/// An error about one input field. The message is "field: detail"; the field is also kept apart
/// (empty when the thrower gave only a message), so an interface whose fields are spelt otherwise
/// (the ROS request's `initial_angular_velocity` for the scene's `initial.angular_velocity`) can
/// name its own field without parsing the message (ros/conversions.hpp, requestFieldName).
class FieldError : public std::runtime_error {
 public:
  explicit FieldError(const std::string& message) : std::runtime_error(message) {}
  FieldError(const std::string& field, const std::string& detail)
      : std::runtime_error(field + ": " + detail), field_(field), detail_(detail) {}
  /// The scene key / request path the error is about ("constraints[0].max_torque_norm"); empty
  /// if not given separately.
  const std::string& field() const { return field_; }
  /// The message without the field (empty if the field was not given separately).
  const std::string& detail() const { return detail_; }

 private:
  std::string field_;
  std::string detail_;
};

/// Bad user input: a scene key, a request field, a command-line flag.
class InvalidInput : public FieldError {
 public:
  using FieldError::FieldError;
};

/// The implicit step of a scheme has no solution the Newton iteration can find (h·|Ω| too large).
class StepTooLarge : public FieldError {
 public:
  using FieldError::FieldError;
};

}  // namespace attitude_planner
