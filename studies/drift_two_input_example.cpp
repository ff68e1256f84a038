// Worked example of the drift + two-input problem (seed 001) for docs/design/drift_two_input.md:
// plans a maneuver, checks the closed forms of Prop. 4.2/4.3 against the flow, and writes the
// CSVs that scripts/plot_drift_two_input.py plots.
//   drift_two_input_example [output_dir]    (default: docs/results)
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "attitude_planner/drift_two_input/closed_forms.hpp"
#include "attitude_planner/drift_two_input/planner.hpp"

using namespace attitude_planner;
namespace dti = attitude_planner::drift_two_input;

namespace {

// max |p_closed − p_numeric| over [0, min(8 s, 60/ω)], fourth-order flow with h ω = 1e-3
double maxDeviation(const DriftTwoInputClosedForm& cf, const Vector3& p0,
                    const DriftTwoInputWeights& w) {
  const double omega =
      dti::velocity<double>(p0, w).norm() + p0.norm() * std::max(1 / w.c1, 1 / w.c2);
  const double T = std::min(8.0, 60.0 / omega);
  DriftTwoInputIntegration o;
  o.order = 4;
  o.substeps = 10;
  const auto tr = integrateDriftTwoInputExtremal(
      Matrix3::Identity(), p0, T, static_cast<int>(std::ceil(T * omega / 1e-2)), w, o);
  double e = 0.0;
  for (size_t k = 0; k < tr.t.size(); ++k) e = std::max(e, (cf.evaluate(tr.t[k]) - tr.p[k]).norm());
  return e;
}

void closedFormTable() {
  std::printf("\nclosed forms vs numerical flow (random p0, 8 per case/ordering/form):\n");
  std::printf(
      "| case | ordering | phi | costates | max abs error of p(t) |\n|---|---|---|---|---|\n");
  {
    const DriftTwoInputWeights w{1.7, 1.7};
    double worst = 0;
    int n = 0;
    for (double p1 : {-1.5, 0.0, 0.8})
      for (double p2 : {-0.9, 0.0, 1.2})
        for (double p3 : {-2.0, 0.5, 1.7, 3.0}) {
          const Vector3 p0(p1, p2, p3);
          worst = std::max(worst, maxDeviation(DriftTwoInputClosedForm(p0, w), p0, w));
          ++n;
        }
    std::printf("| circular (Prop. 4.2) | c1 = c2 | cos/sin | %d | %.2e |\n", n, worst);
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> nd(0.0, 1.0);
  std::map<std::tuple<int, bool, int>, std::pair<int, double>> stats;
  int outside = 0, total = 0;
  for (const DriftTwoInputWeights& w :
       {DriftTwoInputWeights{3.0, 1.0}, {1.0, 3.0}, {2.0, 0.5}, {0.5, 2.0}}) {
    std::map<DriftTwoInputCase, int> taken;
    for (int i = 0; i < 20000 && (taken[DriftTwoInputCase::kEllipticCaseI] < 4 ||
                                  taken[DriftTwoInputCase::kEllipticCaseII] < 4);
         ++i) {
      const double scale = std::array<double, 4>{0.5, 1.0, 2.0, 4.0}[i % 4];
      const Vector3 p0(scale * nd(rng), scale * nd(rng), scale * nd(rng));
      ++total;
      const DriftTwoInputClosedForm probe(p0, w);
      if (!probe.valid()) {
        ++outside;
        continue;
      }
      if (taken[probe.stateCase()]++ >= 4) continue;
      for (EllipticForm f :
           {EllipticForm::kDc, EllipticForm::kNs, EllipticForm::kNc, EllipticForm::kDs}) {
        const DriftTwoInputClosedForm cf(p0, w, f);
        if (cf.form() != f) continue;
        auto& s = stats[{static_cast<int>(cf.stateCase()), cf.swapped(), static_cast<int>(f)}];
        s.first++;
        s.second = std::max(s.second, maxDeviation(cf, p0, w));
      }
    }
  }
  for (const auto& [key, s] : stats) {
    std::printf("| %s | %s | %s | %d | %.2e |\n",
                toString(static_cast<DriftTwoInputCase>(std::get<0>(key))).c_str(),
                std::get<1>(key) ? "c1 < c2" : "c2 < c1",
                toString(static_cast<EllipticForm>(std::get<2>(key))).c_str(), s.first, s.second);
  }
  std::printf("(%d of %d random costates were outside the stated cases and were reported)\n",
              outside, total);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "docs/results";
  DriftTwoInputRequest rq;
  rq.g0 = Matrix3::Identity();
  rq.g1 = so3::fromAxisAngle(Vector3(1, 1, 0), 1.2);
  rq.duration = 3.0;
  rq.steps = 60;
  rq.weights = {1.0, 2.0};
  const DriftTwoInputPlan plan = planDriftTwoInput(rq);
  std::printf(
      "worked example: g0 = I, g1 = rotation of 1.2 rad about (1,1,0)/sqrt2, T = 3 s, "
      "N = 60, c1 = 1, c2 = 2, default starts\n%s\n",
      plan.message.c_str());
  std::printf("converged %d, iterations %d, continuation stages %d, integration steps %d\n",
              plan.converged(), plan.iterations, plan.continuation_stages, plan.integration_steps);
  std::printf("p(0) = (%.12f, %.12f, %.12f), cost = %.12f, terminal error = %.3e rad\n",
              plan.initial_costate.x(), plan.initial_costate.y(), plan.initial_costate.z(),
              plan.cost, plan.terminal_error);
  const auto& tr = plan.trajectory;
  double dC = 0, dH = 0;
  const double C0 = dti::casimir(tr.p[0]), H0 = dti::hamiltonian(tr.p[0], rq.weights);
  for (const auto& p : tr.p) {
    dC = std::max(dC, std::abs(dti::casimir(p) - C0));
    dH = std::max(dH, std::abs(dti::hamiltonian(p, rq.weights) - H0));
  }
  std::printf("C = %.12f (max drift %.2e), H = %.12f (max drift %.2e)\n", C0, dC, H0, dH);
  const DriftTwoInputClosedForm cf(plan.initial_costate, rq.weights);
  std::printf("closed form for this p(0): %s\n", cf.message().c_str());

  const std::string traj_path = dir + "/drift_two_input_example.csv";
  FILE* f = std::fopen(traj_path.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", traj_path.c_str());
    return 1;
  }
  std::fprintf(f, "k,t,qw,qx,qy,qz,p1,p2,p3,u1,u2\n");
  for (size_t k = 0; k < tr.t.size(); ++k) {
    const Eigen::Quaterniond q = so3::toQuaternion(tr.g[k]);
    std::fprintf(f, "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k, tr.t[k],
                 q.w(), q.x(), q.y(), q.z(), tr.p[k].x(), tr.p[k].y(), tr.p[k].z(), tr.u[k].x(),
                 tr.u[k].y());
  }
  std::fclose(f);

  // Orbits on the sphere C = C0 (Remark 3.1): the example's extremal (orbit 0, over a long time)
  // and others through points of the same sphere; each is the sphere ∩ {H = const}.
  const std::string orbit_path = dir + "/drift_two_input_orbits.csv";
  f = std::fopen(orbit_path.c_str(), "w");
  std::fprintf(f, "orbit,c1,c2,t,p1,p2,p3,H,C\n");
  std::vector<Vector3> starts{plan.initial_costate};
  const double R = std::sqrt(C0);
  for (double th : {0.35, 0.8, 1.25, 1.7, 2.2, 2.7}) {
    for (double ph : {0.0, M_PI / 2}) {
      starts.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph),
                          R * std::cos(th));
    }
  }
  DriftTwoInputIntegration o;
  o.order = 4;
  o.substeps = 20;  // 600 samples of 0.05 s each: enough for the plot, a small CSV
  for (size_t i = 0; i < starts.size(); ++i) {
    const auto orb =
        integrateDriftTwoInputExtremal(Matrix3::Identity(), starts[i], 30.0, 600, rq.weights, o);
    for (size_t k = 0; k < orb.t.size(); ++k) {
      std::fprintf(f, "%zu,%g,%g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g\n", i, rq.weights.c1, rq.weights.c2,
                   orb.t[k], orb.p[k].x(), orb.p[k].y(), orb.p[k].z(),
                   dti::hamiltonian(orb.p[k], rq.weights), dti::casimir(orb.p[k]));
    }
  }
  std::fclose(f);
  std::printf("wrote %s and %s\n", traj_path.c_str(), orbit_path.c_str());
  closedFormTable();
  return 0;
}
