// Minimum time's objective as the free-time interior point minimizes it (a TranscriptionObjective,
// objective.hpp): the duration in units of the start's, plus the effort weighted by ε(μ), the
// regularization that vanishes with the barrier.
#pragma once

#include <algorithm>
#include <string>

#include "planning/transcription/objective.hpp"

namespace attitude_planner {

/// Minimum time as the free-time interior point minimizes it, in units of a duration T₀ (the
/// start's, N h₀, unless a reference is named: FreeTimeScale): Φ = T/T₀ + ε(μ) C, where ε(μ) = ε₀
/// clamp(μ/μ₀, ε_min, 1) is a regularization that vanishes with the barrier μ (minimum time alone
/// is bang–bang: where a torque is strictly inside its bounds ε makes the Newton system definite)
/// and ε₀ C₀ = kInitialEffortShare at the effort C₀ (the start's, or the reference's).
/// effortWeight() is ε at the barrier last set.
class MinimumTimeObjective final : public TranscriptionObjective {
 public:
  /// ε₀ C₀ = this at the start (C₀ its effort): a light regularization, gone as μ → 0.
  static constexpr double kInitialEffortShare = 1e-2;
  /// ε never falls below this × ε₀: where the plan is strictly inside its bounds (the switches)
  /// minimum time alone has no curvature, and a shifted Newton step stalls there (measured on
  /// Bilimoria–Wie: stationarity stuck at 1e-6); T moves by O(ε) ~ 1e-10 T₀.
  static constexpr double kFinalEffortFraction = 1e-8;

  /// N steps from h₀ (the start's time step, η = h/h₀ the unknown) with effort C₀ at T₀; μ₀ the
  /// first barrier. T₀ = N h₀ unless `reference_duration` (> 0) names another (FreeTimeScale).
  MinimumTimeObjective(int steps, double start_time_step, double start_cost, double mu0,
                       double reference_duration = 0.0)
      : steps_(steps),
        h0_(start_time_step),
        t0_(reference_duration > 0.0 ? reference_duration : steps * start_time_step),
        mu0_(mu0),
        epsilon0_(start_cost > 0 ? kInitialEffortShare / start_cost : 0.0),
        epsilon_(epsilon0_) {}
  /// ε(μ), and effortWeight() from now on.
  double setBarrier(double mu) {
    epsilon_ = epsilon0_ * std::clamp(mu / mu0_, kFinalEffortFraction, 1.0);
    return epsilon_;
  }
  std::string name() const override {
    return "time / T0 + " + std::to_string(epsilon_) + " effort";
  }
  double effortWeight() const override { return epsilon_; }
  double timeTerm(double duration, double* first, double* second) const override {
    *first = 1.0 / startDuration();
    *second = 0.0;
    return duration / startDuration();
  }
  /// Φ at time step h with effort C and weight ε (a line search holds the ε of its barrier).
  double value(double h, double cost, double epsilon) const {
    return steps_ * h / startDuration() + epsilon * cost;
  }
  /// ∂(T/T₀)/∂η with η = h/h₀: N h₀/T₀ (1 up to round-off where T₀ is the start's own).
  double timeGradient() const { return steps_ * h0_ / startDuration(); }
  /// T₀.
  double startDuration() const { return t0_; }
  /// T − T₀ (Σ zc + εC) [s] at time step h: on the central path the local minimum of Φ lies at
  /// most the duality gap Σ zc below the iterate's value (weak duality of the barrier problem's
  /// Lagrangian, local), and εC, which vanishes with μ, at most its own size.
  double lowerBound(double h, double gap, double cost, double epsilon) const {
    return steps_ * h - startDuration() * (gap + epsilon * cost);
  }

 private:
  int steps_;
  double h0_, t0_, mu0_, epsilon0_, epsilon_;
};

}  // namespace attitude_planner
