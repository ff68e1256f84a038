// The benchmark harness builds and runs: benchmark_solvers --quick solves the seed's rest-to-rest
// example at N = 16 with every solver and agrees on the cost. No timing is checked here.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

namespace {

const std::string kBin = AP_BINARY_DIR "/../../devel/lib/attitude_planner/";

TEST(BenchmarkSolvers, QuickRunSolvesWithEverySolverAndAgreesOnCost) {
  const std::string tool = kBin + "benchmark_solvers";
  ASSERT_EQ(access(tool.c_str(), X_OK), 0) << "benchmark_solvers not built at " << kBin;
  FILE* pipe = popen(("'" + tool + "' --quick 2>&1").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int raw = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(raw)) << output;
  EXPECT_EQ(WEXITSTATUS(raw), 0) << output;
  for (const char* solver : {"newton", "slsqp", "auglag", "complex_step"}) {
    EXPECT_NE(output.find(std::string("\"solver\": \"") + solver + "\""), std::string::npos)
        << solver << " missing from:\n"
        << output;
  }
}

}  // namespace
