// Name tables: the one place where the values of an enumeration meet the names users type (scene
// keys, command-line flag values, request fields, JSON). Each enumeration declares one table next
// to itself, and its xName / parseX are generated from it, as is the list of accepted names in
// every error message: adding a name is adding one row.
#pragma once

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

/// One row of a name table: a value and the one name it is spelled with.
template <class Enum>
struct NamedValue {
  Enum value;
  const char* name;
};

/// "a", "a or b", "a, b or c": a list of names as messages spell it.
inline std::string oneOf(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
    text += names[i];
  }
  return text;
}

/// The names of a table, in table order.
template <class Enum, std::size_t N>
std::vector<std::string> namesOf(const NamedValue<Enum> (&table)[N]) {
  std::vector<std::string> names;
  for (const NamedValue<Enum>& row : table) names.emplace_back(row.name);
  return names;
}

/// The value named `text`, or nothing.
template <class Enum, std::size_t N>
std::optional<Enum> findByName(const NamedValue<Enum> (&table)[N], const std::string& text) {
  for (const NamedValue<Enum>& row : table) {
    if (text == row.name) return row.value;
  }
  return std::nullopt;
}

/// The name of `value`. A value without a row is a programming error (std::logic_error).
template <class Enum, std::size_t N>
std::string nameIn(const NamedValue<Enum> (&table)[N], Enum value) {
  for (const NamedValue<Enum>& row : table) {
    if (row.value == value) return row.name;
  }
  throw std::logic_error("name table: value " + std::to_string(static_cast<long>(value)) +
                         " has no name");
}

/// The value named `text`; otherwise throws InvalidInput naming `field` and `text` and listing
/// the accepted names: "<field>: unknown value '<text>' (expected a, b or c)".
template <class Enum, std::size_t N>
Enum parseIn(const NamedValue<Enum> (&table)[N], const std::string& text,
             const std::string& field) {
  if (const std::optional<Enum> value = findByName(table, text)) return *value;
  throw InvalidInput(field + ": unknown value '" + text + "' (expected " + oneOf(namesOf(table)) +
                     ")");
}

}  // namespace attitude_planner
