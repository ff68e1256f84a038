#include "attitude_planner/analysis/replanning.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

Maneuver remainderOf(const Maneuver& maneuver, int k) {
  const int N = maneuver.steps();
  if (k < 0 || k > N) {
    throw InvalidInput("remainderOf: node " + std::to_string(k) + " is outside 0.." +
                       std::to_string(N));
  }
  Maneuver rest;
  rest.time_step = maneuver.time_step;
  for (int i = k; i <= N; ++i) {
    rest.time.push_back((i - k) * maneuver.time_step);
    rest.attitude.push_back(maneuver.attitude[i]);
    rest.angular_velocity.push_back(maneuver.angular_velocity[i]);
    rest.torque.push_back(maneuver.torque[i]);
  }
  return rest;
}

PlanningProblem remainderProblem(const PlanningProblem& problem, int k, const Matrix3& attitude,
                                 const Vector3& angular_velocity) {
  const int left = problem.steps - k;
  if (k < 0 || left < kMinSteps) {
    throw InvalidInput("re-plan from node " + std::to_string(k) + " of " +
                       std::to_string(problem.steps) + ": " + std::to_string(left) +
                       " steps left, fewer than " + std::to_string(kMinSteps));
  }
  const double h = problem.duration / problem.steps;
  PlanningProblem rest = problem;
  rest.steps = left;
  rest.duration = left * h;
  rest.initial_attitude = attitude;
  rest.initial_velocity = angular_velocity;
  if (problem.effects && !problem.effects->empty()) {
    rest.effects = std::make_shared<const EffectModel>(problem.effects->timeShifted(k * h));
  }
  rest.direction = RotationDirection::Shortest;
  rest.extra_revolutions = 0;
  rest.accuracy = AccuracyTarget();
  rest.objective = Objective::MinimumEffort;
  rest.time_margin = 0.0;
  return rest;
}

RigidBodyState schemeStartOf(SchemeKind scheme, const Matrix3& inertia, const EffectModel* effects,
                             const RigidBodyState& body, const Vector3& command, double t,
                             double time_step) {
  if (scheme != SchemeKind::Paper && scheme != SchemeKind::Variational) return body;
  const RigidBodyState midpoint = predictState(inertia, effects, body, command, t, 0.5 * time_step);
  return RigidBodyState{body.attitude, midpoint.angular_velocity};  // R_0 is the node's R(t_k)
}

int lastReplanNode(int steps, double time_step, double natural_frequency) {
  const double settling = kReplanSettlingTimeConstants / natural_frequency;  // [s]
  const int steps_left =
      std::max(kMinSteps, static_cast<int>(std::ceil(settling / time_step - 1e-9)));
  return steps - steps_left;
}

int replanPeriodSteps(double period, int steps, double time_step) {
  if (!(std::isfinite(period) && period >= 0.0)) {
    throw InvalidInput("~replan_period: must be >= 0 s (0 = T / " +
                       std::to_string(kDefaultReplansPerManeuver) + "), got " +
                       exactNumber(period));
  }
  const double raw =
      period == 0.0 ? static_cast<double>(steps) / kDefaultReplansPerManeuver : period / time_step;
  return std::max(1, static_cast<int>(std::lround(raw)));
}

RecedingHorizonRun::RecedingHorizonRun(const Maneuver& plan, SchemeKind scheme,
                                       const Matrix3& inertia,
                                       std::shared_ptr<const EffectModel> effects,
                                       const Actuation& actuation, TrackingOptions options,
                                       std::optional<RigidBodyState> start)
    : scheme_(scheme),
      inertia_(inertia),
      effects_(std::move(effects)),
      actuation_(actuation),
      options_(options),
      steps_(plan.steps()),
      time_step_(plan.time_step) {
  if (options_.natural_frequency == 0.0) {
    options_.natural_frequency = defaultTrackingFrequency(steps_ * time_step_);
  }
  if (!start) start = RigidBodyState{plan.attitude.front(), plan.angular_velocity.front()};
  segments_.push_back(fly(plan, 0, start->attitude, start->angular_velocity));
}

RecedingHorizonRun::Segment RecedingHorizonRun::fly(const Maneuver& rows, int k,
                                                    const Matrix3& attitude,
                                                    const Vector3& angular_velocity) const {
  Segment s;
  s.node = k;
  const double t0 = k * time_step_;
  if (effects_ && !effects_->empty()) {
    s.effects = k == 0 ? effects_ : std::make_shared<const EffectModel>(effects_->timeShifted(t0));
  }
  s.reference =
      std::make_shared<const ManeuverInterpolation>(rows, scheme_, inertia_, s.effects.get());
  // The noise stream continued: the first run drew one sample per control step, j = 0..M.
  Actuation actuation = actuation_;
  const int skipped = segments_.empty() ? 0 : k * segments_.front().run.substeps;
  for (int j = 0; j < skipped; ++j) actuation.apply(Vector3::Zero());
  s.run = simulateTracking(*s.reference, attitude, angular_velocity, s.effects.get(), &actuation,
                           options_);
  s.body = std::make_shared<const ManeuverInterpolation>(s.run.actual, scheme_, inertia_, nullptr,
                                                         TorqueHold::StepStart);
  return s;
}

void RecedingHorizonRun::adopt(const Maneuver& plan, int planned_from, int at) {
  const int expected = steps_ - planned_from;
  if (planned_from < 0 || plan.steps() != expected ||
      std::abs(plan.time_step - time_step_) > 1e-9 * time_step_) {
    throw InvalidInput("re-plan from node " + std::to_string(planned_from) + ": " +
                       std::to_string(plan.steps()) + " steps of " +
                       std::to_string(plan.time_step) + " s, expected " + std::to_string(expected) +
                       " of " + std::to_string(time_step_) + " s");
  }
  if (at < planned_from || at >= steps_ || at < segments_.back().node) {
    throw InvalidInput("re-plan from node " + std::to_string(planned_from) +
                       " cannot be adopted at node " + std::to_string(at));
  }
  const ManeuverSample state = bodyAtNode(at);
  Segment next =
      fly(remainderOf(plan, at - planned_from), at, state.attitude, state.angular_velocity);
  if (at == segments_.back().node) segments_.pop_back();  // replaced before it flew at all
  segments_.push_back(std::move(next));
}

const RecedingHorizonRun::Segment& RecedingHorizonRun::segmentAt(double t) const {
  for (std::size_t i = segments_.size(); i-- > 1;) {
    if (t >= segments_[i].node * time_step_) return segments_[i];
  }
  return segments_.front();
}

ManeuverSample RecedingHorizonRun::bodyAtNode(int k) const {
  const double t = k * time_step_;
  const Segment& s = segmentAt(t);
  // The run's own row at the node (its control grid contains the plan's nodes).
  const int j = (k - s.node) * s.run.substeps;
  ManeuverSample sample;
  sample.time = t;
  sample.attitude = s.run.actual.attitude[j];
  sample.angular_velocity = s.run.actual.angular_velocity[j];
  sample.torque = s.run.actual.torque[j];
  return sample;
}

ManeuverSample RecedingHorizonRun::bodyAt(double t) const {
  const Segment& s = segmentAt(t);
  ManeuverSample sample = s.body->at(t - s.node * time_step_);
  sample.time = t;
  return sample;
}

ManeuverSample RecedingHorizonRun::referenceAt(double t) const {
  const Segment& s = segmentAt(t);
  ManeuverSample sample = s.reference->at(t - s.node * time_step_);
  sample.time = t;
  return sample;
}

Vector3 RecedingHorizonRun::commandAt(const RigidBodyState& state, double t) const {
  const Segment& s = segmentAt(t);
  const TrackingLaw law(*s.reference, s.effects.get(), options_);
  return law.command(state.attitude, state.angular_velocity, t - s.node * time_step_);
}

Maneuver RecedingHorizonRun::planRemainderAt(int k) const {
  const Segment& s = segmentAt(k * time_step_);
  return remainderOf(s.reference->nodes(), k - s.node);
}

int RecedingHorizonRun::controlSamples(int i) const {
  const Segment& s = segments_[i];
  const int end_node = i + 1 < static_cast<int>(segments_.size()) ? segments_[i + 1].node : steps_;
  return (end_node - s.node) * s.run.substeps;
}

double RecedingHorizonRun::effort() const {
  double sum = 0.0;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const Maneuver& a = segments_[i].run.actual;
    const int samples = controlSamples(static_cast<int>(i));
    for (int j = 0; j < samples; ++j) sum += 0.5 * a.torque[j].squaredNorm() * a.time_step;
  }
  return sum;
}

double RecedingHorizonRun::maxAttitudeError() const {
  double worst = 0.0;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const Segment& s = segments_[i];
    const Maneuver& a = s.run.actual;
    const int samples = controlSamples(static_cast<int>(i));
    for (int j = 0; j <= samples; ++j) {
      const ManeuverSample r = s.reference->at(a.time[j]);
      worst = std::max(worst, so3::angleBetween(r.attitude, a.attitude[j]));
    }
  }
  return worst;
}

}  // namespace attitude_planner
