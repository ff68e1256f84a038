// Independent cross-check of the Newton solver: NLopt's SLSQP on the direct method
// (direct_method.hpp). Shares nothing with newton_solver.cpp but the dynamics (simulate) and the
// final replay (evaluatePlan), so agreement of the two is evidence that both are right.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlopt.hpp>
#include <string>

#include "attitude_planner/errors.hpp"
#include "planning/direct_method.hpp"
#include "planning/solvers.hpp"

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
  info.gradient_norm = std::max(c.value.cwiseAbs().maxCoeff(),
                                stationarityResidual(x, c.jacobian).cwiseAbs().maxCoeff());
  cb->history.push_back(info);
  if (cb->options->on_iteration && !cb->options->on_iteration(info)) {
    cb->stop_reason = "cancelled";
    cb->opt->force_stop();
  }
}

}  // namespace

PlanResult solveWithNlopt(const PlanningProblem& problem, const SolverOptions& options) {
  if (problem.effects && !problem.effects->empty()) {
    PlanResult refused;
    refused.message =
        "solver nlopt: planning with effects is implemented in the newton solver only (its "
        "constraint Jacobians do not include effect torques); use --solver newton";
    return refused;
  }
  const int N = problem.steps;
  if (N > kMaxNloptSteps) {
    PlanResult refused;
    refused.solver = solverName(SolverKind::Nlopt);
    refused.scheme = problem.scheme;
    refused.message =
        "not converged; nlopt cross-check is dense (O(N^2) memory, O(N^3) time): "
        "steps " +
        std::to_string(N) + " > " + std::to_string(kMaxNloptSteps) +
        " refused; use the newton solver";
    return refused;
  }
  const unsigned n = 3u * static_cast<unsigned>(N - 1);

  // Initial guess: zero torques (SLSQP's first QP is then the linearized minimum-norm transfer),
  // or the warm start's torques when it has the same N.
  std::vector<double> x(n, 0.0);
  if (options.warm_start && options.warm_start->steps() == N &&
      static_cast<int>(options.warm_start->torque.size()) == N + 1) {
    const Eigen::VectorXd w = unknownsFromTorqueSequence(options.warm_start->torque);
    for (unsigned i = 0; i < n; ++i) x[i] = w(i);
  }

  nlopt::opt opt(nlopt::LD_SLSQP, n);
  Callbacks cb;
  cb.problem = &problem;
  cb.options = &options;
  cb.opt = &opt;
  opt.set_min_objective(objective, nullptr);
  opt.add_equality_mconstraint(
      constraints, &cb, std::vector<double>(kTerminalConstraints, kNloptConstraintTolerance));
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

  nlopt::result code = nlopt::FAILURE;
  std::string exception_text;
  double f = 0.0;
  try {
    code = opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
    code = nlopt::ROUNDOFF_LIMITED;
  } catch (const nlopt::forced_stop&) {
    code = nlopt::FORCED_STOP;
  } catch (const std::exception& e) {
    code = nlopt::FAILURE;
    exception_text = e.what();
  }

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
        "nlopt: " + resultName(code) + "; final torques cannot be replayed: " + e.what();
    return result;
  }

  // The optimality residual measured here, not NLopt's word: constraint violation and the part of
  // the cost gradient outside the span of the constraint gradients (relative to |∇f| = |τ|).
  const TerminalConstraints c = evaluateTerminalConstraints(problem, xv, true);
  const double violation = c.value.cwiseAbs().maxCoeff();
  // With bounds, stationarity holds on the free variables only (bound multipliers take the rest).
  std::vector<int> free;
  for (int i = 0; i < static_cast<int>(n); ++i) {
    if (!problem.hasTorqueBounds() || std::abs(xv(i)) < problem.max_torque(i % 3) * (1.0 - 1e-9)) {
      free.push_back(i);
    }
  }
  Eigen::VectorXd x_free(free.size());
  Eigen::MatrixXd jacobian_free(c.jacobian.rows(), free.size());
  for (size_t j = 0; j < free.size(); ++j) {
    x_free(j) = xv(free[j]);
    jacobian_free.col(j) = c.jacobian.col(free[j]);
  }
  const double stationarity =
      free.empty() ? 0.0
                   : stationarityResidual(x_free, jacobian_free).cwiseAbs().maxCoeff() /
                         std::max(xv.cwiseAbs().maxCoeff(), 1e-300);
  result.max_residual = std::max(violation, stationarity);

  const bool nlopt_success =
      code > 0 && code != nlopt::MAXEVAL_REACHED && code != nlopt::MAXTIME_REACHED;
  const bool feasible = result.terminal_attitude_error <= kConstraintTolerance &&
                        result.terminal_velocity_error <= kConstraintTolerance;
  if (cb.stop_reason == "cancelled") {
    result.termination = Termination::Cancelled;
  } else if (nlopt_success && feasible) {
    result.termination = Termination::Converged;
  } else if (code == nlopt::MAXTIME_REACHED) {
    result.termination = Termination::TimedOut;
  } else {
    result.termination = Termination::NotConverged;
  }
  std::string message = "nlopt SLSQP: " + resultName(code);
  if (!cb.stop_reason.empty()) message += " (" + cb.stop_reason + ")";
  if (!exception_text.empty()) message += " (" + exception_text + ")";
  char figures[160];
  std::snprintf(figures, sizeof figures,
                "; constraint violation %.3g, relative stationarity residual %.3g", violation,
                stationarity);
  message += figures;
  if (!result.converged() && nlopt_success && !feasible)
    message += "; terminal constraints not met";
  if (cb.stop_reason == "cancelled") message = "cancelled; " + message;
  result.message = (result.converged() ? "converged; " : "not converged; ") + message;
  return result;
}

}  // namespace attitude_planner
