// Small tools the studies (studies/*.cpp) share: wall time, median, the machine's load average,
// and the `--flag value` command line.
#pragma once

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace attitude_planner::study {

/// Wall time since `since` [s].
inline double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// The median of `v` (0 if empty).
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// `v` printed with the printf `format` (e.g. "%.3g").
inline std::string formatted(double v, const char* format) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

/// The 1, 5 and 15 min load averages, "%.2f %.2f %.2f" (−1 each if /proc/loadavg is unreadable).
inline std::string loadAverage() {
  double a[3] = {-1, -1, -1};
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf %lf %lf", &a[0], &a[1], &a[2]) != 3) a[0] = a[1] = a[2] = -1;
    std::fclose(f);
  }
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.2f %.2f %.2f", a[0], a[1], a[2]);
  return buffer;
}

/// A study's command line that cannot be read; the message names the flag and the value.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `value` of `flag` as a whole number of type `Integer`: all of it, in the type's range (a seed
/// is unsigned, so "-1" is refused rather than wrapped).
template <class Integer>
Integer integerFlag(const std::string& flag, const std::string& value) {
  Integer parsed{};
  const char* end = value.data() + value.size();
  const auto [stop, error] = std::from_chars(value.data(), end, parsed);
  if (value.empty() || error != std::errc() || stop != end) {
    throw UsageError(flag + " " + value + ": not a whole number in [" +
                     std::to_string(std::numeric_limits<Integer>::min()) + ", " +
                     std::to_string(std::numeric_limits<Integer>::max()) + "]");
  }
  return parsed;
}

/// `value` of `flag` as comma-separated numbers ("1.5,2"), each one `accepts`; `what` says what
/// they must be in the usage error that names the item refused.
inline std::vector<double> numberListFlag(const std::string& flag, const std::string& value,
                                          const std::function<bool(double)>& accepts,
                                          const std::string& what) {
  std::vector<double> out;
  std::stringstream in(value);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0' || !accepts(x)) {
      throw UsageError(flag + ": '" + item + "' is not " + what);
    }
    out.push_back(x);
  }
  return out;
}

/// The `--flag value` pairs of a study's command line, each bound to the option it sets (which
/// keeps its default when the flag is absent). Unknown flags and a flag without a value are
/// usage errors, never ignored: a mistyped flag would otherwise run the default study silently.
class FlagReader {
 public:
  template <class Integer>
  FlagReader& add(const std::string& flag, Integer* target) {
    setters_[flag] = [flag, target](const std::string& v) {
      *target = integerFlag<Integer>(flag, v);
    };
    return *this;
  }
  FlagReader& add(const std::string& flag, std::string* target) {
    setters_[flag] = [target](const std::string& v) { *target = v; };
    return *this;
  }
  /// A list of numbers (numberListFlag).
  FlagReader& add(const std::string& flag, std::vector<double>* target,
                  std::function<bool(double)> accepts, std::string what) {
    setters_[flag] = [flag, target, accepts, what](const std::string& v) {
      *target = numberListFlag(flag, v, accepts, what);
    };
    return *this;
  }
  /// `flag` must be given (it has no default).
  FlagReader& require(const std::string& flag) {
    required_.insert(flag);
    return *this;
  }

  /// Sets the options from `argv`; throws UsageError.
  void read(int argc, char** argv) const {
    std::set<std::string> missing = required_;
    for (int i = 1; i < argc; i += 2) {
      const std::string flag = argv[i];
      const auto setter = setters_.find(flag);
      if (setter == setters_.end()) throw UsageError("unknown flag " + flag);
      if (i + 1 == argc) throw UsageError(flag + " needs a value");
      setter->second(argv[i + 1]);
      missing.erase(flag);
    }
    if (!missing.empty()) throw UsageError(*missing.begin() + " is required");
  }

 private:
  std::map<std::string, std::function<void(const std::string&)>> setters_;
  std::set<std::string> required_;
};

/// `reader.read(argc, argv)`, and on a usage error "`program`: error" and `usage` on stderr and
/// exit status 2, the same for every study.
inline void readFlagsOrExit(const FlagReader& reader, int argc, char** argv, const char* program,
                            const char* usage) {
  try {
    reader.read(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << program << ": " << e.what() << "\nusage: " << program << " " << usage << "\n";
    std::exit(2);
  }
}

}  // namespace attitude_planner::study
