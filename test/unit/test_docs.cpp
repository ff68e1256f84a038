// The documentation cannot rot unnoticed: scripts/check_docs.py (relative links and anchors in
// README.md, CHANGELOG.md and docs/, docs/ paths named anywhere in the package, README.md's copy
// of examples/*.cpp) runs in the default suite, and README.md's C++ example is built and run.
// scripts/function_lengths keeps every function in src/ short enough to read at once.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "tool_runner.hpp"

namespace {

using attitude_planner_test::runCommand;
using attitude_planner_test::runProgram;
using attitude_planner_test::ToolRun;

const std::string kSourceDir = AP_SOURCE_DIR;

/// scripts/check_docs.py on the repository `repo` with the checks named in `checks`.
ToolRun checkDocs(const std::string& repo, const std::string& checks) {
  return runCommand("/usr/bin/python3 '" + kSourceDir + "/scripts/check_docs.py' --repo '" + repo +
                    "' " + checks);
}

TEST(DocsCheck, RelativeLinksInReadmeAndDocsResolve) {
  const ToolRun r = checkDocs(kSourceDir, "links");
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST(DocsCheck, DocsPathsNamedInThePackageExist) {
  const ToolRun r = checkDocs(kSourceDir, "mentions");
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST(DocsCheck, ReadmeHoldsTheExampleProgramVerbatim) {
  const ToolRun r = checkDocs(kSourceDir, "examples");
  EXPECT_EQ(r.status, 0) << r.output;
}

/// The checker itself: a page with a broken link, a missing heading and a stale path fails.
/// (The paths are spelled kDocs + "/..." so that this file names no docs/ path that is missing.)
TEST(DocsCheck, ReportsBrokenLinksMissingHeadingsAndStalePaths) {
  const std::string kDocs = "docs";
  char pattern[] = "/tmp/ap_docs_check_XXXXXX";
  const char* dir = mkdtemp(pattern);
  ASSERT_NE(dir, nullptr);
  const std::string repo = dir;
  std::filesystem::create_directories(repo + "/" + kDocs + "/results");
  std::ofstream(repo + "/" + kDocs + "/results/page.md") << "# Page\n\n## Some `code` heading\n";
  std::ofstream(repo + "/README.md")
      << "# Readme\n\n[ok](" << kDocs << "/results/page.md#some-code-heading) [gone](" << kDocs
      << "/gone.md) [anchor](" << kDocs << "/results/page.md#no-such-heading)\n\n```\n"
      << "[in code](ignored.md)\n```\n";
  std::ofstream(repo + "/" + kDocs + "/results/stale.md") << "Written by " << kDocs << "/old.md.\n";
  const ToolRun r = checkDocs(repo, "links mentions");
  std::filesystem::remove_all(repo);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("README.md:3: broken link " + kDocs + "/gone.md"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("no heading #no-such-heading"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("names " + kDocs + "/old.md"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("some-code-heading"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("ignored.md"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("4 problem(s)"), std::string::npos) << r.output;
}

// The code's shape: no function in src/ over 100 lines (docs/ARCHITECTURE.md, "Function
// length"); scripts/function_lengths counts from the signature to the closing brace.
TEST(CodeShape, NoFunctionInSrcOrStudiesIsLongerThanAHundredLines) {
  // src/ holds the core, the nodes and the tools (src/tools); studies/ the programs behind docs/.
  const ToolRun r =
      runCommand("/usr/bin/python3 '" + kSourceDir + "/scripts/function_lengths' '" + kSourceDir +
                 "/src' '" + kSourceDir + "/studies' --top 3 --fail-over 100");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(r.output.empty()) << "the scan found no function";
}

/// The lines of C++ sources under `dir` (recursive) that contain one of `needles`, "path:line:
/// text" each, skipping the files whose path contains one of `exempt`. `files` counts the sources
/// read.
std::vector<std::string> linesContaining(const std::string& dir,
                                         const std::vector<std::string>& needles,
                                         const std::vector<std::string>& exempt, int* files) {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    const std::string path = entry.path().string();
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
    bool skip = false;
    for (const std::string& e : exempt) skip = skip || path.find(e) != std::string::npos;
    if (skip) continue;
    ++*files;
    std::ifstream in(path);
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      const bool found = std::any_of(needles.begin(), needles.end(), [&](const std::string& n) {
        return line.find(n) != std::string::npos;
      });
      if (found)
        out.push_back(path.substr(dir.size()) + ":" + std::to_string(number) + ": " + line);
    }
  }
  return out;
}

/// The lines that switch or branch on a stage quantity's name (StageQuantity::…, quantity() ==
/// / !=).
std::vector<std::string> quantityBranches(const std::string& dir,
                                          const std::vector<std::string>& exempt, int* files) {
  return linesContaining(dir, {"StageQuantity::", "quantity() ==", "quantity() !="}, exempt, files);
}

// Stage quantities are objects (src/planning/transcription/stage_quantities.hpp): the solvers and
// the plan's check ask them and never switch on a quantity's name. Only the quantity classes and
// the dense NLPs (crosscheck/: independent derivatives on purpose) may name one.
TEST(CodeShape, NoSwitchOnAStageQuantityOutsideTheQuantityClasses) {
  int files = 0;
  const std::vector<std::string> found = quantityBranches(
      kSourceDir + "/src/planning",
      {"/crosscheck/", "/transcription/stage_quantities.", "/transcription/wheel_quantities."},
      &files);
  EXPECT_GT(files, 20) << "the scan read no sources";
  std::string listed;
  for (const std::string& line : found) listed += line + "\n";
  EXPECT_TRUE(found.empty()) << listed;
  // The scan itself finds what it looks for: the quantity classes and the cross-check name them.
  int exempt_files = 0;
  EXPECT_FALSE(
      quantityBranches(kSourceDir + "/src/planning/transcription", {}, &exempt_files).empty());
  EXPECT_FALSE(
      quantityBranches(kSourceDir + "/src/planning/crosscheck", {}, &exempt_files).empty());
}

// One SolveContext per request: a phase's iteration count is read from the context
// (SolveContext::IterationTally), never summed from its solves' results, and the clauses a solver
// or driver adds to a message are recorded as data (problem/message_notes.hpp: addNote), worded
// in one place, never appended by hand. Both at 0 in src/planning outside those two files; the
// scan also counts `message.append(`, so that an append cannot hide under another spelling.
TEST(CodeShape, HandMergedMessagesAndIterationCountsOnlyFall) {
  constexpr std::size_t kMessageAppendsLeft = 0;  // main 84c3efb: 22
  constexpr std::size_t kIterationSumsLeft = 0;   // main 84c3efb: 9
  const std::string planning = kSourceDir + "/src/planning";
  const std::vector<std::string> owners = {"/problem/solve_context.", "/problem/message_notes."};
  int files = 0;
  const std::vector<std::string> appends = {"message +=", "message.append(", "message->append("};
  const auto messages = linesContaining(planning, appends, owners, &files);
  const auto iterations = linesContaining(planning, {"iterations +="}, owners, &files);
  EXPECT_GT(files, 40) << "the scan read no sources";
  std::string listed;
  for (const std::string& line : messages) listed += line + "\n";
  for (const std::string& line : iterations) listed += line + "\n";
  EXPECT_LE(messages.size(), kMessageAppendsLeft) << listed;
  EXPECT_LE(iterations.size(), kIterationSumsLeft) << listed;
  // The scan finds what it looks for: the one place that appends a clause (the fold).
  int owner_files = 0;
  EXPECT_FALSE(linesContaining(planning + "/problem", appends, {}, &owner_files).empty());
  RecordProperty("message_appends", static_cast<int>(messages.size()));
  RecordProperty("iteration_sums", static_cast<int>(iterations.size()));
}

// The message is the fold of the answer's clauses (PlanResult::clauses, rendered in
// problem/message_notes): the lines that assign a message outside it (a copy, a frame built by
// hand, `message =` at a line's end included) only fall, and so do the words recorded as a bare
// Reason (recordReason) instead of a kind, a note or a frame. An answer's message stores nothing:
// PlanResult and the free-time outcome declare it as the rendering of their clauses.
TEST(CodeShape, MessageAssignmentsOnlyFall) {
  // main 5e2b279: 49; 52ad54e: 41; e0578f8: 30; 9bd3e73: 24; a32e35a: 15 (19 with the lines
  // ending in `message =`)
  constexpr std::size_t kMessageAssignmentsLeft = 0;
  constexpr std::size_t kBareReasonsLeft = 3;
  const std::vector<std::string> owners = {"/problem/solve_context.", "/problem/message_notes."};
  const std::regex assignment(R"re(message\s*(=$|=[^=]|\+=))re");
  int files = 0;
  std::vector<std::string> assigned;
  for (const std::string& line :
       linesContaining(kSourceDir + "/src/planning", {"message"}, owners, &files)) {
    if (std::regex_search(line, assignment)) assigned.push_back(line);
  }
  int reason_files = 0;
  const auto reasons =
      linesContaining(kSourceDir + "/src/planning", {"recordReason("}, owners, &reason_files);
  EXPECT_GT(files, 40) << "the scan read no sources";
  std::string listed;
  for (const std::string& line : assigned) listed += line + "\n";
  for (const std::string& line : reasons) listed += line + "\n";
  EXPECT_LE(assigned.size(), kMessageAssignmentsLeft) << listed;
  EXPECT_LE(reasons.size(), kBareReasonsLeft) << listed;
  // The scan finds what it looks for: the fold's own assignments.
  int owner_files = 0;
  std::size_t owned = 0;
  for (const std::string& line :
       linesContaining(kSourceDir + "/src/planning/problem", {"message"}, {}, &owner_files)) {
    owned += std::regex_search(line, assignment) ? 1 : 0;
  }
  EXPECT_GT(owned, 0u) << "the scan finds what it looks for";
  int declaring_files = 0;
  std::vector<std::string> declared;
  for (const std::string& dir : {"/include/attitude_planner/planning", "/src/planning"}) {
    for (const std::string& line :
         linesContaining(kSourceDir + dir, {"std::string message"}, owners, &declaring_files)) {
      declared.push_back(line);
    }
  }
  ASSERT_EQ(declared.size(), 2u) << "PlanResult's and FreeTimeOutcome's message";
  for (const std::string& line : declared) {
    EXPECT_NE(line.find("std::string message() const"), std::string::npos) << line;
  }
  RecordProperty("message_assignments", static_cast<int>(assigned.size()));
  RecordProperty("bare_reasons", static_cast<int>(reasons.size()));
}

/// The indented block after "It prints:" in README.md, one string per line.
std::vector<std::string> readmePrintedLines() {
  std::ifstream readme(kSourceDir + "/README.md");
  std::vector<std::string> lines;
  bool in_block = false;
  for (std::string line; std::getline(readme, line);) {
    if (line == "It prints:") {
      in_block = true;
    } else if (in_block && line.rfind("    ", 0) == 0) {
      lines.push_back(line.substr(4));
    } else if (in_block && !lines.empty()) {
      break;
    }
  }
  return lines;
}

/// README.md's C++ example (examples/plan_rest_to_rest.cpp) plans the seed's slew, converges, and
/// prints what the README says it prints (the replay miss, round-off, only to its order).
TEST(ReadmeExample, PlansTheSeedsRestToRestSlewAndPrintsWhatTheReadmeShows) {
  const ToolRun r = runProgram(AP_STUDY_DIR, "plan_rest_to_rest", "", 120);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.rfind("converged in ", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("cost 7.910254"), std::string::npos) << r.output;  // the seed's optimum
  const std::vector<std::string> shown = readmePrintedLines();
  ASSERT_EQ(shown.size(), 2u) << "README.md: no two-line block after \"It prints:\"";
  const std::string::size_type miss = shown[0].find(", replay miss");
  ASSERT_NE(miss, std::string::npos) << shown[0];
  EXPECT_EQ(r.output.rfind(shown[0].substr(0, miss), 0), 0u)
      << "README.md shows: " << shown[0] << "\nthe example prints: " << r.output;
  EXPECT_NE(r.output.find("e-15 rad\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\n" + shown[1] + "\n"), std::string::npos)
      << "README.md shows: " << shown[1] << "\nthe example prints: " << r.output;
}

}  // namespace
