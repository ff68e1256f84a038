// The least raise of a shift that makes a test succeed, where success is monotone in the raise
// (H + λ s I definite for every λ above its least definite shift): the raise a one-by-one scan
// 0, 1, 2, … would stop at, with about 2 log₂ of its distance from a guess in tests.
#pragma once

#include <algorithm>

namespace attitude_planner {

/// The least r in [0, most] with succeeds(r), −1 if none (succeeds(r) true for every r at least
/// the least one). Tries 0 (no raise: the common case), then `guess` (clamped to [1, most]), then
/// steps away from it by 1, 2, 4, … (down while the tests succeed, up while they fail) to the
/// first change, and bisects between the last failure and the first success. From a guess of 1
/// and a least raise near 18 (a fresh shift on the twist Newton's survey grid) 10 tests where the
/// scan makes 19; from the raise an earlier start needed, 3 to 7.
template <typename Succeeds>
int leastSucceedingRaise(int most, Succeeds&& succeeds, int guess = 1) {
  if (most < 0) return -1;
  if (succeeds(0)) return 0;
  if (most == 0) return -1;
  guess = std::clamp(guess, 1, most);
  int failed = 0, success = -1;  // the greatest raise known to fail, the least known to succeed
  if (succeeds(guess)) {
    success = guess;
    for (int step = 1; success - failed > 1; step *= 2) {
      const int probe = std::max(failed + 1, success - step);
      if (!succeeds(probe)) {
        failed = probe;
        break;
      }
      success = probe;
    }
  } else {
    failed = guess;
    for (int step = 1; failed < most; step *= 2) {
      const int probe = std::min(most, failed + step);
      if (succeeds(probe)) {
        success = probe;
        break;
      }
      failed = probe;
    }
    if (success < 0) return -1;
  }
  while (success - failed > 1) {
    const int middle = failed + (success - failed) / 2;
    if (succeeds(middle)) {
      success = middle;
    } else {
      failed = middle;
    }
  }
  return success;
}

}  // namespace attitude_planner
