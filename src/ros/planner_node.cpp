#include "attitude_planner/ros/planner_node.hpp"

#include <algorithm>

#include "attitude_planner/ros/parameters.hpp"

namespace attitude_planner {

int errorCodeOf(Termination termination) {
  switch (termination) {
    case Termination::Converged:
      return PlanErrorCode::SUCCESS;
    case Termination::NotConverged:
      return PlanErrorCode::NOT_CONVERGED;
    case Termination::Infeasible:
      return PlanErrorCode::INFEASIBLE;
    case Termination::StepTooLarge:
      return PlanErrorCode::STEP_TOO_LARGE;
    case Termination::TimedOut:
      return PlanErrorCode::TIMED_OUT;
    case Termination::Cancelled:
      return PlanErrorCode::CANCELLED;
    case Termination::InvalidInput:
      return PlanErrorCode::INVALID_INPUT;
  }
  return PlanErrorCode::INTERNAL_ERROR;
}

void describeCurrentException(int* error_code, std::string* message) {
  try {
    throw;
  } catch (const InvalidInput& e) {
    *error_code = errorCodeOf(Termination::InvalidInput);
    *message = e.what();
  } catch (const StepTooLarge& e) {
    *error_code = errorCodeOf(Termination::StepTooLarge);
    *message = e.what();
  } catch (const std::exception& e) {
    *error_code = PlanErrorCode::INTERNAL_ERROR;
    *message = std::string("internal error: ") + e.what();
  } catch (...) {
    *error_code = PlanErrorCode::INTERNAL_ERROR;
    *message = "internal error: unknown exception";
  }
}

DriftPlanOutcome planDriftRequest(const PlanDriftTwoInput::Request& req,
                                  const ros_conversions::PlannerDefaults& defaults) {
  DriftPlanOutcome out;
  try {
    out.request = ros_conversions::driftRequestFromMsg(req, defaults);
    const ros::WallTime start = ros::WallTime::now();
    out.plan = planDriftTwoInput(out.request);
    out.solve_time_s = (ros::WallTime::now() - start).toSec();
    out.solver_ran = true;
    out.error_code = errorCodeOf(out.plan.termination);
    out.message = out.plan.message;
  } catch (...) {
    describeCurrentException(&out.error_code, &out.message);
  }
  return out;
}

void fillDriftResponse(const DriftPlanOutcome& outcome, const std::string& world_frame,
                       const std::string& body_frame, PlanDriftTwoInput::Response* res) {
  res->success = outcome.error_code == PlanErrorCode::SUCCESS;
  res->error_code.val = outcome.error_code;
  res->message = outcome.message;
  if (!outcome.solver_ran) return;
  const DriftTwoInputPlan& p = outcome.plan;
  if (!p.trajectory.g.empty()) {
    res->maneuver = ros_conversions::driftManeuverToMsg(p.trajectory, outcome.request.weights,
                                                        world_frame, body_frame, ros::Time::now());
  }
  res->initial_costate = ros_conversions::vectorToMsg(p.initial_costate);
  res->cost = p.cost;
  res->iterations = p.iterations;
  res->continuation_stages = p.continuation_stages;
  res->terminal_attitude_error = p.terminal_error;
  res->solve_time = outcome.solve_time_s;
}

PlannerNode::PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  ros_conversions::PlannerDefaults d;
  d.scheme = readNamedParam(pnh, "default_scheme", d.scheme, kSchemeNames);
  d.solver = readNamedParam(pnh, "solver", d.solver, kSolverNames);
  d.tolerance = readParam<double>(
      pnh, "tolerance", d.tolerance, [](double v) { return std::isfinite(v) && v > 0.0; }, "> 0");
  d.max_iterations = readParam<int>(
      pnh, "max_iterations", d.max_iterations, [](int v) { return v > 0; }, "> 0");
  d.time_budget = readParam<double>(
      pnh, "time_budget", d.time_budget, [](double v) { return std::isfinite(v) && v >= 0.0; },
      ">= 0 s, 0 = none");
  d.max_steps = readParam<int>(
      pnh, "max_steps", d.max_steps, [](int v) { return v >= kMinSteps; },
      ">= " + std::to_string(kMinSteps));
  d.steps = readParam<int>(
      pnh, "default_steps", std::min(d.steps, d.max_steps),
      [&](int v) { return v >= kMinSteps && v <= d.max_steps; },
      ">= " + std::to_string(kMinSteps) + " and <= ~max_steps");
  d.max_solve_time = readParam<double>(
      pnh, "max_solve_time", d.max_solve_time, [](double v) { return std::isfinite(v) && v > 0.0; },
      "> 0 s");
  defaults_ = d;
  world_frame_ = readParam<std::string>(
      pnh, "world_frame", "world", [](const std::string& s) { return !s.empty(); }, "non-empty");
  body_frame_ = readParam<std::string>(
      pnh, "body_frame", "body", [](const std::string& s) { return !s.empty(); }, "non-empty");
  threads_ = readParam<int>(
      pnh, "threads", 4, [](int v) { return v >= 2; }, ">= 2");

  service_ = nh_.advertiseService("plan_attitude_maneuver", &PlannerNode::onPlanService, this);
  drift_service_ =
      nh_.advertiseService("plan_drift_two_input", &PlannerNode::onPlanDriftService, this);
  action_server_ = std::make_unique<actionlib::SimpleActionServer<PlanAttitudeManeuverAction>>(
      nh_, "plan_attitude_maneuver_action",
      [this](const PlanAttitudeManeuverGoalConstPtr& goal) { onPlanGoal(goal); }, false);
  action_server_->start();
  ROS_INFO_STREAM("attitude_planner_node ready: services "
                  << service_.getService() << ", " << drift_service_.getService() << ", action "
                  << nh_.resolveName("plan_attitude_maneuver_action") << " (scheme "
                  << schemeName(d.scheme) << ", solver " << solverName(d.solver) << ", steps "
                  << d.steps << ", tolerance " << d.tolerance << ", max_iterations "
                  << d.max_iterations << ", time_budget " << d.time_budget << " s, max_steps "
                  << d.max_steps << ", max_solve_time " << d.max_solve_time << " s)");
}

bool PlannerNode::onPlanService(PlanAttitudeManeuver::Request& req,
                                PlanAttitudeManeuver::Response& res) {
  try {
    const PlanOutcome outcome = planRequest(req, defaults_, nullptr);
    fillResponse(outcome, world_frame_, body_frame_, &res);
    if (res.success) {
      ROS_INFO("plan: N = %d converged in %d iterations, %.3f s, cost %.6g", res.steps,
               res.iterations, res.solve_time, res.cost);
    } else {
      ROS_WARN("plan failed (error %d): %s", res.error_code.val, res.message.c_str());
    }
  } catch (const std::exception& e) {  // e.g. bad_alloc while filling the response
    res = PlanAttitudeManeuver::Response();
    res.success = false;
    res.error_code.val = PlanErrorCode::INTERNAL_ERROR;
    res.message = std::string("internal error: ") + e.what();
  }
  return true;
}

bool PlannerNode::onPlanDriftService(PlanDriftTwoInput::Request& req,
                                     PlanDriftTwoInput::Response& res) {
  try {
    fillDriftResponse(planDriftRequest(req, defaults_), world_frame_, body_frame_, &res);
    if (res.success) {
      ROS_INFO("drift plan: N = %d converged in %d iterations, %.3f s, cost %.6g", req.steps,
               res.iterations, res.solve_time, res.cost);
    } else {
      ROS_WARN("drift plan failed (error %d): %s", res.error_code.val, res.message.c_str());
    }
  } catch (const std::exception& e) {  // e.g. bad_alloc while filling the response
    res = PlanDriftTwoInput::Response();
    res.success = false;
    res.error_code.val = PlanErrorCode::INTERNAL_ERROR;
    res.message = std::string("internal error: ") + e.what();
  }
  return true;
}

void PlannerNode::onPlanGoal(const PlanAttitudeManeuverGoalConstPtr& goal) {
  PlanAttitudeManeuverResult result;
  try {
    PlanAttitudeManeuverFeedback feedback;
    const PlanOutcome outcome =
        planRequest(*goal, defaults_, [&](const IterationInfo& info, double elapsed) {
          feedback.iteration = info.iteration;
          feedback.cost = info.cost;
          feedback.residual = info.gradient_norm;
          feedback.step_length = info.step_length;
          feedback.elapsed = elapsed;
          action_server_->publishFeedback(feedback);
          return !action_server_->isPreemptRequested();
        });
    fillResponse(outcome, world_frame_, body_frame_, &result);
  } catch (const std::exception& e) {
    result = PlanAttitudeManeuverResult();
    result.error_code.val = PlanErrorCode::INTERNAL_ERROR;
    result.message = std::string("internal error: ") + e.what();
  }
  if (result.success) {
    action_server_->setSucceeded(result, result.message);
  } else if (result.error_code.val == PlanErrorCode::CANCELLED ||
             action_server_->isPreemptRequested()) {
    // A preempted goal ends PREEMPTED whatever the solver had reached.
    if (result.error_code.val != PlanErrorCode::CANCELLED) {
      result.error_code.val = PlanErrorCode::CANCELLED;
      result.message = "cancelled (" + result.message + ")";
    }
    action_server_->setPreempted(result, result.message);
  } else {
    action_server_->setAborted(result, result.message);
  }
}

}  // namespace attitude_planner
