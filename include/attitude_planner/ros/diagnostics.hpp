// /diagnostics for the planner and tracker nodes (diagnostic_msgs/DiagnosticArray, one status per
// node, published every kDiagnosticsPeriod seconds of wall time; rqt_runtime_monitor and the
// diagnostic_aggregator read it). The statuses are built here from plain data, so their wording
// and their level rules are tested without a master (test_ros_conversions).
#pragma once

#include <deque>
#include <map>
#include <mutex>
#include <string>

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace attitude_planner {

/// Wall time [s] between two /diagnostics messages of a node.
inline constexpr double kDiagnosticsPeriod = 1.0;

/// The answers a node gave (service calls and action goals), thread-safe: every interface
/// records the error code (PlanErrorCode) and wall time of each answer it sends.
class AnswerStatistics {
 public:
  struct Summary {
    int answered = 0;
    int succeeded = 0;
    std::map<int, int> failed;  ///< answers per PlanErrorCode other than SUCCESS
    int last_code = 0;          ///< the newest answer's code (0: none yet)
    double last_s = 0.0;        ///< the newest answer's wall time [s]
    double median_s = 0.0;      ///< median wall time of the last kRecent answers [s]
    double max_s = 0.0;         ///< longest of the last kRecent answers [s]
  };
  static constexpr std::size_t kRecent = 100;

  void record(int error_code, double wall_time_s);
  Summary summary() const;

 private:
  mutable std::mutex mutex_;
  Summary counts_;
  std::deque<double> recent_;  ///< wall times of the last kRecent answers [s]
};

/// What the planner node is doing now.
struct PlannerLoad {
  int action_workers = 0;   ///< ~action_workers
  int busy_workers = 0;     ///< accepted goals not ended (solving or queued for a worker)
  int stopping_solves = 0;  ///< service solves past their deadline, told to stop, not returned
};

/// The planner's status. Level: ERROR when the newest answer was INTERNAL_ERROR (a bug: the
/// message says to report it); WARN when every action worker is busy (a new goal is REJECTED)
/// or stopped solves are still running; OK otherwise. Keys: answers, failures per error code,
/// wall times, workers.
diagnostic_msgs::DiagnosticStatus plannerStatus(const std::string& name,
                                                const AnswerStatistics::Summary& answers,
                                                const PlannerLoad& load);

/// What the tracker node is doing now.
struct TrackerHealth {
  std::string mode;               ///< ~mode
  std::string plant;              ///< ~plant: internal | external
  bool running = false;           ///< a maneuver is being flown
  double time = 0.0;              ///< maneuver time of the newest sample [s]
  double duration = 0.0;          ///< the maneuver's T [s]
  double attitude_error = 0.0;    ///< |log(R_dᵀR)| at the newest sample [rad]
  double rate_error = 0.0;        ///< |e_Ω| at the newest sample [rad/s]
  double measurement_age = -1.0;  ///< external plant: age of the newest odometry [s] (< 0: none)
  /// External plant with wheels: age of the newest wheel_measurement [s] (< 0: none)
  double wheel_measurement_age = -1.0;
  /// External plant: why the newest sample had no usable measurement (stale, missing, wrong
  /// frames), as the tracker's own check said; empty when it had one.
  std::string measurement_problem;
  int replans = 0;             ///< replan: re-plans adopted in this run
  int replan_failures = 0;     ///< replan: re-plans that failed in this run
  int runs_finished = 0;       ///< runs that have their `done`
  std::string frame_conflict;  ///< another node publishing our body transform (empty: none)
};

/// The tracker's status. Level: ERROR when another node publishes our body transform; WARN
/// while flying with an external plant that gave the newest sample no usable measurement, or
/// after a failed re-plan in this run; OK otherwise.
diagnostic_msgs::DiagnosticStatus trackerStatus(const std::string& name,
                                                const TrackerHealth& health);

/// "SUCCESS", "INVALID_INPUT", ... for a PlanErrorCode value ("code <v>" for an unknown one).
std::string errorCodeName(int code);

}  // namespace attitude_planner
