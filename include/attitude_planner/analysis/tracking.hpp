// A plan as a continuous reference, and the closed loop that tracks it (the tracker's `feedback`
// mode, docs/ros_tracker.md). ROS-free: the tracker node converts and calls.
//
// Between the nodes a plan is interpolated the way its scheme moves (the "scheme's own
// interpolation"): the torque with the scheme's hold (naturalHold: node-centred for paper and
// variational, linear for second_order, cubic for fourth_order); the attitude along the step's
// geodesic R_k exp(s log(R_kᵀ R_{k+1})), s ∈ [0, 1], which is exactly the paper scheme's motion
// (constant body rate log(F_k)/h over the step); the body rate for paper linear between the step
// rates placed at the step midpoints (so that its derivative is the node-centred torque's
// acceleration), linear between the node rates otherwise (variational's rows J⁻¹μ(F_k) follow the
// node's impulse h τ_k: the rate at t_k is taken halfway through it); fourth_order, not a
// discretization, moves as the continuous body under its cubic hold (one RKMK4 step from the
// node, as replayPlan does).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/analysis/accuracy.hpp"
#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/dynamics/tracking_controller.hpp"
#include "attitude_planner/name_table.hpp"

namespace attitude_planner {

/// How the tracker drives the body along a plan.
enum class TrackingMode {
  Replay,    ///< open loop: the plan's torques, as planned (the default)
  Feedback,  ///< the geometric tracking law around the plan (simulateTracking)
  Replan,    ///< the law on plans re-planned from the current state (analysis/replanning.hpp)
};

/// The names of the modes (the tracker's ~mode, ReplayResult.mode).
inline constexpr NamedValue<TrackingMode> kTrackingModeNames[] = {
    {TrackingMode::Replay, "replay"},
    {TrackingMode::Feedback, "feedback"},
    {TrackingMode::Replan, "replan"},
};

/// "replay", "feedback" or "replan".
inline std::string trackingModeName(TrackingMode mode) {
  return nameIn(kTrackingModeNames, mode);
}

/// Throws InvalidInput naming the first row if maneuver.time[k] is not k · time_step within
/// kTimeGridTolerance · T (a message whose times and step disagree is ambiguous: refused).
void requireUniformTimeGrid(const Maneuver& maneuver);

/// Relative tolerance of requireUniformTimeGrid (times are k h in floating point, up to round-off).
inline constexpr double kTimeGridTolerance = 1e-9;

/// The state of a rigid body: where a run starts when it takes over from another (a new maneuver
/// mid-run is flown from the body's state, not from its plan's R_0), or a measurement.
struct RigidBodyState {
  Matrix3 attitude = Matrix3::Identity();      ///< R, body → world
  Vector3 angular_velocity = Vector3::Zero();  ///< Ω [rad/s], body frame
};

/// One sample of an interpolated maneuver.
struct ManeuverSample {
  double time = 0.0;                           ///< t [s] since t_0
  Matrix3 attitude = Matrix3::Identity();      ///< R(t), body → world
  Vector3 angular_velocity = Vector3::Zero();  ///< Ω(t) [rad/s], body
  Vector3 torque = Vector3::Zero();            ///< τ(t) [N·m], body (the hold's value)
};

/// The mean over [t0, t1] [s] of a hold f(t) that is a polynomial of degree ≤ 3 between the
/// half-steps j h/2 (every TorqueHold: the node-centred hold breaks at the step midpoints, the
/// others at the nodes; a linear hold of wheel torques too): two-point Gauss–Legendre on each
/// piece, exact there. A sampled command that holds this mean over [t0, t1) follows the plan
/// without lag; f(t0) held would lag it by half a sample. t1 ≤ t0: f(t0).
template <class Value, class Hold>
Value meanOverHold(const Hold& f, double t0, double t1, double time_step) {
  if (!(t1 > t0)) return f(t0);
  const double half = 0.5 * time_step;
  const double gauss = 0.5 / std::sqrt(3.0);  // the points: the middle ± gauss × the length
  Value sum = 0.0 * f(t0);
  for (double a = t0; a < t1;) {
    double b = std::min(t1, (std::floor(a / half) + 1.0) * half);
    if (!(b > a)) b = std::min(t1, a + half);  // a on a break, up to round-off
    const double middle = 0.5 * (a + b), length = b - a;
    sum += (0.5 * length) * (f(middle - gauss * length) + f(middle + gauss * length));
    a = b;
  }
  return sum / (t1 - t0);
}

/// A maneuver on its uniform node grid, evaluated at any t ∈ [0, T].
class ManeuverInterpolation {
 public:
  /// `maneuver` rows k = 0..N (N ≥ 1; fourth_order's cubic hold needs N ≥ 3), interpolated with
  /// `scheme`'s rules (file comment), or with the zero-order hold of the step's start τ_k when
  /// `hold` is TorqueHold::StepStart (a sampled controller's output); `effects` (may be null) act
  /// on fourth_order's in-between motion and enter referenceAt's Ω̇.
  ManeuverInterpolation(Maneuver maneuver, SchemeKind scheme, const Matrix3& inertia,
                        const EffectModel* effects, TorqueHold hold);
  /// The same with the scheme's own hold (naturalHold).
  ManeuverInterpolation(Maneuver maneuver, SchemeKind scheme, const Matrix3& inertia,
                        const EffectModel* effects);

  double duration() const { return maneuver_.time_step * steps(); }  ///< T [s]
  int steps() const { return maneuver_.steps(); }                    ///< N
  const Maneuver& nodes() const { return maneuver_; }
  const Matrix3& inertia() const { return inertia_; }  ///< J [kg·m²]
  /// R(t), Ω(t), τ(t); t is clamped to [0, T].
  ManeuverSample at(double t) const;
  /// The tracking reference at t: R(t), Ω(t) and Ω̇(t) = J⁻¹(τ(t) + τ_e(R(t), t) − Ω × JΩ)
  /// (the acceleration the plan's torque and the known effects give the body).
  AttitudeReference referenceAt(double t) const;
  /// τ(t) of the hold on node step k (t_k ≤ t ≤ t_{k+1}).
  Vector3 torqueOnStep(int k, double t) const;
  /// The mean of the hold's τ over [t0, t1] (both clamped to [0, T]; τ(t0) when empty): what
  /// an open-loop command held over a sample delivers without lagging the plan (meanOverHold).
  Vector3 meanTorque(double t0, double t1) const;

 private:
  /// paper's Ω(t): the step rates Ω_k at the midpoints t_k + h/2, linear in between.
  Vector3 paperRateAt(double t) const;
  /// Ω at node k: the row, except variational's, which is moved back by half the node's impulse.
  Vector3 nodeRate(int k) const;

  Maneuver maneuver_;
  SchemeKind scheme_;
  Matrix3 inertia_, inertia_inverse_;
  const EffectModel* effects_;
  TorqueHold hold_;
};

/// Settings of the closed loop.
struct TrackingOptions {
  double natural_frequency = 0.0;  ///< ω_n [rad/s] of the law; 0 = defaultTrackingFrequency(T)
  double damping = 1.0;            ///< ζ > 0
};

/// ω_n = kTrackingCyclesPerManeuver / T [rad/s]: the error's time constant 1/ω_n is a small,
/// fixed fraction of the maneuver (T/40), so disturbances are rejected well before the end
/// while the gains stay proportional to the plan's own accelerations.
double defaultTrackingFrequency(double duration);
inline constexpr double kTrackingCyclesPerManeuver = 40.0;
/// Largest ω_n · Δt of the sampled controller (Δt the control period): the control runs on the
/// plan's node grid, subdivided until ω_n Δt ≤ 0.2 rad, so sampling barely changes the
/// continuous law's damping.
inline constexpr double kMaxControlPhasePerSample = 0.2;

/// A closed-loop run.
struct TrackingRun {
  /// The body on the control grid t_j = j Δt, j = 0..M (Δt = h / substeps): R, Ω and, in the
  /// torque column, the control the actuators delivered over [t_j, t_{j+1}) (after saturation
  /// and noise; row M the command at T).
  Maneuver actual;
  int substeps = 1;                      ///< control samples per plan step
  double natural_frequency = 0.0;        ///< ω_n used [rad/s]
  double effort = 0.0;                   ///< ½∫|u|² dt of the delivered control [N²·m²·s]
  double terminal_attitude_error = 0.0;  ///< ‖log(R_d(T)ᵀ R(T))‖ [rad]
  double terminal_velocity_error = 0.0;  ///< |Ω(T) − Ω_d(T)| [rad/s]
  double max_attitude_error = 0.0;       ///< max_j ‖log(R_d(t_j)ᵀ R(t_j))‖ [rad]
};

/// Tracks `reference` with the geometric law (tracking_controller.hpp) from (R_0, Ω_0): the
/// control u_j = τ(R_j, Ω_j; reference at t_j) − τ_e(R_j, t_j) (the known effects compensated;
/// at zero error u = the plan's τ(t)) is held over each control period, passed through
/// `actuation` (saturation, then noise; may be null) and drives the continuous rigid body
/// Ṙ = RΩ^, JΩ̇ = JΩ × Ω + u + τ_e(R, t) (RKMK4, one step per control period, effects at every
/// stage). Throws InvalidInput for bad options (naming them).
TrackingRun simulateTracking(const ManeuverInterpolation& reference,
                             const Matrix3& initial_attitude, const Vector3& initial_velocity,
                             const EffectModel* effects, Actuation* actuation,
                             const TrackingOptions& options);

/// The sampled tracking law around a plan, evaluated on any state: what simulateTracking applies
/// at every control sample, and what the tracker sends to an external plant (~plant external)
/// from the measured state.
class TrackingLaw {
 public:
  /// `reference` and `effects` (may be null) must outlive the law; options.natural_frequency
  /// 0 = defaultTrackingFrequency(T). Throws InvalidInput for bad options (naming them).
  TrackingLaw(const ManeuverInterpolation& reference, const EffectModel* effects,
              const TrackingOptions& options);
  /// u = τ(R, Ω; reference at t) − τ_e(R, t) [N·m], body frame: the actuator command (the known
  /// effects compensated; at zero error the plan's τ(t)).
  Vector3 command(const Matrix3& attitude, const Vector3& angular_velocity, double t) const;
  double naturalFrequency() const { return natural_frequency_; }  ///< ω_n [rad/s]
  /// Control samples per plan step of simulateTracking: ω_n Δt ≤ kMaxControlPhasePerSample.
  int substepsPerPlanStep() const;

 private:
  const ManeuverInterpolation& reference_;
  const EffectModel* effects_;
  double natural_frequency_;
  TrackingGains gains_;
};

/// The state `dt` [s] after `state` (at maneuver time t) of the continuous rigid body under the
/// held torque u and the known `effects` (may be null): one RKMK4 step, dt may be negative. The
/// tracker moves a measurement to the time of its command with it (the measurement's age is
/// transport and sampling lag; moving only the attitude at the measured rate leaves the rate
/// Ω̇ · age behind, which the law's damping turns into an attitude offset of order 2ζ Ω̇ age / ω_n).
RigidBodyState predictState(const Matrix3& inertia, const EffectModel* effects,
                            const RigidBodyState& state, const Vector3& torque, double t,
                            double dt);

/// The continuous rigid body as a plant (attitude_plant_node): Ṙ = RΩ^, JΩ̇ = JΩ × Ω + u + τ_e(R, t)
/// with the delivered torque u held between commands (zero-order hold) and the effects on the
/// maneuver's clock t, integrated by RKMK4 (simulateTracking's integrator) in steps of at most
/// `max_step`. Commands pass through `actuation` (saturation, then noise) once each.
class RigidBodyPlant {
 public:
  /// At t = 0 in (R_0, Ω_0). `effects` may be null; `max_step` > 0 [s] (throws InvalidInput
  /// naming it otherwise).
  RigidBodyPlant(const Matrix3& inertia, const Matrix3& initial_attitude,
                 const Vector3& initial_velocity, std::shared_ptr<const EffectModel> effects,
                 Actuation actuation, double max_step);
  /// Holds the commanded torque τ [N·m] (body) from now on; returns the torque delivered.
  Vector3 command(const Vector3& commanded);
  /// Integrates to maneuver time t; a t at or before time() changes nothing.
  void advanceTo(double t);
  double time() const { return time_; }                          ///< t [s]
  const Matrix3& attitude() const { return attitude_; }          ///< R(t), body → world
  const Vector3& angularVelocity() const { return velocity_; }   ///< Ω(t) [rad/s], body
  const Vector3& deliveredTorque() const { return delivered_; }  ///< u [N·m], body

 private:
  Matrix3 inertia_, inertia_inverse_;
  std::shared_ptr<const EffectModel> effects_;
  Actuation actuation_;
  double max_step_;
  double time_ = 0.0;
  Matrix3 attitude_;
  Vector3 velocity_;
  Vector3 delivered_ = Vector3::Zero();
};

/// The open-loop effort ½∫|τ|² dt [N²·m²·s] of node torques under their scheme's weights
/// (h · schemeCost): the replay's counterpart of TrackingRun::effort.
double openLoopEffort(SchemeKind scheme, const Maneuver& replayed);

}  // namespace attitude_planner
