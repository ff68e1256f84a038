#include "attitude_planner/dynamics/maneuver.hpp"

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {
constexpr const char* kCsvHeader = "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz";
}

void writeManeuverCsv(const Maneuver& m, const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw InvalidInput("--csv: cannot write '" + path + "'");
  std::fprintf(file.get(), "%s\n", kCsvHeader);
  for (int k = 0; k <= m.steps(); ++k) {
    const Eigen::Quaterniond q = so3::toQuaternion(m.attitude[k]);
    const Vector3& w = m.angular_velocity[k];
    const Vector3& t = m.torque[k];
    std::fprintf(file.get(),
                 "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k,
                 m.time[k], q.w(), q.x(), q.y(), q.z(), w.x(), w.y(), w.z(), t.x(), t.y(), t.z());
  }
}

Maneuver readManeuverCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidInput("maneuver CSV: cannot read '" + path + "'");
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != kCsvHeader) {
    throw InvalidInput("maneuver CSV '" + path + "': header is '" + line + "', expected '" +
                       kCsvHeader + "'");
  }
  Maneuver m;
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string cell;
    double v[12];
    int n = 0;
    while (n < 12 && std::getline(ss, cell, ',')) {
      try {
        size_t used = 0;
        v[n] = std::stod(cell, &used);
        if (used != cell.size() && cell.substr(used).find_first_not_of(" \r") != std::string::npos)
          throw std::invalid_argument(cell);
      } catch (const std::exception&) {
        throw InvalidInput("maneuver CSV '" + path + "' line " + std::to_string(line_number) +
                           ": column " + std::to_string(n + 1) + " is not a number: '" + cell +
                           "'");
      }
      ++n;
    }
    if (n != 12) {
      throw InvalidInput("maneuver CSV '" + path + "' line " + std::to_string(line_number) +
                         ": expected 12 columns, got " + std::to_string(n));
    }
    if (static_cast<int>(v[0]) != static_cast<int>(m.time.size())) {
      throw InvalidInput("maneuver CSV '" + path + "' line " + std::to_string(line_number) +
                         ": k = " + std::to_string(static_cast<int>(v[0])) + " out of order");
    }
    m.time.push_back(v[1]);
    m.attitude.push_back(so3::fromQuaternion(Eigen::Quaterniond(v[2], v[3], v[4], v[5])));
    m.angular_velocity.emplace_back(v[6], v[7], v[8]);
    m.torque.emplace_back(v[9], v[10], v[11]);
  }
  if (m.time.size() < 2) throw InvalidInput("maneuver CSV '" + path + "': fewer than 2 rows");
  m.time_step = m.time[1] - m.time[0];
  return m;
}

}  // namespace attitude_planner

namespace attitude_planner {

std::vector<Matrix3> resampleAttitudes(const Maneuver& m, int steps) {
  const int n = m.steps();
  if (n < 1 || steps < 1) throw InvalidInput("resampleAttitudes: need at least one step");
  // Δ_i = log(R_iᵀ R_{i+1}); the body velocity (× step) at node i, in frame R_i: ½(Δ_{i−1} + Δ_i)
  // (a step's rotation vector is the same in both of its end frames).
  std::vector<Vector3> delta(n);
  for (int i = 0; i < n; ++i)
    delta[i] = so3::log(Matrix3(m.attitude[i].transpose() * m.attitude[i + 1]));
  const auto slope = [&](int i) {
    if (i <= 0) return delta[0];
    if (i >= n) return delta[n - 1];
    return Vector3(0.5 * (delta[i - 1] + delta[i]));
  };
  std::vector<Matrix3> out(steps + 1);
  for (int j = 0; j <= steps; ++j) {
    const double x = double(j) * n / steps;  // position in original steps
    int i = std::min(static_cast<int>(x), n - 1);
    const double s = x - i;
    // Hermite basis on [0, 1]: φ(0) = 0, φ'(0) = v_i, φ(1) = Δ_i, φ'(1) = v_{i+1} (frame R_i:
    // F_i leaves Δ_i fixed, and the slope at i+1 is rotated back by F_i).
    const Matrix3 F = so3::exp(delta[i]);
    const Vector3 v0 = slope(i), v1 = F * slope(i + 1);
    const double h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
                 h11 = s * s * s - s * s;
    out[j] = m.attitude[i] * so3::exp(Vector3(h10 * v0 + h01 * delta[i] + h11 * v1));
  }
  return out;
}

}  // namespace attitude_planner
