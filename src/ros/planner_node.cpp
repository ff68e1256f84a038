#include "attitude_planner/ros/planner_node.hpp"

#include <diagnostic_msgs/DiagnosticArray.h>

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <sstream>

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

std::string infeasibleSummary(const PlanningProblem& problem, const PlanResult& result) {
  std::ostringstream s;
  s << "infeasible: ";
  if (result.duration_verdict.proven_infeasible) {
    // The core's message opens with the bound and the bounds in force, then how it is proven.
    const std::string& m = result.message();
    return m.substr(0, m.find(" (proven")) +
           " (proven; duration_verdict); details has the solver's account";
  }
  const ConstraintCheck check = result.maneuver.attitude.empty()
                                    ? ConstraintCheck()
                                    : checkConstraints(problem, result.maneuver);
  if (!check.worst.empty()) {
    s << check.worst << " cannot be met (the returned plan violates it " << check.worst_where
      << ")";
  } else {
    s << "no maneuver found that meets the constraints in force (";
    for (std::size_t i = 0; i < result.constraints.size(); ++i) {
      s << (i == 0 ? "" : ", ") << result.constraints[i];
    }
    s << ")";
  }
  s << "; details has the solver's account";
  return s.str();
}

void enforceDeadline(PlanOutcome* outcome) {
  if (outcome->error_code != PlanErrorCode::SUCCESS || !(outcome->time_budget_s > 0.0) ||
      outcome->wall_time_s <= outcome->time_budget_s) {
    return;
  }
  std::ostringstream s;
  s << "timed out: the plan converged after " << outcome->wall_time_s
    << " s, past the time budget of " << outcome->time_budget_s
    << " s (the late plan is returned; details has the solver's account)";
  outcome->error_code = PlanErrorCode::TIMED_OUT;
  outcome->message = s.str();
}

PlanOutcome deadlineOutcome(double budget) {
  PlanOutcome out;
  out.error_code = PlanErrorCode::TIMED_OUT;
  out.time_budget_s = budget;
  std::ostringstream s;
  s << "timed out: no plan within the time budget of " << budget
    << " s (the solve, stopped early for the hand-over, had not returned the plan it reached "
    << answerDeadline(budget) - budget << " s after it; its late result is dropped)";
  out.message = s.str();
  return out;
}

void describeCurrentException(int* error_code, std::string* message) {
  try {
    throw;
  } catch (const InvalidInput& e) {
    *error_code = errorCodeOf(Termination::InvalidInput);
    *message = ros_conversions::requestErrorMessage(e);
  } catch (const StepTooLarge& e) {
    *error_code = errorCodeOf(Termination::StepTooLarge);
    *message = ros_conversions::requestErrorMessage(e);
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

PlanAttitudeManeuverFeedback iterationFeedback(const IterationInfo& info, double elapsed_s) {
  PlanAttitudeManeuverFeedback feedback;
  feedback.iteration = info.iteration;
  feedback.cost = info.cost;
  feedback.residual = info.gradient_norm;
  feedback.step_length = info.step_length;
  feedback.elapsed = elapsed_s;
  feedback.steps = info.steps;
  feedback.effort = info.effort;
  feedback.attempt = info.attempt.number;
  feedback.stage = info.attempt.number > 0 ? attemptStageName(info.attempt.stage) : "";
  feedback.long_way = info.attempt.homotopy.long_way;
  feedback.extra_revolutions = info.attempt.homotopy.extra_revolutions;
  return feedback;
}

std::optional<PlanAttitudeManeuverFeedback> keptAttemptFeedback(const PlanOutcome& outcome,
                                                                int last_iteration) {
  if (!outcome.solver_ran) return std::nullopt;
  const PlanResult& r = outcome.result;
  PlanAttitudeManeuverFeedback feedback;
  feedback.iteration = last_iteration;
  feedback.cost = r.cost;
  feedback.residual = r.max_residual;
  feedback.elapsed = outcome.wall_time_s;
  feedback.steps = r.maneuver.steps();
  feedback.effort = r.effort;
  feedback.kept = true;
  const auto kept =
      std::find_if(r.attempts.begin(), r.attempts.end(), [](const Attempt& a) { return a.kept; });
  if (kept != r.attempts.end()) {
    feedback.attempt = static_cast<int>(kept - r.attempts.begin()) + 1;
    feedback.stage = attemptStageName(kept->stage);
    feedback.long_way = kept->homotopy.long_way;
    feedback.extra_revolutions = kept->homotopy.extra_revolutions;
  }
  return feedback;
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
  res->other_costs = p.other_costs;
  res->iterations = p.iterations;
  res->continuation_stages = p.continuation_stages;
  res->terminal_attitude_error = p.terminal_error;
  res->solve_time = outcome.solve_time_s;
}

PlannerNode::PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  configureAllocator();  // before any solve: what stopped solves free goes back to the system
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
  action_workers_ = readParam<int>(
      pnh, "action_workers", 2, [](int v) { return v >= 1; }, ">= 1");
  warnUnknownParameters(pnh);
  for (int i = 0; i < action_workers_; ++i) workers_.emplace_back([this] { workerLoop(); });

  service_ = nh_.advertiseService("plan_attitude_maneuver", &PlannerNode::onPlanService, this);
  drift_service_ =
      nh_.advertiseService("plan_drift_two_input", &PlannerNode::onPlanDriftService, this);
  action_server_ = std::make_unique<ActionServer>(
      nh_, "plan_attitude_maneuver_action", [this](GoalHandle goal) { onGoal(goal); },
      [this](GoalHandle goal) { onCancel(goal); }, false);
  action_server_->start();
  diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  diagnostics_timer_ =
      nh_.createWallTimer(ros::WallDuration(kDiagnosticsPeriod),
                          [this](const ros::WallTimerEvent&) { publishDiagnostics(); });
  ROS_INFO_STREAM("attitude_planner_node ready: services "
                  << service_.getService() << ", " << drift_service_.getService() << ", action "
                  << nh_.resolveName("plan_attitude_maneuver_action") << " (scheme "
                  << schemeName(d.scheme) << ", solver " << solverName(d.solver) << ", steps "
                  << d.steps << ", tolerance " << d.tolerance << ", max_iterations "
                  << d.max_iterations << ", time_budget " << d.time_budget << " s, max_steps "
                  << d.max_steps << ", max_solve_time " << d.max_solve_time << " s, "
                  << action_workers_ << " action workers)");
}

PlannerNode::~PlannerNode() {
  reapLateSolves(true);
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    stopping_ = true;
    for (auto& [id, goal] : active_) goal.cancel->store(true);
  }
  goal_ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
  // The goals' deadline watches stop (joined) while the action server still exists.
  std::map<std::string, ActiveGoal> left;
  std::deque<ActiveGoal> queued;
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    left.swap(active_);
    queued.swap(queued_);
  }
}

PlanOutcome PlannerNode::planServiceRequest(const PlanAttitudeManeuver::Request& req,
                                            ServiceTimes* times) {
  const ros::WallTime entered = ros::WallTime::now();
  reapLateSolves(false);
  times->reap_s = (ros::WallTime::now() - entered).toSec();
  const double budget = ros_conversions::effectiveTimeBudget(req.time_budget, defaults_);
  times->budget_s = budget;
  if (!(budget > 0.0)) return planRequest(req, defaults_, nullptr);
  auto slot = std::make_shared<SolveSlot>();
  // The deadline counts from the callback's entry, as an action goal's from its acceptance: the
  // reaping above is part of the budget, and the solve gets what is left of it.
  auto copy = std::make_shared<PlanAttitudeManeuver::Request>(req);
  copy->time_budget = std::max(budget - times->reap_s, 1e-6);
  std::shared_ptr<const PlanAttitudeManeuver::Request> request = copy;
  std::thread solve([slot, request, defaults = defaults_] {
    PlanOutcome outcome = planRequest(*request, defaults, nullptr, &slot->cancel);
    std::lock_guard<std::mutex> lock(slot->mutex);
    slot->outcome = std::move(outcome);
    slot->done = true;
    slot->finished.notify_all();
  });
  std::unique_lock<std::mutex> lock(slot->mutex);
  const auto deadline = std::chrono::duration<double>(answerDeadline(budget) - times->reap_s);
  const ros::WallTime waiting = ros::WallTime::now();
  const bool solved = slot->finished.wait_for(lock, deadline, [&] { return slot->done; });
  times->wait_s = (ros::WallTime::now() - waiting).toSec();
  if (solved) {
    lock.unlock();
    solve.join();
    returnFreedMemory();
    return std::move(slot->outcome);
  }
  lock.unlock();
  slot->cancel.store(true);
  std::lock_guard<std::mutex> late(late_mutex_);
  late_solves_.emplace_back(std::move(solve), slot);
  return deadlineOutcome(budget);
}

void returnFreedMemory() {
  // A solve's memory is freed into its thread's malloc arena, which glibc keeps: after 20 stopped
  // N = 1e5 solves the node held 698 MB it no longer used (docs/ros_timing.md). malloc_trim(0)
  // hands the free pages of every arena back to the system (milliseconds; nothing is in use).
  malloc_trim(0);
}

void configureAllocator() {
  mallopt(M_MMAP_THRESHOLD, kMmapThreshold);  // a fixed threshold: no dynamic raise
}

void PlannerNode::reapLateSolves(bool all) {
  std::lock_guard<std::mutex> late(late_mutex_);
  const std::size_t before = late_solves_.size();
  for (auto it = late_solves_.begin(); it != late_solves_.end();) {
    bool done = false;
    {
      std::lock_guard<std::mutex> lock(it->second->mutex);
      done = it->second->done;
    }
    if (!done && !all) {
      ++it;
      continue;
    }
    it->second->cancel.store(true);
    it->first.join();
    it = late_solves_.erase(it);
  }
  if (late_solves_.size() < before) returnFreedMemory();  // the joined solves' memory
}

bool PlannerNode::onPlanService(PlanAttitudeManeuver::Request& req,
                                PlanAttitudeManeuver::Response& res) {
  const ros::WallTime received = ros::WallTime::now();
  ServiceTimes times;
  try {
    const PlanOutcome outcome = planServiceRequest(req, &times);
    const ros::WallTime filling = ros::WallTime::now();
    fillResponse(outcome, world_frame_, body_frame_, &res);
    times.fill_s = (ros::WallTime::now() - filling).toSec();
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
  const double in_callback = (ros::WallTime::now() - received).toSec();
  answers_.record(res.error_code.val, in_callback);
  if (times.budget_s > 0.0) {
    // Where an answer's time goes inside the node (docs/ros_timing.md reads these lines).
    ROS_INFO(
        "service timing: budget %.3f s, answered by %.3f s: reaping stopped solves %.1f ms, "
        "solve or deadline wait %.1f ms, response fill %.1f ms, in the callback %.1f ms",
        times.budget_s, answerDeadline(times.budget_s), 1e3 * times.reap_s, 1e3 * times.wait_s,
        1e3 * times.fill_s, 1e3 * in_callback);
  }
  return true;
}

bool PlannerNode::onPlanDriftService(PlanDriftTwoInput::Request& req,
                                     PlanDriftTwoInput::Response& res) {
  const ros::WallTime received = ros::WallTime::now();
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
  answers_.record(res.error_code.val, (ros::WallTime::now() - received).toSec());
  return true;
}

/// Calls `on_deadline` once `seconds` [s] of wall time have passed, unless destroyed before (the
/// action's deadline: the worker holds one while it solves).
class DeadlineWatch {
 public:
  DeadlineWatch(double seconds, std::function<void()> on_deadline) {
    if (!(seconds > 0.0)) return;
    thread_ = std::thread([this, seconds, on_deadline = std::move(on_deadline)] {
      std::unique_lock<std::mutex> lock(mutex_);
      if (ended_.wait_for(lock, std::chrono::duration<double>(seconds), [&] { return over_; }))
        return;
      lock.unlock();
      on_deadline();
    });
  }
  ~DeadlineWatch() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      over_ = true;
    }
    ended_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  DeadlineWatch(const DeadlineWatch&) = delete;
  DeadlineWatch& operator=(const DeadlineWatch&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable ended_;
  bool over_ = false;
  std::thread thread_;
};

void PlannerNode::onGoalDeadline(const ActiveGoal& goal) {
  goal.cancel->store(true);
  GoalHandle handle = goal.handle;
  boost::recursive_mutex::scoped_lock lock(action_server_->statusMutex());
  if (handle.getGoalStatus().status != actionlib_msgs::GoalStatus::ACTIVE) return;
  PlanAttitudeManeuverResult late;
  fillResponse(deadlineOutcome(goal.budget), world_frame_, body_frame_, &late);
  handle.setAborted(late, late.message);
  answers_.record(late.error_code.val, (ros::WallTime::now() - goal.accepted).toSec());
}

void PlannerNode::onGoal(GoalHandle goal) {
  const std::string id = goal.getGoalID().id;
  ActiveGoal active{goal, std::make_shared<std::atomic<bool>>(false),
                    std::make_shared<std::atomic<double>>(0.0)};
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    const bool full = static_cast<int>(active_.size()) >= action_workers_;
    if (!stopping_ && !full) active_[id] = active;  // the slot is reserved before accepting
    if (stopping_ || full) active.cancel = nullptr;
  }
  if (!active.cancel) {
    PlanAttitudeManeuverResult result;
    result.error_code.val = PlanErrorCode::REJECTED;
    result.message = "rejected: all " + std::to_string(action_workers_) +
                     " action workers (~action_workers) are busy with other goals; send it again "
                     "when one ends, or call the service plan_attitude_maneuver";
    ROS_WARN("goal %s %s", id.c_str(), result.message.c_str());
    goal.setRejected(result, result.message);
    answers_.record(result.error_code.val, 0.0);
    return;
  }
  goal.setAccepted();  // a cancel already received turns this into PREEMPTING: served as such
  // The deadline counts from here, not from when a worker takes the goal: a goal queued behind
  // workers still stopping cancelled N = 1e5 solves is answered by its budget all the same.
  active.accepted = ros::WallTime::now();
  active.budget = ros_conversions::effectiveTimeBudget(goal.getGoal()->time_budget, defaults_);
  active.cancel_grace = cancelGrace(largestPlannedSteps(*goal.getGoal(), defaults_));
  active.deadline = std::make_shared<DeadlineWatch>(
      answerDeadline(active.budget),
      [this, watched = ActiveGoal{active.handle, active.cancel, active.ended_at, nullptr,
                                  active.accepted, active.budget}] { onGoalDeadline(watched); });
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    active_[id] = active;  // with its deadline
  }
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    queued_.push_back(active);
  }
  goal_ready_.notify_one();
}

namespace {

/// The goal has ended (PREEMPTED by onCancel, RECALLED, ...): nothing more may be sent for it.
bool goalEnded(unsigned status) {
  using actionlib_msgs::GoalStatus;
  return status != GoalStatus::PENDING && status != GoalStatus::ACTIVE &&
         status != GoalStatus::PREEMPTING && status != GoalStatus::RECALLING;
}

}  // namespace

void PlannerNode::onCancel(GoalHandle goal) {
  std::unique_lock<std::mutex> goals(goals_mutex_);
  auto it = active_.find(goal.getGoalID().id);
  if (it == active_.end()) return;  // ended already, or not yet accepted (its worker ends it)
  it->second.cancel->store(true);   // this goal only: the solver stops
  // A solver that hands its plan over within the goal's grace (cancelGrace of its N) has its
  // worker end the goal, with the plan it had reached (serveGoal: the plan's fill and transfer
  // follow the hand-over, and are no solve to wait for); the wait holds no lock (goal_ended_ is
  // notified under goals_mutex_). (A goal still queued behind busy workers ends after the grace,
  // without a plan.)
  const std::shared_ptr<std::atomic<bool>> handed_over = it->second.handed_over;
  const double grace = it->second.cancel_grace;
  goal_ended_.wait_for(goals, std::chrono::duration<double>(grace), [&] {
    return goalEnded(goal.getGoalStatus().status) || handed_over->load();
  });
  if (handed_over->load()) return;  // its worker ends it, PREEMPTED with the plan
  // Else the goal ends now, not when the solver has stopped and its N = 1e5 plan has been
  // evaluated: the worker's late result is discarded (serveGoal). Under the server's lock, so
  // that the worker cannot end it in between.
  it = active_.find(goal.getGoalID().id);
  boost::recursive_mutex::scoped_lock lock(action_server_->statusMutex());
  if (goal.getGoalStatus().status != actionlib_msgs::GoalStatus::PREEMPTING) return;
  PlanAttitudeManeuverResult result;
  result.success = false;
  result.error_code.val = PlanErrorCode::CANCELLED;
  result.message =
      "cancelled by its client (the solve was stopped; it had not returned its plan within " +
      exactNumber(grace) + " s, so no plan is returned)";
  double waited = 0.0;
  if (it != active_.end()) {
    // Its slot is free before the result goes out: a goal sent on receiving it is accepted
    // (queued for the worker, which is stopping this solve).
    it->second.ended_at->store(ros::WallTime::now().toSec());
    if (!it->second.accepted.isZero())
      waited = (ros::WallTime::now() - it->second.accepted).toSec();
    active_.erase(it);
  }
  goal.setCanceled(result, result.message);
  answers_.record(result.error_code.val, waited);
}

void PlannerNode::workerLoop() {
  for (;;) {
    ActiveGoal goal;
    {
      std::unique_lock<std::mutex> lock(goals_mutex_);
      goal_ready_.wait(lock, [this] { return stopping_ || !queued_.empty(); });
      if (queued_.empty()) return;  // stopping, nothing left
      goal = queued_.front();
      queued_.pop_front();
      if (stopping_) goal.cancel->store(true);
    }
    serveGoal(goal);
  }
}

void PlannerNode::serveGoal(const ActiveGoal& goal) {
  GoalHandle handle = goal.handle;
  const std::string id = handle.getGoalID().id;
  // A cancel that arrived before the goal was in active_ (so onCancel found no flag to set).
  const unsigned status = handle.getGoalStatus().status;
  if (goalEnded(status)) {  // cancelled (onCancel) or past its deadline while it waited
    std::lock_guard<std::mutex> lock(goals_mutex_);
    active_.erase(id);  // its slot (onCancel freed it already)
    return;
  }
  if (status == actionlib_msgs::GoalStatus::PREEMPTING) goal.cancel->store(true);
  PlanAttitudeManeuverResult result;
  try {
    const PlanAttitudeManeuverGoalConstPtr request = handle.getGoal();
    // The deadline (goal.deadline, armed at acceptance) answers by answerDeadline(budget)
    // even when the stopped solve takes longer to return; its late result is discarded below.
    // The solve gets what is left of the budget after the wait in the queue.
    PlanAttitudeManeuverGoal solve_request = *request;
    if (goal.budget > 0.0) {
      const double waited = (ros::WallTime::now() - goal.accepted).toSec();
      solve_request.time_budget = std::max(goal.budget - waited, 1e-6);
    }
    int last_iteration = 0;
    const PlanOutcome outcome = planRequest(
        solve_request, defaults_,
        [&](const IterationInfo& info, double elapsed) {
          last_iteration = info.iteration;
          handle.publishFeedback(iterationFeedback(info, elapsed));
          return true;  // the cancel reaches the core through goal.cancel
        },
        goal.cancel.get());
    {
      std::lock_guard<std::mutex> goals(goals_mutex_);  // a cancel waiting for the plan (onCancel)
      goal.handed_over->store(true);
    }
    goal_ended_.notify_all();
    if (const auto kept = keptAttemptFeedback(outcome, last_iteration)) {
      handle.publishFeedback(*kept);
    }
    fillResponse(outcome, world_frame_, body_frame_, &result);
  } catch (const std::exception& e) {
    result = PlanAttitudeManeuverResult();
    result.error_code.val = PlanErrorCode::INTERNAL_ERROR;
    result.message = std::string("internal error: ") + e.what();
  }
  returnFreedMemory();  // the solve's arena, before the worker takes the next goal
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    active_.erase(id);  // the worker is free for the next goal
  }
  // Under the server's lock the goal's status cannot change: a cancel received at any time up to
  // here (PREEMPTING, or our flag) ends the goal PREEMPTED, whatever the solver reached.
  boost::recursive_mutex::scoped_lock lock(action_server_->statusMutex());
  if (goalEnded(handle.getGoalStatus().status)) {  // cancelled: its result was sent then
    const double ended = goal.ended_at->load();
    if (ended > 0.0) {
      ROS_INFO("goal %s: the worker stopped %.3f s after the cancel ended the goal", id.c_str(),
               ros::WallTime::now().toSec() - ended);
    }
    return;
  }
  const bool cancelled = goal.cancel->load() ||
                         handle.getGoalStatus().status == actionlib_msgs::GoalStatus::PREEMPTING;
  if (cancelled) {
    if (result.error_code.val != PlanErrorCode::CANCELLED) {
      result.message = "cancelled (the cancel arrived as the solve ended: " + result.message + ")";
      result.success = false;
      result.error_code.val = PlanErrorCode::CANCELLED;
    }
    handle.setCanceled(result, result.message);
  } else if (result.success) {
    handle.setSucceeded(result, result.message);
  } else {
    handle.setAborted(result, result.message);
  }
  lock.unlock();
  answers_.record(result.error_code.val, (ros::WallTime::now() - goal.accepted).toSec());
  {
    std::lock_guard<std::mutex> goals(goals_mutex_);  // a cancel waiting for this end (onCancel)
  }
  goal_ended_.notify_all();
}

void PlannerNode::publishDiagnostics() {
  PlannerLoad load;
  load.action_workers = action_workers_;
  {
    std::lock_guard<std::mutex> lock(goals_mutex_);
    load.busy_workers = static_cast<int>(active_.size());
  }
  {
    std::lock_guard<std::mutex> late(late_mutex_);
    for (const auto& [thread, slot] : late_solves_) {
      std::lock_guard<std::mutex> lock(slot->mutex);
      if (!slot->done) ++load.stopping_solves;
    }
  }
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  array.status.push_back(
      plannerStatus(ros::this_node::getName() + ": planner", answers_.summary(), load));
  diagnostics_pub_.publish(array);
}

}  // namespace attitude_planner
