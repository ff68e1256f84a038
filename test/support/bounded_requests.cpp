#include "support/bounded_requests.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "attitude_planner/analysis/replanning.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"
#include "support/bounded_references.hpp"
#include "support/random_problems.hpp"

namespace attitude_planner {
namespace robustness {

namespace {

/// A converged plan may leave a bound by this much (relative) before the check calls it wrong.
constexpr double kPlanOutsideBounds = 1e-6;

/// f in [lo, hi], from the case's seed (deterministic, no std::*_distribution).
double fractionOf(std::uint64_t seed, double lo, double hi) {
  const double u = static_cast<double>((seed >> 11) % 1000003) / 1000003.0;
  return lo + (hi - lo) * u;
}

}  // namespace

std::optional<BoundedRequest> boundedRequest(std::uint64_t suite_seed, int index) {
  const RandomCase base = randomCase(suite_seed, index);
  const BoundedReference ref = storedReference(suite_seed, index);
  if (!ref.converged) return std::nullopt;
  BoundedRequest r;
  r.index = index;
  r.problem = base.problem;
  r.fraction = fractionOf(base.seed, 0.6, 0.9);
  static const char* kKinds[] = {"norm", "box", "norm+rate", "replan"};
  r.kind = kKinds[index % 4];
  if (r.kind == "replan") {
    r.problem = remainderProblem(base.problem, ref.rest_node, ref.rest_attitude, ref.rest_rate);
    r.problem.constraints = {PlanningConstraint::maxTorqueNorm(r.fraction * ref.rest_peak_torque)};
  } else if (r.kind == "box") {
    r.problem.max_torque = r.fraction * ref.peak_axis_torque;
  } else {
    r.problem.constraints = {PlanningConstraint::maxTorqueNorm(r.fraction * ref.peak_torque)};
  }
  if (r.kind == "norm+rate") {
    const double boundary =
        std::max(base.problem.initial_velocity.norm(), base.problem.final_velocity.norm());
    const double rate = fractionOf(base.seed >> 7, 0.8, 1.0) * ref.peak_rate;
    r.problem.constraints.push_back(PlanningConstraint::maxAngularRate(std::max(rate, boundary)));
  }
  if ((index / 4) % 4 == 3) {
    r.problem.objective = Objective::MinimumTime;
    r.problem.duration = 0.0;
  }
  char label[300];
  std::snprintf(label, sizeof label, "%s, %s f=%.2f%s", base.label.c_str(), r.kind.c_str(),
                r.fraction, r.problem.objective == Objective::MinimumTime ? " minimum_time" : "");
  r.label = label;
  return r;
}

namespace {

/// The least T of the minimum-time problem under the same bounds (0: none converged).
double minimumTimeOf(const PlanningProblem& problem, const SolverOptions& options) {
  PlanningProblem fastest = problem;
  fastest.objective = Objective::MinimumTime;
  fastest.time_margin = 0.0;
  fastest.duration = 0.0;
  try {
    const PlanResult r = planManeuver(fastest, options);
    return r.converged() ? r.minimum_duration : 0.0;
  } catch (const FieldError&) {
    return 0.0;
  }
}

/// Whether the plan starts and ends at the request's states (within 1e-8, rates relative to the
/// larger boundary rate) and meets every bound: a plan of the request at its T.
bool planMeetsRequest(const PlanningProblem& p, const Maneuver& m) {
  if (m.attitude.empty()) return false;
  const double rate_scale = std::max({1.0, p.initial_velocity.norm(), p.final_velocity.norm()});
  const bool ends = so3::angleBetween(m.attitude.front(), p.initial_attitude) <= 1e-8 &&
                    so3::angleBetween(m.attitude.back(), p.final_attitude) <= 1e-8 &&
                    (m.angular_velocity.front() - p.initial_velocity).norm() <= 1e-8 * rate_scale &&
                    (m.angular_velocity.back() - p.final_velocity).norm() <= 1e-8 * rate_scale;
  return ends && checkConstraints(p, m).max_relative_violation <= kPlanOutsideBounds;
}

/// Whether `m` is a plan of the request at its own T (N steps ending at T) that meets it
/// (planMeetsRequest). An "infeasible" answer may carry a local minimum-time plan at another T.
bool planAtTMeetsRequest(const PlanningProblem& p, const Maneuver& m) {
  const bool at_T = m.steps() == p.steps && !m.time.empty() &&
                    std::abs(m.time.back() - p.duration) <= 1e-9 * p.duration;
  return at_T && planMeetsRequest(p, m);
}

void checkVerdict(const PlanningProblem& p, const SolverOptions& options, VerdictCheck* check) {
  const PlanResult& r = check->result;
  const DurationVerdict& v = r.duration_verdict;
  if (!r.converged() && v.plan_within_bounds && !planMeetsRequest(p, r.maneuver)) {
    check->wrong = "within bounds";
  } else if (r.termination == Termination::Infeasible && p.duration > 0.0 &&
             planAtTMeetsRequest(p, r.maneuver)) {
    check->wrong = "infeasible with a plan";
  } else if (r.converged() && p.objective == Objective::MinimumEffort) {
    const double outside = checkConstraints(p, r.maneuver).max_relative_violation;
    if (outside > kPlanOutsideBounds) check->wrong = "converged";
  } else if (r.converged() && r.minimum_duration > 0.0) {
    check->check_duration = 0.99 * r.minimum_duration;
    if (probeAt(p, check->check_duration, options).converged) check->wrong = "minimum time";
  } else if (r.termination == Termination::Infeasible && v.proven_infeasible) {
    const double T_star = minimumTimeOf(p, options);
    check->check_duration = T_star;
    if (T_star > 0.0 && T_star < p.duration) check->wrong = "proven";
  } else if (r.termination == Termination::Infeasible && v.least_duration_found > 0.0) {
    check->check_duration = 0.98 * v.least_duration_found;
    if (p.objective == Objective::MinimumEffort && check->check_duration > p.duration &&
        probeAt(p, check->check_duration, options).converged) {
      check->wrong = "local";
    }
  }
}

}  // namespace

ProbeAt probeAt(const PlanningProblem& problem, double T, const SolverOptions& options) {
  PlanningProblem at = problem;
  at.objective = Objective::MinimumEffort;
  at.time_margin = 0.0;
  at.duration = T;
  ProbeAt probe;
  probe.duration = T;
  const auto start = std::chrono::steady_clock::now();
  try {
    const PlanResult r = planManeuver(at, options);
    probe.converged = r.converged() &&
                      checkConstraints(at, r.maneuver).max_relative_violation <= kPlanOutsideBounds;
    probe.plan = probe.converged || (!r.converged() && planAtTMeetsRequest(at, r.maneuver));
    probe.outcome = outcomeName(r);
    probe.message = r.message();
    probe.iterations = r.iterations;
  } catch (const FieldError& e) {
    probe.outcome = "input error";
    probe.message = e.what();
  }
  probe.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return probe;
}

VerdictCheck planAndCheck(const BoundedRequest& request, const SolverOptions& options) {
  VerdictCheck check;
  const auto start = std::chrono::steady_clock::now();
  try {
    check.result = planManeuver(request.problem, options);
  } catch (const FieldError& e) {
    check.input_error = e.what();
    return check;
  }
  check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  checkVerdict(request.problem, options, &check);
  return check;
}

std::string attemptLines(const PlanResult& result) {
  std::ostringstream out;
  for (const Attempt& a : result.attempts) {
    out << "  " << attemptStageName(a.stage) << " " << attemptStartName(a.start) << " N=" << a.steps
        << " " << terminationName(a.termination) << " it=" << a.iterations << " cost=" << a.cost
        << (a.kept ? " kept" : "") << "\n";
  }
  return out.str();
}

std::string outcomeName(const VerdictCheck& check) {
  if (!check.input_error.empty()) return "input error";
  return outcomeName(check.result);
}

std::string outcomeName(const PlanResult& r) {
  if (r.termination == Termination::Infeasible) {
    return r.duration_verdict.proven_infeasible ? "infeasible (proven)" : "infeasible (local)";
  }
  return terminationName(r.termination);
}

}  // namespace robustness
}  // namespace attitude_planner
