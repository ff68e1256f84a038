// Receding-horizon re-planning around the tracking law (the tracker's `replan` mode,
// docs/ros_tracker.md). ROS-free: the tracker node asks the planner service for the re-plans and
// studies/tracking_study.cpp calls planManeuver directly with the same problem and warm start.
//
// Every re-plan keeps the first plan's node grid: planned from node k_r (t_r = k_r h) in the
// body's simulated state there, over the remaining N − k_r steps of the same h, to the same target
// under the same constraints and limits, with the effects' clock moved on by t_r (the gravity
// gradient's orbit has moved on), warm-started with the rows k_r..N of the plan being flown.
// It is adopted at a node k_s ≥ k_r (when it has arrived): from t_s on the tracking law flies it
// from the body's state at t_s. So the body follows one continuous closed loop whose reference
// is replaced at nodes, and every re-plan is a problem of the same family as the first plan.
#pragma once

#include <memory>
#include <vector>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// Rows k..N of `maneuver` (time from 0, the same h): what is left of it from node k.
Maneuver remainderOf(const Maneuver& maneuver, int k);

/// The problem of the rest of `problem` from node k of its grid (t_k = k h) in the state
/// (R, Ω): N − k steps over T − t_k, the same target, inertia, scheme, torque bounds and
/// constraints; the effects on a clock moved on by t_k (EffectModel::timeShifted); minimum effort
/// (a minimum-time plan being flown has its T), the shortest way with no extra turns (the warm
/// start keeps the plan's homotopy class). Throws InvalidInput if fewer than kMinSteps steps
/// remain.
PlanningProblem remainderProblem(const PlanningProblem& problem, int k, const Matrix3& attitude,
                                 const Vector3& angular_velocity);

/// The body's state at node k (t = t_k, continuous: R(t_k), Ω(t_k)) as the boundary data of a
/// re-plan in `scheme`. second_order and fourth_order impose Ω_0 at the instant t_k: Ω(t_k) itself.
/// paper and variational take Ω_0 as the rate of the first step (paper: log(F_0)/h; variational:
/// the rate just after the node's impulse), whose value is the body's rate at the step's midpoint
/// to second order (ManeuverInterpolation reads their rows so): Ω(t_k + h/2), predicted by
/// predictState under `command` [N·m] held and the known `effects` (may be null). Planning from
/// Ω(t_k) instead gives the new plan a first step off by (h/2)Ω̇, which its torque at node 1 must
/// undo: about half the torque in force, beyond the actuator limits when they are active
/// (torque_limited.yaml: 4 of 9 re-plans "infeasible", docs/ros_tracker.md).
RigidBodyState schemeStartOf(SchemeKind scheme, const Matrix3& inertia, const EffectModel* effects,
                             const RigidBodyState& body, const Vector3& command, double t,
                             double time_step);

/// Re-plans are not sent once less than this many of the law's time constants 1/ω_n are left:
/// an answer adopted then has little time to be flown, and under active actuator limits the rest
/// is too short to absorb the body's offset (the last re-plan of torque_limited.yaml, 0.8 s =
/// 2.5/ω_n before the end, needed 5 % more torque than the limit: "infeasible from here"); the
/// law alone finishes the maneuver. 3 rather than 4 (about the law's settling time): at 4 the
/// paper scheme's seed example loses the last re-plan's restart from the body's own rate
/// (terminal rate error 1.5e-4 → 3.7e-3 rad/s, tracking_study; docs/ros_tracker.md).
inline constexpr double kReplanSettlingTimeConstants = 3.0;

/// The last node a re-plan may start from: the largest k with at least kMinSteps steps and
/// kReplanSettlingTimeConstants / ω_n of maneuver time left (ω_n = `natural_frequency` > 0);
/// −1 if none.
int lastReplanNode(int steps, double time_step, double natural_frequency);

/// The closed loop of the `replan` mode: the tracking law flies the newest adopted plan; the body
/// is continuous across adoptions (one simulation per adopted plan, from the state at its node,
/// with the actuator noise stream continued where it was).
/// Re-plans per maneuver when no period is given: every T/10 (tracking_study's default; the
/// measured table in docs/ros_tracker.md).
inline constexpr int kDefaultReplansPerManeuver = 10;

/// Plan steps between re-plans: `period` [s] > 0 rounded to whole steps of `time_step`; `period`
/// 0 = steps / kDefaultReplansPerManeuver rounded (T/10, whatever the plan's step); at least one
/// step either way. Throws InvalidInput naming `~replan_period` for a negative or non-finite one.
int replanPeriodSteps(double period, int steps, double time_step);

class RecedingHorizonRun {
 public:
  /// Starts by flying `plan` (the first plan, rows 0..N) from `start` (default: its R_0, Ω_0):
  /// until the first adoption this is simulateTracking's run. `effects` (may be null) act on the
  /// body on the maneuver's clock; `actuation` is copied fresh (saturation and noise from its
  /// first sample); options.natural_frequency 0 = defaultTrackingFrequency(T) of the first plan,
  /// kept for all.
  RecedingHorizonRun(const Maneuver& plan, SchemeKind scheme, const Matrix3& inertia,
                     std::shared_ptr<const EffectModel> effects, const Actuation& actuation,
                     TrackingOptions options, std::optional<RigidBodyState> start = std::nullopt);

  /// Adopts `plan`, planned from node `planned_from` (its row 0 is node planned_from), from node
  /// `at` (planned_from ≤ at < N) on. Throws InvalidInput if its grid does not fit (steps
  /// N − planned_from, time step h) or if `at` is outside that range.
  void adopt(const Maneuver& plan, int planned_from, int at);

  /// The body's simulated state at node k (under the plans adopted so far).
  ManeuverSample bodyAtNode(int k) const;
  /// The body and the reference (the plan in force) at maneuver time t ∈ [0, T].
  ManeuverSample bodyAt(double t) const;
  ManeuverSample referenceAt(double t) const;
  /// The law's command on the state (R, Ω) at maneuver time t against the plan in force (its
  /// TrackingLaw, on its segment's clock and effects, gains of naturalFrequency()): what the
  /// tracker sends an external plant in replan mode.
  Vector3 commandAt(const RigidBodyState& state, double t) const;
  /// Rows k..N of the plan in force at node k (its warm start for a re-plan from k).
  Maneuver planRemainderAt(int k) const;

  int steps() const { return steps_; }            ///< N of the first plan
  double timeStep() const { return time_step_; }  ///< h [s]
  int adoptions() const { return static_cast<int>(segments_.size()) - 1; }
  double naturalFrequency() const { return options_.natural_frequency; }  ///< ω_n [rad/s]
  /// ½∫|u|² dt of the delivered control over [0, T] [N²·m²·s].
  double effort() const;
  /// max over [0, T] of ‖log(R_dᵀR)‖ against the plan in force [rad].
  double maxAttitudeError() const;

 private:
  /// One adopted plan and the body's run under it from its node on.
  struct Segment {
    int node = 0;  ///< the node it was adopted at (its reference's row 0 and the run's start)
    std::shared_ptr<const ManeuverInterpolation> reference;  ///< the plan from `node` on
    std::shared_ptr<const EffectModel> effects;              ///< the effects from t_node on
    TrackingRun run;                                         ///< the body from t_node on
    std::shared_ptr<const ManeuverInterpolation> body;       ///< run.actual interpolated
  };
  /// Flies `rows` (the plan from node k on) from the body's state at node k.
  Segment fly(const Maneuver& rows, int k, const Matrix3& attitude,
              const Vector3& angular_velocity) const;
  /// The segment in force at maneuver time t.
  const Segment& segmentAt(double t) const;
  /// The control samples of the segments' runs, [begin, end) on the run of segment i.
  int controlSamples(int i) const;

  SchemeKind scheme_;
  Matrix3 inertia_;
  std::shared_ptr<const EffectModel> effects_;
  Actuation actuation_;  ///< fresh: every segment replays the stream up to its start
  TrackingOptions options_;
  int steps_ = 0;
  double time_step_ = 0.0;
  std::vector<Segment> segments_;
};

}  // namespace attitude_planner
