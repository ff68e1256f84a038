#include "support/bounded_references.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "support/random_problems.hpp"

namespace attitude_planner {
namespace robustness {

namespace {

using Key = std::pair<std::uint64_t, int>;
using References = std::map<Key, BoundedReference>;

constexpr const char* kRegenerate = "scripts/bounded_references";

double peakNorm(const std::vector<Vector3>& v) {
  double peak = 0.0;
  for (const Vector3& x : v) peak = std::max(peak, x.norm());
  return peak;
}

Vector3 peakPerAxis(const std::vector<Vector3>& v) {
  Vector3 peak = Vector3::Zero();
  for (const Vector3& x : v) peak = peak.cwiseMax(x.cwiseAbs());
  return peak;
}

/// The numbers of one entry in the file's column order (seed and index first).
std::vector<double> numbersOf(const BoundedReference& r) {
  std::vector<double> v = {r.duration,
                           static_cast<double>(r.steps),
                           r.initial_rate,
                           r.final_rate,
                           r.converged ? 1.0 : 0.0,
                           r.peak_torque,
                           r.peak_axis_torque.x(),
                           r.peak_axis_torque.y(),
                           r.peak_axis_torque.z(),
                           r.peak_rate,
                           static_cast<double>(r.rest_node)};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) v.push_back(r.rest_attitude(i, j));
  }
  for (int i = 0; i < 3; ++i) v.push_back(r.rest_rate(i));
  v.push_back(r.rest_peak_torque);
  return v;
}

constexpr std::size_t kNumbers = 24;

BoundedReference fromNumbers(std::uint64_t seed, int index, const std::vector<double>& v) {
  BoundedReference r;
  r.seed = seed;
  r.index = index;
  r.duration = v[0];
  r.steps = static_cast<int>(v[1]);
  r.initial_rate = v[2];
  r.final_rate = v[3];
  r.converged = v[4] != 0.0;
  r.peak_torque = v[5];
  r.peak_axis_torque = Vector3(v[6], v[7], v[8]);
  r.peak_rate = v[9];
  r.rest_node = static_cast<int>(v[10]);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.rest_attitude(i, j) = v[11 + 3 * i + j];
  }
  r.rest_rate = Vector3(v[20], v[21], v[22]);
  r.rest_peak_torque = v[23];
  return r;
}

std::string lineOf(const BoundedReference& r) {
  std::ostringstream out;
  out << r.seed << "," << r.index;
  char number[40];
  for (double x : numbersOf(r)) {
    std::snprintf(number, sizeof number, ",%.17g", x);
    out << number;
  }
  return out.str();
}

std::string headerLines() {
  std::string columns =
      "seed,index,duration,steps,initial_rate,final_rate,converged,peak_torque,peak_torque_x,"
      "peak_torque_y,peak_torque_z,peak_rate,rest_node";
  for (const char* c : {"R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22"}) {
    columns += std::string(",rest_") + c;
  }
  columns += ",rest_rate_x,rest_rate_y,rest_rate_z,rest_peak_torque";
  return std::string(
             "# The seeded bounded suite's references (test/support/bounded_references.hpp):\n"
             "# the unbounded minimum-effort plan of each random case, planned once.\n"
             "# Regenerate: ") +
         kRegenerate + "\n" + columns + "\n";
}

/// Entries of the file at `path` (none where it does not exist). Throws on a malformed line.
References readReferences(const std::string& path) {
  References refs;
  std::ifstream in(path);
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#' || line.rfind("seed,", 0) == 0) continue;
    std::istringstream fields(line);
    std::string field;
    std::vector<std::string> cells;
    while (std::getline(fields, field, ',')) cells.push_back(field);
    if (cells.size() != kNumbers + 2) {
      throw std::runtime_error(path + ":" + std::to_string(line_number) + ": " +
                               std::to_string(cells.size()) + " fields, expected " +
                               std::to_string(kNumbers + 2));
    }
    std::vector<double> v;
    for (std::size_t i = 2; i < cells.size(); ++i) v.push_back(std::stod(cells[i]));
    const std::uint64_t seed = std::stoull(cells[0]);
    const int index = std::stoi(cells[1]);
    refs[{seed, index}] = fromNumbers(seed, index, v);
  }
  return refs;
}

/// The file's entries, read once per path.
const References& cachedReferences(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, References> files;
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = files.find(path);
  if (it == files.end()) it = files.emplace(path, readReferences(path)).first;
  return it->second;
}

std::string caseFigures(double duration, int steps, double initial_rate, double final_rate) {
  char text[200];
  std::snprintf(text, sizeof text, "T = %.17g s, N = %d, |W0| = %.17g, |WN| = %.17g", duration,
                steps, initial_rate, final_rate);
  return text;
}

}  // namespace

std::string boundedReferencesPath() {
  const char* path = std::getenv("AP_BOUNDED_REFERENCES");
  if (path != nullptr && *path != '\0') return path;
  return AP_SOURCE_DIR "/test/data/bounded_references.csv";
}

BoundedReference storedReference(std::uint64_t seed, int index, const std::string& path) {
  const References& refs = cachedReferences(path);
  const std::string which =
      "bounded suite: seed " + std::to_string(seed) + " request " + std::to_string(index) + ": ";
  const auto it = refs.find({seed, index});
  if (it == refs.end()) {
    throw std::runtime_error(which + "no reference in " + path + " (add the seed with " +
                             kRegenerate + ", or name a file holding it in AP_BOUNDED_REFERENCES)");
  }
  const BoundedReference& r = it->second;
  const PlanningProblem p = randomCase(seed, index).problem;
  const std::string now =
      caseFigures(p.duration, p.steps, p.initial_velocity.norm(), p.final_velocity.norm());
  const std::string stored = caseFigures(r.duration, r.steps, r.initial_rate, r.final_rate);
  if (now != stored) {
    throw std::runtime_error(
        which + "the reference in " + path + " is stale: it was computed for " + stored +
        ", the random case now draws " + now + " (regenerate with " + kRegenerate + ")");
  }
  return r;
}

BoundedReference computedReference(std::uint64_t seed, int index) {
  const RandomCase base = randomCase(seed, index);
  BoundedReference r;
  r.seed = seed;
  r.index = index;
  r.duration = base.problem.duration;
  r.steps = base.problem.steps;
  r.initial_rate = base.problem.initial_velocity.norm();
  r.final_rate = base.problem.final_velocity.norm();
  PlanResult unbounded;
  try {
    unbounded = planManeuver(base.problem);
  } catch (const std::exception&) {
    return r;
  }
  if (!unbounded.converged()) return r;
  const Maneuver& plan = unbounded.maneuver;
  r.converged = true;
  r.peak_torque = peakNorm(plan.torque);
  r.peak_axis_torque = peakPerAxis(plan.torque);
  r.peak_rate = peakNorm(plan.angular_velocity);
  r.rest_node = plan.steps() / 3;
  r.rest_attitude = plan.attitude[r.rest_node];
  r.rest_rate = plan.angular_velocity[r.rest_node];
  r.rest_peak_torque =
      peakNorm(std::vector<Vector3>(plan.torque.begin() + r.rest_node, plan.torque.end()));
  return r;
}

void writeReferences(std::uint64_t seed, int count, const std::string& path) {
  References refs = readReferences(path);
  for (auto it = refs.begin(); it != refs.end();) {
    it = it->first.first == seed ? refs.erase(it) : std::next(it);
  }
  for (int i = 0; i < count; ++i) refs[{seed, i}] = computedReference(seed, i);
  std::ofstream out(path);
  out << headerLines();
  for (const auto& [key, r] : refs) out << lineOf(r) << "\n";
}

}  // namespace robustness
}  // namespace attitude_planner
