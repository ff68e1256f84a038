// cancel_handover_study: how long a stopped solve takes to hand its plan over, in-process
// (docs/ros_planner.md, "Handing a stopped N = 1e5 plan over"; scripts/cancel_handover).
//
//   cancel_handover_study [--steps N] [--delays 0.5,1,2] [--budgets 1e-6,0.3,1] [--repeats R]
//
// The seed slew (π/3 about x in 12.8 s, the seed's inertia) at N steps with a tolerance no solve
// meets (1e-300), so only the cancel ends it. For each delay d the cancel flag
// (SolverOptions::cancel_requested, as the planner node's action sets it) is raised d seconds
// after the first reported iteration; the hand-over is the wall time from raising the flag to
// planManeuver returning. The table also says what ran at the cancel (the last reported
// iteration's attempt stage and grid N) and what came back (rows, termination, residuals).
// With --budgets the solves are stopped by their time budget B instead (SolverOptions::
// time_budget_s, as the planner node's deadline does): the hand-over is the wall time from B to
// planManeuver returning, with the solving thread's CPU time over the whole call beside it.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <time.h>

#include "attitude_planner/planner.hpp"
#include "support/seed_examples.hpp"
#include "support/study_tools.hpp"

namespace ap = attitude_planner;
namespace st = attitude_planner::study;
using Clock = std::chrono::steady_clock;

namespace {

struct Settings {
  int steps = 100000;
  std::vector<double> delays{0.5, 1.0, 2.0};
  std::vector<double> budgets;  ///< when given: stopped by these budgets, not by cancels
  int repeats = 1;
};

/// What the solve was doing when the flag was raised (the last iteration reported before it).
struct AtCancel {
  std::string stage;
  int steps = 0;
  int iteration = 0;
};

struct Handover {
  double delay = 0.0;
  AtCancel at_cancel;
  double seconds = 0.0;      ///< cancel (or the budget) → planManeuver returned [s]
  double cpu_seconds = 0.0;  ///< the solving thread's CPU time over the whole call [s]
  ap::PlanResult result;
};

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/// The seed slew stopped by its time budget `budget` [s] (tolerance 1e-300: nothing else ends it).
Handover budgetedRun(const ap::PlanningProblem& problem, double budget) {
  AtCancel last;
  ap::SolverOptions options;
  options.tolerance = 1e-300;
  options.max_iterations = 1000000;
  options.time_budget_s = budget;
  options.on_iteration = [&](const ap::IterationInfo& info) {
    last = {ap::attemptStageName(info.attempt.stage), info.steps, info.iteration};
    return true;
  };
  Handover h;
  h.delay = budget;
  const double cpu = threadCpuSeconds();
  const Clock::time_point start = Clock::now();
  h.result = ap::planManeuver(problem, options);
  h.seconds = std::chrono::duration<double>(Clock::now() - start).count() - budget;
  h.cpu_seconds = threadCpuSeconds() - cpu;
  h.at_cancel = last;
  return h;
}

Handover cancelledRun(const ap::PlanningProblem& problem, double delay) {
  std::atomic<bool> cancel{false};
  std::atomic<bool> started{false};
  std::mutex mutex;
  AtCancel last;
  ap::SolverOptions options;
  options.tolerance = 1e-300;
  options.max_iterations = 1000000;
  options.cancel_requested = &cancel;
  options.on_iteration = [&](const ap::IterationInfo& info) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!cancel.load())
      last = {ap::attemptStageName(info.attempt.stage), info.steps, info.iteration};
    started = true;
    return true;
  };
  Handover h;
  h.delay = delay;
  const double cpu = threadCpuSeconds();
  Clock::time_point cancelled_at;
  std::thread canceller([&] {
    while (!started.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::duration<double>(delay));
    std::lock_guard<std::mutex> lock(mutex);
    h.at_cancel = last;
    cancelled_at = Clock::now();
    cancel = true;
  });
  h.result = ap::planManeuver(problem, options);
  const Clock::time_point returned = Clock::now();
  h.cpu_seconds = threadCpuSeconds() - cpu;
  canceller.join();
  h.seconds = std::chrono::duration<double>(returned - cancelled_at).count();
  if (std::getenv("CANCEL_HANDOVER_TIMESTAMPS")) {  // for perf record -k CLOCK_MONOTONIC windows
    std::fprintf(stderr, "cancel at %.6f, returned at %.6f (CLOCK_MONOTONIC s)\n",
                 std::chrono::duration<double>(cancelled_at.time_since_epoch()).count(),
                 std::chrono::duration<double>(returned.time_since_epoch()).count());
  }
  return h;
}

std::vector<double> parseList(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::stod(item));
  return out;
}

Settings parseArguments(int argc, char** argv) {
  Settings s;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--steps") {
      s.steps = std::atoi(argv[i + 1]);
    } else if (flag == "--delays") {
      s.delays = parseList(argv[i + 1]);
    } else if (flag == "--budgets") {
      s.budgets = parseList(argv[i + 1]);
    } else if (flag == "--repeats") {
      s.repeats = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      std::exit(2);
    }
  }
  return s;
}

/// The attempts run, in the order they ended: "class_survey (converged), class_refine (cancelled)".
std::string trail(const ap::PlanResult& r) {
  std::string out;
  for (const ap::Attempt& a : r.attempts) {
    out += (out.empty() ? "" : ", ") + ap::attemptStageName(a.stage) +
           " N = " + std::to_string(a.steps) + " (" + ap::terminationName(a.termination) + ")";
  }
  return out;
}

void printRow(const Handover& h) {
  const ap::PlanResult& r = h.result;
  std::printf(
      "| %.3g | %s | %d | %d | %.1f | %.2f | %.1f | %s | %d | %.2g | %.3g | %s |\n", h.delay,
      h.at_cancel.stage.c_str(), h.at_cancel.steps, h.at_cancel.iteration, 1e3 * h.seconds,
      1e6 * h.seconds / std::max<std::size_t>(r.maneuver.attitude.size(), 1), 1e3 * h.cpu_seconds,
      ap::terminationName(r.termination).c_str(), static_cast<int>(r.maneuver.attitude.size()),
      r.step_residual, r.max_residual, trail(r).c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const Settings s = parseArguments(argc, argv);
  ap::PlanningProblem problem = ap::test_support::seedProblem(false);
  problem.steps = s.steps;
  const bool budgets = !s.budgets.empty();
  std::printf("cancel_handover_study: the seed slew at N = %d, tolerance 1e-300; load %s\n\n",
              s.steps, st::loadAverage().c_str());
  std::printf(budgets ? "| time budget B [s] | stage at B | grid N at B | iteration | "
                        "B -> plan returned [ms] | per row [us] | CPU of the call [ms] | "
                      : "| cancel after first iteration [s] | stage at cancel | grid N at cancel | "
                        "iteration | cancel -> plan returned [ms] | per row [us] | CPU of the "
                        "call [ms] | ");
  std::printf("termination | rows | step residual | max residual | attempts |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const ap::Termination stopped = budgets ? ap::Termination::TimedOut : ap::Termination::Cancelled;
  std::vector<double> seconds;
  for (int repeat = 0; repeat < s.repeats; ++repeat) {
    for (double value : budgets ? s.budgets : s.delays) {
      const Handover h = budgets ? budgetedRun(problem, value) : cancelledRun(problem, value);
      printRow(h);
      if (h.result.termination == stopped) seconds.push_back(h.seconds);
      std::fflush(stdout);
    }
  }
  std::vector<double> sorted = seconds;
  std::sort(sorted.begin(), sorted.end());
  std::printf("\nstopped runs: %zu, hand-over median %.1f ms, max %.1f ms; load %s\n",
              seconds.size(), 1e3 * st::median(seconds), sorted.empty() ? 0.0 : 1e3 * sorted.back(),
              st::loadAverage().c_str());
  return 0;
}
