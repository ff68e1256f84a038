// Plans to a requested accuracy: what the caller asks for (AccuracyTarget, in PlanningProblem)
// and what the planner reports back (AccuracyEstimate, in PlanResult). The measures and the
// planner that chooses N are in accuracy.hpp; the measured orders are in docs/results/accuracy.md.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/name_table.hpp"

namespace attitude_planner {

/// Which error of a plan a target bounds (docs/results/accuracy.md, "The three measures").
enum class AccuracyMeasure {
  None,          ///< no target: plan at PlanningProblem::steps
  TerminalMiss,  ///< ‖log(R_Tᵀ R(T))‖ [rad] when the torques drive the continuous body (ZOH)
  CostError,  ///< |h Σ½|τ_k|² − ½∫|τ|²dt| [N²·m²·s] against the continuous optimum
};

/// The names of the measures (request field `accuracy_measure`, JSON `accuracy.measure`); None
/// has no name: it is spelled by leaving the measure out.
inline constexpr NamedValue<AccuracyMeasure> kAccuracyMeasureNames[] = {
    {AccuracyMeasure::TerminalMiss, "terminal_miss"},
    {AccuracyMeasure::CostError, "cost_error"},
};

/// "terminal_miss" / "cost_error" ("" for None).
inline std::string accuracyMeasureName(AccuracyMeasure measure) {
  return measure == AccuracyMeasure::None ? "" : nameIn(kAccuracyMeasureNames, measure);
}
/// The measure named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline AccuracyMeasure parseAccuracyMeasure(const std::string& text, const std::string& field) {
  return parseIn(kAccuracyMeasureNames, text, field);
}

/// A requested accuracy instead of a number of steps.
struct AccuracyTarget {
  AccuracyMeasure measure = AccuracyMeasure::None;
  double value = 0.0;          ///< the bound on the measure (its units), finite and > 0
  bool choose_scheme = false;  ///< also choose the scheme (any of the four, least work)
  int max_steps = 1 << 18;     ///< largest N the planner may choose

  bool active() const { return measure != AccuracyMeasure::None; }
};

/// The accuracy of the returned plan, when a target was given.
struct AccuracyEstimate {
  bool requested = false;
  AccuracyMeasure measure = AccuracyMeasure::None;
  double target = 0.0;
  /// Error of the returned plan: terminal_miss — measured by the zero-order-hold replay of the
  /// plan itself; cost_error — Richardson estimate |hC(N) − h'C(N/2)| / (2^p − 1).
  double estimated_error = 0.0;
  /// What the coarse resolutions and the order predicted for the chosen N (before solving it).
  double predicted_error = 0.0;
  double order = 0.0;  ///< convergence order p assumed (the measured one; cost error with node
                       ///< constraints: at most 1)
  std::string method;  ///< how estimated_error was obtained
  std::vector<int> steps_tried;            ///< every N solved, in order (coarse resolutions first)
  std::vector<double> errors_tried;        ///< the estimate at each of them
  std::vector<std::string> schemes_tried;  ///< the scheme of each of them
};

}  // namespace attitude_planner
