#include "attitude_planner/io/plan_flags.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

const char* const kPlanFlagNames[] = {"--steps",           "--scheme",
                                      "--solver",          "--precision",
                                      "--tolerance",       "--max-iterations",
                                      "--time-budget",     "--threads",
                                      "--target-miss",     "--target-cost-error",
                                      "--objective",       "--time-margin",
                                      "--direction",       "--extra-revolutions",
                                      "--point-body-axis", "--point-world-direction",
                                      "--advanced"};

int parseInteger(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || v > 2147483647L ||
      v < -2147483647L) {
    throw InvalidInput(flag, "expected an integer, got '" + text + "'");
  }
  return static_cast<int>(v);
}

double parseFinite(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v)) {
    throw InvalidInput(flag, "expected a finite number, got '" + text + "'");
  }
  return v;
}

/// A number flag that must be > 0 (`unit` follows the bound in the message, e.g. " s").
double parsePositive(const std::string& flag, const std::string& text, const char* unit = "") {
  const double v = parseFinite(flag, text);
  if (!(v > 0.0)) throw InvalidInput(flag, std::string("must be > 0") + unit + ", got " + text);
  return v;
}

/// "NAME=VALUE" (--advanced): one field of the advanced parameters, checked against its range.
void applyAdvancedFlag(const std::string& flag, const std::string& text,
                       AdvancedParameters* advanced) {
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos) {
    throw InvalidInput(flag,
                       "expected NAME=VALUE (e.g. interior_point.armijo=1e-4), got '" + text + "'");
  }
  const double value = parseFinite(flag, text.substr(equals + 1));
  try {
    setAdvancedParameter(advanced, text.substr(0, equals), value);
  } catch (const InvalidInput& e) {
    throw InvalidInput(flag, e.what());
  }
}

/// "X,Y,Z": a finite nonzero vector (a pointing flag's value).
Vector3 parseDirectionVector(const std::string& flag, const std::string& text) {
  Vector3 v;
  std::size_t at = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = i < 2 ? text.find(',', at) : text.size();
    if (comma == std::string::npos) {
      throw InvalidInput(flag, "expected three numbers X,Y,Z, got '" + text + "'");
    }
    v(i) = parseFinite(flag, text.substr(at, comma - at));
    at = comma + 1;
  }
  if (v.norm() == 0.0) throw InvalidInput(flag, "zero vector '" + text + "' has no direction");
  return v;
}

/// The flags whose value is a name: checked by the core's own name tables.
bool applyNamedFlag(const std::string& flag, const std::string& value, PlanFlags* flags) {
  PlanFlags& f = *flags;
  if (flag == "--scheme") {
    PlanningProblem checked;
    applySchemeName(value, flag, &checked);
    f.scheme = value;
  } else if (flag == "--solver") {
    parseSolver(value, flag);
    f.solver = value;
    f.solver_given = true;
  } else if (flag == "--precision") {
    parsePrecision(value, flag);
    f.precision = value;
  } else if (flag == "--objective") {
    parseObjective(value, flag);
    f.objective = value;
  } else if (flag == "--direction") {
    parseDirection(value, flag);
    f.direction = value;
  } else {
    return false;
  }
  return true;
}

}  // namespace

bool isPlanFlag(const std::string& flag) {
  for (const char* name : kPlanFlagNames) {
    if (flag == name) return true;
  }
  return false;
}

void applyPlanFlag(const std::string& flag, const std::string& value, PlanFlags* flags) {
  PlanFlags& f = *flags;
  if (applyNamedFlag(flag, value, flags)) return;
  if (flag == "--steps") {
    // Its range is the planner's rule (validateProblem / planDriftTwoInput), checked there.
    f.steps = parseInteger(flag, value);
  } else if (flag == "--tolerance") {
    f.tolerance = parsePositive(flag, value);
  } else if (flag == "--max-iterations") {
    f.max_iterations = parseInteger(flag, value);
    if (f.max_iterations < 1) {
      throw InvalidInput(flag, "must be >= 1, got " + std::to_string(f.max_iterations));
    }
  } else if (flag == "--time-budget") {
    f.time_budget = parsePositive(flag, value, " s");
  } else if (flag == "--threads") {
    f.threads = parseInteger(flag, value);
    if (f.threads < 1) throw InvalidInput(flag, "must be >= 1, got " + value);
  } else if (flag == "--target-miss" || flag == "--target-cost-error") {
    f.target_value = parsePositive(flag, value);
    f.target_flag = flag;
  } else if (flag == "--time-margin") {
    f.time_margin = parseFinite(flag, value);
    if (!(f.time_margin >= 0.0)) {
      throw InvalidInput(flag, "must be a finite number >= 0, got " + value);
    }
  } else if (flag == "--extra-revolutions") {
    f.extra_revolutions = parseInteger(flag, value);
    requireExtraRevolutions(f.extra_revolutions, flag);
  } else if (flag == "--point-body-axis") {
    f.point_body_axis = parseDirectionVector(flag, value);
  } else if (flag == "--point-world-direction") {
    f.point_world_direction = parseDirectionVector(flag, value);
  } else if (flag == "--advanced") {
    applyAdvancedFlag(flag, value, &f.advanced);
  } else {
    throw InvalidInput(flag, "not a planning flag (value '" + value + "')");
  }
}

void checkPlanFlagCombination(const PlanFlags& flags) {
  if (!flags.target_flag.empty() && flags.steps) {
    throw InvalidInput(flags.target_flag + " chooses N: do not give --steps with it");
  }
  if (flags.point_body_axis.has_value() != flags.point_world_direction.has_value()) {
    throw InvalidInput(
        "--point-body-axis and --point-world-direction: give both (a pointing end condition) or "
        "neither");
  }
  if (flags.scheme == kAutoSchemeName && flags.target_flag.empty()) {
    throw InvalidInput("--scheme auto needs --target-miss or --target-cost-error");
  }
}

void applyPlanFlags(const PlanFlags& flags, PlanningProblem* problem, SolverOptions* options) {
  PlanningProblem& p = *problem;
  if (flags.steps) p.steps = *flags.steps;
  if (!flags.scheme.empty()) applySchemeName(flags.scheme, "--scheme", &p);
  if (!flags.target_flag.empty()) {
    p.accuracy.measure = flags.target_flag == "--target-miss" ? AccuracyMeasure::TerminalMiss
                                                              : AccuracyMeasure::CostError;
    p.accuracy.value = flags.target_value;
  }
  if (!flags.objective.empty()) p.objective = parseObjective(flags.objective, "--objective");
  if (flags.time_margin >= 0.0) p.time_margin = flags.time_margin;
  if (!flags.direction.empty()) p.direction = parseDirection(flags.direction, "--direction");
  if (flags.extra_revolutions >= 0) p.extra_revolutions = flags.extra_revolutions;
  if (flags.point_body_axis && flags.point_world_direction) {
    p.end_condition.kind = EndConditionKind::Pointing;
    p.end_condition.body_axis = *flags.point_body_axis;
    p.end_condition.world_direction = *flags.point_world_direction;
  }

  options->solver = parseSolver(flags.solver, "--solver");
  options->precision = parsePrecision(flags.precision, "--precision");
  if (flags.tolerance > 0.0) options->tolerance = flags.tolerance;
  if (flags.max_iterations > 0) options->max_iterations = flags.max_iterations;
  options->time_budget_s = flags.time_budget;
  if (flags.threads > 0) options->threads = flags.threads;
  options->advanced = flags.advanced;
}

}  // namespace attitude_planner
