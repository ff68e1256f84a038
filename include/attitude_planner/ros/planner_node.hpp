// attitude_planner_node: the planner behind services and an action. A thin adapter: it converts
// the request, calls planManeuver() / planDriftTwoInput() (the same entry points as the CLI) and
// fills the response.
//
//   service  plan_attitude_maneuver         (attitude_planner/PlanAttitudeManeuver)   rigid body
//   action   plan_attitude_maneuver_action  (attitude_planner/PlanAttitudeManeuverAction)
//   topic    /diagnostics                   (diagnostic_msgs/DiagnosticArray) every second: the
//            status `<node>: planner` (answers by error code, wall times, busy workers)
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
//                                       parallel)
//   ~action_workers  int     2          action goals solved in parallel (>= 1); a goal arriving
//                                       while all are busy is REJECTED (error REJECTED)
//
// Each solve owns all its state, so concurrent requests never share mutable data: service calls
// are solved in parallel (~threads), and so are action goals (~action_workers): goals never
// preempt each other; a goal ends PREEMPTED (error CANCELLED) only when its own client cancels it,
// and then whatever the solver had reached (the cancel is checked under the action server's lock
// against the goal's own status, so a cancel that arrives in the last iteration still wins).
// A request's time_budget is a deadline: a solve whose wall time exceeded it answers TIMED_OUT,
// never SUCCESS. A solve stopped by its budget or its cancel answers with the plan it had reached
// (unconverged_plan true: the dynamics and boundary data hold, optimality does not) when it hands
// it over in time: the core stops a hand-over's time before the deadline (solveBudget), and a
// cancel waits for it (cancelGrace).
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <actionlib/server/action_server.h>
#include <ros/ros.h>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanAttitudeManeuverAction.h"
#include "attitude_planner/PlanDriftTwoInput.h"
#include "attitude_planner/PlanErrorCode.h"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "attitude_planner/ros/diagnostics.hpp"

namespace attitude_planner {

/// What one planning request produced, whatever happened.
struct PlanOutcome {
  int error_code = PlanErrorCode::INTERNAL_ERROR;  ///< a PlanErrorCode constant
  std::string message;                             ///< outcome in words, one line
  std::string details;      ///< the solver's full account (the core's message) when it ran
  bool solver_ran = false;  ///< `result` is meaningful
  PlanResult result;        ///< the core's result
  PlanningProblem problem;  ///< the parsed problem (if parsing succeeded)
  ros_conversions::OutputSelection output;  ///< how much of the maneuver to return
  double time_budget_s = 0.0;  ///< the request's budget, its deadline [s] (0 = none); the core ran
                               ///< under solveBudget of it
  double wall_time_s = 0.0;    ///< wall time of planManeuver [s]
};

/// The one-line message of an infeasible result, built from its figures (the worst violated
/// constraint of the returned plan and where: checkConstraints), never from the core's message,
/// which goes whole to `details`.
std::string infeasibleSummary(const PlanningProblem& problem, const PlanResult& result);

/// Applies the deadline: a result that converged after its time budget had run out (wall time
/// > budget) becomes TIMED_OUT with a one-line message saying by how much.
void enforceDeadline(PlanOutcome* outcome);

/// The PlanErrorCode constant of a termination: the one mapping from the core's status to the
/// interface's (INTERNAL_ERROR is not a termination: it is an exception the core did not expect).
int errorCodeOf(Termination termination);

/// Runs one request through the core. `keep_going(info, elapsed_s)` is called after every
/// iteration; returning false cancels. `cancel` (optional) is handed to the core
/// (SolverOptions::cancel_requested), which polls it inside long iterations too. Never throws.
template <class Request>
PlanOutcome planRequest(const Request& req, const ros_conversions::PlannerDefaults& defaults,
                        const std::function<bool(const IterationInfo&, double)>& keep_going,
                        const std::atomic<bool>* cancel = nullptr);

/// The action feedback of one reported iteration: its figures and the attempt it belongs to
/// (IterationInfo::attempt), so that a convergence plot tells one attempt from the next.
PlanAttitudeManeuverFeedback iterationFeedback(const IterationInfo& info, double elapsed_s);

/// A goal's last feedback: the returned plan's cost, effort and N (residual: its max_residual),
/// tagged with the attempt kept (kept true; attempt = its 1-based place in the result's
/// attempts, 0 when the trail marks none) and numbered `last_iteration` (the last iteration
/// reported: this message adds none). The feedback then ends on what the result holds, not on
/// the last iterate of a discarded attempt; elapsed: the solve's wall time. Nothing when the
/// solver did not run.
std::optional<PlanAttitudeManeuverFeedback> keptAttemptFeedback(const PlanOutcome& outcome,
                                                                int last_iteration);

/// The error code and message of the exception being handled (call only inside a catch block):
/// InvalidInput and StepTooLarge through errorCodeOf, named in the request's fields
/// (ros_conversions::requestErrorMessage); anything else → INTERNAL_ERROR.
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

/// The answer to a request with a time budget B comes by answerDeadline(B) = B + max(B
/// kDeadlineSlack, kHandoverFloor) [s]: within 1.1 B + 0.05 s (docs/ros_timing.md). The core
/// stops at its own budget, solveBudget(B, N) <= B, and returns the plan it had reached (an
/// anytime plan: unconverged_plan); the time from there to answerDeadline(B) is what it has to
/// carry that plan to N, measure it and hand it over. A solve still running at answerDeadline(B)
/// is told to stop and its result is dropped: the answer is TIMED_OUT without a plan.
inline constexpr double kDeadlineSlack = 0.08;
inline constexpr double kHandoverFloor = 0.04;  ///< [s]
inline double answerDeadline(double budget) {
  return budget + std::max(budget * kDeadlineSlack, kHandoverFloor);
}

/// What a stopped solve needs, at most, to hand its plan over at N nodes [s]: it carries its
/// iterate to the requested grid (a ReducedProblem on each finer level), builds the N + 1 rows
/// and measures its residuals (one gradient and the step residual), each a pass over the grid.
/// Measured in-process (studies/cancel_handover_study.cpp, docs/ros_planner.md "Handing a
/// stopped N = 1e5 plan over"): 0.7-0.9 us of CPU per node, and in wall time on the 2 shared
/// cores up to 2.3 us per node after a cancel (load 8.5) and 7.7 us per node after a budget
/// that stopped the class survey on its coarsest grid (load 10.7: every level up to N built).
/// kHandoverPerNode allows about 1.3 times the worst of those: 1 s at N = 1e5, 1.3 ms at N = 128.
inline constexpr double kHandoverPerNode = 1e-5;  ///< [s] per node of the requested grid
inline double handoverEstimate(int steps) {
  return kHandoverPerNode * steps;
}

/// The core's own time budget for a request with budget B [s] (0 = none) planned at up to N
/// nodes: B, less what the hand-over needs beyond the answer's slack, so that the stopped solve's
/// plan is handed over by answerDeadline(B): min(B, answerDeadline(B) - handoverEstimate(N)),
/// at least kLeastSolveBudget (then the solve stops at its start: its plan is the first iterate).
/// At N = 128 nothing is taken (the hand-over fits in the slack); at N = 1e5 a budget below
/// about 12.5 s loses up to 1 s (a solve that would have converged in that second answers
/// TIMED_OUT with its iterate instead).
inline constexpr double kLeastSolveBudget = 1e-6;  ///< [s]
inline double solveBudget(double budget, int steps) {
  if (!(budget > 0.0)) return budget;
  return std::max(kLeastSolveBudget,
                  std::min(budget, answerDeadline(budget) - handoverEstimate(steps)));
}

/// An action goal cancelled while a worker solves it ends when the worker has stopped, with the
/// plan the solve had reached, if the solve returns it within cancelGrace(N) [s]; else the cancel
/// ends it then, without a plan (the worker's result is dropped). A cancel is answered within
/// that wait plus the plan's fill and transfer (30-90 ms for the 8.8 MB of an N = 1e5 plan)
/// plus transport. kCancelGrace is the scheduling of the worker thread (it dominates at small N).
inline constexpr double kCancelGrace = 0.03;  ///< [s]
inline double cancelGrace(int steps) {
  return kCancelGrace + handoverEstimate(steps);
}
/// The largest N a request (service request or action goal) may be planned at: its steps
/// (0: ~default_steps), or ~max_steps when an accuracy target lets the planner choose N.
template <class Request>
int largestPlannedSteps(const Request& request, const ros_conversions::PlannerDefaults& defaults) {
  if (!request.accuracy_measure.empty()) return defaults.max_steps;  // the planner chooses N
  return request.steps > 0 ? std::min(request.steps, defaults.max_steps) : defaults.steps;
}

/// Whether a result's plan is an unconverged iterate (the response's unconverged_plan): the solver
/// ran, returned a maneuver, and did not converge.
inline bool isUnconvergedPlan(const PlanResult& result) {
  return !result.converged() && !result.maneuver.attitude.empty();
}

/// A solve run on its own thread so that its caller can answer at the deadline without it.
struct SolveSlot {
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;                ///< `outcome` is the solve's
  PlanOutcome outcome;              ///< set when done
  std::atomic<bool> cancel{false};  ///< tells the solve to stop (deadline passed, or shutdown)
};

/// The TIMED_OUT outcome of a request answered at its deadline `budget` [s] without its solve.
PlanOutcome deadlineOutcome(double budget);

/// Hands the memory freed by finished solves back to the system (glibc keeps it in the solving
/// threads' malloc arenas otherwise).
void returnFreedMemory();

/// Sets the allocator up for solves on many threads (the node calls it once, at start): blocks
/// of kMmapThreshold and more are mapped on their own and unmapped when freed. glibc's default
/// raises that threshold after the first large free (up to 32 MB), so a solve's row arrays and
/// Newton pieces then come from the solving thread's arena, which malloc_trim does not shrink:
/// 13 stopped N = 2e4 solves on 4 threads kept 38 MB (docs/ros_timing.md, test
/// Memory.StoppedSolvesLeaveNothingBehindOnceJoined).
void configureAllocator();
inline constexpr int kMmapThreshold = 4 << 20;  ///< [bytes]

/// Calls a function once a wall time has passed unless destroyed before (planner_node.cpp): an
/// action goal's deadline, armed when the goal is accepted.
class DeadlineWatch;

/// The node: service + action around planRequest().
class PlannerNode {
 public:
  /// Reads the private parameters (range-checked, logged fall-back), starts the action workers
  /// and advertises the interfaces.
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& private_nh);
  /// Cancels the running goals and joins the workers.
  ~PlannerNode();

  /// Service threads requested by ~threads.
  int threads() const { return threads_; }

 private:
  /// ActionServer whose lock a worker can hold while it reads a goal's status and ends it, so a
  /// cancel cannot slip in between (actionlib sets PREEMPTING under this lock).
  class ActionServer : public actionlib::ActionServer<PlanAttitudeManeuverAction> {
   public:
    using actionlib::ActionServer<PlanAttitudeManeuverAction>::ActionServer;
    boost::recursive_mutex& statusMutex() { return this->lock_; }
  };
  using GoalHandle = ActionServer::GoalHandle;
  /// An accepted goal waiting for or running on a worker.
  struct ActiveGoal {
    GoalHandle handle;
    std::shared_ptr<std::atomic<bool>> cancel;  ///< set by the goal's own cancel
    /// Wall time [s] at which onCancel ended the goal (0: not ended by a cancel), for the log line
    /// that says how long the worker took to stop after it (docs/ros_timing.md).
    std::shared_ptr<std::atomic<double>> ended_at;
    /// The goal's deadline, from its acceptance (a goal queued behind busy workers counts its
    /// wait): ends it ABORTED / TIMED_OUT at answerDeadline(budget), queued or solving.
    std::shared_ptr<DeadlineWatch> deadline;
    ros::WallTime accepted;  ///< when it was accepted
    double budget = 0.0;     ///< its effective time budget [s] (0 = none)
    /// Set (under goals_mutex_, goal_ended_ notified) when its solve has returned: from then on
    /// the worker ends the goal with the plan whatever a cancel says, so a cancel waits
    /// cancel_grace for the core's hand-over, not for the plan's fill and transfer.
    std::shared_ptr<std::atomic<bool>> handed_over = std::make_shared<std::atomic<bool>>(false);
    /// How long its cancel waits for the stopped solve's plan [s]: cancelGrace of its N.
    double cancel_grace = kCancelGrace;
  };
  /// The deadline of an accepted goal passed: tells its solve to stop and ends it ABORTED with
  /// TIMED_OUT (unless it has ended); frees its slot if no worker has taken it.
  void onGoalDeadline(const ActiveGoal& goal);

  /// Where a service answer's wall time went inside the node [s] (logged for budgeted requests).
  struct ServiceTimes {
    double budget_s = 0.0;  ///< the effective time budget (0 = none)
    double reap_s = 0.0;    ///< joining the stopped solves of earlier requests
    double wait_s = 0.0;    ///< the solve, or the wait up to its answer deadline
    double fill_s = 0.0;    ///< filling the response
  };
  /// planRequest for the service, answered by its deadline (answerDeadline): the solve runs on a
  /// thread of its own, left to stop (and joined later) when the deadline passes first.
  PlanOutcome planServiceRequest(const PlanAttitudeManeuver::Request& req, ServiceTimes* times);
  /// Joins the late solves that have stopped (all of them, cancelled first, when `all`).
  void reapLateSolves(bool all);
  /// Service callback: always returns true (the outcome is in the response).
  bool onPlanService(PlanAttitudeManeuver::Request& req, PlanAttitudeManeuver::Response& res);
  /// plan_drift_two_input callback: always returns true (the outcome is in the response).
  bool onPlanDriftService(PlanDriftTwoInput::Request& req, PlanDriftTwoInput::Response& res);
  /// New goal: accepted and queued for a worker, or REJECTED when every worker is busy.
  void onGoal(GoalHandle goal);
  /// Cancel of one goal (only that goal's flag is set): ended by its worker with the plan the
  /// solve had reached if that comes within the goal's cancel_grace, else here without a plan.
  void onCancel(GoalHandle goal);
  /// Worker thread: takes accepted goals until shutdown.
  void workerLoop();
  /// Solves one goal (feedback per iteration) and ends it: PREEMPTED if its cancel arrived at
  /// any time before the end, else SUCCEEDED or ABORTED by its error code.
  void serveGoal(const ActiveGoal& goal);
  /// Publishes the node's status on /diagnostics (the wall timer's callback).
  void publishDiagnostics();

  ros::NodeHandle nh_;  ///< public handle: the service and action resolve here
  ros_conversions::PlannerDefaults defaults_;  ///< read once in the constructor, then const
  std::string world_frame_;                    ///< frame_id of returned maneuvers
  std::string body_frame_;                     ///< child_frame_id of returned maneuvers
  int threads_ = 4;                            ///< spinner threads
  int action_workers_ = 2;                     ///< goals solved in parallel
  ros::ServiceServer service_;                 ///< plan_attitude_maneuver
  ros::ServiceServer drift_service_;           ///< plan_drift_two_input

  std::mutex goals_mutex_;  ///< guards the four members below
  std::condition_variable goal_ready_;
  /// Notified (under goals_mutex_) when a worker has ended a goal: a cancel waits on it for the
  /// stopped solve's plan (ActiveGoal::cancel_grace).
  std::condition_variable goal_ended_;
  std::deque<ActiveGoal> queued_;             ///< accepted, not yet on a worker
  std::map<std::string, ActiveGoal> active_;  ///< accepted and not ended, by goal id
  bool stopping_ = false;                     ///< the node is shutting down
  std::vector<std::thread> workers_;          ///< ~action_workers threads
  std::mutex late_mutex_;                     ///< guards late_solves_
  /// Service solves still stopping after their request was answered at its deadline.
  std::vector<std::pair<std::thread, std::shared_ptr<SolveSlot>>> late_solves_;
  /// plan_attitude_maneuver_action (several goals at a time); last: destroyed first
  std::unique_ptr<ActionServer> action_server_;
  AnswerStatistics answers_;          ///< every answer sent, for /diagnostics
  ros::Publisher diagnostics_pub_;    ///< /diagnostics
  ros::WallTimer diagnostics_timer_;  ///< every kDiagnosticsPeriod
};

// ---- templates ----------------------------------------------------------------------------------

template <class Request>
PlanOutcome planRequest(const Request& req, const ros_conversions::PlannerDefaults& defaults,
                        const std::function<bool(const IterationInfo&, double)>& keep_going,
                        const std::atomic<bool>* cancel) {
  PlanOutcome out;
  try {
    out.output = ros_conversions::outputSelectionFromRequest(req.return_maneuver, req.output_steps);
    SolverOptions options;
    out.problem = ros_conversions::problemFromRequest(req, defaults, &options);
    // The deadline is the request's budget (enforceDeadline); the core stops early enough to
    // hand its plan over by the answer's deadline (solveBudget).
    out.time_budget_s = options.time_budget_s;
    options.time_budget_s = solveBudget(options.time_budget_s, largestPlannedSteps(req, defaults));
    Maneuver guess;  // the request's warm start, if any (lives through the solve)
    if (ros_conversions::initialGuessFromMsg(req.initial_guess, "initial_guess", &guess)) {
      options.warm_start = &guess;
    }
    // The time budget (options.time_budget_s) is enforced by the core, which then ends
    // TimedOut; the callback and the flag only cancel (node shutting down, action cancelled).
    options.cancel_requested = cancel;
    const ros::WallTime start = ros::WallTime::now();
    options.on_iteration = [&](const IterationInfo& info) {
      const double elapsed = (ros::WallTime::now() - start).toSec();
      const bool cancelled = cancel && cancel->load();
      // Without ros::init (a test, a tool) there is no shutdown to honour: ros::ok() is false.
      const bool shutting_down = ros::isInitialized() && !ros::ok();
      return !shutting_down && !cancelled && (!keep_going || keep_going(info, elapsed));
    };
    out.result = planManeuver(out.problem, options);
    out.wall_time_s = (ros::WallTime::now() - start).toSec();
    out.solver_ran = true;
    out.error_code = errorCodeOf(out.result.termination);
    out.message = out.result.termination == Termination::Infeasible
                      ? infeasibleSummary(out.problem, out.result)
                      : out.result.message();
    out.details = out.result.message();
    enforceDeadline(&out);
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
  res->details = outcome.details;
  if (!outcome.solver_ran) return;
  const PlanResult& r = outcome.result;
  PlanningProblem planned = outcome.problem;  // with an accuracy target the planner chose these
  if (r.accuracy.requested) planned.scheme = r.scheme;
  if (!r.maneuver.attitude.empty()) {
    planned.steps = r.maneuver.steps();
    const bool wheels = planned.reaction_wheels.present();
    const WheelStates states =
        wheels ? wheelStates(planned.scheme, planned.inertia, planned.reaction_wheels, r.maneuver,
                             planned.worldDisturbance())
               : WheelStates();
    if (outcome.output.output == ros_conversions::ManeuverOutput::Nodes) {
      const WheelStates shown =
          ros_conversions::decimatedWheelStates(states, outcome.output.max_nodes);
      // Decimated only when asked: a full plan goes to the message without a copy of its rows.
      const int max_nodes = outcome.output.max_nodes;
      const bool decimate = max_nodes > 0 && max_nodes < r.maneuver.steps() + 1;
      const Maneuver decimated =
          decimate ? ros_conversions::decimatedManeuver(r.maneuver, max_nodes) : Maneuver();
      res->maneuver =
          ros_conversions::maneuverToMsg(decimate ? decimated : r.maneuver, planned, world_frame,
                                         body_frame, ros::Time::now(), wheels ? &shown : nullptr);
    }
    if (wheels) {
      res->reaction_wheels = ros_conversions::wheelSummaryToMsg(
          planned.reaction_wheels,
          planWheelPeaks(planned.reaction_wheels, states, schemeHasEndTorques(planned.scheme)),
          r.minimized_effort);
    }
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
  res->replay_measured = r.replay_measured;
  res->step_residual = r.step_residual;
  res->final_twist = r.pointing.active ? r.pointing.final_twist : 0.0;
  res->pointing_error = r.pointing.active ? r.pointing.error : 0.0;
  res->twist_stationarity = r.pointing.active ? r.pointing.twist_stationarity : 0.0;
  res->unconverged_plan = isUnconvergedPlan(r);
  res->attempts.clear();
  for (const Attempt& a : r.attempts) res->attempts.push_back(ros_conversions::attemptToMsg(a));
  res->minimum_time = ros_conversions::minimumTimeToMsg(r.minimum_time);
  res->duration_verdict = ros_conversions::durationVerdictToMsg(r.duration_verdict);
  res->verdict_kind = verdictKindName(r.verdict);
  res->verdict_figures = ros_conversions::verdictFiguresToMsg(r.verdict);
  res->pointing_infeasible_basis = outcome.problem.end_condition.pointing()
                                       ? pointingInfeasibleBasisName(r.pointing.infeasible_basis)
                                       : std::string();
}

}  // namespace attitude_planner
