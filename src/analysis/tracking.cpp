#include "attitude_planner/analysis/tracking.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"

namespace attitude_planner {

void requireUniformTimeGrid(const Maneuver& maneuver) {
  const int N = maneuver.steps();
  const double h = maneuver.time_step;
  const double tolerance = kTimeGridTolerance * std::max(1.0, N * h);
  for (int k = 0; k <= N; ++k) {
    if (std::abs(maneuver.time[k] - k * h) > tolerance) {
      throw InvalidInput("maneuver.time[" + std::to_string(k) +
                         "] = " + exactNumber(maneuver.time[k]) +
                         " s disagrees with k * time_step = " + exactNumber(k * h) +
                         " s (time_step = " + exactNumber(h) +
                         " s; time[] must be the uniform grid k h since header.stamp)");
    }
  }
}

namespace {

/// Times within this fraction of h from a node are the node (its row, exactly).
constexpr double kNodeSnap = 1e-9;

/// One RKMK4 step of the continuous rigid body from (R, Ω) over `dt` under the torque τ(s),
/// s ∈ [0, dt] (control and effects): R exp(u^), u̇ = J_r(u)⁻¹ Ω, JΩ̇ = JΩ × Ω + τ(s).
/// (The same integrator as replayPlan's cubic hold, simulation.cpp.)
void rigidBodyStep(const Matrix3& J, const Matrix3& J_inverse, double dt,
                   const std::function<Vector3(const Matrix3&, double)>& torque, Matrix3* R,
                   Vector3* W) {
  const Matrix3 R0 = *R;
  const Vector3 W0 = *W;
  const auto f = [&](const Vector3& u, const Vector3& w, double s, Vector3* du, Vector3* dw) {
    *du = so3::rightJacobianInverse(u) * w;
    *dw = J_inverse * ((J * w).cross(w) + torque(R0 * so3::exp(u), s));
  };
  Vector3 u1, w1, u2, w2, u3, w3, u4, w4;
  f(Vector3::Zero(), W0, 0.0, &u1, &w1);
  f(0.5 * dt * u1, W0 + 0.5 * dt * w1, 0.5 * dt, &u2, &w2);
  f(0.5 * dt * u2, W0 + 0.5 * dt * w2, 0.5 * dt, &u3, &w3);
  f(dt * u3, W0 + dt * w3, dt, &u4, &w4);
  *R = reorthonormalize(R0 * so3::exp(Vector3(dt / 6.0 * (u1 + 2.0 * u2 + 2.0 * u3 + u4))));
  *W = W0 + dt / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
}

}  // namespace

ManeuverInterpolation::ManeuverInterpolation(Maneuver maneuver, SchemeKind scheme,
                                             const Matrix3& inertia, const EffectModel* effects,
                                             TorqueHold hold)
    : maneuver_(std::move(maneuver)),
      scheme_(scheme),
      inertia_(inertia),
      inertia_inverse_(inertia.inverse()),
      effects_(effects && !effects->empty() ? effects : nullptr),
      hold_(hold) {
  const int N = maneuver_.steps();
  if (N < 1 || maneuver_.time.size() != maneuver_.attitude.size() ||
      maneuver_.angular_velocity.size() != maneuver_.attitude.size() ||
      maneuver_.torque.size() != maneuver_.attitude.size()) {
    throw InvalidInput("maneuver: needs N >= 1 and rows k = 0..N in every column");
  }
  if (!(maneuver_.time_step > 0.0)) {
    throw InvalidInput("maneuver.time_step: must be > 0 s, got " +
                       exactNumber(maneuver_.time_step));
  }
  if (hold_ == TorqueHold::PiecewiseCubic && N < 3) {
    throw InvalidInput("maneuver: the cubic hold of scheme " + schemeName(scheme) +
                       " needs N >= 3, got N = " + std::to_string(N));
  }
}

ManeuverInterpolation::ManeuverInterpolation(Maneuver maneuver, SchemeKind scheme,
                                             const Matrix3& inertia, const EffectModel* effects)
    : ManeuverInterpolation(std::move(maneuver), scheme, inertia, effects, naturalHold(scheme)) {}

Vector3 ManeuverInterpolation::torqueOnStep(int k, double t) const {
  const double h = maneuver_.time_step;
  const double s = t - k * h;  // ∈ [0, h]
  const std::vector<Vector3>& tau = maneuver_.torque;
  switch (hold_) {
    case TorqueHold::NodeCentred:
      return s < 0.5 * h ? tau[k] : tau[k + 1];
    case TorqueHold::StepStart:
      return tau[k];
    case TorqueHold::PiecewiseLinear:
      return tau[k] + (s / h) * (tau[k + 1] - tau[k]);
    case TorqueHold::PiecewiseCubic: {
      const std::array<Vector3, 4> c = cubicHoldCoefficients(tau, k, h);
      return c[0] + s * (c[1] + s * (c[2] + s * c[3]));
    }
  }
  return tau[k];
}

Vector3 ManeuverInterpolation::meanTorque(double t0, double t1) const {
  const double a = std::clamp(t0, 0.0, duration()), b = std::clamp(t1, 0.0, duration());
  if (!(b > a)) return at(a).torque;
  const double h = maneuver_.time_step;
  const auto hold = [&](double t) {  // t inside a piece: its step is the one that holds it
    return torqueOnStep(std::clamp(static_cast<int>(std::floor(t / h)), 0, steps() - 1), t);
  };
  return meanOverHold<Vector3>(hold, a, b, h);
}

Vector3 ManeuverInterpolation::paperRateAt(double t) const {
  // paper: row k is the rate of step k (log(F_k)/h), its value at the step's midpoint to second
  // order; linear between the midpoints, its derivative is the node-centred torque's
  // (J(Ω_k − Ω_{k−1})/h ≈ τ_k, seed 000 eq. (18)), so the reference's rate and acceleration agree.
  const int N = steps();
  const double h = maneuver_.time_step;
  const double m = t / h - 0.5;  // in units of h from the first midpoint
  if (m <= 0.0) return maneuver_.angular_velocity[0];
  if (m >= N - 1) return maneuver_.angular_velocity[N - 1];
  const int left = std::min(N - 2, static_cast<int>(std::floor(m)));
  const double w = m - left;
  const Vector3& W_left = maneuver_.angular_velocity[left];
  return W_left + w * (maneuver_.angular_velocity[left + 1] - W_left);
}

Vector3 ManeuverInterpolation::nodeRate(int k) const {
  const Vector3& row = maneuver_.angular_velocity[k];
  if (scheme_ != SchemeKind::Variational || hold_ == TorqueHold::StepStart || k == steps()) {
    return row;
  }
  // variational: row k is J⁻¹ μ(F_k), the rate just after the impulse h τ_k at t_k; the body
  // under the node-centred hold passes t_k halfway through it.
  return row - 0.5 * maneuver_.time_step * (inertia_inverse_ * maneuver_.torque[k]);
}

ManeuverSample ManeuverInterpolation::at(double t) const {
  const int N = steps();
  const double h = maneuver_.time_step;
  ManeuverSample sample;
  sample.time = std::min(std::max(t, 0.0), N * h);
  const bool paper_rates = scheme_ == SchemeKind::Paper && hold_ != TorqueHold::StepStart;
  // A node (to round-off in t): its own row, exactly.
  const long nearest = std::lround(sample.time / h);
  if (std::abs(sample.time - nearest * h) <= kNodeSnap * h) {
    sample.attitude = maneuver_.attitude[nearest];
    sample.angular_velocity = paper_rates ? paperRateAt(nearest * h) : nodeRate(nearest);
    sample.torque = maneuver_.torque[nearest];
    return sample;
  }
  // The step that holds t.
  const int k = std::min(N - 1, static_cast<int>(std::floor(sample.time / h)));
  const double s = sample.time - k * h;
  sample.torque = torqueOnStep(k, sample.time);
  const Matrix3& R_k = maneuver_.attitude[k];
  const Vector3& W_k = maneuver_.angular_velocity[k];
  if (hold_ == TorqueHold::PiecewiseCubic && scheme_ == SchemeKind::FourthOrder) {
    // The continuous body under the cubic hold, from node k (replayPlan's integrator).
    Matrix3 R = R_k;
    Vector3 W = W_k;
    const auto torque = [&](const Matrix3& R_s, double ds) {
      Vector3 total = torqueOnStep(k, k * h + ds);
      if (effects_) total += effects_->torque(R_s, k * h + ds);
      return total;
    };
    rigidBodyStep(inertia_, inertia_inverse_, s, torque, &R, &W);
    sample.attitude = R;
    sample.angular_velocity = W;
    return sample;
  }
  const double fraction = s / h;
  const Vector3 step = so3::log(Matrix3(R_k.transpose() * maneuver_.attitude[k + 1]));
  sample.attitude = R_k * so3::exp(Vector3(fraction * step));
  sample.angular_velocity = paper_rates
                                ? paperRateAt(sample.time)
                                : Vector3(nodeRate(k) + fraction * (nodeRate(k + 1) - nodeRate(k)));
  return sample;
}

AttitudeReference ManeuverInterpolation::referenceAt(double t) const {
  const ManeuverSample s = at(t);
  AttitudeReference r;
  r.attitude = s.attitude;
  r.angular_velocity = s.angular_velocity;
  Vector3 torque = s.torque;
  if (effects_) torque += effects_->torque(s.attitude, s.time);
  const Vector3& w = s.angular_velocity;
  r.angular_acceleration = inertia_inverse_ * (torque - w.cross(inertia_ * w));
  return r;
}

double defaultTrackingFrequency(double duration) {
  return kTrackingCyclesPerManeuver / duration;
}

namespace {

/// Fills the run's terminal and worst errors against the reference.
void measureErrors(const ManeuverInterpolation& reference, TrackingRun* run) {
  const Maneuver& a = run->actual;
  const int M = a.steps();
  for (int j = 0; j <= M; ++j) {
    const ManeuverSample r = reference.at(a.time[j]);
    run->max_attitude_error =
        std::max(run->max_attitude_error, so3::angleBetween(r.attitude, a.attitude[j]));
  }
  const ManeuverSample end = reference.at(reference.duration());
  run->terminal_attitude_error = so3::angleBetween(end.attitude, a.attitude[M]);
  run->terminal_velocity_error = (a.angular_velocity[M] - end.angular_velocity).norm();
}

}  // namespace

TrackingLaw::TrackingLaw(const ManeuverInterpolation& reference, const EffectModel* effects,
                         const TrackingOptions& options)
    : reference_(reference),
      effects_(effects && !effects->empty() ? effects : nullptr),
      natural_frequency_(options.natural_frequency == 0.0
                             ? defaultTrackingFrequency(reference.duration())
                             : options.natural_frequency),
      gains_(trackingGains(reference.inertia(), natural_frequency_, options.damping)) {}

Vector3 TrackingLaw::command(const Matrix3& attitude, const Vector3& angular_velocity,
                             double t) const {
  Vector3 u = trackingTorque(reference_.inertia(), gains_, attitude, angular_velocity,
                             reference_.referenceAt(t));
  if (effects_) u -= effects_->torque(attitude, t);  // the known effects are compensated
  return u;
}

int TrackingLaw::substepsPerPlanStep() const {
  const double h = reference_.nodes().time_step;
  return std::max(1,
                  static_cast<int>(std::ceil(natural_frequency_ * h / kMaxControlPhasePerSample)));
}

TrackingRun simulateTracking(const ManeuverInterpolation& reference,
                             const Matrix3& initial_attitude, const Vector3& initial_velocity,
                             const EffectModel* effects, Actuation* actuation,
                             const TrackingOptions& options) {
  const double T = reference.duration();
  const int N = reference.steps();
  const TrackingLaw law(reference, effects, options);
  TrackingRun run;
  run.natural_frequency = law.naturalFrequency();
  const Matrix3& inertia = reference.inertia();
  run.substeps = law.substepsPerPlanStep();
  const int M = N * run.substeps;
  const double dt = T / M;
  const bool with_effects = effects && !effects->empty();
  const Matrix3 inertia_inverse = inertia.inverse();

  Maneuver& a = run.actual;
  a.time_step = dt;
  a.time.resize(M + 1);
  a.attitude.resize(M + 1);
  a.angular_velocity.resize(M + 1);
  a.torque.resize(M + 1);
  Matrix3 R = initial_attitude;
  Vector3 W = initial_velocity;
  for (int j = 0; j <= M; ++j) {
    const double t = j * dt;
    a.time[j] = t;
    a.attitude[j] = R;
    a.angular_velocity[j] = W;
    Vector3 u = law.command(R, W, t);
    if (actuation && !actuation->empty()) u = actuation->apply(u);
    a.torque[j] = u;
    if (j == M) break;
    run.effort += 0.5 * u.squaredNorm() * dt;
    const auto torque = [&](const Matrix3& R_s, double s) {
      return with_effects ? Vector3(u + effects->torque(R_s, t + s)) : u;
    };
    rigidBodyStep(inertia, inertia_inverse, dt, torque, &R, &W);
  }
  measureErrors(reference, &run);
  return run;
}

RigidBodyState predictState(const Matrix3& inertia, const EffectModel* effects,
                            const RigidBodyState& state, const Vector3& torque, double t,
                            double dt) {
  RigidBodyState out = state;
  if (dt == 0.0) return out;
  const bool with_effects = effects && !effects->empty();
  const auto total = [&](const Matrix3& R_s, double s) {
    return with_effects ? Vector3(torque + effects->torque(R_s, t + s)) : torque;
  };
  rigidBodyStep(inertia, inertia.inverse(), dt, total, &out.attitude, &out.angular_velocity);
  return out;
}

RigidBodyPlant::RigidBodyPlant(const Matrix3& inertia, const Matrix3& initial_attitude,
                               const Vector3& initial_velocity,
                               std::shared_ptr<const EffectModel> effects, Actuation actuation,
                               double max_step)
    : inertia_(inertia),
      inertia_inverse_(inertia.inverse()),
      effects_(effects && !effects->empty() ? std::move(effects) : nullptr),
      actuation_(std::move(actuation)),
      max_step_(max_step),
      attitude_(initial_attitude),
      velocity_(initial_velocity) {
  if (!(std::isfinite(max_step) && max_step > 0.0)) {
    throw InvalidInput("max_step: must be a finite time > 0 s, got " + exactNumber(max_step));
  }
}

Vector3 RigidBodyPlant::command(const Vector3& commanded) {
  delivered_ = actuation_.empty() ? commanded : actuation_.apply(commanded);
  return delivered_;
}

void RigidBodyPlant::advanceTo(double t) {
  if (!(t > time_)) return;
  // Equal steps of at most max_step: the held torque plus the effects at every RKMK4 stage.
  const int steps = std::max(1, static_cast<int>(std::ceil((t - time_) / max_step_)));
  const double dt = (t - time_) / steps;
  for (int i = 0; i < steps; ++i) {
    const double t_step = time_ + i * dt;
    const auto torque = [&](const Matrix3& R_s, double s) {
      return effects_ ? Vector3(delivered_ + effects_->torque(R_s, t_step + s)) : delivered_;
    };
    rigidBodyStep(inertia_, inertia_inverse_, dt, torque, &attitude_, &velocity_);
  }
  time_ = t;
}

double openLoopEffort(SchemeKind scheme, const Maneuver& replayed) {
  return replayed.time_step * schemeCost(scheme, replayed.torque);
}

}  // namespace attitude_planner
