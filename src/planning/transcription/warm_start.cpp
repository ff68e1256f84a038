// Warm starts: the checks of an initial guess and its resampling to the problem's grid
// (warm_start.hpp).
#include "attitude_planner/planning/warm_start.hpp"

#include <cmath>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

std::string row(const std::string& field, const std::string& column, int k) {
  return field + "." + column + "[" + std::to_string(k) + "]";
}

std::string numbers(const Eigen::MatrixXd& m) {
  std::string out = "[";
  for (int i = 0; i < m.size(); ++i) out += (i ? ", " : "") + exactNumber(m.data()[i]);
  return out + "]";
}

/// Every row of another column finite (only the attitudes are used as the start; NLopt takes the
/// torques too when they have a row per node, so their length is not a rule).
void requireFinite(const std::vector<Vector3>& column, const std::string& field,
                   const std::string& name) {
  for (std::size_t k = 0; k < column.size(); ++k) {
    if (!column[k].allFinite()) {
      throw InvalidInput(row(field, name, static_cast<int>(k)) +
                         ": not finite: " + numbers(column[k]));
    }
  }
}

}  // namespace

void validateInitialGuess(const Maneuver& guess, const std::string& field) {
  const std::size_t rows = guess.attitude.size();
  if (rows < 2) {
    throw InvalidInput(field + ": needs at least 2 rows (N >= 1), got " + std::to_string(rows));
  }
  for (std::size_t k = 0; k < rows; ++k) {
    const Matrix3& R = guess.attitude[k];
    if (!R.allFinite()) {
      throw InvalidInput(row(field, "attitude", static_cast<int>(k)) +
                         ": not finite: " + numbers(R));
    }
    const double error = so3::orthogonalityError(R);
    if (error > kGuessOrthogonalityTolerance) {
      throw InvalidInput(row(field, "attitude", static_cast<int>(k)) +
                         ": not a rotation (|R^T R - I| + |det R - 1| = " + exactNumber(error) +
                         ")");
    }
  }
  for (std::size_t k = 0; k < guess.time.size(); ++k) {
    if (!std::isfinite(guess.time[k])) {
      throw InvalidInput(row(field, "time", static_cast<int>(k)) +
                         ": not finite: " + exactNumber(guess.time[k]));
    }
  }
  requireFinite(guess.angular_velocity, field, "angular_velocity");
  requireFinite(guess.torque, field, "torque");
}

Maneuver initialGuessOnGrid(const Maneuver& guess, const PlanningProblem& problem) {
  const int N = problem.steps;
  Maneuver out;
  if (guess.steps() == N) {
    out = guess;
  } else {
    out.attitude = resampleAttitudes(guess, N);
  }
  out.time_step = problem.duration / N;
  out.time.resize(N + 1);
  for (int k = 0; k <= N; ++k) out.time[k] = k * out.time_step;
  return out;
}

PlanningProblem remainderProblem(const PlanningProblem& problem, const Maneuver& plan, int k) {
  const int N = problem.steps;
  if (plan.steps() != N || static_cast<int>(plan.angular_velocity.size()) != N + 1) {
    throw InvalidInput("remainder: the plan has " + std::to_string(plan.steps()) +
                       " steps, the problem " + std::to_string(N));
  }
  if (k < 0 || k > N - kMinSteps) {
    throw InvalidInput("remainder: node k = " + std::to_string(k) + " must be in [0, " +
                       std::to_string(N - kMinSteps) + "] (at least " + std::to_string(kMinSteps) +
                       " steps left)");
  }
  PlanningProblem rest = problem;
  rest.steps = N - k;
  rest.duration = problem.duration * (N - k) / N;
  rest.initial_attitude = plan.attitude[k];
  rest.initial_velocity = plan.angular_velocity[k];
  return rest;
}

Maneuver remainderOfPlan(const Maneuver& plan, int k) {
  const int N = plan.steps();
  if (k < 0 || k >= N) {
    throw InvalidInput("remainder: node k = " + std::to_string(k) + " must be in [0, " +
                       std::to_string(N - 1) + "]");
  }
  Maneuver rest;
  rest.time_step = plan.time_step;
  rest.attitude.assign(plan.attitude.begin() + k, plan.attitude.end());
  if (!plan.angular_velocity.empty()) {
    rest.angular_velocity.assign(plan.angular_velocity.begin() + k, plan.angular_velocity.end());
  }
  if (!plan.torque.empty()) {
    rest.torque.assign(plan.torque.begin() + k, plan.torque.end());
    rest.torque.front() = Vector3::Zero();
  }
  for (int j = k; j <= N; ++j) {
    rest.time.push_back(plan.time.empty() ? (j - k) * plan.time_step : plan.time[j] - plan.time[k]);
  }
  return rest;
}

}  // namespace attitude_planner
