// What a solve returns (PlanResult) and the trail of attempts behind it (Attempt).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "attitude_planner/name_table.hpp"
#include "attitude_planner/planning/driver_verdict.hpp"
#include "attitude_planner/planning/message_clauses.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/termination.hpp"

namespace attitude_planner {

/// One grid level of a continuation solve (coarsest first; the last one is the requested N).
struct LevelSummary {
  int steps = 0;       ///< N of this level
  int iterations = 0;  ///< Newton iterations on this level
  Termination termination = Termination::NotConverged;
  double relative_gradient = 0.0;  ///< max|∇C| / (|∂τ/∂R|·max|τ|) at the level's last iterate
  double newton_decrement = 0.0;  ///< relative Newton decrement of its last iteration
  std::string reason;             ///< why the level ended, one sentence
};

/// Where an attempt's iterate started.
enum class AttemptStart {
  Hermite,          ///< the rate-honouring Hermite curve to the chosen lift (newtonInitialSteps)
  CoarseLevel,      ///< the coarser grid level's plan, refined (grid continuation)
  WarmStart,        ///< the caller's guess (SolverOptions::warm_start)
  Coasting,         ///< the torque-free motions from both ends blended
  InertiaHomotopy,  ///< an extremal of the sphere J̄ = tr(J)/3·I carried to J in stages
  UnconstrainedOptimum,  ///< the unconstrained optimum (the interior point's start)
  PreviousAttempt,       ///< the plan of the attempt before it (staged continuations, retries)
  EigenaxisSlew,         ///< minimum_time: the eigenaxis bang–bang slew at its closed-form T
  Excursion,             ///< minimum_time: the eigenaxis slew with an excursion off its axis
  /// minimum_time with cones: the minimum-effort plan under every constraint (cones tightened)
  ConstrainedMinimumEffort,
};
inline constexpr NamedValue<AttemptStart> kAttemptStartNames[] = {
    {AttemptStart::Hermite, "hermite"},
    {AttemptStart::CoarseLevel, "coarse_level"},
    {AttemptStart::WarmStart, "warm_start"},
    {AttemptStart::Coasting, "coasting"},
    {AttemptStart::InertiaHomotopy, "inertia_homotopy"},
    {AttemptStart::UnconstrainedOptimum, "unconstrained_optimum"},
    {AttemptStart::PreviousAttempt, "previous_attempt"},
    {AttemptStart::EigenaxisSlew, "eigenaxis_slew"},
    {AttemptStart::Excursion, "excursion"},
    {AttemptStart::ConstrainedMinimumEffort, "constrained_minimum_effort"},
};

/// How the problem was posed to the solver of an attempt.
enum class Formulation {
  Unconstrained,  ///< Newton on the reduced problem (no node constraints)
  FreeSlacks,     ///< interior point, c(x) − s = 0 with s > 0
  Elastic,        ///< interior point, ℓ1-elastic: elastic variables with a penalty
};
inline constexpr NamedValue<Formulation> kFormulationNames[] = {
    {Formulation::Unconstrained, "unconstrained"},
    {Formulation::FreeSlacks, "free_slacks"},
    {Formulation::Elastic, "elastic"},
};

/// How an attempt's Newton steps were globalized (step control).
enum class Globalization {
  TrustRegion,  ///< Levenberg–Marquardt shift, Nielsen's update (Newton's default)
  LineSearch,   ///< the least definite shift, then backtracking (Armijo)
};
inline constexpr NamedValue<Globalization> kGlobalizationNames[] = {
    {Globalization::TrustRegion, "trust_region"},
    {Globalization::LineSearch, "line_search"},
};

/// The class a request asks for (its direction and extra revolutions).
inline HomotopyClass homotopyClassOf(const PlanningProblem& problem) {
  return {problem.direction == RotationDirection::LongWay, problem.extra_revolutions};
}

/// Whether a and b are one class: the same way round and the same extra turns.
inline bool sameHomotopyClass(const HomotopyClass& a, const HomotopyClass& b) {
  return a.long_way == b.long_way && a.extra_revolutions == b.extra_revolutions;
}

/// `problem` asking for class `homotopy` (its direction and extra revolutions; the inverse of
/// homotopyClassOf).
inline PlanningProblem pinnedToClass(PlanningProblem problem, const HomotopyClass& homotopy) {
  problem.direction = homotopy.long_way ? RotationDirection::LongWay : RotationDirection::Shortest;
  problem.extra_revolutions = homotopy.extra_revolutions;
  return problem;
}

/// The parameters of an attempt's start, structured (JSON `attempts[i].start_detail`, PlanAttempt's
/// `start_detail`): what the message's start name ("excursion 0.3 rad about [0, 0.707, 0.707]",
/// "coarse grid (N = 64, ...)") is rendered from. Filled by minimum time's free-time solves and
/// its search; every field keeps its "none" value where it does not apply.
struct StartDetail {
  /// T [s] the start was posed at (minimum time: the structured start's first T, a refined
  /// level's coarser T*, the search's T for its plan; the search's probes: their first T); NaN:
  /// the request's own duration.
  double duration = std::numeric_limits<double>::quiet_NaN();
  /// The rotation axis of the eigenaxis slew the start was built on, body frame, unit (minimum
  /// time's eigenaxis and excursion starts); zero: none.
  Vector3 eigenaxis = Vector3::Zero();
  /// Excursion: the body-frame axis it turns about (unit, ⟂ `eigenaxis`) and its size [rad]
  /// (R(t) = R_0 exp(θ(s) ê) exp(ε sin²(πs) p̂), minimum_time_starts.hpp); zero: none.
  Vector3 excursion_axis = Vector3::Zero();
  double excursion = 0.0;
  /// Excursion: the fraction s = t/T where its bump peaks (sin²(π s^a), a = ln ½ / ln peak):
  /// ½ for the symmetric ones, 0.4 for those skewed in time around cones; ½ also where there is
  /// no excursion.
  double excursion_peak = 0.5;
  /// The start was replaced by the minimum-effort plan under the cones from it (a free-time start
  /// must clear its cones strictly: coneClearStart).
  bool cleared_of_cones = false;
  /// CoarseLevel: N of the coarser grid whose answer started it; 0: none.
  int coarse_steps = 0;
  /// CoarseLevel with coarse_steps > 0: the start of the coarsest grid's solve the refinement
  /// descends from (its eigenaxis, excursion and cone clearing are carried above); else unused
  /// (JSON and msg write the attempt's own start).
  AttemptStart origin = AttemptStart::Hermite;
  /// Pointing end condition: the twist ψ [rad] about the boresight the start was posed at
  /// (planning/pointing.hpp); NaN: none.
  double twist = std::numeric_limits<double>::quiet_NaN();
  /// Minimum time with spinning ends: the free-time solve's elastic phase, where it had one,
  /// began at a barrier μ on the scale of the start's violations, not at μ₀ (the second solve
  /// from the same start: ElasticBarrier::FromViolations, free_time_solver.hpp).
  bool elastic_from_violations = false;
};

/// One solve the planner ran for a request (PlanResult::attempts, JSON `attempts`), in the order
/// the attempts ended: the structured trail from which the message is rendered.
struct Attempt {
  AttemptStage stage = AttemptStage::Solve;
  AttemptStart start = AttemptStart::Hermite;
  Formulation formulation = Formulation::Unconstrained;
  /// Newton's step control (interior-point attempts leave the default).
  Globalization globalization = Globalization::TrustRegion;
  HomotopyClass homotopy;  ///< the class its start was in
  int steps = 0;           ///< N of the grid it solved on (its finest level; a class survey's grid)
  Termination termination = Termination::NotConverged;
  int iterations = 0;  ///< iterations of this attempt, its coarser grid levels included
  /// The scheme's Σ ½ w_k |τ_k|² of its plan [N²·m²] at `steps` (a class survey: on its coarser
  /// grid, comparable only with the other classes' surveys); NaN when it left no plan.
  double cost = std::numeric_limits<double>::quiet_NaN();
  bool kept = false;         ///< its plan is the one returned
  StartDetail start_detail;  ///< its start's parameters (where the start has any)
  /// false: its solver converged, but its plan was not kept and the check every plan kept passes
  /// (planInconsistency: the equations of motion step by step) was not run on it.
  bool plan_checked = true;
};

/// The extremal a solve returned, structured: its homotopy class, the rotation its start turned
/// through (angle about axis, from R_1 to R_{N−1}), and the other attempts it was chosen among.
/// PlanResult::extremal is rendered from it (describeExtremal).
struct ExtremalSummary {
  bool known = false;  ///< false: no extremal was described (e.g. NLopt, or no plan)
  HomotopyClass homotopy;
  double angle = 0.0;               ///< |lift| [rad], extra turns included
  Vector3 axis = Vector3::UnitX();  ///< the lift's axis (frame of R_1)
  /// The attempts it was chosen among (the cheapest converged is kept), with their costs.
  std::vector<Attempt> others;
};

/// "solve", "class_survey", ... (JSON, tests).
std::string attemptStageName(AttemptStage stage);
/// "hermite", "coarse_level", ... (JSON, tests).
std::string attemptStartName(AttemptStart start);
/// "unconstrained", "free_slacks", "elastic" (JSON, tests).
std::string formulationName(Formulation formulation);
/// "trust_region", "line_search" (JSON, tests).
std::string globalizationName(Globalization globalization);
/// The start an attempt descends from: StartDetail::origin for a refinement of a coarser grid's
/// answer (coarse_steps > 0), else the attempt's own start (JSON and msg `start_detail.origin`).
AttemptStart originOf(const Attempt& attempt);
/// PlanResult::extremal, e.g. "nearest lift: 3.14159 rad about [1, 0, 0] from R_1 to R_{N-1}",
/// then the others' costs: the one place the structure becomes prose.
std::string describeExtremal(const ExtremalSummary& extremal);

/// minimum_time: how T* was found. A KKT point: one free-time interior-point solve (T = N h an
/// unknown, src/planning/interior_point/free_time_solver.hpp) ended with these residuals of the
/// discrete minimum-time problem (unknowns δ and η = h/h₀, objective T/T₀); else T* is the least
/// duration a search over minimum-effort solves found feasible (an upper bound).
struct MinimumTimeCertificate {
  bool kkt_point = false;
  double stationarity = 0.0;       ///< max-norm of ∇(T/T₀) − Σ zᵢ∇cᵢ over (δ, η)
  double time_stationarity = 0.0;  ///< its η row alone
  double complementarity = 0.0;    ///< Σ zᵢcᵢ (the duality gap, relative to T₀)
  int solves = 0;                  ///< free-time solves run (one per start)
  /// Starts cleared of the cones by a minimum-effort solve under the cones alone (a start, not
  /// an attempt: in no attempt of the trail), their interior-point iterations (within the
  /// request's), and how many of them ended at a plan an earlier clearing reached (joined).
  int cone_clearings = 0;
  int cone_clearing_iterations = 0;
  int cone_clearings_joined = 0;
  /// With kkt_point: the reduced Hessian on the tangent of the active constraints is positive
  /// definite there (a strict local minimum of the discrete problem); false: a saddle or a
  /// degenerate KKT point (FreeTimeOutcome::second_order_sufficient).
  bool second_order_sufficient = false;
};

/// What backs a verdict on durations (bounded requests, minimum time): a proven lower bound on
/// the duration any plan needs, and the least duration at which this request found a plan. An
/// "infeasible" answer rests on one of them, and says which (docs/design/planner_behaviour.md).
struct DurationVerdict {
  /// T_c [s]: no plan of the continuous problem is shorter (proven from the momentum the torque
  /// bounds allow and the angle to turn; the grid is held to it within O(h)); 0: none applies.
  double lower_bound = 0.0;
  std::string lower_bound_basis;  ///< how lower_bound is proven (empty with none)
  /// The figures of that proof (lower_bound_basis renders them): the rate limit w [rad/s] and the
  /// largest torque magnitude a [N m] the torque bounds allow; 0 where none bounds it.
  double rate_limit = 0.0;
  double torque_limit = 0.0;
  /// The answer "infeasible" is proven (the request's T is below lower_bound on its grid), not
  /// the local verdict of a solve.
  bool proven_infeasible = false;
  /// The least T [s] at which a plan meeting the bounds was found (a local minimum-time plan:
  /// not a requirement); 0: none was found or sought.
  double least_duration_found = 0.0;
  /// With spinning ends, a request's T above the durations at which plans were found from the
  /// minimum-time plan: the longest T [s] at which one was (where the ladder of durations from
  /// T* stopped: not a limit); 0: none was sought.
  double longest_duration_found = 0.0;
  /// Bounded minimum effort: the returned plan meets the dynamics, the ends and every bound at
  /// the requested T, checked step by step (true for every converged answer; an answer that
  /// stopped short of optimality may still hold a plan at T, not shown optimal).
  bool plan_within_bounds = false;
  /// Durations proven to hold no plan on the request's grid [s], no_plan_from to no_plan_to: the
  /// paper scheme's last free step into a final rate on the rate limit has no room there (its
  /// least rate over the allowed torques exceeds the limit at every step h in the range); 0, 0:
  /// none proven. Minimum time answers `infeasible` where the range covers every duration the
  /// grid holds, and a bounded minimum-effort request whose T lies in it before any solve.
  double no_plan_from = 0.0;
  double no_plan_to = 0.0;
};

/// What a pointing request's "infeasible" rests on (PointingSummary::infeasible_basis, JSON
/// `pointing.infeasible_basis`; pointingInfeasibleBasis is the rule).
enum class PointingInfeasibleBasis {
  None,  ///< the answer is not "infeasible"
  /// The interior point's verdicts at the start twists and ways round tried, and no check over
  /// the twist (cones and rate limits without a torque bound): local, another twist may admit a
  /// plan.
  LocalToStarts,
  /// Minimum time with the twist free under the same bounds (a torque bound present) found its
  /// least T above the request's (a local T*: DurationVerdict::least_duration_found) or none.
  MinimumTimeOverTwist,
  /// Proven: T below a proven lower bound, or no duration admits a plan.
  Proven,
};
inline constexpr NamedValue<PointingInfeasibleBasis> kPointingInfeasibleBasisNames[] = {
    {PointingInfeasibleBasis::None, "none"},
    {PointingInfeasibleBasis::LocalToStarts, "local_to_starts"},
    {PointingInfeasibleBasis::MinimumTimeOverTwist, "minimum_time_over_twist"},
    {PointingInfeasibleBasis::Proven, "proven"},
};
/// "none", "local_to_starts", ... (JSON).
std::string pointingInfeasibleBasisName(PointingInfeasibleBasis basis);

/// A pointing end condition's answer (PlanningProblem::end_condition); `active` false otherwise.
struct PointingSummary {
  bool active = false;
  /// ψ [rad] chosen: R_N = R_ref(b, d) exp(ψ b^) (planning/pointing.hpp: pointingReference).
  double final_twist = 0.0;
  /// The end condition's residual: angle(R_N b, d) [rad] on the returned maneuver's R_N.
  double error = 0.0;
  /// The Lagrangian's ∂L/∂ψ at the answer: unconstrained minimum effort ∂C/∂ψ [N²·m²/rad];
  /// with stage constraints or torque bounds ∂L/∂ψ, L = C − Σ zᵢcᵢ [N²·m²/rad]; minimum time
  /// ∂L/∂ψ of L = T/T₀ + εC − Σ zᵢcᵢ [1/rad] (T₀ the free-time start's duration, ε → 0).
  double twist_gradient = 0.0;
  /// |twist_gradient| relative: minimum effort as max_residual is (to max|∂τ/∂δ|·max|τ|),
  /// minimum time as the free-time residuals are (already relative to T₀): the stationarity in ψ.
  double twist_stationarity = 0.0;
  int starts = 0;  ///< twist × class starts surveyed
  /// What an "infeasible" answer rests on (set for every pointing request, `active` or not).
  PointingInfeasibleBasis infeasible_basis = PointingInfeasibleBasis::None;
};

/// Which torques the effort a plan minimizes is made of (JSON `reaction_wheels.effort_minimized`,
/// ReactionWheelsSummary.effort_minimized). With reaction wheels the two differ: the body torque τ
/// the array exerts, or the wheels' own torques u (A u = −(τ + Ω × A h_w)).
enum class MinimizedEffort {
  BodyTorque,   ///< Σ ½ w_k |τ_k|², τ_k the torque on the body
  WheelTorque,  ///< Σ ½ w_k |u_k|², u_k the wheels' torques
};
inline constexpr NamedValue<MinimizedEffort> kMinimizedEffortNames[] = {
    {MinimizedEffort::BodyTorque, "body_torque"},
    {MinimizedEffort::WheelTorque, "wheel_torque"},
};
/// "body_torque", "wheel_torque" (JSON, messages).
std::string minimizedEffortName(MinimizedEffort effort);

/// What a solve returns: the plan, how the solve ended (`termination`, explained by `message`),
/// and the figures that judge it.
struct PlanResult {
  Termination termination = Termination::NotConverged;
  bool converged() const { return termination == Termination::Converged; }
  /// Human-readable explanation of `termination`: the fold of `clauses`, rendered on each call
  /// (renderClauses, src/planning/problem/message_notes). There is no other copy of the words: a
  /// solver or driver records clauses, never a message.
  std::string message() const;
  /// The message as data, in the order its clauses were recorded: the solver's words or verdict,
  /// the notes after it, the frames around it (message_clauses.hpp).
  std::vector<MessageClause> clauses;
  /// A driver's verdict as data (kind and figures; JSON `verdict`): where a driver answered
  /// (before any solve, a local "infeasible", the search's end, ...), its first clause of
  /// `message` is rendered from it (recordVerdict); SolverReason where a solver's reason stands.
  /// The clauses may hold the verdicts of the solves its reason came from too.
  Verdict verdict;
  /// Every solve run for this request, in order (the trail); the kept one has `kept`.
  std::vector<Attempt> attempts;
  /// The grid levels solved, coarsest first (continuation); empty for solvers without levels.
  std::vector<LevelSummary> levels;
  std::string solver;  ///< "newton" or "nlopt"
  SchemeKind scheme = SchemeKind::Paper;
  /// R_k, Ω_k, τ_k, k = 0..N: the plan itself (Newton, interior point: the solver's attitudes,
  /// their velocities and torques; NLopt: its torques replayed).
  Maneuver maneuver;
  double duration = 0.0;  ///< T [s] of the returned plan (minimum_time: chosen by the planner)
  /// T* [s]: the least duration found feasible (objective minimum_time; else 0).
  double minimum_duration = 0.0;
  /// minimum_time: what backs T* (the free-time interior point's KKT residuals, or the search).
  MinimumTimeCertificate minimum_time;
  /// Bounded requests: what backs a verdict on the duration (DurationVerdict).
  DurationVerdict duration_verdict;
  /// Σ_k ½ w_k |τ_k|² [N²·m²]: the scheme's own objective (w_k = 1, k = 1..N−1, for paper and
  /// variational, as in the seed; second_order: k = 0..N with w_0 = w_N = ½; fourth_order:
  /// Gregory's end-corrected weights, schemeTorqueWeight).
  double cost = 0.0;
  /// h · cost [N²·m²·s]: the scheme's quadrature of ½∫₀ᵀ|τ|²dt, comparable across schemes and
  /// with the continuous optimum.
  double effort = 0.0;
  /// Which torques `cost` sums and the objective minimizes (minimum effort; minimum time's effort
  /// term and its time_margin plan): set by planManeuver from the transcription's cost
  /// (ReducedProblem::kMinimizedEffort), which every writer reads from here.
  MinimizedEffort minimized_effort = MinimizedEffort::BodyTorque;
  int iterations = 0;  ///< Newton iterations, coarser continuation levels included
  /// First-order optimality residual at the end: max-norm of ∇C relative to |∂τ/∂R|·max|τ|
  /// (the interior point: of the KKT stationarity residual ∇C − Σ zᵢ∇cᵢ with its multipliers).
  double max_residual = 0.0;
  /// Newton: √(gᵀH⁻¹g)/|τ|₂ of the last iteration, ≈ the relative ℓ2 torque error before the
  /// final step (the convergence test); NLopt: 0.
  double newton_decrement = 0.0;
  double dynamics_residual = 0.0;  ///< worst implicit-step residual on replay [N·m·s]
  /// Worst residual of the discrete equations of motion and boundary data on the returned
  /// maneuver, step by step, relative to the problem's scales (measureStepResidual); part of
  /// the convergence verdict.
  double step_residual = 0.0;
  double terminal_attitude_error = 0.0;  ///< ‖log(R_N*ᵀ R_N)‖ [rad] of the replayed maneuver
  /// |Ω_N − Ω(T)| [rad/s] of the replay (Ω_N = Ω_{N−1} for paper and variational)
  double terminal_velocity_error = 0.0;
  /// max(terminal_attitude_error, T·terminal_velocity_error) [rad]: how far the planned torques,
  /// replayed open-loop from R_0, Ω_0 through the same integrator, end from the target. A
  /// sensitivity of the maneuver (round-off grows like e^{λT} on unstable motions), reported,
  /// never a reason to refuse an optimum; +inf where the replay parted so far that a step had no
  /// root while every step replayed from the plan's own state lands on it (judgeFailedReplay).
  double replay_miss = 0.0;
  /// false: the open-loop replay was not run, so dynamics_residual, terminal_attitude_error,
  /// terminal_velocity_error and replay_miss are NaN (not measured). A plan stopped by its time
  /// budget or its caller (TimedOut, Cancelled) is handed over without it: at N = 1e5 the replay
  /// took 0.10–0.14 s of a hand-over that a cancel waits 30 ms for; the stopped plan is judged
  /// by step_residual and max_residual, measured as always.
  bool replay_measured = true;
  double solve_time_s = 0.0;           ///< wall time [s]
  std::vector<IterationInfo> history;  ///< one entry per iteration
  /// Which extremal was found, e.g. "short way: 3.14159 rad about [1, 0, 0]" (Newton), with the
  /// cost of the other way when both were solved.
  std::string extremal;
  /// The same, structured (Newton; `known` false for the other solvers).
  ExtremalSummary extremal_summary;
  /// The effects in the planning model (scene keys), in order; "actuator_limits" last when the
  /// control torques are bounded.
  std::vector<std::string> effects;
  /// The accuracy of the plan when PlanningProblem::accuracy was given (requested = true).
  AccuracyEstimate accuracy;
  /// The node constraints in force (scene keys, in order; "actuator_limits" first when bounded).
  std::vector<std::string> constraints;
  /// Worst violation over all nodes and constraints, each in its own unit (N m, rad/s, rad), ≥ 0,
  /// measured on the returned maneuver (checkConstraints).
  double max_constraint_violation = 0.0;
  /// The same over the continuous motion between the nodes too (R_k exp(s ω_k^), torques held):
  /// what a cone's `margin` is for (checkConstraints), ≥ max_constraint_violation.
  double max_violation_between_nodes = 0.0;
  /// Node constraints at their bound (within kActiveConstraintTolerance relative) on the result.
  int active_constraints = 0;
  /// Interior-point plans under per-axis torque bounds: the discrete PMP switching function
  /// σ_k = τ_k + (z⁺_k − z⁻_k)/(a w_k) per axis [N m], k = 0..N (z± the multipliers of the upper
  /// and lower bound, a the bound, w_k the cost weight): the minimizer of the Lagrangian in τ_k
  /// without the bound, so τ_k = sat(σ_k) at a KKT point, and a bang–bang plan switches where σ_k
  /// changes sign. A minimum-time answer (free-time solve) carries minimum time's own:
  /// σ_k = (z⁺_k − z⁻_k)/(a w_k) (dimensionless, the multipliers of T/T₀), τ_k = ±a where σ_k ≷ 0,
  /// crossing zero at a switch. Empty otherwise.
  std::vector<Vector3> switching_function;
  /// The twist chosen and the end condition's residual for a pointing request.
  PointingSummary pointing;
};

}  // namespace attitude_planner
