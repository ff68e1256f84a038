#include "attitude_planner/planning/minimum_time.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "planning/interior_point/free_time_solver.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/grid_continuation.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

/// Each step of the downward continuation in T shortens it by 5 %.
constexpr double kContinuationFactor = 0.95;
/// The largest angles of the excursion starts off the eigenaxis [rad], and their first T
/// relative to the eigenaxis slew's least T.
constexpr double kExcursionAngles[] = {0.3, 0.8};
constexpr double kExcursionStartFactors[] = {1.04, 0.96};
/// The structured starts' first T, relative to the eigenaxis slew's least T.
constexpr double kEigenaxisStartFactor = 1.02;
/// A search doubles its first T at most this many times looking for a feasible one.
constexpr int kMaxDoublings = 12;
/// Grids above this N search from the T* plan of the grid with half the steps.
constexpr int kCoarsestSearchGrid = 64;
/// That search's first T, relative to the coarse grid's T*.
constexpr double kCoarseStartFactor = 1.01;

/// The smallest torque every bound in force allows about any axis [N m].
double smallestAuthority(const PlanningProblem& problem) {
  double authority = std::numeric_limits<double>::infinity();
  if (problem.hasTorqueBounds()) authority = problem.max_torque.minCoeff();
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind == ConstraintKind::MaxTorqueNorm) authority = std::min(authority, c.limit);
  }
  return authority;
}

void validateMinimumTime(const PlanningProblem& problem) {
  if (!std::isfinite(smallestAuthority(problem))) {
    throw InvalidInput(
        "objective: 'minimum_time' needs a torque bound (effects: [actuator_limits: ...] or "
        "constraints: [max_torque_norm: ...]); without one any duration > 0 is feasible");
  }
  if (problem.accuracy.active()) {
    throw InvalidInput(
        "objective: 'minimum_time' with an accuracy target is not supported (give steps)");
  }
}

}  // namespace

double eigenaxisDurationGuess(const PlanningProblem& problem) {
  const double largest_moment =
      Eigen::SelfAdjointEigenSolver<Matrix3>(problem.inertia).eigenvalues().maxCoeff();
  const double acceleration = smallestAuthority(problem) / largest_moment;  // [rad/s²]
  const double angle =
      std::max(so3::angleBetween(problem.initial_attitude, problem.final_attitude), 1e-3);
  // Rest to rest: accelerate half way, brake half way; boundary rates add the time to stop and
  // to spin up at the same acceleration.
  const double spin = (problem.initial_velocity.norm() + problem.final_velocity.norm()) /
                      std::max(acceleration, 1e-300);
  return 2.0 * std::sqrt(angle / acceleration) + spin;
}

namespace {

/// A rest-to-rest slew R(t) = R_0 exp(θ(s) ê) exp(b(s) p̂), s = t/T: the eigenaxis bang–bang
/// θ(s) = 2Θs² (s ≤ ½), Θ(1 − 2(1 − s)²) (s > ½) about ê = log(R_0ᵀR_T)/Θ, and an excursion
/// b(s) = ε sin²(πs) about a unit p̂ ⟂ ê (ε = 0: the eigenaxis slew itself), which leaves both
/// ends and their rest untouched. The attitudes at the N + 1 nodes: a start for the search.
Maneuver excursionSlew(const PlanningProblem& problem, const Vector3& excursion_axis,
                       double excursion) {
  const Vector3 rotation = so3::log(problem.initial_attitude.transpose() * problem.final_attitude);
  const double angle = rotation.norm();
  const Vector3 axis = angle > 0 ? Vector3(rotation / angle) : Vector3::UnitX();
  Maneuver m;
  const int N = problem.steps;
  m.time_step = problem.duration / N;
  for (int k = 0; k <= N; ++k) {
    const double s = static_cast<double>(k) / N;
    const double theta = s <= 0.5 ? 2.0 * angle * s * s : angle * (1.0 - 2.0 * (1 - s) * (1 - s));
    const double bump = excursion * std::pow(std::sin(M_PI * s), 2);
    m.time.push_back(s * problem.duration);
    m.attitude.push_back(problem.initial_attitude * so3::exp(theta * axis) *
                         so3::exp(bump * excursion_axis));
    m.angular_velocity.push_back(Vector3::Zero());
    m.torque.push_back(Vector3::Zero());
  }
  return m;
}

/// The least T at which the eigenaxis bang–bang slew keeps the torque bounds (per axis and norm)
/// and rate limits in force: its torques τ = J ê θ̈ + θ̇² ê × J ê scale like 1/T² and its peak
/// rate 2Θ/T like 1/T, so T follows in closed form from the profile at T = 1.
double eigenaxisBangBangDuration(const PlanningProblem& problem) {
  const Vector3 rotation = so3::log(problem.initial_attitude.transpose() * problem.final_attitude);
  const double angle = std::max(rotation.norm(), 1e-9);
  const Vector3 e = rotation / angle;
  const Matrix3& J = problem.inertia;
  // At T = 1: θ̈ = ±4Θ, θ̇ ≤ 2Θ (peak at s = ½, where the gyroscopic term is largest).
  const Vector3 gyroscopic = e.cross(J * e) * (4.0 * angle * angle);  // θ̇² ê × Jê at s = ½
  const Vector3 inertial = J * e * (4.0 * angle);
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
  }
  double T = std::sqrt(T_squared);
  for (const PlanningConstraint& c : problem.constraints)
    if (c.kind == ConstraintKind::MaxAngularRate) T = std::max(T, 2.0 * angle / c.limit);
  return T;
}

/// One search on T from one start.
struct SearchOutcome {
  std::string start;      ///< which start
  PlanResult best;        ///< the plan at the least feasible T (if feasible)
  bool feasible = false;  ///< some T was found feasible
  double T_lo = 0.0;      ///< the bracket [T_lo infeasible, T_hi feasible]
  double T_hi = 0.0;
  int solves = 0;
  int iterations = 0;  ///< iterations of all its solves
};

/// A plan at T proves T feasible when it meets every node constraint and the discrete equations
/// step by step (planInconsistency): the reduced problem's iterates satisfy the dynamics and the
/// boundary data by construction, so a minimum-effort solve that stops short of optimality (the
/// iteration limit, a stalled line search) still proves T feasible. Whether it also minimizes the
/// effort does not matter to the search (measured: on Bilimoria–Wie's case the solves just below
/// the T* found stopped at the iteration limit with feasible iterates).
bool provesFeasible(const PlanningProblem& problem, const PlanResult& r) {
  if (r.converged()) return true;
  if (r.termination != Termination::NotConverged || r.maneuver.steps() != problem.steps) {
    return false;
  }
  return planInconsistency(problem, r, true).empty();
}

/// The search for T*: several starts, each a continuation downwards in T over minimum-effort
/// solves warm-started from the last feasible plan, and a bisection of the best bracket.
class MinimumTimeSearch {
 public:
  MinimumTimeSearch(const PlanningProblem& problem, const SolverOptions& options)
      : problem_(problem), options_(options), start_(std::chrono::steady_clock::now()) {
    effort_ = problem;
    effort_.objective = Objective::MinimumEffort;
    effort_.time_margin = 0.0;
  }

  /// The plan at the least feasible T found (minimum_duration = T*), or why there is none.
  PlanResult run() {
    const double guess =
        problem_.duration > 0 ? problem_.duration : eigenaxisDurationGuess(problem_);
    searchFromCoarseGrid();
    const bool searched_coarse = !outcomes_.empty() && outcomes_.back().feasible;
    if (!searched_coarse) outcomes_.push_back(search("continuation", nullptr, guess));
    if (!searched_coarse && isRestToRest()) searchStructuredStarts();
    SearchOutcome* found = leastFeasible();
    if (found) bisect(found);
    for (const SearchOutcome& o : outcomes_) solves_ += o.solves;
    if (!found) return noneFeasible(guess);
    return atMinimumTime(*found);
  }

 private:
  SolverOptions remaining() const { return withRemainingBudget(options_, start_); }

  /// One minimum-effort solve at T from `warm`: true, with the plan kept in `out`, if it proves
  /// T feasible (provesFeasible).
  bool tryDuration(double T, const Maneuver* warm, SearchOutcome* out) {
    effort_.duration = T;
    SolverOptions o = remaining();
    if (warm) {
      o.warm_start = warm;
      o.constrained_from_warm_start = true;
    }
    PlanResult r = planAtResolution(effort_, o);
    ++out->solves;
    out->iterations += r.iterations;
    if (r.termination == Termination::TimedOut || r.termination == Termination::Cancelled) {
      stopped_ = r.termination;
    }
    if (!provesFeasible(effort_, r)) return false;
    out->best = std::move(r);
    out->feasible = true;
    return true;
  }

  bool stopped() const { return stopped_.has_value(); }

  /// One search from one start: `from` (attitudes, any T) starts the first solve at T_first;
  /// null: the minimum-effort problem's own start (its unconstrained optimum). Each later solve
  /// starts from the last feasible plan (same N).
  SearchOutcome search(const std::string& name, const Maneuver* from, double T_first) {
    SearchOutcome out;
    out.start = name;
    const auto feasible = [&](double T) {
      return tryDuration(T, out.feasible ? &out.best.maneuver : from, &out);
    };
    double T = T_first;
    for (int doublings = 0; !feasible(T) && !stopped(); T *= 2.0) {
      if (++doublings > kMaxDoublings) return out;
    }
    if (!out.feasible) return out;
    // Down from the first feasible T in small steps, each warm-started from the last feasible
    // plan: a large step leaves the interior point far outside the bounds (torques grow like
    // 1/T²), where it can stop at a local minimum of the violation.
    out.T_hi = T;
    out.T_lo = T * kContinuationFactor;
    while (!stopped() && feasible(out.T_lo)) {
      out.T_hi = out.T_lo;
      out.T_lo *= kContinuationFactor;
    }
    return out;
  }

  /// Bisection of a search's bracket [T_lo infeasible, T_hi feasible], from its plans.
  void bisect(SearchOutcome* out) {
    while (!stopped() && out->T_hi - out->T_lo > kMinimumTimeTolerance * out->T_hi) {
      const double mid = 0.5 * (out->T_lo + out->T_hi);
      const Maneuver from = out->best.maneuver;
      (tryDuration(mid, &from, out) ? out->T_hi : out->T_lo) = mid;
    }
  }

  /// Above kCoarsestSearchGrid the starts are searched on a coarser grid (N/2, recursively) and
  /// its T* plan, resampled, starts the search here just above its T* (the discrete T*
  /// converges in N; measured, Betts's case: every start searched at N = 128 stopped above 34 s,
  /// while the N = 64 search reaches 28.6 s). The full set of starts runs here only if that
  /// finds nothing.
  void searchFromCoarseGrid() {
    if (problem_.steps <= kCoarsestSearchGrid || problem_.steps % 2 != 0) return;
    PlanningProblem coarse_problem = problem_;
    coarse_problem.steps = problem_.steps / 2;
    coarse_problem.time_margin = 0.0;
    const PlanResult coarse = MinimumTimeSearch(coarse_problem, remaining()).run();
    if (!coarse.converged()) return;
    Maneuver resampled = coarse.maneuver;
    resampled.attitude = resampleAttitudes(coarse.maneuver, problem_.steps);
    outcomes_.push_back(search("coarse grid (N = " + std::to_string(coarse_problem.steps) + ")",
                               &resampled, coarse.minimum_duration * kCoarseStartFactor));
    coarse_minimum_duration_ = coarse.minimum_duration;
  }

  bool isRestToRest() const {
    return !stopped() && problem_.initial_velocity.isZero(0.0) &&
           problem_.final_velocity.isZero(0.0) &&
           so3::angleBetween(problem_.initial_attitude, problem_.final_attitude) > 0;
  }

  /// Rest to rest: the eigenaxis bang–bang slew at the least T its bounds allow and excursions
  /// off it about the two axes perpendicular to the eigenaxis, both signs, two sizes, first
  /// solved just above and just below the eigenaxis T (the eigenaxis slew is a symmetric saddle
  /// the solver cannot leave on its own; the nutating time-optimal slews lie below it, and which
  /// excursion reaches the published T* differs between Betts's and Bilimoria–Wie's cases).
  void searchStructuredStarts() {
    const double T_eigenaxis = eigenaxisBangBangDuration(problem_);
    const Vector3 e =
        so3::log(problem_.initial_attitude.transpose() * problem_.final_attitude).normalized();
    const Vector3 p1 = e.unitOrthogonal(), p2 = e.cross(p1);
    std::vector<StructuredStart> starts{{"eigenaxis", e, 0.0, kEigenaxisStartFactor}};
    for (const double angle : kExcursionAngles) {
      for (const double factor : kExcursionStartFactors) {
        for (const auto& [name, axis] : {std::pair<std::string, Vector3>{"+p1", p1},
                                         {"-p1", -p1},
                                         {"+p2", p2},
                                         {"-p2", -p2}}) {
          std::ostringstream label;
          label << "excursion " << angle << " rad " << name << " from " << factor << " T_eig";
          starts.push_back({label.str(), axis, angle, factor});
        }
      }
    }
    for (const StructuredStart& st : starts) {
      if (stopped()) break;
      PlanningProblem shaped = effort_;
      shaped.duration = T_eigenaxis * st.duration_factor;
      const Maneuver slew = excursionSlew(shaped, st.axis, st.angle);
      outcomes_.push_back(search(st.name, &slew, shaped.duration));
    }
  }

  /// The search with the least feasible T (only its bracket is bisected: a 5 % bracket each, and
  /// bisecting them all cost 5× the solves, measured on the seed's torque_limited scene, for T*
  /// within 2e-4 of each other).
  SearchOutcome* leastFeasible() {
    SearchOutcome* found = nullptr;
    for (SearchOutcome& o : outcomes_) {
      if (o.feasible && (!found || o.T_hi < found->T_hi)) found = &o;
    }
    return found;
  }

  PlanResult noneFeasible(double guess) const {
    PlanResult none;
    if (stopped_) {
      none.termination = *stopped_;
      none.message = terminationName(*stopped_) + " before any duration was found feasible";
    } else {
      none.termination = Termination::Infeasible;
      none.message = "infeasible: no duration up to 2^" + std::to_string(kMaxDoublings) +
                     " times the first guess " + exactNumber(guess) +
                     " s admits a plan under the bounds and constraints in force (a local "
                     "search: every start's solves ended infeasible or unconverged)";
    }
    none.attempts = trail();
    return none;
  }

  /// One attempt per start of the search (its solves summed), in the order the starts ran.
  std::vector<Attempt> trail() const {
    std::vector<Attempt> attempts;
    for (const SearchOutcome& o : outcomes_) {
      Attempt a;
      a.stage = AttemptStage::MinimumTimeProbe;
      a.start = o.start == "continuation" ? AttemptStart::Hermite : AttemptStart::WarmStart;
      a.formulation = Formulation::FreeSlacks;
      a.steps = problem_.steps;
      a.termination = o.feasible ? Termination::Converged : Termination::Infeasible;
      a.iterations = o.iterations;
      if (o.feasible) a.cost = o.best.cost;
      attempts.push_back(a);
    }
    return attempts;
  }

  PlanResult atMinimumTime(const SearchOutcome& found) const {
    PlanResult result = found.best;
    if (!result.converged()) {
      // At T* the feasible set shrinks to the bang–bang plan: its minimum-effort solve may stop
      // short of optimality while its plan meets every constraint, which is what T* rests on.
      result.termination = Termination::Converged;
      result.message = "feasible at T* (its minimum-effort solve stopped short of optimality: " +
                       result.message + ")";
    }
    result.minimum_duration = found.T_hi;
    result.attempts = trail();
    for (std::size_t i = 0; i < outcomes_.size(); ++i) {
      result.attempts[i].kept = &outcomes_[i] == &found;
    }
    result.message += searchNote(found);
    return result;
  }

  /// T* is the least duration the interior point found feasible: an upper bound on the true
  /// minimum (a false "infeasible" below it cannot be told from a true one;
  /// docs/results/minimum_time.md).
  std::string searchNote(const SearchOutcome& found) const {
    std::ostringstream note;
    note << "; minimum time T* = " << found.T_hi << " s, the least duration found feasible, from "
         << "the " << found.start << " start (bracket [" << found.T_lo << ", " << found.T_hi
         << "] s; starts:";
    for (const SearchOutcome& o : outcomes_) {
      note << " " << o.start << " ";
      if (o.feasible) {
        note << o.T_hi << " s;";
      } else {
        note << "none feasible;";
      }
    }
    note << " " << solves_ << " minimum-effort solves"
         << (stopped_ ? ", stopped by " + terminationName(*stopped_) : std::string()) << ")";
    if (coarse_minimum_duration_ > 0) {
      note << "; on the coarse grid T* = " << coarse_minimum_duration_ << " s";
    }
    return note.str();
  }

  struct StructuredStart {
    std::string name;
    Vector3 axis;
    double angle, duration_factor;
  };

  const PlanningProblem& problem_;
  SolverOptions options_;
  std::chrono::steady_clock::time_point start_;
  PlanningProblem effort_;
  std::vector<SearchOutcome> outcomes_;
  std::optional<Termination> stopped_;
  double coarse_minimum_duration_ = 0.0;
  int solves_ = 0;
};

/// The free-time solves' tolerance on the KKT residuals (objective T/T₀, constraints
/// dimensionless): the duality gap Σ zc bounds T − T* relative to T₀ by this much.
constexpr double kFreeTimeTolerance = 1e-9;
constexpr int kFreeTimeMaxIterations = 500;
/// The excursion starts: their size [rad] and first T relative to the eigenaxis slew's.
constexpr double kFreeTimeExcursion = 0.3;
/// With cones also excursions this large [rad]: a detour round a cone is a larger departure.
constexpr double kFreeTimeConeExcursion = 0.8;
constexpr double kFreeTimeStartFactor = 0.96;
/// A body axis whose part perpendicular to the eigenaxis is shorter than this gives no start.
constexpr double kSmallestProjection = 0.3;
/// Two excursion axes closer than this (cosine) are one start.
constexpr double kSameAxis = 0.99;
/// The starts run on the coarsest of N, N/2, ... at or above this N; the best is refined up.
constexpr int kFreeTimeStartGrid = 64;

/// One start of the free-time solve.
struct FreeTimeStart {
  std::string name;
  AttemptStart kind;
  std::vector<Matrix3> attitudes;  ///< R_0..R_N
  double duration;
};

/// The axes ⟂ ê the excursions turn about: the body axes' parts perpendicular to the eigenaxis
/// and their normalized sums and differences (the box bounds act on body axes, so the nutating
/// optima turn about them and their diagonals: measured, Bilimoria–Wie reaches its published T*
/// only from a diagonal, Betts's from the diagonals of y and z). Body-fixed: the same in every
/// world frame.
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

std::string axisName(const Vector3& v) {
  std::ostringstream out;
  out << "[" << std::round(v.x() * 1000) / 1000 << ", " << std::round(v.y() * 1000) / 1000 << ", "
      << std::round(v.z() * 1000) / 1000 << "]";
  return out.str();
}

/// Spinning ends: the reduced problem's own start (the geodesic between the fixed inner
/// attitudes) at the eigenaxis guess. (An empty list of attitudes here once reached
/// setInteriorFromAttitudes: every spinning minimum-time request ended "invalid input".)
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
  return {"geodesic", AttemptStart::Hermite, attitudes, at.duration};
}

/// The structured starts: rest to rest, the eigenaxis bang–bang slew at its closed-form T and
/// excursions off it (excursionAxes); otherwise the reduced problem's own start at the eigenaxis
/// guess.
std::vector<FreeTimeStart> freeTimeStarts(const PlanningProblem& problem, bool rest_to_rest) {
  if (!rest_to_rest) return {geodesicStart(problem)};
  const double T_eigenaxis = eigenaxisBangBangDuration(problem);
  PlanningProblem at = problem;
  at.duration = T_eigenaxis;
  const Vector3 e =
      so3::log(problem.initial_attitude.transpose() * problem.final_attitude).normalized();
  std::vector<FreeTimeStart> starts{
      {"eigenaxis", AttemptStart::EigenaxisSlew, excursionSlew(at, e, 0.0).attitude, T_eigenaxis}};
  // With cones both signs of each excursion: a cone is passed on one side or the other, and
  // the sides are different local minima of T.
  std::vector<Vector3> axes = excursionAxes(e);
  const bool cones = std::any_of(problem.constraints.begin(), problem.constraints.end(),
                                 [](const PlanningConstraint& c) { return c.isCone(); });
  if (cones) {
    for (std::size_t i = 0, n = axes.size(); i < n; ++i) axes.push_back(-axes[i]);
  }
  if (cones) {
    starts.push_back({"minimum effort under the constraints",
                      AttemptStart::ConstrainedMinimumEffort, starts.front().attitudes,
                      kEigenaxisStartFactor * T_eigenaxis});
  }
  for (const double size : {kFreeTimeExcursion, kFreeTimeConeExcursion}) {
    if (size != kFreeTimeExcursion && !cones) break;
    for (const Vector3& axis : axes) {
      std::ostringstream name;
      name << "excursion " << size << " rad about " << axisName(axis);
      starts.push_back({name.str(), AttemptStart::Excursion, excursionSlew(at, axis, size).attitude,
                        kFreeTimeStartFactor * T_eigenaxis});
    }
  }
  return starts;
}

/// A free-time solve's start must clear its cones strictly: raising T moves no attitude, so the
/// start's clearance is all the room the barrier has. Starts are taken this far [rad] inside the
/// cones' node bounds.
constexpr double kConeStartClearance = 0.01;

/// The smallest clearance of the free attitudes R_1..R_{N−1} to their cones' node bounds [rad]
/// (+∞ without cones).
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

/// R_k turned (in the world frame, about s × R_k b) just far enough to clear each cone's node
/// bound by `clearance`: for a resampled coarse T* plan, whose new nodes between the coarse ones
/// dip past an active bound by O(h²).
std::vector<Matrix3> pushedOutOfCones(const PlanningProblem& problem, std::vector<Matrix3> R,
                                      double clearance) {
  for (const PlanningConstraint& c : problem.constraints) {
    if (!c.isCone()) continue;
    const bool keep_out = c.kind == ConstraintKind::KeepOut;
    for (std::size_t k = 1; k + 1 < R.size(); ++k) {
      const double turn = clearance - (coneMargin(c, R[k]) - c.margin);
      if (turn <= 0) continue;
      const Vector3 v = R[k] * c.body_axis;
      Vector3 axis = c.world_direction.cross(v);  // turning about it by + moves v away from s
      axis = axis.norm() > 1e-12 ? axis.normalized() : c.world_direction.unitOrthogonal();
      R[k] = so3::exp((keep_out ? turn : -turn) * axis) * R[k];
    }
  }
  return R;
}

/// A start that clears the cones: the minimum-effort plan at `duration` under the cones alone,
/// their node bounds tightened by kConeStartClearance (the torque bounds left out: the free-time
/// solve meets them by raising T), warm-started from `attitudes` so that each start keeps its own
/// side of a cone; cold if that does not converge. `every_constraint`: the other bounds kept and a
/// cold solve (the ConstrainedMinimumEffort start). Empty if none converges.
std::optional<std::vector<Matrix3>> coneClearStart(const PlanningProblem& problem,
                                                   const std::vector<Matrix3>& attitudes,
                                                   double duration, const SolverOptions& options,
                                                   bool every_constraint = false) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = duration;
  if (!every_constraint) {
    effort.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  }
  effort.constraints.clear();
  for (PlanningConstraint c : problem.constraints) {
    if (c.isCone()) c.margin += kConeStartClearance;
    if (c.isCone() || every_constraint) effort.constraints.push_back(c);
  }
  // A cone tightened past a cone (node half angle outside (0, π)) is no problem to solve
  // (validateProblem would refuse it): no cleared start.
  for (const PlanningConstraint& c : effort.constraints) {
    if (c.isCone() && !(c.nodeHalfAngle() > 0.0 && c.nodeHalfAngle() < M_PI)) return std::nullopt;
  }
  try {
    SolverOptions o = options;
    PlanResult r;
    if (!every_constraint) {
      ReducedProblem np(effort);
      np.setInteriorFromAttitudes(attitudes);
      const Maneuver guess = np.maneuver(np.current());
      o.warm_start = &guess;
      o.constrained_from_warm_start = true;
      r = planAtResolution(effort, o);
    }
    if (!r.converged()) {
      o.warm_start = nullptr;
      o.constrained_from_warm_start = false;
      r = planAtResolution(effort, o);
    }
    if (r.converged()) return r.maneuver.attitude;
  } catch (const StepTooLarge&) {  // a boundary rate with no step at this T: no cleared start
  }
  return std::nullopt;
}

/// The free-time answer on a coarser grid carried to grid p at its T: the coarse rates
/// interpolated in time (ReducedProblem::initializeFromCoarser), so the torques stay near the
/// coarse ones. (Resampling the attitudes instead put torque spikes of ~1.5× the bound next to
/// the switches of a bang–bang plan: the free-time start then had to raise T by ~27 % before
/// every bound held, measured on Bilimoria–Wie, N = 512 → 1024.) With cones the new nodes
/// between the coarse ones dip past an active bound by O(h²): they are turned out of the cones
/// (pushedOutOfCones), as a free-time start must clear them strictly.
std::vector<Matrix3> prolonged(const PlanningProblem& p, const FreeTimeOutcome& coarse) {
  PlanningProblem at = p;
  at.duration = coarse.duration;
  std::vector<Matrix3> attitudes;
  try {
    ReducedProblem np(at);
    np.initializeFromCoarser(coarse.steps);
    attitudes = np.attitudes(np.current());
  } catch (const StepTooLarge&) {  // the boundary rates admit no step at this h
    attitudes = resampleAttitudes(coarse.maneuver, p.steps);
  }
  if (coneClearance(p, attitudes) < 0.5 * kConeStartClearance) {
    attitudes = pushedOutOfCones(p, attitudes, kConeStartClearance);
  }
  return attitudes;
}

/// What one free-time grid level hands the next: its outcome (plan, T, steps).
struct FreeTimeCarry {
  FreeTimeOutcome outcome;
  bool empty() const { return outcome.steps.empty(); }
};

/// The free-time grid levels (strategies/grid_continuation.hpp): N, N/2, ... down to the coarsest
/// at or above kFreeTimeStartGrid, each solved to kFreeTimeTolerance. A refinement by 2 at a time:
/// measured, a resampled N = 64 plan started N = 512 so far from its optimum that the solve slid
/// to the eigenaxis slew's T. Below 2 kFreeTimeStartGrid a grid's half would be under the
/// coarsest, so it is solved on its own. A refined level that does not converge ends the
/// continuation with no answer (a fresh start there would be another attempt; the caller falls
/// back to the search).
GridLevelRule freeTimeGridRule() {
  GridLevelRule rule;
  rule.coarsest_steps = kFreeTimeStartGrid;
  rule.coarsening_factor = 2;
  rule.direct_up_to = 2 * kFreeTimeStartGrid - 1;
  rule.coarse_tolerance_floor = 0.0;
  rule.unconverged_ends = true;
  return rule;
}

/// A free-time level's end as the continuation's result and its LevelSummary (the relative
/// gradient: the stationarity of the minimum-time Lagrangian).
PlanResult levelResult(int steps, const FreeTimeOutcome& o) {
  PlanResult r;
  r.termination = o.termination;
  r.message = o.message;
  r.iterations = o.iterations;
  LevelSummary level;
  level.steps = steps;
  level.iterations = o.iterations;
  level.termination = o.termination;
  level.relative_gradient = o.stationarity;
  level.reason = o.message;
  r.levels.push_back(level);
  return r;
}

/// Minimum time as one interior-point problem per start (free_time_solver.hpp): each start one
/// free-time solve, the least T kept; the starts run on the coarsest level of the free-time grid
/// continuation (freeTimeGridRule) and the best is resumed through the finer levels, each solved
/// once from the coarser answer prolonged (its rates interpolated). The answer is then polished:
/// the minimum-effort plan at T* from the free-time plan (its multipliers give the switching
/// functions). Empty if no solve converged (the caller falls back to the search).
class FreeTimeMinimumTime {
 public:
  FreeTimeMinimumTime(const PlanningProblem& problem, const SolverOptions& options)
      : problem_(problem), context_(options) {}

  std::optional<PlanResult> run() {
    const bool rest_to_rest =
        problem_.initial_velocity.isZero(0.0) && problem_.final_velocity.isZero(0.0) &&
        so3::angleBetween(problem_.initial_attitude, problem_.final_attitude) > 0;
    const std::vector<PlanningProblem> levels = gridLevels(problem_, freeTimeGridRule());
    const PlanningProblem& coarsest = levels.front();
    const int best = solveStarts(coarsest, freeTimeStarts(coarsest, rest_to_rest));
    if (best < 0) return std::nullopt;
    levels_ = levelResult(coarsest.steps, outcomes_[best]).levels;
    if (levels.size() == 1) return polished(outcomes_[best], names_[best]);
    std::optional<FreeTimeOutcome> refined = refine(levels, outcomes_[best]);
    if (!refined) return std::nullopt;
    best_attempt_ = trail_.size() - 1;  // the refined solve is the one returned
    return polished(*refined, "coarse grid (N = " + std::to_string(coarsest.steps) + ", " +
                                  names_[best] + "), refined by 2 at a time");
  }

 private:
  /// One free-time solve from `start` (N + 1 attitudes, clear of the cones) at T = duration,
  /// recorded in the trail.
  FreeTimeOutcome solve(const PlanningProblem& p, const std::vector<Matrix3>& start,
                        double duration, AttemptStart kind) {
    const SolverOptions remaining = context_.remainingOptions();
    FreeTimeOutcome o =
        solveFreeTime(p, start, duration, kFreeTimeTolerance, kFreeTimeMaxIterations, &remaining);
    Attempt a;
    a.stage = AttemptStage::MinimumTimeSolve;
    a.start = kind;
    a.formulation = Formulation::FreeSlacks;
    a.steps = p.steps;
    a.termination = o.termination;
    a.iterations = o.iterations;
    a.cost = o.duration;  // the free-time objective: T [s]
    trail_.push_back(a);
    ++solves_;
    return o;
  }

  /// A structured start made to clear the cones: the ConstrainedMinimumEffort start is the
  /// minimum-effort plan under every constraint; any other start too close to a cone is replaced
  /// by the minimum-effort plan under the cones alone from it (coneClearStart).
  std::vector<Matrix3> clearOfCones(const PlanningProblem& p, const FreeTimeStart& st) {
    const SolverOptions remaining = context_.remainingOptions();
    if (st.kind == AttemptStart::ConstrainedMinimumEffort) {
      return coneClearStart(p, st.attitudes, st.duration, remaining, true).value_or(st.attitudes);
    }
    if (coneClearance(p, st.attitudes) >= 0.5 * kConeStartClearance) return st.attitudes;
    return coneClearStart(p, st.attitudes, st.duration, remaining).value_or(st.attitudes);
  }

  /// Runs every start on `grid`; returns the index of the converged one with the least T (−1:
  /// none converged).
  int solveStarts(const PlanningProblem& grid, const std::vector<FreeTimeStart>& starts) {
    int best = -1;
    for (const FreeTimeStart& st : starts) {
      if (budgetSpent(context_.remainingOptions())) break;
      outcomes_.push_back(solve(grid, clearOfCones(grid, st), st.duration, st.kind));
      names_.push_back(st.name);
      const FreeTimeOutcome& o = outcomes_.back();
      if (o.termination == Termination::Converged &&
          (best < 0 || o.duration < outcomes_[best].duration)) {
        best = static_cast<int>(outcomes_.size()) - 1;
        best_attempt_ = trail_.size() - 1;
      }
    }
    return best;
  }

  /// The coarsest level's best answer carried through the finer `levels` (the grid continuation
  /// resumed from it): each level one free-time solve from the coarser answer prolonged, at its
  /// T. Empty if a level does not converge or the solve is stopped (cancel, deadline).
  std::optional<FreeTimeOutcome> refine(const std::vector<PlanningProblem>& levels,
                                        const FreeTimeOutcome& coarsest) {
    std::optional<FreeTimeOutcome> finest;
    const LevelSolver<FreeTimeCarry> level = [&](const LevelRequest<FreeTimeCarry>& r,
                                                 FreeTimeCarry* handed_on) {
      if (r.replay_only || !r.coarse) {  // stopped: no answer on this level
        PlanResult stopped;
        stopped.termination = r.stop ? r.stop->termination : Termination::NotConverged;
        return stopped;
      }
      const FreeTimeOutcome& coarse = r.coarse->outcome;
      FreeTimeOutcome o = solve(r.problem, prolonged(r.problem, coarse), coarse.duration,
                                AttemptStart::CoarseLevel);
      PlanResult result = levelResult(r.problem.steps, o);
      if (handed_on) {
        handed_on->outcome = std::move(o);
      } else {
        finest = std::move(o);
      }
      return result;
    };
    // The polish writes the message from the whole trail; the levels keep their own.
    const ContinuationFinish finish = [](const ContinuationRecord&, PlanResult*) {};
    const SolvedLevel<FreeTimeCarry> from{0, Termination::Converged, {coarsest}, {}, false};
    const PlanResult result = resumeGridContinuation(levels, from, context_, freeTimeGridRule(),
                                                     kFreeTimeTolerance, level, finish);
    if (!result.converged() || !finest) return std::nullopt;
    levels_.insert(levels_.end(), result.levels.begin(), result.levels.end());
    return finest;
  }

  /// The plan at T*: the minimum-effort plan at T* from the free-time plan if that proves T*
  /// feasible (provesFeasible), else the free-time plan itself evaluated at T* by the same solve.
  PlanResult polished(const FreeTimeOutcome& answer, const std::string& from) {
    PlanningProblem effort = problem_;
    effort.objective = Objective::MinimumEffort;
    effort.time_margin = 0.0;
    effort.duration = answer.duration;
    SolverOptions o = context_.remainingOptions();
    o.warm_start = &answer.maneuver;
    o.constrained_from_warm_start = true;
    PlanResult result = planAtResolution(effort, o);
    const std::vector<Attempt> polish_attempts = result.attempts;
    const bool feasible = provesFeasible(effort, result);
    // A polish that stops short of optimality with a plan meeting every constraint still gives
    // the plan at T* (provesFeasible).
    if (feasible) result.termination = Termination::Converged;
    std::string polish_note;
    if (!feasible) {
      // At T* the feasible set is (nearly) the one bang–bang plan: the polish can stop short
      // (measured at N ≥ 512); the free-time plan itself is the answer then.
      polish_note = "; its minimum-effort polish at T* did not converge (" + result.message +
                    "): the plan is the free-time solve's";
      result = freeTimePlan(effort, answer);
    }
    for (Attempt a : polish_attempts) {
      a.stage = AttemptStage::MinimumTimePolish;
      a.kept = false;
      trail_.push_back(a);
    }
    if (!trail_.empty()) trail_[best_attempt_].kept = true;
    std::ostringstream note;
    note << "minimum time T* = " << answer.duration
         << " s: a KKT point of the discrete minimum-time problem (one free-time interior-point "
            "solve from the "
         << from << " start, " << answer.iterations << " iterations; stationarity "
         << answer.stationarity << ", h row " << answer.time_row << ", complementarity "
         << answer.complementarity << "; starts:";
    for (std::size_t i = 0; i < outcomes_.size(); ++i) {
      note << " " << names_[i] << " ";
      if (outcomes_[i].termination == Termination::Converged) {
        note << outcomes_[i].duration << " s;";
      } else {
        note << terminationName(outcomes_[i].termination) << ";";
      }
    }
    note << " " << solves_ << " free-time solves)";
    note << polish_note;
    result.message = note.str();
    result.minimum_duration = answer.duration;
    result.minimum_time.kkt_point = true;
    result.minimum_time.stationarity = answer.stationarity;
    result.minimum_time.time_stationarity = answer.time_row;
    result.minimum_time.complementarity = answer.complementarity;
    result.minimum_time.solves = solves_;
    result.attempts = trail_;
    // The free-time levels first, then the polish's own.
    result.levels.insert(result.levels.begin(), levels_.begin(), levels_.end());
    return result;
  }

  /// The free-time plan as the answer (at T*, measured as every plan is: evaluatePlan, the
  /// replay, the constraint figures).
  static PlanResult freeTimePlan(const PlanningProblem& effort, const FreeTimeOutcome& answer) {
    PlanResult r;
    r.solver = "interior_point";
    r.termination = Termination::Converged;
    r.iterations = answer.iterations;
    evaluatePlan(effort, answer.maneuver.torque, &r, &answer.maneuver);
    try {
      replayFigures(effort, &r);
    } catch (const StepTooLarge& e) {
      r.termination = Termination::StepTooLarge;
      r.message = std::string("replay of the planned torques failed: ") + e.what();
    }
    const ConstraintCheck check = checkConstraints(effort, r.maneuver);
    r.constraints = check.names;
    r.max_constraint_violation = check.max_violation;
    r.max_violation_between_nodes = check.max_violation_between_nodes;
    r.active_constraints = check.active;
    return r;
  }

  const PlanningProblem& problem_;
  SolveContext context_;
  std::vector<FreeTimeOutcome> outcomes_;
  std::vector<LevelSummary> levels_;  ///< the kept start's level and each refined level
  std::vector<std::string> names_;
  std::vector<Attempt> trail_;
  std::size_t best_attempt_ = 0;
  int solves_ = 0;
};

/// What T* is, for messages.
std::string tStarKind(const PlanResult& r) {
  return r.minimum_time.kkt_point ? "minimum time, a KKT point of the discrete minimum-time problem"
                                  : "minimum time, the least duration found feasible";
}

/// T* and its plan: the free-time interior point where it applies (freeTimeUnsupported), else,
/// or if none of its solves converged, the search (MinimumTimeSearch, an upper bound).
PlanResult minimumTimePlan(const PlanningProblem& problem, const SolverOptions& options) {
  const std::string unsupported = freeTimeUnsupported(problem);
  std::string why;
  if (unsupported.empty()) {
    std::optional<PlanResult> free_time = FreeTimeMinimumTime(problem, options).run();
    if (free_time && free_time->converged()) return *free_time;
    why = free_time ? "the free-time plan's replay failed" : "no free-time solve converged";
  } else {
    why = "the free-time interior point does not take " + unsupported + " yet";
  }
  PlanResult result = MinimumTimeSearch(problem, options).run();
  result.message += "; searched on T (" + why + ")";
  return result;
}

/// `problem` as a minimum-effort problem at T from the plan `at_minimum_time` (attitudes at
/// T*): slower than the bang–bang plan, every node constraint is met with room (torques scale
/// like (T*/T)², rates like T*/T for rest-to-rest motions), so the interior point starts
/// strictly inside instead of from the unconstrained optimum.
PlanResult planFromMinimumTimePlan(const PlanningProblem& problem, double T,
                                   const Maneuver& at_minimum_time, const SolverOptions& options) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = T;
  SolverOptions o = options;
  o.warm_start = &at_minimum_time;
  o.constrained_from_warm_start = true;
  return planAtResolution(effort, o);
}

}  // namespace

PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  validateMinimumTime(problem);
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = minimumTimePlan(problem, options);
  if (!result.converged()) return result;
  const double T_star = result.minimum_duration;
  if (problem.duration > 0 && T_star > problem.duration * (1.0 + kMinimumTimeTolerance)) {
    // `duration` is an upper bound: the request asked for T ≤ duration.
    result.termination = Termination::Infeasible;
    std::ostringstream why;
    why << "infeasible: needs T >= " << T_star << " s under these bounds (" << tStarKind(result)
        << "), requested duration <= " << problem.duration << " s";
    result.message = why.str() + result.message;
    return result;
  }
  if (problem.time_margin > 0.0) {
    const std::vector<Attempt> search_trail = result.attempts;
    const Maneuver at_minimum_time = result.maneuver;
    result = planFromMinimumTimePlan(problem, (1.0 + problem.time_margin) * T_star, at_minimum_time,
                                     withRemainingBudget(options, start));
    std::vector<Attempt> attempts = search_trail;
    for (Attempt& a : attempts) a.kept = false;
    for (Attempt a : result.attempts) {
      a.stage = AttemptStage::MinimumTimeMargin;
      attempts.push_back(a);
    }
    result.attempts = attempts;
    std::ostringstream note;
    note << "; planned at (1 + " << problem.time_margin << ") T* = " << result.duration
         << " s from the T* plan (minimum time T* = " << T_star << " s)";
    result.message += note.str();
  }
  result.minimum_duration = T_star;
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = planAtResolution(problem, options);
  if (result.termination != Termination::Infeasible || !std::isfinite(smallestAuthority(problem)) ||
      problem.accuracy.active()) {
    return result;
  }
  // The interior point's "infeasible" is local (its elastic form stopped at a minimum of the
  // violation): the minimum-time problem under the same bounds backs it or refutes it.
  PlanningProblem fastest = problem;
  fastest.objective = Objective::MinimumTime;
  fastest.time_margin = 0.0;
  fastest.duration = 0.0;
  const PlanResult minimum_time = minimumTimePlan(fastest, withRemainingBudget(options, start));
  const auto finish = [&](PlanResult r) {
    r.minimum_duration = minimum_time.converged() ? minimum_time.minimum_duration : 0.0;
    r.solve_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  };
  std::ostringstream why;
  if (!minimum_time.converged()) {
    why << "infeasible (a local verdict: the minimum-time problem under the same bounds found "
           "no feasible duration either, "
        << terminationName(minimum_time.termination) << "): " << result.message;
    result.message = why.str();
    return finish(result);
  }
  const double T_star = minimum_time.minimum_duration;
  if (T_star > problem.duration) {
    why << "infeasible: needs T >= " << T_star << " s under these bounds ("
        << tStarKind(minimum_time) << "), requested " << problem.duration << " s";
    result.message = why.str();
    return finish(result);
  }
  PlanResult again = planFromMinimumTimePlan(problem, problem.duration, minimum_time.maneuver,
                                             withRemainingBudget(options, start));
  why << "; started from the minimum-time plan (T* = " << T_star
      << " s) after the first solve ended infeasible";
  if (again.termination == Termination::Infeasible) {
    // Feasible at T* ≤ T, yet not reached from T*'s plan: not a proof of infeasibility.
    again.termination = Termination::NotConverged;
    again.message = "not converged (feasible: T* = " + exactNumber(T_star) +
                    " s <= the requested duration, but the minimum-effort solve from the "
                    "minimum-time plan ended at an infeasible point): " +
                    again.message;
  }
  again.message += why.str();
  std::vector<Attempt> attempts = result.attempts;
  for (Attempt a : minimum_time.attempts) {
    a.kept = false;
    attempts.push_back(a);
  }
  for (Attempt a : again.attempts) {
    a.stage = AttemptStage::ConstrainedRetry;
    a.start = AttemptStart::WarmStart;
    attempts.push_back(a);
  }
  again.attempts = attempts;
  return finish(again);
}

}  // namespace attitude_planner
