#include "attitude_planner/ros/diagnostics.hpp"

#include <algorithm>
#include <sstream>
#include <vector>

#include "attitude_planner/PlanErrorCode.h"

namespace attitude_planner {

namespace {

using diagnostic_msgs::DiagnosticStatus;

void add(DiagnosticStatus* status, const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue pair;
  pair.key = key;
  pair.value = value;
  status->values.push_back(pair);
}

template <class T>
void add(DiagnosticStatus* status, const std::string& key, const T& value) {
  std::ostringstream s;
  s << value;
  add(status, key, s.str());
}

}  // namespace

std::string errorCodeName(int code) {
  switch (code) {
    case PlanErrorCode::SUCCESS:
      return "SUCCESS";
    case PlanErrorCode::INVALID_INPUT:
      return "INVALID_INPUT";
    case PlanErrorCode::NOT_CONVERGED:
      return "NOT_CONVERGED";
    case PlanErrorCode::TIMED_OUT:
      return "TIMED_OUT";
    case PlanErrorCode::CANCELLED:
      return "CANCELLED";
    case PlanErrorCode::STEP_TOO_LARGE:
      return "STEP_TOO_LARGE";
    case PlanErrorCode::INFEASIBLE:
      return "INFEASIBLE";
    case PlanErrorCode::REJECTED:
      return "REJECTED";
    case PlanErrorCode::INTERNAL_ERROR:
      return "INTERNAL_ERROR";
    default:
      return "code " + std::to_string(code);
  }
}

void AnswerStatistics::record(int error_code, double wall_time_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.answered;
  if (error_code == PlanErrorCode::SUCCESS) {
    ++counts_.succeeded;
  } else {
    ++counts_.failed[error_code];
  }
  counts_.last_code = error_code;
  counts_.last_s = wall_time_s;
  recent_.push_back(wall_time_s);
  if (recent_.size() > kRecent) recent_.pop_front();
}

AnswerStatistics::Summary AnswerStatistics::summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Summary s = counts_;
  if (recent_.empty()) return s;
  std::vector<double> times(recent_.begin(), recent_.end());
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  s.median_s = times[times.size() / 2];
  s.max_s = *std::max_element(times.begin(), times.end());
  return s;
}

DiagnosticStatus plannerStatus(const std::string& name, const AnswerStatistics::Summary& answers,
                               const PlannerLoad& load) {
  DiagnosticStatus status;
  status.name = name;
  status.hardware_id = "attitude_planner";
  std::ostringstream message;
  message << answers.answered << " answered, " << answers.answered - answers.succeeded
          << " failed; " << load.busy_workers << " of " << load.action_workers
          << " action workers busy";
  status.level = DiagnosticStatus::OK;
  if (load.busy_workers >= load.action_workers || load.stopping_solves > 0) {
    status.level = DiagnosticStatus::WARN;
    if (load.busy_workers >= load.action_workers) message << " (new goals are rejected)";
    if (load.stopping_solves > 0)
      message << "; " << load.stopping_solves << " stopped solves still running";
  }
  if (answers.last_code == PlanErrorCode::INTERNAL_ERROR) {
    status.level = DiagnosticStatus::ERROR;
    message << "; the last answer was INTERNAL_ERROR (a bug in the planner: please report it)";
  }
  status.message = message.str();
  add(&status, "answered", answers.answered);
  add(&status, "succeeded", answers.succeeded);
  for (const auto& [code, count] : answers.failed)
    add(&status, "failed " + errorCodeName(code), count);
  add(&status, "last answer", answers.answered > 0 ? errorCodeName(answers.last_code) : "none");
  add(&status, "last wall time [s]", answers.last_s);
  add(&status, "median wall time [s] (last 100)", answers.median_s);
  add(&status, "longest wall time [s] (last 100)", answers.max_s);
  add(&status, "action workers", load.action_workers);
  add(&status, "busy action workers", load.busy_workers);
  add(&status, "stopped solves still running", load.stopping_solves);
  return status;
}

DiagnosticStatus trackerStatus(const std::string& name, const TrackerHealth& health) {
  DiagnosticStatus status;
  status.name = name;
  status.hardware_id = "attitude_planner";
  std::ostringstream message;
  message << health.mode << " (" << health.plant << " plant), "
          << (health.running ? "flying" : "idle");
  status.level = DiagnosticStatus::OK;
  if (health.plant == "external" && health.running && !health.measurement_problem.empty()) {
    status.level = DiagnosticStatus::WARN;
    message << "; no usable measurement: " << health.measurement_problem;
  }
  if (health.replan_failures > 0) {
    status.level = DiagnosticStatus::WARN;
    message << "; " << health.replan_failures << " re-plans failed in this run";
  }
  if (!health.frame_conflict.empty()) {
    status.level = DiagnosticStatus::ERROR;
    message << "; " << health.frame_conflict;
  }
  status.message = message.str();
  add(&status, "mode", health.mode);
  add(&status, "plant", health.plant);
  add(&status, "running", health.running ? "true" : "false");
  add(&status, "maneuver time [s]", health.time);
  add(&status, "duration [s]", health.duration);
  add(&status, "attitude error [rad]", health.attitude_error);
  add(&status, "angular velocity error [rad/s]", health.rate_error);
  add(&status, "measurement age [s]", health.measurement_age);
  add(&status, "wheel measurement age [s]", health.wheel_measurement_age);
  add(&status, "re-plans adopted", health.replans);
  add(&status, "re-plans failed", health.replan_failures);
  add(&status, "runs finished", health.runs_finished);
  return status;
}

}  // namespace attitude_planner
