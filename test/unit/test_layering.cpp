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
/// src/planner.cpp; "base" is errors.hpp, name_table.hpp and
/// input_rules.hpp, allowed everywhere.
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
  if (relative == "errors.hpp" || relative == "name_table.hpp" || relative == "input_rules.hpp") {
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
