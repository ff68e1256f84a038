// Independent cross-check of the Newton solver: NLopt's SLSQP on the direct method
// (direct_method.hpp). Shares nothing with newton_solver.cpp but the dynamics (simulate) and the
// final replay (evaluatePlan), so agreement of the two is evidence that both are right.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlopt.hpp>
#include <string>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "planning/crosscheck/nlopt_solver.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/direct_method.hpp"

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

/// The node constraints of PlanningProblem::constraints as NLopt inequalities h(x) ≤ 0 on the
/// torques x = (τ_1..τ_{N−1}), each dimensionless: |τ_k|²/t² − 1, |Ω_k|²/w² − 1 (k = 1..N−2),
/// ±(sᵀR_k b − cos α) (k = 1..N). Exact Jacobian by forward sensitivities of the simulation,
/// O(N²) (direct_method.hpp: δF_k = dμ(F_k)⁻¹(dG(F_{k−1}) δF_{k−1} + h δτ_k),
/// δθ_{k+1} = F_kᵀ δθ_k + δF_k): independent of the interior-point solver's derivatives.
int nodeInequalityCount(const PlanningProblem& problem) {
  const int N = problem.steps;
  int m = 0;
  for (const PlanningConstraint& c : problem.constraints) {
    m += c.kind == ConstraintKind::MaxTorqueNorm    ? N - 1
         : c.kind == ConstraintKind::MaxAngularRate ? N - 2
                                                    : N;
  }
  return m;
}

void nodeInequalities(unsigned m, double* result, unsigned n, const double* x_raw, double* grad,
                      void* data) {
  const PlanningProblem& problem = *static_cast<const PlanningProblem*>(data);
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
  // Rows: value and, per row, the 1×3 derivative of its quantity w.r.t. F_k (rate) or θ_k (cone).
  struct Row {
    int k;
    bool on_step;  // rate: depends on F_k; cone: on θ_k; norm: on τ_k only
    bool torque;
    Eigen::RowVector3d d;
  };
  std::vector<Row> rows;
  unsigned i = 0;
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind == ConstraintKind::MaxTorqueNorm) {
      for (int k = 1; k <= N - 1; ++k, ++i) {
        result[i] = input.torque[k].squaredNorm() / (c.limit * c.limit) - 1.0;
        rows.push_back({k, false, true, 2.0 * input.torque[k].transpose() / (c.limit * c.limit)});
      }
    } else if (c.kind == ConstraintKind::MaxAngularRate) {
      for (int k = 1; k <= N - 2; ++k, ++i) {
        const Vector3 Omega = scheme.velocity(F[k]);
        result[i] = Omega.squaredNorm() / (c.limit * c.limit) - 1.0;
        const Matrix3 V =
            problem.scheme == SchemeKind::Paper
                ? Matrix3(so3::rightJacobianInverse(so3::log(F[k])) / h)
                : Matrix3(problem.inertia.inverse() * scheme.momentumJacobian<double>(F[k]));
        rows.push_back({k, true, false, 2.0 * Omega.transpose() * V / (c.limit * c.limit)});
      }
    } else {
      const double sign = c.kind == ConstraintKind::KeepOut ? 1.0 : -1.0;
      for (int k = 1; k <= N; ++k, ++i) {
        const Vector3 v = R[k].transpose() * c.world_direction;
        result[i] = sign * (v.dot(c.body_axis) - std::cos(c.nodeHalfAngle()));
        rows.push_back({k, false, false, sign * c.body_axis.cross(v).transpose()});
      }
    }
  }
  if (!grad) return;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> G(grad, m, n);
  for (const Row& r : rows) {
    if (r.torque) G.block<1, 3>(&r - rows.data(), 3 * (r.k - 1)) = r.d;
  }
  for (int j = 1; j <= N - 1; ++j) {
    sensitivities(j);
    for (std::size_t row = 0; row < rows.size(); ++row) {
      const Row& r = rows[row];
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
  if (!problem.constraints.empty()) {
    const int m = nodeInequalityCount(problem);
    opt.add_inequality_mconstraint(nodeInequalities, const_cast<PlanningProblem*>(&problem),
                                   std::vector<double>(m, kNloptConstraintTolerance));
  }
  if (problem.hasTorqueBounds()) {
    std::vector<double> lower(n), upper(n);
    for (unsigned i = 0; i < n; ++i) {
      upper[i] = problem.max_torque(i % 3);
      lower[i] = -upper[i];
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
  std::string message = "nlopt SLSQP: " + resultName(o.code);
  if (!o.stop_reason.empty()) message += " (" + o.stop_reason + ")";
  if (!o.exception_text.empty()) message += " (" + o.exception_text + ")";
  char figures[160];
  std::snprintf(figures, sizeof figures,
                "; constraint violation %.3g, relative stationarity residual %.3g", o.violation,
                o.stationarity);
  message += figures;
  if (!result->converged() && nlopt_success && !feasible)
    message += "; terminal constraints not met";
  if (o.stop_reason == "cancelled") message = "cancelled; " + message;
  result->message = (result->converged() ? "converged; " : "not converged; ") + message;
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
    result.message =
        "nlopt: " + resultName(outcome.code) + "; final torques cannot be replayed: " + e.what();
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
