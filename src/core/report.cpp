#include "attitude_planner/report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

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
  if (!std::isfinite(value)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string planResultJson(const PlanningProblem& problem, const PlanResult& r) {
  std::ostringstream out;
  out << "{\n"
      << "  \"converged\": " << (r.converged ? "true" : "false") << ",\n"
      << "  \"message\": " << jsonString(r.message) << ",\n"
      << "  \"solver\": " << jsonString(r.solver) << ",\n"
      << "  \"scheme\": " << jsonString(schemeName(problem.scheme)) << ",\n"
      << "  \"steps\": " << problem.steps << ",\n"
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
  out << "]\n"
      << "}\n";
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
                schemeName(problem.scheme).c_str(), problem.steps, problem.duration,
                problem.duration / problem.steps, r.iterations, r.cost, r.terminal_attitude_error,
                r.terminal_velocity_error, r.max_residual, r.dynamics_residual, r.solve_time_s);
  std::string text = buffer;
  std::string effects;
  for (const std::string& e : r.effects) effects += (effects.empty() ? "" : ", ") + e;
  if (problem.hasTorqueBounds())
    effects += std::string(effects.empty() ? "" : ", ") + "actuator_limits";
  text += "planned effects          " + (effects.empty() ? std::string("none") : effects) + "\n";
  if (!r.extremal.empty()) text += "extremal                 " + r.extremal + "\n";
  return text;
}

}  // namespace attitude_planner
