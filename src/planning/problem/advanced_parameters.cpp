// The advanced parameters' table (advanced_parameters.hpp): every field once, with the range it
// must lie in, read by the validation and by the setter of a named field.
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/advanced_parameters.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// An integer field's upper bound where nothing else bounds it: the field stays an int.
constexpr double kLargestCount = 1e9;

struct Range {
  double lower;
  double upper;
  bool lower_open;
  bool upper_open;
};

constexpr Range kPositive{0, kInf, true, false};                 // (0, ∞)
constexpr Range kNonNegative{0, kInf, false, false};             // [0, ∞)
constexpr Range kOpenUnit{0, 1, true, true};                     // (0, 1): a fraction
constexpr Range kUpToOne{0, 1, true, false};                     // (0, 1]
constexpr Range kBelowOne{0, 1, false, true};                    // [0, 1)
constexpr Range kAboveOne{1, kInf, true, false};                 // (1, ∞): a growth factor
constexpr Range kAtLeastOne{1, kInf, false, false};              // [1, ∞)
constexpr Range kCount{1, kLargestCount, false, false};          // an integer ≥ 1
constexpr Range kCountOrNone{0, kLargestCount, false, false};    // an integer ≥ 0
constexpr Range kSteps{kMinSteps, kLargestCount, false, false};  // a grid's N
constexpr Range kArmijo{0, 0.5, true, true};  // (0, ½): a full Newton step passes near the solution
constexpr Range kCoarsening{2, 64, false, false};  // each coarser level has fewer steps

struct FieldName;

/// The common start of a group's field names ("newton."), joined to a field's own name by +.
struct NamePrefix {
  std::string text;
  FieldName operator+(const char* field) const;
};

/// A field's full name as its two parts: spelled out (str) only where a name is read, so that
/// the validation of every request builds no strings (measured: 150 names, 13 us a request).
struct FieldName {
  const NamePrefix& prefix;
  const char* field;
  std::string str() const { return prefix.text + field; }
  bool is(const std::string& name) const {
    return name.size() == prefix.text.size() + std::char_traits<char>::length(field) &&
           name.compare(0, prefix.text.size(), prefix.text) == 0 &&
           name.compare(prefix.text.size(), std::string::npos, field) == 0;
  }
};

FieldName NamePrefix::operator+(const char* field) const {
  return {*this, field};
}

/// Visits each profile field of `profile` as (name, value, range).
template <typename Profile, typename Visit>
void forEachProfileField(const std::string& group, Profile& profile, Visit& visit) {
  const NamePrefix prefix{group};
  visit(prefix + "initial_barrier", profile.initial_barrier, kPositive);
  visit(prefix + "theta_mu", profile.theta_mu, Range{1, 2, true, true});  // IPOPT: θ_μ ∈ (1, 2)
  visit(prefix + "max_halvings", profile.max_halvings, Range{1, 1074, false, false});
  visit(prefix + "floor_halvings", profile.floor_halvings, Range{1, 1074, false, false});
  visit(prefix + "first_shift", profile.first_shift, kOpenUnit);
  visit(prefix + "initial_penalty", profile.initial_penalty, kPositive);
  visit(prefix + "penalty_growth", profile.penalty_growth, kAboveOne);
}

/// Visits every Newton field of `p` (NewtonParameters, const or not) in the struct's order.
template <typename Newton, typename Visit>
void forEachNewtonField(Newton& p, Visit& visit) {
  const NamePrefix n{"newton."};
  visit(n + "normal_equations_max_steps", p.normal_equations_max_steps, kCountOrNone);
  visit(n + "round_off_acceptance_min", p.round_off_acceptance_min, kOpenUnit);
  visit(n + "round_off_floor_factor", p.round_off_floor_factor, kPositive);
  visit(n + "final_step_prediction_margin", p.final_step_prediction_margin, kUpToOne);
  visit(n + "negligible_decrease", p.negligible_decrease, kBelowOne);
  visit(n + "stall_decrement_ratio", p.stall_decrement_ratio, kOpenUnit);
  visit(n + "stall_iterations", p.stall_iterations, kCount);
  visit(n + "cost_floor", p.cost_floor, kPositive);
  visit(n + "round_off_report", p.round_off_report, kNonNegative);
  visit(n + "max_step_attempts", p.max_step_attempts, kCount);
  visit(n + "smallest_shift", p.smallest_shift, kPositive);
  visit(n + "negligible_shift", p.negligible_shift, kNonNegative);
  visit(n + "indefinite_shift_growth", p.indefinite_shift_growth, kAboveOne);
  visit(n + "first_rejection_shift", p.first_rejection_shift, kPositive);
  visit(n + "accept_ratio", p.accept_ratio, kOpenUnit);
  visit(n + "shift_min_factor", p.shift_min_factor, kOpenUnit);
  visit(n + "initial_shift_growth", p.initial_shift_growth, kAboveOne);
  visit(n + "shift_growth_growth", p.shift_growth_growth, kAtLeastOne);
  visit(n + "armijo", p.armijo, kArmijo);
  visit(n + "max_halvings", p.max_halvings, Range{1, 1074, false, false});
  visit(n + "backtrack_factor", p.backtrack_factor, kOpenUnit);
  visit(n + "line_search_shift_carry", p.line_search_shift_carry, kNonNegative);
  visit(n + "coarsest_steps", p.coarsest_steps, kSteps);
  visit(n + "coarsening_factor", p.coarsening_factor, kCoarsening);
  visit(n + "coarse_max_step_angle", p.coarse_max_step_angle, kPositive);
  visit(n + "coarse_tolerance_floor", p.coarse_tolerance_floor, kOpenUnit);
  visit(n + "class_survey_min_steps", p.class_survey_min_steps, kSteps);
  visit(n + "class_refine_margin", p.class_refine_margin, kNonNegative);
  visit(n + "unconstrained_refine_margin", p.unconstrained_refine_margin, kNonNegative);
  visit(n + "same_extremal_cost", p.same_extremal_cost, kBelowOne);
  visit(n + "cheaper_tie", p.cheaper_tie, kBelowOne);
  // 0: the stalled spinning solve's continuation in the boundary rates is not tried (the probes
  // below T* ask for that, drivers/minimum_time.cpp).
  visit(n + "rate_continuation_max_stages", p.rate_continuation_max_stages, kCountOrNone);
  visit(n + "rate_continuation_first_increment", p.rate_continuation_first_increment, kUpToOne);
  visit(n + "rate_continuation_max_increment", p.rate_continuation_max_increment, kUpToOne);
  visit(n + "rate_continuation_min_increment", p.rate_continuation_min_increment, kUpToOne);
  visit(n + "coasting_iteration_factor", p.coasting_iteration_factor, kCount);
  visit(n + "inertia_homotopy_stages", p.inertia_homotopy_stages, kCount);
  visit(n + "more_starts_above_iterations", p.more_starts_above_iterations, kCountOrNone);
}

/// Visits every field of `a` (AdvancedParameters, const or not) in the struct's order. Ranges:
/// where the method needs them (a fraction to the boundary in (0, 1), a growth above 1, a count
/// at least 1, Armijo's constant in (0, ½) so that a Newton step's full length passes near the
/// solution, a grid of at least kMinSteps), else positive.
template <typename Advanced, typename Visit>
void forEachField(Advanced& a, Visit&& visit) {
  forEachNewtonField(a.newton, visit);
  const NamePrefix drivers{""};
  visit(drivers + "search_work_allowance", a.search_work_allowance, kPositive);
  auto& p = a.interior_point;
  const NamePrefix ip{"interior_point."};
  forEachProfileField(ip.text + "fixed_step.", p.fixed_step, visit);
  forEachProfileField(ip.text + "free_time.", p.free_time, visit);
  visit(ip + "warm_barrier", p.warm_barrier, kPositive);
  visit(ip + "final_barrier_fraction", p.final_barrier_fraction, kUpToOne);
  visit(ip + "final_barrier_round_off_steps", p.final_barrier_round_off_steps, kCount);
  visit(ip + "barrier_snap_factor", p.barrier_snap_factor, kAtLeastOne);
  visit(ip + "mehrotra_exponent", p.mehrotra_exponent, kPositive);
  visit(ip + "barrier_progress_floor", p.barrier_progress_floor, kNonNegative);
  visit(ip + "barrier_progress_floor_steps", p.barrier_progress_floor_steps, kCount);
  visit(ip + "monotone_kappa_epsilon", p.monotone_kappa_epsilon, kPositive);
  visit(ip + "monotone_kappa_mu", p.monotone_kappa_mu, kOpenUnit);
  visit(ip + "monotone_stalled_steps", p.monotone_stalled_steps, kCount);
  visit(ip + "loqo_scale", p.loqo_scale, kUpToOne);
  visit(ip + "loqo_centrality", p.loqo_centrality, kPositive);
  visit(ip + "loqo_cap", p.loqo_cap, kPositive);
  visit(ip + "fraction_to_boundary", p.fraction_to_boundary, kOpenUnit);
  visit(ip + "dual_safeguard", p.dual_safeguard, kAtLeastOne);
  visit(ip + "elastic_dual_floor", p.elastic_dual_floor, kOpenUnit);
  visit(ip + "slack_push", p.slack_push, kOpenUnit);
  visit(ip + "warm_slack_push", p.warm_slack_push, kOpenUnit);
  visit(ip + "initial_multiplier_cap", p.initial_multiplier_cap, kPositive);
  visit(ip + "penalty_raise_violation", p.penalty_raise_violation, kPositive);
  visit(ip + "merit_multiplier_margin", p.merit_multiplier_margin, kAtLeastOne);
  visit(ip + "merit_infeasibility_fraction", p.merit_infeasibility_fraction, kOpenUnit);
  visit(ip + "max_inertia_corrections", p.max_inertia_corrections, kCount);
  visit(ip + "shift_growth", p.shift_growth, kAboveOne);
  visit(ip + "shift_row_floor", p.shift_row_floor, kBelowOne);
  visit(ip + "line_search_shift", p.line_search_shift, kPositive);
  visit(ip + "max_shift_floor", p.max_shift_floor, kPositive);
  visit(ip + "negligible_shift", p.negligible_shift, kNonNegative);
  visit(ip + "armijo", p.armijo, kArmijo);
  visit(ip + "merit_round_off", p.merit_round_off, kBelowOne);
  visit(ip + "stall_acceptance", p.stall_acceptance, kOpenUnit);
  visit(ip + "stall_acceptance_steps", p.stall_acceptance_steps, kCount);
  visit(ip + "stall_ratio", p.stall_ratio, kOpenUnit);
  visit(ip + "stalled_iterations", p.stalled_iterations, kCount);
  visit(ip + "quadratic_step", p.quadratic_step, kUpToOne);
  visit(ip + "quadratic_margin", p.quadratic_margin, kPositive);
  visit(ip + "reachable_fraction", p.reachable_fraction, kPositive);
  visit(ip + "floor_factor", p.floor_factor, kPositive);
  visit(ip + "violation_stall", p.violation_stall, kCount);
  visit(ip + "free_slack_violation_stall", p.free_slack_violation_stall, kCount);
  visit(ip + "violation_progress", p.violation_progress, kBelowOne);
  visit(ip + "feasibility_tolerance", p.feasibility_tolerance, kOpenUnit);
  visit(ip + "round_off_slack_residual", p.round_off_slack_residual, kNonNegative);
  visit(ip + "cost_scale_floor", p.cost_scale_floor, kPositive);
  visit(ip + "angle_floor", p.angle_floor, kPositive);
  visit(ip + "start_growth", p.start_growth, kAboveOne);
  visit(ip + "start_margin", p.start_margin, kOpenUnit);
  visit(ip + "max_start_growths", p.max_start_growths, kCountOrNone);
  visit(ip + "largest_start_raise", p.largest_start_raise, kAtLeastOne);
  visit(ip + "near_kkt_barrier", p.near_kkt_barrier, kUpToOne);
  visit(ip + "elastic_kink_width", p.elastic_kink_width, kPositive);
  visit(ip + "resumed_shift_divisor", p.resumed_shift_divisor, kAboveOne);
  visit(ip + "resumed_shift_growth", p.resumed_shift_growth, kAboveOne);
  visit(ip + "smallest_resumed_shift", p.smallest_resumed_shift, kOpenUnit);
  visit(ip + "max_uniform_shift", p.max_uniform_shift, kPositive);
  visit(ip + "damping_cut_step", p.damping_cut_step, kUpToOne);
  visit(ip + "damping_cut_steps", p.damping_cut_steps, kCount);
  visit(ip + "damped_barrier", p.damped_barrier, kUpToOne);
  visit(ip + "damping_growth", p.damping_growth, kAboveOne);
  visit(ip + "smallest_damping", p.smallest_damping, kOpenUnit);
  visit(ip + "coarsest_grid", p.coarsest_grid, Range{16, kLargestCount, false, false});
  visit(ip + "coarsening_factor", p.coarsening_factor, kCoarsening);
}

/// "a finite number > 0", "an integer in [1, 1074]", "a finite number in (0, 0.5)".
std::string rangeWords(const AdvancedField& f) {
  const std::string kind = f.integer ? "an integer" : "a finite number";
  const std::string low = exactNumber(f.lower);
  if (std::isinf(f.upper)) return kind + (f.lower_open ? " > " : " >= ") + low;
  return kind + " in " + (f.lower_open ? "(" : "[") + low + ", " + exactNumber(f.upper) +
         (f.upper_open ? ")" : "]");
}

bool inRange(const AdvancedField& f, double value) {
  if (!std::isfinite(value)) return false;
  if (f.integer && value != std::floor(value)) return false;
  const bool above = f.lower_open ? value > f.lower : value >= f.lower;
  const bool below = f.upper_open ? value < f.upper : value <= f.upper;
  return above && below;
}

void requireInRange(const AdvancedField& f, double value) {
  if (!inRange(f, value)) {
    throw InvalidInput("advanced." + f.name,
                       "must be " + rangeWords(f) + ", got " + exactNumber(value));
  }
}

template <typename Value>
AdvancedField fieldOf(const std::string& name, const Value& value, const Range& range) {
  return {name,
          range.lower,
          range.upper,
          range.lower_open,
          range.upper_open,
          std::is_integral_v<Value>,
          static_cast<double>(value)};
}

}  // namespace

std::vector<AdvancedField> advancedFields(const AdvancedParameters& parameters) {
  std::vector<AdvancedField> fields;
  forEachField(parameters, [&](const FieldName& name, const auto& value, const Range& range) {
    fields.push_back(fieldOf(name.str(), value, range));
  });
  return fields;
}

void validateAdvancedParameters(const AdvancedParameters& parameters) {
  forEachField(parameters, [](const FieldName& name, const auto& value, const Range& range) {
    AdvancedField f = fieldOf(std::string(), value, range);
    if (inRange(f, f.value)) return;
    f.name = name.str();
    requireInRange(f, f.value);
  });
}

void setAdvancedParameter(AdvancedParameters* parameters, const std::string& name, double value) {
  bool found = false;
  forEachField(*parameters, [&](const FieldName& field, auto& target, const Range& range) {
    if (!field.is(name)) return;
    requireInRange(fieldOf(field.str(), target, range), value);
    target = static_cast<std::remove_reference_t<decltype(target)>>(value);
    found = true;
  });
  if (found) return;
  std::string known;
  for (const AdvancedField& f : advancedFields(*parameters))
    known += (known.empty() ? "" : ", ") + f.name;
  throw InvalidInput("advanced." + name, "not an advanced parameter (known: " + known + ")");
}

}  // namespace attitude_planner
