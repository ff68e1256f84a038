// Measures the integrators: long-run energy and momentum behaviour of both schemes on the
// free rigid body, and the seed's SO(2) check (Fig. 1). Writes docs/results/integrators.md and CSVs for
// the plot script. Usage: integrator_study [OUT_DIR=docs/results]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "attitude_planner/dynamics/simulation.hpp"

using namespace attitude_planner;

namespace {

struct LongRun {
  double max_energy_deviation = 0;    // max |E_k − E_0|/E_0
  double energy_drift_per_1000s = 0;  // least-squares slope of (E_k − E_0)/E_0
  double max_momentum_error = 0;      // max |π_k − π_0|/|π_0|, π_k = R_k μ(F_k)
  double max_orthogonality_error = 0;
  double seconds = 0;
};

// Free rigid body J = diag(1,2,3), Ω0 = (0.6,0.5,0.4), h = 0.01, T = 2000 s.
LongRun longRun(SchemeKind kind, const std::string& csv_path) {
  const Matrix3 J = Vector3(1, 2, 3).asDiagonal();
  const double h = 0.01;
  const int N = 200000;
  const DiscreteScheme scheme(kind, J, h);
  SimulationInput input;
  input.initial_velocity = Vector3(0.6, 0.5, 0.4);
  input.torque.assign(N + 1, Vector3::Zero());
  const auto t0 = std::chrono::steady_clock::now();
  const Maneuver m = simulate(scheme, input);
  LongRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto energy = [&](int k) {
    const Vector3& w = m.angular_velocity[k];
    return 0.5 * w.dot(J * w);
  };
  const auto spatial_momentum = [&](int k) {
    const Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
    return Vector3(m.attitude[k] * scheme.momentum<double>(F));
  };
  const double E0 = energy(0);
  const Vector3 pi0 = spatial_momentum(0);
  FILE* csv = std::fopen(csv_path.c_str(), "w");
  std::fprintf(csv, "t,relative_energy_error,relative_momentum_error\n");
  double st = 0, se = 0, stt = 0, ste = 0;
  int count = 0;
  for (int k = 0; k < N; ++k) {
    const double e = (energy(k) - E0) / E0;
    const double p = (spatial_momentum(k) - pi0).norm() / pi0.norm();
    r.max_energy_deviation = std::max(r.max_energy_deviation, std::abs(e));
    r.max_momentum_error = std::max(r.max_momentum_error, p);
    r.max_orthogonality_error =
        std::max(r.max_orthogonality_error, so3::orthogonalityError(m.attitude[k]));
    const double t = m.time[k];
    st += t;
    se += e;
    stt += t * t;
    ste += t * e;
    ++count;
    if (k % 100 == 0) std::fprintf(csv, "%.17g,%.17g,%.17g\n", t, e, p);
  }
  std::fclose(csv);
  r.energy_drift_per_1000s = 1000.0 * (count * ste - st * se) / (count * stt - st * st);
  return r;
}

// Seed Fig. 1: θ̇ = ω, ω̇ = τ/I, τ = sin(πt/2), T = 10, I = 1, θ(0) = 3, ω(0) = 4, run on the
// SO(3) integrators about a principal axis (where both reduce to the seed's eq. (26)).
struct So2Error {
  double theta = 0, omega = 0;
};
So2Error so2Check(SchemeKind kind, int N) {
  const double T = 10.0, h = T / N;
  const DiscreteScheme scheme(kind, Matrix3::Identity(), h);
  SimulationInput input;
  input.initial_attitude = so3::fromAxisAngle(Vector3::UnitZ(), 3.0);
  input.initial_velocity = Vector3(0, 0, 4.0);
  input.torque.assign(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) input.torque[k] = Vector3(0, 0, std::sin(M_PI * k * h / 2));
  const Maneuver m = simulate(scheme, input);
  So2Error err;
  for (int k = 0; k < N; ++k) {
    const double t = k * h;
    const double theta = 3 + 4 * t + 2 / M_PI * t - 4 / (M_PI * M_PI) * std::sin(M_PI * t / 2);
    const double omega = 4 + 2 / M_PI * (1 - std::cos(M_PI * t / 2));
    err.theta = std::max(
        err.theta, so3::angleBetween(so3::fromAxisAngle(Vector3::UnitZ(), theta), m.attitude[k]));
    err.omega = std::max(err.omega, std::abs(m.angular_velocity[k].z() - omega));
  }
  return err;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "docs/results";
  FILE* md = std::fopen((out + "/integrators.md").c_str(), "w");
  if (!md) {
    std::fprintf(stderr, "cannot write %s/integrators.md\n", out.c_str());
    return 1;
  }
  std::fprintf(md,
               "# Integrators: measured behaviour\n\n"
               "Regenerate: `scripts/integrator_study` (runs `integrator_study docs/results` and the plot "
               "script).\n\n"
               "## Free rigid body over T = 2000 s\n\n"
               "J = diag(1, 2, 3) kg m², Ω0 = (0.6, 0.5, 0.4) rad/s, h = 0.01 s, 200 000 steps, "
               "no torque. Energy E_k = ½ Ω_kᵀ J Ω_k with the scheme's reported Ω_k; spatial "
               "momentum π_k = R_k μ(F_k).\n\n"
               "| scheme | max \\|E−E0\\|/E0 | energy drift per 1000 s (LSQ slope) | "
               "max \\|π−π0\\|/\\|π0\\| | max ‖RᵀR−I‖+\\|det R−1\\| | wall time [s] |\n"
               "|---|---|---|---|---|---|\n");
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const LongRun r = longRun(kind, out + "/energy_" + schemeName(kind) + ".csv");
    std::fprintf(md, "| %s | %.3e | %.3e | %.3e | %.3e | %.2f |\n", schemeName(kind).c_str(),
                 r.max_energy_deviation, r.energy_drift_per_1000s, r.max_momentum_error,
                 r.max_orthogonality_error, r.seconds);
    std::printf("%s: max energy dev %.3e, drift/1000s %.3e, momentum %.3e, orth %.3e, %.2fs\n",
                schemeName(kind).c_str(), r.max_energy_deviation, r.energy_drift_per_1000s,
                r.max_momentum_error, r.max_orthogonality_error, r.seconds);
  }
  std::fprintf(
      md,
      "\n![energy](integrators_energy.png)\n\n"
      "## The seed's SO(2) check (Fig. 1)\n\n"
      "θ̇ = ω, ω̇ = τ/I, τ(t) = sin(πt/2), T = 10, I = 1, θ(0) = 3, ω(0) = 4, integrated by "
      "the SO(3) schemes about a principal axis with J = I. `paper` reduces exactly to the "
      "seed's eq. (26) (symplectic Euler); `variational` reduces to sin(θ_{k+1} − θ_k) = "
      "h ω_k, whose arcsin costs it a larger θ constant. Errors are the maximum over the "
      "grid against the exact solution; the torque acts at the nodes (τ_k = τ(t_k)).\n\n"
      "| scheme | N | max θ error [rad] | max ω error [rad/s] | observed order (θ) |\n"
      "|---|---|---|---|---|\n");
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    double previous = 0;
    int previous_n = 0;
    for (int N : {1000, 1500, 2000}) {
      const So2Error e = so2Check(kind, N);
      std::string order = "";
      if (previous_n) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.3f",
                      std::log(previous / e.theta) / std::log(double(N) / previous_n));
        order = buf;
      }
      std::fprintf(md, "| %s | %d | %.3e | %.3e | %s |\n", schemeName(kind).c_str(), N, e.theta,
                   e.omega, order.c_str());
      std::printf("SO(2) %s N=%d theta %.3e omega %.3e %s\n", schemeName(kind).c_str(), N, e.theta,
                  e.omega, order.c_str());
      previous = e.theta;
      previous_n = N;
    }
  }
  std::fprintf(
      md,
      "\n## Findings\n\n"
      "- Both schemes conserve the spatial angular momentum to round-off (the simulation carries "
      "π_k = R_k μ(F_k) in the world frame, so it does not accumulate a rounding bias) and keep "
      "R_k on SO(3) to ~1e-15 (one Newton–Schulz re-orthonormalization per step).\n"
      "- `variational` (Lee–Leok–McClamroch LGVI) keeps the energy to round-off on this run: no "
      "drift at all, not merely a bounded oscillation.\n"
      "- `paper` (seed eq. (18)) is not energy-stable: its energy decays monotonically until the "
      "body spins about its major axis, E → |π|²/(2 J_max) = 0.6965 E0 here (the −0.3035 "
      "plateau), with a time constant of a few hundred seconds at h = 0.01 s. The scheme conserves "
      "momentum but is numerically dissipative, like implicit Euler on Euler's equations: its "
      "variation (seed eq. (21), δg_k = h g_k δΩ_k) drops the dexp factor, so eq. (18) is not the "
      "discrete Euler–Poincaré equation of any discrete Lagrangian.\n"
      "- SO(2) check: θ converges at order 2 and ω at order 1 for both schemes (node-applied "
      "torque is a left-rectangle rule for the impulse).\n");
  std::fclose(md);
  return 0;
}
