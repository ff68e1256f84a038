// The time step h as a global unknown of the transcription: the objectives (objective.hpp), the
// h-derivatives of the torques (ReducedProblem::evaluateWithTimeStep) against central finite
// differences of the cost, and a bordered Newton solve of a free-h problem against a 1-D search
// over h with the fixed-h solver.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "attitude_planner/planner.hpp"
#include "planning/linalg/bordered_band.hpp"
#include "planning/transcription/minimum_time_objective.hpp"
#include "planning/transcription/objective.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "support/perturbed_problem.hpp"

using namespace attitude_planner;

namespace {

constexpr SchemeKind kDiscretizations[] = {SchemeKind::Paper, SchemeKind::Variational,
                                           SchemeKind::SecondOrder};

/// A generic problem: non-diagonal inertia, spinning ends, a 2 rad turn.
PlanningProblem randomProblem(SchemeKind scheme, int N, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PlanningProblem p;
  p.inertia << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  p.allow_nonphysical_inertia = true;
  p.duration = 6.0 + u(rng);
  p.steps = N;
  p.initial_velocity = 0.3 * Vector3(u(rng), u(rng), u(rng));
  p.final_attitude = so3::fromAxisAngle(Vector3(u(rng), u(rng), u(rng)), 2.0 + u(rng));
  p.final_velocity = 0.3 * Vector3(u(rng), u(rng), u(rng));
  p.scheme = scheme;
  return p;
}

using test_support::perturbedReducedProblem;

/// `p` with external effects strong against its torques and moving in time (T ≈ 6 s): a fast
/// "orbit" (n = 1 rad/s) and constant torques in the world and the body frame.
PlanningProblem withEffects(PlanningProblem p) {
  auto model = std::make_shared<EffectModel>();
  model->add(std::make_unique<GravityGradient>(1.0, 1.0, p.inertia));
  model->add(std::make_unique<DisturbanceTorque>(Vector3(0.5, -0.2, 0.3), TorqueFrame::World));
  model->add(std::make_unique<DisturbanceTorque>(Vector3(-0.1, 0.4, 0.2), TorqueFrame::Body));
  p.effects = model;
  return p;
}

/// Effort plus a term in T² (a time penalty with a minimum in T): an objective written outside
/// the library, as a user of the interface would.
class EffortPlusTimeSquared : public TranscriptionObjective {
 public:
  explicit EffortPlusTimeSquared(double kappa) : kappa_(kappa) {}
  std::string name() const override { return "effort + kappa T^2"; }
  double effortWeight() const override { return 1.0; }
  double timeTerm(double T, double* first, double* second) const override {
    *first = 2.0 * kappa_ * T;
    *second = 2.0 * kappa_;
    return kappa_ * T * T;
  }

 private:
  double kappa_;
};

/// Φ(δ, h) at the free attitudes R_j exp(δ_j^) and time step h, from the torques themselves
/// (ReducedProblem::cost: not the stencils the derivatives are built from).
double objectiveAt(const ReducedProblem& rp, const TranscriptionObjective& objective,
                   const Eigen::VectorXd& delta, double h) {
  ReducedProblem q = rp;
  q.setCurrent(rp.retract(delta, 1.0));
  q.setTimeStep(h);
  double first, second;
  return objective.effortWeight() * q.cost(q.current()) +
         objective.timeTerm(q.steps() * h, &first, &second);
}

/// The derivatives of evaluateWithTimeStep in the scaled unknowns (δ, η), h = h₀(1 + η) (so that
/// every entry has the objective's unit), against central differences of objectiveAt.
void expectDerivativesMatchFiniteDifferences(const ReducedProblem& rp,
                                             const TranscriptionObjective& objective,
                                             const std::string& label) {
  const int n = rp.unknowns();
  const double h0 = rp.timeStep();
  Eigen::VectorXd gradient, border;
  BandedSymmetricMatrix band(n, 8);
  double corner = 0.0;
  const double value = rp.evaluateWithTimeStep(objective, &gradient, &band, &border, &corner);
  Eigen::MatrixXd H(n + 1, n + 1);
  H.topLeftCorner(n, n) = band.toDense();
  H.topRightCorner(n, 1) = h0 * border;
  H.bottomLeftCorner(1, n) = h0 * border.transpose();
  H(n, n) = h0 * h0 * corner;
  Eigen::VectorXd g = gradient;
  g(n) *= h0;

  const auto f = [&](const Eigen::VectorXd& x) {
    return objectiveAt(rp, objective, x.head(n), h0 * (1.0 + x(n)));
  };
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n + 1);
  EXPECT_NEAR(f(zero), value, 1e-13 * std::abs(value)) << label;
  // Steps: 1e-6 for the gradient (truncation ~1e-12, round-off ~1e-10 relative), 1e-4 for the
  // second differences (truncation ~1e-8, round-off ~1e-8 relative).
  constexpr double kGradientStep = 1e-6, kHessianStep = 1e-4;
  Eigen::VectorXd g_fd(n + 1);
  for (int i = 0; i <= n; ++i) {
    Eigen::VectorXd e = zero;
    e(i) = kGradientStep;
    g_fd(i) = (f(e) - f(-e)) / (2 * kGradientStep);
  }
  const double g_scale = g_fd.cwiseAbs().maxCoeff();
  EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff(), 1e-7 * g_scale)
      << label << "\nanalytic " << g.transpose() << "\nfinite   " << g_fd.transpose();
  Eigen::MatrixXd H_fd(n + 1, n + 1);
  const double e2 = kHessianStep;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= i; ++j) {
      Eigen::VectorXd ei = zero, ej = zero;
      ei(i) = e2;
      ej(j) = e2;
      H_fd(i, j) = H_fd(j, i) =
          (f(ei + ej) - f(ei - ej) - f(ej - ei) + f(-ei - ej)) / (4 * e2 * e2);
    }
  }
  const double H_scale = H_fd.cwiseAbs().maxCoeff();
  EXPECT_LE((H - H_fd).cwiseAbs().maxCoeff(), 1e-5 * H_scale)
      << label << " (band " << (H - H_fd).topLeftCorner(n, n).cwiseAbs().maxCoeff() << ", border "
      << (H - H_fd).col(n).head(n).cwiseAbs().maxCoeff() << ", corner "
      << std::abs(H(n, n) - H_fd(n, n)) << " of " << H_scale << ")";
  // The border and corner themselves must be checked, not hidden under the band's scale.
  EXPECT_LE((H - H_fd).col(n).cwiseAbs().maxCoeff(),
            1e-5 * std::max(H_fd.col(n).cwiseAbs().maxCoeff(), 1e-3 * H_scale))
      << label << "\nborder analytic " << H.col(n).transpose() << "\nborder finite   "
      << H_fd.col(n).transpose();
}

}  // namespace

// Every discretization, three random problems each, and objectives with and without a time term.
TEST(GlobalUnknowns, TimeStepDerivativesMatchFiniteDifferences) {
  const EffortObjective effort;
  const TimePlusEffortObjective time_plus_effort(0.01);
  const EffortPlusTimeSquared effort_plus_time_squared(0.7);
  // Free time's objective T/T₀ + ε(μ)C at a barrier between μ₀ and its floor.
  MinimumTimeObjective minimum_time(9, 0.3, 2.0, 0.1);
  minimum_time.setBarrier(0.01);
  // ... and on a scale shared with other starts (T₀ = 3.7 s, not N h₀ = 2.7 s).
  MinimumTimeObjective shared_scale(9, 0.3, 2.0, 0.1, 3.7);
  shared_scale.setBarrier(0.01);
  const TranscriptionObjective* objectives[] = {
      &effort, &time_plus_effort, &effort_plus_time_squared, &minimum_time, &shared_scale};
  for (SchemeKind scheme : kDiscretizations) {
    for (unsigned seed : {1u, 2u, 3u}) {
      for (const bool effects : {false, true}) {
        const PlanningProblem problem = randomProblem(scheme, 9, seed);
        const ReducedProblem rp =
            perturbedReducedProblem(effects ? withEffects(problem) : problem, 10 + seed);
        for (const TranscriptionObjective* objective : objectives) {
          expectDerivativesMatchFiniteDifferences(
              rp, *objective,
              schemeName(scheme) + " seed " + std::to_string(seed) + " " + objective->name() +
                  (effects ? " with effects" : ""));
        }
      }
    }
  }
}

// The torques' own h-derivative ∂r_k/∂h (what constraints on τ will need), node by node, and
// with weights w unrelated to the torques (a constraint's multipliers) ∂²(wᵀr_k)/∂h² and
// ∂²(wᵀr_k)/∂δ∂h on the free nodes; with and without effects (whose time t_k = k h moves).
TEST(GlobalUnknowns, TorqueTimeDerivativesMatchFiniteDifferences) {
  for (SchemeKind scheme : kDiscretizations) {
    for (const bool effects : {false, true}) {
      const PlanningProblem problem = randomProblem(scheme, 10, 4);
      const ReducedProblem rp =
          perturbedReducedProblem(effects ? withEffects(problem) : problem, 5);
      const std::string label = schemeName(scheme) + (effects ? " with effects" : "");
      const double h = rp.timeStep(), step = 1e-6 * h, wide = 1e-4 * h;
      const auto at = [&](double dh) {
        ReducedProblem q = rp;
        q.setTimeStep(h + dh);
        return q;
      };
      const ReducedProblem plus = at(step), minus = at(-step), wide_plus = at(wide),
                           wide_minus = at(-wide);
      const std::vector<Vector3> tau = rp.torques(rp.current());
      const std::vector<Vector3> tau_plus = plus.torques(plus.current());
      const std::vector<Vector3> tau_minus = minus.torques(minus.current());
      const std::vector<Vector3> tau_wide_plus = wide_plus.torques(wide_plus.current());
      const std::vector<Vector3> tau_wide_minus = wide_minus.torques(wide_minus.current());
      std::mt19937 rng(6);
      std::normal_distribution<double> normal;
      std::vector<Vector3> weight(rp.steps() + 1);
      for (Vector3& w : weight) w = Vector3(normal(rng), normal(rng), normal(rng));
      // Jᵀw of every stencil at h ± step, over (δ_{k−1}, δ_k, δ_{k+1}).
      const auto weighted_jacobians = [&](const ReducedProblem& q) {
        std::vector<Eigen::Matrix<double, 9, 1>> out(q.steps() + 1);
        q.forEachStencil(false, [&](const ReducedProblem::Stencil& st) {
          out[st.k] = st.jacobian.transpose() * weight[st.k];
        });
        return out;
      };
      const auto jw_plus = weighted_jacobians(plus), jw_minus = weighted_jacobians(minus);
      double scale = 0.0;
      for (const Vector3& t : tau) scale = std::max(scale, t.norm() / h);
      int visited = 0;
      rp.forEachStencilWithTimeStep(
          [&](const ReducedProblem::TimeStepStencil& st) {
            const int k = st.k;
            const double root = std::sqrt(rp.scheme().torqueWeight(k, rp.steps()));
            const Vector3 fd = root * (tau_plus[k] - tau_minus[k]) / (2 * step);
            EXPECT_LE((st.tau_h - fd).norm(), 1e-7 * scale) << label << " k " << k;
            const double fd_hh = root *
                                 weight[k].dot(tau_wide_plus[k] - 2 * tau[k] + tau_wide_minus[k]) /
                                 (wide * wide);
            EXPECT_NEAR(st.second_hh, fd_hh, 1e-5 * weight[k].norm() * scale / h)
                << label << " k " << k;
            for (int s = 0; s < 3; ++s) {
              if (rp.variableIndex(k - 1 + s) < 0) continue;  // free nodes: held as h moves
              const Vector3 fd_h = (jw_plus[k] - jw_minus[k]).segment<3>(3 * s) / (2 * step);
              EXPECT_LE((st.second_h.segment<3>(3 * s) - fd_h).norm(),
                        1e-6 * (fd_h.norm() + weight[k].norm() * st.jacobian.norm() / h))
                  << label << " k " << k << " node " << k - 1 + s;
            }
            ++visited;
          },
          [&](int k, const Vector3&) { return weight[k]; });
      EXPECT_EQ(visited, scheme == SchemeKind::SecondOrder ? rp.steps() + 1 : rp.steps() - 1);
    }
  }
}

// Today's objective is unchanged: the band and the node gradient are evaluate()'s, bit for bit.
TEST(GlobalUnknowns, EffortObjectiveIsTodaysEvaluateBitForBit) {
  for (SchemeKind scheme : kDiscretizations) {
    const ReducedProblem rp = perturbedReducedProblem(randomProblem(scheme, 40, 6), 7);
    const int n = rp.unknowns();
    Eigen::VectorXd g_today, g, border;
    BandedSymmetricMatrix H_today(n, 8), H(n, 8);
    double scale = 0.0, corner = 0.0;
    const double c_today = rp.evaluate(&g_today, &H_today, &scale);
    const double c = rp.evaluateWithTimeStep(EffortObjective(), &g, &H, &border, &corner);
    EXPECT_EQ(c, c_today);
    EXPECT_EQ((g.head(n) - g_today).cwiseAbs().maxCoeff(), 0.0) << schemeName(scheme);
    EXPECT_EQ((H.toDense() - H_today.toDense()).cwiseAbs().maxCoeff(), 0.0) << schemeName(scheme);
  }
}

TEST(GlobalUnknowns, TimeObjectiveIsTheDuration) {
  const ReducedProblem rp =
      perturbedReducedProblem(randomProblem(SchemeKind::SecondOrder, 20, 8), 9);
  const int n = rp.unknowns();
  Eigen::VectorXd g, border;
  BandedSymmetricMatrix H(n, 8);
  double corner = 1.0;
  const double T = rp.evaluateWithTimeStep(TimeObjective(), &g, &H, &border, &corner);
  EXPECT_DOUBLE_EQ(T, rp.steps() * rp.timeStep());
  EXPECT_EQ(g.head(n).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(g(n), rp.steps());  // dT/dh = N
  EXPECT_EQ(H.toDense().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(corner, 0.0);
  EXPECT_THROW(TimePlusEffortObjective(-1.0), InvalidInput);
}

// setTimeStep keeps the free attitudes and honours the boundary velocities at the new h: its
// torques are those of a problem built at that duration through the same attitudes (with
// effects too: read at t_k = k h_new).
// Free time's objective: 1 + ε₀C₀ = 1 + kInitialEffortShare at the start, ε(μ) linear in μ
// between μ₀ and its floor kFinalEffortFraction ε₀, and its value through evaluateWithTimeStep
// (the stencils) the one the solver's merit forms from the torques.
TEST(GlobalUnknowns, MinimumTimeObjectiveStartsAtOneAndItsEffortWeightFollowsTheBarrier) {
  for (unsigned seed : {4u, 5u, 6u}) {
    const ReducedProblem rp =
        perturbedReducedProblem(randomProblem(SchemeKind::SecondOrder, 12, seed), seed);
    const double h0 = rp.timeStep(), C0 = rp.cost(rp.current()), mu0 = 0.1 / (seed + 1);
    MinimumTimeObjective objective(rp.steps(), h0, C0, mu0);
    const double epsilon0 = objective.setBarrier(mu0);
    EXPECT_NEAR(objective.value(h0, C0, epsilon0), 1.0 + MinimumTimeObjective::kInitialEffortShare,
                1e-15);
    EXPECT_EQ(objective.setBarrier(10 * mu0), epsilon0);
    EXPECT_NEAR(objective.setBarrier(0.25 * mu0), 0.25 * epsilon0, 1e-16 * epsilon0);
    EXPECT_NEAR(objective.setBarrier(1e-20 * mu0),
                MinimumTimeObjective::kFinalEffortFraction * epsilon0, 1e-16 * epsilon0);
    const double epsilon = objective.setBarrier(0.5 * mu0);
    Eigen::VectorXd g;
    const double value = rp.evaluateWithTimeStep(objective, &g, nullptr, nullptr, nullptr);
    EXPECT_NEAR(value, objective.value(h0, C0, epsilon), 1e-14);
    // Without effort (C₀ = 0: ε = 0) ∂Φ/∂η = h₀ ∂Φ/∂h is the time row the solver adds, 1.
    const MinimumTimeObjective time_only(rp.steps(), h0, 0.0, mu0);
    rp.evaluateWithTimeStep(time_only, &g, nullptr, nullptr, nullptr);
    EXPECT_NEAR(g(rp.unknowns()) * h0, time_only.timeGradient(), 1e-15);
    EXPECT_NEAR(time_only.timeGradient(), 1.0, 1e-15);
    EXPECT_NEAR(objective.lowerBound(h0, 0.0, C0, 0.0), rp.steps() * h0, 1e-15 * rp.steps() * h0);
  }
}

// On a scale shared by the starts of one grid (FreeTimeScale: T₀ and C₀ a reference's, not the
// start's): Φ = T/T₀ + εC with ε₀ C₀ = kInitialEffortShare, the time row N h₀/T₀ (the unknown
// is still η = h/h₀), and the lower bound T − T₀ (gap + εC) in that T₀.
TEST(GlobalUnknowns, MinimumTimeObjectiveOnASharedScaleMeasuresTimeInTheReferenceDuration) {
  for (unsigned seed : {7u, 8u}) {
    const ReducedProblem rp =
        perturbedReducedProblem(randomProblem(SchemeKind::SecondOrder, 12, seed), seed);
    const double h0 = rp.timeStep(), C0 = rp.cost(rp.current()), mu0 = 0.1;
    const double T_ref = 1.3 * rp.steps() * h0, C_ref = 0.6 * C0;
    MinimumTimeObjective objective(rp.steps(), h0, C_ref, mu0, T_ref);
    const double epsilon0 = objective.setBarrier(mu0);
    EXPECT_NEAR(epsilon0 * C_ref, MinimumTimeObjective::kInitialEffortShare, 1e-16);
    EXPECT_NEAR(objective.value(h0, C0, epsilon0), rp.steps() * h0 / T_ref + epsilon0 * C0, 1e-15);
    Eigen::VectorXd g;
    const double value = rp.evaluateWithTimeStep(objective, &g, nullptr, nullptr, nullptr);
    EXPECT_NEAR(value, objective.value(h0, C0, epsilon0), 1e-14);
    const MinimumTimeObjective time_only(rp.steps(), h0, 0.0, mu0, T_ref);
    rp.evaluateWithTimeStep(time_only, &g, nullptr, nullptr, nullptr);
    EXPECT_NEAR(g(rp.unknowns()) * h0, time_only.timeGradient(), 1e-15);
    EXPECT_NEAR(time_only.timeGradient(), rp.steps() * h0 / T_ref, 1e-15);
    const double h = 0.9 * h0, gap = 1e-3, epsilon = 0.5 * epsilon0;
    EXPECT_NEAR(objective.lowerBound(h, gap, C0, epsilon),
                rp.steps() * h - T_ref * (gap + epsilon * C0), 1e-14 * T_ref);
  }
}

TEST(GlobalUnknowns, SetTimeStepIsTheProblemAtTheNewDuration) {
  for (SchemeKind scheme : kDiscretizations) {
    for (const bool effects : {false, true}) {
      PlanningProblem problem =
          effects ? withEffects(randomProblem(scheme, 16, 10)) : randomProblem(scheme, 16, 10);
      ReducedProblem rp = perturbedReducedProblem(problem, 11);
      const std::vector<Matrix3> R_before = rp.attitudes(rp.current());
      const double h = rp.timeStep(), h_new = 1.3 * h;
      rp.setTimeStep(h_new);
      problem.duration = problem.steps * h_new;
      ReducedProblem fresh(problem);
      fresh.setInteriorFromAttitudes(R_before);
      const std::vector<Matrix3> R_after = rp.attitudes(rp.current());
      for (int j = rp.firstFreeNode(); j <= rp.lastFreeNode(); ++j) {
        EXPECT_LE((R_after[j] - R_before[j]).cwiseAbs().maxCoeff(), 1e-14) << j;
      }
      const std::vector<Vector3> tau = rp.torques(rp.current());
      const std::vector<Vector3> tau_fresh = fresh.torques(fresh.current());
      double scale = 0.0, difference = 0.0;
      for (size_t k = 0; k < tau.size(); ++k) {
        scale = std::max(scale, tau_fresh[k].norm());
        difference = std::max(difference, (tau[k] - tau_fresh[k]).norm());
      }
      EXPECT_LE(difference, 1e-10 * scale) << schemeName(scheme) << " effects " << effects;
      // And back: the same steps to round-off.
      ReducedProblem back = rp;
      back.setTimeStep(h);
      const ReducedProblem original = perturbedReducedProblem(randomProblem(scheme, 16, 10), 11);
      for (int j = 0; j < rp.steps(); ++j) {
        EXPECT_LE((back.current()[j] - original.current()[j]).norm(), 1e-14) << j;
      }
    }
  }
}

TEST(GlobalUnknowns, RefusedForANonPositiveTimeStep) {
  const PlanningProblem problem = randomProblem(SchemeKind::Variational, 12, 12);
  ReducedProblem plain(problem);
  EXPECT_THROW(plain.setTimeStep(0.0), InvalidInput);
  EXPECT_THROW(plain.setTimeStep(std::nan("")), InvalidInput);
  ReducedProblem with_effects(withEffects(problem));
  EXPECT_THROW(with_effects.setTimeStep(-0.1), InvalidInput);
}

namespace {

/// Ψ(T) = min over the attitudes of C at duration T, plus κT²: the fixed-h solver's answer.
double profileAt(PlanningProblem problem, double kappa, double T) {
  problem.duration = T;
  const PlanResult result = planManeuver(problem);
  EXPECT_TRUE(result.converged()) << result.message();
  return result.cost + kappa * T * T;
}

/// min_T Ψ(T) by a scan over [T_low, T_high] then golden-section search around the best sample.
double minimizeProfile(const PlanningProblem& problem, double kappa, double T_low, double T_high) {
  constexpr int kSamples = 17;
  int best = 0;
  std::vector<double> T(kSamples), psi(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    T[i] = T_low + (T_high - T_low) * i / (kSamples - 1);
    psi[i] = profileAt(problem, kappa, T[i]);
    if (psi[i] < psi[best]) best = i;
  }
  EXPECT_GT(best, 0);
  EXPECT_LT(best, kSamples - 1);  // an interior minimum
  double a = T[std::max(best - 1, 0)], b = T[std::min(best + 1, kSamples - 1)];
  const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - ratio * (b - a), d = a + ratio * (b - a);
  double fc = profileAt(problem, kappa, c), fd = profileAt(problem, kappa, d);
  while (b - a > 1e-9 * b) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - ratio * (b - a), fc = profileAt(problem, kappa, c);
    } else {
      a = c, c = d, fc = fd, d = a + ratio * (b - a), fd = profileAt(problem, kappa, d);
    }
  }
  return 0.5 * (a + b);
}

struct FreeTimeStepSolve {
  double duration = 0.0, value = 0.0;
  std::vector<double> gradient_norms;  ///< |∇Φ| in (δ, η = Δh/h) per iterate
  bool converged = false;
};

/// Newton on Φ(δ, h) with the bordered banded step (band: the node unknowns, border: h), a
/// backtracking line search on Φ. Every Hessian met must be positive definite (the start is the
/// fixed-h optimum near the answer): this is the machinery, not a product solver.
FreeTimeStepSolve solveWithFreeTimeStep(ReducedProblem rp,
                                        const TranscriptionObjective& objective) {
  constexpr int kMaxIterations = 30;
  constexpr double kRelativeGradientTolerance = 1e-13, kRoundOffFloor = 1e-9;
  FreeTimeStepSolve out;
  const int n = rp.unknowns();
  for (int it = 0; it < kMaxIterations; ++it) {
    Eigen::VectorXd g, border;
    BandedSymmetricMatrix band(n, 8);
    double corner = 0.0;
    const double value = rp.evaluateWithTimeStep(objective, &g, &band, &border, &corner);
    const double h = rp.timeStep();
    Eigen::VectorXd scaled = g;
    scaled(n) *= h;
    out.gradient_norms.push_back(scaled.norm());
    out.duration = rp.steps() * h;
    out.value = value;
    // Converged at the tolerance, or at the round-off floor (below kRoundOffFloor, no longer
    // halving).
    const double r = scaled.norm() / out.gradient_norms.front();
    const size_t k = out.gradient_norms.size();
    const bool stalled =
        k >= 2 && r < kRoundOffFloor && out.gradient_norms[k - 1] > 0.5 * out.gradient_norms[k - 2];
    if (r <= kRelativeGradientTolerance || stalled) {
      out.converged = true;
      break;
    }
    BorderedBanded factor;
    if (!factor.factor(band, Eigen::MatrixXd(border), Eigen::MatrixXd::Constant(1, 1, corner))) {
      ADD_FAILURE() << "bordered factorization failed at iteration " << it;
      break;
    }
    EXPECT_EQ(factor.inertia().negative, 0) << "iteration " << it;
    Eigen::VectorXd step = -g;
    factor.solve(&step);
    const double slope = g.dot(step);
    double alpha = 1.0;
    ReducedProblem trial = rp;
    for (int back = 0; back < 30; ++back, alpha *= 0.5) {
      trial = rp;
      trial.setCurrent(rp.retract(step.head(n), alpha));
      trial.setTimeStep(h + alpha * step(n));
      double first, second;
      const double trial_value =
          objective.effortWeight() * trial.cost(trial.current()) +
          objective.timeTerm(trial.steps() * trial.timeStep(), &first, &second);
      if (trial_value <= value + 1e-4 * alpha * slope || std::abs(slope) < 1e-14 * value) break;
    }
    rp = trial;
  }
  return out;
}

}  // namespace

// min C + κT² over the attitudes and h at once (one Newton solve with a bordered step), against
// a scan over T of the fixed-h solver's minima: the same T* and Φ*, reached quadratically.
TEST(GlobalUnknowns, FreeTimeStepNewtonAgreesWithAScanOverTheDuration) {
  for (SchemeKind scheme : kDiscretizations) {
    PlanningProblem problem = randomProblem(scheme, 24, 20);
    problem.duration = 6.0;
    // κ = 2 C(6)/6²: C ~ T⁻⁴ puts the minimum near T = 6 s; start the free solve at T = 5 s.
    const double kappa = 2.0 * planManeuver(problem).cost / 36.0;
    problem.duration = 5.0;
    const PlanResult start = planManeuver(problem);
    ASSERT_TRUE(start.converged()) << start.message();
    ReducedProblem rp(problem);
    rp.setInteriorFromAttitudes(start.maneuver.attitude);
    const FreeTimeStepSolve free = solveWithFreeTimeStep(rp, EffortPlusTimeSquared(kappa));
    ASSERT_TRUE(free.converged) << schemeName(scheme);

    const double T_scan = minimizeProfile(problem, kappa, 3.0, 10.0);
    const double psi_scan = profileAt(problem, kappa, T_scan);
    std::printf("%-12s T* free h %.12f  scan %.12f  Phi* %.14g  %.14g  iterations %zu\n",
                schemeName(scheme).c_str(), free.duration, T_scan, free.value, psi_scan,
                free.gradient_norms.size() - 1);
    for (size_t i = 0; i < free.gradient_norms.size(); ++i) {
      std::printf("  |grad| %zu  %.3e\n", i, free.gradient_norms[i]);
    }
    EXPECT_NEAR(free.duration, T_scan, 1e-6 * T_scan) << schemeName(scheme);
    EXPECT_NEAR(free.value, psi_scan, 1e-11 * psi_scan) << schemeName(scheme);
    // Quadratic convergence: once the relative gradient r is below 1e-2, each step squares it
    // (r_{k+1} ≤ 10 r_k², a linear rate fails this), until round-off (1e-11) is reached.
    const double g0 = free.gradient_norms.front();
    int quadratic_steps = 0;
    for (size_t i = 0; i + 1 < free.gradient_norms.size(); ++i) {
      const double r = free.gradient_norms[i] / g0, r_next = free.gradient_norms[i + 1] / g0;
      if (r > 1e-2 || r_next < 1e-11) continue;
      EXPECT_LE(r_next, 10.0 * r * r) << schemeName(scheme) << " iteration " << i;
      ++quadratic_steps;
    }
    EXPECT_GE(quadratic_steps, 1) << schemeName(scheme);
  }
}
