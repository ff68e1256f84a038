// The fuzz targets (test/fuzz/) replayed over their corpus in the normal suite, so they
// cannot rot: the shipped scenes, the hostile scenes, the request seeds and every input a fuzz
// run found to crash (test/fuzz/regressions/, kept after the fix). A target that crashes, throws
// or aborts on one of them fails this test (gtest reports the exception; an abort kills the
// binary, which scripts/test counts as failed).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#define AP_FUZZ_NO_ENTRY
#include "../fuzz/fuzz_request.cpp"
#include "../fuzz/fuzz_scene.cpp"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> filesIn(const std::vector<std::string>& dirs) {
  std::vector<fs::path> out;
  for (const std::string& d : dirs) {
    if (!fs::exists(d)) continue;
    for (const auto& e : fs::directory_iterator(d)) {
      if (e.is_regular_file() && e.path().filename().string()[0] != '.') out.push_back(e.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::uint8_t> bytesOf(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

const std::string kSource = AP_SOURCE_DIR;

}  // namespace

TEST(FuzzReplay, SceneTargetOverItsCorpus) {
  const auto files = filesIn({kSource + "/scenes", kSource + "/test/hostile/scenes",
                              kSource + "/test/fuzz/regressions/scene"});
  EXPECT_GE(files.size(), 35u);
  for (const fs::path& f : files) {
    const std::vector<std::uint8_t> data = bytesOf(f);
    EXPECT_NO_THROW(ap_fuzz::fuzzScene(data.data(), data.size())) << f;
  }
}

TEST(FuzzReplay, RequestTargetOverItsCorpus) {
  const auto files =
      filesIn({kSource + "/test/fuzz/seeds/request", kSource + "/test/fuzz/regressions/request"});
  EXPECT_GE(files.size(), 3u);
  for (const fs::path& f : files) {
    const std::vector<std::uint8_t> data = bytesOf(f);
    EXPECT_NO_THROW(ap_fuzz::fuzzRequest(data.data(), data.size())) << f;
  }
}
