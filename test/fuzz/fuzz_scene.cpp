// libFuzzer target: arbitrary bytes as a scene file. The parser must either return a
// scene or throw InvalidInput; a parsed rigid-body scene must survive validation, a formatScene
// round trip and (small N only) a bounded plan whose result is finite. Anything else — another
// exception type, a crash, a sanitizer report, a hang, a broken invariant (abort) — is a bug.
// Built by scripts/fuzz (clang-14, -fsanitize=fuzzer,address,undefined); replayed over its corpus
// in the normal test suite by test/unit/test_fuzz_replay.cpp (AP_FUZZ_NO_ENTRY).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "fuzz_common.hpp"

namespace ap_fuzz {

inline int fuzzScene(const std::uint8_t* data, std::size_t size) {
  namespace ap = attitude_planner;
  if (size > 4096) return 0;  // scenes are short; long inputs only slow the search down
  const std::string text(reinterpret_cast<const char*>(data), size);
  ap::Scene scene;
  try {
    scene = ap::parseScene(text, "<fuzz>");
  } catch (const ap::InvalidInput&) {
    return 0;  // the expected refusal
  }
  if (scene.system == ap::SystemKind::DriftTwoInput) {
    try {
      ap::driftTwoInputRequest(scene);
    } catch (const ap::InvalidInput&) {
    }
    return 0;
  }
  ap::validateProblem(scene.problem);  // parseScene validated it: must not throw now
  // formatScene writes what parseScene reads back to the same problem.
  const ap::Scene back = ap::parseScene(ap::formatScene(scene), "<formatted>");
  invariant(back.problem.steps == scene.problem.steps, "round trip keeps N");
  invariant(back.problem.duration == scene.problem.duration, "round trip keeps T");
  invariant(
      (back.problem.inertia - scene.problem.inertia).norm() <= 1e-15 * scene.problem.inertia.norm(),
      "round trip keeps J");
  invariant(back.problem.extra_revolutions == scene.problem.extra_revolutions,
            "round trip keeps extra_revolutions");
  if (!scene.effects.empty()) return 0;  // effects: planning tested elsewhere, slower
  boundedPlan(scene.problem);
  return 0;
}

}  // namespace ap_fuzz

#ifndef AP_FUZZ_NO_ENTRY
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ap_fuzz::fuzzScene(data, size);
}
#endif
