#include "planning/drivers/minimum_time_starts.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <sstream>

#include "attitude_planner/planning/minimum_time.hpp"
#include "attitude_planner/planning/reaction_wheels.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/strategies/starts.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

/// The excursion starts: their size [rad] and first T relative to the eigenaxis
/// slew's.
constexpr double kFreeTimeExcursion = 0.3;
/// With cones also excursions this large [rad]: a detour round a cone is a
/// larger departure.
constexpr double kFreeTimeConeExcursion = 0.8;
constexpr double kFreeTimeStartFactor = 0.96;
/// The tolerance of the minimum-effort solve that clears a start of the cones (coneClearStart): it
/// makes a start, which the free-time solve moves anyway, not an answer. Measured on
/// scenes/min_time_keep_out.yaml at N = 128: 1e-4 instead of the request's 1e-10 took the six
/// clearing solves from 149 to 99 interior-point iterations, every T* of the cone table the same.
/// 1e-3 instead of 1e-4, on the seeded cone suite (scripts/minimum_time_cost.py, seed 4949, 20
/// requests): 11,057 -> 10,105 iterations, every T* the same to 1e-9; 1e-2 gave 9,888 but one
/// request 27 % more (docs/results/minimum_time_clearing_tolerance.md). With the clearings
/// started from the cone's near side (onTheNearSide), 1e-3 is too loose: clearings of one plan,
/// reached from starts on different sides of it, end 1.2e-3 to 5e-3 apart (seed 4949 #12), one
/// plan counted as several starts (StartsClearedToOneMinimumEffortPlanAreOneStart); at 1e-4 they
/// agree within kSameStart, for 48,098 instead of 47,251 iterations on the 120 seeded cone
/// requests, every T* the same (docs/results/minimum_time_cone_sides.md).
constexpr double kConeClearTolerance = 1e-4;
/// The iterations the warm clearing solve gets before the cold one (coneClearStart). A warm solve
/// that has not cleared its start by then is crossing the cone the long way: measured on the
/// seeded cone suite (scripts/minimum_time_cost.py, seed 4949), the warm solves that converged
/// took 4-65 iterations but for a tail of 93-244, while a cold solve takes 4-8; the clearings
/// were 37 % of minimum time's iterations around a cone.
constexpr int kConeClearWarmIterations = 60;
/// The rotation [rad] of a boundary step at the boundary rate that a start's duration keeps to
/// (representableDuration): beyond about pi no step exists, and the implicit variational step
/// loses its solution earlier on thin bodies (h |Omega| = 2.25 rad measured).
constexpr double kLargestBoundaryStepRotation = 1.0;

/// The tolerance of the class optima that start a spinning minimum-time problem (classOptimum):
/// a start, which the free-time solve moves anyway, not an answer.
constexpr double kClassOptimumTolerance = 1e-6;

/// A body axis whose part perpendicular to the eigenaxis is shorter than this
/// gives no start.
constexpr double kSmallestProjection = 0.3;
/// Two excursion axes closer than this (cosine) are one start.
constexpr double kSameAxis = 0.99;
/// With cones the excursions' directions: this many evenly spaced about the eigenaxis
/// (coneExcursionAxes), with the eigenaxis slew turned round the cone on each side
/// (coneSideStarts). Measured (docs/results/minimum_time_cone_sides.md, fewer excursion
/// directions): on 380 seeded cone requests 4 to 12 evenly spaced directions kept every T* of the
/// up to 18 directions of excursionAxes and their negatives but one (8181 #4, +1.09 %: a basin
/// narrower than 30 degrees in direction, between two of the directions); with the two sides too
/// every T* was kept, on those and on 160 requests of seeds never looked at before, at 0.62x the
/// iterations.
constexpr int kConeExcursionDirections = 4;
/// With cones the excursions' bumps peak at these s = t/T (skewedExcursionSlew): skewed in time.
/// A symmetric start meets the time-symmetric KKT points (saddles on second_order, poorer local
/// minima on paper), a skewed one the passage of the cone that is not symmetric. Measured on
/// scenes/min_time_keep_out.yaml, 0.8 rad excursions, paper: 29.7113 s at N = 32 and 29.2354 s at
/// N = 64 with peak 0.4, 29.7404 s and 29.2470 s with 0.5 (above the search's 29.7113, 29.2354);
/// second_order reaches the same T* either way (its symmetric saddle is left, leaveSaddles).
constexpr double kConeExcursionPeaks[] = {0.4};

std::string axisName(const Vector3& v) {
  std::ostringstream out;
  out << "[" << std::round(v.x() * 1000) / 1000 << ", " << std::round(v.y() * 1000) / 1000 << ", "
      << std::round(v.z() * 1000) / 1000 << "]";
  return out.str();
}

/// Spinning ends: the reduced problem's own start (the geodesic between the
/// fixed inner attitudes) at the eigenaxis guess. (An empty list of attitudes
/// here once reached setInteriorFromAttitudes: every spinning minimum-time
/// request ended "invalid input".)
FreeTimeStart geodesicStart(const PlanningProblem& problem) {
  PlanningProblem at = problem;
  at.duration = eigenaxisDurationGuess(problem);
  std::vector<Matrix3> attitudes;
  try {
    const ReducedProblem np(at);
    attitudes = np.attitudes(np.current());
  } catch (const StepTooLarge&) {  // no boundary step at that h: the solve reports it
    attitudes.assign(problem.steps + 1, problem.initial_attitude);
  }
  FreeTimeStart start{"geodesic", AttemptStart::Hermite, attitudes, at.duration};
  start.detail.duration = at.duration;
  return start;
}

/// The unconstrained minimum-effort plan (Newton) in class `c` at the start's T, or nothing where
/// it does not converge. Its torques are the least the class's motions at that T need, so a
/// free-time solve from it starts inside the bounds far more often than from the Hermite curve
/// Newton starts from (measured: from the Hermite curves every start of several spinning
/// requests went elastic and ran to the iteration limit, docs/results/bounded_verdicts.md).
std::optional<std::vector<Matrix3>> classOptimum(const PlanningProblem& at, const HomotopyClass& c,
                                                 SolveContext& context) {
  PlanningProblem in_class = at;
  in_class.objective = Objective::MinimumEffort;
  in_class.constraints.clear();
  in_class.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  in_class.time_margin = 0.0;
  in_class.direction = c.long_way ? RotationDirection::LongWay : RotationDirection::Shortest;
  in_class.extra_revolutions = c.extra_revolutions;
  SolverOptions options;
  options.advanced = context.options().advanced;
  options.enumerate_classes = false;
  options.tolerance = kClassOptimumTolerance;
  try {
    // A start of the free-time solves (a few Newton steps at the coarsest grid), in the request's
    // context: its iterations are reported and numbered with the request's, and its budget and
    // cancel flag stop it (then it gives no start). Its attempts stay out of the answer's trail.
    const SolveContext::Aside start_only(context);
    const SolveContext::Scope scope(context, AttemptStage::MinimumTimeSolve, c);
    const PlanResult r = solveWithNewton(in_class, SolveRequest(options), context);
    if (r.converged()) return r.maneuver.attitude;
  } catch (const StepTooLarge& e) {  // no boundary step at the guess's h
  }
  return std::nullopt;
}

/// The classes whose lifts start a spinning minimum-time problem (spinningStarts): the nearest
/// and the other way round, each with 0 and 1 extra turn, as the class survey of minimum effort.
constexpr HomotopyClass kSpinningStartClasses[] = {{false, 0}, {true, 0}, {false, 1}, {true, 1}};

/// Spinning ends: the unconstrained optima in the classes of kSpinningStartClasses
/// (classOptimum), the geodesic (geodesicStart) and the coasting start (the torque-free motions
/// from both ends, blended), all at the eigenaxis guess. Minimum time with spinning ends has
/// local minima in several classes, which one geodesic start misses
/// (docs/results/bounded_verdicts.md). The class optima come first: they start inside the bounds
/// most often, and the watch then stops the later starts that cannot beat the least T found. The
/// class optima are solved at once (runBranches), each in a branch of `context`.
std::vector<FreeTimeStart> spinningStarts(const PlanningProblem& problem, SolveContext& context) {
  std::vector<FreeTimeStart> starts;
  PlanningProblem at = problem;
  at.duration = eigenaxisDurationGuess(problem);
  const auto add = [&](const std::string& name, AttemptStart kind, std::vector<Matrix3> attitudes) {
    starts.push_back({name, kind, std::move(attitudes), at.duration});
    starts.back().detail.duration = at.duration;
  };
  constexpr int kClasses = std::size(kSpinningStartClasses);
  std::optional<std::vector<Matrix3>> optima[kClasses];
  runBranches(context, kClasses, [&](int i, SolveContext& branch) {
    optima[i] = classOptimum(at, kSpinningStartClasses[i], branch);
  });
  for (int i = 0; i < kClasses; ++i) {
    const HomotopyClass& c = kSpinningStartClasses[i];
    if (optima[i]) {
      add(std::string("unconstrained optimum in the ") + (c.long_way ? "other-way" : "nearest") +
              " lift + " + std::to_string(c.extra_revolutions) + " turn(s)",
          AttemptStart::UnconstrainedOptimum, std::move(*optima[i]));
    }
  }
  starts.push_back(geodesicStart(problem));
  try {
    if (const std::optional<Maneuver> coast = coastingStart(at)) {
      add("coasting", AttemptStart::Coasting, coast->attitude);
    }
  } catch (const StepTooLarge&) {  // no boundary step at the guess's h
  }
  return starts;
}

/// An excursion start's parameters as data (Attempt::start_detail).
void describeExcursion(const Vector3& eigenaxis, const Vector3& axis, double size,
                       FreeTimeStart* start) {
  StartDetail& detail = start->detail;
  detail.duration = start->duration;
  detail.eigenaxis = eigenaxis;
  detail.excursion_axis = axis;
  detail.excursion = size;
}

}  // namespace

double eigenaxisDurationGuess(const PlanningProblem& problem) {
  const Matrix3& J = problem.inertia;
  const double largest_moment = Eigen::SelfAdjointEigenSolver<Matrix3>(J).eigenvalues().maxCoeff();
  const double authority =
      std::max(torqueAuthority(problem).smallest_about_any_axis, 1e-300);  // [N m]
  const double angle =
      std::max(so3::angleBetween(problem.initial_attitude, problem.final_attitude), 1e-3);
  // Rest to rest: accelerate half way, brake half way. Boundary rates add the time to shed and
  // to gain their momentum |J Omega| at that authority; |Omega| times the largest moment
  // overstated it several times on thin bodies and put the first step beyond pi on the grid.
  const double spin =
      ((J * problem.initial_velocity).norm() + (J * problem.final_velocity).norm()) / authority;
  const double guess = 2.0 * std::sqrt(angle * largest_moment / authority) + spin;
  const double proven = durationLowerBound(problem).seconds;
  return std::max(std::min(guess, representableDuration(problem)), proven);
}

double representableDuration(const PlanningProblem& problem) {
  const double rate = std::max(problem.initial_velocity.norm(), problem.final_velocity.norm());
  if (rate == 0.0) return std::numeric_limits<double>::infinity();
  return problem.steps * kLargestBoundaryStepRotation / rate;
}

namespace {

/// excursionSlew with the bump sin²(π φ(s)) peaking at s = `peak`: φ(s) = s + c s(1 − s), c =
/// (½ − peak)/(peak (1 − peak)), a smooth monotone warp of time (|c| < 1) with φ(peak) = ½. Its
/// slope at the ends is finite (1 ± c), so the start's end torques are of the bump's size: the
/// former warp s^a (a = ln ½ / ln peak) had an infinite slope at s = 0 and the starts' first
/// torques 7–14× their bounds (every skewed start then began elastic).
Maneuver skewedExcursionSlew(const PlanningProblem& problem, const Vector3& excursion_axis,
                             double excursion, double peak) {
  const double warp = (0.5 - peak) / (peak * (1 - peak));
  const Vector3 rotation = so3::log(problem.initial_attitude.transpose() * problem.final_attitude);
  const double angle = rotation.norm();
  const Vector3 axis = angle > 0 ? Vector3(rotation / angle) : Vector3::UnitX();
  Maneuver m;
  const int N = problem.steps;
  m.time_step = problem.duration / N;
  for (int k = 0; k <= N; ++k) {
    const double s = static_cast<double>(k) / N;
    const double theta = s <= 0.5 ? 2.0 * angle * s * s : angle * (1.0 - 2.0 * (1 - s) * (1 - s));
    const double bump = excursion * std::pow(std::sin(M_PI * (s + warp * s * (1 - s))), 2);
    m.time.push_back(s * problem.duration);
    m.attitude.push_back(problem.initial_attitude * so3::exp(theta * axis) *
                         so3::exp(bump * excursion_axis));
    m.angular_velocity.push_back(Vector3::Zero());
    m.torque.push_back(Vector3::Zero());
  }
  return m;
}

}  // namespace

Maneuver excursionSlew(const PlanningProblem& problem, const Vector3& excursion_axis,
                       double excursion) {
  return skewedExcursionSlew(problem, excursion_axis, excursion, 0.5);
}

double eigenaxisBangBangDuration(const PlanningProblem& problem) {
  const Vector3 rotation = so3::log(problem.initial_attitude.transpose() * problem.final_attitude);
  const double angle = std::max(rotation.norm(), 1e-9);
  const Vector3 e = rotation / angle;
  const Matrix3& J = problem.inertia;
  // At T = 1: θ̈ = ±4Θ, θ̇ ≤ 2Θ (peak at s = ½, where the gyroscopic term is
  // largest).
  const Vector3 gyroscopic = e.cross(J * e) * (4.0 * angle * angle);  // θ̇² ê × Jê at s = ½
  const Vector3 inertial = J * e * (4.0 * angle);
  const ReactionWheels& wheels = problem.reaction_wheels;
  const WheelArray wheel_array = wheels.present() ? wheelArray(wheels) : WheelArray{};
  double T_squared = 0.0;
  for (const double sign : {1.0, -1.0}) {  // accelerating and braking at the peak rate
    const Vector3 tau = sign * inertial + gyroscopic;
    if (problem.hasTorqueBounds()) {
      T_squared =
          std::max(T_squared, (tau.cwiseAbs().array() / problem.max_torque.array()).maxCoeff());
    }
    for (const PlanningConstraint& c : problem.constraints)
      if (c.kind == ConstraintKind::MaxTorqueNorm)
        T_squared = std::max(T_squared, tau.norm() / c.limit);
    // With reaction wheels their torque limits bound it too (a wheel-limited request may have no
    // other torque bound; T was then 0): the array's torque −τ by the minimum-norm law, u = −A⁺τ
    // (the gyroscopic term of the wheels' momentum left out of a start's figure).
    if (wheels.present()) {
      const Eigen::VectorXd u = wheel_array.pseudo_inverse * tau;
      for (int i = 0; i < wheels.count(); ++i)
        T_squared = std::max(T_squared, std::abs(u(i)) / wheels.torqueLimit(i));
    }
  }
  double T = std::sqrt(T_squared);
  for (const PlanningConstraint& c : problem.constraints)
    if (c.kind == ConstraintKind::MaxAngularRate) T = std::max(T, 2.0 * angle / c.limit);
  return T;
}

std::vector<Vector3> excursionAxes(const Vector3& e) {
  std::vector<Vector3> projected;
  for (int a = 0; a < 3; ++a) {
    const Vector3 p = Vector3::Unit(a) - e * e(a);
    if (p.norm() > kSmallestProjection) projected.push_back(p.normalized());
  }
  std::vector<Vector3> axes = projected;
  for (std::size_t i = 0; i < projected.size(); ++i) {
    for (std::size_t j = i + 1; j < projected.size(); ++j) {
      for (const double sign : {1.0, -1.0}) {
        const Vector3 d = projected[i] + sign * projected[j];
        if (d.norm() > kSmallestProjection) axes.push_back(d.normalized());
      }
    }
  }
  std::vector<Vector3> distinct;
  for (const Vector3& a : axes) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(),
                                  [&](const Vector3& b) { return a.dot(b) > kSameAxis; });
    if (!seen) distinct.push_back(a);
  }
  return distinct;
}

namespace {

/// kConeExcursionDirections directions evenly spaced in the plane perpendicular to the eigenaxis
/// `e`, from the body axis whose part perpendicular to it is longest: body-fixed, so the same in
/// every world frame, and the same set whatever the body axes' labels or signs.
std::vector<Vector3> coneExcursionAxes(const Vector3& e) {
  Vector3 reference = Vector3::Zero();
  for (int a = 0; a < 3; ++a) {
    const Vector3 perpendicular = Vector3::Unit(a) - e * e(a);
    if (perpendicular.norm() > reference.norm()) reference = perpendicular;
  }
  reference.normalize();
  const Vector3 across = e.cross(reference);
  std::vector<Vector3> axes;
  for (int j = 0; j < kConeExcursionDirections; ++j) {
    const double angle = 2.0 * M_PI * j / kConeExcursionDirections;
    axes.push_back(std::cos(angle) * reference + std::sin(angle) * across);
  }
  return axes;
}

}  // namespace

std::vector<FreeTimeStart> freeTimeStarts(const PlanningProblem& problem, bool rest_to_rest,
                                          SolveContext& context) {
  if (!rest_to_rest) return spinningStarts(problem, context);
  const double T_eigenaxis = eigenaxisBangBangDuration(problem);
  PlanningProblem at = problem;
  at.duration = T_eigenaxis;
  const Vector3 e =
      so3::log(problem.initial_attitude.transpose() * problem.final_attitude).normalized();
  std::vector<FreeTimeStart> starts{
      {"eigenaxis", AttemptStart::EigenaxisSlew, excursionSlew(at, e, 0.0).attitude, T_eigenaxis}};
  starts.back().detail.duration = T_eigenaxis;
  starts.back().detail.eigenaxis = e;
  if (!problem.hasCones()) {
    for (const Vector3& axis : excursionAxes(e)) {
      std::ostringstream name;
      name << "excursion " << kFreeTimeExcursion << " rad about " << axisName(axis);
      starts.push_back({name.str(), AttemptStart::Excursion,
                        excursionSlew(at, axis, kFreeTimeExcursion).attitude,
                        kFreeTimeStartFactor * T_eigenaxis});
      describeExcursion(e, axis, kFreeTimeExcursion, &starts.back());
    }
    return starts;
  }
  // With cones the excursions of a detour's size, skewed in time
  // (kConeExcursionPeaks), about directions all round the eigenaxis (a cone is passed on one side
  // or the other, and the sides are different local minima of T); the 0.3 rad ones reached no KKT
  // point the 0.8 rad ones and the eigenaxis did not (measured, scenes/min_time_keep_out.yaml,
  // second_order, paper and variational at N = 32 and 64), and clearing each start of the cones
  // is a minimum-effort solve.
  for (const double peak : kConeExcursionPeaks) {
    for (const Vector3& axis : coneExcursionAxes(e)) {
      std::ostringstream name;
      name << "excursion " << kFreeTimeConeExcursion << " rad about " << axisName(axis)
           << " peaking at s = " << peak;
      starts.push_back({name.str(), AttemptStart::Excursion,
                        skewedExcursionSlew(at, axis, kFreeTimeConeExcursion, peak).attitude,
                        kFreeTimeStartFactor * T_eigenaxis});
      describeExcursion(e, axis, kFreeTimeConeExcursion, &starts.back());
      starts.back().detail.excursion_peak = peak;
    }
  }
  // And the eigenaxis slew turned round the cone it crosses most deeply, on each side
  // (coneSideStarts): a detour where the cone is, which directions spaced about the eigenaxis may
  // pass between. An eigenaxis start (no bump), at the excursions' T.
  const std::vector<Maneuver> sides = coneSideStarts(at, excursionSlew(at, e, 0.0));
  for (std::size_t side = 0; side < sides.size(); ++side) {
    starts.push_back({"eigenaxis round the cone on side " + std::to_string(side + 1),
                      AttemptStart::EigenaxisSlew, sides[side].attitude,
                      kFreeTimeStartFactor * T_eigenaxis});
    describeExcursion(e, Vector3::Zero(), 0.0, &starts.back());
  }
  return starts;
}

double coneClearance(const PlanningProblem& problem, const std::vector<Matrix3>& R) {
  double smallest = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : problem.constraints) {
    if (!c.isCone()) continue;
    for (std::size_t k = 1; k + 1 < R.size(); ++k) {
      smallest = std::min(smallest, coneMargin(c, R[k]) - c.margin);
    }
  }
  return smallest;
}

namespace {

/// Each node's turn out of cone `c` (pushedOutOfCones): the turn node j needs to clear the bound
/// by `clearance`, spread to the nodes within W = max(2, N/kConePushTaper) of it by the weight
/// cos²(π|k − j| / (2(W + 1))), the largest of these at each node.
std::vector<double> taperedConeTurns(const PlanningConstraint& c, const std::vector<Matrix3>& R,
                                     double clearance) {
  const int n = static_cast<int>(R.size());
  const int W = std::max(2, (n - 1) / kConePushTaper);
  std::vector<double> turns(n, 0.0);
  for (int j = 1; j + 1 < n; ++j) {
    const double needed = clearance - (coneMargin(c, R[j]) - c.margin);
    if (needed <= 0) continue;
    for (int k = std::max(1, j - W); k <= std::min(n - 2, j + W); ++k) {
      const double weight = std::cos(M_PI * std::abs(k - j) / (2.0 * (W + 1)));
      turns[k] = std::max(turns[k], needed * weight * weight);
    }
  }
  return turns;
}

}  // namespace

std::vector<Matrix3> pushedOutOfCones(const PlanningProblem& problem, std::vector<Matrix3> R,
                                      double clearance) {
  for (const PlanningConstraint& c : problem.constraints) {
    if (!c.isCone()) continue;
    const bool keep_out = c.kind == ConstraintKind::KeepOut;
    const std::vector<double> turns = taperedConeTurns(c, R, clearance);
    for (std::size_t k = 1; k + 1 < R.size(); ++k) {
      if (turns[k] <= 0) continue;
      const Vector3 v = R[k] * c.body_axis;
      Vector3 axis = c.world_direction.cross(v);  // turning about it by + moves v away from s
      axis = axis.norm() > 1e-12 ? axis.normalized() : c.world_direction.unitOrthogonal();
      R[k] = so3::exp((keep_out ? turns[k] : -turns[k]) * axis) * R[k];
    }
  }
  return R;
}

double largestDifference(const std::vector<Matrix3>& a, const std::vector<Matrix3>& b) {
  double largest = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    largest = std::max(largest, (a[k] - b[k]).cwiseAbs().maxCoeff());
  }
  return largest;
}

namespace {

/// `attitudes` turned round the keep-out cone they cross most deeply, on the side nearer them
/// (of coneSideStarts' two, the one that moves them least); `attitudes` where they cross none.
/// The warm clearing solve starts there (coneClearStart): from the attitudes inside the cone its
/// first steps chose the side, often the far one, a long way round or no plan in
/// kConeClearWarmIterations (then the cold solve). Measured on the seeded cone suite
/// (scripts/minimum_time_cost.py, seed 4949, 20 requests, one thread): every start cleared
/// crossed the cone; the clearings 3,774 -> 1,716 iterations, the requests 9,903 -> 7,530, every
/// T* the same to 1e-9 (the far side: 8,883; the cold solve alone for every crossing start:
/// 12,631 and one T* 0.95 % higher; all at kConeClearTolerance 1e-3)
/// (docs/results/minimum_time_cone_sides.md).
std::vector<Matrix3> onTheNearSide(const PlanningProblem& problem,
                                   const std::vector<Matrix3>& attitudes) {
  Maneuver start;
  start.attitude = attitudes;
  const std::vector<Maneuver> sides = coneSideStarts(problem, start);
  if (sides.empty()) return attitudes;
  const auto moved = [&](const Maneuver& side) {
    return largestDifference(side.attitude, attitudes);
  };
  return std::min_element(sides.begin(), sides.end(),
                          [&](const Maneuver& a, const Maneuver& b) { return moved(a) < moved(b); })
      ->attitude;
}

}  // namespace

std::optional<std::vector<Matrix3>> coneClearStart(const PlanningProblem& problem,
                                                   const std::vector<Matrix3>& attitudes,
                                                   double duration, SolveContext& context,
                                                   const SolveContext::IterateWatch& joins) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = duration;
  effort.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  effort.constraints.clear();
  for (PlanningConstraint c : problem.constraints) {
    if (!c.isCone()) continue;
    c.margin += kConeStartClearance;
    effort.constraints.push_back(c);
  }
  // A cone tightened past a cone (node half angle outside (0, π)) is no problem
  // to solve (validateProblem would refuse it): no cleared start.
  for (const PlanningConstraint& c : effort.constraints) {
    if (c.isCone() && !(c.nodeHalfAngle() > 0.0 && c.nodeHalfAngle() < M_PI)) return std::nullopt;
  }
  // A start, not an attempt: its solves stay out of the answer's trail.
  const SolveContext::Aside start_only(context);
  std::optional<SolveContext::WatchIterates> watching;
  if (joins) watching.emplace(context, joins);
  try {
    SolveRequest o(context.options());
    o.tolerance = std::max(o.tolerance, kConeClearTolerance);
    o.enumerate_classes = false;  // a start keeps its class (the free-time solves compare them)
    ReducedProblem np(effort);
    np.setInteriorFromAttitudes(onTheNearSide(effort, attitudes));
    const Maneuver guess = np.maneuver(np.current());
    o.warm_start = &guess;
    o.start.from_constrained_plan = true;
    const int max_iterations = o.max_iterations;
    o.max_iterations = std::min(max_iterations, kConeClearWarmIterations);
    PlanResult r = planAtResolution(effort, o, context);
    if (watching && watching->stoppedASolve()) return std::nullopt;  // the caller's plan
    if (!r.converged()) {
      o.warm_start = nullptr;
      o.start.from_constrained_plan = false;
      o.max_iterations = max_iterations;
      r = planAtResolution(effort, o, context);
    }
    if (r.converged() && !(watching && watching->stoppedASolve())) return r.maneuver.attitude;
  } catch (const StepTooLarge&) {  // a boundary rate with no step at this T: no cleared start
  }
  return std::nullopt;
}

std::optional<std::vector<Matrix3>> coneClearStart(const PlanningProblem& problem,
                                                   const std::vector<Matrix3>& attitudes,
                                                   double duration, const SolverOptions& options) {
  SolveContext context(options);
  return coneClearStart(problem, attitudes, duration, context);
}

}  // namespace attitude_planner
