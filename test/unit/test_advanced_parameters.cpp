// The advanced parameters (advanced_parameters.hpp: the Newton solver's and the interior point's):
// every field in the table, every field bounded and named when out of range, a set value reaching
// the solver it tunes, the defaults the planner's own.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/advanced_parameters.hpp"
#include "planning/problem/solve_request.hpp"
#include "support/scene_problem.hpp"

namespace ap = attitude_planner;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The numeric members of `struct_name` as `header` (in include/attitude_planner/planning/)
/// declares them ("double name = ..." or "double name;"): read from the source, so a field added
/// without a table row is found.
std::set<std::string> declaredFields(const std::string& header, const std::string& struct_name) {
  std::ifstream in(AP_SOURCE_DIR "/include/attitude_planner/planning/" + header);
  std::stringstream text;
  text << in.rdbuf();
  const std::string source = text.str();
  const std::size_t begin = source.find("struct " + struct_name + " {");
  const std::size_t end = source.find("\n};", begin);
  const std::string body = source.substr(begin, end - begin);
  const std::regex member(R"(\n  (?:double|int) (\w+)(?: = [^;]+)?;)");
  std::set<std::string> names;
  for (std::sregex_iterator it(body.begin(), body.end(), member), last; it != last; ++it) {
    names.insert((*it)[1]);
  }
  return names;
}

/// The message of the InvalidInput `set` throws ("" if none).
template <typename Call>
std::string refusal(Call set, std::string* field = nullptr) {
  try {
    set();
  } catch (const ap::InvalidInput& e) {
    if (field) *field = e.field();
    return e.what();
  }
  return "";
}

/// The values of every field of `a`, in the table's order.
std::vector<double> valuesOf(const ap::AdvancedParameters& a) {
  std::vector<double> values;
  for (const ap::AdvancedField& f : ap::advancedFields(a)) values.push_back(f.value);
  return values;
}

/// Values just outside `f`'s range (and non-finite ones, and a fraction for an integer field).
std::vector<double> outside(const ap::AdvancedField& f) {
  std::vector<double> values = {std::nan(""), kInf, -kInf};
  values.push_back(f.lower_open ? f.lower : std::nextafter(f.lower, -kInf));
  if (std::isfinite(f.upper))
    values.push_back(f.upper_open ? f.upper : std::nextafter(f.upper, kInf));
  if (f.integer) values.push_back(f.lower + 1.5);
  return values;
}

}  // namespace

TEST(AdvancedParameters, EveryFieldOfTheStructsHasOneRowInTheTable) {
  std::set<std::string> expected;
  const std::string ip_header = "interior_point_parameters.hpp";
  for (const std::string& profile : {"fixed_step.", "free_time."}) {
    for (const std::string& name : declaredFields(ip_header, "InteriorPointProfile")) {
      expected.insert("interior_point." + profile + name);
    }
  }
  for (const std::string& name : declaredFields(ip_header, "InteriorPointParameters")) {
    expected.insert("interior_point." + name);
  }
  const std::set<std::string> newton = declaredFields("newton_parameters.hpp", "NewtonParameters");
  for (const std::string& name : newton) expected.insert("newton." + name);
  const std::set<std::string> drivers =
      declaredFields("advanced_parameters.hpp", "AdvancedParameters");
  expected.insert(drivers.begin(), drivers.end());
  std::set<std::string> listed;
  for (const ap::AdvancedField& f : ap::advancedFields({})) {
    EXPECT_TRUE(listed.insert(f.name).second) << f.name << " listed twice";
  }
  EXPECT_EQ(listed, expected);
  EXPECT_GE(expected.size(), 70u + 30u);  // the parser found the structs
  EXPECT_GE(newton.size(), 30u);
  EXPECT_EQ(drivers.count("search_work_allowance"), 1u);
}

TEST(AdvancedParameters, EachRowNamesItsOwnField) {
  // Setting one field moves that row's value alone: no two rows read the same member.
  const std::vector<ap::AdvancedField> defaults = ap::advancedFields({});
  for (const ap::AdvancedField& f : defaults) {
    ap::AdvancedParameters moved;
    const double other = f.integer ? f.value + 1 : std::nextafter(f.value, kInf);
    ap::setAdvancedParameter(&moved, f.name, other);
    const std::vector<ap::AdvancedField> after = ap::advancedFields(moved);
    for (std::size_t i = 0; i < after.size(); ++i) {
      EXPECT_EQ(after[i].value, after[i].name == f.name ? other : defaults[i].value)
          << "setting " << f.name << " moved " << after[i].name;
    }
  }
}

TEST(AdvancedParameters, DefaultsAreTheSolversConstantsAndValid) {
  const ap::InteriorPointParameters p;
  // The values the solvers held as literals and copies before they were profiles.
  const ap::InteriorPointProfile fixed = p.fixed_step, free = p.free_time;
  EXPECT_EQ(fixed.initial_barrier, 1.0);
  EXPECT_EQ(fixed.theta_mu, 1.5);
  EXPECT_EQ(fixed.max_halvings, 60);
  EXPECT_EQ(fixed.floor_halvings, 5);
  EXPECT_EQ(fixed.first_shift, 1e-14);
  EXPECT_EQ(fixed.initial_penalty, 1e4);
  EXPECT_EQ(fixed.penalty_growth, 1e4);
  EXPECT_EQ(free.initial_barrier, 0.1);
  EXPECT_EQ(free.theta_mu, 1.3);
  EXPECT_EQ(free.max_halvings, 40);
  EXPECT_EQ(free.floor_halvings, 40);
  EXPECT_EQ(free.first_shift, 1e-10);
  EXPECT_EQ(free.initial_penalty, 100.0);
  EXPECT_EQ(free.penalty_growth, 10.0);
  EXPECT_EQ(p.final_barrier_fraction, 0.1);
  EXPECT_EQ(p.resumed_shift_divisor, 3.0);  // IPOPT κ_w⁻ = 1/3
  EXPECT_EQ(p.resumed_shift_growth, 8.0);   // IPOPT κ_w⁺
  // The Newton solver's: a few of its step control's and stopping test's.
  const ap::NewtonParameters n = ap::AdvancedParameters{}.newton;
  EXPECT_EQ(n.normal_equations_max_steps, 256);
  EXPECT_EQ(n.armijo, 1e-4);
  EXPECT_EQ(n.max_halvings, 40);
  EXPECT_EQ(n.smallest_shift, 1e-14);
  EXPECT_EQ(n.accept_ratio, 1e-4);
  EXPECT_EQ(n.coarsest_steps, 16);
  EXPECT_EQ(n.class_refine_margin, 0.5);
  EXPECT_EQ(n.unconstrained_refine_margin, 0.35);
  EXPECT_EQ(n.rate_continuation_min_increment, 1.0 / 64);
  EXPECT_NO_THROW(ap::validateAdvancedParameters({}));
  EXPECT_NO_THROW(ap::validateOptions({}));
}

TEST(AdvancedParameters, EachFieldRefusesAValueOutsideItsRangeNamingTheFieldAndTheValue) {
  for (const ap::AdvancedField& f : ap::advancedFields({})) {
    for (const double bad : outside(f)) {
      ap::AdvancedParameters a;
      std::string field;
      const std::string message =
          refusal([&] { ap::setAdvancedParameter(&a, f.name, bad); }, &field);
      EXPECT_EQ(field, "advanced." + f.name) << message;
      EXPECT_NE(message.find("got " + ap::exactNumber(bad)), std::string::npos) << message;
      EXPECT_EQ(valuesOf(a), valuesOf({})) << "a refused value was set";
    }
    ap::AdvancedParameters a;  // a closed bound is inside
    if (!f.lower_open) EXPECT_NO_THROW(ap::setAdvancedParameter(&a, f.name, f.lower)) << f.name;
  }
}

TEST(AdvancedParameters, TheRangesTheMethodNeeds) {
  // Rows written out: the table's words and bounds for the fields whose range is the method's.
  struct Row {
    const char* name;
    double value;
    const char* message;
  };
  const Row rows[] = {
      {"interior_point.armijo", 0.5,
       "advanced.interior_point.armijo: must be a finite number in (0, 0.5), got 0.5"},
      {"interior_point.free_time.theta_mu", 1.0,
       "advanced.interior_point.free_time.theta_mu: must be a finite number in (1, 2), got 1"},
      {"interior_point.fixed_step.max_halvings", 0,
       "advanced.interior_point.fixed_step.max_halvings: must be an integer in [1, 1074], got 0"},
      {"interior_point.fraction_to_boundary", 1.0,
       "advanced.interior_point.fraction_to_boundary: must be a finite number in (0, 1), got 1"},
      {"interior_point.resumed_shift_growth", 1.0,
       "advanced.interior_point.resumed_shift_growth: must be a finite number > 1, got 1"},
      {"interior_point.coarsening_factor", 1,
       "advanced.interior_point.coarsening_factor: must be an integer in [2, 64], got 1"},
      {"interior_point.warm_barrier", -1e-3,
       "advanced.interior_point.warm_barrier: must be a finite number > 0, got -0.001"},
      {"newton.armijo", 0.0, "advanced.newton.armijo: must be a finite number in (0, 0.5), got 0"},
      {"newton.coarsest_steps", 3,
       "advanced.newton.coarsest_steps: must be an integer in [4, 1000000000], got 3"},
      {"newton.indefinite_shift_growth", 0.5,
       "advanced.newton.indefinite_shift_growth: must be a finite number > 1, got 0.5"},
      {"newton.more_starts_above_iterations", -1,
       "advanced.newton.more_starts_above_iterations: must be an integer in [0, 1000000000], got "
       "-1"},
      {"search_work_allowance", 0.0,
       "advanced.search_work_allowance: must be a finite number > 0, got 0"},
      {"interior_point.armijo_typo", 0.1, "advanced.interior_point.armijo_typo: not an advanced"},
  };
  for (const Row& row : rows) {
    ap::AdvancedParameters a;
    const std::string message = refusal([&] { ap::setAdvancedParameter(&a, row.name, row.value); });
    EXPECT_EQ(message.substr(0, std::string(row.message).size()), row.message);
  }
}

TEST(AdvancedParameters, AValueWrittenIntoTheOptionsIsRefusedByThePlanner) {
  ap::SolverOptions newton;
  newton.advanced.newton.backtrack_factor = 1.0;
  EXPECT_EQ(refusal([&] { ap::validateOptions(newton); }),
            "advanced.newton.backtrack_factor: must be a finite number in (0, 1), got 1");
  EXPECT_NE(refusal([&] {
              ap::planManeuver(ap::test_support::sceneProblem("rest_to_rest", 16), newton);
            }),
            "");
  ap::SolverOptions o;
  o.advanced.interior_point.free_time.theta_mu = 2.5;
  EXPECT_EQ(
      refusal([&] { ap::validateOptions(o); }),
      "advanced.interior_point.free_time.theta_mu: must be a finite number in (1, 2), got 2.5");
  // Both drivers check them: minimum effort under bounds and minimum time.
  EXPECT_NE(
      refusal([&] { ap::planManeuver(ap::test_support::sceneProblem("torque_limited", 16), o); }),
      "");
  EXPECT_NE(refusal([&] {
              ap::planManeuver(ap::test_support::sceneProblem("min_time_bilimoria_wie", 16), o);
            }),
            "");
}

TEST(AdvancedParameters, AFixedStepProfileValueReachesTheInteriorPoint) {
  const ap::PlanningProblem p = ap::test_support::sceneProblem("torque_limited", 32);
  const ap::PlanResult base = ap::planManeuver(p);
  ap::SolverOptions o;
  o.advanced.interior_point.fixed_step.initial_barrier = 1e-2;  // μ₀ 100× smaller
  const ap::PlanResult moved = ap::planManeuver(p, o);
  ASSERT_TRUE(base.converged()) << base.message();
  ASSERT_TRUE(moved.converged()) << moved.message();
  EXPECT_NE(moved.iterations, base.iterations);
  EXPECT_NEAR(moved.cost, base.cost, 1e-8 * base.cost);  // another path to the same optimum
}

TEST(AdvancedParameters, AFreeTimeProfileValueReachesTheMinimumTimeSolver) {
  const ap::PlanningProblem p = ap::test_support::sceneProblem("min_time_bilimoria_wie", 32);
  const ap::PlanResult base = ap::planManeuver(p);
  ap::SolverOptions o;
  o.advanced.interior_point.free_time.theta_mu = 1.2;
  const ap::PlanResult moved = ap::planManeuver(p, o);
  ASSERT_TRUE(base.converged()) << base.message();
  ASSERT_TRUE(moved.converged()) << moved.message();
  EXPECT_NE(moved.iterations, base.iterations);
  EXPECT_NEAR(moved.minimum_duration, base.minimum_duration, 1e-8);  // the same T*
}

TEST(AdvancedParameters, ANewtonValueReachesTheNewtonSolver) {
  // Every Newton start begins at the grid continuation's coarsest level: one level fewer (the
  // coarsest grid at the requested N) changes the iterations the walk takes, not its optimum.
  const ap::PlanningProblem p = ap::test_support::sceneProblem("rest_to_rest", 256);
  const ap::PlanResult base = ap::planManeuver(p);
  ap::SolverOptions o;
  o.advanced.newton.coarsest_steps = 256;
  const ap::PlanResult moved = ap::planManeuver(p, o);
  ASSERT_TRUE(base.converged()) << base.message();
  ASSERT_TRUE(moved.converged()) << moved.message();
  EXPECT_GT(base.levels.size(), moved.levels.size());  // the coarse levels are gone
  EXPECT_NE(moved.iterations, base.iterations);
  EXPECT_NEAR(moved.cost, base.cost, 1e-8 * base.cost);
}

TEST(SolveRequest, TheDeprecatedStartFieldsBecomeTheStartAndAreCleared) {
  const ap::Maneuver optimum;
  ap::SolverOptions user;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
  user.constrained_from_warm_start = true;
  user.warm_start_strictly_inside = true;
  user.unconstrained_optimum = &optimum;
  const ap::SolveRequest request(user);
  EXPECT_FALSE(request.constrained_from_warm_start);
  EXPECT_FALSE(request.warm_start_strictly_inside);
  EXPECT_EQ(request.unconstrained_optimum, nullptr);
#pragma GCC diagnostic pop
  EXPECT_TRUE(request.start.from_constrained_plan);
  EXPECT_TRUE(request.start.strictly_inside);
  EXPECT_EQ(request.start.unconstrained_optimum, &optimum);
  const ap::SolveRequest plain{ap::SolverOptions{}};
  EXPECT_FALSE(plain.start.from_constrained_plan || plain.start.strictly_inside);
  EXPECT_EQ(plain.start.unconstrained_optimum, nullptr);
}

TEST(SolveRequest, TheDeprecatedStartFieldsAreReadOnlyWhereTheyAreTranslated) {
  // The planner hands its start in SolveRequest::start: the public fields stay for API users.
  namespace fs = std::filesystem;
  const std::string fields[] = {"constrained_from_warm_start", "warm_start_strictly_inside",
                                ".unconstrained_optimum"};
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(fs::path(AP_SOURCE_DIR) / "src")) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".cpp" && ext != ".hpp") continue;
    if (entry.path().filename() == "solve_request.hpp") continue;  // the translation
    ++files;
    std::ifstream in(entry.path());
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      for (const std::string& field : fields) {
        for (std::size_t at = line.find(field); at != std::string::npos;
             at = line.find(field, at + 1)) {
          const bool the_start = at >= 5 && line.compare(at - 5, 5, "start") == 0;
          EXPECT_TRUE(the_start) << entry.path() << ":" << number << ": " << line;
        }
      }
    }
  }
  EXPECT_GT(files, 100);
}
