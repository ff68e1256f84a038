// robustness_report: runs the hard-case catalog (robustness_cases.hpp) and the
// hostile scene corpus, and writes docs/results/robustness.md with every measured figure. The
// figures are those the tests assert (test_hard_cases, test_hostile_inputs); scripts/robustness
// calls this with the request table written by test_ros_conversions and the last fuzz summary.
//
//   robustness_report [--all] [--case NAME]... [--hostile DIR] [--requests FILE] [--fuzz FILE]
//                     [--random FILE] (the randomized suite's section, benchmark_solvers)
//                     [--notes FILE] [--out FILE]
#include <sys/utsname.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "support/robustness_cases.hpp"
#include "support/study_tools.hpp"

namespace ap = attitude_planner;
namespace rb = attitude_planner::robustness;
namespace fs = std::filesystem;

namespace {

using attitude_planner::study::loadAverage;

std::string g(double v, const char* format = "%.3g") {
  return attitude_planner::study::formatted(v, format);
}

/// Text for a markdown table cell: pipes escaped, one line.
std::string cell(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') {
      out += "\\|";
    } else {
      out += c == '\n' ? ' ' : c;
    }
  }
  return out;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string relationText(const rb::Check& c) {
  if (c.relation == "true") return "holds";
  return c.relation + " " + g(c.bound);
}

std::string measuredText(const rb::Check& c) {
  if (c.relation == "true") return c.passed ? "yes" : "**no**";
  return g(c.measured);
}

void writeCase(std::ostream& out, const rb::HardCase& c, const rb::CaseOutcome& o) {
  out << "### " << c.name << " (" << c.group << ")\n\n";
  out << "- Problem: " << c.what << "\n";
  out << "- Pass criterion: " << c.criterion << "\n";
  out << "- Result: " << (o.passed() ? "**pass**" : "**FAIL**") << " (" << g(o.time_s, "%.2f")
      << " s for the whole case)\n\n";
  if (!o.runs.empty()) {
    out << "| run | N | converged | iterations | cost Σ½\\|τ\\|² | terminal attitude error [rad] | "
           "terminal velocity error [rad/s] | max residual | Newton decrement | dynamics "
           "residual | time [s] |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const rb::RunFigures& f : o.runs) {
      out << "| " << cell(f.label) << " | " << f.steps << " | " << (f.converged ? "yes" : "no")
          << " | " << f.iterations << " | " << g(f.cost, "%.10g") << " | "
          << g(f.terminal_attitude_error, "%.2g") << " | " << g(f.terminal_velocity_error, "%.2g")
          << " | " << g(f.max_residual, "%.2g") << " | " << g(f.newton_decrement, "%.2g") << " | "
          << g(f.dynamics_residual, "%.2g") << " | " << g(f.solve_time_s, "%.3f") << " |\n";
    }
    out << "\n";
  }
  // The per-run default checks (converged, finite, terminal errors, residuals reported) are in
  // the run table; the table below lists the case's own checks and any failed default one.
  out << "| check | measured | required | pass |\n|---|---|---|---|\n";
  for (const rb::Check& k : o.checks) {
    const bool per_run_default =
        k.quantity.find(": converged") != std::string::npos ||
        k.quantity.find(": no NaN/Inf") != std::string::npos ||
        k.quantity.find(": terminal attitude error [rad]") != std::string::npos ||
        k.quantity.find(": terminal velocity error [rad/s]") != std::string::npos ||
        k.quantity.find(": residuals reported") != std::string::npos;
    if (per_run_default && k.passed) continue;
    out << "| " << cell(k.quantity) << (k.note.empty() ? "" : " — " + cell(k.note)) << " | "
        << measuredText(k) << " | " << relationText(k) << " | " << (k.passed ? "yes" : "**no**")
        << " |\n";
  }
  std::size_t defaults = 0;
  for (const rb::Check& k : o.checks) defaults += k.passed ? 1 : 0;
  out << "\n" << o.checks.size() << " checks, " << defaults << " passed.\n\n";
  if (!o.passed()) out << "Failed:\n\n```\n" << o.failures() << "```\n\n";
  std::vector<std::string> extremals;
  for (const rb::RunFigures& f : o.runs) {
    if (f.extremal.find("cheaper of both ways") != std::string::npos)
      extremals.push_back(f.label + ": " + f.extremal);
  }
  if (!extremals.empty()) {
    out << "Extremals chosen (PlanResult::extremal):\n\n";
    for (const std::string& e : extremals) out << "- " << cell(e) << "\n";
    out << "\n";
  }
}

/// The command line: which cases and which extra sections.
struct ReportArgs {
  bool all = false;
  std::vector<std::string> only;
  std::string hostile, requests, fuzz, random_suite, notes, out_path;
};

/// Parses the arguments; exits with status 2 on a usage error.
ReportArgs parseArguments(int argc, char** argv) {
  ReportArgs args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "robustness_report: " << a << ": missing value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--all") {
      args.all = true;
    } else if (a == "--case") {
      args.only.push_back(next());
    } else if (a == "--hostile") {
      args.hostile = next();
    } else if (a == "--requests") {
      args.requests = next();
    } else if (a == "--fuzz") {
      args.fuzz = next();
    } else if (a == "--random") {
      args.random_suite = next();
    } else if (a == "--notes") {
      args.notes = next();
    } else if (a == "--out") {
      args.out_path = next();
    } else {
      std::cerr << "usage: robustness_report [--all] [--case NAME]... [--hostile DIR] "
                   "[--requests FILE] [--fuzz FILE] [--random FILE] [--notes FILE] [--out FILE]\n";
      std::exit(2);
    }
  }
  return args;
}

/// The hard cases run: the summary table, each case's section, the counts and the wall time.
struct HardCaseRun {
  std::ostringstream summary, cases_md;
  int passed = 0, failed = 0, not_run = 0;
  double total_s = 0.0;
};

void runHardCases(const ReportArgs& args, HardCaseRun* run) {
  const auto start = std::chrono::steady_clock::now();
  run->summary << "| case | group | pass criterion | result | time [s] |\n|---|---|---|---|---|\n";
  for (const rb::HardCase& c : rb::hardCases()) {
    if (!args.only.empty() &&
        std::find(args.only.begin(), args.only.end(), c.name) == args.only.end())
      continue;
    if (c.slow && !args.all) {
      ++run->not_run;
      run->summary << "| " << c.name << " | " << c.group << " | " << cell(c.criterion)
                   << " | not run here (slow: `scripts/robustness --all`) | |\n";
      continue;
    }
    std::cerr << "robustness_report: " << c.name << " ...\n";
    const rb::CaseOutcome o = rb::runCase(c);
    (o.passed() ? run->passed : run->failed) += 1;
    run->summary << "| " << c.name << " | " << c.group << " | " << cell(c.criterion) << " | "
                 << (o.passed() ? "pass" : "**FAIL**") << " | " << g(o.time_s, "%.2f") << " |\n";
    writeCase(run->cases_md, c, o);
  }
  run->total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The page's heading, how it was made, and the hard-case section.
void writeHardCases(std::ostream& out, const ReportArgs& args, const HardCaseRun& run,
                    const std::string& load_start) {
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  out << "# Robustness: hard cases and hostile input (issue 7)\n\n"
      << "Generated by `scripts/robustness" << (args.all ? " --all" : "")
      << "` (tool `robustness_report`) on " << date << "; do not edit by hand. The same catalog "
      << "(`test/support/robustness_cases.cpp`) is asserted by `test/unit/test_hard_cases.cpp` in "
         "`scripts/test` (slow cases under `scripts/test --all`); the bad-input tables by "
         "`test/unit/test_hostile_inputs.cpp` and `test/ros/test_ros_conversions.cpp`, the node "
         "behaviour by the rostests `test_planner_service` and `test_planner_action`.\n\n"
      << "Machine: " << std::thread::hardware_concurrency()
      << " cores shared with other builds; load average (1/5/15 min) " << load_start
      << " at the start, " << loadAverage() << " at the end; the cases took "
      << g(run.total_s, "%.1f") << " s. Times are wall times and vary ±50 % with the load.\n\n";
  out << "## Hard cases\n\n" << run.passed << " passed, " << run.failed << " failed";
  if (run.not_run) out << ", " << run.not_run << " slow case(s) not run in this report";
  out << ". Every run is also checked for: converged, no NaN/Inf in R_k, Ω_k, τ_k, terminal "
         "attitude and velocity errors ≤ 1e-9 (unless the case states otherwise) and finite "
         "residuals (max residual = relative first-order residual; Newton decrement = relative "
         "torque accuracy of the last step; dynamics residual = worst implicit-step residual of "
         "the replay [N m s]).\n\n"
      << run.summary.str() << "\n"
      << run.cases_md.str();
}

/// Every bad scene file of `dir` with the message loading it gives.
void writeHostileScenes(std::ostream& out, const std::string& dir_path) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir_path)) {
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  out << "## Bad input: scene files and the command line\n\n"
      << "Each file of `test/hostile/scenes/` (" << files.size()
      << " files) is one bad scene; `plan_maneuver FILE` exits with status 1 and prints "
         "`plan_maneuver: invalid input: ` and the message below (checked by "
         "`test_hostile_inputs`, which also checks that the message contains the file's "
         "`# expect:` text). Command-line flags with bad values (`--tolerance -1e-3`, "
         "`--time-budget -5`, `--extra-revolutions -1`, `--direction sideways`, `--tolerance "
         "nan`) exit with status 1 as invalid input naming the flag and the value; 2 is kept for "
         "a malformed command line (an unknown option, a missing value).\n\n"
      << "| file | what is wrong | message |\n|---|---|---|\n";
  for (const fs::path& f : files) {
    std::string message = "(accepted!)";
    try {
      ap::loadScene(f.string());
    } catch (const ap::InvalidInput& e) {
      message = e.what();
    } catch (const std::exception& e) {
      message = std::string("UNEXPECTED ") + e.what();
    }
    std::string what = f.stem().string();
    std::replace(what.begin(), what.end(), '_', ' ');
    const std::string dir = f.parent_path().string() + "/";
    if (message.rfind(dir, 0) == 0) message = message.substr(dir.size());
    out << "| `" << f.filename().string() << "` | " << what << " | `" << cell(message) << "` |\n";
  }
  out << "\n";
}

/// The table of spoiled requests (written by test_ros_conversions to `path`).
void writeBadRequests(std::ostream& out, const std::string& path) {
  out << "## Bad input: service and action requests\n\n"
      << "Each row is a seed request (`plan_attitude_maneuver`) with one field spoiled, run "
         "through the node's request path (`planRequest`: conversion, validation, solve) by "
         "`test_ros_conversions`; the rostests check the same through the live node, that it "
         "answers the next request, and the action's ABORTED state. Error codes: -1 "
         "INVALID_INPUT, -5 STEP_TOO_LARGE (msg/PlanErrorCode.msg).\n\n"
      << "| request | error code | message |\n|---|---|---|\n"
      << readFile(path) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  const ReportArgs args = parseArguments(argc, argv);
  std::ostringstream out;
  const std::string load_start = loadAverage();
  HardCaseRun run;
  runHardCases(args, &run);
  writeHardCases(out, args, run, load_start);
  if (!args.hostile.empty()) writeHostileScenes(out, args.hostile);
  if (!args.requests.empty()) writeBadRequests(out, args.requests);
  if (!args.fuzz.empty()) out << readFile(args.fuzz) << "\n";
  if (!args.random_suite.empty()) out << readFile(args.random_suite) << "\n";
  if (!args.notes.empty()) out << readFile(args.notes) << "\n";
  if (args.out_path.empty()) {
    std::cout << out.str();
  } else {
    std::ofstream file(args.out_path);
    file << out.str();
    if (!file) {
      std::cerr << "robustness_report: cannot write " << args.out_path << "\n";
      return 1;
    }
  }
  std::cerr << "robustness_report: " << run.passed << " passed, " << run.failed << " failed, "
            << run.not_run << " not run\n";
  return run.failed == 0 ? 0 : 1;
}
