// The hard-case catalog (robustness_cases.hpp). Each case states its pass criterion
// in words (HardCase::criterion) and checks exactly that in code next to it; bounds that differ
// from the defaults (terminal error ≤ 1e-9) say why.
#include "support/robustness_cases.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "planning/problem/verdict.hpp"

namespace attitude_planner {
namespace robustness {

namespace {

std::string sci(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool allFinite(const Maneuver& m) {
  for (std::size_t k = 0; k < m.attitude.size(); ++k) {
    if (!m.attitude[k].allFinite()) return false;
  }
  for (const Vector3& w : m.angular_velocity) {
    if (!w.allFinite()) return false;
  }
  for (const Vector3& t : m.torque) {
    if (!t.allFinite()) return false;
  }
  return true;
}

/// max_k |τ_k| [N m].
double largestTorque(const Maneuver& m) {
  double largest = 0.0;
  for (const Vector3& t : m.torque) largest = std::max(largest, t.norm());
  return largest;
}

/// max_k |a_k − s·b_k| (s a scale) over two torque sequences of the same length.
double torqueGap(const Maneuver& a, const Maneuver& b, double scale = 1.0) {
  if (a.torque.size() != b.torque.size()) return std::numeric_limits<double>::infinity();
  double gap = 0.0;
  for (std::size_t k = 0; k < a.torque.size(); ++k)
    gap = std::max(gap, (a.torque[k] - scale * b.torque[k]).norm());
  return gap;
}

/// Net rotation the path turns through about `axis`: Σ_k log(R_kᵀ R_{k+1})·axis [rad].
double turnedAbout(const Maneuver& m, const Vector3& axis) {
  double total = 0.0;
  for (int k = 0; k < m.steps(); ++k)
    total += so3::log(Matrix3(m.attitude[k].transpose() * m.attitude[k + 1])).dot(axis);
  return total;
}

/// Same bits in every attitude, velocity and torque, and the same cost.
bool bitIdentical(const PlanResult& a, const PlanResult& b) {
  const Maneuver &x = a.maneuver, &y = b.maneuver;
  if (x.attitude.size() != y.attitude.size() || x.torque.size() != y.torque.size()) return false;
  if (std::memcmp(&a.cost, &b.cost, sizeof(double)) != 0) return false;
  for (std::size_t k = 0; k < x.attitude.size(); ++k) {
    if (std::memcmp(x.attitude[k].data(), y.attitude[k].data(), 9 * sizeof(double)) != 0 ||
        std::memcmp(x.angular_velocity[k].data(), y.angular_velocity[k].data(),
                    3 * sizeof(double)) != 0 ||
        std::memcmp(x.torque[k].data(), y.torque[k].data(), 3 * sizeof(double)) != 0) {
      return false;
    }
  }
  return a.iterations == b.iterations && a.extremal == b.extremal;
}

/// Rest to rest by `angle` about `axis` from the identity.
PlanningProblem restToRest(const Matrix3& inertia, const Vector3& axis, double angle,
                           double duration, int steps, SchemeKind scheme = SchemeKind::Paper) {
  PlanningProblem p;
  p.inertia = inertia;
  p.duration = duration;
  p.steps = steps;
  p.final_attitude = so3::fromAxisAngle(axis, angle);
  p.scheme = scheme;
  p.allow_nonphysical_inertia = true;  // the seed's J; harmless for physical ones
  return p;
}

/// The seed's slew-up: π/6 about x in 12.8 s, ending with Ω_{N−1} = (0.3, 0.2, 0.3).
PlanningProblem seedSlewUp(int steps, SchemeKind scheme = SchemeKind::Paper) {
  PlanningProblem p = restToRest(seedInertia(), Vector3::UnitX(), M_PI / 6, 12.8, steps, scheme);
  p.final_velocity = Vector3(0.3, 0.2, 0.3);
  return p;
}

const Vector3 kDiagonalAxis = Vector3(1, 2, 3).normalized();

// ---- 1. cut locus ------------------------------------------------------------------------------

void cutLocus(Recorder& r, const Vector3& axis) {
  const Matrix3 J = seedInertia();
  const auto problem = [&](double angle) { return restToRest(J, axis, angle, 12.8, 64); };
  const PlanResult at = r.plan("θ = π", problem(M_PI));
  const PlanResult again = r.plan("θ = π (repeated)", problem(M_PI));
  const PlanResult below3 = r.plan("θ = π − 1e-3", problem(M_PI - 1e-3));
  const PlanResult below6 = r.plan("θ = π − 1e-6", problem(M_PI - 1e-6));
  const PlanResult below9 = r.plan("θ = π − 1e-9", problem(M_PI - 1e-9));
  const PlanResult above6 = r.plan("θ = π + 1e-6", problem(M_PI + 1e-6));
  // Lipschitz constants measured on the widest gap; the narrower gaps must shrink with δ.
  const double cost_slope = std::abs(below3.cost - at.cost) / 1e-3;
  const double torque_slope = torqueGap(below3.maneuver, at.maneuver) / 1e-3;
  const double cost_floor = 1e-12 * at.cost, torque_floor = 1e-9 * largestTorque(at.maneuver);
  r.atMost("|C(π−1e-6) − C(π)| [N²m²] ≤ 2·slope·δ + 1e-12·C", std::abs(below6.cost - at.cost),
           2 * cost_slope * 1e-6 + cost_floor);
  r.atMost("|C(π−1e-9) − C(π)| [N²m²] ≤ 2·slope·δ + 1e-12·C", std::abs(below9.cost - at.cost),
           2 * cost_slope * 1e-9 + cost_floor);
  r.atMost("|C(π+1e-6) − C(π−1e-6)| [N²m²] ≤ 2·slope·2δ + 1e-12·C",
           std::abs(above6.cost - below6.cost), 2 * cost_slope * 2e-6 + cost_floor);
  r.atMost("max_k|τ(π−1e-6) − τ(π)| [N m] ≤ 2·slope·δ + 1e-9·max|τ|",
           torqueGap(below6.maneuver, at.maneuver), 2 * torque_slope * 1e-6 + torque_floor);
  r.atMost("max_k|τ(π−1e-9) − τ(π)| [N m] ≤ 2·slope·δ + 1e-9·max|τ|",
           torqueGap(below9.maneuver, at.maneuver), 2 * torque_slope * 1e-9 + torque_floor);
  r.atMost("max_k|τ(π+1e-6) − τ(π)| [N m] ≤ 2·slope·δ + 1e-9·max|τ|",
           torqueGap(above6.maneuver, at.maneuver), 2 * torque_slope * 1e-6 + torque_floor);
  r.holds("θ = π: bit-identical when repeated", bitIdentical(at, again));
  const auto surveyed = [&at](bool long_way) {
    return std::any_of(at.attempts.begin(), at.attempts.end(), [&](const Attempt& a) {
      return a.stage == AttemptStage::ClassSurvey && a.homotopy.long_way == long_way &&
             a.homotopy.extra_revolutions == 0 && std::isfinite(a.cost);
    });
  };
  r.holds("θ = π: both ways solved (class survey), one kept, the others' costs in the extremal",
          surveyed(false) && surveyed(true) &&
              std::count_if(at.attempts.begin(), at.attempts.end(),
                            [](const Attempt& a) { return a.kept; }) == 1 &&
              at.extremal_summary.others.size() + 1 == at.attempts.size(),
          at.extremal);
}

// ---- 2. beyond π -------------------------------------------------------------------------------

void beyondPi(Recorder& r) {
  const Matrix3 J = seedInertia();
  const Vector3 x = Vector3::UnitX();
  const double theta = 2 * M_PI - 0.1;
  const PlanResult short_way = r.plan("θ = 2π − 0.1 about x", restToRest(J, x, theta, 12.8, 64));
  const PlanResult direct = r.plan("θ = −0.1 about x (the same rotation, written short)",
                                   restToRest(J, x, -0.1, 12.8, 64));
  r.atMost("|C(2π − 0.1) − C(−0.1)| / C", std::abs(short_way.cost - direct.cost) / direct.cost,
           1e-9);
  const double turned_short = turnedAbout(short_way.maneuver, x);
  r.atMost("short way: |net turn about x + 0.1| [rad]", std::abs(turned_short + 0.1), 0.05);

  PlanningProblem long_way = restToRest(J, x, theta, 12.8, 64);
  long_way.direction = RotationDirection::LongWay;
  const PlanResult lw = r.plan("θ = 2π − 0.1 about x, direction = LongWay", long_way);
  r.atLeast("long way: net turn about x [rad] ≥ π", turnedAbout(lw.maneuver, x), M_PI);
  r.holds("long way: the extremal's class is the other way round",
          lw.extremal_summary.homotopy.long_way, lw.extremal);

  PlanningProblem extra = restToRest(J, x, theta, 12.8, 64);
  extra.extra_revolutions = 1;
  const PlanResult xt = r.plan("θ = 2π − 0.1 about x, extra_revolutions = 1", extra);
  r.atMost("one extra turn: net turn about x [rad] ≤ −π", turnedAbout(xt.maneuver, x), -M_PI);
  r.atLeast("C(long way) / C(short way) ≥ 1", lw.cost / short_way.cost, 1.0);
  r.atLeast("C(extra turn) / C(short way) ≥ 1", xt.cost / short_way.cost, 1.0);

  // θ = 1 rad, variational: the three ways (measured net turns about x 1.0, −4.42, +5.69 rad;
  // the seed's J is not isotropic, so the paths leave the x axis).
  PlanningProblem one = restToRest(J, x, 1.0, 12.8, 128, SchemeKind::Variational);
  const PlanResult s1 = r.plan("θ = 1 about x (variational, N = 128)", one);
  one.direction = RotationDirection::LongWay;
  const PlanResult l1 = r.plan("θ = 1, LongWay", one);
  one.direction = RotationDirection::Shortest;
  one.extra_revolutions = 1;
  const PlanResult e1 = r.plan("θ = 1, extra_revolutions = 1", one);
  r.atMost("θ = 1 short: |net turn − 1| [rad]", std::abs(turnedAbout(s1.maneuver, x) - 1.0), 0.5);
  r.atMost("θ = 1 long way: net turn [rad] ≤ −π", turnedAbout(l1.maneuver, x), -M_PI);
  r.atLeast("θ = 1 extra turn: net turn [rad] ≥ π + 1", turnedAbout(e1.maneuver, x), M_PI + 1);

  // A negative number of turns is refused, naming the field.
  PlanningProblem negative = restToRest(J, x, 1.0, 12.8, 64);
  negative.extra_revolutions = -1;
  std::string refusal = "(accepted)";
  try {
    planManeuver(negative);
  } catch (const InvalidInput& e) {
    refusal = e.what();
  }
  r.holds("extra_revolutions = −1 refused (InvalidInput naming the field)",
          refusal.find("extra_revolutions") != std::string::npos, refusal);
}

// ---- 3. tiny maneuvers --------------------------------------------------------------------------

void tinyRotations(Recorder& r) {
  const Matrix3 J = seedInertia();
  const PlanResult a =
      r.plan("θ = 1e-10 about (1,2,3)/√14", restToRest(J, kDiagonalAxis, 1e-10, 12.8, 64));
  const PlanResult b =
      r.plan("θ = 1e-6 about (1,2,3)/√14", restToRest(J, kDiagonalAxis, 1e-6, 12.8, 64));
  const double unit = largestTorque(b.maneuver) / 1e-6;  // max|τ/θ| [N m/rad]
  r.atMost("max_k|τ(1e-10)/1e-10 − τ(1e-6)/1e-6| / max|τ/θ|",
           torqueGap(a.maneuver, b.maneuver, 1e-10 / 1e-6) / 1e-10 / unit, 1e-6);
  r.atLeast("max|τ(1e-10)| / 1e-10 / max|τ/θ| (not a zero answer)",
            largestTorque(a.maneuver) / 1e-10 / unit, 0.999999);
  r.atMost("θ = 1e-10: terminal attitude error / θ", a.terminal_attitude_error / 1e-10, 1e-5);
  r.atMost("θ = 1e-6: terminal attitude error / θ", b.terminal_attitude_error / 1e-6, 1e-9);
}

void zeroManeuver(Recorder& r) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational}) {
    const std::string name = schemeName(scheme);
    const PlanResult z = r.plan("R_N = R_0 at rest (" + name + ")",
                                restToRest(seedInertia(), Vector3::UnitX(), 0.0, 12.8, 64, scheme));
    r.atMost(name + ": max_k |τ_k| [N m] (exactly 0)", largestTorque(z.maneuver), 0.0);
    r.atMost(name + ": iterations", z.iterations, 1);
  }
}

// ---- 4. inertia --------------------------------------------------------------------------------

/// 2 rad about (1,2,3)/√14 in 10 s, ending with Ω = (0.05, −0.1, 0.15) rad/s.
PlanningProblem genericSlew(const Matrix3& J, int steps) {
  PlanningProblem p = restToRest(J, kDiagonalAxis, 2.0, 10.0, steps);
  p.allow_nonphysical_inertia = false;  // these inertias are physical: checked
  p.final_velocity = Vector3(0.05, -0.1, 0.15);
  return p;
}

void anisotropicInertia(Recorder& r) {
  r.plan("J = diag(0.01, 1, 1.005)", genericSlew(Vector3(0.01, 1, 1.005).asDiagonal(), 128));
  r.plan("J = diag(1, 100, 100.5)", genericSlew(Vector3(1, 100, 100.5).asDiagonal(), 128));
}

void nearlyIsotropicInertia(Recorder& r) {
  // diag(1, 1, 1 + 1e-9): within 1e-9 of J = I, where the optimum turns about the axis only.
  const Vector3 a = kDiagonalAxis;
  PlanningProblem p = restToRest(Vector3(1, 1, 1 + 1e-9).asDiagonal(), a, 2.0, 10.0, 128);
  p.allow_nonphysical_inertia = false;
  const PlanResult near = r.plan("J = diag(1, 1, 1 + 1e-9), rest to rest", p);
  p.inertia = Matrix3::Identity();
  const PlanResult iso = r.plan("J = I (reference)", p);
  const double largest = largestTorque(iso.maneuver);
  r.atMost("max_k|τ(diag(1,1,1+1e-9)) − τ(I)| / max|τ|",
           torqueGap(near.maneuver, iso.maneuver) / largest, 1e-7);
  double off_axis = 0.0;
  for (const Vector3& t : near.maneuver.torque) off_axis = std::max(off_axis, t.cross(a).norm());
  r.atMost("max_k|τ_k × a| / max|τ| (torque along the axis)", off_axis / largest, 1e-7);
}

void rotatedInertia(Recorder& r) {
  // Body axes b' = Q b: J' = Q J Qᵀ, R' = R Qᵀ, Ω' = Q Ω, so the optimal τ' = Q τ.
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const Matrix3 Q = so3::exp(Vector3(n(rng), n(rng), n(rng)));
  const PlanningProblem p = seedSlewUp(64);
  PlanningProblem q = p;
  const Matrix3 rotated = Q * p.inertia * Q.transpose();
  q.inertia = 0.5 * (rotated + rotated.transpose());
  q.initial_attitude = p.initial_attitude * Q.transpose();
  q.final_attitude = p.final_attitude * Q.transpose();
  q.initial_velocity = Q * p.initial_velocity;
  q.final_velocity = Q * p.final_velocity;
  const PlanResult a = r.plan("seed slew-up, seed J", p);
  const PlanResult b = r.plan("the same in body axes rotated by a random Q", q);
  double gap = 0.0;
  for (std::size_t k = 0; k < a.maneuver.torque.size() && k < b.maneuver.torque.size(); ++k)
    gap = std::max(gap, (b.maneuver.torque[k] - Q * a.maneuver.torque[k]).norm());
  r.atMost("max_k|τ'_k − Q τ_k| [N m]", gap, 1e-10);
  r.atMost("|C' − C| / C", std::abs(b.cost - a.cost) / a.cost, 1e-12);
}

void scaledInertia(Recorder& r) {
  const PlanningProblem p = seedSlewUp(64);
  const PlanResult base = r.plan("seed slew-up, seed J", p);
  const double largest = largestTorque(base.maneuver);
  for (double s : {1e6, 1e-6}) {
    PlanningProblem q = p;
    q.inertia = s * p.inertia;
    const PlanResult scaled = r.plan("J·" + sci(s), q);
    r.atMost("max_k|τ(J·" + sci(s) + ")/" + sci(s) + " − τ(J)| / max|τ|",
             torqueGap(scaled.maneuver, base.maneuver, s) / s / largest, 1e-10);
  }
}

// ---- 5. dynamics -------------------------------------------------------------------------------

void spinningEnds(Recorder& r) {
  // Ω_0 = (0, 0, 5) → Ω_{N−1} = (3, 0, 0): ~10 turns over 12.8 s. From a geodesic guess (which
  // ignores the spin) this took > 200 iterations; the Hermite guess matches the end velocities.
  PlanningProblem p = restToRest(seedInertia(), Vector3::UnitX(), 1.0, 12.8, 128);
  p.initial_velocity = Vector3(0, 0, 5);
  p.final_velocity = Vector3(3, 0, 0);
  const PlanResult res = r.plan("Ω (0,0,5) → (3,0,0) rad/s, 1 rad about x, N = 128", p);
  // Measured 168 from the Hermite guess (~10 turns away from the extremal's shape): within the
  // default iteration limit, not fast (see docs/results/robustness.md). The other classes are
  // solved too (the class survey), and a class above 40 iterations from the more starts: what is
  // asserted is that no level of the kept solve needed more than the default limit.
  int most = 0;
  for (const LevelSummary& level : res.levels) most = std::max(most, level.iterations);
  r.atMost("iterations on any level of the kept solve (default limit 200)", most, 200);
}

void intermediateAxisSpin(Recorder& r) {
  // J = diag(1, 2, 3) spinning at 1 rad/s about its intermediate axis y (unstable: perturbations
  // grow like e^{λt}, λ = √((J2−J1)(J3−J2)/(J1J3)) = 0.577 s⁻¹: 3e7 over 30 s, 1e15 over 60 s —
  // single shooting cannot work), ending 0.2 rad about x away from where the steady spin would
  // be. h = 0.1 s throughout.
  // One extremal's solve across T (the nearest lift, next to the steady spin): the other classes
  // of the class survey are not what the iteration criterion compares.
  SolverOptions one_class;
  one_class.enumerate_classes = false;
  std::vector<int> iterations;
  for (double T : {10.0, 30.0, 60.0}) {
    PlanningProblem p;
    p.inertia = Vector3(1, 2, 3).asDiagonal();
    p.duration = T;
    p.steps = static_cast<int>(std::lround(10 * T));
    p.initial_velocity = Vector3(0, 1, 0);
    p.final_velocity = Vector3(0, 1, 0);
    p.final_attitude = so3::exp(Vector3(0, T, 0)) * so3::exp(Vector3(0.2, 0, 0));
    const std::string label = "T = " + sci(T) + " s, N = " + std::to_string(p.steps);
    if (T < 60.0) {
      iterations.push_back(r.plan(label, p, one_class).iterations);
      continue;
    }
    // T = 60 s: the Newton iteration converges as fast, and the plan satisfies the discrete
    // equations step by step; only its open-loop replay (forward integration of the torques
    // from R_0, Ω_0) amplifies round-off by e^{λT} ≈ 1e15. That is a property of the motion,
    // reported as replay_miss, not a reason to refuse the optimum.
    const PlanResult res = planManeuver(p, one_class);
    r.record(label, p, res);
    iterations.push_back(res.iterations);
    r.holds("T = 60: converged (judged by the plan, not by its open-loop replay)", res.converged(),
            res.message().substr(0, 160));
    r.atMost("T = 60: relative first-order residual at the end (stationary point found)",
             res.max_residual, 1e-9);
    r.atMost("T = 60: relative step residual of the plan", res.step_residual,
             measureStepResidual(p, res.maneuver).tolerance);
    r.atMost("T = 60: the plan's R_N from the target [rad]",
             so3::angleBetween(res.maneuver.attitude[p.steps], p.final_attitude), 1e-9);
    r.atLeast("T = 60: replay miss [rad] reported (round-off amplified by e^{λT})", res.replay_miss,
              1e-9);
    r.atMost("T = 60: replay miss [rad] ≤ 10·T·eps·e^{λT} (round-off amplification)",
             res.replay_miss, 10 * 60.0 * 2.2e-16 * std::exp(std::sqrt(1.0 / 3.0) * 60.0));
  }
  r.atMost("iterations(T = 60) − iterations(T = 10)", iterations[2] - iterations[0], 4);
  r.atMost("iterations(T = 30) − iterations(T = 10)", iterations[1] - iterations[0], 4);
}

/// The 77-day-style slow maneuver: the seed's J, 1 rad about x, rest to rest in 6.65e6 s.
void slowManeuver(Recorder& r, int steps, double terminal_bound) {
  const PlanningProblem p = restToRest(seedInertia(), Vector3::UnitX(), 1.0, 6.65e6, steps);
  PlanningProblem coarse = p;
  coarse.steps = 1000;
  const PlanResult ref = r.plan("N = 1000 (reference)", coarse);
  const PlanResult res = r.plan("N = " + std::to_string(steps), p, {}, terminal_bound);
  // h·C approximates ½∫|τ|²dt: the grids agree to O(h) (the paper scheme's Ω is first order,
  // docs/results/integrators.md; measured 2.7e-3 between N = 1e3 and 1e4).
  const double hc = res.cost * p.duration / steps, hc_ref = ref.cost * p.duration / 1000;
  r.atMost("|h·C(N) − h·C(1000)| / h·C(1000)", std::abs(hc - hc_ref) / hc_ref, 1e-2);
}

// ---- 6. step size ------------------------------------------------------------------------------

/// What a plan that may legitimately fail for a too-large step did: "converged" or the error.
std::string convergesOrClearError(Recorder& r, const std::string& label, const PlanningProblem& p) {
  try {
    const PlanResult res = planManeuver(p);
    r.record(label, p, res);
    if (res.converged()) {
      r.checkConverged(label + ": converged", p, res, 1e-9);
      return "converged";
    }
    r.holds(label + ": not converged, and the result says step too large / increase steps",
            res.termination == Termination::StepTooLarge &&
                res.message().find("increase steps") != std::string::npos,
            res.message());
    return res.message();
  } catch (const StepTooLarge& e) {
    r.holds(label + ": StepTooLarge naming the fix (increase steps)",
            std::string(e.what()).find("increase steps") != std::string::npos, e.what());
    return e.what();
  }
}

void stepTooLarge(Recorder& r) {
  // Paper scheme: one step turns by h|Ω|, which must stay below π.
  PlanningProblem spin = restToRest(seedInertia(), Vector3::UnitX(), 1.0, 1.0, 8);
  spin.initial_velocity = Vector3(0, 0, 40);
  const std::string paper = convergesOrClearError(r, "paper, Ω_0 = 40 rad/s, h|Ω_0| = 5", spin);
  r.holds("h|Ω_0| = 5 > π is refused as step too large", paper != "converged", paper);
  spin.steps = 16;
  convergesOrClearError(r, "paper, h|Ω_0| = 2.5", spin);
  spin.steps = 64;
  const std::string fine = convergesOrClearError(r, "paper, h|Ω_0| = 0.625", spin);
  r.holds("h|Ω_0| = 0.625 converges", fine == "converged", fine);
  // Variational scheme: μ(F) is bounded over SO(3), so a large momentum has no step at all.
  PlanningProblem fast =
      restToRest(seedInertia(), Vector3::UnitX(), 1.0, 10.0, 10, SchemeKind::Variational);
  fast.final_velocity = Vector3(50, 0, 0);
  const std::string variational =
      convergesOrClearError(r, "variational, Ω_{N−1} = 50 rad/s, h = 1 s", fast);
  r.holds("variational, no step exists: refused as step too large", variational != "converged",
          variational);
  // The interior: ~4 turns in 6 free steps (≈ 4 rad per step) at rest at both ends.
  PlanningProblem turns = restToRest(seedInertia(), Vector3::UnitX(), 3.0, 8.0, 8);
  turns.extra_revolutions = 3;
  convergesOrClearError(r, "paper, 3 rad + 3 turns in N = 8 (interior steps ≈ 4 rad)", turns);
}

// ---- 7. integrator drift ------------------------------------------------------------------------

void integratorDrift(Recorder& r) {
  const Matrix3 J = Vector3(1, 2, 3).asDiagonal();
  const int N = 1000000;
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const DiscreteScheme scheme(kind, J, 0.01);
    SimulationInput input;
    input.initial_velocity = Vector3(0.6, 0.5, 0.4);
    input.torque.assign(N + 1, Vector3::Zero());
    const Maneuver m = simulate(scheme, input);
    const auto spatial = [&](int k) {
      return Vector3(m.attitude[k] * scheme.momentum<double>(
                                         Matrix3(m.attitude[k].transpose() * m.attitude[k + 1])));
    };
    const Vector3 pi0 = spatial(0);
    double worst_momentum = 0, worst_orthogonality = 0;
    for (int k = 0; k < N; ++k) {
      worst_momentum = std::max(worst_momentum, (spatial(k) - pi0).norm() / pi0.norm());
      worst_orthogonality = std::max(worst_orthogonality, so3::orthogonalityError(m.attitude[k]));
    }
    worst_orthogonality = std::max(worst_orthogonality, so3::orthogonalityError(m.attitude[N]));
    const std::string name = schemeName(kind);
    r.atMost(name + ": max_k ‖R_kᵀR_k − I‖ + |det R_k − 1|", worst_orthogonality, 1e-14);
    r.atMost(name + ": max_k |π_k − π_0| / |π_0| (spatial momentum)", worst_momentum, 1e-13);
    r.holds(name + ": every R_k, Ω_k finite", allFinite(m));
  }
}

// ---- 8. determinism ----------------------------------------------------------------------------

void determinism(Recorder& r) {
  PlanningProblem spin = restToRest(seedInertia(), Vector3::UnitX(), 1.0, 12.8, 128);
  spin.initial_velocity = Vector3(0, 0, 5);
  spin.final_velocity = Vector3(3, 0, 0);
  const std::pair<std::string, PlanningProblem> problems[] = {
      {"seed slew-up N = 64 (normal equations)", seedSlewUp(64)},
      {"seed slew-up N = 1024 (augmented system, grid continuation)", seedSlewUp(1024)},
      {"seed slew-up N = 256, variational", seedSlewUp(256, SchemeKind::Variational)},
      {"π about (1,2,3)/√14 (both ways solved)",
       restToRest(seedInertia(), kDiagonalAxis, M_PI, 12.8, 64)},
      {"spinning ends N = 128", spin},
  };
  for (const auto& [label, p] : problems) {
    const PlanResult a = r.plan(label, p);
    const PlanResult b = r.plan(label + " (repeated)", p);
    r.holds(label + ": bit-identical R_k, Ω_k, τ_k, cost, iterations, extremal",
            bitIdentical(a, b));
  }
}

}  // namespace

Matrix3 seedInertia() {
  return (Matrix3() << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37).finished();
}

bool CaseOutcome::passed() const {
  for (const Check& c : checks) {
    if (!c.passed) return false;
  }
  return !checks.empty();
}

std::string CaseOutcome::failures() const {
  std::ostringstream out;
  if (checks.empty()) out << "no check ran\n";
  for (const Check& c : checks) {
    if (c.passed) continue;
    out << c.quantity << ": measured " << c.measured << ", required " << c.relation << " "
        << c.bound;
    if (!c.note.empty()) out << " (" << c.note << ")";
    out << "\n";
  }
  return out.str();
}

void Recorder::record(const std::string& label, const PlanningProblem& problem,
                      const PlanResult& res) {
  RunFigures f;
  f.label = label;
  f.converged = res.converged();
  f.finite = allFinite(res.maneuver) && std::isfinite(res.cost);
  f.steps = problem.steps;
  f.iterations = res.iterations;
  f.cost = res.cost;
  f.terminal_attitude_error = res.terminal_attitude_error;
  f.terminal_velocity_error = res.terminal_velocity_error;
  f.max_residual = res.max_residual;
  f.newton_decrement = res.newton_decrement;
  f.dynamics_residual = res.dynamics_residual;
  f.solve_time_s = res.solve_time_s;
  f.extremal = res.extremal;
  f.message = res.message();
  outcome_.runs.push_back(f);
}

PlanResult Recorder::plan(const std::string& label, const PlanningProblem& problem,
                          const SolverOptions& options, double terminal_bound) {
  PlanResult res = planManeuver(problem, options);
  record(label, problem, res);
  holds(label + ": converged", res.converged(), res.message());
  checkConverged(label, problem, res, terminal_bound);
  return res;
}

void Recorder::checkConverged(const std::string& label, const PlanningProblem& problem,
                              const PlanResult& res, double terminal_bound) {
  holds(label + ": no NaN/Inf in R_k, Ω_k, τ_k, cost",
        allFinite(res.maneuver) && std::isfinite(res.cost));
  const bool parted = std::isinf(res.replay_miss);
  if (!parted) {
    atMost(label + ": terminal attitude error [rad]", res.terminal_attitude_error, terminal_bound);
    atMost(label + ": terminal velocity error [rad/s]", res.terminal_velocity_error,
           terminal_bound);
  } else {
    // The open-loop replay's ends were never reached, so the plan's own are checked, and each
    // of its steps replayed from its own state (the replay the verdict trusts).
    const int N = res.maneuver.steps();
    atMost(label + ": open-loop replay parted; the plan's terminal attitude error [rad]",
           N == problem.steps ? so3::angleBetween(problem.final_attitude, res.maneuver.attitude[N])
                              : std::numeric_limits<double>::infinity(),
           terminal_bound);
    const std::string why = N == problem.steps ? planInconsistency(problem, res, false) : "no plan";
    holds(label + ": open-loop replay parted; the plan meets its ends and the discrete equations",
          why.empty(), why);
    const StepwiseReplay stepwise =
        why.empty() ? replayStepByStep(problem, res.maneuver) : StepwiseReplay{};
    holds(label + ": open-loop replay parted; every step replayed from the plan's own state",
          why.empty() && stepwise.reproduces(),
          sci(stepwise.worst_angle) + " rad at k = " + std::to_string(stepwise.worst_step));
  }
  holds(label + ": residuals reported (finite)",
        std::isfinite(res.max_residual) && std::isfinite(res.newton_decrement) &&
            (parted || std::isfinite(res.dynamics_residual)));
}

bool Recorder::atMost(const std::string& quantity, double measured, double bound) {
  outcome_.checks.push_back({quantity, measured, "<=", bound, measured <= bound, ""});
  return outcome_.checks.back().passed;
}

bool Recorder::atLeast(const std::string& quantity, double measured, double bound) {
  outcome_.checks.push_back({quantity, measured, ">=", bound, measured >= bound, ""});
  return outcome_.checks.back().passed;
}

bool Recorder::holds(const std::string& quantity, bool value, const std::string& note) {
  outcome_.checks.push_back({quantity, value ? 1.0 : 0.0, "true", 1.0, value, note});
  return value;
}

CaseOutcome runCase(const HardCase& hard_case) {
  Recorder recorder;
  const auto start = std::chrono::steady_clock::now();
  try {
    hard_case.run(recorder);
  } catch (const std::exception& e) {
    recorder.holds("no unexpected exception", false, e.what());
  }
  recorder.outcome().time_s = seconds(start);
  return recorder.outcome();
}

const std::vector<HardCase>& hardCases() {
  static const std::vector<HardCase> cases = {
      {"CutLocusAboutX", "1. cut locus",
       "seed J, rest to rest, T = 12.8 s, N = 64, θ = π − 1e-3, π − 1e-6, π − 1e-9, π (twice), "
       "π + 1e-6 about x",
       "each run: converged, terminal errors ≤ 1e-9, no NaN, residuals finite; cost and torques "
       "continuous in θ: |C(π∓δ) − C(π)| ≤ 2·s·δ + 1e-12·C and max|Δτ| ≤ 2·s_τ·δ + 1e-9·max|τ| "
       "(s, s_τ the slopes measured at δ = 1e-3); at exactly π bit-identical when repeated and "
       "PlanResult::extremal names the way taken",
       false, [](Recorder& r) { cutLocus(r, Vector3::UnitX()); }},
      {"CutLocusAboutDiagonal", "1. cut locus", "as CutLocusAboutX, about (1,2,3)/√14",
       "as CutLocusAboutX", false, [](Recorder& r) { cutLocus(r, kDiagonalAxis); }},
      {"BeyondPiShortWayLongWayExtraTurns", "2. beyond π",
       "seed J, θ = 2π − 0.1 about x (N = 64): default, LongWay, extra_revolutions = 1; θ = 1 rad "
       "(variational, N = 128) the three ways; extra_revolutions = −1",
       "all converge (terminal ≤ 1e-9); the default equals the −0.1 rad problem (cost to 1e-9 "
       "relative, net turn −0.1 ± 0.05 rad); LongWay turns ≥ π the other way, one extra turn "
       "≥ π further, both cost more; −1 turns refused with InvalidInput naming extra_revolutions",
       false, beyondPi},
      {"TinyRotationsScaleLinearly", "3. tiny maneuvers",
       "seed J, rest to rest, θ = 1e-10 and 1e-6 about (1,2,3)/√14, T = 12.8 s, N = 64",
       "converged, terminal ≤ 1e-9 (and ≤ 1e-5·θ, 1e-9·θ); τ/θ equal to 1e-6 relative "
       "(max_k|τ_a/θ_a − τ_b/θ_b| ≤ 1e-6·max|τ/θ|)",
       false, tinyRotations},
      {"ZeroManeuverIsExactlyZero", "3. tiny maneuvers",
       "seed J, R_N = R_0, at rest, N = 64, both schemes",
       "converged, τ_k = 0 exactly for every k, ≤ 1 iteration", false, zeroManeuver},
      {"StronglyAnisotropicInertia", "4. inertia",
       "J = diag(0.01, 1, 1.005) and diag(1, 100, 100.5): 2 rad about (1,2,3)/√14 in 10 s to "
       "Ω = (0.05, −0.1, 0.15), N = 128",
       "converged, terminal ≤ 1e-9, no NaN", false, anisotropicInertia},
      {"NearlyIsotropicInertia", "4. inertia",
       "J = diag(1, 1, 1 + 1e-9) and J = I: 2 rad about (1,2,3)/√14 rest to rest in 10 s, N = 128",
       "converged; torques within 1e-7·max|τ| of J = I's and along the axis to 1e-7", false,
       nearlyIsotropicInertia},
      {"RotatedInertiaEquivariance", "4. inertia",
       "seed slew-up (N = 64) and the same problem in body axes rotated by a random Q "
       "(J' = QJQᵀ, R' = RQᵀ, Ω' = QΩ)",
       "both converge; τ'_k = Q τ_k to 1e-10 N m, costs equal to 1e-12 relative", false,
       rotatedInertia},
      {"ScaledInertia", "4. inertia", "seed slew-up (N = 64) with J, J·1e6, J·1e-6",
       "all converge; τ(sJ) = s·τ(J) to 1e-10 relative", false, scaledInertia},
      {"SpinningEnds", "5. dynamics",
       "seed J, Ω_0 = (0, 0, 5) → Ω_{N−1} = (3, 0, 0) rad/s, 1 rad about x, T = 12.8 s, N = 128",
       "converged, terminal ≤ 1e-9, every level of the kept solve within the default 200 "
       "iterations (the total, with every class and the more starts, is reported)",
       false, spinningEnds},
      {"IntermediateAxisSpin", "5. dynamics",
       "J = diag(1, 2, 3), Ω = (0, 1, 0) rad/s at both ends (intermediate axis), target 0.2 rad "
       "off the steady spin, T = 10, 30, 60 s at h = 0.1 s",
       "T = 10, 30: converged, terminal ≤ 1e-9; T = 60: converged (residual ≤ 1e-9, step "
       "residual within tolerance, plan's R_N on the target to 1e-9) while the open-loop replay "
       "misses by ~eps·e^{λT} (e^{λT} ≈ 1e15), reported as replay_miss ≥ 1e-9 (a sensitivity "
       "of the motion, not a failure of the plan); iterations at "
       "T = 30, 60 at most 4 more than at T = 10 (the nearest lift's solve alone)",
       false, intermediateAxisSpin},
      {"SlowManeuverN1e4", "5. dynamics",
       "77-day-style: seed J, 1 rad about x, rest to rest, T = 6.65e6 s, N = 1e4 (and N = 1000 as "
       "reference)",
       "converged, terminal ≤ 1e-9; h·C within 1e-2 of N = 1000's (first-order scheme)", false,
       [](Recorder& r) { slowManeuver(r, 10000, 1e-9); }},
      {"SlowManeuverN1e5", "5. dynamics", "as SlowManeuverN1e4 with N = 1e5 (slow)",
       "converged, terminal ≤ 1e-9 (the solver itself accepts up to 1e-9·N·1e-4 = 1e-8 here, the "
       "round-off floor growing like N²); h·C within 1e-2 of N = 1000's (first-order scheme)",
       true, [](Recorder& r) { slowManeuver(r, 100000, 1e-9); }},
      {"SlowManeuverN1e6", "5. dynamics",
       "as SlowManeuverN1e4 with N = 1e6 (slow; ~2.3 kB/step, 2.3 GB)",
       "converged, terminal ≤ 1e-9 (the solver itself accepts up to 1e-7 here); h·C within 1e-2 "
       "of N = 1000's (first-order scheme)",
       true, [](Recorder& r) { slowManeuver(r, 1000000, 1e-9); }},
      {"StepTooLargeIsAClearError", "6. step size",
       "paper: Ω_0 = 40 rad/s with h|Ω_0| = 5, 2.5, 0.625; variational: Ω_{N−1} = 50 rad/s at "
       "h = 1 s; paper: 3 rad + 3 turns in N = 8",
       "each either converges (terminal ≤ 1e-9) or fails with StepTooLarge / "
       "PlanResult::step_too_large and a message saying 'increase steps'; h|Ω| > π (paper) and "
       "the variational case are refused; h|Ω_0| = 0.625 converges",
       false, stepTooLarge},
      {"TorqueFreeMillionSteps", "7. integrator drift",
       "J = diag(1, 2, 3), Ω_0 = (0.6, 0.5, 0.4) rad/s, h = 0.01 s, 1e6 torque-free steps, both "
       "schemes",
       "‖RᵀR − I‖ + |det R − 1| ≤ 1e-14 at every step and the spatial momentum to 1e-13 relative "
       "(the issue asks 1e-12 and 1e-10)",
       false, integratorDrift},
      {"BitIdenticalRepeats", "8. determinism",
       "five problems (normal equations, augmented system with continuation, variational, both "
       "ways at π, spinning ends), each planned twice in one process",
       "the two results are bit-identical (every R_k, Ω_k, τ_k, cost, iterations, extremal)", false,
       determinism},
  };
  return cases;
}

}  // namespace robustness
}  // namespace attitude_planner
