// spinning_minimum_time_study: minimum time with spinning ends under torque bounds, the requests
// the free-time interior point finds hardest. The requests are the minimum-time requests with a
// nonzero end rate of the seeded bounded suite (test/support/bounded_requests.hpp), optionally
// re-posed on one scheme and N (the free-time solver is the same for every scheme; the paper
// scheme adds its boundary steps). Each answer is checked independently (planAndCheck: a
// minimum-effort plan at 0.99 T* would refute T*). Writes docs/results/spinning_minimum_time.md
// (scripts/spinning_minimum_time).
//
//   spinning_minimum_time_study [--count K] [--seed S] [--scheme NAME] [--steps N] [--out FILE]
//                               [--only I] [--probe-scan F1,F2,...]
//
// --probe-scan: below each converged T*, a cold minimum-effort solve at (1 - F) T* for each F (the
// check's solve, at more durations): where the planner's own probes below T* stop, this says
// whether plans lie further below (a second table; measurement, not a verdict check).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "planning/strategies/starts.hpp"
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
  int count = 30;  ///< requests to plan (drawn until this many qualify)
  int only = -1;   ///< ≥ 0: that bounded-suite index alone, with its trail on stderr
  std::uint64_t seed = 77;
  std::string scheme;  ///< empty: as drawn
  int steps = 0;       ///< 0: as drawn
  std::string out;
  std::vector<double> probe_fractions;  ///< --probe-scan
};

Options parse(int argc, char** argv) {
  Options o;
  st::FlagReader flags;
  flags.add("--count", &o.count)
      .add("--seed", &o.seed)
      .add("--scheme", &o.scheme)
      .add("--steps", &o.steps)
      .add("--out", &o.out)
      .add("--only", &o.only)
      .add(
          "--probe-scan", &o.probe_fractions, [](double f) { return f > 0.0 && f < 1.0; },
          "a fraction in (0, 1)");
  st::readFlagsOrExit(flags, argc, argv, "spinning_minimum_time_study",
                      "[--count K] [--seed S] [--scheme NAME] [--steps N] [--out FILE] [--only I] "
                      "[--probe-scan F1,F2,...]");
  return o;
}

bool spinningMinimumTime(const ap::PlanningProblem& p) {
  return p.objective == ap::Objective::MinimumTime && ap::hasSpinningEnds(p);
}

/// Request `index` of the bounded suite if it is a spinning minimum-time request, re-posed.
std::optional<rb::BoundedRequest> drawn(const Options& o, int index) {
  std::optional<rb::BoundedRequest> r = rb::boundedRequest(o.seed, index);
  if (!r || !spinningMinimumTime(r->problem)) return std::nullopt;
  if (!o.scheme.empty()) r->problem.scheme = ap::parseScheme(o.scheme, "--scheme");
  if (o.steps > 0) r->problem.steps = o.steps;
  return r;
}

/// The label in a table cell: its |Ω| bars escaped.
std::string escapedPipes(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

struct Tally {
  std::ostringstream rows, scan_rows;
  int scanned = 0, scan_below = 0, scan_below_one_percent = 0;
  std::map<std::string, int> outcomes;
  int requests = 0, wrong = 0, free_time_attempts = 0, free_time_converged = 0;
  std::vector<double> times;

  void add(int index, const rb::BoundedRequest& request, const rb::VerdictCheck& c) {
    ++requests;
    const std::string outcome = rb::outcomeName(c);
    ++outcomes[outcome];
    if (!c.wrong.empty()) ++wrong;
    times.push_back(c.seconds);
    int attempts = 0, converged = 0;
    for (const ap::Attempt& a : c.result.attempts) {
      if (a.stage != ap::AttemptStage::MinimumTimeSolve) continue;
      ++attempts;
      if (a.termination == ap::Termination::Converged) ++converged;
    }
    free_time_attempts += attempts;
    free_time_converged += converged;
    const ap::PlanningProblem& p = request.problem;
    rows << "| " << index << " | " << escapedPipes(request.label) << " | "
         << ap::schemeName(p.scheme) << " | " << p.steps << " | "
         << g(p.initial_velocity.norm(), "%.3g") << " / " << g(p.final_velocity.norm(), "%.3g")
         << " | " << outcome << " | " << g(c.result.minimum_duration) << " | " << converged << " / "
         << attempts << " | " << c.result.iterations << " | "
         << (c.wrong.empty() ? "ok" : "**" + c.wrong + "**") << " | " << g(c.seconds, "%.3f")
         << " |\n";
  }

  /// One row of the probe scan below T* (`probes`, in --probe-scan's order).
  void addScan(int index, double T_star, const std::vector<rb::ProbeAt>& probes) {
    ++scanned;
    double lowest = T_star;
    scan_rows << "| " << index << " | " << g(T_star, "%.6g") << " |";
    for (const rb::ProbeAt& p : probes) {
      scan_rows << " "
                << (p.converged ? "plan"
                    : p.plan    ? "plan (not converged)"
                                : p.outcome)
                << " (" << p.iterations << ") |";
      if (p.plan) lowest = std::min(lowest, p.duration);
    }
    const double below = 1.0 - lowest / T_star;
    if (below > 0.0) ++scan_below;
    if (below > 0.01) ++scan_below_one_percent;
    scan_rows << " " << g(lowest, "%.6g") << " | " << g(100.0 * below, "%.2f") << " |\n";
  }

  std::string renderScan(const Options& o) const {
    if (o.probe_fractions.empty()) return {};
    std::ostringstream out;
    out << "\n## Probe scan below T*\n\n`--probe-scan`: below each converged T*, a cold "
           "minimum-effort solve at (1 - F) T* (planManeuver, minimum effort, as the check's "
           "solve at 0.99 T*); a cell is `plan` (converged within the bounds), `plan (not "
           "converged)` (an answer within the bounds that meets the boundary states) or the "
           "outcome, with its iterations. "
        << scan_below << " of " << scanned << " rows have a plan below T* ("
        << scan_below_one_percent << " more than 1 % below).\n\n| # | T* [s] |";
    for (const double f : o.probe_fractions) out << " " << g(1.0 - f, "%.4g") << " T* |";
    out << " lowest T with a plan [s] | below T* [%] |\n|---|---|";
    for (std::size_t i = 0; i < o.probe_fractions.size(); ++i) out << "---|";
    out << "---|---|\n" << scan_rows.str();
    return out.str();
  }

  std::string render(const Options& o) const {
    std::ostringstream out;
    out << "# Minimum time with spinning ends under torque bounds\n\nGenerated by "
           "`scripts/spinning_minimum_time` (studies/spinning_minimum_time_study.cpp; `--count "
        << o.count << " --seed " << o.seed << (o.scheme.empty() ? "" : " --scheme " + o.scheme)
        << (o.steps > 0 ? " --steps " + std::to_string(o.steps) : "") << "`), load average "
        << st::loadAverage()
        << ". The requests: the minimum-time requests with a nonzero end rate of the seeded "
           "bounded suite (test/support/bounded_requests.hpp; their bounds fractions of the stored "
           "references in test/data/bounded_references.csv, the same requests on every library), "
           "re-posed as the command says. "
           "Check: a minimum-effort plan at 0.99 T* refutes T* (planAndCheck).\n\n"
        << "| outcome | requests |\n|---|---|\n";
    for (const auto& [name, n] : outcomes) out << "| " << name << " | " << n << " |\n";
    out << "\nAnswers refuted by the check: **" << wrong
        << "**. Free-time solves converged: " << free_time_converged << " of " << free_time_attempts
        << ". Wall time per request: median " << g(st::median(times), "%.3f") << " s, longest "
        << g(times.empty() ? 0.0 : *std::max_element(times.begin(), times.end()), "%.1f")
        << " s.\n\n| # | request | scheme | N | abs Omega_0 / abs Omega_N [rad/s] | outcome | T* "
           "[s] "
           "| free-time solves converged | iterations | check | wall [s] |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|\n"
        << rows.str() << renderScan(o);
    return out.str();
  }
};

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  Tally tally;
  for (int index = 0; tally.requests < o.count && index < 100 * o.count; ++index) {
    if (o.only >= 0 && index != o.only) continue;
    const std::optional<rb::BoundedRequest> request = drawn(o, index);
    if (!request) continue;
    const rb::VerdictCheck c = rb::planAndCheck(*request);
    tally.add(index, *request, c);
    if (!o.probe_fractions.empty() && c.result.converged() && c.result.minimum_duration > 0.0) {
      std::vector<rb::ProbeAt> probes;
      for (const double f : o.probe_fractions) {
        probes.push_back(rb::probeAt(request->problem, (1.0 - f) * c.result.minimum_duration));
        std::cerr << "  probe " << g(1.0 - f, "%.4g") << " T* = " << g(probes.back().duration)
                  << " s: " << probes.back().outcome << (probes.back().plan ? " (a plan)" : "")
                  << ", " << probes.back().iterations << " iterations, "
                  << g(probes.back().seconds, "%.2f") << " s\n";
        if (o.only >= 0) std::cerr << "    " << probes.back().message << "\n";
      }
      tally.addScan(index, c.result.minimum_duration, probes);
    }
    std::cerr << index << " " << rb::outcomeName(c) << " " << c.wrong << " " << g(c.seconds, "%.2f")
              << " s\n";
    if (o.only >= 0) {
      std::cerr << request->label << "\n"
                << c.result.message() << "\n"
                << rb::attemptLines(c.result);
      break;
    }
    if (!o.out.empty()) std::ofstream(o.out) << tally.render(o);
  }
  const std::string page = tally.render(o);
  if (!o.out.empty())
    std::ofstream(o.out) << page;
  else
    std::cout << page;
  return 0;
}
