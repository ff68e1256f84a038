// attitude_planner_node: the planner behind services and an action. A thin adapter: it converts
// the request, calls planManeuver() / planDriftTwoInput() (the same entry points as the CLI) and
// fills the response.
//
//   service  plan_attitude_maneuver         (attitude_planner/PlanAttitudeManeuver)   rigid body
//   action   plan_attitude_maneuver_action  (attitude_planner/PlanAttitudeManeuverAction)
//   service  plan_drift_two_input           (attitude_planner/PlanDriftTwoInput)  seed 001's
//            drift + two-input system; a service of its own rather than a `system` field in
//            PlanAttitudeManeuver: the two problems share no request field but the attitudes and
//            T, N, and adding fields would change the MD5 sum of a published interface (existing
//            clients would be refused by the node).
//
// Private parameters (defaults for the request fields left empty / zero):
//   ~default_scheme  string  "paper"    discretization ("paper" | "variational")
//   ~solver          string  "newton"   "newton" | "nlopt"
//   ~tolerance       double  1e-10      optimality tolerance (> 0)
//   ~max_iterations  int     200        iteration limit (> 0)
//   ~time_budget     double  30.0       wall-time limit per solve [s] (0 = none)
//   ~max_steps       int     100000     largest accepted N (>= 4; both services)
//   ~default_steps   int     128        N of a request with steps 0 (>= 4, <= ~max_steps; both
//                                       services)
//   ~max_solve_time  double  300.0      cap on every request's time budget [s] (> 0): a request
//                                       asking for more (or for none) gets this budget
//   ~world_frame     string  "world"    frame_id of the returned maneuver
//   ~body_frame      string  "body"     child_frame_id of the returned maneuver
//   ~threads         int     4          service threads (>= 2: concurrent requests are solved in
//   parallel)
//
// Each solve owns all its state, so concurrent requests never share mutable data: service calls
// are solved in parallel (~threads); the action serves one goal at a time (a new goal preempts
// the running one, which ends PREEMPTED with error CANCELLED).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <actionlib/server/simple_action_server.h>
#include <ros/ros.h>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanAttitudeManeuverAction.h"
#include "attitude_planner/PlanDriftTwoInput.h"
#include "attitude_planner/PlanErrorCode.h"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {

/// What one planning request produced, whatever happened.
struct PlanOutcome {
  int error_code = PlanErrorCode::INTERNAL_ERROR;  ///< a PlanErrorCode constant
  std::string message;                             ///< outcome in words
  bool solver_ran = false;                         ///< `result` is meaningful
  PlanResult result;                               ///< the core's result
  PlanningProblem problem;                         ///< the parsed problem (if parsing succeeded)
};

/// The PlanErrorCode constant of a termination: the one mapping from the core's status to the
/// interface's (INTERNAL_ERROR is not a termination: it is an exception the core did not expect).
int errorCodeOf(Termination termination);

/// Runs one request through the core. `keep_going(info, elapsed_s)` is called after every
/// iteration; returning false cancels. Never throws.
template <class Request>
PlanOutcome planRequest(const Request& req, const ros_conversions::PlannerDefaults& defaults,
                        const std::function<bool(const IterationInfo&, double)>& keep_going);

/// The error code and message of the exception being handled (call only inside a catch block):
/// InvalidInput and StepTooLarge through errorCodeOf, anything else → INTERNAL_ERROR.
void describeCurrentException(int* error_code, std::string* message);

/// What one plan_drift_two_input request produced, whatever happened.
struct DriftPlanOutcome {
  int error_code = PlanErrorCode::INTERNAL_ERROR;  ///< a PlanErrorCode constant
  std::string message;                             ///< outcome in words
  bool solver_ran = false;                         ///< `plan` is meaningful
  DriftTwoInputPlan plan;                          ///< the core's result
  DriftTwoInputRequest request;                    ///< the parsed request (if parsing succeeded)
  double solve_time_s = 0.0;                       ///< wall time of planDriftTwoInput [s]
};

/// Runs one plan_drift_two_input request through planDriftTwoInput(): converged → SUCCESS,
/// otherwise NOT_CONVERGED; bad fields → INVALID_INPUT. Never throws.
DriftPlanOutcome planDriftRequest(const PlanDriftTwoInput::Request& req,
                                  const ros_conversions::PlannerDefaults& defaults);

/// Copies a drift outcome into the plan_drift_two_input response.
void fillDriftResponse(const DriftPlanOutcome& outcome, const std::string& world_frame,
                       const std::string& body_frame, PlanDriftTwoInput::Response* res);

/// Copies an outcome into a service response or action result (same fields).
template <class Response>
void fillResponse(const PlanOutcome& outcome, const std::string& world_frame,
                  const std::string& body_frame, Response* res);

/// The node: service + action around planRequest().
class PlannerNode {
 public:
  /// Reads the private parameters (range-checked, logged fall-back) and advertises the interfaces.
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& private_nh);

  /// Service threads requested by ~threads.
  int threads() const { return threads_; }

 private:
  /// Service callback: always returns true (the outcome is in the response).
  bool onPlanService(PlanAttitudeManeuver::Request& req, PlanAttitudeManeuver::Response& res);
  /// plan_drift_two_input callback: always returns true (the outcome is in the response).
  bool onPlanDriftService(PlanDriftTwoInput::Request& req, PlanDriftTwoInput::Response& res);
  /// Action execute callback: feedback per iteration; preemption cancels the solve.
  void onPlanGoal(const PlanAttitudeManeuverGoalConstPtr& goal);

  ros::NodeHandle nh_;  ///< public handle: the service and action resolve here
  ros_conversions::PlannerDefaults defaults_;  ///< read once in the constructor, then const
  std::string world_frame_;                    ///< frame_id of returned maneuvers
  std::string body_frame_;                     ///< child_frame_id of returned maneuvers
  int threads_ = 4;                            ///< spinner threads
  ros::ServiceServer service_;                 ///< plan_attitude_maneuver
  ros::ServiceServer drift_service_;           ///< plan_drift_two_input
  /// plan_attitude_maneuver_action (one goal at a time)
  std::unique_ptr<actionlib::SimpleActionServer<PlanAttitudeManeuverAction>> action_server_;
};

// ---- templates ----------------------------------------------------------------------------------

template <class Request>
PlanOutcome planRequest(const Request& req, const ros_conversions::PlannerDefaults& defaults,
                        const std::function<bool(const IterationInfo&, double)>& keep_going) {
  PlanOutcome out;
  try {
    SolverOptions options;
    out.problem = ros_conversions::problemFromRequest(req, defaults, &options);
    Maneuver guess;  // the request's warm start, if any (lives through the solve)
    if (ros_conversions::initialGuessFromMsg(req.initial_guess, "initial_guess", &guess)) {
      options.warm_start = &guess;
    }
    // The time budget (options.time_budget_s) is enforced by the core, which then ends
    // TimedOut; the callback only cancels (node shutting down, action preempted).
    const ros::WallTime start = ros::WallTime::now();
    options.on_iteration = [&](const IterationInfo& info) {
      const double elapsed = (ros::WallTime::now() - start).toSec();
      return ros::ok() && (!keep_going || keep_going(info, elapsed));
    };
    out.result = planManeuver(out.problem, options);
    out.solver_ran = true;
    out.error_code = errorCodeOf(out.result.termination);
    out.message = out.result.message;
  } catch (...) {
    describeCurrentException(&out.error_code, &out.message);
  }
  return out;
}

template <class Response>
void fillResponse(const PlanOutcome& outcome, const std::string& world_frame,
                  const std::string& body_frame, Response* res) {
  res->success = outcome.error_code == PlanErrorCode::SUCCESS;
  res->error_code.val = outcome.error_code;
  res->message = outcome.message;
  if (!outcome.solver_ran) return;
  const PlanResult& r = outcome.result;
  PlanningProblem planned = outcome.problem;  // with an accuracy target the planner chose these
  if (r.accuracy.requested) planned.scheme = r.scheme;
  if (!r.maneuver.attitude.empty()) {
    planned.steps = r.maneuver.steps();
    res->maneuver = ros_conversions::maneuverToMsg(r.maneuver, planned, world_frame, body_frame,
                                                   ros::Time::now());
  }
  res->steps = planned.steps;
  res->scheme = schemeName(planned.scheme);
  res->estimated_error = r.accuracy.estimated_error;
  res->predicted_error = r.accuracy.predicted_error;
  res->cost = r.cost;
  res->effort = r.effort;
  res->duration = r.duration;
  res->minimum_duration = r.minimum_duration;
  res->iterations = r.iterations;
  res->max_residual = r.max_residual;
  res->terminal_attitude_error = r.terminal_attitude_error;
  res->terminal_velocity_error = r.terminal_velocity_error;
  res->solve_time = r.solve_time_s;
  res->effects = r.effects;
  res->constraints = r.constraints;
  res->max_constraint_violation = r.max_constraint_violation;
  res->max_violation_between_nodes = r.max_violation_between_nodes;
  res->active_constraints = r.active_constraints;
  res->replay_miss = r.replay_miss;
  res->step_residual = r.step_residual;
}

}  // namespace attitude_planner
