// Independent cross-check of the Newton solver: NLopt's SLSQP on the direct method
// (direct_method.hpp). Shares nothing with newton_solver.cpp but the dynamics (simulate) and the
// final replay (evaluatePlan), so agreement of the two is evidence that both are right.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlopt.hpp>
#include <sstream>
#include <string>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "planning/crosscheck/nlopt_solver.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/direct_method.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

namespace {

/// Terminal errors [rad], [rad/s] below which the constraints count as met.
constexpr double kConstraintTolerance = 1e-10;
/// Per-constraint tolerance handed to SLSQP [rad], [rad/s]: tighter than kConstraintTolerance so
/// that a "success" return leaves margin.
constexpr double kNloptConstraintTolerance = 1e-13;

/// Largest N the cross-check accepts: SLSQP is dense (O(n²) memory, O(n³) time per iteration in
/// n = 3(N − 1) unknowns), ~3.4 s at N = 128 here; N = 1024 already needs ~100 MB and hours.
constexpr int kMaxNloptSteps = 1024;

/// Constraint value [rad], [rad/s] reported for a trial point whose simulation fails: far larger
/// than any real miss (≤ π rad), finite so that SLSQP's merit function stays meaningful.
constexpr double kFailedSimulationMiss = 1e3;
/// Failed trial simulations tolerated before the solve is abandoned.
constexpr int kMaxFailedSimulations = 50;

std::string resultName(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "NLOPT_SUCCESS";
    case nlopt::STOPVAL_REACHED:
      return "NLOPT_STOPVAL_REACHED";
    case nlopt::FTOL_REACHED:
      return "NLOPT_FTOL_REACHED";
    case nlopt::XTOL_REACHED:
      return "NLOPT_XTOL_REACHED";
    case nlopt::MAXEVAL_REACHED:
      return "NLOPT_MAXEVAL_REACHED";
    case nlopt::MAXTIME_REACHED:
      return "NLOPT_MAXTIME_REACHED";
    case nlopt::FAILURE:
      return "NLOPT_FAILURE";
    case nlopt::INVALID_ARGS:
      return "NLOPT_INVALID_ARGS";
    case nlopt::OUT_OF_MEMORY:
      return "NLOPT_OUT_OF_MEMORY";
    case nlopt::ROUNDOFF_LIMITED:
      return "NLOPT_ROUNDOFF_LIMITED";
    case nlopt::FORCED_STOP:
      return "NLOPT_FORCED_STOP";
    default:
      break;
  }
  return "NLOPT_UNKNOWN(" + std::to_string(static_cast<int>(r)) + ")";
}

/// The node constraints of PlanningProblem::constraints (the stage constraints that are not a
/// side of the actuator box, which are bounds on x here) as NLopt inequalities on the torques
/// x = (τ_1..τ_{N−1}): each row g(r) ≤ upper as g − upper ≤ 0, or lower − g ≤ 0
/// (stage_constraints.hpp, dimensionless), r = τ_k (k = 1..N−1), Ω_k (k = 1..N−2; Ω_0, Ω_{N−1} are
/// fixed by the boundary data) or sᵀR_k b (k = 1..N). Exact Jacobian by forward sensitivities of
/// the simulation, O(N²) (direct_method.hpp: δF_k = dμ(F_k)⁻¹(dG(F_{k−1}) δF_{k−1} + h δτ_k),
/// δθ_{k+1} = F_kᵀ δθ_k + δF_k): independent of the interior-point solver's derivatives.
struct NodeRows {
  const PlanningProblem* problem = nullptr;
  StageConstraints rows;  ///< the stage constraints that are rows (not box sides)
};

/// The instances of a quantity as rows of this transcription (its unknowns are the torques).
StageSupport rowRange(StageQuantity quantity, int N) {
  switch (quantity) {
    case StageQuantity::Torque:
      return {1, N - 1, 0, 1};
    case StageQuantity::StepRate:
      return {1, N - 2, 0, 1};
    case StageQuantity::Pointing:
      return {1, N, 0, 1};
    case StageQuantity::NodeRate:  // schemes with end torques are refused (plan_at_resolution)
      break;
    case StageQuantity::WheelMomentum:
    case StageQuantity::WheelTorque:
      throw InvalidInput("solver", "nlopt: reaction wheels are planned by solver newton only");
  }
  throw InvalidInput("scheme", "nlopt: the direct method has no node rates (no end torques)");
}

int nodeInequalityCount(const NodeRows& rows) {
  int m = 0;
  for (const auto& c : rows.rows) {
    const StageSupport s = rowRange(c->quantity(), rows.problem->steps);
    m += s.last_k - s.first_k + 1;
  }
  return m;
}

/// +1 for a row with a finite upper side (g − upper ≤ 0), −1 for a lower one (lower − g ≤ 0).
double rowSign(const StageConstraint& c) {
  return std::isfinite(c.rowUpper()) ? 1.0 : -1.0;
}

/// The row g − upper (or lower − g) of `c` at its quantity r.
double rowExcess(const StageConstraint& c, const Vector3& r) {
  return std::isfinite(c.rowUpper()) ? c.rowValue(r) - c.rowUpper() : c.rowLower() - c.rowValue(r);
}

/// One node inequality: its node and the 1×3 derivative of its row w.r.t. τ_k (torque), F_k (step
/// rate) or θ_k (cone).
struct NodeRow {
  int k;
  bool on_step;  // rate: depends on F_k; cone: on θ_k; torque: on τ_k only
  bool torque;
  Eigen::RowVector3d d;
};

/// The node inequalities' values (into `result`) and derivatives in their quantities, on the
/// simulated attitudes R_k and steps F_k.
std::vector<NodeRow> nodeRowValues(const NodeRows& node_rows, const DiscreteScheme& scheme,
                                   const std::vector<Vector3>& torque,
                                   const std::vector<Matrix3>& R, const std::vector<Matrix3>& F,
                                   double* result) {
  const PlanningProblem& problem = *node_rows.problem;
  const int N = problem.steps;
  const double h = problem.duration / N;
  std::vector<NodeRow> rows;
  unsigned i = 0;
  for (const auto& c : node_rows.rows) {
    const StageSupport s = rowRange(c->quantity(), N);
    const double sign = rowSign(*c);
    for (int k = s.first_k; k <= s.last_k; ++k, ++i) {
      switch (c->quantity()) {
        case StageQuantity::Torque: {
          result[i] = rowExcess(*c, torque[k]);
          rows.push_back({k, false, true, sign * c->rowGradient(torque[k]).transpose()});
          break;
        }
        case StageQuantity::StepRate: {
          const Vector3 Omega = scheme.velocity(F[k]);
          result[i] = rowExcess(*c, Omega);
          const Matrix3 V =
              problem.scheme == SchemeKind::Paper
                  ? Matrix3(so3::rightJacobianInverse(so3::log(F[k])) / h)
                  : Matrix3(problem.inertia.inverse() * scheme.momentumJacobian<double>(F[k]));
          rows.push_back({k, true, false, sign * c->rowGradient(Omega).transpose() * V});
          break;
        }
        case StageQuantity::Pointing: {  // p = sᵀR_k b = vᵀb, v = R_kᵀ s; ∂p/∂θ_k = (b × v)ᵀ
          const Vector3& b = c->spec()->body_axis;
          const Vector3 v = R[k].transpose() * c->spec()->world_direction;
          const Vector3 p(v.dot(b), 0.0, 0.0);
          result[i] = rowExcess(*c, p);
          rows.push_back({k, false, false, sign * c->rowGradient(p)(0) * b.cross(v).transpose()});
          break;
        }
        case StageQuantity::NodeRate:
        case StageQuantity::WheelMomentum:
        case StageQuantity::WheelTorque:
          break;  // refused by rowRange
      }
    }
  }
  return rows;
}

void nodeInequalities(unsigned m, double* result, unsigned n, const double* x_raw, double* grad,
                      void* data) {
  const NodeRows& node_rows = *static_cast<const NodeRows*>(data);
  const PlanningProblem& problem = *node_rows.problem;
  const int N = problem.steps;
  const double h = problem.duration / N;
  const DiscreteScheme scheme(problem.scheme, problem.inertia, h);
  const Eigen::Map<const Eigen::VectorXd> x(x_raw, n);
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = torqueSequenceFromUnknowns(x);
  Maneuver trajectory;
  try {
    trajectory = simulate(scheme, input);
  } catch (const StepTooLarge&) {
    for (unsigned i = 0; i < m; ++i) result[i] = kFailedSimulationMiss;
    if (grad) std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);
    return;
  }
  const std::vector<Matrix3>& R = trajectory.attitude;
  std::vector<Matrix3> F(N);
  for (int k = 0; k < N; ++k) F[k] = R[k].transpose() * R[k + 1];
  // Sensitivities for one torque τ_j: X_k = ∂F_k/∂τ_j, Θ_k = ∂θ_k/∂τ_j (3×3 each).
  std::vector<Matrix3> dmu_inverse(N), carried(N);
  if (grad) {
    std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);
    for (int k = 0; k < N; ++k) {
      dmu_inverse[k] = scheme.momentumJacobian<double>(F[k]).inverse();
      carried[k] = carriedMomentumJacobian(scheme, F[k]);
    }
  }
  std::vector<Matrix3> X(N, Matrix3::Zero()), Theta(N + 1, Matrix3::Zero());
  const auto sensitivities = [&](int j) {
    std::fill(X.begin(), X.end(), Matrix3::Zero());
    std::fill(Theta.begin(), Theta.end(), Matrix3::Zero());
    X[j] = h * dmu_inverse[j];
    Theta[j + 1] = X[j];
    for (int k = j + 1; k < N; ++k) {
      X[k] = dmu_inverse[k] * carried[k - 1] * X[k - 1];
      Theta[k + 1] = F[k].transpose() * Theta[k] + X[k];
    }
  };
  const std::vector<NodeRow> rows = nodeRowValues(node_rows, scheme, input.torque, R, F, result);
  if (!grad) return;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> G(grad, m, n);
  for (const NodeRow& r : rows) {
    if (r.torque) G.block<1, 3>(&r - rows.data(), 3 * (r.k - 1)) = r.d;
  }
  for (int j = 1; j <= N - 1; ++j) {
    sensitivities(j);
    for (std::size_t row = 0; row < rows.size(); ++row) {
      const NodeRow& r = rows[row];
      if (r.torque) continue;
      G.block<1, 3>(row, 3 * (j - 1)) =
          r.on_step ? Eigen::RowVector3d(r.d * X[r.k]) : Eigen::RowVector3d(r.d * Theta[r.k]);
    }
  }
}

/// State shared with the NLopt callbacks.
struct Callbacks {
  const PlanningProblem* problem = nullptr;
  const SolverOptions* options = nullptr;
  nlopt::opt* opt = nullptr;
  NodeRows node_rows;  ///< the node inequalities' constraints (pointing into *problem)
  std::vector<IterationInfo> history;
  std::string stop_reason;     ///< set when a callback forces a stop
  int evaluations = 0;         ///< constraint Jacobian evaluations (one per SLSQP iterate)
  int failed_simulations = 0;  ///< trials whose simulation failed (StepTooLarge)
};

double objective(unsigned n, const double* x, double* grad, void*) {
  double f = 0.0;
  for (unsigned i = 0; i < n; ++i) {
    f += 0.5 * x[i] * x[i];
    if (grad) grad[i] = x[i];
  }
  return f;
}

void constraints(unsigned m, double* result, unsigned n, const double* x_raw, double* grad,
                 void* data) {
  auto* cb = static_cast<Callbacks*>(data);
  const Eigen::Map<const Eigen::VectorXd> x(x_raw, n);
  TerminalConstraints c;
  try {
    c = evaluateTerminalConstraints(*cb->problem, x, grad != nullptr);
  } catch (const StepTooLarge& e) {
    // SLSQP's line search tried torques so large that an implicit step has no solution. Report a
    // large miss with a zero gradient so that the merit function rejects the trial and the line
    // search backtracks; give up only if that keeps happening.
    if (++cb->failed_simulations > kMaxFailedSimulations) {
      cb->stop_reason = std::string("trial torques made the simulation fail: ") + e.what();
      cb->opt->force_stop();
    }
    for (unsigned i = 0; i < m; ++i) result[i] = kFailedSimulationMiss;
    if (grad) std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);
    return;
  }
  for (unsigned i = 0; i < m; ++i) result[i] = c.value(i);
  if (!grad) return;
  // NLopt wants grad[i*n + j] = ∂c_i/∂x_j: row-major.
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(grad, m, n) =
      c.jacobian;

  IterationInfo info;
  info.iteration = ++cb->evaluations;
  info.cost = 0.5 * x.squaredNorm();
  info.steps = cb->problem->steps;
  info.effort = info.cost * cb->problem->duration / cb->problem->steps;
  info.gradient_norm = std::max(c.value.cwiseAbs().maxCoeff(),
                                stationarityResidual(x, c.jacobian).cwiseAbs().maxCoeff());
  cb->history.push_back(info);
  if (cb->options->on_iteration && !cb->options->on_iteration(info)) {
    cb->stop_reason = "cancelled";
    cb->opt->force_stop();
  }
}

}  // namespace

namespace {

// Initial guess: zero torques (SLSQP's first QP is then the linearized minimum-norm transfer),
// or the warm start's torques when it has the same N.
std::vector<double> initialUnknowns(const PlanningProblem& problem, const SolverOptions& options,
                                    unsigned n) {
  const int N = problem.steps;
  std::vector<double> x(n, 0.0);
  if (options.warm_start && options.warm_start->steps() == N &&
      static_cast<int>(options.warm_start->torque.size()) == N + 1) {
    const Eigen::VectorXd w = unknownsFromTorqueSequence(options.warm_start->torque);
    for (unsigned i = 0; i < n; ++i) x[i] = w(i);
  }
  return x;
}

// Objective, constraints, bounds (x clipped into them) and stopping rules of the SLSQP run.
void configure(nlopt::opt& opt, Callbacks& cb, const PlanningProblem& problem,
               const SolverOptions& options, std::vector<double>& x) {
  const unsigned n = static_cast<unsigned>(x.size());
  opt.set_min_objective(objective, nullptr);
  opt.add_equality_mconstraint(
      constraints, &cb, std::vector<double>(kTerminalConstraints, kNloptConstraintTolerance));
  // Box sides are bounds on the torque unknowns; every other stage constraint is a row.
  Vector3 lower_bound = Vector3::Constant(-HUGE_VAL), upper_bound = Vector3::Constant(HUGE_VAL);
  bool bounded = false;
  cb.node_rows.problem = &problem;
  for (auto& c : buildStageConstraints(problem)) {
    if (c->axis() < 0) {
      cb.node_rows.rows.push_back(std::move(c));
      continue;
    }
    bounded = true;
    lower_bound(c->axis()) = std::max(lower_bound(c->axis()), c->rowLower());
    upper_bound(c->axis()) = std::min(upper_bound(c->axis()), c->rowUpper());
  }
  if (!cb.node_rows.rows.empty()) {
    const int m = nodeInequalityCount(cb.node_rows);
    opt.add_inequality_mconstraint(nodeInequalities, &cb.node_rows,
                                   std::vector<double>(m, kNloptConstraintTolerance));
  }
  if (bounded) {
    std::vector<double> lower(n), upper(n);
    for (unsigned i = 0; i < n; ++i) {
      upper[i] = upper_bound(i % 3);
      lower[i] = lower_bound(i % 3);
      x[i] = std::min(std::max(x[i], lower[i]), upper[i]);
    }
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
  }
  opt.set_xtol_rel(1e-14);
  opt.set_ftol_rel(1e-15);
  opt.set_maxeval(std::max(options.max_iterations, 1));
  if (options.time_budget_s > 0.0) opt.set_maxtime(options.time_budget_s);
}

// NLopt's result code; its exceptions for a stop are codes too, any other's text goes to
// *exception_text.
nlopt::result optimize(nlopt::opt& opt, std::vector<double>& x, std::string* exception_text) {
  double f = 0.0;
  try {
    return opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
    return nlopt::ROUNDOFF_LIMITED;
  } catch (const nlopt::forced_stop&) {
    return nlopt::FORCED_STOP;
  } catch (const std::exception& e) {
    *exception_text = e.what();
    return nlopt::FAILURE;
  }
}

// The relative stationarity residual at x, measured here, not NLopt's word: the part of the
// cost gradient outside the span of the constraint gradients (relative to |∇f| = |τ|).
double relativeStationarity(const PlanningProblem& problem, const Eigen::VectorXd& xv,
                            const Eigen::MatrixXd& jacobian) {
  // With bounds, stationarity holds on the free variables only (bound multipliers take the rest).
  std::vector<int> free;
  for (int i = 0; i < static_cast<int>(xv.size()); ++i) {
    if (!problem.hasTorqueBounds() || std::abs(xv(i)) < problem.max_torque(i % 3) * (1.0 - 1e-9)) {
      free.push_back(i);
    }
  }
  Eigen::VectorXd x_free(free.size());
  Eigen::MatrixXd jacobian_free(jacobian.rows(), free.size());
  for (size_t j = 0; j < free.size(); ++j) {
    x_free(j) = xv(free[j]);
    jacobian_free.col(j) = jacobian.col(free[j]);
  }
  // With node constraints beyond the bounds their multipliers are not recovered here: the
  // stationarity residual is then not measured (0), the violation still is.
  return free.empty() || !problem.constraints.empty()
             ? 0.0
             : stationarityResidual(x_free, jacobian_free).cwiseAbs().maxCoeff() /
                   std::max(xv.cwiseAbs().maxCoeff(), 1e-300);
}

// How the run ended, from NLopt's code, the callbacks' stop reason and the replayed plan.
struct Outcome {
  nlopt::result code = nlopt::FAILURE;
  std::string stop_reason;
  std::string exception_text;
  double violation = 0.0;
  double stationarity = 0.0;
};

void setTermination(const Outcome& o, PlanResult* result) {
  const bool nlopt_success =
      o.code > 0 && o.code != nlopt::MAXEVAL_REACHED && o.code != nlopt::MAXTIME_REACHED;
  const bool feasible = result->terminal_attitude_error <= kConstraintTolerance &&
                        result->terminal_velocity_error <= kConstraintTolerance;
  if (o.stop_reason == "cancelled") {
    result->termination = Termination::Cancelled;
  } else if (nlopt_success && feasible) {
    result->termination = Termination::Converged;
  } else if (o.code == nlopt::MAXTIME_REACHED) {
    result->termination = Termination::TimedOut;
  } else {
    result->termination = Termination::NotConverged;
  }
  recordVerdict(result, verdicts::NloptEnded{resultName(o.code), o.stop_reason, o.exception_text,
                                             result->converged(),
                                             !result->converged() && nlopt_success && !feasible,
                                             o.violation, o.stationarity});
}

}  // namespace

PlanResult solveWithNlopt(const PlanningProblem& problem, const SolverOptions& options) {
  if (problem.effects && !problem.effects->empty()) {  // a refusal of the request, as below
    throw InvalidInput("solver",
                       "nlopt: planning with effects is implemented in the newton solver only "
                       "(its constraint Jacobians do not include effect torques); use --solver "
                       "newton");
  }
  const int N = problem.steps;
  if (N > kMaxNloptSteps) {  // a refusal of the request, not a solve that failed to converge
    throw InvalidInput("steps", std::to_string(N) + " > " + std::to_string(kMaxNloptSteps) +
                                    " is refused by solver nlopt (the cross-check is dense: "
                                    "O(N^2) memory, O(N^3) time); use the newton solver");
  }
  const unsigned n = 3u * static_cast<unsigned>(N - 1);
  std::vector<double> x = initialUnknowns(problem, options, n);
  nlopt::opt opt(nlopt::LD_SLSQP, n);
  Callbacks cb;
  cb.problem = &problem;
  cb.options = &options;
  cb.opt = &opt;
  configure(opt, cb, problem, options, x);
  Outcome outcome;
  outcome.code = optimize(opt, x, &outcome.exception_text);
  outcome.stop_reason = cb.stop_reason;

  PlanResult result;
  result.solver = solverName(SolverKind::Nlopt);
  result.iterations = cb.evaluations;
  result.history = std::move(cb.history);
  const Eigen::Map<const Eigen::VectorXd> xv(x.data(), n);
  const std::vector<Vector3> torque = torqueSequenceFromUnknowns(xv);
  try {
    evaluatePlan(problem, torque, &result);
  } catch (const StepTooLarge& e) {
    result.termination = Termination::StepTooLarge;
    recordReason(&result, "nlopt: " + resultName(outcome.code) +
                              "; final torques cannot be replayed: " + e.what());
    return result;
  }
  const TerminalConstraints c = evaluateTerminalConstraints(problem, xv, true);
  outcome.violation = c.value.cwiseAbs().maxCoeff();
  outcome.stationarity = relativeStationarity(problem, xv, c.jacobian);
  result.max_residual = std::max(outcome.violation, outcome.stationarity);
  setTermination(outcome, &result);
  return result;
}

}  // namespace attitude_planner
