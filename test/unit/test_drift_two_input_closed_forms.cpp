// Closed forms of seed 001 (Prop. 4.2, Prop. 4.3 with corrections) against the numerical
// extremal flow on grids of initial costates that cover every stated case, both orderings of
// (c1, c2) and both representations of each case; costates outside the cases are reported.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "attitude_planner/drift_two_input/closed_forms.hpp"
#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/errors.hpp"

using namespace attitude_planner;

namespace {

// max_t |p_closed(t) − p_numeric(t)| over [0, T]. The reference is the fourth-order flow with
// h ω = 1e-3, ω = |∇H(p0)| + |p0| max(1/c1, 1/c2) (a bound on the rates), and at most ωT = 60
// (several periods of p), so its own error stays near 1e-12.
double maxDeviation(const DriftTwoInputClosedForm& cf, const Vector3& p0,
                    const DriftTwoInputWeights& w, double T_max) {
  const double omega =
      drift_two_input::velocity<double>(p0, w).norm() + p0.norm() * std::max(1 / w.c1, 1 / w.c2);
  const double T = std::min(T_max, 60.0 / omega);
  DriftTwoInputIntegration o;
  o.order = 4;
  o.substeps = 10;
  const int steps = static_cast<int>(std::ceil(T * omega / 1e-2));
  const auto tr = integrateDriftTwoInputExtremal(Matrix3::Identity(), p0, T, steps, w, o);
  double e = 0.0;
  for (size_t k = 0; k < tr.t.size(); ++k) e = std::max(e, (cf.evaluate(tr.t[k]) - tr.p[k]).norm());
  return e;
}

}  // namespace

TEST(DriftTwoInputClosedForms, CircularSolutionMatchesFlowOnAGrid) {
  const DriftTwoInputWeights w{1.7, 1.7};
  double worst = 0.0;
  int n = 0;
  for (double p1 : {-1.5, 0.0, 0.8}) {
    for (double p2 : {-0.9, 0.0, 1.2}) {
      for (double p3 : {-2.0, 0.5, 1.7, 3.0}) {  // 1.7 = c: p1, p2 frozen
        const Vector3 p0(p1, p2, p3);
        DriftTwoInputClosedForm cf(p0, w);
        ASSERT_TRUE(cf.valid());
        EXPECT_EQ(cf.stateCase(), DriftTwoInputCase::kCircular);
        worst = std::max(worst, maxDeviation(cf, p0, w, 10.0));
        ++n;
      }
    }
  }
  std::printf("circular: %d initial costates, max |p_cf - p_num| = %.3g\n", n, worst);
  RecordProperty("circular_max_error", std::to_string(worst));
  EXPECT_LE(worst, 1e-10);
}

TEST(DriftTwoInputClosedForms, EllipticSolutionsMatchFlowInEveryCaseOrderingAndForm) {
  std::mt19937 rng(7);
  std::normal_distribution<double> nd(0.0, 1.0);
  // key: case, swapped (c1 < c2), form
  std::map<std::tuple<int, bool, int>, std::pair<int, double>> stats;
  int outside = 0;
  const DriftTwoInputWeights weights[] = {{3.0, 1.0}, {1.0, 3.0}, {2.0, 0.5}, {0.5, 2.0}};
  for (const auto& w : weights) {
    std::map<DriftTwoInputCase, int> taken;  // at most 4 costates per case and weights
    for (int i = 0; i < 20000 && (taken[DriftTwoInputCase::kEllipticCaseI] < 4 ||
                                  taken[DriftTwoInputCase::kEllipticCaseII] < 4);
         ++i) {
      const double scale = std::array<double, 4>{0.5, 1.0, 2.0, 4.0}[i % 4];
      const Vector3 p0(scale * nd(rng), scale * nd(rng), scale * nd(rng));
      const DriftTwoInputClosedForm probe(p0, w);
      if (probe.stateCase() == DriftTwoInputCase::kOutsideStatedCases) {
        EXPECT_FALSE(probe.valid());
        EXPECT_THROW(probe.evaluate(0.1), InvalidInput);
        ++outside;
        continue;
      }
      if (taken[probe.stateCase()]++ >= 4) continue;
      for (EllipticForm form :
           {EllipticForm::kDc, EllipticForm::kNs, EllipticForm::kNc, EllipticForm::kDs}) {
        DriftTwoInputClosedForm cf(p0, w, form);
        if (cf.form() != form) continue;  // the form belongs to the other case
        ASSERT_TRUE(cf.valid()) << cf.message();
        EXPECT_EQ(cf.swapped(), w.c1 < w.c2);
        const double e = maxDeviation(cf, p0, w, 8.0);
        EXPECT_LE(e, 1e-10) << cf.message() << " p0 = " << p0.transpose();
        auto& s = stats[{static_cast<int>(cf.stateCase()), cf.swapped(), static_cast<int>(form)}];
        s.first++;
        s.second = std::max(s.second, e);
      }
    }
  }
  for (const auto& [key, s] : stats) {
    std::printf("%s, %s, phi = %s: %d costates, max |p_cf - p_num| = %.3g\n",
                toString(static_cast<DriftTwoInputCase>(std::get<0>(key))).c_str(),
                std::get<1>(key) ? "c1 < c2" : "c2 < c1",
                toString(static_cast<EllipticForm>(std::get<2>(key))).c_str(), s.first, s.second);
  }
  // every case × ordering × form of that case was exercised
  for (bool swapped : {false, true}) {
    for (auto [c, f] : {std::pair{DriftTwoInputCase::kEllipticCaseI, EllipticForm::kDc},
                        {DriftTwoInputCase::kEllipticCaseI, EllipticForm::kNs},
                        {DriftTwoInputCase::kEllipticCaseII, EllipticForm::kNc},
                        {DriftTwoInputCase::kEllipticCaseII, EllipticForm::kDs}}) {
      const auto it = stats.find({static_cast<int>(c), swapped, static_cast<int>(f)});
      ASSERT_NE(it, stats.end()) << toString(c) << " " << toString(f) << " swapped " << swapped;
      EXPECT_GE(it->second.first, 8);  // 4 per weights, two weights per ordering
    }
  }
  EXPECT_GT(outside, 0);
}

TEST(DriftTwoInputClosedForms, CostatesOutsideTheStatedCasesAreReportedNotEvaluated) {
  const DriftTwoInputWeights w{3.0, 1.0};
  // h0² < c0: p3 = 0, small (p1, p2): h0 = ½(p1²/3 + p2²) < |p|
  DriftTwoInputClosedForm a(Vector3(0.3, 0.2, 0.0), w);
  EXPECT_EQ(a.stateCase(), DriftTwoInputCase::kOutsideStatedCases);
  EXPECT_FALSE(a.valid());
  EXPECT_NE(a.message().find("h0^2 > c0"), std::string::npos) << a.message();
  EXPECT_THROW(a.evaluate(1.0), InvalidInput);
  // h0² > c0 but β > c1 (p3 large): neither (i) nor (ii)
  DriftTwoInputClosedForm b(Vector3(0.1, 0.1, 5.0), w);
  EXPECT_EQ(b.stateCase(), DriftTwoInputCase::kOutsideStatedCases);
  EXPECT_NE(b.message().find("neither (i)"), std::string::npos) << b.message();
  EXPECT_THROW(b.evaluate(1.0), InvalidInput);
  // the zero costate (c0 = 0) is outside Prop. 4.3 too
  EXPECT_FALSE(DriftTwoInputClosedForm(Vector3::Zero(), w).valid());
}

TEST(DriftTwoInputClosedForms, PrintedProposition42HasTheWrongRotationSense) {
  // seed: p1 = √k1 cos((1 − k2/c) t + k3), k3 = −atan(p2(0)/p1(0)); it solves the reversed flow
  const DriftTwoInputWeights w{2.0, 2.0};
  const Vector3 p0(0.6, 0.8, 0.5);
  DriftTwoInputClosedForm cf(p0, w);
  const double t = 1.0, k1 = 1.0, k2 = 0.5, k3 = -std::atan(p0.y() / p0.x());
  const Vector3 printed(std::sqrt(k1) * std::cos((1 - k2 / w.c1) * t + k3),
                        std::sqrt(k1) * std::sin((1 - k2 / w.c1) * t + k3), k2);
  EXPECT_GT((printed - cf.evaluate(t)).norm(), 0.1);
  EXPECT_LE(maxDeviation(cf, p0, w, 3.0), 1e-10);
}

TEST(DriftTwoInputClosedForms, PlannedExtremalsFollowTheClosedForms) {
  // The planner's output against Prop. 4.2 / 4.3 at every sample, at two samplings N.
  // c1 = c2 with default starts: the symmetric extremals the planner starts from are exact
  // (g(T) = g0 exp(T p̂0/c) exp(−(p3/c − 1)T E3)), so the cheapest needs no Newton correction.
  DriftTwoInputRequest rq;
  rq.g1 = so3::exp(Vector3(0.7, -0.5, 0.9));
  rq.duration = 4.0;
  rq.weights = {1.5, 1.5};
  for (int N : {50, 800}) {
    rq.steps = N;
    const DriftTwoInputPlan plan = planDriftTwoInput(rq);
    ASSERT_TRUE(plan.converged()) << plan.message;
    EXPECT_LE(plan.iterations, 1) << plan.message;
    const DriftTwoInputClosedForm cf(plan.initial_costate, rq.weights);
    ASSERT_TRUE(cf.valid()) << cf.message();
    double e = 0;
    for (size_t k = 0; k < plan.trajectory.t.size(); ++k) {
      e = std::max(e, (cf.evaluate(plan.trajectory.t[k]) - plan.trajectory.p[k]).norm());
    }
    std::printf("circular, N = %d: cost %.10g, max |p_cf - p_plan| = %.3g\n", N, plan.cost, e);
    EXPECT_LE(e, 1e-11);
  }
  // c1 ≠ c2: an extremal in case (i) or (ii) (p0 from the random search of the test above),
  // its endpoint as the target, a perturbed guess: the planner returns that extremal and its
  // samples follow the elliptic form.
  const DriftTwoInputWeights w{3.0, 1.0};
  std::mt19937 rng(11);
  std::normal_distribution<double> nd(0.0, 1.0);
  int checked = 0;
  for (int i = 0; i < 5000 && checked < 4; ++i) {
    const Vector3 p0(nd(rng), nd(rng), nd(rng));
    const DriftTwoInputClosedForm cf(p0, w);
    if (!cf.valid() || cf.stateCase() == DriftTwoInputCase::kCircular) continue;
    DriftTwoInputRequest er;
    er.weights = w;
    er.duration = 2.0;
    er.steps = 200;
    er.g1 = sampleDriftTwoInputExtremal(er.g0, p0, er.duration, 1, w).g.back();
    er.initial_costate = p0 + Vector3(0.02, -0.02, 0.01);
    const DriftTwoInputPlan plan = planDriftTwoInput(er);
    ASSERT_TRUE(plan.converged()) << plan.message;
    ASSERT_LE((plan.initial_costate - p0).norm(), 1e-9) << plan.message;
    double e = 0;
    for (size_t k = 0; k < plan.trajectory.t.size(); ++k) {
      e = std::max(e, (cf.evaluate(plan.trajectory.t[k]) - plan.trajectory.p[k]).norm());
    }
    std::printf("%s: max |p_cf - p_plan| = %.3g\n", toString(cf.stateCase()).c_str(), e);
    EXPECT_LE(e, 1e-10);
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}
