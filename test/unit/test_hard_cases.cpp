// The named hard cases (test/support/robustness_cases.hpp). One test per
// case; each case's pass criterion is written next to its code in test/support/robustness_cases.cpp
// and printed here on failure, with every check that failed. Cases tagged slow (N = 1e5, 1e6)
// run only under ATTITUDE_PLANNER_SLOW_TESTS=1 (`scripts/test --all`); otherwise they are
// reported as skipped, saying how to run them. docs/results/robustness.md lists the measured
// figures
// (`scripts/robustness`).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "support/robustness_cases.hpp"

using namespace attitude_planner;
using robustness::HardCase;

namespace attitude_planner::robustness {
/// gtest prints a parameter by its name (not its bytes).
void PrintTo(const HardCase& c, std::ostream* os) {
  *os << c.name;
}
}  // namespace attitude_planner::robustness

namespace {

bool slowTestsEnabled() {
  const char* v = std::getenv("ATTITUDE_PLANNER_SLOW_TESTS");
  return v != nullptr && std::strcmp(v, "") != 0 && std::strcmp(v, "0") != 0;
}

}  // namespace

class HardCases : public ::testing::TestWithParam<HardCase> {};

TEST_P(HardCases, MeetsItsPassCriterion) {
  const HardCase& c = GetParam();
  if (c.slow && !slowTestsEnabled()) {
    GTEST_SKIP() << c.name << " is slow: run scripts/test --all (ATTITUDE_PLANNER_SLOW_TESTS=1)";
  }
  const robustness::CaseOutcome outcome = robustness::runCase(c);
  for (const robustness::RunFigures& f : outcome.runs) {
    std::printf(
        "  %-58s conv %d  it %3d  cost %.10g  err %.1e/%.1e  resid %.1e  decr %.1e  %.3f s\n",
        f.label.c_str(), f.converged, f.iterations, f.cost, f.terminal_attitude_error,
        f.terminal_velocity_error, f.max_residual, f.newton_decrement, f.solve_time_s);
  }
  for (const robustness::Check& k : outcome.checks) {
    if (k.relation != "true") {
      std::printf("  [%s] %s: %.3g %s %.3g\n", k.passed ? "ok" : "FAIL", k.quantity.c_str(),
                  k.measured, k.relation.c_str(), k.bound);
    } else if (!k.passed || !k.note.empty()) {
      std::printf("  [%s] %s%s%s\n", k.passed ? "ok" : "FAIL", k.quantity.c_str(),
                  k.note.empty() ? "" : ": ", k.note.c_str());
    }
  }
  RecordProperty("case_time_s", std::to_string(outcome.time_s));
  EXPECT_TRUE(outcome.passed()) << c.name << " (" << c.group << ")\n  problem: " << c.what
                                << "\n  criterion: " << c.criterion << "\n  failed:\n"
                                << outcome.failures();
}

INSTANTIATE_TEST_SUITE_P(Issue7, HardCases, ::testing::ValuesIn(robustness::hardCases()),
                         [](const ::testing::TestParamInfo<HardCase>& info) {
                           return info.param.name;
                         });
