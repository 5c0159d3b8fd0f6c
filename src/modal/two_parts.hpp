// SPDX-License-Identifier: MIT
// Splits a loop over [0, count) in two parts, the second on a helper std::thread.
//
// The block Lanczos stage streams its basis and the factor through one core otherwise.
// OpenBLAS's own threads would do the same split, but its idle threads spin (sched_yield),
// which on a shared 2-core machine takes the core from the thread doing the work; a joined
// std::thread only costs its start (~50 us) and sleeps in join (tests/bench/modal).
#pragma once

#include <system_error>
#include <thread>

namespace strike {

/// Calls work(begin, end, part) for part 0 on [0, split) in this thread and for part 1 on
/// [split, count) in a helper thread, or work(0, count, 0) alone when `parallel` is false,
/// count < 2, or no thread can be started. `work` must not throw: a throw in the helper
/// thread would end the process.
template <class Index, class Work>
void inTwoParts(Index count, Index split, bool parallel, const Work& work) {
  if (parallel && count >= 2 && split > 0 && split < count) {
    std::thread helper;
    try {
      helper = std::thread([&] { work(split, count, 1); });
    } catch (const std::system_error&) {
      work(Index{0}, count, 0);
      return;
    }
    work(Index{0}, split, 0);
    helper.join();
    return;
  }
  work(Index{0}, count, 0);
}

}  // namespace strike
