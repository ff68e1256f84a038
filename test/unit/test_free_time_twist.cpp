// The twist ψ of a pointing end condition as a global unknown of the free-time interior point:
// its entries of the Newton system against central differences, and minimum-time pointing answers
// against a sweep of fixed twists on seeded random requests on Betts's body.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "planning/transcription/stage_transcription.hpp"
#include "support/perturbed_problem.hpp"
#include "support/pointing_requests.hpp"

using namespace attitude_planner;

namespace {

constexpr SchemeKind kDiscretizations[] = {SchemeKind::Paper, SchemeKind::Variational,
                                           SchemeKind::SecondOrder};

/// ψ's entries of the free-time system of L = C (the effort alone: weights r), summed over the
/// stencils as the solver scatters them: ∂C/∂ψ, ∂²C/∂ψ∂η, ∂²C/∂ψ² and ∂²C/∂δ∂ψ (η = h/h₀).
struct SummedEntries {
  double gradient = 0.0, time = 0.0, twist = 0.0;
  Eigen::VectorXd nodes;
  double path_term = 0.0;  ///< the part of `time` from the path's curvature at R_{N−1}
};

/// The ψ entries a KktSink over (δ, η, ψ) and addLocalVector left: ∂L/∂ψ, ∂²L/∂ψ∂η, ∂²L/∂ψ²,
/// ∂²L/∂δ∂ψ, and ∂L/∂η, ∂²L/∂η², ∂L/∂δ.
struct Scattered {
  KktBlocks<double> kkt;
  Eigen::VectorXd gradient;
  Scattered(const ReducedProblem& rp, double h0)
      : kkt(rp.unknowns()), sink(rp, FreeTimeStep{h0}, &kkt), rp_(rp) {
    gradient = Eigen::VectorXd::Zero(rp.unknowns() + 2);
  }
  /// One local block with its Lagrangian gradient, as the solver scatters it.
  void add(int first, int width, const Eigen::Matrix<double, 10, 10>& H,
           const Eigen::Matrix<double, 10, 1>& lagrangian) {
    sink.addBlock(first, width, H, &lagrangian);
    addLocalVector<FreeTimeStep>(rp_, lagrangian, 1.0, first, width, &gradient);
  }
  double twistGradient() const { return gradient(rp_.unknowns() + 1); }
  double time() const { return kkt.corner(0, 1); }
  double twist() const { return kkt.corner(1, 1); }
  Eigen::VectorXd nodes() const { return kkt.border.col(1); }
  KktSink<double, FreeTimeStep> sink;

 private:
  const ReducedProblem& rp_;
};

SummedEntries summedEntries(const ReducedProblem& rp) {
  const double h0 = rp.timeStep();
  SummedEntries sum;
  Scattered scattered(rp, h0);
  rp.forEachStencilWithTimeStep([&](const ReducedProblem::TimeStepStencil& st) {
    Eigen::Matrix<double, 3, 10> G;
    G.leftCols<9>() = st.jacobian;
    G.col(9) = st.tau_h * h0;
    Eigen::Matrix<double, 10, 10> H = G.transpose() * G;
    H.topLeftCorner<9, 9>() += st.second;
    H.block<9, 1>(0, 9) += st.second_h * h0;
    H.block<1, 9>(9, 0) += (st.second_h * h0).transpose();
    H(9, 9) += st.second_hh * h0 * h0;
    const Eigen::Matrix<double, 10, 1> lagrangian = G.transpose() * st.tau;
    scattered.add(st.k - 1, 3, H, lagrangian);
    const int slot = rp.steps() - 1 - (st.k - 1);
    if (slot >= 0 && slot < 3) {
      const Vector3 e = rp.twistMotion(rp.steps() - 1), d = rp.nodePath(rp.steps() - 1).first * h0;
      sum.path_term += lagrangian.segment<3>(3 * slot).dot(0.5 * e.cross(d));
    }
  });
  sum.gradient = scattered.twistGradient();
  sum.time = scattered.time();
  sum.twist = scattered.twist();
  sum.nodes = scattered.nodes();
  return sum;
}

/// rp with h = h₀(1 + a) and ψ moved by b, the free attitudes held.
ReducedProblem movedTo(const ReducedProblem& rp, double a, double b) {
  ReducedProblem q = rp;
  q.setCurrentWithTwist(q.retractWithTwist(Eigen::VectorXd::Zero(q.unknowns()), b, 1.0), b);
  q.setTimeStep(rp.timeStep() * (1.0 + a));
  return q;
}

double costAt(const ReducedProblem& rp, double a, double b) {
  const ReducedProblem q = movedTo(rp, a, b);
  return q.cost(q.current());
}

TEST(FreeTimeTwist, EntriesMatchCentralDifferencesForEveryScheme) {
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    // Spinning ends: h moves R_1 and R_{N−1} of paper and variational (the path's curvature term).
    PlanningProblem p = test_support::randomPointingRequest(17, 24, true, scheme);
    p.final_attitude = pointingAttitude(p.end_condition, 0.4);
    const ReducedProblem rp = test_support::perturbedReducedProblem(p, 5);
    const SummedEntries got = summedEntries(rp);
    const double C = rp.cost(rp.current()), e = 1e-4;
    const double slope = (costAt(rp, 0, e) - costAt(rp, 0, -e)) / (2 * e);
    EXPECT_NEAR(got.gradient, slope, 1e-6 * (std::abs(slope) + C));
    const double curvature = (costAt(rp, 0, e) - 2 * C + costAt(rp, 0, -e)) / (e * e);
    EXPECT_NEAR(got.twist, curvature, 1e-4 * (std::abs(curvature) + C));
    const double mixed =
        (costAt(rp, e, e) - costAt(rp, e, -e) - costAt(rp, -e, e) + costAt(rp, -e, -e)) /
        (4 * e * e);
    EXPECT_NEAR(got.time, mixed, 1e-4 * (std::abs(mixed) + C));
    if (scheme != SchemeKind::SecondOrder) {  // the curvature term: 10x the tolerance above
      EXPECT_GT(std::abs(got.path_term), 1e-3 * (std::abs(mixed) + C));
    }
    // The border: ∂/∂ψ of the node gradient (evaluateWithTwist's node part) at ±Δψ.
    const auto nodeGradient = [&](double b) {
      Eigen::VectorXd g, unused_border;
      double unused_corner = 0.0, unused_scale = 0.0;
      movedTo(rp, 0, b).evaluateWithTwist(&g, nullptr, &unused_border, &unused_corner,
                                          &unused_scale);
      return Eigen::VectorXd(g.head(rp.unknowns()));
    };
    const Eigen::VectorXd fd = (nodeGradient(e) - nodeGradient(-e)) / (2 * e);
    EXPECT_LT((fd - got.nodes).cwiseAbs().maxCoeff(),
              1e-5 * (got.nodes.cwiseAbs().maxCoeff() + 1.0));
  }
}

/// ψ's and η's entries of L = Σ q over every instance of the stage quantities other than the
/// torque (a cone, a rate) on the twist's support (supportWithTwist: R_{N−1}, R_N are rows), as
/// the free-time solver scatters them (λ = 1 for every instance), and L itself.
struct RowSums {
  double value = 0.0;                              ///< L
  double gradient = 0.0, time = 0.0, twist = 0.0;  ///< ∂L/∂ψ, ∂²L/∂ψ∂η, ∂²L/∂ψ²
  double time_gradient = 0.0, time_curvature = 0.0;  ///< ∂L/∂η, ∂²L/∂η²
  Eigen::VectorXd nodes;                             ///< ∂²L/∂δ∂ψ
  Eigen::VectorXd node_gradient;                     ///< ∂L/∂δ
};

RowSums rowSums(const PlanningProblem& p, const ReducedProblem& rp, double h0) {
  RowSums sum;
  Scattered scattered(rp, h0);
  const StageConstraints constraints = buildStageConstraints(p);
  const QuantityInputs at(rp, rp.current());
  const auto unit = [](int, const Vector3&) { return Vector3(1.0, 0.0, 0.0); };
  for (const auto& c : constraints) {
    const StageQuantityModel& q = c->quantityModel();
    if (q.formedByCostStencil()) continue;
    const StageSupport support =
        q.supportWithTwist(rp.firstFreeNode(), rp.lastFreeNode(), rp.steps());
    for (int k = support.first_k; k <= support.last_k; ++k) sum.value += q.value(at, k)(0);
    q.forEachTermsWithTimeStep(rp, support, h0, unit, [&](const QuantityTermsWithTimeStep& t) {
      const Eigen::Matrix<double, 10, 1> g = t.jacobian.row(0).transpose();
      scattered.add(t.k + support.node_offset, support.width, t.curvature, g);
    });
  }
  const int n = rp.unknowns();
  sum.gradient = scattered.twistGradient();
  sum.time = scattered.time();
  sum.twist = scattered.twist();
  sum.time_gradient = scattered.gradient(n);
  sum.time_curvature = scattered.kkt.corner(0, 0);
  sum.nodes = scattered.nodes();
  sum.node_gradient = scattered.gradient.head(n);
  return sum;
}

TEST(FreeTimeTwist, ConeAndRateRowsOnTheNodesTheTwistMovesMatchCentralDifferences) {
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    // Spinning ends (h moves R_{N−1} of paper and variational); a cone on an axis other than the
    // boresight (ψ moves its value at R_{N−1} and R_N) and a rate limit.
    PlanningProblem p = test_support::randomPointingRequest(23, 24, true, scheme);
    p.final_attitude = pointingAttitude(p.end_condition, -0.7);
    const Vector3 other = p.end_condition.body_axis.unitOrthogonal();
    p.constraints.push_back(PlanningConstraint::keepOut(other, Vector3(0.3, -0.5, 0.8), 0.2));
    p.constraints.push_back(PlanningConstraint::maxAngularRate(10.0));
    const ReducedProblem rp = test_support::perturbedReducedProblem(p, 7);
    const double h0 = rp.timeStep(), e = 1e-4;
    const RowSums got = rowSums(p, rp, h0);
    const auto L = [&](double a, double b) { return rowSums(p, movedTo(rp, a, b), h0).value; };
    const double L0 = got.value;
    const double twist_slope = (L(0, e) - L(0, -e)) / (2 * e);
    EXPECT_NE(got.gradient, 0.0);  // the rows on R_{N−1}, R_N move with ψ
    EXPECT_NEAR(got.gradient, twist_slope, 1e-6 * (std::abs(twist_slope) + 1.0));
    const double twist_curvature = (L(0, e) - 2 * L0 + L(0, -e)) / (e * e);
    EXPECT_NEAR(got.twist, twist_curvature, 1e-4 * (std::abs(twist_curvature) + 1.0));
    const double mixed = (L(e, e) - L(e, -e) - L(-e, e) + L(-e, -e)) / (4 * e * e);
    EXPECT_NEAR(got.time, mixed, 1e-4 * (std::abs(mixed) + 1.0));
    const double time_slope = (L(e, 0) - L(-e, 0)) / (2 * e);
    EXPECT_NEAR(got.time_gradient, time_slope, 1e-6 * (std::abs(time_slope) + 1.0));
    const double time_curvature = (L(e, 0) - 2 * L0 + L(-e, 0)) / (e * e);
    EXPECT_NEAR(got.time_curvature, time_curvature, 1e-4 * (std::abs(time_curvature) + 1.0));
    const Eigen::VectorXd fd = (rowSums(p, movedTo(rp, 0, e), h0).node_gradient -
                                rowSums(p, movedTo(rp, 0, -e), h0).node_gradient) /
                               (2 * e);
    EXPECT_LT((fd - got.nodes).cwiseAbs().maxCoeff(),
              1e-5 * (got.nodes.cwiseAbs().maxCoeff() + 1.0));
  }
}

/// Every row's gradient over the transcription's unknowns, formed through its passes (the torque
/// rows in the cost's stencil pass, the others by quantity) with no barrier form.
template <typename TimeStep>
void formGradients(StageTranscription<TimeStep>* rows, const ReducedProblem& rp,
                   const TimeStep& step) {
  using Rows = typename StageTranscription<TimeStep>::Rows;
  using Row = typename StageTranscription<TimeStep>::Row;
  const auto cost = [](int, const Vector3& r) { return r; };
  const auto row = [](const Rows&, Row&, double) {};
  rows->forEachTorqueStencil(rp, step, false, cost, row,
                             [&](const typename TimeStep::Stencil& st, double root) {
                               rows->chainTorques(st, root, step.jacobian(st),
                                                  [](const Rows&, const Row&, const Vector3&) {});
                             });
  for (const std::vector<int>& block : rows->blocks) {
    rows->forEachQuantityInstance(
        rp, step, block, false, [](int) {}, [](const Rows&, Row&) {},
        [](const auto&, const auto*) {});
  }
}

/// The rows' values after the transcription's move by t·d over (δ, η, ψ): h first (free time's
/// order), then the nodes and the twist (retract, accept).
template <typename TimeStep>
std::vector<double> valuesMovedBy(const StageTranscription<TimeStep>& rows,
                                  const ReducedProblem& rp, const Eigen::VectorXd& d, double t,
                                  double h0) {
  ReducedProblem q = rp;
  if constexpr (TimeStep::kEntries == 10) q.setTimeStep(rp.timeStep() + t * h0 * d(rp.unknowns()));
  StageTranscription<TimeStep>::accept(q, StageTranscription<TimeStep>::retract(q, d, t), d, t);
  std::vector<double> c;
  rows.forEachValue(QuantityInputs(q, q.current()),
                    [&](const auto&, int, const auto&, double value) { c.push_back(value); });
  return c;
}

/// One time step's rows: gᵀd (dot) against central differences of the values along d over every
/// unknown, and addRow its adjoint.
template <typename TimeStep>
void checkRowsAlongDirections(const PlanningProblem& p, const ReducedProblem& rp,
                              const TimeStep& step, std::mt19937* rng) {
  const StageConstraints constraints = buildStageConstraints(p);
  StageTranscription<TimeStep> rows(constraints, rp);
  formGradients(&rows, rp, step);
  const int m = rp.unknowns() + TimeStep::globals(rp);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd d(m);
  for (int i = 0; i < m; ++i) d(i) = 1e-2 * normal(*rng);
  const double e = 1e-5;
  const std::vector<double> plus = valuesMovedBy(rows, rp, d, e, rp.timeStep());
  const std::vector<double> minus = valuesMovedBy(rows, rp, d, -e, rp.timeStep());
  std::size_t i = 0;
  double largest = 0.0;
  rows.forEach([&](const auto& g, int k, const auto& in) {
    const double slope = rows.dot(rp, g, k, in.g, d), fd = (plus[i] - minus[i]) / (2 * e);
    EXPECT_NEAR(slope, fd, 1e-8 * (std::abs(fd) + 1.0)) << "row " << i;
    Eigen::VectorXd scattered = Eigen::VectorXd::Zero(m);
    rows.addRow(rp, g, k, in.g, 1.0, &scattered);
    EXPECT_NEAR(scattered.dot(d), slope, 1e-13 * (std::abs(slope) + 1.0)) << "row " << i;
    largest = std::max(largest, std::abs(slope));
    ++i;
  });
  EXPECT_EQ(i, plus.size());
  EXPECT_GT(largest, 0.0);  // the direction moves the rows
}

TEST(TranscriptionRows, TheirSlopeOverNodesTimeStepAndTwistMatchesCentralDifferences) {
  std::mt19937 rng(49);
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    // Spinning ends, a pointing end (ψ free), a cone off the boresight, a rate limit and a torque
    // bound: every quantity's rows, on the nodes ψ and h move.
    PlanningProblem p = test_support::randomPointingRequest(31, 24, true, scheme);
    p.final_attitude = pointingAttitude(p.end_condition, 0.4);
    const Vector3 other = p.end_condition.body_axis.unitOrthogonal();
    p.constraints.push_back(PlanningConstraint::keepOut(other, Vector3(0.3, -0.5, 0.8), 0.2));
    p.constraints.push_back(PlanningConstraint::maxAngularRate(10.0));
    p.constraints.push_back(PlanningConstraint::maxTorqueNorm(50.0));
    const ReducedProblem rp = test_support::perturbedReducedProblem(p, 11);
    ASSERT_TRUE(rp.hasTwist());
    checkRowsAlongDirections(p, rp, FixedTimeStep{}, &rng);
    checkRowsAlongDirections(p, rp, FreeTimeStep{rp.timeStep()}, &rng);
  }
}

TEST(FreeTimeTwist, WithoutPointingNoEntries) {
  PlanningProblem p = test_support::randomPointingRequest(19, 16, true, SchemeKind::Paper);
  p.end_condition = EndCondition();
  const ReducedProblem rp(p);
  KktBlocks<double> kkt(rp.unknowns());
  KktSink<double, FreeTimeStep> sink(rp, FreeTimeStep{rp.timeStep()}, &kkt);
  const Eigen::Matrix<double, 10, 1> g = Eigen::Matrix<double, 10, 1>::Ones();
  sink.addBlock(p.steps - 2, 3, Eigen::Matrix<double, 10, 10>::Identity(), &g);
  EXPECT_EQ(kkt.globals(), 1);  // η alone
  EXPECT_EQ(kkt.border.cols(), 1);
  EXPECT_GT(kkt.corner(0, 0), 0.0);
}

TEST(FreeTimeTwist, ARankOneTermLandsWhereItsOuterProductBlockDoes) {
  // KktSink::addRankOne(w, g) over (δ, η) with ψ free: the band, the η and ψ columns and the corner
  // of addBlock(w g gᵀ) (no Lagrangian gradient: no path term), on the last stencils (which ψ
  // moves) and an inner one (which it does not), every scheme.
  for (const SchemeKind scheme : kDiscretizations) {
    SCOPED_TRACE(schemeName(scheme));
    const PlanningProblem p = test_support::randomPointingRequest(19, 16, true, scheme);
    const ReducedProblem rp(p);
    ASSERT_TRUE(rp.hasTwist());
    std::mt19937 rng(23);
    std::normal_distribution<double> normal;
    Eigen::Matrix<double, 10, 1> g;
    for (int i = 0; i < 10; ++i) g(i) = normal(rng);
    const double w = 0.37;
    for (const int first : {p.steps - 2, p.steps - 3, 4}) {
      SCOPED_TRACE("first node " + std::to_string(first));
      KktBlocks<double> rank_one(rp.unknowns()), block(rp.unknowns());
      KktSink<double, FreeTimeStep>(rp, FreeTimeStep{rp.timeStep()}, &rank_one)
          .addRankOne(first, 3, g, w);
      KktSink<double, FreeTimeStep>(rp, FreeTimeStep{rp.timeStep()}, &block)
          .addBlock(first, 3, w * g * g.transpose());
      EXPECT_LT((rank_one.corner - block.corner).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((rank_one.border - block.border).cwiseAbs().maxCoeff(), 1e-12);
      double band = 0.0;
      for (int i = 0; i < rp.unknowns(); ++i) {
        for (int j = std::max(0, i - ReducedProblem::kHalfBandwidth); j <= i; ++j)
          band = std::max(band, std::abs(rank_one.band(i, j) - block.band(i, j)));
      }
      EXPECT_LT(band, 1e-12);
      EXPECT_GT(block.corner.cwiseAbs().maxCoeff(), 1e-3);  // η's entries at least
      if (first == p.steps - 2) EXPECT_GT(std::abs(block.corner(1, 1)), 1e-6);  // ψ's
    }
  }
}

TEST(PointingMinimumTime, AtMostTheSweepsBestTwistOnSeededRandomRequests) {
  // Every discretization: h and ψ both move R_{N−1} of paper and variational.
  const std::pair<unsigned, SchemeKind> requests[] = {{4201u, SchemeKind::SecondOrder},
                                                      {4202u, SchemeKind::Paper},
                                                      {4204u, SchemeKind::Variational}};
  for (const auto& [seed, scheme] : requests) {
    SCOPED_TRACE("seed " + std::to_string(seed) + ", " + schemeName(scheme));
    const PlanningProblem p = test_support::randomBettsPointingRequest(seed, 32, scheme);
    const PlanResult r = planManeuver(p);
    ASSERT_TRUE(r.converged()) << r.message();
    ASSERT_TRUE(r.pointing.active);
    EXPECT_TRUE(r.minimum_time.kkt_point) << r.message();
    const test_support::TwistSweep sweep = test_support::sweepTwist(p);
    EXPECT_LE(r.minimum_duration, sweep.best * (1.0 + 1e-6))
        << "swept best at twist " << sweep.best_twist << "; " << r.message();
    EXPECT_LT(r.pointing.error, 1e-9);
    EXPECT_LT(pointingError(r.maneuver.attitude.back(), p.end_condition), 1e-9);
    EXPECT_LT(r.pointing.twist_stationarity, 1e-8);
    EXPECT_NEAR(twistOf(r.maneuver.attitude.back(), p.end_condition), r.pointing.final_twist, 1e-9);
    EXPECT_GE(r.pointing.starts, 4);      // the survey grid's start twists, then N's
    EXPECT_GE(r.minimum_time.solves, 4);  // at least one free-time solve per start twist
    EXPECT_TRUE(std::isfinite(r.attempts.front().start_detail.twist));
  }
}

TEST(PointingMinimumTime, BacksABoundedPointingVerdictWithTheTwistFree) {
  // Minimum effort under the same torque bounds below and above T* (the twist free): below, the
  // verdict is infeasible with T* as the least duration found; above, never infeasible.
  PlanningProblem p = test_support::randomBettsPointingRequest(4203, 32, SchemeKind::SecondOrder);
  const PlanResult fastest = planManeuver(p);
  ASSERT_TRUE(fastest.converged()) << fastest.message();
  const double T_star = fastest.minimum_duration;
  p.objective = Objective::MinimumEffort;
  p.duration = 0.97 * T_star;
  const PlanResult below = planManeuver(p);
  EXPECT_EQ(below.termination, Termination::Infeasible) << below.message();
  EXPECT_NEAR(below.duration_verdict.least_duration_found, T_star, 1e-6 * T_star);
  EXPECT_EQ(below.pointing.infeasible_basis, PointingInfeasibleBasis::MinimumTimeOverTwist);
  p.duration = 1.05 * T_star;
  const PlanResult above = planManeuver(p);
  EXPECT_NE(above.termination, Termination::Infeasible) << above.message();
  EXPECT_EQ(above.pointing.infeasible_basis, PointingInfeasibleBasis::None);
}

}  // namespace
