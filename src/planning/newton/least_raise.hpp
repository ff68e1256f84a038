// The least raise of a shift that makes a test succeed, where success is monotone in the raise
// (H + λ s I definite for every λ above its least definite shift): the raise a one-by-one scan
// 0, 1, 2, … would stop at, with about 2 log₂ of it tests instead.
#pragma once

#include <algorithm>

namespace attitude_planner {

/// The least r in [0, most] with succeeds(r), −1 if none (succeeds(r) true for every r at least
/// the least one). Tries 0, then doubles (1, 2, 4, …, `most`) to the first success and bisects
/// between it and the last failure: from a fresh shift (a least raise near 18 on the twist
/// Newton's survey grid) 11 tests where the scan makes 19, from a carried one (a raise of 0 to 2)
/// as many as the scan.
template <typename Succeeds>
int leastSucceedingRaise(int most, Succeeds&& succeeds) {
  if (most < 0) return -1;
  if (succeeds(0)) return 0;
  int failed = 0, first_success = -1;
  for (int probe = 1; failed < most; probe = std::min(most, 2 * probe)) {
    if (succeeds(probe)) {
      first_success = probe;
      break;
    }
    failed = probe;
  }
  if (first_success < 0) return -1;
  while (first_success - failed > 1) {
    const int middle = failed + (first_success - failed) / 2;
    if (succeeds(middle)) {
      first_success = middle;
    } else {
      failed = middle;
    }
  }
  return first_success;
}

}  // namespace attitude_planner
