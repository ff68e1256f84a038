#include "attitude_planner/io/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <memory>
#include <sstream>

#include "attitude_planner/analysis/wheel_peaks.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string jsonNumber(double value) {
  return std::isfinite(value) ? exactNumber(value) : "null";
}

namespace {

/// N and scheme of the returned plan: chosen by the planner when an accuracy target was given.
int planSteps(const PlanningProblem& problem, const PlanResult& r) {
  return r.accuracy.requested && !r.maneuver.attitude.empty() ? r.maneuver.steps() : problem.steps;
}
SchemeKind planScheme(const PlanningProblem& problem, const PlanResult& r) {
  return r.accuracy.requested ? r.scheme : problem.scheme;
}

std::string accuracyJson(const AccuracyEstimate& a) {
  std::ostringstream out;
  out << "{\"measure\": " << jsonString(accuracyMeasureName(a.measure))
      << ", \"target\": " << jsonNumber(a.target)
      << ", \"estimated_error\": " << jsonNumber(a.estimated_error)
      << ", \"predicted_error\": " << jsonNumber(a.predicted_error)
      << ", \"order\": " << jsonNumber(a.order) << ", \"method\": " << jsonString(a.method)
      << ", \"steps_tried\": [";
  for (size_t i = 0; i < a.steps_tried.size(); ++i) out << (i ? ", " : "") << a.steps_tried[i];
  out << "], \"errors_tried\": [";
  for (size_t i = 0; i < a.errors_tried.size(); ++i)
    out << (i ? ", " : "") << jsonNumber(a.errors_tried[i]);
  out << "], \"schemes_tried\": [";
  for (size_t i = 0; i < a.schemes_tried.size(); ++i)
    out << (i ? ", " : "") << jsonString(a.schemes_tried[i]);
  out << "]}";
  return out.str();
}

std::string levelJson(const LevelSummary& level) {
  std::ostringstream out;
  out << "{\"steps\": " << level.steps << ", \"iterations\": " << level.iterations
      << ", \"termination\": " << jsonString(terminationName(level.termination))
      << ", \"relative_gradient\": " << jsonNumber(level.relative_gradient)
      << ", \"newton_decrement\": " << jsonNumber(level.newton_decrement)
      << ", \"reason\": " << jsonString(level.reason) << "}";
  return out.str();
}

std::string vectorJson(const Vector3& v) {
  return "[" + jsonNumber(v.x()) + ", " + jsonNumber(v.y()) + ", " + jsonNumber(v.z()) + "]";
}

/// An attempt's start parameters (StartDetail): a duration of the request's own is null, a zero
/// axis is none.
std::string startDetailJson(const Attempt& a) {
  const StartDetail& d = a.start_detail;
  std::ostringstream out;
  out << "{\"duration\": " << jsonNumber(d.duration)
      << ", \"eigenaxis\": " << vectorJson(d.eigenaxis)
      << ", \"excursion_axis\": " << vectorJson(d.excursion_axis)
      << ", \"excursion\": " << jsonNumber(d.excursion)
      << ", \"excursion_peak\": " << jsonNumber(d.excursion_peak)
      << ", \"cleared_of_cones\": " << (d.cleared_of_cones ? "true" : "false")
      << ", \"coarse_steps\": " << d.coarse_steps
      << ", \"origin\": " << jsonString(attemptStartName(originOf(a)))
      << ", \"twist\": " << jsonNumber(d.twist)
      << ", \"elastic_from_violations\": " << (d.elastic_from_violations ? "true" : "false") << "}";
  return out.str();
}

std::string jsonVector(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + jsonNumber(v(i));
  return s + "]";
}

/// The pointing answer (PlanResult::pointing): the end condition, the twist chosen about the
/// boresight, the final attitude [w, x, y, z] (the returned maneuver's R_N), the residual and the
/// stationarity in the twist.
std::string pointingJson(const PlanningProblem& problem, const PlanResult& r) {
  const Eigen::Quaterniond q = r.maneuver.attitude.empty()
                                   ? Eigen::Quaterniond::Identity()
                                   : so3::toQuaternion(r.maneuver.attitude.back());
  std::ostringstream out;
  out << "{\"body_axis\": " << jsonVector(problem.end_condition.body_axis)
      << ", \"world_direction\": " << jsonVector(problem.end_condition.world_direction)
      << ", \"final_twist\": " << jsonNumber(r.pointing.final_twist)
      << ", \"final_attitude\": " << jsonVector(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()))
      << ", \"error\": " << jsonNumber(r.pointing.error)
      << ", \"twist_gradient\": " << jsonNumber(r.pointing.twist_gradient)
      << ", \"twist_stationarity\": " << jsonNumber(r.pointing.twist_stationarity)
      << ", \"starts\": " << r.pointing.starts << ", \"infeasible_basis\": "
      << jsonString(pointingInfeasibleBasisName(r.pointing.infeasible_basis)) << "}";
  return out.str();
}

/// One attempt of the trail (PlanResult::attempts) as a JSON object; a cost without a plan is
/// null.
std::string attemptJson(const Attempt& a) {
  std::ostringstream out;
  out << "{\"stage\": " << jsonString(attemptStageName(a.stage))
      << ", \"start\": " << jsonString(attemptStartName(a.start))
      << ", \"formulation\": " << jsonString(formulationName(a.formulation))
      << ", \"long_way\": " << (a.homotopy.long_way ? "true" : "false")
      << ", \"extra_revolutions\": " << a.homotopy.extra_revolutions << ", \"steps\": " << a.steps
      << ", \"termination\": " << jsonString(terminationName(a.termination))
      << ", \"iterations\": " << a.iterations << ", \"cost\": " << jsonNumber(a.cost)
      << ", \"kept\": " << (a.kept ? "true" : "false")
      << ", \"plan_checked\": " << (a.plan_checked ? "true" : "false")
      << ", \"start_detail\": " << startDetailJson(a) << "}";
  return out.str();
}

/// Per wheel: the plan's peak |h_w,i| and |u_i|, their limits and margins (limit − peak, < 0 where
/// the plan exceeds it), the array's peak |A h_w| with the envelope's margin (null: none), and
/// which torques the plan's effort sums (PlanResult::minimized_effort).
/// Torque peaks over the nodes the plan carries torques at (1..N−1; 0..N with end torques).
std::string wheelsJson(const PlanningProblem& problem, const PlanResult& r) {
  const ReactionWheels& wheels = problem.reaction_wheels;
  const WheelPeaks peaks = planWheelPeaks(
      wheels,
      wheelStates(problem.scheme, problem.inertia, wheels, r.maneuver, problem.worldDisturbance()),
      schemeHasEndTorques(problem.scheme));
  const double peak_norm = peaks.peak_momentum_norm;
  std::ostringstream out;
  out << "{\"wheels\": [";
  for (int i = 0; i < wheels.count(); ++i) {
    const double peak_h = peaks.peak_momentum(i), peak_u = peaks.peak_torque(i);
    out << (i ? ", " : "") << "{\"name\": " << jsonString(wheelName(i))
        << ", \"peak_momentum\": " << jsonNumber(peak_h)
        << ", \"max_momentum\": " << jsonNumber(wheels.momentumLimit(i))
        << ", \"momentum_margin\": " << jsonNumber(wheels.momentumLimit(i) - peak_h)
        << ", \"peak_torque\": " << jsonNumber(peak_u)
        << ", \"max_torque\": " << jsonNumber(wheels.torqueLimit(i))
        << ", \"torque_margin\": " << jsonNumber(wheels.torqueLimit(i) - peak_u) << "}";
  }
  const double envelope = wheels.max_momentum_norm;
  out << "], \"peak_momentum_norm\": " << jsonNumber(peak_norm)
      << ", \"max_momentum_norm\": " << (std::isfinite(envelope) ? jsonNumber(envelope) : "null")
      << ", \"momentum_norm_margin\": "
      << (std::isfinite(envelope) ? jsonNumber(envelope - peak_norm) : "null")
      << ", \"effort_minimized\": " << jsonString(minimizedEffortName(r.minimized_effort)) << "}";
  return out.str();
}

/// {"kind": ..., "figures": {name: value, ...}}: the driver's verdict as data (driver_verdict.hpp).
std::string verdictJson(const Verdict& verdict) {
  std::ostringstream out;
  out << "{\"kind\": " << jsonString(verdictKindName(verdict)) << ", \"figures\": {";
  const std::vector<VerdictFigure> figures = verdictFigures(verdict);
  for (std::size_t i = 0; i < figures.size(); ++i) {
    out << (i ? ", " : "") << jsonString(figures[i].name) << ": " << jsonNumber(figures[i].value);
  }
  out << "}}";
  return out.str();
}

}  // namespace

std::string planResultJson(const PlanningProblem& problem, const PlanResult& r) {
  std::ostringstream out;
  out << "{\n"
      << "  \"converged\": " << (r.converged() ? "true" : "false") << ",\n"
      << "  \"termination\": " << jsonString(terminationName(r.termination)) << ",\n"
      << "  \"message\": " << jsonString(r.message()) << ",\n"
      << "  \"solver\": " << jsonString(r.solver) << ",\n"
      << "  \"scheme\": " << jsonString(schemeName(planScheme(problem, r))) << ",\n"
      << "  \"steps\": " << planSteps(problem, r) << ",\n"
      << "  \"duration\": " << jsonNumber(r.duration > 0 ? r.duration : problem.duration) << ",\n"
      << "  \"objective\": " << jsonString(objectiveName(problem.objective)) << ",\n"
      << "  \"minimum_duration\": " << jsonNumber(r.minimum_duration) << ",\n"
      << "  \"minimum_time\": {\"kkt_point\": " << (r.minimum_time.kkt_point ? "true" : "false")
      << ", \"stationarity\": " << jsonNumber(r.minimum_time.stationarity)
      << ", \"time_stationarity\": " << jsonNumber(r.minimum_time.time_stationarity)
      << ", \"complementarity\": " << jsonNumber(r.minimum_time.complementarity)
      << ", \"solves\": " << r.minimum_time.solves << ", \"second_order_sufficient\": "
      << (r.minimum_time.second_order_sufficient ? "true" : "false")
      << ", \"cone_clearings\": " << r.minimum_time.cone_clearings
      << ", \"cone_clearing_iterations\": " << r.minimum_time.cone_clearing_iterations
      << ", \"cone_clearings_joined\": " << r.minimum_time.cone_clearings_joined << "},\n"
      << "  \"duration_verdict\": {\"lower_bound\": " << jsonNumber(r.duration_verdict.lower_bound)
      << ", \"lower_bound_basis\": " << jsonString(r.duration_verdict.lower_bound_basis)
      << ", \"proven_infeasible\": " << (r.duration_verdict.proven_infeasible ? "true" : "false")
      << ", \"least_duration_found\": " << jsonNumber(r.duration_verdict.least_duration_found)
      << ", \"longest_duration_found\": " << jsonNumber(r.duration_verdict.longest_duration_found)
      << ", \"rate_limit\": " << jsonNumber(r.duration_verdict.rate_limit)
      << ", \"torque_limit\": " << jsonNumber(r.duration_verdict.torque_limit)
      << ", \"plan_within_bounds\": " << (r.duration_verdict.plan_within_bounds ? "true" : "false")
      << ", \"no_plan_from\": " << jsonNumber(r.duration_verdict.no_plan_from)
      << ", \"no_plan_to\": " << jsonNumber(r.duration_verdict.no_plan_to) << "},\n"
      << "  \"verdict\": " << verdictJson(r.verdict) << ",\n"
      << "  \"iterations\": " << r.iterations << ",\n"
      << "  \"cost\": " << jsonNumber(r.cost) << ",\n"
      << "  \"effort\": " << jsonNumber(r.effort) << ",\n"
      << "  \"terminal_attitude_error\": " << jsonNumber(r.terminal_attitude_error) << ",\n"
      << "  \"terminal_velocity_error\": " << jsonNumber(r.terminal_velocity_error) << ",\n"
      << "  \"max_residual\": " << jsonNumber(r.max_residual) << ",\n"
      << "  \"dynamics_residual\": " << jsonNumber(r.dynamics_residual) << ",\n"
      << "  \"step_residual\": " << jsonNumber(r.step_residual) << ",\n"
      << "  \"replay_miss\": " << jsonNumber(r.replay_miss) << ",\n"
      << "  \"replay_measured\": " << (r.replay_measured ? "true" : "false") << ",\n"
      << "  \"solve_time_s\": " << jsonNumber(r.solve_time_s) << ",\n"
      << "  \"extremal\": " << jsonString(r.extremal) << ",\n"
      << "  \"effects\": [";
  for (size_t i = 0; i < r.effects.size(); ++i) out << (i ? ", " : "") << jsonString(r.effects[i]);
  out << "],\n  \"levels\": [";
  for (size_t i = 0; i < r.levels.size(); ++i) out << (i ? ", " : "") << levelJson(r.levels[i]);
  out << "],\n  \"attempts\": [";
  for (size_t i = 0; i < r.attempts.size(); ++i) {
    out << (i ? ",\n    " : "\n    ") << attemptJson(r.attempts[i]);
  }
  out << "],\n  \"constraints\": [";
  for (size_t i = 0; i < r.constraints.size(); ++i)
    out << (i ? ", " : "") << jsonString(r.constraints[i]);
  out << "],\n  \"max_constraint_violation\": " << jsonNumber(r.max_constraint_violation)
      << ",\n  \"active_constraints\": " << r.active_constraints
      << ",\n  \"max_violation_between_nodes\": " << jsonNumber(r.max_violation_between_nodes);
  if (r.accuracy.requested) out << ",\n  \"accuracy\": " << accuracyJson(r.accuracy);
  if (problem.reaction_wheels.present() && r.maneuver.steps() > 0) {
    out << ",\n  \"reaction_wheels\": " << wheelsJson(problem, r);
  }
  if (r.pointing.active) {
    out << ",\n  \"final_twist\": " << jsonNumber(r.pointing.final_twist)
        << ",\n  \"pointing\": " << pointingJson(problem, r);
  }
  out << "\n}\n";
  return out.str();
}

namespace {

/// One aligned "label  value" line of the text summary.
std::string line(const std::string& label, const std::string& value) {
  std::string text = label;
  text.resize(std::max<std::size_t>(label.size() + 1, 25), ' ');
  return text + value + "\n";
}

/// A number in printf's %g style with `digits` significant digits (std::string, no buffer).
std::string general(double value, int digits) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

}  // namespace

std::string planResultText(const PlanningProblem& problem, const PlanResult& r) {
  const int N = planSteps(problem, r);
  std::string text;
  text += line("converged", r.converged() ? "yes" : "NO (" + terminationName(r.termination) + ")");
  text += line("message", r.message());
  text += line("solver / scheme", r.solver + " / " + schemeName(planScheme(problem, r)));
  const double T = r.duration > 0 ? r.duration : problem.duration;
  text += line("steps N, duration T",
               std::to_string(N) + ", " + general(T, 6) + " s (h = " + general(T / N, 6) + " s)");
  if (problem.objective == Objective::MinimumTime) {
    text += line("minimum duration T*", general(r.minimum_duration, 8) + " s");
  }
  text += line("iterations", std::to_string(r.iterations));
  text += line("cost sum 1/2|tau_k|^2", general(r.cost, 12) + " N^2 m^2");
  text += line("effort h*cost", general(r.effort, 12) + " N^2 m^2 s");
  text += line("terminal attitude error", general(r.terminal_attitude_error, 3) + " rad");
  text += line("terminal velocity error", general(r.terminal_velocity_error, 3) + " rad/s");
  text += line("max residual", general(r.max_residual, 3));
  text += line("dynamics residual", general(r.dynamics_residual, 3) + " N m s");
  text += line("step residual", general(r.step_residual, 3) + " (relative)");
  text +=
      line("replay miss", r.replay_measured
                              ? general(r.replay_miss, 3) + " rad (open-loop replay, sensitivity)"
                              : "not measured (a stopped plan is handed over without its replay)");
  std::ostringstream time;
  time << std::fixed << std::setprecision(3) << r.solve_time_s << " s";
  text += line("solve time", time.str());
  std::string effects;
  for (const std::string& e : r.effects) effects += (effects.empty() ? "" : ", ") + e;
  text += line("planned effects", effects.empty() ? std::string("none") : effects);
  if (!r.extremal.empty()) text += line("extremal", r.extremal);
  if (r.pointing.active) {
    text += line("final twist", general(r.pointing.final_twist, 12) + " rad about the boresight");
    text += line("pointing error", general(r.pointing.error, 3) + " rad");
  }
  if (r.levels.size() > 1) {
    std::string levels;
    for (const LevelSummary& level : r.levels) {
      levels += (levels.empty() ? "" : ", ") + std::string("N = ") + std::to_string(level.steps) +
                ": " + std::to_string(level.iterations) + " it " +
                terminationName(level.termination);
    }
    text += line("grid levels", levels);
  }
  if (!r.constraints.empty()) {
    std::string names;
    for (const std::string& c : r.constraints) names += (names.empty() ? "" : ", ") + c;
    text += line("constraints", names + " (" + std::to_string(r.active_constraints) +
                                    " active, max violation " +
                                    general(r.max_constraint_violation, 3) + ", between nodes " +
                                    general(r.max_violation_between_nodes, 3) + ")");
  }
  if (r.accuracy.requested) {
    const AccuracyEstimate& a = r.accuracy;
    std::string tried;
    for (size_t i = 0; i < a.steps_tried.size(); ++i) {
      tried += (i ? ", " : "") + a.schemes_tried[i] + " " + std::to_string(a.steps_tried[i]);
    }
    text += line("accuracy target", accuracyMeasureName(a.measure) + " <= " + general(a.target, 3));
    text += line("estimated error", general(a.estimated_error, 3) + " (predicted " +
                                        general(a.predicted_error, 3) + ", order " +
                                        general(a.order, 3) + "; " + a.method + ")");
    text += line("resolutions solved", tried);
  }
  return text;
}

std::string driftTwoInputPlanJson(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s) {
  std::ostringstream out;
  out << "{\n"
      << "  \"converged\": " << (plan.converged() ? "true" : "false") << ",\n"
      << "  \"termination\": " << jsonString(terminationName(plan.termination)) << ",\n"
      << "  \"message\": " << jsonString(plan.message) << ",\n"
      << "  \"system\": \"drift_two_input\",\n"
      << "  \"steps\": " << request.steps << ",\n"
      << "  \"duration\": " << jsonNumber(request.duration) << ",\n"
      << "  \"control_weights\": "
      << jsonVector(Eigen::Vector2d(request.weights.c1, request.weights.c2)) << ",\n"
      << "  \"iterations\": " << plan.iterations << ",\n"
      << "  \"continuation_stages\": " << plan.continuation_stages << ",\n"
      << "  \"cost\": " << jsonNumber(plan.cost) << ",\n"
      << "  \"terminal_attitude_error\": " << jsonNumber(plan.terminal_error) << ",\n"
      << "  \"initial_costate\": " << jsonVector(plan.initial_costate) << ",\n"
      << "  \"initial_costate_guess\": "
      << (request.initial_costate ? jsonVector(*request.initial_costate) : std::string("null"))
      << ",\n"
      << "  \"extremal\": " << jsonString(plan.extremal) << ",\n"
      << "  \"other_extremal_costs\": [";
  for (size_t i = 0; i < plan.other_costs.size(); ++i) {
    out << (i ? ", " : "") << jsonNumber(plan.other_costs[i]);
  }
  out << "],\n"
      << "  \"starts\": " << plan.starts << ",\n"
      << "  \"converged_starts\": " << plan.converged_starts << ",\n"
      << "  \"integration_steps\": " << plan.integration_steps << ",\n"
      << "  \"timed_out\": " << (plan.termination == Termination::TimedOut ? "true" : "false")
      << ",\n"
      << "  \"solve_time_s\": " << jsonNumber(solve_time_s) << "\n"
      << "}\n";
  return out.str();
}

std::string driftTwoInputPlanText(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s) {
  const Vector3& p = plan.initial_costate;
  std::string text;
  text += line("system", "drift_two_input (seed 001)");
  text += line("converged", plan.converged() ? "yes" : "NO");
  text += line("message", plan.message);
  text += line("control weights c1, c2",
               general(request.weights.c1, 6) + ", " + general(request.weights.c2, 6));
  text += line("steps N, duration T",
               std::to_string(request.steps) + ", " + general(request.duration, 6) +
                   " s (h = " + general(request.duration / request.steps, 6) + " s)");
  text +=
      line("iterations", std::to_string(plan.iterations) + " (" +
                             std::to_string(plan.continuation_stages) + " continuation stages)");
  text += line("initial costate p(0)", "(" + general(p.x(), 12) + ", " + general(p.y(), 12) + ", " +
                                           general(p.z(), 12) + ")");
  text += line("cost 1/2 int c.u^2 dt", general(plan.cost, 12));
  text += line("extremal", plan.extremal);
  text += line("terminal attitude error", general(plan.terminal_error, 3) + " rad");
  std::ostringstream time;
  time << std::fixed << std::setprecision(4) << solve_time_s << " s";
  text += line("solve time", time.str());
  return text;
}

}  // namespace attitude_planner
