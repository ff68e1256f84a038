// pointing_study (pointing targets): seeded random pointing requests (random inertia,
// b, d, R_0; rest and spinning starts; paper and second_order), each planned as one pointing
// request and judged against a 5° sweep of fixed-attitude solves over the twist refined by golden
// section (test_support::sweepTwist); the time of one pointing solve beside one fixed-attitude
// solve at the chosen twist (median thread CPU time of `--repeats` runs each, side by side). Writes
// the raw data as JSON for scripts/plot_pointing.py (docs/results/pointing.md, scripts/pointing).
//
// With `--constrained C`, C more requests with one binding constraint each (in turn a keep-out cone
// between R_0 b and d, a torque box, a torque norm bound: randomConstrainedPointingRequest). With
// `--minimum-time M`, M minimum-time requests on Betts's body (randomBettsPointingRequest; rest
// to rest, second_order), their "cost" T* and the sweep's fixed-twist T*. With `--sweep 0`, no
// sweep (its fields null): the times of a larger suite alone, judged against a sweep run before.
//
//   pointing_study [--count K] [--constrained C] [--minimum-time M] [--seed S] [--steps N]
//   [--repeats R] [--sweep 0|1] --out RAW.json
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "support/bounded_requests.hpp"
#include "support/pointing_requests.hpp"
#include "support/study_tools.hpp"

namespace ap = attitude_planner;
namespace st = attitude_planner::study;

namespace {

struct Options {
  int count = 32, constrained = 12, minimum_time = 0, steps = 64, repeats = 5;
  int sweep = 1;  ///< 0: no sweep (the times and answers alone; the sweep's fields null)
  int trail = 0;  ///< 1: each request's attempts (both plans') written to stderr
  unsigned seed = 41;
  std::string out;
};

Options parse(int argc, char** argv) {
  Options o;
  st::FlagReader flags;
  flags.add("--count", &o.count)
      .add("--constrained", &o.constrained)
      .add("--minimum-time", &o.minimum_time)
      .add("--seed", &o.seed)
      .add("--steps", &o.steps)
      .add("--repeats", &o.repeats)
      .add("--sweep", &o.sweep)
      .add("--trail", &o.trail)
      .add("--out", &o.out)
      .require("--out");
  st::readFlagsOrExit(flags, argc, argv, "pointing_study",
                      "[--count K] [--constrained C] [--minimum-time M] [--seed S] [--steps N] "
                      "[--repeats R] [--sweep 0|1] [--trail 0|1] --out RAW.json");
  return o;
}

/// The CPU time [s] of this thread: a solve's own work, not the time other processes on a shared
/// machine took from it (wall times here varied 4x between repeats at a load of 7 on 2 cores).
double threadSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/// The median thread CPU time of `repeats` plans of `problem` (planManeuver, single-threaded) and
/// the last result.
ap::PlanResult timed(const ap::PlanningProblem& problem, int repeats, double* seconds) {
  std::vector<double> times;
  ap::PlanResult r;
  for (int i = 0; i < repeats; ++i) {
    const double start = threadSeconds();
    r = ap::planManeuver(problem);
    times.push_back(threadSeconds() - start);
  }
  *seconds = st::median(times);
  return r;
}

/// `r`'s attempts, one a line: stage, start, N, iterations, termination, cost, twist.
void writeTrail(const std::string& label, const ap::PlanResult& r) {
  std::cerr << label << ": " << r.iterations << " iterations, " << r.attempts.size()
            << " attempts\n";
  for (const ap::Attempt& a : r.attempts) {
    std::cerr << "  " << ap::attemptStageName(a.stage) << " " << ap::attemptStartName(a.start)
              << " N=" << a.steps << " it=" << a.iterations << " "
              << ap::terminationName(a.termination) << " cost=" << a.cost
              << " twist=" << a.start_detail.twist << (a.kept ? " kept" : "") << "\n";
  }
}

std::string number(double v) {
  return std::isfinite(v) ? st::formatted(v, "%.17g") : "null";
}

std::string list(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + number(v[i]);
  return s + "]";
}

/// One request's JSON object: the pointing answer, its sweep and the two times.
std::string caseJson(unsigned seed, bool spinning, const std::string& binding,
                     const ap::PlanningProblem& p, int repeats, bool swept, bool trail) {
  double pointing_time = 0.0, fixed_time = 0.0;
  const ap::PlanResult r = timed(p, repeats, &pointing_time);
  ap::PlanningProblem fixed = p;
  fixed.end_condition = ap::EndCondition();
  fixed.final_attitude = ap::pointingAttitude(p.end_condition, r.pointing.final_twist);
  const ap::PlanResult f = timed(fixed, repeats, &fixed_time);
  if (trail) {
    writeTrail("request " + std::to_string(seed) + " pointing", r);
    writeTrail("request " + std::to_string(seed) + " fixed", f);
  }
  attitude_planner::test_support::TwistSweep sweep;
  if (swept) {
    sweep = attitude_planner::test_support::sweepTwist(p);
  } else {
    sweep.best = sweep.best_twist = sweep.worst = std::numeric_limits<double>::quiet_NaN();
  }
  // What the sweep compares: the effort, or T* for a minimum-time request.
  const bool timed_request = p.objective == ap::Objective::MinimumTime;
  const double value = timed_request ? r.minimum_duration : r.cost;
  const double fixed_value = timed_request ? f.minimum_duration : f.cost;
  std::ostringstream out;
  out << "{\"seed\": " << seed << ", \"spinning\": " << (spinning ? "true" : "false")
      << ", \"binding\": \"" << binding << "\""
      << ", \"scheme\": \"" << ap::schemeName(p.scheme) << "\", \"steps\": " << p.steps
      << ", \"converged\": " << (r.converged() ? "true" : "false") << ", \"outcome\": \""
      << attitude_planner::robustness::outcomeName(r)
      << "\", \"least_duration_found\": " << number(r.duration_verdict.least_duration_found)
      << ", \"duration\": " << number(p.duration) << ", \"objective\": \""
      << (timed_request ? "minimum_time" : "minimum_effort") << "\""
      << ", \"cost\": " << number(value) << ", \"twist\": " << number(r.pointing.final_twist)
      << ", \"error\": " << number(r.pointing.error)
      << ", \"stationarity\": " << number(r.pointing.twist_stationarity)
      << ", \"iterations\": " << r.iterations << ", \"attempts\": " << r.attempts.size()
      << ", \"time\": " << number(pointing_time) << ", \"fixed_time\": " << number(fixed_time)
      << ", \"fixed_cost\": " << number(fixed_value) << ", \"fixed_iterations\": " << f.iterations
      << ", \"sweep_best\": " << number(sweep.best)
      << ", \"sweep_best_twist\": " << number(sweep.best_twist)
      << ", \"sweep_worst\": " << number(sweep.worst)
      << ", \"sweep_twists\": " << list(sweep.twists) << ", \"sweep_costs\": " << list(sweep.costs)
      << "}";
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    std::ofstream out(o.out);
    out << "{\"steps\": " << o.steps << ", \"seed\": " << o.seed << ", \"repeats\": " << o.repeats
        << ", \"load\": \"" << st::loadAverage() << "\", \"cases\": [\n";
    for (int i = 0; i < o.count; ++i) {
      const unsigned seed = o.seed * 1000 + i;
      const bool spinning = i % 2 == 1;
      const ap::SchemeKind scheme = i % 4 < 2 ? ap::SchemeKind::Paper : ap::SchemeKind::SecondOrder;
      const ap::PlanningProblem p =
          attitude_planner::test_support::randomPointingRequest(seed, o.steps, spinning, scheme);
      out << (i ? ",\n" : "")
          << caseJson(seed, spinning, "none", p, o.repeats, o.sweep != 0, o.trail != 0);
      out.flush();
      std::cerr << "request " << i + 1 << " of " << o.count << " done\n";
    }
    using attitude_planner::test_support::PointingBinding;
    const std::pair<PointingBinding, const char*> bindings[] = {
        {PointingBinding::KeepOut, "keep_out"},
        {PointingBinding::TorqueBox, "torque_box"},
        {PointingBinding::TorqueNorm, "torque_norm"}};
    for (int i = 0; i < o.constrained; ++i) {
      const unsigned seed = o.seed * 1000 + 500 + i;
      const bool spinning = i % 2 == 1;
      const ap::SchemeKind scheme = i % 4 < 2 ? ap::SchemeKind::Paper : ap::SchemeKind::SecondOrder;
      const auto& [binding, name] = bindings[i % 3];
      const ap::PlanningProblem p =
          attitude_planner::test_support::randomConstrainedPointingRequest(seed, o.steps, spinning,
                                                                           scheme, binding);
      out << (o.count + i ? ",\n" : "")
          << caseJson(seed, spinning, name, p, o.repeats, o.sweep != 0, o.trail != 0);
      out.flush();
      std::cerr << "constrained request " << i + 1 << " of " << o.constrained << " done\n";
    }
    for (int i = 0; i < o.minimum_time; ++i) {
      const unsigned seed = o.seed * 1000 + 800 + i;
      const ap::PlanningProblem p = attitude_planner::test_support::randomBettsPointingRequest(
          seed, o.steps, ap::SchemeKind::SecondOrder);
      const bool first = o.count + o.constrained + i == 0;
      out << (first ? "" : ",\n")
          << caseJson(seed, false, "torque_box", p, o.repeats, o.sweep != 0, o.trail != 0);
      out.flush();
      std::cerr << "minimum-time request " << i + 1 << " of " << o.minimum_time << " done\n";
    }
    out << "\n]}\n";
  } catch (const std::exception& e) {
    std::cerr << "pointing_study: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
