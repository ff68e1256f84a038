// Accuracy measures of discrete plans and planning to a requested accuracy (accuracy.hpp).
#include "attitude_planner/analysis/accuracy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

ZeroOrderHoldReplay replayZeroOrderHold(const PlanningProblem& problem, const Maneuver& plan,
                                        TorqueHold hold) {
  const int N = plan.steps();
  if (N < 1 || static_cast<int>(plan.torque.size()) != N + 1) {
    throw InvalidInput("zero-order-hold replay: the plan needs N + 1 >= 2 torques");
  }
  const double T = problem.duration;
  const double h = T / N;
  // GBS order 16: steps of T/64, and at most a quarter radian of rotation, are accurate to
  // round-off on smooth maneuvers (more steps only add round-off).
  double max_rate = 0.0;
  for (const Vector3& w : plan.angular_velocity) max_rate = std::max(max_rate, w.norm());
  const double max_step = std::min(T / 64, max_rate > 0.0 ? 0.25 / max_rate : T);
  Matrix3 R = problem.initial_attitude;
  Vector3 W = problem.initial_velocity;
  const auto hold_torque = [&](const Vector3& tau, double length) {
    if (length <= 0.0) return;
    const int steps = std::max(1, static_cast<int>(std::ceil(length / max_step - 1e-9)));
    propagateRigidBody(problem.inertia, tau, length, steps, &R, &W);
  };
  if (hold == TorqueHold::PiecewiseCubic) {
    for (int k = 0; k < N; ++k) {
      const int steps = std::max(1, static_cast<int>(std::ceil(h / max_step - 1e-9)));
      propagateRigidBody(problem.inertia, cubicHoldCoefficients(plan.torque, k, h), h, steps, &R,
                         &W);
    }
  } else if (hold == TorqueHold::PiecewiseLinear) {
    for (int k = 0; k < N; ++k) {
      const int steps = std::max(1, static_cast<int>(std::ceil(h / max_step - 1e-9)));
      propagateRigidBody(problem.inertia, plan.torque[k], plan.torque[k + 1], h, steps, &R, &W);
    }
  } else if (hold == TorqueHold::NodeCentred) {
    hold_torque(plan.torque[0], 0.5 * h);
    for (int k = 1; k < N; ++k) hold_torque(plan.torque[k], h);
    hold_torque(plan.torque[N], 0.5 * h);
  } else {
    for (int k = 0; k < N; ++k) hold_torque(plan.torque[k], h);
  }
  ZeroOrderHoldReplay out;
  out.attitude = R;
  out.angular_velocity = W;
  out.attitude_miss = so3::angleBetween(problem.final_attitude, R);
  out.velocity_miss = (W - problem.final_velocity).norm();
  return out;
}

TorqueHold naturalHold(SchemeKind scheme) {
  switch (scheme) {
    case SchemeKind::SecondOrder:
      return TorqueHold::PiecewiseLinear;
    case SchemeKind::FourthOrder:
      return TorqueHold::PiecewiseCubic;
    case SchemeKind::Paper:
    case SchemeKind::Variational:
      break;
  }
  return TorqueHold::NodeCentred;
}

AccuracyMeasures measureAccuracy(const PlanningProblem& problem, const Maneuver& plan,
                                 const ContinuousReference& reference) {
  AccuracyMeasures m;
  const int N = plan.steps();
  m.steps = N;
  const double h = problem.duration / N;
  m.cost_integral = h * schemeCost(problem.scheme, plan.torque);
  m.cost_error = std::abs(m.cost_integral - reference.cost);
  std::vector<double> times(N + 1);
  for (int k = 0; k <= N; ++k) times[k] = problem.duration * k / N;
  const std::vector<ContinuousState> states = reference.sample(times);
  for (int k = 0; k <= N; ++k) {
    m.trajectory_error =
        std::max(m.trajectory_error, so3::angleBetween(states[k].attitude, plan.attitude[k]));
    if (schemeHasEndTorques(problem.scheme) || (k >= 1 && k < N)) {
      m.torque_error = std::max(m.torque_error, (plan.torque[k] - states[k].torque()).norm());
    }
  }
  m.miss = replayZeroOrderHold(problem, plan, naturalHold(problem.scheme));
  m.miss_step_start = replayZeroOrderHold(problem, plan, TorqueHold::StepStart);
  return m;
}

double measuredOrder(SchemeKind scheme, AccuracyMeasure measure) {
  // Least-squares slopes over N = 64..16384 on both seed examples (docs/results/accuracy.md,
  // "Observed orders"); test_accuracy.cpp checks them on a small sweep. The cost converges at order
  // 1 in both schemes (the boundary data Ω_0, Ω_{N−1} hold over a whole step: the maneuver is
  // effectively h shorter); the attitude miss at order 2 only for the variational scheme.
  // second_order: order 2 in every measure; fourth_order (its Richardson extrapolation): order 4
  // in every measure (docs/results/accuracy.md, docs/design/fourth_order.md).
  if (scheme == SchemeKind::SecondOrder) return 2.0;
  if (scheme == SchemeKind::FourthOrder) return 4.0;
  switch (measure) {
    case AccuracyMeasure::TerminalMiss:
      return scheme == SchemeKind::Variational ? 2.0 : 1.0;
    case AccuracyMeasure::CostError:
      return 1.0;
    case AccuracyMeasure::None:
      break;
  }
  return 1.0;
}

namespace {

/// The order planToAccuracy assumes: the measured one, but for the cost error of a problem with
/// node constraints at most 1 (the bounds' active sets start and end between nodes, so the
/// smooth-case order need not hold; docs/design/fourth_order.md measured none on torque_limited):
/// the Richardson estimate |ΔC|/(2^p − 1) is then an upper bound rather than an underestimate. The
/// terminal miss is measured by the replay whatever the order, which only steers the prediction.
double assumedOrder(const PlanningProblem& problem, SchemeKind scheme, AccuracyMeasure measure) {
  const double order = measuredOrder(scheme, measure);
  if (measure == AccuracyMeasure::CostError && problem.hasNodeConstraints()) {
    return std::min(order, 1.0);
  }
  return order;
}

/// One resolution of the ladder: the plan and its error estimate.
struct Rung {
  PlanResult plan;
  double error = 0.0;
};

/// Solves `problem` at N and estimates its error for `measure` (cost: Richardson with N/2).
Rung solveRung(PlanningProblem problem, int N, SolveContext& context, double order) {
  const AccuracyMeasure measure = problem.accuracy.measure;
  problem.accuracy = AccuracyTarget{};
  problem.steps = N;
  Rung rung;
  rung.plan = planAtResolution(problem, SolveRequest(context.options()), context);
  if (!rung.plan.converged()) return rung;
  if (measure == AccuracyMeasure::TerminalMiss) {
    rung.error = replayZeroOrderHold(problem, rung.plan.maneuver).attitude_miss;
  } else {
    problem.steps = N / 2;
    const PlanResult half = planAtResolution(problem, SolveRequest(context.options()), context);
    if (!half.converged()) {
      rung.plan.termination = half.termination;
      takeReason(&rung.plan, half);
      frameMessage(&rung.plan, frames::RichardsonHalfStopped{N / 2});
      return rung;
    }
    const double T = problem.duration;
    // C(N) ≈ C* + a N^−p  ⇒  C(N) − C* ≈ (C(N) − C(N/2)) / (2^p − 1)
    rung.error =
        std::abs(T / N * rung.plan.cost - T / (N / 2) * half.cost) / (std::pow(2.0, order) - 1.0);
  }
  return rung;
}

/// N ≈ N_0 (e_0/target)^{1/p} with a 15 % margin, even, at least 16.
int predictSteps(int N0, double error0, double target, double order) {
  const double N = 1.15 * N0 * std::pow(std::max(error0, 1e-300) / target, 1.0 / order);
  const double even = 2.0 * std::ceil(std::min(N, 1e9) / 2.0);
  return static_cast<int>(std::max(16.0, even));
}

// Coarse resolution of each candidate scheme (N = kCoarse; its estimate uses N/2 too).
constexpr int kCoarse = 64;

/// The scheme whose predicted N costs the least work, with its coarse plan; `failed` when a
/// coarse plan did not converge (that plan, its message saying so, in `coarse`).
struct SchemeChoice {
  int N = 0;
  SchemeKind scheme = SchemeKind::Paper;
  Rung coarse;
  bool failed = false;
};

SchemeChoice chooseScheme(const PlanningProblem& problem, SolveContext& context,
                          AccuracyEstimate* estimate) {
  const AccuracyTarget& target = problem.accuracy;
  std::vector<SchemeKind> schemes = {problem.scheme};
  if (target.choose_scheme) {
    schemes = {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder,
               SchemeKind::FourthOrder};
  }
  SchemeChoice best;
  best.scheme = problem.scheme;
  double best_work = 0.0;
  for (SchemeKind scheme : schemes) {
    PlanningProblem candidate = problem;
    candidate.scheme = scheme;
    const double p = assumedOrder(problem, scheme, target.measure);
    Rung coarse = solveRung(candidate, kCoarse, context, p);
    estimate->steps_tried.push_back(kCoarse);
    estimate->errors_tried.push_back(coarse.error);
    estimate->schemes_tried.push_back(schemeName(scheme));
    if (!coarse.plan.converged()) {
      frameMessage(&coarse.plan, frames::CoarseResolutionStopped{schemeName(scheme)});
      SchemeChoice failed;
      failed.coarse = coarse;
      failed.failed = true;
      return failed;
    }
    const int N = predictSteps(kCoarse, coarse.error, target.value, p);
    // The work of a plan is O(N) per solve; fourth_order solves second_order at N and 2N.
    const double work = scheme == SchemeKind::FourthOrder ? 3.0 * N : double(N);
    if (best.N == 0 || work < best_work) {
      best.N = N;
      best_work = work;
      best.scheme = scheme;
      best.coarse = coarse;
    }
  }
  return best;
}

}  // namespace

PlanResult planToAccuracy(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  const auto start = std::chrono::steady_clock::now();
  const AccuracyTarget& target = problem.accuracy;
  AccuracyEstimate estimate;
  estimate.requested = true;
  estimate.measure = target.measure;
  estimate.target = target.value;
  estimate.method = target.measure == AccuracyMeasure::TerminalMiss
                        ? "zero-order-hold replay of the plan (measured)"
                        : "Richardson: |hC(N) - h'C(N/2)| / (2^p - 1)";
  const auto finish = [&](PlanResult result) {
    result.accuracy = estimate;
    result.solve_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  // One request for all resolutions: one time budget (each solve gets what is left of it, and
  // ends TimedOut when nothing is), one iteration numbering, one cancel flag.
  SolveContext context(options);
  const SchemeChoice choice = chooseScheme(problem, context, &estimate);
  if (choice.failed) return finish(choice.coarse.plan);
  const int best_N = choice.N;
  const SchemeKind best_scheme = choice.scheme;
  const Rung& best_coarse = choice.coarse;
  PlanningProblem chosen = problem;
  chosen.scheme = best_scheme;
  estimate.order = assumedOrder(problem, best_scheme, target.measure);
  estimate.predicted_error = best_coarse.error * std::pow(double(kCoarse) / best_N, estimate.order);

  int N = best_N;
  Rung last = best_coarse;
  for (int round = 0; round < 4; ++round) {
    if (N > target.max_steps) {
      // The finest plan solved so far, with its own estimate.
      estimate.estimated_error = last.error;
      PlanResult failed = last.plan;
      failed.termination = Termination::NotConverged;
      frameMessage(&failed,
                   frames::AccuracyNeedsSteps{target.value, accuracyMeasureName(target.measure), N,
                                              target.max_steps});
      return finish(failed);
    }
    Rung rung = solveRung(chosen, N, context, estimate.order);
    estimate.steps_tried.push_back(N);
    estimate.errors_tried.push_back(rung.error);
    estimate.schemes_tried.push_back(schemeName(best_scheme));
    if (!rung.plan.converged()) return finish(rung.plan);
    estimate.estimated_error = rung.error;
    last = rung;
    if (rung.error <= target.value) {
      addNote(&rung.plan, notes::AccuracyReached{accuracyMeasureName(target.measure), rung.error,
                                                 target.value, N, schemeName(best_scheme)});
      return finish(rung.plan);
    }
    const int next = predictSteps(N, rung.error, target.value, estimate.order);
    estimate.predicted_error = rung.error * std::pow(double(N) / next, estimate.order);
    if (round == 3) {
      rung.plan.termination = Termination::NotConverged;
      frameMessage(&rung.plan, frames::AccuracyNotReached{accuracyMeasureName(target.measure),
                                                          rung.error, target.value, N});
      return finish(rung.plan);
    }
    N = std::max(next, N + 2);
  }
  return finish(best_coarse.plan);  // not reached
}

}  // namespace attitude_planner
