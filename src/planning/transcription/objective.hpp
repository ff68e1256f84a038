// The objective of the transcription as a choice, not a constant: with the time step h a global
// unknown (T = N h) next to the node unknowns, an objective is
//
//     Φ(δ, h) = ε · C(δ, h) + φ(T),     C = Σ_k ½ w_k |τ_k|²  (ReducedProblem::cost),
//
// where C is the scheme's cost the Newton and interior-point solvers minimize today at a fixed h
// (the physical effort is h·C) and φ a term in the duration alone. ReducedProblem::
// evaluateWithTimeStep forms Φ's gradient in (δ, h) and its Hessian as a band (the node
// unknowns), a border column (∂²Φ/∂δ∂h) and a corner (∂²Φ/∂h²): the blocks of a bordered
// banded Newton system (planning/linalg/bordered_band.hpp).
#pragma once

#include <cmath>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

class TranscriptionObjective {
 public:
  virtual ~TranscriptionObjective() = default;
  /// A short name for messages ("effort", "time", "time + 0.001 effort").
  virtual std::string name() const = 0;
  /// ε ≥ 0, the weight of C; 0: the torques enter only through the constraints.
  virtual double effortWeight() const = 0;
  /// φ(T) [s, or the objective's unit], with dφ/dT and d²φ/dT² in *first, *second.
  virtual double timeTerm(double duration, double* first, double* second) const = 0;
};

/// Today's objective: C at a fixed h (ε = 1, φ = 0). ReducedProblem::evaluate is this objective
/// with h fixed; evaluateWithTimeStep gives the same numbers for the band and the gradient.
class EffortObjective : public TranscriptionObjective {
 public:
  std::string name() const override { return "effort"; }
  double effortWeight() const override { return 1.0; }
  double timeTerm(double, double* first, double* second) const override {
    *first = *second = 0.0;
    return 0.0;
  }
};

/// Minimum time: φ = T, ε = 0 (Hessian band zero: meaningful with constraints on the torques).
class TimeObjective : public TranscriptionObjective {
 public:
  std::string name() const override { return "time"; }
  double effortWeight() const override { return 0.0; }
  double timeTerm(double duration, double* first, double* second) const override {
    *first = 1.0;
    *second = 0.0;
    return duration;
  }
};

/// T + ε·C: minimum time regularized by the effort (a unique, smooth answer where minimum time
/// alone is bang–bang or singular).
class TimePlusEffortObjective : public TranscriptionObjective {
 public:
  /// Throws InvalidInput unless effort_weight is finite and ≥ 0.
  explicit TimePlusEffortObjective(double effort_weight) : epsilon_(effort_weight) {
    if (!(std::isfinite(effort_weight) && effort_weight >= 0.0)) {
      throw InvalidInput("objective: effort_weight must be finite and >= 0, got " +
                         std::to_string(effort_weight));
    }
  }
  std::string name() const override { return "time + " + std::to_string(epsilon_) + " effort"; }
  double effortWeight() const override { return epsilon_; }
  double timeTerm(double duration, double* first, double* second) const override {
    *first = 1.0;
    *second = 0.0;
    return duration;
  }

 private:
  double epsilon_;
};

}  // namespace attitude_planner
