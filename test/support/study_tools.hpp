// Small tools the studies (studies/*.cpp) share: wall time, median, the machine's load average.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
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

}  // namespace attitude_planner::study
