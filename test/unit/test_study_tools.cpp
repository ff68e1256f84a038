// The studies' shared command-line reader (test/support/study_tools.hpp): flags set the options
// bound to them, absent flags keep their defaults, and every usage error names the flag and the
// value instead of running a default study or wrapping a number.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "support/study_tools.hpp"

namespace st = attitude_planner::study;

namespace {

struct Options {
  int count = 30;
  std::uint64_t seed = 77;
  unsigned small_seed = 41;
  std::string out;
};

st::FlagReader readerFor(Options* o) {
  st::FlagReader flags;
  flags.add("--count", &o->count)
      .add("--seed", &o->seed)
      .add("--small-seed", &o->small_seed)
      .add("--out", &o->out);
  return flags;
}

/// The usage error's message of reading `args` (empty: none was thrown).
std::string usageError(std::vector<std::string> args, bool require_out = false) {
  Options o;
  st::FlagReader flags = readerFor(&o);
  if (require_out) flags.require("--out");
  args.insert(args.begin(), "study");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  try {
    flags.read(static_cast<int>(argv.size()), argv.data());
  } catch (const st::UsageError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(StudyFlags, SetTheBoundOptionsAndKeepTheDefaultsOfAbsentOnes) {
  Options o;
  std::vector<std::string> args = {"study", "--seed", "18446744073709551615", "--out", "a.md"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  readerFor(&o).read(static_cast<int>(argv.size()), argv.data());
  EXPECT_EQ(o.seed, UINT64_MAX);
  EXPECT_EQ(o.out, "a.md");
  EXPECT_EQ(o.count, 30);
  EXPECT_EQ(o.small_seed, 41u);
}

TEST(StudyFlags, UsageErrorsNameTheFlagAndTheValue) {
  EXPECT_EQ(usageError({"--count", "7"}), "");
  EXPECT_EQ(usageError({"--cout", "7"}), "unknown flag --cout");
  EXPECT_EQ(usageError({"--count"}), "--count needs a value");
  EXPECT_EQ(usageError({"--count", "7"}, true), "--out is required");
  for (const std::string bad : {"abc", "1.5", "12x", "", "99999999999"}) {
    const std::string message = usageError({"--count", bad});
    EXPECT_EQ(message.rfind("--count " + bad + ": not a whole number in [", 0), 0u) << message;
  }
  // A seed is unsigned: -1 is refused, not wrapped to the largest seed.
  EXPECT_NE(usageError({"--small-seed", "-1"}), "");
  EXPECT_NE(usageError({"--small-seed", "4294967296"}), "");
}

TEST(StudyFlags, NumberListsKeepTheirOrderAndNameTheItemRefused) {
  const auto positive = [](double x) { return x > 0.0; };
  EXPECT_EQ(st::numberListFlag("--probe-at", "1.5,2,0.25", positive, "a duration > 0"),
            (std::vector<double>{1.5, 2.0, 0.25}));
  for (const std::string bad : {"1,x", "1,,2", "1,-2", "2.5s", "0"}) {
    try {
      st::numberListFlag("--probe-at", bad, positive, "a duration > 0");
      ADD_FAILURE() << bad << " was read";
    } catch (const st::UsageError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("--probe-at: '", 0), 0u) << message;
      EXPECT_NE(message.find("is not a duration > 0"), std::string::npos) << message;
    }
  }
}
