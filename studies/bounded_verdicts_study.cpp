// bounded_verdicts_study (honest verdicts on bounded requests): seeded bounded
// requests like the held-out ones (test/support/bounded_requests.hpp: random bodies and slews,
// spinning ends, norm and box bounds at 0.6–0.9 of the unbounded plan's peak, rate limits,
// re-plans cut from plans, a quarter as minimum time), each verdict checked independently
// (planAndCheck), and the special requests of the issue (identical states, a hopeless N = 2e6
// request, extreme magnitudes) with their wall times; writes docs/results/bounded_verdicts.md
// (scripts/bounded_verdicts).
//
// With --write-references FILE it plans the references of requests 0..K−1 of seed S instead
// (test/support/bounded_references.hpp) and writes them into FILE (scripts/bounded_references).
//
//   bounded_verdicts_study [--count K] [--seed S] [--out FILE] [--only I]
//                          [--write-references FILE] [--probe-at T1,T2,...] [--progress K]
//
// With --only I and --probe-at, request I is not planned as asked: a cold minimum-effort solve at
// each listed T under its bounds (probeAt, the check's own solve) is reported on stderr instead,
// to trace a verdict (where plans lie in T). With --only I and --progress K, every K-th iteration
// of the request is reported on stderr (its attempt, stage, grid and the seconds so far), to see
// where a long request spends its time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"
#include "support/bounded_references.hpp"
#include "support/bounded_requests.hpp"
#include "support/study_tools.hpp"

namespace ap = attitude_planner;
namespace rb = attitude_planner::robustness;
namespace st = attitude_planner::study;

namespace {

std::string g(double v, const char* format = "%.4g") {
  return st::formatted(v, format);
}

struct Options {
  int count = 200;
  int only = -1;  ///< ≥ 0: that request alone (its label and verdict on stderr)
  std::uint64_t seed = 45;
  std::string out;
  std::string write_references;  ///< non-empty: the references written there, nothing planned
  std::vector<double> probe_durations;  ///< --probe-at [s], with --only
  int progress = 0;                     ///< --progress K, with --only: every K-th iteration
};

Options parse(int argc, char** argv) {
  Options o;
  st::FlagReader flags;
  flags.add("--count", &o.count)
      .add("--seed", &o.seed)
      .add("--out", &o.out)
      .add("--only", &o.only)
      .add("--write-references", &o.write_references)
      .add(
          "--probe-at", &o.probe_durations, [](double T) { return T > 0.0; }, "a duration > 0 [s]")
      .add("--progress", &o.progress);
  st::readFlagsOrExit(flags, argc, argv, "bounded_verdicts_study",
                      "[--count K] [--seed S] [--out FILE] [--only I] [--write-references FILE] "
                      "[--probe-at T1,T2,...] [--progress K]");
  if (o.progress < 0) {
    std::cerr << "bounded_verdicts_study: --progress " << o.progress << ": needs K > 0\n";
    std::exit(2);
  }
  if ((!o.probe_durations.empty() || o.progress > 0) && o.only < 0) {
    std::cerr << "bounded_verdicts_study: --probe-at and --progress need --only I\n";
    std::exit(2);
  }
  return o;
}

/// The suite's rows so far and their counts by outcome and by what was found wrong.
struct SuiteTally {
  std::ostringstream rows;
  std::map<std::string, int> outcomes, wrong;
  int drawn = 0, requests = 0, skipped = 0, input_errors = 0;
  std::vector<double> times;

  void add(int i, const rb::BoundedRequest& request, const rb::VerdictCheck& c) {
    const std::string outcome = rb::outcomeName(c);
    ++requests;
    ++outcomes[outcome];
    if (!c.input_error.empty()) ++input_errors;
    if (!c.wrong.empty()) ++wrong[c.wrong];
    times.push_back(c.seconds);
    const ap::DurationVerdict& v = c.result.duration_verdict;
    rows << "| " << i << " | " << request.label << " | " << outcome << " | "
         << g(request.problem.duration) << " | " << g(v.lower_bound) << " | "
         << g(v.least_duration_found) << " | " << g(v.longest_duration_found) << " | "
         << g(c.result.minimum_duration) << " | "
         << (c.wrong.empty() ? (c.input_error.empty() ? "ok" : c.input_error)
                             : "**" + c.wrong + "**")
         << " | " << g(c.seconds, "%.3f") << " |\n";
  }

  /// The section; `count` the requests asked for (fewer drawn so far: a run still going, or
  /// stopped, says so).
  std::string render(const Options& o) const {
    std::ostringstream out;
    out << "## The seeded suite (seed " << o.seed << ", " << requests << " requests; " << skipped
        << " drawn cases skipped: their unbounded plan did not converge)\n\n";
    if (drawn < o.count && o.only < 0) {
      out << "**Partial: " << drawn << " of the " << o.count
          << " requests asked for were drawn when this page was written** (the study rewrites it "
             "after each request; a run stopped early leaves this).\n\n";
    }
    out << "| outcome | requests |\n|---|---|\n";
    for (const auto& [name, n] : outcomes) out << "| " << name << " | " << n << " |\n";
    out << "\nInternal errors reported as input errors: **" << input_errors
        << "**. Verdicts found wrong by the independent check:";
    if (wrong.empty()) out << " **none**";
    for (const auto& [name, n] : wrong) out << " " << name << ": **" << n << "**;";
    const double longest = times.empty() ? 0.0 : *std::max_element(times.begin(), times.end());
    out << "\n\nWall time per request: median " << g(st::median(times), "%.3f") << " s, longest "
        << g(longest, "%.1f") << " s.\n\n";
    out << "| # | request | outcome | T [s] | proven T_c [s] | least T found [s] | longest T "
           "found [s] | T* [s] | check | wall [s] |\n|---|---|---|---|---|---|---|---|---|---|\n"
        << rows.str();
    return out.str();
  }
};

/// Options whose callback reports every `every`-th iteration on stderr (none for 0).
ap::SolverOptions progressReports(int every) {
  ap::SolverOptions options;
  if (every <= 0) return options;
  const auto start = std::chrono::steady_clock::now();
  options.on_iteration = [every, start](const ap::IterationInfo& info) {
    if (info.iteration % every != 0) return true;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cerr << "iteration " << info.iteration << ": attempt " << info.attempt.number << " ("
              << ap::attemptStageName(info.attempt.stage) << "), N = " << info.steps << ", "
              << g(seconds, "%.1f") << " s\n";
    return true;
  };
  return options;
}

/// The suite, request by request; `written` gets the section after each request.
void runSuite(const Options& o, const std::function<void(const std::string&)>& written) {
  SuiteTally tally;
  for (int i = 0; i < o.count; ++i) {
    if (o.only >= 0 && i != o.only) continue;
    ++tally.drawn;
    const std::optional<rb::BoundedRequest> request = rb::boundedRequest(o.seed, i);
    if (request && o.only >= 0) std::cerr << request->label << "\n";
    if (!request) {
      ++tally.skipped;
      continue;
    }
    const rb::VerdictCheck c = rb::planAndCheck(*request, progressReports(o.progress));
    tally.add(i, *request, c);
    std::cerr << i << " " << rb::outcomeName(c) << " " << c.wrong << " " << g(c.seconds, "%.2f")
              << " s\n";
    if (o.only >= 0) std::cerr << c.result.message() << "\n" << rb::attemptLines(c.result);
    written(tally.render(o));
  }
  written(tally.render(o));
}

/// Request `o.only` probed at each of `o.probe_durations` (a cold minimum-effort solve under its
/// bounds), one line each on stderr.
void probeRequest(const Options& o) {
  const std::optional<rb::BoundedRequest> request = rb::boundedRequest(o.seed, o.only);
  if (!request) {
    std::cerr << o.only << ": no request (its unbounded plan did not converge)\n";
    return;
  }
  std::cerr << request->label << "\n";
  for (const double T : o.probe_durations) {
    const rb::ProbeAt p = rb::probeAt(request->problem, T);
    std::cerr << "  probe T = " << g(T, "%.6g") << " s: " << p.outcome
              << (p.plan ? " (a plan)" : "") << ", " << p.iterations << " iterations, "
              << g(p.seconds, "%.2f") << " s\n    " << p.message.substr(0, 400) << "\n";
  }
}

/// One special request: its outcome and wall time (an exception is an outcome too).
std::string specialRow(const std::string& what, const ap::PlanningProblem& p) {
  const auto start = std::chrono::steady_clock::now();
  std::string outcome;
  try {
    const ap::PlanResult r = ap::planManeuver(p);
    outcome = "**" + ap::terminationName(r.termination) + "**: " + r.message().substr(0, 220);
  } catch (const ap::FieldError& e) {
    outcome = std::string("refused: ") + e.what();
  }
  return "| " + what + " | " + outcome + " | " + g(st::seconds(start), "%.3f") + " |\n";
}

std::string specialSection() {
  ap::PlanningProblem slew;
  slew.inertia = ap::Vector3(10.0, 20.0, 30.0).asDiagonal();
  slew.final_attitude = Eigen::AngleAxisd(3.0, ap::Vector3::UnitZ()).toRotationMatrix();
  slew.constraints = {ap::PlanningConstraint::maxTorqueNorm(0.1)};
  slew.duration = 20.0;
  std::ostringstream out;
  out << "## The special requests of the issue\n\n| request | answer | wall [s] |\n|---|---|---|\n";
  ap::PlanningProblem same = slew;
  same.final_attitude = same.initial_attitude;
  same.objective = ap::Objective::MinimumTime;
  same.duration = 0.0;
  out << specialRow("minimum time, identical rest states", same);
  ap::PlanningProblem hopeless = slew;
  hopeless.steps = 2000000;
  out << specialRow("3 rad, |tau| <= 0.1 N m, T = 20 s, N = 2e6", hopeless);
  ap::PlanningProblem huge = slew;
  huge.constraints = {};
  huge.max_torque = ap::Vector3::Constant(1e300);
  huge.objective = ap::Objective::MinimumTime;
  huge.duration = 0.0;
  out << specialRow("minimum time, |tau_i| <= 1e300 N m", huge);
  ap::PlanningProblem slow = slew;
  slow.constraints.push_back(ap::PlanningConstraint::maxAngularRate(1e-300));
  slow.objective = ap::Objective::MinimumTime;
  slow.duration = 0.0;
  out << specialRow("minimum time, |Omega| <= 1e-300 rad/s", slow);
  ap::PlanningProblem heavy = slew;
  heavy.inertia *= 1e300;
  out << specialRow("J x 1e300", heavy);
  ap::PlanningProblem brief = slew;
  brief.duration = 1e-300;
  out << specialRow("T = 1e-300 s", brief);
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  if (!o.write_references.empty()) {
    rb::writeReferences(o.seed, o.count, o.write_references);
    return 0;
  }
  if (!o.probe_durations.empty()) {
    probeRequest(o);
    return 0;
  }
  std::ostringstream head;
  head << "# Honest verdicts on bounded requests\n\nGenerated by `scripts/bounded_verdicts` "
          "(studies/bounded_verdicts_study.cpp; `--count "
       << o.count << " --seed " << o.seed << "`), load average " << st::loadAverage()
       << ". The requests' bounds are fractions of stored references (the unbounded plans' "
          "peaks as one library planned them once: test/data/bounded_references.csv, "
          "`scripts/bounded_references`), so a row is the same request on every library. What "
          "each check means: test/support/bounded_requests.hpp; the design: "
          "docs/design/planner_behaviour.md#verdicts-on-durations.\n\n"
       << specialSection() << "\n";
  std::string last;
  runSuite(o, [&](const std::string& suite) {
    last = head.str() + suite;
    if (!o.out.empty()) std::ofstream(o.out) << last;
  });
  if (o.out.empty()) std::cout << last;
  return 0;
}
