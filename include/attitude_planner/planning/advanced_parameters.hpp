// The solvers' tuning a user may set (SolverOptions::advanced): the Newton solver's and the
// interior point's parameter structs, and one table that names every field with the range it must
// lie in (src/planning/problem/advanced_parameters.cpp), read by the validation, by the setter of
// a named field (plan_maneuver --advanced NAME=VALUE) and by the list of fields.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "attitude_planner/planning/newton_parameters.hpp"

namespace attitude_planner {

/// The tuning a user may set beside the solver options (SolverOptions::advanced): every field
/// has a default that is the planner's own, and bounds validateAdvancedParameters checks.
struct AdvancedParameters {
  NewtonParameters newton;                 ///< "newton.<field>": the unconstrained solver
  InteriorPointParameters interior_point;  ///< "interior_point.<field>": under constraints
  /// "search_work_allowance": the work (node-iterations: Σ over the iterations of the grid's N)
  /// that each search for a better answer than the one in hand may spend: the minimum-time search
  /// on durations (its coarse grids included) and the probes below a minimum time with spinning
  /// ends. Checked between their solves, so such a search ends after at most this and the solve in
  /// progress, on any grid, without a time budget, at the same point on every run (seconds would
  /// not); where it stops one, the answer says so. Why 2e7: 1-2 minutes on a 2-core machine
  /// (4-8 us a node-iteration, measured at N = 410 and 787 on held-out requests whose probes and
  /// search had run 100,000 iterations, 250 s to over 800 s, before an answer), and above the whole
  /// work of the seed-45 spinning suite's longest requests (36,000-49,000 iterations at
  /// N = 128-303: at most 1.3e7), whose probes found their lower T*.
  double search_work_allowance = 2e7;
};

/// One settable field of AdvancedParameters: its name ("newton.armijo", "interior_point.armijo",
/// "interior_point.free_time.theta_mu") and the range it must lie in (a finite number; an
/// integer where `integer`; an infinite bound is no bound).
struct AdvancedField {
  std::string name;
  double lower = 0.0;
  double upper = 0.0;
  bool lower_open = false;  ///< the value must exceed `lower` (else be at least it)
  bool upper_open = false;  ///< the value must stay below `upper` (else at most it)
  bool integer = false;
  double value = 0.0;  ///< its value in the AdvancedParameters listed
};

/// Every field of `parameters`, in the struct's order, with its range and value.
std::vector<AdvancedField> advancedFields(const AdvancedParameters& parameters);

/// Throws InvalidInput naming the field and the value ("advanced.interior_point.armijo: must be
/// in (0, 0.5), got 0.7") unless every field of `parameters` lies in its range.
void validateAdvancedParameters(const AdvancedParameters& parameters);

/// Sets the field `name` (as advancedFields names it) to `value`, checked against its range:
/// throws InvalidInput naming an unknown field (with the known ones) or a value out of range.
void setAdvancedParameter(AdvancedParameters* parameters, const std::string& name, double value);

}  // namespace attitude_planner
