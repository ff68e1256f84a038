// What the command-line tools share: how a malformed command line, a bad value and a failed run
// reach the user, and the exit statuses they end with (0 done, 1 bad input or a failed run, 2 a
// malformed command line with the usage text). A header, not a tool: CMakeLists.txt builds one
// executable per src/tools/*.cpp.
#pragma once

#include <exception>
#include <iostream>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {
namespace tools {

/// A malformed command line (unknown option, missing value or argument): the usage text, exit 2.
struct UsageError {
  std::string message;
};

/// A flag whose value is invalid (not a number, NaN, out of range, unknown name): bad input like
/// a bad scene value, exit status 1, the message names the flag and the value.
struct InvalidFlagValue {
  std::string message;
};

/// The tool `name`'s main: `parse(argc, argv)` makes its arguments (with a `help` flag), `run`
/// their exit status; every error is printed once, prefixed by the tool's name.
template <class Parse, class Run>
int runTool(const char* name, const char* usage, int argc, char** argv, const Parse& parse,
            const Run& run) {
  decltype(parse(argc, argv)) args;
  try {
    args = parse(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << name << ": " << e.message << "\n\n" << usage;
    return 2;
  } catch (const InvalidFlagValue& e) {
    std::cerr << name << ": " << e.message << "\n";
    return 1;
  }
  if (args.help) {
    std::cout << usage;
    return 0;
  }
  try {
    return run(args);
  } catch (const InvalidInput& e) {
    std::cerr << name << ": invalid input: " << e.what() << "\n";
  } catch (const StepTooLarge& e) {  // says what to change itself
    std::cerr << name << ": " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << name << ": error: " << e.what() << "\n";
  }
  return 1;
}

}  // namespace tools
}  // namespace attitude_planner
