#include "attitude_planner/io/csv.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"

namespace attitude_planner {

namespace {
constexpr const char* kCsvHeader = "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz";

/// The header of writeManeuverCsv, with or without wheel columns (",u1,...,un,h1,...,hn").
bool isManeuverHeader(const std::string& line) {
  const std::string base = kCsvHeader;
  if (line.compare(0, base.size(), base) != 0) return false;
  if (line.size() == base.size()) return true;
  std::string expected = base;
  int n = 1;
  while (expected.size() < line.size()) {
    expected = base;
    for (const char* column : {"u", "h"})
      for (int i = 1; i <= n; ++i) expected += "," + std::string(column) + std::to_string(i);
    if (expected == line) return true;
    ++n;
  }
  return false;
}

/// The file's rows, each followed by `extra(k)` (empty, or ",..." columns) before the newline.
void writeRows(const Maneuver& m, const std::string& path, const std::string& header,
               const std::function<std::string(int)>& extra) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw InvalidInput("--csv: cannot write '" + path + "'");
  std::fprintf(file.get(), "%s\n", header.c_str());
  for (int k = 0; k <= m.steps(); ++k) {
    const Eigen::Quaterniond q = so3::toQuaternion(m.attitude[k]);
    const Vector3& w = m.angular_velocity[k];
    const Vector3& t = m.torque[k];
    std::fprintf(file.get(),
                 "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g%s\n", k,
                 m.time[k], q.w(), q.x(), q.y(), q.z(), w.x(), w.y(), w.z(), t.x(), t.y(), t.z(),
                 extra(k).c_str());
  }
}

}  // namespace

void writeManeuverCsv(const Maneuver& m, const std::string& path) {
  writeRows(m, path, kCsvHeader, [](int) { return std::string(); });
}

void writeManeuverCsv(const Maneuver& m, const WheelStates& wheels, const std::string& path) {
  const int n = wheels.momentum.empty() ? 0 : static_cast<int>(wheels.momentum[0].size());
  std::string header = kCsvHeader;
  for (const char* column : {"u", "h"})
    for (int i = 1; i <= n; ++i) header += "," + std::string(column) + std::to_string(i);
  writeRows(m, path, header, [&](int k) {
    std::string cells;
    for (const auto* values : {&wheels.torque[k], &wheels.momentum[k]})
      for (int i = 0; i < n; ++i) cells += "," + exactNumber((*values)(i));
    return cells;
  });
}

namespace {

/// Opens a maneuver CSV and reads its header (checked), which it returns.
std::string openManeuverCsv(const std::string& path, std::ifstream* in) {
  in->open(path);
  if (!*in) throw InvalidInput("maneuver CSV: cannot read '" + path + "'");
  std::string line;
  std::getline(*in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (!isManeuverHeader(line)) {
    throw InvalidInput("maneuver CSV '" + path + "': header is '" + line + "', expected '" +
                       kCsvHeader + "' (and wheel columns u1..un,h1..hn)");
  }
  return line;
}

}  // namespace

Maneuver readManeuverCsv(const std::string& path) {
  std::ifstream in;
  openManeuverCsv(path, &in);
  std::string line;
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
    // The scene's and the messages' quaternion rule (finite, unit within 1e-3), then normalized.
    m.attitude.push_back(attitudeFromQuaternion(
        Eigen::Vector4d(v[2], v[3], v[4], v[5]),
        "maneuver CSV '" + path + "' line " + std::to_string(line_number) + " (qw,qx,qy,qz)"));
    m.angular_velocity.emplace_back(v[6], v[7], v[8]);
    m.torque.emplace_back(v[9], v[10], v[11]);
  }
  if (m.time.size() < 2) throw InvalidInput("maneuver CSV '" + path + "': fewer than 2 rows");
  m.time_step = m.time[1] - m.time[0];
  return m;
}

std::vector<Eigen::VectorXd> readWheelTorquesCsv(const std::string& path) {
  std::ifstream in;
  std::string line = openManeuverCsv(path, &in);
  // 12 plan columns, then n torques and n momenta.
  const int n = static_cast<int>((std::count(line.begin(), line.end(), ',') + 1 - 12) / 2);
  std::vector<Eigen::VectorXd> out;
  if (n == 0) return out;
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string cell;
    Eigen::VectorXd u(n);
    for (int column = 0; column < 12 + n; ++column) {
      if (!std::getline(ss, cell, ',')) {
        throw InvalidInput("maneuver CSV '" + path + "' line " + std::to_string(line_number) +
                           ": expected " + std::to_string(12 + 2 * n) + " columns");
      }
      if (column < 12) continue;
      try {
        u(column - 12) = std::stod(cell);
      } catch (const std::exception&) {
        throw InvalidInput("maneuver CSV '" + path + "' line " + std::to_string(line_number) +
                           ": column u" + std::to_string(column - 11) + " is not a number: '" +
                           cell + "'");
      }
    }
    out.push_back(u);
  }
  return out;
}

void writeDriftTwoInputCsv(const DriftTwoInputTrajectory& tr, const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw InvalidInput("--csv: cannot write '" + path + "'");
  std::fprintf(file.get(), "%s\n", kDriftTwoInputCsvHeader);
  for (std::size_t k = 0; k < tr.g.size(); ++k) {
    const Eigen::Quaterniond q = so3::toQuaternion(tr.g[k]);
    const Eigen::Vector2d& u = tr.u[k];
    const Vector3& p = tr.p[k];
    std::fprintf(file.get(), "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k,
                 tr.t[k], q.w(), q.x(), q.y(), q.z(), u.x(), u.y(), p.x(), p.y(), p.z());
  }
  if (std::fflush(file.get()) != 0) throw InvalidInput("--csv: cannot write '" + path + "'");
}

}  // namespace attitude_planner
