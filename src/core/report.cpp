#include "attitude_planner/report.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "attitude_planner/errors.hpp"

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

}  // namespace

std::string planResultJson(const PlanningProblem& problem, const PlanResult& r) {
  std::ostringstream out;
  out << "{\n"
      << "  \"converged\": " << (r.converged ? "true" : "false") << ",\n"
      << "  \"message\": " << jsonString(r.message) << ",\n"
      << "  \"solver\": " << jsonString(r.solver) << ",\n"
      << "  \"scheme\": " << jsonString(schemeName(planScheme(problem, r))) << ",\n"
      << "  \"steps\": " << planSteps(problem, r) << ",\n"
      << "  \"duration\": " << jsonNumber(problem.duration) << ",\n"
      << "  \"iterations\": " << r.iterations << ",\n"
      << "  \"cost\": " << jsonNumber(r.cost) << ",\n"
      << "  \"terminal_attitude_error\": " << jsonNumber(r.terminal_attitude_error) << ",\n"
      << "  \"terminal_velocity_error\": " << jsonNumber(r.terminal_velocity_error) << ",\n"
      << "  \"max_residual\": " << jsonNumber(r.max_residual) << ",\n"
      << "  \"dynamics_residual\": " << jsonNumber(r.dynamics_residual) << ",\n"
      << "  \"solve_time_s\": " << jsonNumber(r.solve_time_s) << ",\n"
      << "  \"extremal\": " << jsonString(r.extremal) << ",\n"
      << "  \"effects\": [";
  for (size_t i = 0; i < r.effects.size(); ++i) out << (i ? ", " : "") << jsonString(r.effects[i]);
  out << "]";
  if (r.accuracy.requested) out << ",\n  \"accuracy\": " << accuracyJson(r.accuracy);
  out << "\n}\n";
  return out.str();
}

std::string planResultText(const PlanningProblem& problem, const PlanResult& r) {
  char buffer[1024];
  std::snprintf(buffer, sizeof buffer,
                "converged                %s\n"
                "message                  %s\n"
                "solver / scheme          %s / %s\n"
                "steps N, duration T      %d, %.6g s (h = %.6g s)\n"
                "iterations               %d\n"
                "cost sum 1/2|tau_k|^2    %.12g N^2 m^2\n"
                "terminal attitude error  %.3g rad\n"
                "terminal velocity error  %.3g rad/s\n"
                "max residual             %.3g\n"
                "dynamics residual        %.3g N m s\n"
                "solve time               %.3f s\n",
                r.converged ? "yes" : "NO", r.message.c_str(), r.solver.c_str(),
                schemeName(planScheme(problem, r)).c_str(), planSteps(problem, r), problem.duration,
                problem.duration / planSteps(problem, r), r.iterations, r.cost,
                r.terminal_attitude_error, r.terminal_velocity_error, r.max_residual,
                r.dynamics_residual, r.solve_time_s);
  std::string text = buffer;
  std::string effects;
  for (const std::string& e : r.effects) effects += (effects.empty() ? "" : ", ") + e;
  text += "planned effects          " + (effects.empty() ? std::string("none") : effects) + "\n";
  if (!r.extremal.empty()) text += "extremal                 " + r.extremal + "\n";
  if (r.accuracy.requested) {
    const AccuracyEstimate& a = r.accuracy;
    std::string tried;
    for (size_t i = 0; i < a.steps_tried.size(); ++i) {
      tried += (i ? ", " : "") + a.schemes_tried[i] + " " + std::to_string(a.steps_tried[i]);
    }
    std::snprintf(buffer, sizeof buffer,
                  "accuracy target          %s <= %.3g\n"
                  "estimated error          %.3g (predicted %.3g, order %.3g; %s)\n"
                  "resolutions solved       %s\n",
                  accuracyMeasureName(a.measure).c_str(), a.target, a.estimated_error,
                  a.predicted_error, a.order, a.method.c_str(), tried.c_str());
    text += buffer;
  }
  return text;
}

void writeDriftTwoInputCsv(const DriftTwoInputTrajectory& tr, const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw InvalidInput("--csv: cannot write '" + path + "'");
  std::fprintf(file.get(), "%s\n", kDriftTwoInputCsvHeader);
  for (std::size_t k = 0; k < tr.g.size(); ++k) {
    const Eigen::Quaterniond q = so3::toQuaternion(tr.g[k]);
    const Eigen::Vector2d& u = tr.u[k];
    const Vector3& p = tr.p[k];
    std::fprintf(file.get(), "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k,
                 tr.t[k], q.w(), q.x(), q.y(), q.z(), u.x(), u.y(), p.x(), p.y(), p.z());
  }
  if (std::fflush(file.get()) != 0) throw InvalidInput("--csv: cannot write '" + path + "'");
}

namespace {

std::string jsonVector(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + jsonNumber(v(i));
  return s + "]";
}

}  // namespace

std::string driftTwoInputPlanJson(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s) {
  std::ostringstream out;
  out << "{\n"
      << "  \"converged\": " << (plan.converged ? "true" : "false") << ",\n"
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
      << "  \"timed_out\": " << (plan.timed_out ? "true" : "false") << ",\n"
      << "  \"solve_time_s\": " << jsonNumber(solve_time_s) << "\n"
      << "}\n";
  return out.str();
}

std::string driftTwoInputPlanText(const DriftTwoInputRequest& request,
                                  const DriftTwoInputPlan& plan, double solve_time_s) {
  char buffer[4096];
  const Vector3& p = plan.initial_costate;
  std::snprintf(buffer, sizeof buffer,
                "system                   drift_two_input (seed 001)\n"
                "converged                %s\n"
                "message                  %s\n"
                "control weights c1, c2   %.6g, %.6g\n"
                "steps N, duration T      %d, %.6g s (h = %.6g s)\n"
                "iterations               %d (%d continuation stages)\n"
                "initial costate p(0)     (%.12g, %.12g, %.12g)\n"
                "cost 1/2 int c.u^2 dt    %.12g\n"
                "extremal                 %s\n"
                "terminal attitude error  %.3g rad\n"
                "solve time               %.4f s\n",
                plan.converged ? "yes" : "NO", plan.message.c_str(), request.weights.c1,
                request.weights.c2, request.steps, request.duration,
                request.duration / request.steps, plan.iterations, plan.continuation_stages, p.x(),
                p.y(), p.z(), plan.cost, plan.extremal.c_str(), plan.terminal_error, solve_time_s);
  return buffer;
}

}  // namespace attitude_planner
