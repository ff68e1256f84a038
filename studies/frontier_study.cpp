// frontier_study: the accuracy-versus-solve-time frontier. For each scene, solves the
// continuous reference (continuous_reference.hpp), then, side by side in one process,
//   ours      planManeuver (Newton) with every scheme of the scheme name table (kSchemeNames) at
//             N = 8, 16, ..., --max-steps;
//   ipopt_hs  IPOPT on Hermite–Simpson collocation of the continuous problem (separated form,
//             quaternion states, exact sparse Jacobian and Hessian:
//             test/support/hermite_simpson.hpp) at N = 4, 6, 8, 12, ... mesh intervals,
// all cold (from the geodesic), solve time the median of --repeats runs, and records the
// relative torque error at the mesh nodes, the relative effort error and the solve time. Writes
// one JSON object (raw data for scripts/plot_frontier.py, which writes docs/results/frontier.md and
// docs/results/frontier.png).
//
// Accuracy (the same for every method): with τ(t) the continuous optimum and
// τ_max = max_t |τ(t)| (sampled at 4001 points),
//   torque error  max_k |τ_k − τ(t_k)| / τ_max over the mesh nodes t_k = kT/N at which the method
//                 has a torque (paper, variational: k = 1..N−1, their τ_0 = τ_N are not
//                 unknowns; second_order and ipopt_hs: k = 0..N); ipopt_hs's midpoints are
//                 reported separately (torque_error_midpoints);
//   effort error  |E − E*| / E*, E the method's own quadrature of ½∫|τ|²dt (ours: PlanResult::
//                 effort; ipopt_hs: its Simpson objective), E* the reference's.
//
// usage: frontier_study OUT.json SCENE.yaml... [--repeats K] [--max-steps N] [--max-hs-steps N]
//                       [--time-limit S] [--ipopt-tol TOL] [--ipopt-print LEVEL]
//                       [--tolerance TOL] [--only METHOD]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "attitude_planner/analysis/continuous_reference.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planner.hpp"
#include "support/hermite_simpson.hpp"
#include "support/study_tools.hpp"

#ifdef AP_HAVE_IPOPT
#include <coin/IpoptConfig.h>
#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>
#endif

using namespace attitude_planner;

namespace {

using attitude_planner::study::loadAverage;
using attitude_planner::study::median;
using attitude_planner::study::seconds;

std::string sceneName(const std::string& path) {
  std::string base = path.substr(path.find_last_of('/') + 1);
  return base.substr(0, base.find('.'));
}

std::string timesJson(const std::vector<double>& times) {
  std::string s = "[";
  char buffer[32];
  for (size_t i = 0; i < times.size(); ++i) {
    std::snprintf(buffer, sizeof buffer, "%s%.6g", i ? ", " : "", times[i]);
    s += buffer;
  }
  return s + "]";
}

/// max |τ_i − τ(t_i)| over the given samples [N·m]; `worst`: the t_i where it is largest.
double torqueError(const ContinuousReference& ref, const std::vector<double>& t,
                   const std::vector<Vector3>& tau, double* worst = nullptr) {
  const std::vector<ContinuousState> exact = ref.sample(t);
  double e = 0.0;
  for (size_t i = 0; i < t.size(); ++i) {
    const double d = (tau[i] - exact[i].torque()).norm();
    if (d > e) {
      e = d;
      if (worst) *worst = t[i];
    }
  }
  return e;
}

/// max_k ‖log(R(t_k)ᵀ R_k)‖ over the nodes t_k = kT/N, k = 0..N [rad] (the trajectory error).
double attitudeError(const ContinuousReference& ref, double duration,
                     const std::vector<Matrix3>& attitude) {
  const int N = static_cast<int>(attitude.size()) - 1;
  std::vector<double> t(N + 1);
  for (int k = 0; k <= N; ++k) t[k] = duration * k / N;
  const std::vector<ContinuousState> exact = ref.sample(t);
  double e = 0.0;
  for (int k = 0; k <= N; ++k) e = std::max(e, so3::angleBetween(exact[k].attitude, attitude[k]));
  return e;
}

#ifdef AP_HAVE_IPOPT
/// IPOPT's view of the Hermite–Simpson transcription (all evaluations delegate to it).
class HermiteSimpsonNlp : public Ipopt::TNLP {
 public:
  explicit HermiteSimpsonNlp(const PlanningProblem& problem) : hs_(problem) {}
  const peers::HermiteSimpsonTranscription& transcription() const { return hs_; }
  std::vector<double> solution;
  int iterations = 0;

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = hs_.variables();
    m = hs_.constraints();
    nnz_jac = static_cast<Ipopt::Index>(hs_.jacobianRows().size());
    nnz_h = static_cast<Ipopt::Index>(hs_.hessianRows().size());
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index m,
                       Ipopt::Number* gl, Ipopt::Number* gu) override {
    hs_.bounds(xl, xu);
    for (int i = 0; i < m; ++i) gl[i] = gu[i] = 0.0;
    return true;
  }
  bool get_starting_point(Ipopt::Index, bool, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    hs_.startingPoint(x);
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = hs_.objective(x);
    return true;
  }
  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* g) override {
    hs_.objectiveGradient(x, g);
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) override {
    hs_.constraintValues(x, g);
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) {
      std::copy(hs_.jacobianRows().begin(), hs_.jacobianRows().end(), iRow);
      std::copy(hs_.jacobianColumns().begin(), hs_.jacobianColumns().end(), jCol);
    } else {
      hs_.jacobianValues(x, values);
    }
    return true;
  }
  bool eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
              const Ipopt::Number* lambda, bool, Ipopt::Index, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) {
      std::copy(hs_.hessianRows().begin(), hs_.hessianRows().end(), iRow);
      std::copy(hs_.hessianColumns().begin(), hs_.hessianColumns().end(), jCol);
    } else {
      hs_.hessianValues(x, obj_factor, lambda, values);
    }
    return true;
  }
  bool intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index iter, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    iterations = iter;
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    solution.assign(x, x + n);
  }

 private:
  peers::HermiteSimpsonTranscription hs_;
};

struct HsOutcome {
  bool ok = false;
  int status = 0;
  int iterations = 0;
  double time_s = 0.0;
  std::vector<double> x;
};

/// One cold solve, timed from building the NLP to the end of OptimizeTNLP.
HsOutcome solveHermiteSimpson(const PlanningProblem& problem, double tol, int print_level) {
  const auto t0 = std::chrono::steady_clock::now();
  Ipopt::SmartPtr<HermiteSimpsonNlp> nlp = new HermiteSimpsonNlp(problem);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", print_level);
  if (print_level > 0) app->Options()->SetStringValue("print_timing_statistics", "yes");
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_approximation", "exact");
  app->Options()->SetStringValue("linear_solver", "mumps");
  app->Options()->SetNumericValue("tol", tol);
  app->Options()->SetNumericValue("constr_viol_tol", tol);
  app->Options()->SetIntegerValue("max_iter", 3000);
  HsOutcome out;
  if (app->Initialize() != Ipopt::Solve_Succeeded) return out;
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.time_s = seconds(t0);
  out.status = static_cast<int>(status);
  out.ok = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  out.iterations = nlp->iterations;
  out.x = nlp->solution;
  return out;
}
#endif

/// The command line: the output, the scenes and the study's limits.
struct FrontierArgs {
  std::string out_path;
  std::vector<std::string> scenes;
  int repeats = 3;
  int max_steps = 32768;
  int max_hs_steps = 24576;
  double time_limit = 40.0;  // per method: no larger N once a solve takes longer [s]
  double ipopt_tol = 1e-12;
  int ipopt_print = 0;  // --ipopt-print LEVEL: IPOPT's own log and timing statistics (diagnosis)
  SolverOptions ours;   // --tolerance TOL: ours' Newton tolerance (default SolverOptions, 1e-10)
  std::string only;     // --only METHOD: run one method (diagnosis)
};

FrontierArgs parseArguments(int argc, char** argv) {
  FrontierArgs args;
  args.out_path = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeats" && i + 1 < argc) {
      args.repeats = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--max-steps" && i + 1 < argc) {
      args.max_steps = std::atoi(argv[++i]);
    } else if (a == "--max-hs-steps" && i + 1 < argc) {
      args.max_hs_steps = std::atoi(argv[++i]);
    } else if (a == "--time-limit" && i + 1 < argc) {
      args.time_limit = std::atof(argv[++i]);
    } else if (a == "--ipopt-tol" && i + 1 < argc) {
      args.ipopt_tol = std::atof(argv[++i]);
    } else if (a == "--ipopt-print" && i + 1 < argc) {
      args.ipopt_print = std::atoi(argv[++i]);
    } else if (a == "--tolerance" && i + 1 < argc) {
      args.ours.tolerance = std::atof(argv[++i]);
    } else if (a == "--only" && i + 1 < argc) {
      args.only = argv[++i];
    } else {
      args.scenes.push_back(a);
    }
  }
  return args;
}

/// A scene's continuous reference and its largest torque (the errors' scale).
struct SceneReference {
  ContinuousReference ref;
  double tau_max = 0.0;
};

SceneReference referenceOf(const PlanningProblem& problem) {
  SceneReference out{solveContinuousReference(problem), 0.0};
  std::vector<double> dense(4001);
  for (size_t i = 0; i < dense.size(); ++i)
    dense[i] = problem.duration * static_cast<double>(i) / (dense.size() - 1);
  for (const ContinuousState& s : out.ref.sample(dense))
    out.tau_max = std::max(out.tau_max, s.torque().norm());
  return out;
}

/// Ours in one scheme at N = 8, 16, ... until a solve takes longer than the time limit or the
/// errors reach 1e-8: one JSON run per N.
void runOurs(FILE* out, const PlanningProblem& problem, const SceneReference& reference,
             SchemeKind scheme, const FrontierArgs& args) {
  const std::string name = schemeName(scheme);
  const ContinuousReference& ref = reference.ref;
  bool first_run = true;
  for (int N = 8; N <= args.max_steps; N *= 2) {
    PlanningProblem at_N = problem;
    at_N.scheme = scheme;
    at_N.steps = N;
    std::vector<double> times;
    PlanResult plan;
    for (int r = 0; r < args.repeats; ++r) {
      plan = planManeuver(at_N, args.ours);
      times.push_back(plan.solve_time_s);
    }
    const Maneuver& m = plan.maneuver;
    const int first = schemeHasEndTorques(scheme) ? 0 : 1;
    const int last = schemeHasEndTorques(scheme) ? N : N - 1;
    std::vector<double> t;
    std::vector<Vector3> tau;
    for (int k = first; k <= last; ++k) t.push_back(m.time[k]), tau.push_back(m.torque[k]);
    double worst = 0.0;
    const double torque_error = torqueError(ref, t, tau, &worst) / reference.tau_max;
    const double attitude_error = attitudeError(ref, problem.duration, m.attitude);
    const double effort_error = std::abs(plan.effort - ref.cost) / ref.cost;
    const double time = median(times);
    std::fprintf(out,
                 "   %s{\"N\": %d, \"converged\": %s, \"solve_time_s\": %.6g, \"times_s\": %s, "
                 "\"iterations\": %d, \"effort\": %.17g, \"torque_error\": %.6e, "
                 "\"effort_error\": %.6e, \"worst_node_time\": %.6g, "
                 "\"attitude_error\": %.6e}",
                 first_run ? "" : ",\n", N, plan.converged() ? "true" : "false", time,
                 timesJson(times).c_str(), plan.iterations, plan.effort, torque_error, effort_error,
                 worst, attitude_error);
    first_run = false;
    std::fprintf(stderr, "  %s N=%d %.3g ms torque %.3e effort %.3e%s\n", name.c_str(), N,
                 1e3 * time, torque_error, effort_error,
                 plan.converged() ? "" : " (NOT CONVERGED)");
    std::fflush(out);
    if (time > args.time_limit || (torque_error < 1e-8 && effort_error < 1e-8)) break;
  }
}

#ifdef AP_HAVE_IPOPT
/// What a Hermite–Simpson solution is measured by against the reference.
struct HsErrors {
  double torque_error = NAN, midpoint_error = NAN, effort_error = NAN, effort = NAN;
  double norm_drift = NAN, worst = NAN, attitude_error = NAN;
};

HsErrors hsErrors(const peers::HermiteSimpsonTranscription& tr, const std::vector<double>& x,
                  const PlanningProblem& problem, const SceneReference& reference) {
  HsErrors e;
  if (x.empty()) return e;
  const ContinuousReference& ref = reference.ref;
  const std::vector<Vector3> all = tr.torques(x.data());
  std::vector<double> t_nodes, t_mid;
  std::vector<Vector3> tau_nodes, tau_mid;
  e.norm_drift = 0.0;
  for (int p = 0; p < tr.points(); ++p) {
    (p % 2 ? t_mid : t_nodes).push_back(tr.time(p));
    (p % 2 ? tau_mid : tau_nodes).push_back(all[p]);
    e.norm_drift =
        std::max(e.norm_drift,
                 std::abs(Eigen::Map<const Eigen::Vector4d>(x.data() + tr.qIndex(p)).norm() - 1));
  }
  e.torque_error = torqueError(ref, t_nodes, tau_nodes, &e.worst) / reference.tau_max;
  std::vector<Matrix3> nodes;
  for (int p = 0; p < tr.points(); p += 2)
    nodes.push_back(so3::matrixFromQuaternion<double>(
        Eigen::Vector4d(Eigen::Map<const Eigen::Vector4d>(x.data() + tr.qIndex(p)))));
  e.attitude_error = attitudeError(ref, problem.duration, nodes);
  e.midpoint_error = torqueError(ref, t_mid, tau_mid) / reference.tau_max;
  e.effort = tr.objective(x.data());
  e.effort_error = std::abs(e.effort - ref.cost) / ref.cost;
  return e;
}

/// The peer: IPOPT on Hermite–Simpson collocation, N mesh intervals (2N + 1 points), at N = 4,
/// 6, 8, 12, ... until a solve takes longer than the time limit or the errors reach 1e-8.
void runIpoptHermiteSimpson(FILE* out, const PlanningProblem& problem,
                            const SceneReference& reference, const FrontierArgs& args) {
  bool first_run = true;
  std::vector<int> grid;
  for (int N = 4; N <= args.max_hs_steps; N *= 2) {
    grid.push_back(N);
    if (N * 3 / 2 <= args.max_hs_steps) grid.push_back(N * 3 / 2);
  }
  for (int N : grid) {
    PlanningProblem at_N = problem;
    at_N.steps = N;
    std::vector<double> times;
    HsOutcome hs;
    for (int r = 0; r < args.repeats; ++r) {
      hs = solveHermiteSimpson(at_N, args.ipopt_tol, args.ipopt_print);
      times.push_back(hs.time_s);
    }
    const peers::HermiteSimpsonTranscription tr(at_N);
    const HsErrors e = hsErrors(tr, hs.x, problem, reference);
    const double time = median(times);
    std::fprintf(out,
                 "   %s{\"N\": %d, \"converged\": %s, \"ipopt_status\": %d, \"solve_time_s\": "
                 "%.6g, \"times_s\": %s, \"iterations\": %d, \"variables\": %d, "
                 "\"constraints\": %d, \"effort\": %.17g, \"torque_error\": %.6e, "
                 "\"torque_error_midpoints\": %.6e, \"effort_error\": %.6e, "
                 "\"quaternion_norm_drift\": %.3e, \"worst_node_time\": %.6g, "
                 "\"attitude_error\": %.6e}",
                 first_run ? "" : ",\n", N, hs.ok ? "true" : "false", hs.status, time,
                 timesJson(times).c_str(), hs.iterations, tr.variables(), tr.constraints(),
                 e.effort, e.torque_error, e.midpoint_error, e.effort_error, e.norm_drift, e.worst,
                 e.attitude_error);
    first_run = false;
    std::fprintf(
        stderr,
        "  ipopt_hs N=%d %.3g ms (%d it, status %d) torque %.3e (worst at t=%.4g) mid %.3e "
        "effort %.3e\n",
        N, 1e3 * time, hs.iterations, hs.status, e.torque_error, e.worst, e.midpoint_error,
        e.effort_error);
    std::fflush(out);
    if (time > args.time_limit || (e.torque_error < 1e-8 && e.effort_error < 1e-8)) break;
  }
}
#endif

/// One scene's JSON case: its reference, ours in every scheme of the name table (a scheme added
/// there is picked up here) and the IPOPT peer.
void runScene(FILE* out, const std::string& path, bool first_case, const FrontierArgs& args) {
  const Scene scene = loadScene(path);
  const PlanningProblem problem = scene.problem;
  const SceneReference reference = referenceOf(problem);
  const ContinuousReference& ref = reference.ref;
  std::fprintf(stderr, "%s: reference %s, cost %.15g, max |tau| %.6g\n", path.c_str(),
               ref.message.c_str(), ref.cost, reference.tau_max);
  std::fprintf(out,
               "%s{\"scene\": \"%s\", \"duration\": %.17g, \"reference\": {\"converged\": %s, "
               "\"cost\": %.17g, \"max_torque\": %.17g, \"max_defect\": %.3e},\n \"methods\": [\n",
               first_case ? "" : ",\n", sceneName(path).c_str(), problem.duration,
               ref.converged ? "true" : "false", ref.cost, reference.tau_max, ref.max_defect);
  bool first_method = true;
  for (const auto& entry : kSchemeNames) {
    const std::string name = schemeName(entry.value);
    if (!args.only.empty() && args.only != name) continue;
    std::fprintf(out, "%s  {\"method\": \"%s\", \"family\": \"ours\", \"runs\": [\n",
                 first_method ? "" : ",\n", name.c_str());
    first_method = false;
    runOurs(out, problem, reference, entry.value, args);
    std::fprintf(out, "\n  ]}");
  }
#ifdef AP_HAVE_IPOPT
  if (args.only.empty() || args.only == "ipopt_hs") {
    std::fprintf(out, "%s  {\"method\": \"ipopt_hs\", \"family\": \"peer\", \"runs\": [\n",
                 first_method ? "" : ",\n");
    runIpoptHermiteSimpson(out, problem, reference, args);
    std::fprintf(out, "\n  ]}");
  }
#endif
  std::fprintf(out, "\n ]}");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: frontier_study OUT.json SCENE.yaml... [--repeats K] [--max-steps N] "
                 "[--max-hs-steps N] [--time-limit S] [--ipopt-tol TOL]\n");
    return 2;
  }
  const FrontierArgs args = parseArguments(argc, argv);
  FILE* out = std::fopen(args.out_path.c_str(), "w");
  if (!out) {
    std::fprintf(stderr, "frontier_study: cannot write %s\n", args.out_path.c_str());
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
#ifdef AP_HAVE_IPOPT
  const char* ipopt_version = IPOPT_VERSION;
#else
  const char* ipopt_version = "";
#endif
  std::fprintf(out,
               "{\n\"load_average_start\": \"%s\",\n\"repeats\": %d,\n\"ipopt_version\": \"%s\",\n"
               "\"ipopt_tol\": %g,\n\"tolerance\": %g,\n\"cases\": [\n",
               loadAverage().c_str(), args.repeats, ipopt_version, args.ipopt_tol,
               args.ours.tolerance);
  bool first_case = true;
  for (const std::string& path : args.scenes) {
    runScene(out, path, first_case, args);
    first_case = false;
  }
  std::fprintf(out, "\n],\n\"load_average_end\": \"%s\",\n\"wall_time_s\": %.1f\n}\n",
               loadAverage().c_str(), seconds(start));
  std::fclose(out);
  return 0;
}
