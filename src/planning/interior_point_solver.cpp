// Primal–dual interior-point Newton method for the discrete problem with node constraints
// (per-axis torque bounds, torque norm, angular rate, keep-out / keep-in cones), O(N) per
// iteration on the reduced problem's band (reduced_problem.hpp), for every scheme. With end
// torques (second_order) the torque constraints hold at k = 0..N too, the stencils carry the
// residuals √w_k τ_k (constraints act on τ_k), and rates are node rates J⁻¹Π_k through the node
// momentum's stencil (ReducedProblem::forEachNodeMomentum).
//
// Every constraint is stage-local in the reduced unknowns δ_j (R_j → R_j exp(δ_j^)): a torque
// constraint depends on R_{k−1}, R_k, R_{k+1} (τ_k's stencil), a rate constraint on F_k =
// R_kᵀR_{k+1}, a cone on R_k. Each is written dimensionless as c_i(δ) ≥ 0:
//   torque box   1 ∓ τ_{k,a}/a_a          torque norm   1 − |τ_k|²/t²
//   rate         1 − |Ω_k|²/w²            keep_out      cos α − sᵀR_k b      keep_in  sᵀR_k b − cos
//   α
//
// Elastic (ℓ1) formulation, so that every iterate has a finite merit and an infeasible request
// ends at a certificate instead of an endless restoration (as IPOPT's restoration phase and
// Curtis's penalty–interior-point method do):
//   min f(δ) + ρ Σ v_i   s.t.  c_i(δ) + v_i − s_i = 0,  s, v ≥ 0,     f = Σ ½|τ_k|²,
// barrier μ; with multipliers z (of s) and u = ρ − z (of v), the Newton step condenses
// (per constraint, D_i = s_i/z_i + v_i/u_i) to
//   (W + Σ_i g_i g_iᵀ / D_i) dδ = −∇f + Σ_i g_i (z_i + q_i/D_i),   q_i = μ/z_i − s_i − μ/u_i + v_i,
//   W = ∇²f − Σ_i z_i ∇²c_i,  g_i = ∇c_i,  dz_i = (q_i − g_iᵀdδ)/D_i.
// Each g_i g_iᵀ lies inside one stencil's 9×9 block, so the system keeps the unconstrained
// Hessian's band (half bandwidth 8) and is factored by the same banded Cholesky; above N = 1024
// in extended precision (long double, and double-double arithmetic above N = 8192), each
// g_i g_iᵀ formed in it (kExtendedPrecisionAboveSteps). The slacks are eliminated exactly for
// the current c (node_constraints.hpp: elasticSlacks), so the merit
// φ_μ(δ) = f + Σ ψ_μ(c_i) depends on δ alone; the line search is Armijo on φ_μ along the
// retraction, and the dual step keeps z and u positive (fraction to the boundary, τ = 0.99).
// Inertia correction: a multiple of the identity until the Cholesky factorization succeeds.
//
// The free-slack form (Formulation::FreeSlacks, as IPOPT): c(δ) − s = 0 with s > 0 free
// variables, the same condensation with D = s/z, q = μ/z − c (so ds = gᵀdδ + c − s), merit
// f − μ Σ ln s + ν‖c − s‖₁, fraction to the boundary on s and z. Its Hessian carries Newton's own
// multipliers instead of z → ρ for violated constraints, which is where the elastic form stalls.
// A grid level is solved in the free-slack form first, its barrier chosen at every iteration by
// Mehrotra's predictor–corrector (the affine step μ = 0 from the same Cholesky factor gives
// σ = (μ_aff/mean s z)³, the corrector adds ds_aff·dz_aff to the complementarity target), and
// retried in the elastic form if it ends infeasible or unconverged; the minimum-time search's
// feasibility probes take the elastic form first and the free-slack retry keeps a monotone
// barrier (solveOnGridWithRetry).
//
// Elastic barrier update: LOQO's adaptive rule after every iteration (see the loop). At μ_final a
// full step with decrement below the tolerance (or quadratic convergence seen well below the
// stall acceptance) ends the solve; then the elastic violations are v ≈ μ/ρ if the
// constraints can be met. If they cannot at ρ, ρ grows once by kPenaltyGrowth; if they still
// cannot, the request is answered as infeasible, naming the constraint the last iterate still
// violates.
//
// Between nodes: the constraints hold at the nodes only. Within step k the continuous motion
// R_k exp(s ω_k^), s ∈ [0, 1], turns at the constant rate ω_k/h (paper scheme), so a rate limit
// holds between nodes too, and torques are held over a step, so their bounds hold throughout; a
// cone's angle can dip past its bound within a step by up to a − acos(cos a + |ω_k|²/8): the
// cones are imposed at their node half angle, tightened by the user's margin
// (constraints.hpp: requiredConeMargin).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "planning/multiplier_estimate.hpp"
#include "planning/node_constraints.hpp"
#include "planning/reduced_problem.hpp"
#include "planning/solvers.hpp"

namespace attitude_planner {

namespace {

/// Fraction to the boundary τ (IPOPT's τ_min).
constexpr double kFractionToBoundary = 0.99;
/// Initial barrier × f_scale/m: the barrier terms start as large as the cost.
constexpr double kMuStart = 1.0;
/// Dual safeguard: z stays within [μ/(κ_Σ s), κ_Σ μ/s] (IPOPT's κ_Σ).
constexpr double kDualSafeguard = 1e10;
/// Penalty ρ relative to f_scale: far above the multipliers met in practice (a binding node
/// constraint's z is ~ f/N); raised once by kPenaltyGrowth before a request is called infeasible.
constexpr double kInitialPenalty = 1e4;
constexpr double kPenaltyGrowth = 1e4;
/// Initial barrier (× f_scale/m) on a grid started from a coarser grid's solution.
constexpr double kWarmBarrier = 1e-3;
/// Grid continuation (as the Newton solver's): above this N the constrained problem is first
/// solved on a 4× coarser grid.
constexpr int kCoarsestConstrainedGrid = 256;
/// Relative decrement below which a stall at the final barrier counts as converged (at
/// N ≤ 1024; above, it grows like N: measured floors 9e-7 at N = 2048, 2e-6 at N = 8192).
constexpr double kStallAcceptance = 1e-6;
/// Iterations without any reduction of a nonzero violation after which it counts as stalled (the
/// free-slack form's iterates may violate the constraints more for a while on their way: it
/// gets longer).
constexpr int kViolationStall = 8;
constexpr int kFreeSlackViolationStall = 40;
/// Largest relative diagonal shift tried after failed line searches (1e-8, 1e-6, ..., 1e-2).
constexpr double kMaxShiftFloor = 1e-2;
/// Largest violation at which the penalty is raised before a request is called infeasible.
constexpr double kPenaltyRaiseViolation = 1e-3;
/// Above this N the final barrier grows like N (see mu_final).
constexpr int kFinalBarrierRoundOffSteps = 2048;
/// Most halvings of the line search; at the round-off floor (final barrier, feasible, decrement
/// ≤ 10× the stall acceptance) fewer.
constexpr int kMaxHalvings = 60;
constexpr int kFloorHalvings = 5;
/// The barrier never falls below this × (relative decrement)² × cost/m (see the predictor).
constexpr double kBarrierProgressFloor = 0.01;
/// Free slacks start at c pushed inside s > 0 by this (IPOPT's κ₁ push).
constexpr double kSlackPush = 1e-2;
/// A finer level started from a coarser level's duals pushes a binding constraint's slack at
/// most this far inside (kSlackPush would undo the warm start).
constexpr double kWarmSlackPush = 1e-6;
/// An inertia correction (relative shift) this small is round-off, not a change of the step.
constexpr double kNegligibleShift = 1e-12;
/// A slack residual |c − s| below this (a hundredth of the feasibility tolerance) is round-off,
/// not infeasibility: it does not count in the free-slack form's decrement.
constexpr double kRoundOffSlackResidual = 1e-10;
/// Elastic violation (constraint units: relative torque/rate, cosine) that counts as infeasible.
constexpr double kFeasibilityTolerance = kNodeConstraintTolerance;

enum class Family { TorqueUpper, TorqueLower, TorqueNorm, AngularRate, KeepOut, KeepIn };

/// How the constraints c(δ) ≥ 0 enter the Newton system (see the header comment).
enum class Formulation {
  /// ℓ1-elastic, the slacks eliminated for the current c: every iterate has a finite merit and a
  /// stalled violation is a certificate of (local) infeasibility; but a violated constraint's
  /// multiplier tends to ρ, and ρ∇²c then dominates the Hessian.
  Elastic,
  /// IPOPT's: c(δ) − s = 0 with the slacks s > 0 free variables and the multipliers Newton's own
  /// estimates, merit f − μ Σ ln s + ν ‖c − s‖₁. Iterates may violate c; the Hessian carries
  /// only the true multipliers, so Newton converges where the elastic form's curvature stalls.
  FreeSlacks,
};

/// One node constraint c(δ) ≥ 0 and its primal–dual state.
struct Instance {
  double c = 0.0;                 ///< value (dimensionless)
  Eigen::Matrix<double, 9, 1> g;  ///< ∂c/∂δ over the group's local nodes
  double z = 0.0;                 ///< multiplier of c + v − s = 0 (0 < z < ρ)
  double s = 0.0, v = 0.0;        ///< slacks (Elastic: elasticSlacks of c; FreeSlacks: s free)
  double D = 1.0, q = 0.0;        ///< condensation terms (see the header comment)
  double ds = 0.0;                ///< FreeSlacks: the slack's Newton step
};

/// All node constraints of one kind (one axis and sign of the torque box, or one spec).
struct Group {
  Family family;
  int axis = 0;        ///< torque box axis
  double limit = 0.0;  ///< a_axis, t or w
  const PlanningConstraint* spec = nullptr;
  int first_k = 0, last_k = 0;  ///< instances k = first_k..last_k
  int node_offset = 0;          ///< first local node = k + node_offset
  int width = 1;                ///< local nodes (3: torque stencil, 2: step, 1: node)
  std::vector<Instance> at;     ///< at[k − first_k]
  Instance& instance(int k) { return at[k - first_k]; }
};

/// A grid level's multipliers z and slacks s (free-slack form), per group and instance, to start
/// the next finer level from (carried by the instances' times).
struct LevelDuals {
  int steps = 0;
  std::vector<int> first_k;
  std::vector<std::vector<double>> z, s;
  bool empty() const { return steps == 0; }
};

bool isTorqueFamily(Family f) {
  return f == Family::TorqueUpper || f == Family::TorqueLower || f == Family::TorqueNorm;
}

/// Where a local 9-vector over nodes first_node..first_node+width−1 sits among the unknowns:
/// its offset and its free entries first..last−1 (fixed nodes skipped).
struct LocalSlots {
  int offset = 0, first = 0, last = 0;
  bool empty() const { return first >= last; }
};

LocalSlots localSlots(const ReducedProblem& np, int first_node, int width) {
  const int first_free = std::max(0, np.firstFreeNode() - first_node);
  const int last_free = std::min(width - 1, np.lastFreeNode() - first_node);
  return {3 * (first_node - np.firstFreeNode()), 3 * first_free, 3 * (last_free + 1)};
}

/// Adds M (local 9×9, lower triangle used) to the banded Hessian.
template <typename Scalar>
void addLocal(const ReducedProblem& np, BandedSymmetric<Scalar>* H, int first_node, int width,
              const Eigen::Matrix<double, 9, 9>& M) {
  const LocalSlots l = localSlots(np, first_node, width);
  if (!l.empty()) H->template addSymmetricBlock<9>(l.offset, M, l.first, l.last);
}

/// Adds weight·g gᵀ (local) to the banded Hessian, each product formed in its own precision (see
/// kExtendedPrecisionAboveSteps). Rounding the weight only scales the term.
template <typename Scalar>
void addLocalRankOne(const ReducedProblem& np, BandedSymmetric<Scalar>* H, int first_node,
                     int width, const Eigen::Matrix<double, 9, 1>& g, double weight) {
  const LocalSlots l = localSlots(np, first_node, width);
  if (!l.empty()) H->template addRankOne<9>(l.offset, g, weight, l.first, l.last);
}

/// gᵀ dδ over the local nodes (fixed nodes contribute nothing).
double localDot(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g, int first_node,
                int width, const Eigen::VectorXd& d) {
  double sum = 0.0;
  for (int n = 0; n < width; ++n) {
    const int v = np.variableIndex(first_node + n);
    if (v >= 0) sum += g.segment<3>(3 * n).dot(d.segment<3>(v));
  }
  return sum;
}

void addLocalVector(const ReducedProblem& np, const Eigen::Matrix<double, 9, 1>& g, double weight,
                    int first_node, int width, Eigen::VectorXd* out) {
  for (int n = 0; n < width; ++n) {
    const int v = np.variableIndex(first_node + n);
    if (v >= 0) out->segment<3>(v) += weight * g.segment<3>(3 * n);
  }
}

class InteriorPoint {
 public:
  InteriorPoint(const PlanningProblem& problem, ReducedProblem* np, Formulation formulation)
      : problem_(problem),
        np_(*np),
        free_slacks_(formulation == Formulation::FreeSlacks),
        node_rates_(np->scheme().hasEndTorques()),
        inverse_inertia_(problem.inertia.inverse()),
        inverse_inertia_squared_(inverse_inertia_ * inverse_inertia_) {
    // The torques are k = first..last (1..N−1; 0..N with end torques), the free attitudes
    // first + 1..last − 1. Rates: per step (the step's own velocity) for paper and variational,
    // whose first and last steps are boundary data; per node (J⁻¹Π_k, k = 1..N−1) for schemes
    // with end torques, whose node velocities are the plan's.
    const int first = np_.firstFreeNode() - 1, last = np_.lastFreeNode() + 1;
    const auto add = [&](Family family, int first_k, int last_k, int node_offset, int width) {
      Group g;
      g.family = family;
      g.first_k = first_k;
      g.last_k = last_k;
      g.node_offset = node_offset;
      g.width = width;
      g.at.resize(last_k - first_k + 1);
      groups_.push_back(g);
      return &groups_.back();
    };
    if (problem.hasTorqueBounds()) {
      for (int a = 0; a < 3; ++a) {
        for (Family f : {Family::TorqueUpper, Family::TorqueLower}) {
          Group* g = add(f, first, last, -1, 3);
          g->axis = a;
          g->limit = problem.max_torque(a);
        }
      }
    }
    for (const PlanningConstraint& c : problem.constraints) {
      Group* g = nullptr;
      switch (c.kind) {
        case ConstraintKind::MaxTorqueNorm:
          g = add(Family::TorqueNorm, first, last, -1, 3);
          break;
        case ConstraintKind::MaxAngularRate:
          g = node_rates_ ? add(Family::AngularRate, first + 1, last - 1, -1, 3)
                          : add(Family::AngularRate, first, last - 1, 0, 2);
          break;
        case ConstraintKind::KeepOut:  // the fixed attitudes are checked up front
          g = add(Family::KeepOut, first + 1, last - 1, 0, 1);
          break;
        case ConstraintKind::KeepIn:
          g = add(Family::KeepIn, first + 1, last - 1, 0, 1);
          break;
      }
      g->spec = &c;
      g->limit = c.limit;
    }
    for (const Group& g : groups_) constraint_count_ += static_cast<int>(g.at.size());
  }

  int constraintCount() const { return constraint_count_; }
  std::vector<Group>& groups() { return groups_; }
  bool freeSlacks() const { return free_slacks_; }

  /// Constraint values at `steps` into each instance's c (gradients not formed).
  void evaluateValues(const ReducedProblem::Steps& steps, std::vector<Vector3>* torques_out) {
    const std::vector<Vector3> tau = np_.torques(steps);
    std::vector<Matrix3> R;
    for (Group& g : groups_) {
      if ((g.family == Family::KeepOut || g.family == Family::KeepIn) && R.empty()) {
        R = np_.attitudes(steps);
      }
      for (int k = g.first_k; k <= g.last_k; ++k) {
        Instance& in = g.instance(k);
        switch (g.family) {
          case Family::TorqueUpper:
            in.c = 1.0 - tau[k](g.axis) / g.limit;
            break;
          case Family::TorqueLower:
            in.c = 1.0 + tau[k](g.axis) / g.limit;
            break;
          case Family::TorqueNorm:
            in.c = 1.0 - tau[k].squaredNorm() / (g.limit * g.limit);
            break;
          case Family::AngularRate: {
            const Vector3 Omega =
                node_rates_ ? nodeVelocity(steps, k) : np_.scheme().velocity(so3::exp(steps[k]));
            in.c = 1.0 - Omega.squaredNorm() / (g.limit * g.limit);
            break;
          }
          case Family::KeepOut:
            in.c = std::cos(g.spec->nodeHalfAngle()) -
                   g.spec->world_direction.dot(R[k] * g.spec->body_axis);
            break;
          case Family::KeepIn:
            in.c = g.spec->world_direction.dot(R[k] * g.spec->body_axis) -
                   std::cos(g.spec->nodeHalfAngle());
            break;
        }
      }
    }
    if (torques_out) *torques_out = tau;
  }

  /// φ_μ = f + Σ ψ_μ(c_i) at `steps` (and f in *cost).
  double merit(const ReducedProblem::Steps& steps, double mu, double rho, double* cost,
               double slack_alpha = 0.0) {
    std::vector<Vector3> tau;
    evaluateValues(steps, &tau);
    const double f = np_.scheme().cost(tau);
    if (cost) *cost = f;
    return f + constraintMerit(mu, rho, slack_alpha);
  }

  /// The constraints' part of the merit at the current values c: Elastic Σ ψ_μ(c_i) (ρ the
  /// penalty); FreeSlacks Σ −μ ln s_i + ρ|c_i − s_i| (ρ the merit's ν) at s = s + α ds.
  double constraintMerit(double mu, double rho, double alpha) const {
    double phi = 0.0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) {
        if (free_slacks_) {
          const double s = in.s + alpha * in.ds;
          phi += -mu * std::log(s) + rho * std::abs(in.c - s);
        } else {
          phi += elasticSlacks(in.c, mu, rho).psi;
        }
      }
    }
    return phi;
  }

  /// φ_μ = f + Σ ψ_μ(c_i) from the constraint values of the last assembly (f = its cost).
  double assembledMerit(double cost, double mu, double rho) const {
    return cost + constraintMerit(mu, rho, 0.0);
  }

  /// Assembles the condensed Newton system at the current iterate: H, rhs, ∇φ_μ; returns f.
  /// `primal`: the multipliers are replaced by their primal values μ/s (then the step is Newton's
  /// on φ_μ, a descent direction whenever H is positive definite). H = null: the constraint
  /// values and gradients only (no second derivatives; multipliers and slacks untouched).
  template <typename Scalar>
  double assemble(double mu, double rho, bool primal, BandedSymmetric<Scalar>* H,
                  Eigen::VectorXd* rhs, Eigen::VectorXd* merit_gradient, double* gradient_scale) {
    const int n = np_.unknowns();
    if (H) H->setZero();
    rhs->setZero(n);
    merit_gradient->setZero(n);
    const ReducedProblem::Steps& steps = np_.current();
    // Slacks and (safeguarded or primal) multipliers for constraint value c.
    const auto prepare = [&](Instance& in) {
      if (!H) return;  // gradients only: the multipliers and slacks are left as they are
      if (free_slacks_) {
        // s is a variable: the multiplier stays near μ/s, and the condensation is that of
        // c − s = 0 (q = μ/z − c makes ds = gᵀdδ + c − s and dz = (q − gᵀdδ)/D).
        const double z_primal = mu / in.s;
        in.z = primal ? z_primal
                      : std::min(std::max(in.z, mu / (kDualSafeguard * in.s)),
                                 kDualSafeguard * z_primal);
        in.D = in.s / in.z;
        in.q = mu / in.z - in.c;
        return;
      }
      const ElasticSlacks sl = elasticSlacks(in.c, mu, rho);
      in.s = sl.s;
      in.v = sl.v;
      const double z_primal = mu / in.s;
      if (primal) {
        in.z = z_primal;
      } else {
        in.z = std::min(std::max(in.z, mu / (kDualSafeguard * in.s)), kDualSafeguard * z_primal);
        // u = ρ − z stays positive (u → 0 would make D and q infinite).
        const double u_min = std::max(mu / (kDualSafeguard * in.v), 1e-12 * rho);
        in.z = std::min(in.z, rho - u_min);
      }
      const double u = rho - in.z;
      in.D = in.s / in.z + in.v / u;
      in.q = mu / in.z - in.s - mu / u + in.v;
    };
    // Torque constraints: values and multipliers are needed for the stencil's second-order
    // weights (∇²f − Σ z ∇²c, all through ∂²τ_k), so they are formed in the weights callback.
    std::vector<Group*> torque_groups, other_groups;
    for (Group& g : groups_)
      (isTorqueFamily(g.family) ? torque_groups : other_groups).push_back(&g);
    std::vector<double> gauss_newton_factor;  // β_k = 1 + Σ_norm 2z/t², per stencil
    double jacobian_scale = 0.0, torque_scale = 0.0;
    // The stencils hold the residuals r_k = √w_k τ_k (w_k the cost weight, 1 but at the end
    // nodes of schemes with end torques): constraints are on τ_k = r_k/√w_k.
    const auto root = [&](int k) { return std::sqrt(np_.scheme().torqueWeight(k, np_.steps())); };
    const auto weights = [&](int k, const Vector3& residual) {
      const double r = root(k);
      const Vector3 tau = residual / r;
      Vector3 w = residual;
      double beta = 1.0;
      for (Group* g : torque_groups) {
        Instance& in = g->instance(k);
        if (g->family == Family::TorqueNorm) {
          in.c = 1.0 - tau.squaredNorm() / (g->limit * g->limit);
          prepare(in);
          // −z∇²c = (2z/t²) ∇²(½|τ|²) = factor ∇²(½|r|²)
          const double factor = 2.0 * in.z / (g->limit * g->limit * r * r);
          beta += factor;
          w += factor * residual;
        } else {
          const double sign = g->family == Family::TorqueUpper ? 1.0 : -1.0;
          in.c = 1.0 - sign * tau(g->axis) / g->limit;
          prepare(in);
          w(g->axis) += sign * in.z / (g->limit * r);  // −z∇²c = ±(z/a) ∇²τ_a = ±z/(a√w) ∇²r_a
        }
      }
      current_beta_ = beta;
      return w;
    };
    const double cost = np_.forEachStencil(
        H != nullptr,
        [&](const ReducedProblem::Stencil& st) {
          jacobian_scale = std::max(jacobian_scale, st.jacobian.cwiseAbs().maxCoeff());
          torque_scale = std::max(torque_scale, st.tau.cwiseAbs().maxCoeff());
          const Eigen::Matrix<double, 9, 1> grad_f = st.jacobian.transpose() * st.tau;
          const double r = root(st.k);
          for (Group* g : torque_groups) {
            Instance& in = g->instance(st.k);
            if (g->family == Family::TorqueNorm) {
              in.g = -2.0 / (g->limit * g->limit * r * r) * grad_f;
            } else {
              const double sign = g->family == Family::TorqueUpper ? 1.0 : -1.0;
              in.g = -sign / (g->limit * r) * st.jacobian.row(g->axis).transpose();
            }
          }
          if (H) {
            // Jᵀ diag(weight) J: the Gauss–Newton term β JᵀJ and the box constraints' g gᵀ/D
            // (g = ∓J_a/(a r)) per torque axis; the norm constraints' g gᵀ/D apart.
            Vector3 weight = Vector3::Constant(current_beta_);
            for (Group* g : torque_groups) {
              const Instance& in = g->instance(st.k);
              if (g->family == Family::TorqueNorm) {
                addLocalRankOne(np_, H, st.k - 1, 3, in.g, 1.0 / in.D);
              } else {
                weight(g->axis) += 1.0 / (in.D * (g->limit * r) * (g->limit * r));
              }
            }
            for (int a = 0; a < 3; ++a) {
              addLocalRankOne(np_, H, st.k - 1, 3, st.jacobian.row(a).transpose(), weight(a));
            }
            addLocal(np_, H, st.k - 1, 3, st.second);
          }
          addLocalVector(np_, grad_f, 1.0, st.k - 1, 3, merit_gradient);
          addLocalVector(np_, grad_f, -1.0, st.k - 1, 3, rhs);
        },
        torque_groups.empty() ? ReducedProblem::SecondOrderWeights() : weights);
    *gradient_scale = jacobian_scale * std::max(torque_scale, 1e-300);
    // Node rates (schemes with end torques): c = 1 − |J⁻¹Π_k|²/w², through the node momentum's
    // stencil: ∇c = −(2/w²) J_Πᵀ J⁻²Π, −z∇²c = (2z/w²)(J_Πᵀ J⁻² J_Π + Σ_i (J⁻²Π)_i ∇²Π_i).
    std::vector<Group*> node_rate_groups;
    if (node_rates_) {
      for (Group* g : other_groups)
        if (g->family == Family::AngularRate) node_rate_groups.push_back(g);
    }
    if (!node_rate_groups.empty()) {
      double gamma = 0.0;
      const auto rate_weights = [&](int k, const Vector3& Pi) {
        const Vector3 a = inverse_inertia_squared_ * Pi;  // J⁻²Π
        const double rate_squared = Pi.dot(a);            // |J⁻¹Π|²
        gamma = 0.0;
        for (Group* g : node_rate_groups) {
          Instance& in = g->instance(k);
          in.c = 1.0 - rate_squared / (g->limit * g->limit);
          prepare(in);
          gamma += 2.0 * in.z / (g->limit * g->limit);
        }
        return Vector3(gamma * a);
      };
      np_.forEachNodeMomentum(
          [&](const ReducedProblem::NodeMomentum& node) {
            const Vector3 a = inverse_inertia_squared_ * node.momentum;
            const Eigen::Matrix<double, 9, 1> grad = node.jacobian.transpose() * a;
            for (Group* g : node_rate_groups) {
              Instance& in = g->instance(node.k);
              in.g = -2.0 / (g->limit * g->limit) * grad;
            }
            if (!H) return;
            const Eigen::Matrix<double, 9, 9> block =
                gamma * node.jacobian.transpose() * inverse_inertia_squared_ * node.jacobian +
                node.second;
            addLocal(np_, H, node.k - 1, 3, block);
            for (Group* g : node_rate_groups) {
              const Instance& in = g->instance(node.k);
              addLocalRankOne(np_, H, node.k - 1, 3, in.g, 1.0 / in.D);
            }
          },
          rate_weights);
    }
    // Step rates and cone constraints: their own derivatives (node_constraints.hpp).
    std::vector<Matrix3> R;
    for (Group* g : other_groups) {
      if (node_rates_ && g->family == Family::AngularRate) continue;
      if (g->family != Family::AngularRate && R.empty()) R = np_.attitudes(steps);
      for (int k = g->first_k; k <= g->last_k; ++k) {
        Instance& in = g->instance(k);
        Eigen::Matrix<double, 9, 9> block = Eigen::Matrix<double, 9, 9>::Zero();
        in.g.setZero();
        if (g->family == Family::AngularRate) {
          const AngularRateTerms t = angularRateTerms(np_.scheme(), steps[k]);
          const double scale = 2.0 / (g->limit * g->limit);  // c = 1 − scale φ
          in.c = 1.0 - scale * t.half_squared_rate;
          prepare(in);
          in.g.head<6>() = -scale * t.gradient;
          block.topLeftCorner<6, 6>() = (in.z * scale) * t.hessian;  // −z∇²c
        } else {
          const PointingTerms t = pointingTerms(R[k], g->spec->body_axis, g->spec->world_direction);
          const double sign = g->family == Family::KeepOut ? -1.0 : 1.0;  // c = ±p ∓ cos α
          in.c = sign * (t.cosine - std::cos(g->spec->nodeHalfAngle()));
          prepare(in);
          in.g.head<3>() = sign * t.gradient;
          block.topLeftCorner<3, 3>() = (-in.z * sign) * t.hessian;
        }
        if (H) {
          addLocal(np_, H, k + g->node_offset, g->width, block);
          addLocalRankOne(np_, H, k + g->node_offset, g->width, in.g, 1.0 / in.D);
        }
      }
    }
    // ∇φ_μ = ∇f − Σ (μ/s) g (Elastic; FreeSlacks: ∇_δ φ = ∇f, the slacks' part is
    // slackSlope's);  rhs = −∇f + Σ g (z + q/D).
    for (Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const Instance& in = g.instance(k);
        const int first = k + g.node_offset;
        if (!free_slacks_) addLocalVector(np_, in.g, -mu / in.s, first, g.width, merit_gradient);
        addLocalVector(np_, in.g, in.z + in.q / in.D, first, g.width, rhs);
      }
    }
    return cost;
  }

  /// FreeSlacks, Mehrotra's predictor: from the affine-scaling step dδ_aff (solved with μ = 0,
  /// i.e. q = −c), the complementarity the step to the boundary would leave,
  /// μ_aff = mean((s + α_p ds)(z + α_d dz)), and the mean complementarity now (*average). Keeps
  /// each instance's ds_aff·dz_aff (in `products`) for the corrector.
  double affineComplementarity(const Eigen::VectorXd& d, double* average,
                               std::vector<double>* products) const {
    products->clear();
    double alpha_p = 1.0, alpha_d = 1.0, sum = 0.0;
    std::vector<double> ds, dz;
    for (const Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const Instance& in = g.at[k - g.first_k];
        const double lin = localDot(np_, in.g, k + g.node_offset, g.width, d);
        ds.push_back(lin + in.c - in.s);
        dz.push_back((-in.c - lin) / in.D);
        if (ds.back() < 0) alpha_p = std::min(alpha_p, -in.s / ds.back());
        if (dz.back() < 0) alpha_d = std::min(alpha_d, -in.z / dz.back());
        sum += in.s * in.z;
      }
    }
    double affine = 0.0;
    std::size_t i = 0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) {
        affine += (in.s + alpha_p * ds[i]) * (in.z + alpha_d * dz[i]);
        products->push_back(ds[i] * dz[i]);
        ++i;
      }
    }
    const double m = std::max<double>(1.0, static_cast<double>(i));
    *average = sum / m;
    return affine / m;
  }

  /// Adds Σ_i g_i/s_i (the barrier's part of the right-hand side is μ times it) or, with
  /// `products`, the corrector's Σ_i −g_i·products_i/s_i, to `out`.
  void addSlackWeightedGradients(const std::vector<double>* products, Eigen::VectorXd* out) const {
    std::size_t i = 0;
    for (const Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k, ++i) {
        const Instance& in = g.at[k - g.first_k];
        const double weight = products ? -(*products)[i] / in.s : 1.0 / in.s;
        addLocalVector(np_, in.g, weight, k + g.node_offset, g.width, out);
      }
    }
  }

  /// The condensation's q for the complementarity target s z = μ − ds_aff dz_aff (FreeSlacks;
  /// `products` may be null: the plain barrier μ).
  void setComplementarityTarget(double mu, const std::vector<double>* products) {
    std::size_t i = 0;
    for (Group& g : groups_) {
      for (Instance& in : g.at) {
        in.q = (mu - (products ? (*products)[i] : 0.0)) / in.z - in.c;
        ++i;
      }
    }
  }

  /// The largest dual step in (0, 1] keeping z and u = ρ − z at least (1 − τ) of their values,
  /// and the steps dz themselves (stored in `dz`, instance order).
  double dualStep(const Eigen::VectorXd& d, double rho, std::vector<double>* dz) {
    dz->clear();
    double alpha = 1.0;
    for (Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const Instance& in = g.instance(k);
        const double step = (in.q - localDot(np_, in.g, k + g.node_offset, g.width, d)) / in.D;
        dz->push_back(step);
        if (step < 0) alpha = std::min(alpha, -kFractionToBoundary * in.z / step);
        if (free_slacks_) continue;  // z has no upper bound
        const double u = rho - in.z;
        if (step > 0) alpha = std::min(alpha, kFractionToBoundary * u / step);
      }
    }
    return alpha;
  }

  void applyDualStep(const std::vector<double>& dz, double alpha) {
    std::size_t i = 0;
    for (Group& g : groups_) {
      for (Instance& in : g.at) in.z += alpha * dz[i++];
    }
  }

  /// FreeSlacks: the slack steps ds = gᵀdδ + c − s (stored in the instances), the largest step in
  /// (0, 1] keeping s ≥ (1 − τ)s, the slope of the barrier terms −μ Σ ds/s (in *barrier_slope)
  /// and ‖c − s‖₁ (in *residual).
  double slackStep(const Eigen::VectorXd& d, double mu, double* barrier_slope, double* residual,
                   double* significant_residual) {
    double alpha = 1.0, slope = 0.0, sum = 0.0, significant = 0.0;
    for (Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        Instance& in = g.instance(k);
        in.ds = localDot(np_, in.g, k + g.node_offset, g.width, d) + in.c - in.s;
        if (in.ds < 0) alpha = std::min(alpha, -kFractionToBoundary * in.s / in.ds);
        slope -= mu * in.ds / in.s;
        sum += std::abs(in.c - in.s);
        if (std::abs(in.c - in.s) > kRoundOffSlackResidual) significant += std::abs(in.c - in.s);
      }
    }
    *barrier_slope = slope;
    *residual = sum;
    *significant_residual = significant;
    return alpha;
  }

  void applySlackStep(double alpha) {
    for (Group& g : groups_) {
      for (Instance& in : g.at) in.s += alpha * in.ds;
    }
  }

  /// FreeSlacks: the largest multiplier after the dual step dz (for the merit's ν).
  double largestMultiplier(const std::vector<double>& dz, double alpha) const {
    double largest = 0.0;
    std::size_t i = 0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) largest = std::max(largest, in.z + alpha * dz[i++]);
    }
    return largest;
  }

  /// FreeSlacks: max |c − s| at the last evaluated c.
  double maxSlackResidual() const {
    double worst = 0.0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) worst = std::max(worst, std::abs(in.c - in.s));
    }
    return worst;
  }

  /// Mean and smallest complementarity product (s z and v u; FreeSlacks: s z) at the last
  /// evaluated c.
  void complementarity(double mu, double rho, double* average, double* smallest) const {
    double sum = 0.0, low = std::numeric_limits<double>::infinity();
    int count = 0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) {
        if (free_slacks_) {
          sum += in.s * in.z;
          low = std::min(low, in.s * in.z);
          ++count;
          continue;
        }
        const ElasticSlacks sl = elasticSlacks(in.c, mu, rho);
        const double a = sl.s * in.z, b = sl.v * (rho - in.z);
        sum += a + b;
        low = std::min(low, std::min(a, b));
        count += 2;
      }
    }
    *average = sum / std::max(count, 1);
    *smallest = low;
  }

  /// Largest elastic violation max v_i (constraint units) at the last assembly or merit.
  double maxViolation() const {
    double worst = 0.0;
    for (const Group& g : groups_) {
      for (const Instance& in : g.at) worst = std::max(worst, -in.c);
    }
    return worst;
  }

  /// σ_k = τ_k + (z⁺ − z⁻)/(a w_k) per axis (PlanResult::switching_function) at the current
  /// multipliers; empty without per-axis bounds.
  std::vector<Vector3> switchingFunction(const std::vector<Vector3>& torque) const {
    std::vector<Vector3> sigma;
    for (const Group& g : groups_) {
      if (g.family != Family::TorqueUpper && g.family != Family::TorqueLower) continue;
      if (sigma.empty()) sigma = torque;
      const double sign = g.family == Family::TorqueUpper ? 1.0 : -1.0;
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const double weight = np_.scheme().torqueWeight(k, np_.steps());
        sigma[k](g.axis) += sign * g.at[k - g.first_k].z / (g.limit * weight);
      }
    }
    return sigma;
  }

  /// The first-order (KKT stationarity) residual at the current iterate with this solve's
  /// multipliers: max-norm of ∇f − Σ zᵢ∇cᵢ relative to |∂τ/∂R|·max|τ|, as the Newton solver's
  /// max_residual. Re-forms the gradients at the iterate (the last assembly's are the previous
  /// iterate's), first order only, leaving the multipliers as they are.
  double relativeStationarity(double mu, double rho, Eigen::VectorXd* rhs,
                              Eigen::VectorXd* merit_gradient) {
    double scale = 0.0, unused = 0.0;
    assemble<double>(mu, rho, false, nullptr, rhs, merit_gradient, &scale);
    Eigen::VectorXd residual;
    np_.evaluate(&residual, nullptr, &unused);  // ∇f
    for (const Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const Instance& in = g.at[k - g.first_k];
        addLocalVector(np_, in.g, -in.z, k + g.node_offset, g.width, &residual);
      }
    }
    return residual.size() && scale > 0 ? residual.cwiseAbs().maxCoeff() / scale : 0.0;
  }

  /// The multipliers and slacks of this iterate (FreeSlacks), to start a finer level from.
  LevelDuals duals() const {
    LevelDuals d;
    d.steps = np_.steps();
    for (const Group& g : groups_) {
      d.first_k.push_back(g.first_k);
      d.z.emplace_back();
      d.s.emplace_back();
      for (const Instance& in : g.at) {
        d.z.back().push_back(in.z);
        d.s.back().push_back(in.s);
      }
    }
    return d;
  }

  /// FreeSlacks from a coarser level's duals: each instance takes the multiplier of the coarse
  /// instance nearest in time (a node constraint's multiplier does not scale with h: the cost
  /// Σ ½|τ_k|² weighs every node alike), and its slack c pushed inside by at most
  /// kWarmSlackPush where the coarse constraint was binding (its coarse slack below the push),
  /// else as initializeMultipliers pushes it. Returns mean(s z).
  double warmStartDuals(const LevelDuals& coarse) {
    double sum = 0.0;
    int count = 0;
    for (std::size_t gi = 0; gi < groups_.size() && gi < coarse.z.size(); ++gi) {
      Group& g = groups_[gi];
      const std::vector<double>& zc = coarse.z[gi];
      if (zc.empty()) continue;
      for (int k = g.first_k; k <= g.last_k; ++k) {
        const int kc = static_cast<int>(std::lround(double(k) * coarse.steps / np_.steps()));
        const int i = std::min<int>(zc.size() - 1, std::max(0, kc - coarse.first_k[gi]));
        Instance& in = g.instance(k);
        const bool binding = coarse.s[gi][i] < kWarmSlackPush;
        in.z = zc[i];
        in.s = std::max(in.c, binding ? kWarmSlackPush : kSlackPush);
        in.ds = 0.0;
        sum += in.s * in.z;
        ++count;
      }
    }
    return sum / std::max(count, 1);
  }

  // ---- warm start from a plan without multipliers (issue 30; multiplier_estimate.hpp) ----
  /// The duals of a start from the current iterate (a plan given as the initial guess) in the
  /// form a finer grid level takes them (warmStartDuals): re-derived from stationarity there.
  LevelDuals estimatedDuals() {
    Eigen::VectorXd rhs, merit_gradient, cost_gradient;
    double scale = 0.0;
    assemble<double>(0.0, 1.0, false, nullptr, &rhs, &merit_gradient, &scale);  // gradients
    evaluateValues(np_.current(), nullptr);  // values (the torques' are set with H only)
    const double cost = np_.evaluate(&cost_gradient, nullptr, &scale);
    std::vector<StationarityColumn> columns;
    for (const Group& g : groups_) {
      for (int k = g.first_k; k <= g.last_k; ++k) {
        StationarityColumn column{g.at[k - g.first_k].c, g.at[k - g.first_k].g};
        for (int n = 0; n < g.width; ++n)
          column.index[n] = np_.variableIndex(k + g.node_offset + n);
        columns.push_back(column);
      }
    }
    const MultiplierEstimate e =
        estimateMultipliers(cost_gradient, columns, cost / std::max(constraint_count_, 1));
    LevelDuals d;
    d.steps = np_.steps();
    std::size_t i = 0;
    for (const Group& g : groups_) {
      d.first_k.push_back(g.first_k);
      d.z.emplace_back(e.z.begin() + i, e.z.begin() + i + g.at.size());
      d.s.emplace_back(e.s.begin() + i, e.s.begin() + i + g.at.size());
      i += g.at.size();
    }
    return d;
  }
  // ---- end warm start ----

  /// Initial multipliers: the primal ones μ/s, capped at `cap` (violated constraints' primal
  /// multipliers are ≈ ρ: as duals they would swamp the Lagrangian's Hessian).
  void initializeMultipliers(double mu, double rho, double cap) {
    for (Group& g : groups_) {
      for (Instance& in : g.at) {
        if (free_slacks_) {
          in.s = std::max(in.c, kSlackPush);
          in.ds = 0.0;
          in.z = std::min(mu / in.s, cap);
          continue;
        }
        const ElasticSlacks sl = elasticSlacks(in.c, mu, rho);
        in.z = std::min(mu / sl.s, std::min(cap, 0.5 * rho));
      }
    }
  }

 private:
  /// J⁻¹Π_k, Π_k = (μ(F_k) + F_{k−1}ᵀ μ(F_{k−1}))/2: the node velocity of a scheme with end
  /// torques.
  Vector3 nodeVelocity(const ReducedProblem::Steps& steps, int k) const {
    const DiscreteScheme& scheme = np_.scheme();
    const Vector3 Pi =
        0.5 * (scheme.momentumOfStep(steps[k]) +
               so3::exp(steps[k - 1]).transpose() * scheme.momentumOfStep(steps[k - 1]));
    return inverse_inertia_ * Pi;
  }

  const PlanningProblem& problem_;
  ReducedProblem& np_;
  bool free_slacks_;
  bool node_rates_;
  Matrix3 inverse_inertia_;          ///< J⁻¹
  Matrix3 inverse_inertia_squared_;  ///< J⁻²
  std::vector<Group> groups_;
  int constraint_count_ = 0;
  double current_beta_ = 1.0;
};

std::string describeManeuverSpan(const PlanningProblem& problem) {
  std::ostringstream s;
  s << "cannot turn this body by "
    << so3::angleBetween(problem.initial_attitude, problem.final_attitude)
    << " rad in T = " << problem.duration << " s";
  return s.str();
}

/// The interior point on one grid: from `coarse_steps` (a coarser grid's solution, with a small
/// initial barrier) if given, else from options.warm_start; leaves its iterate in `final_steps`.
template <typename Scalar>
PlanResult solveOnGridIn(const PlanningProblem& problem, const SolverOptions& options,
                         Formulation formulation, bool predictor_corrector,
                         const ReducedProblem::Steps* coarse_steps,
                         ReducedProblem::Steps* final_steps, const LevelDuals* coarse_duals,
                         LevelDuals* final_duals) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  PlanResult result;
  result.solver = "interior_point";
  std::optional<ReducedProblem> reduced;
  try {
    reduced.emplace(problem);
  } catch (const StepTooLarge& e) {
    result.message = std::string("boundary velocity: ") + e.what();
    result.termination = Termination::StepTooLarge;
    return result;
  }
  ReducedProblem& np = *reduced;
  const int N = np.steps();
  // The initial guess: the warm start (the unconstrained optimum, from planManeuver), else the
  // geodesic.
  if (options.warm_start) np.setInteriorFromAttitudes(options.warm_start->attitude);
  if (coarse_steps && static_cast<int>(coarse_steps->size()) == problem.steps) {
    np.setCurrent(*coarse_steps);  // a warm start's own steps (solveWithInteriorPointFromGuess)
  } else if (coarse_steps) {
    np.initializeFromCoarser(*coarse_steps);
  }

  // Nodes fixed by the boundary data (R_1, R_{N−1}, F_0, F_{N−1}) are not unknowns: a constraint
  // they violate cannot be repaired by any plan at this N.
  {
    const std::vector<Matrix3> R = np.attitudes(np.current());
    for (const PlanningConstraint& c : problem.constraints) {
      if (!c.isCone()) continue;
      for (int k : {1, N - 1}) {
        if (np.variableIndex(k) >= 0) continue;               // free with end torques
        const double slack = coneMargin(c, R[k]) - c.margin;  // to the node bound
        if (slack < 0.0) {
          std::ostringstream why;
          why << "infeasible: " << describeConstraint(c) << " is violated by " << -slack
              << " rad at k = " << k
              << ", an attitude the boundary velocities fix (increase steps or move the boundary)";
          result.termination = Termination::Infeasible;
          result.message = why.str();
          return result;
        }
      }
    }
  }

  InteriorPoint ip(problem, &np, formulation);
  const bool free_slacks = ip.freeSlacks();
  const int n = np.unknowns();
  BandedSymmetric<Scalar> hessian(n, 8);
  BandedCholeskyFactor<Scalar> cholesky;
  std::vector<double> products;  // ds_aff·dz_aff of the predictor
  Eigen::VectorXd rhs(n), merit_gradient(n), delta(n);
  double gradient_scale = 0.0;

  // Scales: f_scale the cost of the start (the unconstrained optimum), floored by the cost of a
  // torque J·θ/T² at every node so a free coast still has a scale.
  double start_cost = 0.0;
  ip.merit(np.current(), 1.0, 1.0, &start_cost);
  const double J_norm = problem.inertia.norm();
  const double angle =
      std::max(so3::angleBetween(problem.initial_attitude, problem.final_attitude), 1e-3);
  const double floor_torque = J_norm * angle / (problem.duration * problem.duration);
  const double f_scale = std::max(start_cost, 1e-6 * 0.5 * N * floor_torque * floor_torque);
  const int m = std::max(ip.constraintCount(), 1);
  double rho = kInitialPenalty * f_scale;
  double nu = 0.0;  // FreeSlacks: the merit's ν ≥ the multipliers (raised as needed)
  // From a coarse solution the active set is nearly right: a barrier that starts small keeps
  // the iterate near it (measured: N = 1024 from the unconstrained optimum took > 200
  // iterations, from the N = 256 solution ~20).
  const double mu_start = (coarse_steps ? kWarmBarrier : kMuStart) * f_scale / m;
  double mu = mu_start;
  // The final barrier grows with N above kFinalBarrierRoundOffSteps: a torque constraint's value
  // 1 ∓ τ_a/a carries round-off ~ε|Π|/(h a), which grows like N, and final slacks s = μ/z below
  // it make the multipliers noise (measured, torque + rate limits at N = 10⁵: values ±5e-12
  // against slacks of 5e-13, multipliers ±1.5 % from node to node on an active arc, stationarity
  // residual 0.05; with this growth 6.8e-6, the cost 1.3e-10 higher: the barrier's gap).
  const double mu_final =
      std::min(mu, 0.1 * options.tolerance * f_scale / m *
                       std::max(1.0, static_cast<double>(N) / kFinalBarrierRoundOffSteps));
  ip.evaluateValues(np.current(), nullptr);
  ip.initializeMultipliers(mu, rho, 10.0 * f_scale / m);
  if (predictor_corrector && coarse_duals && !coarse_duals->empty() && coarse_steps) {
    // The barrier of the warm start: its own complementarity (the predictor lowers it).
    mu = std::max(mu_final, std::min(mu, ip.warmStartDuals(*coarse_duals)));
  }

  std::string reason = "iteration limit reached";
  Termination ending = Termination::NotConverged;
  int iteration = 0;
  double relative_decrement = 0.0;
  int penalty_raises = 0;
  int stalled_iterations = 0;
  double shift_floor = 0.0;  // raised after a failed line search, reset after a success
  const double stall_acceptance = kStallAcceptance * std::max(1.0, N / 1024.0);
  double best_violation = std::numeric_limits<double>::infinity();
  int last_violation_progress = 0;
  double best_final_decrement = std::numeric_limits<double>::infinity();
  std::vector<double> dz;
  double alpha_dual = 1.0, alpha_slack = 1.0;
  int barrier_stall = 0;  // FreeSlacks: full steps in a row that did not halve the decrement
  double previous_decrement = std::numeric_limits<double>::infinity();
  double previous_alpha = 0.0;  // the last accepted step length
  bool previous_at_final_barrier = false;
  for (;; ++iteration) {
    if (iteration >= options.max_iterations) break;
    if (options.time_budget_s > 0 && elapsed() > options.time_budget_s) {
      reason = "time budget exceeded";
      ending = Termination::TimedOut;
      break;
    }
    bool primal = false;
    double slope = 0.0, cost = 0.0, shift = 0.0;
    double significant_residual = 0.0, decrement_slope = 0.0;
    bool factored = false;
    for (int attempt = 0; attempt < 2 && !factored; ++attempt) {
      cost = ip.assemble(mu, rho, primal, &hessian, &rhs, &merit_gradient, &gradient_scale);
      if (!std::isfinite(cost)) break;
      shift = shift_floor;
      for (int tries = 0; tries < 40; ++tries) {
        delta = rhs;
        BandedSymmetric<Scalar> trial = hessian;
        // Inertia correction relative to each row's scale: at the final barrier the active
        // constraints' rows are ~1/μ larger than the others, and a uniform shift sized by them
        // (the largest diagonal) damped the free directions into linear convergence (measured:
        // torque_limited, second_order, N = 512: 200 iterations at a decrement of 2e-6).
        if (shift > 0) trial.addRelativeToDiagonal(shift, 1e-8 * hessian.maxAbsDiagonal());
        if (cholesky.factor(trial)) {
          cholesky.solve(&delta);
          if (delta.allFinite()) {
            factored = true;
            break;
          }
        }
        shift = shift == 0.0 ? 1e-14 : 100.0 * shift;
      }
      if (factored && predictor_corrector && !primal && mu > mu_final) {
        // Mehrotra's predictor–corrector: the affine-scaling step (μ = 0) says how far the
        // complementarity can fall; the barrier of this step is σ·mean(s z), σ = (μ_aff/mean)³,
        // and the corrector adds the affine step's second-order term ds_aff·dz_aff. One
        // factorization, two more solves.
        const Eigen::VectorXd barrier_part = [&] {
          Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
          ip.addSlackWeightedGradients(nullptr, &v);
          return v;
        }();
        const Eigen::VectorXd affine_rhs = rhs - mu * barrier_part;
        Eigen::VectorXd affine = affine_rhs;
        cholesky.solve(&affine);
        double average = 0.0;
        const double mu_affine = ip.affineComplementarity(affine, &average, &products);
        const double sigma = std::pow(std::min(1.0, mu_affine / average), 3);
        // Not below what the iterate's distance to the barrier problem's solution warrants (a
        // relative decrement d is a cost error ~d²·f; the barrier's is ~m μ): a μ far below it
        // leaves the rest of the way to Newton steps at a tiny μ, whose condensed system (its
        // condition grows like N⁴ and 1/μ) no longer resolves them (measured: torque_limited,
        // N = 2048, stalled 2.4e-7 above the optimum without this floor). The floor rises
        // with N² above N = 1024 for the same reason.
        const double floor_factor =
            std::min(1.0, kBarrierProgressFloor * std::max(1.0, std::pow(N / 1024.0, 2)));
        const double progress_floor =
            std::isfinite(previous_decrement)
                ? floor_factor * previous_decrement * previous_decrement * f_scale / m
                : mu;
        mu = std::max(mu_final, std::min(mu, std::max(sigma * average, progress_floor)));
        if (mu < 10.0 * mu_final) mu = mu_final;
        ip.setComplementarityTarget(mu, &products);
        delta = affine_rhs + mu * barrier_part;
        ip.addSlackWeightedGradients(&products, &delta);
        cholesky.solve(&delta);
      }
      slope = merit_gradient.dot(delta);
      if (factored && free_slacks) {
        // ℓ1 merit: ν at least the multipliers after the step, and large enough that the
        // step decreases the merit by a tenth of its predicted infeasibility reduction.
        double barrier_slope = 0.0, residual = 0.0;
        alpha_slack = ip.slackStep(delta, mu, &barrier_slope, &residual, &significant_residual);
        alpha_dual = ip.dualStep(delta, rho, &dz);
        nu = std::max(nu, 1.1 * ip.largestMultiplier(dz, 0.0));
        const double without_penalty = slope + barrier_slope;
        if (residual > 0.0 && without_penalty > -0.1 * nu * residual) {
          nu = std::max(nu, 2.0 * without_penalty / (0.9 * residual));
        }
        slope = without_penalty - nu * residual;
        // (Its magnitude: a step that mostly repairs round-off residuals may raise f and the
        // barrier a little; that is not convergence.)
        decrement_slope = -std::abs(without_penalty) - nu * significant_residual;
      }
      // The primal–dual step is Newton's on φ_μ only when z = μ/s; if it is not a descent
      // direction the primal multipliers are used (then it is, H being positive definite).
      if (factored && slope >= 0.0 && !primal) {
        factored = false;
        primal = true;
      }
    }
    if (!std::isfinite(cost)) {
      reason = "non-finite cost (step too large for this h? increase steps)";
      ending = Termination::StepTooLarge;
      break;
    }
    if (!factored) {
      reason = "Newton system could not be made positive definite";
      break;
    }
    // Free slacks: the residuals c − s at round-off (~1e-12 each, a torque being a difference of
    // momenta over h) add up over the m constraints in ν‖c − s‖₁ to a floor that grows with m;
    // they do not count in the decrement.
    relative_decrement = std::sqrt(std::max(0.0, -(free_slacks ? decrement_slope : slope))) /
                         std::sqrt(2.0 * f_scale);
    const bool at_final_barrier = mu <= mu_final;
    // At the final barrier the condensed system's condition grows like 1/μ̂ in the active
    // directions: decrements stall at ~1e-9 relative (measured). Two full steps that no longer
    // halve the decrement, below kStallAcceptance, end the solve as at the tolerance.
    // With the constraints still violated at the final barrier, the iterate minimizes the ℓ1
    // violation: a stall there ends the solve too (then: penalty raise, or infeasible).
    const bool violated = ip.maxViolation() > kFeasibilityTolerance;
    if (at_final_barrier && (relative_decrement <= stall_acceptance || violated) &&
        relative_decrement > 0.5 * best_final_decrement) {
      ++stalled_iterations;
    } else if (at_final_barrier) {
      stalled_iterations = 0;
    }
    if (at_final_barrier) best_final_decrement = std::min(best_final_decrement, relative_decrement);
    // A violation that no iteration reduces any more (kViolationStall iterations) is a local
    // minimum of the ℓ1 infeasibility at any barrier: end the solve (then: penalty raise, or
    // infeasible) instead of iterating to the limit.
    if (!violated || ip.maxViolation() < best_violation * (1.0 - 1e-6)) {
      best_violation = violated ? ip.maxViolation() : std::numeric_limits<double>::infinity();
      last_violation_progress = iteration;
    }
    const bool violation_stalled =
        violated && iteration - last_violation_progress >=
                        (free_slacks ? kFreeSlackViolationStall : kViolationStall);
    // Quadratic convergence seen at the final barrier: the last (full) step took the decrement
    // from d₋ to d, so this one leaves about d·(d/d₋)²; well below the stall acceptance it is
    // taken as the last (as the Newton solver does), instead of iterating on to the floor.
    // (A shift of round-off size, which the final barrier's condition can need, counts as none.)
    const bool unshifted = shift <= kNegligibleShift;
    const bool quadratic_finish =
        predictor_corrector && at_final_barrier && previous_at_final_barrier && !violated &&
        unshifted && previous_alpha >= 0.9 && relative_decrement < previous_decrement &&
        relative_decrement * std::pow(relative_decrement / previous_decrement, 2) <=
            0.1 * stall_acceptance;
    // Below a hundredth of the stall acceptance the decrement is at the round-off floor (measured:
    // 4e-9…8e-9 at N = 128…512) when the tolerance lies under it: this step is the last, instead
    // of two more that only show the stall.
    const double reachable_tolerance = predictor_corrector
                                           ? std::max(options.tolerance, 0.01 * stall_acceptance)
                                           : options.tolerance;
    const bool final_step =
        violation_stalled ||
        (at_final_barrier && ((unshifted && relative_decrement <= reachable_tolerance) ||
                              stalled_iterations >= 2 || quadratic_finish));

    // Armijo on φ_μ along the retraction; a predicted decrease below φ's round-off is taken.
    // φ_μ at the current iterate from the values the assembly just formed (no re-evaluation).
    const double penalty = free_slacks ? nu : rho;
    const double phi = ip.assembledMerit(cost, mu, penalty);
    double alpha = free_slacks ? alpha_slack : 1.0;
    bool accepted = final_step || -slope <= 1e-14 * std::abs(phi);
    // At the round-off floor (below) a step the line search must shorten 32× is no progress, and
    // each halving costs a merit evaluation (measured: N = 10⁵, a final level's 60 halvings took
    // 2.4 s of its 11 s, only to end at the floor anyway).
    const bool at_floor =
        at_final_barrier && !violated && relative_decrement <= 10.0 * stall_acceptance;
    const int max_halvings = at_floor ? kFloorHalvings : kMaxHalvings;
    ReducedProblem::Steps trial = np.retract(delta, alpha);
    for (int back = 0; !accepted && back < max_halvings; ++back) {
      const double trial_phi = ip.merit(trial, mu, penalty, nullptr, alpha);
      if (std::isfinite(trial_phi) && trial_phi <= phi + 1e-4 * alpha * slope) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
      trial = np.retract(delta, alpha);
    }
    if (!accepted) {
      // At the final barrier below the round-off floor Armijo fails on noise: the iterate is
      // as good as the floor allows (a full step there was measured to make it worse).
      if (at_floor) {
        std::ostringstream why;
        why << "converged to the round-off floor (relative Newton decrement " << relative_decrement
            << ", the line search can no longer decrease the merit)";
        reason = why.str();
        ending = Termination::Converged;
        break;
      }
      // A direction the line search rejects: regularize more (Levenberg–Marquardt) and retry,
      // a few times, before giving up.
      if (shift_floor < kMaxShiftFloor) {
        shift_floor = std::max(1e-8, 100.0 * shift_floor);
        continue;
      }
      reason = "line search failed";
      break;
    }
    // Multipliers: the values the step was computed with (re-assembled ones were overwritten by
    // merit evaluations' c only), moved by the dual step.
    if (free_slacks) {
      ip.applySlackStep(alpha);
    } else {
      alpha_dual = ip.dualStep(delta, rho, &dz);
    }
    ip.applyDualStep(dz, std::min(alpha_dual, 1.0));
    np.setCurrent(trial);
    shift_floor = shift_floor > 1e-8 ? shift_floor / 100.0 : 0.0;
    IterationInfo info{iteration + 1, cost, relative_decrement, alpha};
    result.history.push_back(info);
    if (options.on_iteration && !options.on_iteration(info)) {
      ending = Termination::Cancelled;
      reason = "cancelled";
      ++iteration;
      break;
    }
    if (final_step) {
      ++iteration;
      // Feasible at this penalty?
      ip.evaluateValues(np.current(), nullptr);
      const double violation = ip.maxViolation();
      if (violation <= kFeasibilityTolerance) {
        ending = Termination::Converged;
        reason = "converged";
        break;
      }
      // A small violation may be a penalty below a multiplier; a large one is not (and at a far
      // larger ρ the cost no longer regularizes the ℓ1 infeasibility minimization: measured, the
      // iterate then wanders to multi-turn motions).
      if (!free_slacks && penalty_raises == 0 && violation <= kPenaltyRaiseViolation) {
        // Perhaps ρ was below a multiplier: raise it once and re-solve from here.
        ++penalty_raises;
        rho *= kPenaltyGrowth;
        mu = mu_start;
        best_violation = std::numeric_limits<double>::infinity();
        last_violation_progress = iteration;
        best_final_decrement = std::numeric_limits<double>::infinity();
        stalled_iterations = 0;
        ip.initializeMultipliers(mu, rho, 10.0 * f_scale / m);
        continue;
      }
      ending = Termination::Infeasible;
      reason = "infeasible";
      break;
    }
    // Barrier update (LOQO's adaptive rule): μ ← σ · mean(s z, v u), σ = 0.1 min(0.05 (1 − ξ)/ξ,
    // 2)³, ξ = smallest / mean product (how far from central), never increasing. Measured against
    // IPOPT's monotone rule on the five constrained scenes at N = 64, 128, 512: 20–25 % fewer
    // iterations, same optima.
    if (predictor_corrector) {
      // μ is chosen by the predictor at the next iteration.
    } else if (!at_final_barrier && free_slacks) {
      // Monotone (Fiacco–McCormick, as IPOPT's): μ falls only once the barrier problem is solved
      // to κ μ, feasibility included; the adaptive rule below would drive μ to μ_final while the
      // iterate is still far from feasible, and the slacks' fraction to the boundary then stalls.
      // A barrier problem whose decrement stalls at the round-off floor above κ μ (two full
      // steps that no longer halve it) is solved as far as it can be (measured: torque + rate
      // limits, N = 8192: 180 full steps at μ = 1.8e-7 × cost/m, the decrement stuck at 2.5e-5).
      const double scaled_mu = mu * m / f_scale;
      barrier_stall =
          alpha == 1.0 && relative_decrement > 0.5 * previous_decrement ? barrier_stall + 1 : 0;
      const bool solved = relative_decrement <= 10.0 * scaled_mu || barrier_stall >= 2;
      if (ip.maxSlackResidual() <= 10.0 * scaled_mu && solved) {
        mu = std::max(mu_final, std::min(0.2 * mu, std::pow(scaled_mu, 1.5) * f_scale / m));
        if (mu < 10.0 * mu_final) mu = mu_final;
        barrier_stall = 0;
      }
    } else if (!at_final_barrier) {
      double average = 0.0, smallest = 0.0;
      ip.complementarity(mu, rho, &average, &smallest);
      const double xi = smallest / average;
      const double sigma = 0.1 * std::pow(std::min(0.05 * (1 - xi) / xi, 2.0), 3);
      mu = std::max(mu_final, std::min(mu, sigma * average));
      // Within 10× of the final barrier the complementarity products sit at round-off and the
      // rule above can leave μ just above μ_final for good (measured: N = 8192, μ = 1.07 μ_final,
      // then no stall test applies): snap to it.
      if (mu < 10.0 * mu_final) mu = mu_final;
    }
    previous_decrement = relative_decrement;
    previous_alpha = alpha;
    previous_at_final_barrier = at_final_barrier;
  }

  result.iterations = iteration;
  result.newton_decrement = relative_decrement;
  if (final_steps) *final_steps = np.current();
  if (final_duals) *final_duals = free_slacks ? ip.duals() : LevelDuals{};
  const Maneuver planned = np.maneuver(np.current());
  result.switching_function = ip.switchingFunction(planned.torque);
  result.max_residual = ip.relativeStationarity(mu, rho, &rhs, &merit_gradient);
  evaluatePlan(problem, planned.torque, &result, &planned);
  const ConstraintCheck check = checkConstraints(problem, result.maneuver);
  std::ostringstream msg;
  if (ending == Termination::Infeasible) {
    msg << "infeasible: " << (check.worst.empty() ? std::string("the constraints") : check.worst)
        << " " << describeManeuverSpan(problem)
        << " (the violation stopped decreasing; the last iterate exceeds it " << check.worst_where
        << ")";
  } else {
    if (ending == Termination::Converged) {
      const std::string inconsistent = planInconsistency(problem, result, true);
      if (!inconsistent.empty()) {
        ending = Termination::NotConverged;
        reason = inconsistent;
      }
    }
    msg << reason;
  }
  result.termination = ending;
  msg << " after " << iteration << " interior-point iterations (relative Newton decrement "
      << relative_decrement << ", barrier " << mu / f_scale << " x cost, max elastic violation "
      << ip.maxViolation() << ")";
  result.message = msg.str();
  result.levels.push_back(
      {N, iteration, ending, result.max_residual, relative_decrement,
       std::string(free_slacks ? "interior point (free slacks): " : "interior point (elastic): ") +
           result.message});
  return result;
}

}  // namespace

namespace {

/// The interior point's Newton system is assembled, factored and solved in extended precision
/// above kExtendedPrecisionAboveSteps: in long double where it is the x87 format (64-bit
/// significand, hardware) up to kLongDoubleMaxSteps, and in double-double arithmetic
/// (double_double.hpp, ~106 bits) above, and everywhere above 1024 where long double is not x87
/// (aarch64: a software quad, slower than double-double; elsewhere plain double). At a bound a
/// constraint's condensed term g gᵀ/D (D → 0) exceeds the curvature ∇²f − Σ z∇²c by up to ~1e12,
/// and the smooth modes' curvature falls like N⁻⁴ against the largest (torques are second
/// differences of attitudes); the step along the active constraints' null space depends on that
/// curvature alone. Measured against IPOPT (docs/constraints.md, torque and rate limits): in
/// double the optima agreed to ≤ 7e-12 up to N = 1024, 1e-9 at 2048, 7e-8 at 4096 and 4e-6 at 8192
/// (553 fewer active constraints than IPOPT's); in long double to ≤ 1e-10 up to 8192, but 2.4e-7
/// above double-double's optimum at 16 384 and 5.5e-6 at 32 768 (9 800 fewer active), and
/// N = 65 536 and 10⁵ did not converge (line search failed: the directions were wrong); in
/// double-double IPOPT's optimum at 8192 to 1e-13 and N = 10⁵ converges in 13–14 iterations on its
/// finest level, at ~1.3–1.4× long double's time per iteration (5–7 vs 1.8 ns per multiply–add;
/// torque + rate limits at N = 2048: 9.8× faster than IPOPT instead of 13.2×).
constexpr int kExtendedPrecisionAboveSteps = 1024;
constexpr int kLongDoubleMaxSteps = 8192;
constexpr bool kLongDoubleIsX87 = std::numeric_limits<long double>::digits == 64;

PlanResult solveOnGrid(const PlanningProblem& problem, const SolverOptions& options,
                       Formulation formulation, bool predictor_corrector,
                       const ReducedProblem::Steps* coarse_steps,
                       ReducedProblem::Steps* final_steps, const LevelDuals* coarse_duals = nullptr,
                       LevelDuals* final_duals = nullptr) {
  const int N = problem.steps;
  if (N <= kExtendedPrecisionAboveSteps) {
    return solveOnGridIn<double>(problem, options, formulation, predictor_corrector, coarse_steps,
                                 final_steps, coarse_duals, final_duals);
  }
  if (kLongDoubleIsX87 && N <= kLongDoubleMaxSteps) {
    return solveOnGridIn<long double>(problem, options, formulation, predictor_corrector,
                                      coarse_steps, final_steps, coarse_duals, final_duals);
  }
  return solveOnGridIn<DoubleDouble>(problem, options, formulation, predictor_corrector,
                                     coarse_steps, final_steps, coarse_duals, final_duals);
}

/// Appends the levels `solved` reports to `levels` (every solve of a plan is listed, in order).
void appendLevels(std::vector<LevelSummary>* levels, const PlanResult& solved) {
  levels->insert(levels->end(), solved.levels.begin(), solved.levels.end());
}

/// solveOnGrid in one formulation, retried once in the other from the same start when it ends
/// infeasible or unconverged: free slacks with Mehrotra's predictor–corrector first (measured,
/// docs/constraints_notes.md: 42 % fewer iterations over the constrained scenes at N = 64 … 8192
/// and the same or lower optima; with the double-double system also above, where the elastic
/// form came first until session 28: torque + rate limits at N = 10⁵ in 14 finest-level
/// iterations, where the elastic form stopped after 25 and its retry took 25 more), the elastic
/// form first for the minimum-time probes. The elastic form stalls
/// where most nodes bind and the violated constraints' curvature (weighted by z → ρ) swamps the
/// Hessian, while the free-slack form's Hessian carries Newton's own multipliers (measured:
/// rate_limited with the variational scheme at N = 128, and torque plus rate limits at N = 128
/// that IPOPT solves, were answered "infeasible" by the elastic form alone); the elastic form
/// certifies infeasibility where the free-slack form's line search fails (the infeasible
/// torque and rate limits of test_interior_point).
PlanResult solveOnGridWithRetry(const PlanningProblem& problem, const SolverOptions& options,
                                const ReducedProblem::Steps* coarse_steps,
                                ReducedProblem::Steps* final_steps,
                                const LevelDuals* coarse_duals = nullptr,
                                LevelDuals* final_duals = nullptr) {
  const auto start = std::chrono::steady_clock::now();
  // The minimum-time search's feasibility probes (started from its last feasible plan) keep the
  // elastic form first: with free slacks first its T* came out up to 0.3 % longer on Bilimoria
  // and Wie's slew and its searches up to 2.7× slower (each infeasible probe paid both forms).
  const bool free_first = !options.constrained_from_warm_start;
  const Formulation forms[2] = {free_first ? Formulation::FreeSlacks : Formulation::Elastic,
                                free_first ? Formulation::Elastic : Formulation::FreeSlacks};
  const char* names[2] = {free_first ? "free slacks" : "the elastic form",
                          free_first ? "the elastic form" : "free slacks"};
  ReducedProblem::Steps first_steps;
  PlanResult first = solveOnGrid(problem, options, forms[0], free_first, coarse_steps, &first_steps,
                                 coarse_duals, final_duals);
  const bool retry = first.termination == Termination::Infeasible ||
                     first.termination == Termination::NotConverged;
  if (!retry) {
    if (final_steps) *final_steps = first_steps;
    return first;
  }
  if (final_duals) *final_duals = LevelDuals{};  // the retry's are not carried
  ReducedProblem::Steps second_steps;
  PlanResult second = solveOnGrid(problem, withRemainingBudget(options, start), forms[1], false,
                                  coarse_steps, &second_steps);
  // The answer: a converged solve, else an infeasibility certificate, else the first solve's
  // reason; every solve's levels and iterations are kept.
  const bool take_second = second.converged() || (first.termination != Termination::Infeasible &&
                                                  second.termination == Termination::Infeasible);
  PlanResult& answer = take_second ? second : first;
  const PlanResult& other = take_second ? first : second;
  std::vector<LevelSummary> levels = first.levels;
  appendLevels(&levels, second);
  answer.levels = levels;
  answer.iterations = first.iterations + second.iterations;
  answer.message +=
      take_second ? std::string("; solved with ") + names[1] + " after " + names[0] + " stopped: "
                  : std::string("; retried with ") + names[1] + ": ";
  answer.message += other.message;
  if (final_steps) *final_steps = take_second ? second_steps : first_steps;
  return answer;
}

/// The interior point on the requested grid, with grid continuation above
/// kCoarsestConstrainedGrid.
PlanResult solveContinued(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (problem.steps <= kCoarsestConstrainedGrid) {
    return solveOnGridWithRetry(problem, options, nullptr, nullptr);
  }
  // The coarsest level starts from its own unconstrained optimum; the finer from the coarser.
  std::vector<int> levels{problem.steps};
  while (levels.back() / 4 >= 16 && levels.back() > kCoarsestConstrainedGrid) {
    levels.push_back(levels.back() / 4);
  }
  ReducedProblem::Steps steps;
  LevelDuals duals;        // the last level's multipliers (free slacks), for the next one
  int feasible_level = 0;  // the finest coarser level that met every constraint
  int iterations = 0;
  std::vector<LevelSummary> solved_levels;  // every solve of every level, in order
  PlanResult result;
  bool stopped = false;  // cancelled or out of time: the remaining levels only carry the iterate
  for (auto level = levels.rbegin(); level != levels.rend(); ++level) {
    PlanningProblem at = problem;
    at.steps = *level;
    SolverOptions level_options = options;
    level_options.warm_start = nullptr;
    if (stopped) level_options.max_iterations = 0;
    PlanResult unconstrained;
    Maneuver resampled;
    if (steps.empty()) {
      // The coarsest level starts from its own unconstrained optimum; Newton reaches it from the
      // warm start (the requested grid's unconstrained optimum) resampled, instead of repeating
      // the grid continuation that found the warm start (measured on 20 constrained cases:
      // 878 → 753 iterations; starting the interior point from the resampled plan itself
      // saved more, 725, but ended further from IPOPT's optimum at N = 2048: 2.1e-9 vs 4.5e-10).
      if (options.warm_start && options.warm_start->steps() == problem.steps) {
        resampled.attitude = resampleAttitudes(*options.warm_start, at.steps);
        level_options.warm_start = &resampled;
      }
      unconstrained = solveWithNewton(at, level_options);
      level_options.warm_start = unconstrained.converged() ? &unconstrained.maneuver : nullptr;
      iterations += unconstrained.iterations;
      appendLevels(&solved_levels, unconstrained);
    }
    ReducedProblem::Steps next;
    LevelDuals next_duals;
    const PlanResult coarse = result;
    result = solveOnGridWithRetry(at, level_options, steps.empty() ? nullptr : &steps, &next,
                                  &duals, &next_duals);
    iterations += result.iterations;
    appendLevels(&solved_levels, result);
    const bool ran_out =
        result.termination == Termination::Cancelled || result.termination == Termination::TimedOut;
    if (!result.converged() && !ran_out && !stopped && !steps.empty() && *level % 2 == 0) {
      // A 4× refinement can start too far from the fine optimum where bounds bind near the ends
      // (measured: torque + rate limits, N = 10⁵ from 25 000, stalled 1 % over a bound near T):
      // once more through the level in between.
      PlanningProblem half = at;
      half.steps = *level / 2;
      ReducedProblem::Steps between, retried;
      SolverOptions from_coarse = withRemainingBudget(options, start);
      from_coarse.warm_start = nullptr;  // both start from the coarse steps
      const PlanResult middle = solveOnGridWithRetry(half, from_coarse, &steps, &between);
      iterations += middle.iterations;
      appendLevels(&solved_levels, middle);
      if (middle.converged()) {
        from_coarse.time_budget_s = withRemainingBudget(options, start).time_budget_s;
        PlanResult fine = solveOnGridWithRetry(at, from_coarse, &between, &retried);
        iterations += fine.iterations;
        appendLevels(&solved_levels, fine);
        if (fine.converged()) {
          fine.message += "; reached through N = " + std::to_string(half.steps) +
                          " after the direct refinement stopped: " + result.message;
          result = fine;
          next = retried;
        }
      }
    }
    if (stopped && coarse.termination == Termination::Infeasible) {
      // Answered on a coarse level; the finer ones only carry its iterate to the requested N.
      result.termination = Termination::Infeasible;
      result.message = coarse.message + " (on the N = " + std::to_string(coarse.maneuver.steps()) +
                       " level of the grid continuation)";
    }
    stopped = stopped || result.termination == Termination::Cancelled ||
              result.termination == Termination::Infeasible ||
              result.termination == Termination::TimedOut;
    steps = result.converged() || stopped ? next : ReducedProblem::Steps{};
    duals = result.converged() ? next_duals : LevelDuals{};
    if (result.converged() && !stopped) feasible_level = *level;
  }
  result.iterations = iterations;
  result.levels = solved_levels;
  if (result.termination == Termination::Infeasible && feasible_level > 0) {
    // A coarser grid met every constraint: the finer level's "infeasible" is its solver stopping
    // (the ℓ1 violation stalled at a local minimum), not a certificate about the request
    // (measured: torque + rate limits at N = 10⁵ stall there while N = 25 000 is feasible).
    result.termination = Termination::NotConverged;
    result.message = "not converged: the N = " + std::to_string(feasible_level) +
                     " level met every constraint, but a finer level stopped (" + result.message +
                     ")";
  }
  if (levels.size() > 1) {
    result.message += "; grid continuation from N = " + std::to_string(levels.back());
  }
  return result;
}

}  // namespace

PlanResult solveWithInteriorPoint(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = solveContinued(problem, options);
  // Pointing cones together with torque or rate limits, from a start inside a cone: the
  // iterate can leave the cone with torques far beyond their bounds and never recover (measured:
  // a Sun keep-out + |τ| ≤ 0.07 N m slew that IPOPT solves was called infeasible after 13
  // iterations). Retry once in two stages: the cones alone (a path around them), then every
  // constraint from that path.
  const bool stuck = result.termination == Termination::Infeasible ||
                     result.termination == Termination::NotConverged;
  const bool cones = std::any_of(problem.constraints.begin(), problem.constraints.end(),
                                 [](const PlanningConstraint& c) { return c.isCone(); });
  const bool others = problem.hasTorqueBounds() ||
                      std::any_of(problem.constraints.begin(), problem.constraints.end(),
                                  [](const PlanningConstraint& c) { return !c.isCone(); });
  if (!stuck || !cones || !others) return result;
  SolverOptions staged = withRemainingBudget(options, start);
  PlanningProblem cones_only = problem;
  cones_only.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  cones_only.constraints.clear();
  for (const PlanningConstraint& c : problem.constraints)
    if (c.isCone()) cones_only.constraints.push_back(c);
  const PlanResult around = solveContinued(cones_only, staged);
  int iterations = result.iterations + around.iterations;
  if (!around.converged()) return result;
  staged.warm_start = &around.maneuver;
  staged.time_budget_s = withRemainingBudget(options, start).time_budget_s;
  PlanResult second = solveContinued(problem, staged);
  iterations += second.iterations;
  const std::string first_message = result.message;
  // The staged answer replaces the first unless it did no better (then the first is kept: its
  // reason is the one measured from the requested start).
  std::vector<LevelSummary> solved_levels = result.levels;
  appendLevels(&solved_levels, around);
  appendLevels(&solved_levels, second);
  if (second.converged() || second.termination == Termination::Infeasible) result = second;
  result.iterations = iterations;
  result.levels = solved_levels;
  result.message +=
      "; retried in two stages (the cones alone, then every constraint from that "
      "path) after: " +
      first_message;
  return result;
}

// ---- warm start from a plan without multipliers (issue 30) ----
PlanResult solveWithInteriorPointFromGuess(const PlanningProblem& problem,
                                           const SolverOptions& options) {
  LevelDuals duals;
  ReducedProblem::Steps steps;
  try {
    ReducedProblem np(problem);
    np.setInteriorFromAttitudes(options.warm_start->attitude);
    InteriorPoint ip(problem, &np, Formulation::FreeSlacks);
    duals = ip.estimatedDuals();
    steps = np.current();
  } catch (const StepTooLarge&) {
    return solveWithInteriorPoint(problem, options);  // reports it
  }
  SolverOptions from = options;
  from.warm_start = nullptr;  // the guess's steps start the level, as a coarser level's would
  PlanResult result = solveOnGridWithRetry(problem, from, &steps, nullptr, &duals);
  result.message += "; from the initial guess, its multipliers re-derived";
  return result;
}
// ---- end warm start ----

}  // namespace attitude_planner
