// The core's layers depend one way (docs/ARCHITECTURE.md): every #include of the package's own
// headers in include/ and src/ is checked against the allowed dependencies of its file's layer,
// and no core file includes a ROS header. Adding a layer means adding it to kAllowed here.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// Which layers a layer may include (itself included). "top" is the entry point planner.hpp /
/// src/planner.cpp; "base" is errors.hpp, name_table.hpp, input_rules.hpp and termination.hpp,
/// allowed everywhere.
const std::map<std::string, std::set<std::string>> kAllowed = {
    {"lie", {"lie"}},
    {"dynamics", {"lie", "dynamics"}},
    {"planning", {"lie", "dynamics", "planning"}},
    {"analysis", {"lie", "dynamics", "planning", "analysis"}},
    {"drift_two_input", {"lie", "drift_two_input"}},
    {"top", {"lie", "dynamics", "planning", "analysis", "top"}},
    {"io", {"lie", "dynamics", "planning", "analysis", "drift_two_input", "top", "io"}},
};

/// The layer of a path below include/attitude_planner/ or src/ ("" if none of the core's).
std::string layerOf(const std::string& relative) {
  if (relative == "planner.hpp" || relative == "planner.cpp") return "top";
  if (relative == "errors.hpp" || relative == "name_table.hpp" || relative == "input_rules.hpp" ||
      relative == "termination.hpp" || relative == "termination.cpp") {
    return "base";
  }
  const auto slash = relative.find('/');
  if (slash == std::string::npos) return "";
  return relative.substr(0, slash);
}

/// The layer an include spelling refers to: "attitude_planner/<layer>/x.hpp" (public) or
/// "<layer>/x.hpp" (private, src/); "" for anything else (std, Eigen, test support).
std::string includedLayer(const std::string& spelling) {
  std::string rest = spelling;
  const std::string prefix = "attitude_planner/";
  if (rest.compare(0, prefix.size(), prefix) == 0) return layerOf(rest.substr(prefix.size()));
  const std::string layer = layerOf(rest);
  return kAllowed.count(layer) ? layer : "";
}

struct CoreFile {
  fs::path path;
  std::string layer;
};

std::vector<CoreFile> coreFiles() {
  std::vector<CoreFile> files;
  const fs::path root(AP_SOURCE_DIR);
  for (const auto& [base, dir] :
       {std::pair{root / "include/attitude_planner", "include"}, std::pair{root / "src", "src"}}) {
    for (const auto& entry : fs::recursive_directory_iterator(base)) {
      if (!entry.is_regular_file()) continue;
      const std::string relative = fs::relative(entry.path(), base).generic_string();
      const std::string layer = layerOf(relative);
      if (kAllowed.count(layer)) files.push_back({entry.path(), layer});
    }
  }
  return files;
}

}  // namespace

TEST(Layering, EveryCoreLayerHasFiles) {
  std::map<std::string, int> count;
  for (const CoreFile& f : coreFiles()) ++count[f.layer];
  for (const auto& [layer, allowed] : kAllowed) EXPECT_GT(count[layer], 0) << layer;
}

TEST(Layering, IncludesPointDownOnly) {
  const std::regex include_line(R"(^\s*#\s*include\s*[<"]([^">]+)[">])");
  int checked = 0;
  for (const CoreFile& f : coreFiles()) {
    std::ifstream in(f.path);
    std::string line;
    while (std::getline(in, line)) {
      std::smatch m;
      if (!std::regex_search(line, m, include_line)) continue;
      const std::string spelling = m[1];
      EXPECT_NE(spelling.compare(0, 4, "ros/"), 0) << f.path << " includes " << spelling;
      EXPECT_EQ(spelling.find("attitude_planner/ros/"), std::string::npos)
          << f.path << " includes " << spelling;
      EXPECT_EQ(spelling.find("support/"), std::string::npos)
          << f.path << " (core) includes test support " << spelling;
      const std::string target = includedLayer(spelling);
      if (target.empty() || target == "base") continue;
      ++checked;
      EXPECT_TRUE(kAllowed.at(f.layer).count(target))
          << f.path << " (layer " << f.layer << ") includes " << spelling << " (layer " << target
          << ")";
    }
  }
  EXPECT_GT(checked, 50);  // the scan found the package's own includes
}

TEST(Layering, PrivateHeadersAreNotIncludedByPublicOnes) {
  // A public header (include/) that includes a private one (src/) would not compile once
  // installed: the private headers are not installed.
  const std::regex private_include(
      R"re(^\s*#\s*include\s*"(lie|dynamics|planning|analysis|drift_two_input|io)/)re");
  const fs::path root(AP_SOURCE_DIR);
  for (const auto& entry : fs::recursive_directory_iterator(root / "include")) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path());
    std::string line;
    while (std::getline(in, line)) {
      EXPECT_FALSE(std::regex_search(line, private_include)) << entry.path() << ": " << line;
    }
  }
}

namespace {

/// Planning's sub-layers (src/planning/<sub>/, docs/ARCHITECTURE.md), in dependency order: a
/// private file may include its own sub-layer and those before it. linalg knows nothing of the
/// problem; strategies (grid and staged continuation, starts) take a solver as a callable, so
/// every solver below them can use them; the solvers sit on the transcription and the
/// strategies; drivers (plan at resolution, fourth order, minimum time) dispatch.
const std::vector<std::string> kPlanningSubLayers = {"linalg",     "problem", "transcription",
                                                     "strategies", "newton",  "interior_point",
                                                     "crosscheck", "drivers"};

int subLayerRank(const std::string& sub) {
  for (std::size_t i = 0; i < kPlanningSubLayers.size(); ++i) {
    if (kPlanningSubLayers[i] == sub) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

TEST(Layering, PlanningSubLayersPointDownOnly) {
  const fs::path planning = fs::path(AP_SOURCE_DIR) / "src/planning";
  const std::regex private_include(R"re(^\s*#\s*include\s*"planning/([a-z_]+)/)re");
  int checked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(planning)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = fs::relative(entry.path(), planning).generic_string();
    const auto slash = relative.find('/');
    ASSERT_NE(slash, std::string::npos) << entry.path() << " is not in a planning sub-layer";
    const std::string own = relative.substr(0, slash);
    ASSERT_GE(subLayerRank(own), 0) << entry.path() << ": unknown sub-layer " << own;
    std::ifstream in(entry.path());
    std::string line;
    while (std::getline(in, line)) {
      std::smatch m;
      if (!std::regex_search(line, m, private_include)) continue;
      ++checked;
      const int target = subLayerRank(m[1]);
      ASSERT_GE(target, 0) << entry.path() << " includes unknown sub-layer " << m[1];
      EXPECT_LE(target, subLayerRank(own)) << entry.path() << " includes " << line;
    }
  }
  EXPECT_GT(checked, 10);
}
